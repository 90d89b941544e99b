"""What goes in and out of :meth:`PumpModel.advance`: inputs (validated), state, outputs.

Everything is SI: rad, rad/s, Pa (absolute), m, m³/s, s.  :class:`Outputs`
exports to arrays and interpolates (``at``); plots live in :mod:`.plots`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..config import PumpConfig
from ..errors import InputError, check_finite
from ..hydraulics.oil import T_MAX_K, T_MIN_K
from ..units import bar_gauge_to_pa_abs, kelvin_to_celsius, rpm_to_rad_s
from . import kernel as K
from .params import N_FLOWS

__all__ = ["Inputs", "PumpState", "Outputs", "check_inputs", "check_oil_temperature", "RANGE_MARGIN", "widened", "widened_text"]


@dataclass(frozen=True)
class Inputs:
    """Operating inputs held over one ``advance`` call.

    Parameters
    ----------
    omega : float
        Shaft speed [rad/s], ≥ 0.
    p_suction : float
        Suction pressure, absolute [Pa].
    p_delivery : float
        Delivery pressure, absolute [Pa] (ignored in ``restriction`` mode,
        where the delivery pressure is a state).
    oil_temperature : float or None
        Oil temperature [K]; None: the config's reference temperature
        (``oil.reference_temperature_c``).  Without an ``oil`` section in the
        config the properties do not depend on it.
    """
    omega: float
    p_suction: float
    p_delivery: float
    oil_temperature: float | None = None


@dataclass(frozen=True)
class PumpState:
    """Everything ``advance`` carries from one call to the next."""
    t: float                    #: time [s]
    theta: float                #: shaft angle [rad] (unwrapped)
    log_density: np.ndarray     #: (N+1,) ln(ρ/ρ₀) of the chambers and the delivery volume [-]
    pressures: np.ndarray       #: (N+1,) the matching absolute pressures [Pa] (derived, for callers)
    eccentricity: np.ndarray    #: (2,) outer-gear centre displacement [m]
    counters: np.ndarray = field(default_factory=lambda: np.zeros(K.N_COUNTERS, dtype=np.int64))
    volumes: np.ndarray = field(default_factory=lambda: np.zeros(N_FLOWS))  #: ∫ flow dt per FL_* index [m³]
    swept_angle: float = 0.0    #: ∫ω dt since start [rad]
    substep: float = 0.0        #: proposed ROS2 sub-step for the next call [s] (0: the output step)
    #: the chamber pressures' recent range, highest − lowest sample, fading by 1/e per revolution [Pa]
    #: (the scale of the sub-step error control: :func:`.step_control.update_range`)
    pressure_range: float = 0.0
    #: (2,) velocity of the outer gear's last move that the chamber volumes have taken up, whose squeeze the next
    #: output step applies (:func:`.volumes.move_volumes`; zero with nominal volumes) [m/s]
    squeeze_velocity: np.ndarray = field(default_factory=lambda: np.zeros(2))
    #: (4,) the full film law's correction λ* − λ^lin [N] of the teeth's two reactions linearised at the free load and
    #: the indices of the two lobes they act on, as the set-up of the step from this state found them (the previous
    #: step's: its Josephy–Newton's start, :func:`.gear_coupling.warm_reactions`), so a call from this state sets that
    #: step up as the call that ended here did; zeros where none
    contact_correction: np.ndarray = field(default_factory=lambda: np.zeros(4))

    @property
    def counts(self) -> dict:
        """Solver steps and events so far."""
        c = self.counters
        return {"steps": int(c[K.C_STEPS]), "cavitation_clamps": int(c[K.C_CAVITATION]),
                "contact_unloaded": int(c[K.C_CONTACT_UNLOADED]),
                "housing_contact": int(c[K.C_HOUSING_CONTACT]),
                "gear_contact_corrections": int(c[K.C_GEAR_CONTACT]),
                "substeps": int(c[K.C_SUBSTEPS]), "rejected_substeps": int(c[K.C_REJECTED]),
                "solver_failures": int(c[K.C_FAILED]), "abandoned_steps": int(c[K.C_ABANDONED])}


@dataclass(frozen=True)
class Outputs:
    """Per-step outputs of one ``advance`` call (row i is the state after step i)."""
    t: np.ndarray                   #: time [s]
    theta: np.ndarray               #: shaft angle [rad]
    chamber_pressures: np.ndarray   #: (n, N) [Pa]
    chamber_peak_pressures: np.ndarray  #: (n, N) each chamber's highest pressure over the step ending at row i [Pa]
    delivery_pressure: np.ndarray   #: [Pa]
    #: net flow out of the delivery port at the step's end: the rate of the delivered volume from the stepper's stages
    #: (:func:`.kernel._delivery_flow`, docs/numerics.md) [m³/s]
    delivery_flow: np.ndarray
    suction_flow: np.ndarray        #: flow in through the suction port [m³/s]
    leak_suction_delivery: np.ndarray  #: [m³/s]
    leak_drain: np.ndarray          #: [m³/s]
    restriction_flow: np.ndarray    #: flow through the delivery restriction [m³/s]
    eccentricity: np.ndarray        #: (n, 2) outer-gear displacement [m]
    load: np.ndarray                #: (n, 2) load on the outer gear F_est [N]
    gaps: np.ndarray                #: (n, N) tooth-tip gap heights [m]
    inner_rotation: np.ndarray      #: γ [rad]
    contact_lobe: np.ndarray        #: index of the lobe in contact
    theoretical_flow: float         #: displacement × speed [m³/s]
    volumetric_efficiency: float    #: mean delivered / theoretical over this call [-]
    port_mass_in: float = 0.0       #: mass through the suction ports over this call / ρ₀ [m³]
    port_mass_out: float = 0.0      #: mass through the delivery ports over this call / ρ₀ [m³]

    def __len__(self) -> int:
        return self.t.size

    def at(self, times) -> dict:
        """Outputs at requested times [s] (linear interpolation between steps).

        Returns a dict of arrays keyed like the fields (per-chamber fields get
        shape (len(times), N); not ``chamber_peak_pressures``, a maximum over each
        step, which does not interpolate).  Times outside the call's span are an error.
        """
        t = np.atleast_1d(np.asarray(times, dtype=float))
        if self.t.size == 0 or t.min() < self.t[0] - 1e-12 or t.max() > self.t[-1] + 1e-12:
            raise InputError("times", [float(t.min()), float(t.max())],
                             f"[{self.t[0] if self.t.size else 0:g}, {self.t[-1] if self.t.size else 0:g}] s")
        out = {}
        for name in ("theta", "delivery_pressure", "delivery_flow", "suction_flow", "leak_suction_delivery",
                     "leak_drain", "restriction_flow", "inner_rotation"):
            out[name] = np.interp(t, self.t, getattr(self, name))
        for name in ("chamber_pressures", "eccentricity", "load", "gaps"):
            v = getattr(self, name)
            out[name] = np.column_stack([np.interp(t, self.t, v[:, k]) for k in range(v.shape[1])])
        out["t"] = t
        return out


#: Share beyond the rated range (``range.max_speed_rpm``, ``range.max_delivery_bar``) within which an input is run
#: [-]: a bench held at its rated point reads above it with every noisy sample, ripple or pressure overshoot, and
#: refusing those would hold the last sample below the limit (a biased input, 42 % of the samples counted as errors
#: at 27.5 bar ± 2 kPa, docs/node.md).
#: Nothing in the model is tabulated against the range; the error budget is measured at its ends
#: (docs/numerics.md, "The pump family").  Beyond the margin an input is refused.
RANGE_MARGIN = 0.1


def widened(rated: float) -> float:
    """The input envelope's limit for a ``rated`` maximum (rpm, bar gauge): rated·(1 + :data:`RANGE_MARGIN`)."""
    return rated * (1.0 + RANGE_MARGIN)


def widened_text(rated: float, unit: str) -> str:
    """How an error names that limit: "0–… unit: the rated … unit + 10 %" (built only for an error)."""
    return f"the rated {rated:g} {unit} + {100 * RANGE_MARGIN:g} %"


def check_inputs(config: PumpConfig, inputs: Inputs) -> Inputs:
    """``inputs`` checked against the envelope of ``config``: speed in [0, max], suction pressure in
    [0.1, 5] bar absolute, delivery pressure from 0.5 bar below the suction pressure to the range's (imposed mode),
    the maxima of speed and delivery pressure (gauge) widened by :data:`RANGE_MARGIN` [rad/s, Pa]; raise
    :class:`InputError` naming the field, value and allowed range."""
    rng, p_atm = config.range, config.fluid.atmospheric_pa
    w = check_finite("shaft_speed", inputs.omega)
    wmax = rpm_to_rad_s(widened(rng.max_speed_rpm))
    if not 0.0 <= w <= wmax:
        raise InputError("shaft_speed", w, f"[0, {wmax:.4g}] rad/s (0–{widened(rng.max_speed_rpm):g} rpm: "
                                           f"{widened_text(rng.max_speed_rpm, 'rpm')})")
    ps = check_finite("suction_pressure", inputs.p_suction)
    if not 1e4 <= ps <= 5e5:
        raise InputError("suction_pressure", ps, "[10000, 500000] Pa absolute")
    pd = check_finite("delivery_pressure", inputs.p_delivery)
    pmax = bar_gauge_to_pa_abs(widened(rng.max_delivery_bar), p_atm)
    if not (config.boundary.mode == "restriction" or ps - 0.5e5 <= pd <= pmax):
        raise InputError("delivery_pressure", pd, f"[{ps - 0.5e5:.6g}, {pmax:.6g}] Pa absolute (up to "
                         f"{widened(rng.max_delivery_bar):g} bar gauge: {widened_text(rng.max_delivery_bar, 'bar')})")
    return Inputs(w, ps, pd, check_oil_temperature(inputs.oil_temperature))


def check_oil_temperature(t_k: float | None) -> float | None:
    """The oil temperature [K] as a float in the range of the oil laws, None passed through; else
    :class:`InputError` naming ``oil_temperature``, the value and the range [K] (°C)."""
    if t_k is None:
        return None
    t = check_finite("oil_temperature", t_k)
    if not T_MIN_K <= t <= T_MAX_K:
        raise InputError("oil_temperature", t, f"[{T_MIN_K:g}, {T_MAX_K:g}] K "
                                               f"({kelvin_to_celsius(T_MIN_K):g}–{kelvin_to_celsius(T_MAX_K):g} °C)")
    return t
