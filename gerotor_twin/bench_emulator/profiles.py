"""Operating profiles of the emulated bench: set-points of shaft speed, delivery pressure, oil temperature.

A :class:`Profile` is a list of :class:`Segment` s; each segment holds or
ramps linearly from the previous set-point to its own over its duration.
The set-points are what the bench operator asks for; the emulated motor and
pressure valve follow them with their own dynamics, the oil temperature
follows its set-point through the sump's warm-up time constant (see
:mod:`~gerotor_twin.bench_emulator.emulator` and
:class:`~gerotor_twin.bench_emulator.sensors.OilBath`).  Every set-point must
lie in the pump's ``range`` (``[0, range.max_speed_rpm]``, ``[0,
range.max_delivery_bar]``).

Built-in profiles (``gerotor-twin synth-bench --profile NAME``), written for
the :data:`REFERENCE_RANGE` (``config/pump.yaml``: 3000 rpm, 27.5 bar) and
scaled to the pump's range by :func:`scale_to_range`:

=============  ==============================================================
``map``        speed/pressure map: plateaus at 1000, 2000, 2950 rpm × 5, 12.5,
               20, 27 bar gauge (serpentine order), 10 s each, joined by 2 s
               ramps; 142 s
``transient``  1000 rpm / 10 bar, speed ramp to 2500 rpm in 5 s, delivery
               pressure steps 10 → 20 → 5 bar, speed ramp down to 1500 rpm; 26 s
``wear``       durability cycle for the wear scenario: 1500 rpm / 20 bar (8 s), then
               three times 2500 rpm / 10 bar and back (1 s ramps, 7 s holds), ending at
               2000 rpm / 15 bar; 64 s (use with ``--wear-to``)
``diagnosis``  the fault classifier's four plateaus: 1000 / 2500 rpm × 5 / 25 bar,
               2.5 s each at 50 °C oil, the four visited twice; 20 s
               (``config/profiles/diagnosis.yaml``, written for the reference range
               like the others)
``test``       0.4 s at 1000 rpm with a pressure step (unit tests)
=============  ==============================================================

A user's profile comes from a YAML file (:mod:`.profile_file`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gerotor_twin.config import OperatingRange
from gerotor_twin.errors import InputError
from gerotor_twin.hydraulics.oil import T_MAX_K, T_MIN_K
from gerotor_twin.units import kelvin_to_celsius

__all__ = ["Segment", "Profile", "PROFILES", "get_profile", "scale_to_range", "REFERENCE_RANGE",
           "MAX_PROFILE_S", "MIN_SEGMENT_S", "OIL_RANGE_C"]

_BAR = 1e5
_RPM = math.pi / 30.0
#: The range the built-in profiles are written for (that of ``config/pump.yaml``).
REFERENCE_RANGE = OperatingRange(max_speed_rpm=3000.0, max_delivery_bar=27.5)
#: Lowest speed of the built-in profiles on the reference range [rpm]: a third of its maximum.
REFERENCE_LOW_RPM = 1000.0
#: Longest profile [s]: the emulator keeps four arrays per 1 ms tick and needs about 2 min of
#: CPU per simulated minute at 2000 rpm.
MAX_PROFILE_S = 3600.0
#: Shortest segment [s]: one emulator tick.
MIN_SEGMENT_S = 1e-3
#: Oil temperatures the oil laws accept [°C].
OIL_RANGE_C = (kelvin_to_celsius(T_MIN_K), kelvin_to_celsius(T_MAX_K))
_STEP_S = 1e-6   # a step is a ramp this short (keeps the set-points a function of time)


@dataclass(frozen=True)
class Segment:
    """One piece of a profile.

    Parameters
    ----------
    duration_s : float
        Length [s] (≥ :data:`MIN_SEGMENT_S`).
    rpm : float
        Speed set-point reached at the end of the segment [rpm].
    bar : float
        Delivery pressure set-point reached at the end [bar gauge].
    ramp : bool
        True: ramp linearly from the previous set-point; False: step at the start, then hold.
    oil_temperature_c : float or None
        Oil temperature set-point reached at the end [°C] (ramped or stepped like the
        others); None: keep the previous one (before the first: the bench's warm-up target,
        ``BenchSpec.temperature_end_c``).
    """
    duration_s: float
    rpm: float
    bar: float
    ramp: bool = False
    oil_temperature_c: float | None = None

    def as_dict(self) -> dict:
        """The fields as a mapping (``oil_temperature_c`` only when set), for metadata."""
        d = {"duration_s": self.duration_s, "rpm": self.rpm, "bar": self.bar, "ramp": self.ramp}
        return d if self.oil_temperature_c is None else {**d, "oil_temperature_c": self.oil_temperature_c}


def check_segments(segments, limits: OperatingRange, where: str = "profile.") -> None:
    """Durations, total length, and every set-point inside ``limits``; else :class:`InputError` naming
    ``{where}segments[i].<field>``, the value and the allowed range."""
    if not segments:
        raise InputError(f"{where}segments", [], "at least one segment")
    total = 0.0
    for i, s in enumerate(segments):
        f = f"{where}segments[{i}]."
        if not (math.isfinite(s.duration_s) and MIN_SEGMENT_S <= s.duration_s <= MAX_PROFILE_S):
            raise InputError(f + "duration_s", s.duration_s, f"[{MIN_SEGMENT_S:g}, {MAX_PROFILE_S:g}] s")
        if not 0 <= s.rpm <= limits.max_speed_rpm:
            raise InputError(f + "rpm", s.rpm, f"[0, {limits.max_speed_rpm:g}] rpm",
                             "the pump's range.max_speed_rpm")
        if not 0 <= s.bar <= limits.max_delivery_bar:
            raise InputError(f + "bar", s.bar, f"[0, {limits.max_delivery_bar:g}] bar gauge",
                             "the pump's range.max_delivery_bar")
        t = s.oil_temperature_c
        if t is not None and not OIL_RANGE_C[0] <= t <= OIL_RANGE_C[1]:
            raise InputError(f + "oil_temperature_c", t, f"[{OIL_RANGE_C[0]:g}, {OIL_RANGE_C[1]:g}] °C",
                             "the range of the oil laws")
        total += s.duration_s
        if total > MAX_PROFILE_S:
            raise InputError(f + "duration_s", s.duration_s, f"a total of at most {MAX_PROFILE_S:g} s",
                             f"the segments up to here last {total:g} s")


@dataclass(frozen=True)
class Profile:
    """A named sequence of segments starting from ``segments[0]``'s set-point.

    ``limits`` is the range the set-points are checked against (default: that of
    ``config/pump.yaml``); ``where`` prefixes the field names of errors; ``source`` is the
    text of the profile file it came from ("" for a built-in profile).
    """
    name: str
    segments: tuple[Segment, ...]
    description: str = ""
    limits: OperatingRange = REFERENCE_RANGE
    where: str = "profile."
    source: str = ""

    def __post_init__(self):
        check_segments(self.segments, self.limits, self.where)

    def check_within(self, limits: OperatingRange) -> None:
        """InputError unless every set-point lies in ``limits`` (the emulated pump's range)."""
        check_segments(self.segments, limits, self.where)

    @property
    def duration_s(self) -> float:
        """Total length [s]."""
        return float(sum(s.duration_s for s in self.segments))

    @property
    def has_oil_temperature(self) -> bool:
        """True when a segment sets the oil temperature."""
        return any(s.oil_temperature_c is not None for s in self.segments)

    def _knots_of(self, values) -> tuple[np.ndarray, np.ndarray]:
        """Break points (time [s], value) of the piecewise-linear set-point taking ``values[i]`` at
        the end of segment i (and ``values[0]`` at the start)."""
        t, v = [0.0], [values[0]]
        for s, x in zip(self.segments, values):
            t0 = t[-1]
            if not s.ramp:   # step: jump at the segment start (a 1 µs ramp keeps it a function)
                t.append(t0 + _STEP_S)
                v.append(x)
            t.append(t0 + s.duration_s)
            v.append(x)
        return np.array(t), np.array(v, dtype=float)

    def setpoints(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Speed [rad/s] and delivery gauge pressure [Pa] set-points at times ``t_s`` [s]."""
        kt, kw = self._knots_of([s.rpm * _RPM for s in self.segments])
        _, kp = self._knots_of([s.bar * _BAR for s in self.segments])
        t = np.asarray(t_s, dtype=float)
        return np.interp(t, kt, kw), np.interp(t, kt, kp)

    def oil_knots(self, before_c: float) -> tuple[np.ndarray, np.ndarray]:
        """Break points of the oil temperature set-point: time [s], temperature [°C].

        A segment without ``oil_temperature_c`` keeps the previous set-point; before the first
        segment that has one the set-point is ``before_c`` [°C].
        """
        values, cur = [], before_c
        for s in self.segments:
            cur = cur if s.oil_temperature_c is None else s.oil_temperature_c
            values.append(cur)
        return self._knots_of(values)

    def plateaus(self, min_s: float = 2.0) -> list[tuple[float, float, float, float]]:
        """Constant set-point stretches of at least ``min_s`` [s]: (t0, t1 [s], rpm, bar)."""
        out, t = [], 0.0
        prev = (self.segments[0].rpm, self.segments[0].bar)
        for s in self.segments:
            hold = (not s.ramp) or (s.rpm, s.bar) == prev
            if hold and s.duration_s >= min_s:
                out.append((t, t + s.duration_s, s.rpm, s.bar))
            prev = (s.rpm, s.bar)
            t += s.duration_s
        return out


def _round_in_range(x: float, top: float, lo: float, hi: float) -> float:
    """``x`` rounded to three significant digits of ``top`` (10 rpm for 3000 rpm, 0.1 bar for 27.5 bar,
    0.01 bar for 5 bar), unless that leaves [lo, hi): then ``x`` itself."""
    r = round(x, 2 - math.floor(math.log10(top)))
    return float(r) if lo <= r < hi else float(x)


def scale_to_range(rpm: float, bar: float, limits: OperatingRange) -> tuple[float, float]:
    """A set-point of a built-in profile (written for :data:`REFERENCE_RANGE`) on a pump of range ``limits``.

    Speed: the reference speeds [1000, 3000] rpm map linearly onto [low, max_speed_rpm], where low is
    ``range.min_speed_rpm`` or, without one, a third of the maximum (as on the reference pump).
    Pressure: the same fraction of ``max_delivery_bar``.  Both rounded to three significant digits
    of the maximum, inside the range.  The reference range gives the reference values exactly.

    Parameters
    ----------
    rpm : float
        Speed on the reference range [rpm] (≥ 1000).
    bar : float
        Delivery pressure on the reference range [bar gauge].
    limits : OperatingRange
        The pump's range ([rpm], [bar]).

    Returns
    -------
    tuple of float
        Speed [rpm] and delivery pressure [bar gauge] for the pump.
    """
    ref, top_w = REFERENCE_RANGE, limits.max_speed_rpm
    low = limits.min_speed_rpm if limits.min_speed_rpm is not None else top_w * REFERENCE_LOW_RPM / ref.max_speed_rpm
    w = low + (rpm - REFERENCE_LOW_RPM) * (top_w - low) / (ref.max_speed_rpm - REFERENCE_LOW_RPM)
    p = bar * limits.max_delivery_bar / ref.max_delivery_bar
    return (_round_in_range(w, top_w, limits.min_speed_rpm or 0.0, top_w),
            _round_in_range(p, limits.max_delivery_bar, 0.0, limits.max_delivery_bar))


# Built-in profiles on the reference range: (duration [s], rpm, bar, ramp).
def _map_segments() -> list[tuple]:
    speeds = (1000.0, 2000.0, 2950.0)
    pressures = (5.0, 12.5, 20.0, 27.0)
    segs = [(10.0, speeds[0], pressures[0], False)]
    for i, rpm in enumerate(speeds):
        order = pressures if i % 2 == 0 else pressures[::-1]
        for j, bar in enumerate(order):
            if i == 0 and j == 0:
                continue
            segs.append((2.0, rpm, bar, True))
            segs.append((10.0, rpm, bar, False))
    return segs


def _transient_segments() -> list[tuple]:
    return [(3.0, 1000, 10, False), (5.0, 2500, 10, True), (4.0, 2500, 10, False), (6.0, 2500, 20, False),
            (4.0, 2500, 5, False), (2.0, 1500, 5, True), (2.0, 1500, 5, False)]


def _wear_segments() -> list[tuple]:
    segs = [(8.0, 1500, 20, False)]
    for _ in range(3):
        segs += [(1.0, 2500, 10, True), (7.0, 2500, 10, False), (1.0, 1500, 20, True), (7.0, 1500, 20, False)]
    return segs + [(1.0, 2000, 15, True), (7.0, 2000, 15, False)]


def _test_segments() -> list[tuple]:
    return [(0.2, 1000, 10, False), (0.2, 1000, 15, False)]


def _diagnosis_segments() -> list[tuple]:
    """The fault classifier's profile (duration, rpm, bar, ramp, oil [°C]): two speeds × two delivery pressures at
    50 °C oil, the four points visited twice, so that a fault growing in time is not the same columns as a loss
    that depends on the operating point (docs/calibration_health.md, "Fault diagnosis"); the same segments as
    ``config/profiles/diagnosis.yaml``, the file form to copy (a test holds them equal)."""
    first = [(2.5, 1000, 5, False, 50.0), (2.5, 1000, 25, False, None), (2.5, 2500, 25, False, None),
             (2.5, 2500, 5, False, None)]
    return first + [first[0][:4] + (None,)] + first[1:]


#: name → (segments on the reference range, description)
PROFILES = {
    "map": (_map_segments, "speed/pressure map: 3 speeds x 4 pressures, 10 s plateaus, 2 s ramps"),
    "transient": (_transient_segments, "speed ramp 1000->2500 rpm, pressure steps 10->20->5 bar, ramp down"),
    "wear": (_wear_segments, "durability cycle 1500/20 <-> 2500/10 (7 s holds, 1 s ramps), 64 s"),
    "diagnosis": (_diagnosis_segments, "fault diagnosis: 1000/2500 rpm x 5/25 bar, 2.5 s each, visited twice, "
                                       "oil 50 C, 20 s"),
    "test": (_test_segments, "unit-test profile"),
}


def get_profile(name: str, limits: OperatingRange | None = None) -> Profile:
    """A built-in profile by name, scaled to the pump's range ``limits`` (default: the reference range,
    that of ``config/pump.yaml``); InputError listing the names otherwise."""
    if name not in PROFILES:
        raise InputError("--profile", name, " | ".join(PROFILES))
    limits = limits or REFERENCE_RANGE
    make, description = PROFILES[name]
    rows = make()
    if limits != REFERENCE_RANGE:      # on the reference range as written (scale_to_range: the identity there)
        rows = [(d, *scale_to_range(rpm, bar, limits), *rest) for d, rpm, bar, *rest in rows]
        description += (f" (scaled to 0-{limits.max_speed_rpm:g} rpm, 0-{limits.max_delivery_bar:g} bar"
                        + (f", from {limits.min_speed_rpm:g} rpm" if limits.min_speed_rpm is not None else "") + ")")
    return Profile(name, tuple(Segment(*row) for row in rows), description, limits)
