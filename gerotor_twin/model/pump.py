"""The pump model: the one stepping entry point ``advance`` (inputs, state, outputs in :mod:`.records`).

``advance(state, t_span, inputs) -> (state, outputs)`` is used by the CLI, the
node and the offline runs alike.  Inputs (shaft speed, suction and delivery
pressure, oil temperature) are held constant over one call and may change
between calls; the shaft angle is integrated from the speed.  The oil
properties follow the temperature input outside the hot loop: the kernel's
μ, ρ₀, conductances and state equation are re-evaluated when the temperature
has moved by more than :data:`TEMPERATURE_STEP_K` since the last evaluation,
and the state is converted so that the pressures are continuous.  Likewise a lateral gap that opens with
the pressure load (``clearances.lateral_opening_m_per_pa``): the lateral conductances follow the delivery −
suction pressure when it has moved the gap by more than :data:`LOAD_GAP_STEP` of itself.  Everything is SI: rad, rad/s,
Pa (absolute), m, m³/s, s.
"""
from __future__ import annotations

import contextlib
import math

import numpy as np

from ..bearing.registry import MODEL_NAMES, make_bearing
from ..bearing.geometry import BearingGeometry
from ..config import Numerics, PumpConfig
from ..errors import InputError
from ..geometry.lateral import lateral_geometry
from ..geometry.tables import GeometryTables, cached_tables
from ..hydraulics.state_equation import convert_log_density, log_density_of
from ..compile_events import announce_compilation
from . import kernel as K
from .records import Inputs, Outputs, PumpState, check_inputs
from .contact import contact
from .gear_coupling import GC_CORR1, GC_CORR_BEFORE
from .params import FL_DELIVERY, FL_MASS_IN, FL_MASS_OUT, at_load, at_temperature, kernel_model, operating, workspace

__all__ = ["Inputs", "PumpState", "Outputs", "PumpModel", "SolverFailure", "BEARING_MODELS", "TEMPERATURE_STEP_K",
           "LOAD_GAP_STEP"]


class SolverFailure(FloatingPointError):
    """An output step the kernel abandoned (:data:`.kernel.STEP_NONFINITE`, :data:`.kernel.STEP_WORK_BOUND`) or a
    non-finite state: the model's state is no longer a solution, and its caller must reset it (the twin does,
    counted and reported: ``twin.clock_driver``)."""


#: Why an output step was abandoned, as a user reads it (kernel.STEP_*).
_ABANDONED = {K.STEP_NONFINITE: "a sub-step at the smallest size gave a non-finite state",
              K.STEP_WORK_BOUND: "numerics.max_substep_attempts = {bound} sub-steps did not finish it (the bound on "
                                 "one step's work)"}

#: The kernel's oil properties are re-evaluated when the oil temperature has moved by more
#: than this since the last evaluation [K] (μ of a VG46 oil changes by ≈ 0.2 % over it at 40 °C).
TEMPERATURE_STEP_K = 0.05

#: The lateral conductances are re-evaluated when the pressure load has moved the lateral gap by more than this
#: share of its unloaded clearance [-] (the leakage, ∝ s³, by 0.3 %).
LOAD_GAP_STEP = 1e-3

BEARING_MODELS = MODEL_NAMES      #: the outer-gear models, by name (one list: bearing.registry)


def _with_micro_motion(km, config: PumpConfig, bearing: str):
    """The kernel model with the choices of ``config.micro_motion``: fixed-centre contact rule
    (sec. 3.7 of [1]) and chamber volumes of the displaced or the centred outer gear."""
    mm = config.micro_motion
    turn = not (bearing == "fixed" and mm.fixed_centre_contact == "none")
    return km._replace(tab=km.tab._replace(turn_inner=turn, volumes_follow_gear=mm.chamber_volumes == "displaced"))


class PumpModel:
    """Lumped-parameter Gerotor pump (sec. 3 of [1]) with a choice of outer-gear model.

    Parameters
    ----------
    config : PumpConfig
        Validated pump description.
    bearing : {"fixed", "mobility", "short", "fdm"}
        Outer-gear model: fixed centre, mobility method (the twin's default),
        short bearing "Method 1", finite-difference Reynolds.
    bearing_options : dict, optional
        Passed to :func:`gerotor_twin.bearing.base.make_bearing` (e.g. the FDM grid).
    """

    def __init__(self, config: PumpConfig, bearing: str = "mobility", bearing_options: dict | None = None,
                 tables: GeometryTables | None = None, progress=None):
        if bearing not in BEARING_MODELS:
            raise InputError("bearing_model", bearing, " | ".join(BEARING_MODELS))
        self.config = config
        self.bearing_name = bearing
        g = config.gears
        self.geometry = g
        self.N = g.chambers
        self.tables = tables if tables is not None else cached_tables(
            g, config.suction_port, config.delivery_port, config.numerics.table_points, progress)
        self.lateral = lateral_geometry(g, config.suction_port, config.delivery_port)
        self._bearing_options = bearing_options or {}
        self._make_bearing(config.fluid.viscosity_pa_s)
        self.displacement = g.displacement_closed_form()   # ideal profiles; δ does not enter
        self.kernel = _with_micro_motion(kernel_model(config, self.tables, self.lateral), config, bearing)
        #: oil temperature the kernel's properties are evaluated at [K]
        self.temperature_k = config.reference_temperature_k
        #: delivery − suction pressure the kernel's lateral gaps are evaluated at [Pa] (:meth:`set_load`)
        self.load_dp = 0.0
        self._ws = workspace(self.N)
        self._move = {"fixed": K.MOVE_FIXED, "mobility": K.MOVE_MOBILITY}.get(bearing, K.MOVE_EXTERNAL)
        self._announced = False                # _first_use

    def replica(self) -> "PumpModel":
        """A model of the same pump (its config as it is now), gear model and bearing options with its own workspace
        and kernel, sharing the geometry tables (a few ms): for work that must leave this model as it is — the health
        monitor's reference point, the node's start-up real-time check — so that only the twin's own ``advance``
        calls write this model."""
        return PumpModel(self.config, self.bearing_name, self._bearing_options, tables=self.tables)

    def _make_bearing(self, mu: float) -> None:
        g = self.geometry
        self.bearing_geometry = BearingGeometry(length_m=g.width, diameter_m=2 * g.outer_radius,
                                                clearance_m=self.config.clearances.housing_radial_m,
                                                viscosity_pa_s=mu)
        self.bearing = make_bearing(self.bearing_name, self.bearing_geometry, **self._bearing_options)

    def set_temperature(self, t_k: float | None, log_density: np.ndarray | None = None) -> np.ndarray | None:
        """Evaluate the oil properties at T [K] (None: the reference temperature) if it moved enough.

        Parameters
        ----------
        t_k : float or None
            Oil temperature [K].
        log_density : ndarray, optional
            A state's ln(ρ/ρ₀) under the current properties [-].

        Returns
        -------
        ndarray or None
            ``log_density`` converted to the new properties (same pressures), or
            ``log_density`` itself if nothing changed.

        Notes
        -----
        Nothing happens without an ``oil`` section (constant properties) or
        when |T − T_kernel| ≤ :data:`TEMPERATURE_STEP_K`.  Otherwise μ, ρ₀,
        the leakage conductances, the state equation (β_L(T)) and the
        viscosity of an external bearing model (short, FDM) are re-evaluated
        (≈ 1–3 ms).
        """
        t = self.config.reference_temperature_k if t_k is None else float(t_k)
        if self.config.oil is None or abs(t - self.temperature_k) <= TEMPERATURE_STEP_K:
            return log_density
        old = self.kernel.eos
        self.kernel = self._loaded(at_temperature(self.kernel, self.config, self.lateral, t))
        self.temperature_k = t
        if self._move == K.MOVE_EXTERNAL:
            self._make_bearing(self.kernel.pc.viscosity)
        return None if log_density is None else convert_log_density(log_density, old, self.kernel.eos)

    def set_load(self, dp_pa: float) -> None:
        """Evaluate the lateral conductances at delivery − suction pressure Δp [Pa] if it moved the gap enough.

        Nothing happens for a rigid pump (``clearances.lateral_opening_m_per_pa`` = 0) or when the gap
        (:func:`~gerotor_twin.model.params.lateral_gap`) moved by at most :data:`LOAD_GAP_STEP` of the unloaded
        clearance since the last evaluation; otherwise ≈ 10 µs.  The state is unchanged (no state variable
        depends on a conductance).
        """
        c = self.config.clearances
        moved = c.lateral_opening_m_per_pa * abs(max(dp_pa, 0.0) - max(self.load_dp, 0.0))
        if moved > LOAD_GAP_STEP * c.lateral_m:
            self.load_dp = float(dp_pa)
            self.kernel = at_load(self.kernel, self.config, self.lateral, self.load_dp)

    def _loaded(self, km):
        """``km`` with its lateral gaps at :attr:`load_dp` (itself for a rigid pump)."""
        if self.config.clearances.lateral_opening_m_per_pa == 0.0:
            return km
        return at_load(km, self.config, self.lateral, self.load_dp)

    def rebuild_kernel(self, config: PumpConfig, tables: GeometryTables) -> None:
        """Take ``config``/``tables`` (e.g. scaled clearances): the kernel as built in ``__init__``
        (micro-motion choices), at the oil temperature the model is at; the state stays valid (a changed
        state equation, ``mixture``: convert it, :func:`~gerotor_twin.hydraulics.state_equation.convert_log_density`).
        A changed housing clearance also rebuilds an external outer-gear model (short bearing, FDM)."""
        km = _with_micro_motion(kernel_model(config, tables, self.lateral), config, self.bearing_name)
        if config.oil is not None and self.temperature_k != config.reference_temperature_k:
            km = at_temperature(km, config, self.lateral, self.temperature_k)
        housing_changed = config.clearances.housing_radial_m != self.config.clearances.housing_radial_m
        self.config, self.geometry, self.tables = config, config.gears, tables
        self.kernel = self._loaded(km)
        if housing_changed and self._move == K.MOVE_EXTERNAL:
            self._make_bearing(km.pc.viscosity)

    @property
    def restriction_mode(self) -> bool:
        return self.config.boundary.mode == "restriction"

    def theoretical_flow(self, omega: float) -> float:
        """Displacement × speed [m³/s]."""
        return self.displacement * omega / (2 * math.pi)

    # ---------------------------------------------------------------- inputs
    def check_inputs(self, inputs: Inputs) -> Inputs:
        """Validate inputs against the documented envelope; raise :class:`InputError` (see :func:`check_inputs`)."""
        return check_inputs(self.config, inputs)

    # ---------------------------------------------------------------- state
    def initial_state(self, inputs: Inputs, theta: float = 0.0, t: float = 0.0) -> PumpState:
        """Chambers at suction pressure, delivery volume at the delivery pressure, centred gear."""
        inputs = self.check_inputs(inputs)
        self.set_temperature(inputs.oil_temperature)
        p = np.full(self.N + 1, inputs.p_suction)
        p[self.N] = inputs.p_delivery if not self.restriction_mode else inputs.p_suction
        for j in range(self.N):        # chambers open to the delivery port start at its pressure
            if self.tables.column("AD", theta, j) > 0:
                p[j] = p[self.N]
        y = np.array([log_density_of(v, self.kernel.eos) for v in p])
        return PumpState(t=t, theta=theta, log_density=y, pressures=p, eccentricity=np.zeros(2))

    def step_size(self, omega: float) -> float:
        """Integration step [s]: the configured angle step, capped in time."""
        n = self.config.numerics
        h_ang = math.radians(n.max_step_deg) / omega if omega > 0 else math.inf
        return min(h_ang, n.max_step_s)

    # -------------------------------------------------------------- advance
    def advance(self, state: PumpState, t_span: float | tuple, inputs: Inputs) -> tuple[PumpState, Outputs]:
        """Advance the model over ``t_span`` with constant ``inputs``.

        Parameters
        ----------
        state : PumpState
            State at the start.
        t_span : float or (t0, t1)
            Duration [s] or an interval whose start must equal ``state.t``.
        inputs : Inputs
            Shaft speed [rad/s], suction and delivery pressure [Pa], oil temperature [K].

        Returns
        -------
        (PumpState, Outputs)
            The new state and one output row per integration step.
        """
        inputs = self.check_inputs(inputs)
        dt = float(t_span[1] - t_span[0]) if isinstance(t_span, tuple) else float(t_span)
        if not (math.isfinite(dt) and dt >= 0):
            raise InputError("t_span", t_span, "a finite, non-negative duration [s]")
        h0 = self.step_size(inputs.omega)
        n = max(1, int(math.ceil(dt / h0 - 1e-9))) if dt > 0 else 0
        h = dt / n if n else 0.0
        y = self.set_temperature(inputs.oil_temperature, state.log_density.copy())
        if self.config.clearances.lateral_opening_m_per_pa:     # plates that deflect: the gaps follow Δp
            p_d = state.pressures[self.N] if self.restriction_mode else inputs.p_delivery   # the line's or imposed
            self.set_load(p_d - inputs.p_suction)
        e = state.eccentricity.copy()
        counters = state.counters.copy()
        vols = state.volumes.copy()
        rec = np.zeros((n, K.N_REC))
        rec_p = np.zeros((n, self.N))
        rec_peak = np.zeros((n, self.N))
        rec_g = np.zeros((n, self.N))
        op = operating(self.kernel, inputs.omega, inputs.p_suction, inputs.p_delivery)
        if not self.restriction_mode:
            y[self.N] = op.s_d
        theta, t = state.theta, state.t
        ws = self._ws
        ws.ctrl[K.CT_SUBSTEP] = state.substep
        ws.ctrl[K.CT_RANGE] = state.pressure_range
        ws.gear[GC_CORR1:GC_CORR1 + 4] = state.contact_correction     # as the set-up at the state found it
        ws.ctrl[K.CT_BOUND] = self.config.numerics.max_substep_attempts
        if self.kernel.tab.volumes_follow_gear:        # the volumes where the state's gear is, squeezed as it moved
            ws.disp[0], ws.disp[1] = e[0], e[1]
            ws.disp[2], ws.disp[3] = state.squeeze_velocity[0], state.squeeze_velocity[1]
        if n:
            if self._move == K.MOVE_EXTERNAL:
                with self._first_use():
                    theta, t = K.integrate_external(self.bearing, y, e, theta, t, n, h, self.kernel, op, ws, rec,
                                                    rec_p, rec_peak, rec_g, counters, vols)
            else:
                with self._first_use():
                    theta, t = K.integrate(y, e, theta, t, n, h, self.kernel, op, ws, rec, rec_p, rec_peak, rec_g,
                                           counters, vols, self._move, self._constraint())
            K.peak_pressures(rec_peak, rec_p, state.pressures, self.kernel.eos)
        if counters[K.C_ABANDONED] != state.counters[K.C_ABANDONED]:
            why = _ABANDONED.get(int(ws.ctrl[K.CT_STATUS]), "unknown status").format(
                bound=self.config.numerics.max_substep_attempts)
            raise SolverFailure(f"output step at t = {t:.6g} s, shaft angle {math.degrees(theta) % 360.0:.1f}° "
                                f"abandoned: {why}")
        if not math.isfinite(float(y.sum()) + float(e[0]) + float(e[1])):      # NaN or ±inf anywhere (ln ρ, e: small)
            raise SolverFailure("pump model produced a non-finite state (solver failure)")
        swept = state.swept_angle + inputs.omega * dt
        if n:
            pres = ws.pres.copy()                  # integrate() leaves the pressures of its last state there
        else:
            pres = np.empty_like(y)
            K.to_pressures(y, self.kernel, pres)
        new = PumpState(t=t, theta=theta, log_density=y, pressures=pres, eccentricity=e, counters=counters,
                        volumes=vols, swept_angle=swept,
                        substep=float(ws.ctrl[K.CT_SUBSTEP]),
                        pressure_range=float(ws.ctrl[K.CT_RANGE]),
                        squeeze_velocity=ws.disp[2:4].copy() if n else state.squeeze_velocity.copy(),
                        contact_correction=ws.gear[GC_CORR_BEFORE:GC_CORR_BEFORE + 4].copy() if n
                        else state.contact_correction.copy())
        return new, self._outputs(rec, rec_p, rec_peak, rec_g, inputs, vols - state.volumes, dt)

    def _constraint(self):
        """The stepper's ``constraint`` argument: the gear's workspace with ``gear_coupling: constrained``, else
        None.  The fixed centre takes the scheme's stepper too (one compiled specialisation per scheme serves
        both compiled gear models); its gear never moves, so none of the constraint's branches runs."""
        return self._ws.gear if self.kernel.pc.gear_constrained else None

    def _first_use(self):
        """Around the first advance of a Method 1 / FDM model or of a stepper whose ``gear_coupling`` is not the
        packaged config's: one line if its kernels compile now (they are not built at install,
        :data:`gerotor_twin.precompile.DEFAULT_MODELS`); later advances: nothing."""
        if self._announced:
            return contextlib.nullcontext()
        self._announced = True
        scheme = self.config.numerics.gear_coupling
        if self._move != K.MOVE_EXTERNAL:
            if scheme == Numerics().gear_coupling:       # the packaged config's scheme: built at install
                return contextlib.nullcontext()
            what, how_long = f"the stepper with numerics.gear_coupling: {scheme}", "about ten seconds"
        else:
            what, how_long = f"the {self.bearing_name} gear model", "seconds to half a minute"
        return announce_compilation(f"gerotor_twin: compiling {what} on its first use (once: {how_long}; "
                                    "cached after) ...")

    def gaps(self, theta: float, e) -> tuple[np.ndarray, float, int]:
        """Tooth-tip gaps [m] at shaft angle θ [rad] for an outer-gear displacement e [m] (sec. 3.7 rule).

        Returns the N gap heights, the inner-gear rotation γ [rad] and the lobe in contact.
        """
        h = np.empty(self.N)
        _ex, _ey, gam, kc = contact(self.kernel.tab, self.N, self.geometry.tip_clearance, float(theta),
                                    float(e[0]), float(e[1]), h, np.empty((self.N, 9)))
        return h, gam, kc

    def _outputs(self, rec, rec_p, rec_peak, rec_g, inputs: Inputs, dvol, dt) -> Outputs:
        qth = self.theoretical_flow(inputs.omega)
        eta = float(dvol[FL_DELIVERY] / (qth * dt)) if qth > 0 and dt > 0 else float("nan")
        return Outputs(
            t=rec[:, K.R_T], theta=rec[:, K.R_THETA], chamber_pressures=rec_p, chamber_peak_pressures=rec_peak,
            delivery_pressure=rec[:, K.R_PD], delivery_flow=rec[:, K.R_QDEL], suction_flow=rec[:, K.R_QSUC],
            leak_suction_delivery=rec[:, K.R_QSD], leak_drain=rec[:, K.R_QDR],
            restriction_flow=rec[:, K.R_QREST], eccentricity=rec[:, K.R_EX:K.R_EY + 1].copy(),   # adjacent columns:
            load=rec[:, K.R_FX:K.R_FY + 1].copy(), gaps=rec_g, inner_rotation=rec[:, K.R_GAMMA],  # a slice's copy
            contact_lobe=rec[:, K.R_KC].astype(int), theoretical_flow=qth, volumetric_efficiency=eta,
            port_mass_in=float(dvol[FL_MASS_IN]), port_mass_out=float(dvol[FL_MASS_OUT]))
