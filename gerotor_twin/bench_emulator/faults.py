"""Fault scenarios of the emulated bench (``synth-bench --fault KIND[,KIND] --fault-to X --fault-start S``).

A :class:`Fault` is one kind of fault with its severity ``to`` (unit per kind, :data:`FAULT_KINDS`),
the time it starts [s] and its ramp [s]: from ``start_s`` the fault's value moves linearly from "no
fault" to ``to`` over ``ramp_s`` and then holds; ``ramp_s = 0`` is a step.  Without a ramp
(``None``) a progressive kind (wear, air, restriction, drift) ramps until the end of the run and a
sudden one (pressure offset, speed dropout) steps.

=======================  ======================================  ========================  ===========
kind                     ``to`` means                            allowed                   default
=======================  ======================================  ========================  ===========
``tip_wear``             tooth-tip clearance × the emulated      [1, 3] [-]                1.5
                         pump's
``lateral_wear``         lateral clearance × the emulated        [1, 3] [-]                1.3
                         pump's
``housing_wear``         outer gear–housing radial clearance ×   [1, 3] [-]                2
                         the emulated pump's (kernel and the
                         outer gear's film)
``air_ingress``          free-air volume fraction at             [1e-6, 0.1] [-]           0.03
                         atmospheric pressure (from the
                         emulated pump's ``mixture.air_fraction``)
``suction_restriction``  suction pressure drop at the rated      [0, 6e4] [Pa]             2e4
                         flow; Δp = to·(Q_in/Q_rated)²
``pressure_offset``      added to the delivery-pressure          [-5e5, 5e5] [Pa]          2e4
                         transducer's samples
``speed_dropout``        fraction of the shaft-speed samples     [0, 1] [-]                0.2
                         missing
``flowmeter_drift``      flow-meter gain error: recorded flow    [-0.5, 0.5] [-]           0.05
                         × (1 + to) at the end of the ramp
=======================  ======================================  ========================  ===========

Where each acts: the pump kinds (wear, air) give the emulated pump new clearances and state
equation every :data:`~.emulator.WEAR_UPDATE_TICKS` ticks (0.1 s; the state keeps its pressures);
the suction restriction lowers the suction pressure the pump sees, with Q_in its intake flow
(mass in / ρ₀) through a first-order lag of :data:`SUCTION_FLOW_TAU_S` and Q_rated the
theoretical flow at ``range.max_speed_rpm``; the sensor kinds act on each sample at its time.
A dropped speed sample is not recorded (its noise and latency are still drawn, so the other
samples are those of the healthy run); the samples dropped are chosen by error diffusion, so after
n samples ⌊Σ fraction(tᵢ)⌋ are missing (a step of fraction f from the start: ⌊n·f⌋).
The gain error of ``flowmeter_drift`` multiplies the whole recorded sample (bias and noise
included): recorded / healthy = 1 + g(t), a drift of ``to / ramp_s`` per second during the ramp.

What the kernel cannot emulate: an outer-gear eccentricity that grows with housing wear (the outer gear
rests on the inner gear, the kernel's gear contact holds it where the tooth contact puts it, so a larger
housing clearance shows only as a small flow loss at high pressure); wear of one lobe or one tooth (one
tooth-tip clearance for every lobe); air ingress with ``fluid_model: paper`` (no free air in eq. (23)):
refused.  A fault holds its severity to the end of the run (a dropout window that ends is not a kind).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from gerotor_twin.errors import InputError, check_range
from gerotor_twin.model.clearance_scale import scaled_config

from .bench_pump import _value
from .sensors import FirstOrderLag

__all__ = ["Fault", "FaultKind", "FaultScenario", "FAULT_KINDS", "PUMP_KINDS", "SUCTION_FLOW_TAU_S",
           "parse_faults"]


@dataclass(frozen=True)
class FaultKind:
    """One kind of fault: what its severity means and which values are allowed.

    Attributes
    ----------
    lo, hi : float
        Allowed severity (unit ``unit``).
    unit : str
        Unit of the severity, as errors and the metadata say it.
    default_to : float
        Severity when ``--fault-to`` leaves it out.
    progressive : bool
        True: without a ramp it grows until the end of the run; False: a step at the start.
    none : float or None
        Value without the fault (None: the emulated pump's own, ``mixture.air_fraction``).
    meaning : str
        What the severity is.
    """
    lo: float
    hi: float
    unit: str
    default_to: float
    progressive: bool
    none: float | None
    meaning: str


#: The fault kinds by name (module docstring).
FAULT_KINDS: dict[str, FaultKind] = {
    "tip_wear": FaultKind(1.0, 3.0, "x tooth-tip clearance", 1.5, True, 1.0,
                          "tooth-tip clearance relative to the emulated pump's"),
    "lateral_wear": FaultKind(1.0, 3.0, "x lateral clearance", 1.3, True, 1.0,
                              "lateral (side-plate) clearance relative to the emulated pump's"),
    "housing_wear": FaultKind(1.0, 3.0, "x housing radial clearance", 2.0, True, 1.0,
                              "outer gear-housing radial clearance relative to the emulated pump's"),
    "air_ingress": FaultKind(1e-6, 0.1, "free-air volume fraction", 0.03, True, None,
                             "free-air volume fraction at atmospheric pressure"),
    "suction_restriction": FaultKind(0.0, 6.0e4, "Pa at rated flow", 2.0e4, True, 0.0,
                                     "suction pressure drop at the rated flow, growing with the flow squared"),
    "pressure_offset": FaultKind(-5.0e5, 5.0e5, "Pa", 2.0e4, False, 0.0,
                                 "offset of the delivery-pressure transducer"),
    "speed_dropout": FaultKind(0.0, 1.0, "fraction of samples", 0.2, False, 0.0,
                               "fraction of the shaft-speed samples missing"),
    "flowmeter_drift": FaultKind(-0.5, 0.5, "gain error", 0.05, True, 0.0,
                                 "flow-meter gain error reached at the end of the ramp"),
}
#: Kinds that change the emulated pump (its config, applied every WEAR_UPDATE_TICKS ticks).
PUMP_KINDS = ("tip_wear", "lateral_wear", "housing_wear", "air_ingress")
#: Time constant of the intake flow the suction restriction sees [s] (the suction line's inertia
#: and volume smooth the kidney's flow ripple).
SUCTION_FLOW_TAU_S = 0.02


@dataclass(frozen=True)
class Fault:
    """One fault of the emulated bench.

    Attributes
    ----------
    kind : str
        A key of :data:`FAULT_KINDS`.
    to : float
        Severity reached at ``start_s + ramp_s`` (unit: ``FAULT_KINDS[kind].unit``).
    start_s : float
        When the fault starts [s from the start of the recording].
    ramp_s : float or None
        How long it takes to reach ``to`` [s] (0: a step); None: the kind's default
        (:meth:`resolved`).
    """
    kind: str
    to: float
    start_s: float = 0.0
    ramp_s: float | None = None

    def __post_init__(self):
        if self.kind not in FAULT_KINDS:
            raise InputError("--fault", self.kind, " | ".join(FAULT_KINDS))
        k = FAULT_KINDS[self.kind]
        _value(self.to, f"--fault-to ({self.kind})", (k.lo, k.hi, k.unit))
        _value(self.start_s, f"--fault-start ({self.kind})", (0.0, math.inf, "s"))
        if self.ramp_s is not None:
            _value(self.ramp_s, f"--fault-ramp ({self.kind})", (0.0, math.inf, "s"))

    def resolved(self, duration_s: float) -> "Fault":
        """The ramp filled in for a run of ``duration_s`` [s]: until the end of the run for a progressive
        kind, 0 (a step) otherwise.

        Raises
        ------
        InputError
            ``start_s`` not before the end of the run.
        """
        check_range(f"--fault-start ({self.kind})", self.start_s, 0.0, duration_s, hi_open=True, unit="s")
        if self.ramp_s is not None:
            return self
        return replace(self, ramp_s=duration_s - self.start_s if FAULT_KINDS[self.kind].progressive else 0.0)

    def progress(self, t_s):
        """How far the fault has gone at time ``t_s`` [s] (scalar or array): 0 before ``start_s``, 1 from
        ``start_s + ramp_s`` on, linear between [-]."""
        t = np.asarray(t_s, dtype=float)
        if not self.ramp_s:
            out = (t >= self.start_s).astype(float)
        else:
            out = np.clip((t - self.start_s) / self.ramp_s, 0.0, 1.0)
        return float(out) if out.ndim == 0 else out

    def value(self, t_s, none: float | None = None):
        """The fault's value at ``t_s`` [s] (unit of the kind): from the value without it (``none``, default
        the kind's) towards ``to``."""
        base = FAULT_KINDS[self.kind].none if none is None else none
        if base is None:
            raise ValueError(f"{self.kind}: the value without the fault depends on the pump; pass it as none")
        return base + (self.to - base) * self.progress(t_s)

    def as_dict(self) -> dict:
        """Kind, severity, its unit and meaning, start, ramp and end [s] (for the metadata)."""
        k = FAULT_KINDS[self.kind]
        end = None if self.ramp_s is None else self.start_s + self.ramp_s
        return {**asdict(self), "end_s": end, "unit": k.unit, "meaning": k.meaning}


def _split(text: str, option: str) -> list[str]:
    items = [s.strip() for s in str(text).split(",")]
    if not all(items):
        raise InputError(option, text, "a comma-separated list without empty items")
    return items


def _numbers(text: str | None, option: str, n: int, one_for_all: bool) -> list[float | None]:
    """``n`` numbers from a comma-separated option: one per kind, or with ``one_for_all`` one value for all
    (None: n × None)."""
    if text is None:
        return [None] * n
    items = _split(text, option)
    if len(items) != n and not (one_for_all and len(items) == 1):
        raise InputError(option, text, f"one value, or {n} (one per --fault kind) separated by commas" if one_for_all
                         else f"{n} values (one per --fault kind) separated by commas")
    out = []
    for s in items:
        try:
            out.append(float(s))
        except ValueError:
            raise InputError(option, s, "a number") from None
    return out * n if len(out) == 1 else out


def parse_faults(kinds: str | None, to: str | None = None, start: str | None = None,
                 ramp: str | None = None) -> tuple[Fault, ...]:
    """The faults of the command line: ``--fault KIND[,KIND]`` with ``--fault-to``, ``--fault-start`` and
    ``--fault-ramp`` (comma-separated: one severity per kind; one start or ramp for all kinds or one per kind).

    ``--fault-to`` defaults to each kind's ``default_to``; ``--fault-start`` to 0 s; ``--fault-ramp``
    to the kind's default (:meth:`Fault.resolved`).  No ``--fault``: no fault, and the other three refused.

    Raises
    ------
    InputError
        An unknown or repeated kind, a count that does not match, a value outside its kind's range.
    """
    if kinds is None:
        for option, text in (("--fault-to", to), ("--fault-start", start), ("--fault-ramp", ramp)):
            if text is not None:
                raise InputError(option, text, "only with --fault KIND[,KIND]")
        return ()
    names = _split(kinds, "--fault")
    for i, name in enumerate(names):
        if name not in FAULT_KINDS:
            raise InputError("--fault", name, " | ".join(FAULT_KINDS))
        if name in names[:i]:
            raise InputError("--fault", kinds, "each kind once")
    tos, starts, ramps = (_numbers(t, o, len(names), o != "--fault-to") for t, o in
                          ((to, "--fault-to"), (start, "--fault-start"), (ramp, "--fault-ramp")))
    return tuple(Fault(name, FAULT_KINDS[name].default_to if x is None else x, s or 0.0, r)
                 for name, x, s, r in zip(names, tos, starts, ramps))


class FaultScenario:
    """The faults of one run, resolved for its duration, with what the emulator asks of them.

    Parameters
    ----------
    faults : sequence of Fault
        At most one per kind.
    duration_s : float
        Length of the run [s].
    """

    def __init__(self, faults=(), duration_s: float = 1.0):
        faults = tuple(faults)
        kinds = [f.kind for f in faults]
        if len(set(kinds)) != len(kinds):
            raise InputError("--fault", ",".join(kinds), "each kind once")
        self.faults = tuple(f.resolved(duration_s) for f in faults)
        self.by_kind = {f.kind: f for f in self.faults}
        self.duration_s = float(duration_s)

    def __bool__(self) -> bool:
        return bool(self.faults)

    @property
    def changes_pump(self) -> bool:
        """True when a fault changes the emulated pump's config (wear, air)."""
        return any(k in self.by_kind for k in PUMP_KINDS)

    def value(self, kind: str, t_s: float, none: float | None = None) -> float:
        """Value of ``kind`` at ``t_s`` [s]; the value without it (``none`` or the kind's) when absent."""
        f = self.by_kind.get(kind)
        if f is None:
            return FAULT_KINDS[kind].none if none is None else none
        return f.value(t_s, none)

    def pump_config(self, emulated, t_s: float, wear: float = 1.0):
        """The emulated pump at ``t_s`` [s]: ``emulated`` (a ``PumpConfig``) with the worn clearances (× ``wear``
        on tip and lateral, the ``--wear-to`` scenario's factor relative to the start [-]) and the free air."""
        return scaled_config(emulated, tip=wear * self.value("tip_wear", t_s),
                             lateral=wear * self.value("lateral_wear", t_s), housing=self.value("housing_wear", t_s),
                             air_fraction=self.value("air_ingress", t_s, emulated.air.air_fraction))

    def check(self, emulated, wear_end: float = 1.0) -> None:
        """Refuse, before any work, a fault the emulated pump (a ``PumpConfig``) cannot take: air ingress
        without the mixture model, a worn clearance outside the config's range at full severity (× the
        ``--wear-to`` factor ``wear_end`` [-])."""
        if "air_ingress" in self.by_kind and emulated.fluid_model != "mixture":
            raise InputError("--fault", "air_ingress", "a pump with fluid_model: mixture",
                             f"fluid_model is {emulated.fluid_model}: eq. (23) has no free air")
        for t in (0.0, math.inf):
            try:
                self.pump_config(emulated, t, wear_end if t else 1.0)
            except InputError as e:
                kinds = ",".join(k for k in PUMP_KINDS if k in self.by_kind)
                why = "at full severity" + (", with --wear-to" if wear_end != 1.0 else "")
                raise InputError(f"--fault-to ({kinds}): emulated pump {e.field}", e.value, e.allowed, why) from None

    def dropped(self, t_s: np.ndarray) -> np.ndarray:
        """Which shaft-speed samples at times ``t_s`` [s] are missing (bool array): error diffusion of the
        dropout fraction, so ⌊Σ fraction(tᵢ)⌋ samples up to each are missing."""
        t = np.asarray(t_s, dtype=float)
        frac = np.broadcast_to(self.value("speed_dropout", t), t.shape)
        count = np.floor(np.cumsum(frac) + 1e-9)
        return np.diff(count, prepend=0.0) > 0

    def speed_dropped(self, decimation: int, dt: float) -> np.ndarray:
        """Which of the run's shaft-speed samples (one every ``decimation`` ticks of ``dt`` [s], the first at
        ``decimation·dt``) are missing (bool array, :meth:`dropped`)."""
        n_ticks = int(round(self.duration_s / dt))
        return self.dropped(np.arange(decimation, n_ticks + 1, decimation) * dt)

    def series(self, step_ticks: int, dt: float, air_fraction: float) -> dict[str, list[float]]:
        """Every fault's value every ``step_ticks`` ticks of ``dt`` [s] over the run (the truth, unit per kind; air
        ingress from the emulated pump's ``air_fraction`` [-]); ``tick``: the tick index of each time."""
        ticks = np.arange(0, int(round(self.duration_s / dt)) + 1, step_ticks)
        t = ticks * dt
        out = {"t_s": t.tolist(), "tick": ticks.tolist()}
        for f in self.faults:
            v = f.value(t, air_fraction if f.kind == "air_ingress" else None)
            out[f.kind] = np.atleast_1d(v).tolist()
        return out

    def as_dict(self) -> list[dict]:
        """Each fault's description (:meth:`Fault.as_dict`)."""
        return [f.as_dict() for f in self.faults]


class SuctionRestriction:
    """The ``suction_restriction`` fault's pressure drop at the pump's inlet [Pa]: to(t)·(Q_in/Q_rated)², with
    Q_in the intake flow through a first-order lag of :data:`SUCTION_FLOW_TAU_S` (0 without the fault).

    Parameters
    ----------
    scenario : FaultScenario
        The run's faults.
    q_rated : float
        Rated flow: theoretical flow at the top of the pump's range [m³/s].
    dt : float
        Tick [s].
    q0 : float
        Intake flow at the start [m³/s].
    """

    def __init__(self, scenario: FaultScenario, q_rated: float, dt: float, q0: float):
        self.fault = scenario.by_kind.get("suction_restriction")
        self.q_rated = q_rated
        self.flow = FirstOrderLag(SUCTION_FLOW_TAU_S, dt, q0)

    def drop(self, t_s: float) -> float:
        """Pressure drop at time ``t_s`` [s] for the intake flow so far [Pa]."""
        return 0.0 if self.fault is None else self.fault.value(t_s) * (self.flow.y / self.q_rated) ** 2

    def feed(self, q_in: float) -> None:
        """The intake flow of the last tick [m³/s]."""
        if self.fault is not None:
            self.flow(q_in)
