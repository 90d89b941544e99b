"""Periodic steady state at a constant operating point, and its summary."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..config import Numerics
from ..errors import InputError
from ..units import P_ATM, bar_gauge_to_pa_abs, rpm_to_rad_s
from .pump import Inputs, Outputs, PumpModel, PumpState
from .records import widened, widened_text
from .volumetric import EdgeLosses

#: The settling test's defaults (:func:`run_steady`): the revolution mean's relative change [-], and the mean
#: eccentricity's change as a fraction of the housing clearance [-]
SETTLE_RTOL = 2e-4
SETTLE_ETOL = 2e-3

#: The defaults of the settings the log-density measure does not read (:func:`reference_config`).
_PRESSURE_MEASURE_ONLY = Numerics()

__all__ = ["SteadyResult", "run_steady", "reference_config", "min_open_gap", "effective_gap"]


def min_open_gap(gaps: np.ndarray, contact_lobe: np.ndarray) -> float:
    """Smallest tooth-tip gap [m] over the rows, each row's contact lobe left out.

    Under the sec. 3.7 rule one lobe touches at every step (gap 0), so the plain minimum is 0 and
    says nothing; this is how close the *other* tips come, the gaps that carry the tip leakage.

    Parameters
    ----------
    gaps : ndarray (n, N)
        Gap heights per output row and lobe [m] (``Outputs.gaps``).
    contact_lobe : ndarray (n,)
        Per row, the lobe with the smallest gap (``Outputs.contact_lobe``).
    """
    g = np.array(gaps, dtype=float)
    if g.size == 0 or g.shape[1] < 2:
        return math.nan
    g[np.arange(g.shape[0]), np.asarray(contact_lobe, dtype=int)] = np.inf
    return float(g.min())


def effective_gap(gaps: np.ndarray) -> float:
    r"""The uniform tooth-tip gap [m] with the same mean laminar conductance as ``gaps``.

    .. math::
        h_\mathrm{eff} = \langle h^3 \rangle^{1/3}

    over every output row and lobe: a slit's laminar conductance goes as h³ (plane Poiseuille),
    so this is the single gap a design study can compare, where the minimum is 0 under the
    sec. 3.7 rule.  Notes: it weights every lobe alike; the tip leakage also depends on each
    lobe's pressure difference, which this figure leaves out.
    """
    g = np.asarray(gaps, dtype=float)
    return float(np.cbrt(np.mean(g ** 3))) if g.size else math.nan


@dataclass(frozen=True)
class SteadyResult:
    """One revolution at periodic steady state, plus its figures of merit."""
    rpm: float
    bar: float
    model: str
    revolutions: int            #: revolutions simulated, the recorded (last) one included
    outputs: Outputs            #: the recorded revolution
    state: PumpState            #: state at its end
    theoretical_flow_m3s: float
    mean_delivery_flow_m3s: float
    volumetric_efficiency: float
    periodicity_error: float    #: relative change of the mean flow from the revolution before the recorded one [-]
    p_atm: float = P_ATM        #: atmospheric pressure of the pump config (gauge zero) [Pa]
    settled: bool = True        #: the settling test passed (False: ``max_revolutions`` came first)

    @property
    def flow_ripple(self) -> float:
        """(max − min)/mean of the delivery flow over the revolution [-]."""
        q = self.outputs.delivery_flow
        return float((q.max() - q.min()) / q.mean()) if q.mean() != 0 else float("nan")

    def summary(self) -> dict:
        """Plain-JSON figures (SI units, efficiency 0–1)."""
        o = self.outputs
        e = o.eccentricity
        return {
            "rpm": self.rpm, "bar": self.bar, "model": self.model,
            "theoretical_flow_m3s": self.theoretical_flow_m3s,
            "mean_delivery_flow_m3s": self.mean_delivery_flow_m3s,
            "volumetric_efficiency": self.volumetric_efficiency,
            "delivery_flow_ripple": self.flow_ripple,
            "min_chamber_pressure_pa": float(o.chamber_pressures.min()),
            "max_chamber_pressure_pa": float(o.chamber_peak_pressures.max()),   # between output angles too
            "mean_eccentricity_m": [float(e[:, 0].mean()), float(e[:, 1].mean())],
            "min_tooth_gap_m": float(o.gaps.min()),
            "min_open_tooth_gap_m": min_open_gap(o.gaps, o.contact_lobe),
            "effective_tooth_gap_m": effective_gap(o.gaps),
            "mean_delivery_pressure_pa": float(o.delivery_pressure.mean()),
            "revolutions": self.revolutions,
            "periodicity_error": self.periodicity_error,
            "settled": self.settled,
            "counts": self.state.counts,
        }


def reference_config(cfg, tolerance: float = 2e-7, max_step_deg: float = 0.25, max_step_s: float | None = None):
    """The same pump with tight solver settings: ``tolerance`` on ln(ρ/ρ₀) everywhere (the reference mode),
    and a work bound per output step (``max_substep_attempts``) an offline run never meets.  The settings of the
    pressure measure alone (``closing_tolerance``, ``log_density_tolerance``: :func:`.step_control.error_weights`)
    take their defaults, so a reference and its cache key (:mod:`.reference_cache`) do not depend on them."""
    n = cfg.numerics
    return replace(cfg, numerics=replace(n, tolerance=tolerance, max_step_deg=max_step_deg,
                                         max_step_s=n.max_step_s if max_step_s is None else max_step_s,
                                         error_measure="log_density",
                                         closing_tolerance=_PRESSURE_MEASURE_ONLY.closing_tolerance,
                                         log_density_tolerance=_PRESSURE_MEASURE_ONLY.log_density_tolerance,
                                         max_substep_attempts=1_000_000))


def _allowed_point(rng) -> dict:
    """The allowed speed and delivery pressure of a steady run, as its errors name them: the model's input envelope,
    the pump's rated range widened by :data:`.records.RANGE_MARGIN` (:func:`.records.widened`)."""
    return {"--rpm": f"(0, {widened(rng.max_speed_rpm):g}] rpm ({widened_text(rng.max_speed_rpm, 'rpm')})",
            "--bar": f"[0, {widened(rng.max_delivery_bar):g}] bar ({widened_text(rng.max_delivery_bar, 'bar')})"}


def run_steady(model: PumpModel, rpm: float, bar: float, max_revolutions: int = 30, min_revolutions: int = 3,
               rtol: float = SETTLE_RTOL, p_suction: float | None = None, progress=None,
               state: PumpState | None = None, etol: float = SETTLE_ETOL,
               oil_temperature: float | None = None) -> SteadyResult:
    """Run revolutions until the revolution-mean delivery flow settles; the settled revolution is the one recorded.

    The recorded revolution is the first, from the ``min_revolutions``-th on, whose mean changed by less than
    ``rtol`` from the revolution before (and its mean eccentricity by less than ``etol``), or the
    ``max_revolutions``-th: the usual test of a cyclic steady state, which takes the last cycle once two
    in a row agree.  Its error against the periodic state is of the order of that change.

    Parameters
    ----------
    model : PumpModel
        The pump.
    rpm : float
        Shaft speed [rpm] (> 0).
    bar : float
        Delivery gauge pressure [bar] (imposed mode; ignored in restriction mode).
    max_revolutions, min_revolutions : int
        At most and at least this many revolutions in all, the recorded one included.
    rtol : float
        Settling criterion on the relative change of the revolution mean [-].
    state : PumpState, optional
        Warm start (e.g. the periodic state of a cheaper outer-gear model); its time and
        angle are kept, its pressures and eccentricity are the initial guess.
    etol : float
        Settling criterion on the change of the revolution-mean eccentricity, as a
        fraction of the housing clearance c [-] (the outer gear settles more slowly
        than the pressures).
    oil_temperature : float, optional
        Oil temperature [K] (default: the config's reference temperature).
    """
    if not (math.isfinite(rpm) and rpm > 0):
        raise InputError("--rpm", rpm, _allowed_point(model.config.range)["--rpm"])
    if not math.isfinite(bar):
        raise InputError("--bar", bar, _allowed_point(model.config.range)["--bar"])
    p_atm = model.config.fluid.atmospheric_pa
    ps = model.config.boundary.suction_pressure_pa if p_suction is None else p_suction
    inputs = Inputs(rpm_to_rad_s(rpm), ps, bar_gauge_to_pa_abs(bar, p_atm), oil_temperature)
    try:
        inputs = model.check_inputs(inputs)
    except InputError as exc:
        name = {"shaft_speed": "--rpm", "delivery_pressure": "--bar",
                "oil_temperature": "--oil-temp"}.get(exc.field, exc.field)
        value = {"--rpm": rpm, "--bar": bar}.get(name, exc.value)
        raise InputError(name, value, _allowed_point(model.config.range).get(name, exc.allowed)) from None
    period = 2 * math.pi / inputs.omega
    state = model.initial_state(inputs) if state is None else state
    c = model.config.clearances.housing_radial_m
    last = last_e = None
    n = 0
    while True:
        state, out = model.advance(state, period, inputs)
        n += 1
        mean = out.volumetric_efficiency
        mean_e = out.eccentricity.mean(axis=0)
        change = float("inf") if last is None else max(
            abs(mean - last) / max(abs(mean), 1e-12), rtol * float(np.hypot(*(mean_e - last_e))) / (etol * c))
        if progress is not None:
            progress(n, change)
        settled = n >= min_revolutions and change < rtol
        if settled or n >= max_revolutions:
            break
        last, last_e = mean, mean_e
    eta = out.volumetric_efficiency         # the recorded revolution: the last, settled one
    final_change = abs(eta - last) / max(abs(eta), 1e-12) if last is not None else float("nan")
    qth = out.theoretical_flow
    edge = EdgeLosses.of(model.config, model.displacement)
    q = eta * qth - edge.flow(inputs.omega, float(np.mean(out.delivery_pressure)), inputs.p_suction)
    return SteadyResult(rpm=rpm, bar=bar, model=model.bearing_name, revolutions=n, outputs=out, state=state,
                        theoretical_flow_m3s=qth, mean_delivery_flow_m3s=q, volumetric_efficiency=q / qth,
                        periodicity_error=final_change, p_atm=p_atm, settled=settled)
