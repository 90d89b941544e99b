"""Operating profiles of the emulated bench: set-points of shaft speed and delivery pressure.

A :class:`Profile` is a list of :class:`Segment` s; each segment holds or
ramps linearly from the previous set-point to its own over its duration.
The set-points are what the bench operator asks for; the emulated motor and
pressure valve follow them with their own dynamics (see
:mod:`~gerotor_twin.bench_emulator.emulator`).

Built-in profiles (``gerotor-twin synth-bench --profile NAME``):

=============  ==============================================================
``map``        speed/pressure map: plateaus at 1000, 2000, 2950 rpm × 5, 12.5,
               20, 27 bar gauge (serpentine order), 10 s each, joined by 2 s
               ramps; 146 s
``transient``  1000 rpm / 10 bar, speed ramp to 2500 rpm in 5 s, delivery
               pressure steps 10 → 20 → 5 bar, speed ramp down to 1500 rpm; 26 s
``wear``       durability cycle for the wear scenario: 1500 rpm / 20 bar (8 s), then
               three times 2500 rpm / 10 bar and back (1 s ramps, 7 s holds), ending at
               2000 rpm / 15 bar; 64 s (use with ``--wear-to``)
``test``       0.4 s at 1000 rpm with a pressure step (unit tests)
=============  ==============================================================
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gerotor_twin.errors import InputError

__all__ = ["Segment", "Profile", "PROFILES", "get_profile"]

_BAR = 1e5
_RPM = math.pi / 30.0


@dataclass(frozen=True)
class Segment:
    """One piece of a profile.

    Parameters
    ----------
    duration_s : float
        Length [s] (> 0).
    rpm : float
        Speed set-point reached at the end of the segment [rpm].
    bar : float
        Delivery pressure set-point reached at the end [bar gauge].
    ramp : bool
        True: ramp linearly from the previous set-point; False: step at the start, then hold.
    """
    duration_s: float
    rpm: float
    bar: float
    ramp: bool = False


@dataclass(frozen=True)
class Profile:
    """A named sequence of segments starting from ``segments[0]``'s set-point."""
    name: str
    segments: tuple[Segment, ...]
    description: str = ""

    def __post_init__(self):
        if not self.segments:
            raise InputError("profile.segments", [], "at least one segment")
        for i, s in enumerate(self.segments):
            if not (math.isfinite(s.duration_s) and s.duration_s > 0):
                raise InputError(f"profile.segments[{i}].duration_s", s.duration_s, "(0, inf) s")
            if not 0 <= s.rpm <= 3000:
                raise InputError(f"profile.segments[{i}].rpm", s.rpm, "[0, 3000] rpm")
            if not 0 <= s.bar <= 27.5:
                raise InputError(f"profile.segments[{i}].bar", s.bar, "[0, 27.5] bar gauge")

    @property
    def duration_s(self) -> float:
        """Total length [s]."""
        return float(sum(s.duration_s for s in self.segments))

    def _knots(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Break points of the piecewise-linear set-points: time [s], speed [rad/s], gauge [Pa]."""
        t, w, p = [0.0], [self.segments[0].rpm * _RPM], [self.segments[0].bar * _BAR]
        for s in self.segments:
            t0 = t[-1]
            if not s.ramp:   # step: jump at the segment start (a 1 µs ramp keeps it a function)
                t.append(t0 + 1e-6)
                w.append(s.rpm * _RPM)
                p.append(s.bar * _BAR)
            t.append(t0 + s.duration_s)
            w.append(s.rpm * _RPM)
            p.append(s.bar * _BAR)
        return np.array(t), np.array(w), np.array(p)

    def setpoints(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Speed [rad/s] and delivery gauge pressure [Pa] set-points at times ``t_s`` [s]."""
        kt, kw, kp = self._knots()
        t = np.asarray(t_s, dtype=float)
        return np.interp(t, kt, kw), np.interp(t, kt, kp)

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


def _map_profile() -> Profile:
    speeds = (1000.0, 2000.0, 2950.0)
    pressures = (5.0, 12.5, 20.0, 27.0)
    segs = [Segment(10.0, speeds[0], pressures[0])]
    for i, rpm in enumerate(speeds):
        order = pressures if i % 2 == 0 else pressures[::-1]
        for j, bar in enumerate(order):
            if i == 0 and j == 0:
                continue
            segs.append(Segment(2.0, rpm, bar, ramp=True))
            segs.append(Segment(10.0, rpm, bar))
    return Profile("map", tuple(segs), "speed/pressure map: 3 speeds x 4 pressures, 10 s plateaus, 2 s ramps")


def _transient_profile() -> Profile:
    segs = (Segment(3.0, 1000, 10), Segment(5.0, 2500, 10, ramp=True), Segment(4.0, 2500, 10),
            Segment(6.0, 2500, 20), Segment(4.0, 2500, 5), Segment(2.0, 1500, 5, ramp=True),
            Segment(2.0, 1500, 5))
    return Profile("transient", segs, "speed ramp 1000->2500 rpm, pressure steps 10->20->5 bar, ramp down")


def _test_profile() -> Profile:
    return Profile("test", (Segment(0.2, 1000, 10), Segment(0.2, 1000, 15)), "unit-test profile")


def _wear_profile() -> Profile:
    segs = [Segment(8.0, 1500, 20)]
    for _ in range(3):
        segs += [Segment(1.0, 2500, 10, ramp=True), Segment(7.0, 2500, 10),
                 Segment(1.0, 1500, 20, ramp=True), Segment(7.0, 1500, 20)]
    segs += [Segment(1.0, 2000, 15, ramp=True), Segment(7.0, 2000, 15)]
    return Profile("wear", tuple(segs), "durability cycle 1500/20 <-> 2500/10 (7 s holds, 1 s ramps), 64 s")


PROFILES = {"map": _map_profile, "transient": _transient_profile, "wear": _wear_profile, "test": _test_profile}


def get_profile(name: str) -> Profile:
    """A built-in profile by name (InputError listing the names otherwise)."""
    if name not in PROFILES:
        raise InputError("--profile", name, " | ".join(PROFILES))
    return PROFILES[name]()
