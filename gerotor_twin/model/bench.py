"""Benchmarks of the pump model (printed figures, never asserted in tests)."""
from __future__ import annotations

import math
import statistics
import time

from .pump import Inputs, PumpModel

__all__ = ["realtime"]


def realtime(config, models=("fixed", "mobility"), speeds=(1000, 2000, 3000), bar=27.5, seconds=1.0,
             repeats=3, out=print) -> list[dict]:
    """Model-only real-time factor: simulated time / wall time, one core, after warm-up.

    Medians of ``repeats`` runs of ``seconds`` simulated at each speed and ``bar``.
    """
    rows = []
    out(f"real-time factor of the pump model ({bar:g} bar, {seconds:g} s simulated, median of {repeats})")
    out(f"  {'model':9s} {'rpm':>5s} {'wall [s]':>9s} {'RTF':>6s} {'sub-steps/s':>12s}")
    for name in models:
        m = PumpModel(config, name)
        for rpm in speeds:
            inp = Inputs(rpm * math.pi / 30, config.boundary.suction_pressure_pa,
                         config.fluid.atmospheric_pa + bar * 1e5)
            s, _ = m.advance(m.initial_state(inp), 0.1, inp)     # warm-up (JIT, transient)
            walls = []
            for _ in range(repeats):
                c0 = s.counts["substeps"]
                t0 = time.perf_counter()
                s, _ = m.advance(s, seconds, inp)
                walls.append(time.perf_counter() - t0)
            wall = statistics.median(walls)
            sub = (s.counts["substeps"] - c0) / seconds
            rows.append({"model": name, "rpm": rpm, "wall_s": wall, "real_time_factor": seconds / wall,
                         "substeps_per_s": sub})
            out(f"  {name:9s} {rpm:5d} {wall:9.3f} {seconds / wall:6.2f} {sub:12.0f}")
    return rows
