"""Benchmarks of the pump model (printed figures, never asserted in tests)."""
from __future__ import annotations

import math
import statistics
import time

from ..bearing.registry import MODEL_NAMES
from .pump import Inputs, PumpModel
from ..units import bar_gauge_to_pa_abs, rpm_to_rad_s

__all__ = ["realtime", "family_realtime", "models_cost", "advance_in_calls"]


def advance_in_calls(model, state, seconds: float, inputs, call_s: float | None = None):
    """``model`` advanced by ``seconds`` [s] from ``state`` in one ``advance`` call (``call_s`` None), or in calls of
    ``call_s`` [s] of model time each, as the node makes them (one per sample period); returns the last state."""
    if not call_s:
        return model.advance(state, seconds, inputs)[0]
    calls = max(1, int(round(seconds / call_s)))
    for _ in range(calls):
        state, _ = model.advance(state, seconds / calls, inputs)
    return state


def realtime(config, models=("fixed", "mobility"), speeds=(1000, 2000, 3000), bar=27.5, seconds=1.0,
             repeats=3, out=print, call_s: float | None = None) -> list[dict]:
    """Model-only real-time factor: simulated time / wall time, one core, after warm-up.

    Medians of ``repeats`` runs of ``seconds`` simulated at each speed and ``bar``, each in one ``advance`` call
    or, with ``call_s`` [s], in calls of that much model time (the node's sample period: then the figure includes
    each call's own cost, :func:`advance_in_calls`).  µs/sub-step: wall time of the last run per ROS2 sub-step
    attempted in it (accepted and rejected).
    """
    rows = []
    how = f"in calls of {1e3 * call_s:g} ms" if call_s else "in one call"
    out(f"real-time factor of the pump model ({bar:g} bar, {seconds:g} s simulated {how}, median of {repeats}; "
        f"RTF = simulated / wall time, CPU RTF = simulated / CPU time of this process)")
    out(f"  {'model':9s} {'rpm':>5s} {'bar':>5s} {'wall [s]':>9s} {'RTF':>6s} {'CPU RTF':>8s} {'sub-steps/rev':>14s} "
        f"{'µs/sub-step':>12s}")
    for name in models:
        m = PumpModel(config, name)
        for rpm in speeds:
            inp = Inputs(rpm_to_rad_s(rpm), config.boundary.suction_pressure_pa,
                         bar_gauge_to_pa_abs(bar, config.fluid.atmospheric_pa))
            s, _ = m.advance(m.initial_state(inp), 0.1, inp)     # warm-up (JIT, transient)
            walls, cpus = [], []
            for _ in range(repeats):
                c0, r0 = s.counts["substeps"], s.counts["rejected_substeps"]
                t0, p0 = time.perf_counter(), time.process_time()
                s = advance_in_calls(m, s, seconds, inp, call_s)
                walls.append(time.perf_counter() - t0)
                cpus.append(time.process_time() - p0)
            wall, cpu = statistics.median(walls), statistics.median(cpus)
            n_sub = s.counts["substeps"] - c0 + s.counts["rejected_substeps"] - r0
            sub = (s.counts["substeps"] - c0) / (seconds * rpm / 60)
            us = 1e6 * walls[-1] / max(n_sub, 1)
            rows.append({"model": name, "rpm": rpm, "bar": bar, "call_s": call_s, "wall_s": wall,
                         "real_time_factor": seconds / wall,
                         "cpu_real_time_factor": seconds / cpu, "substeps_per_revolution": sub,
                         "us_per_substep": us})
            out(f"  {name:9s} {rpm:5d} {bar:5.1f} {wall:9.3f} {seconds / wall:6.2f} {seconds / cpu:8.2f} {sub:14.0f} "
                f"{us:12.2f}")
    return rows


def family_realtime(config, models=("mobility",), seconds=1.0, repeats=3, out=print,
                    call_s: float | None = None) -> list[dict]:
    """:func:`realtime` of one family pump at its top speed and both ends of its delivery pressure.

    Parameters
    ----------
    config : PumpConfig
        The pump (its ``range`` gives the points, :func:`.family.speed_extremes`, :func:`.family.pressure_extremes`).
    models : sequence of str
        Gear models.
    seconds, repeats, call_s : float, int, float or None
        As :func:`realtime`.
    out : callable
        Where the printed table goes.

    Returns
    -------
    list of dict
        The :func:`realtime` rows, low pressure first.
    """
    from .family import pressure_extremes, speed_extremes

    top = int(round(speed_extremes(config)[1]))
    rows = []
    for bar in pressure_extremes(config):
        rows += realtime(config, models=models, speeds=(top,), bar=bar, seconds=seconds, repeats=repeats, out=out,
                         call_s=call_s)
    return rows


def models_cost(config, models=MODEL_NAMES, speeds=(1000, 3000), bar=27.5,
                revolutions=1, out=print) -> list[dict]:
    """Wall time per simulated revolution of each outer-gear model (sec. 4 of [1]: the cost).

    Each model starts from the periodic state of the mobility model at the same point
    (so the slow models are timed at their working point, not on a start-up transient),
    and is timed over ``revolutions`` revolutions after a one-step JIT warm-up.
    """
    from .steady import run_steady

    rows = []
    out(f"wall time per simulated revolution ({bar:g} bar, {revolutions} rev timed, one core)")
    out(f"  {'model':9s} {'rpm':>5s} {'wall/rev [s]':>13s} {'× mobility':>11s} {'real-time factor':>17s}")
    warm = {rpm: run_steady(PumpModel(config, "mobility"), rpm, bar).state for rpm in speeds}
    base = {}
    for name in models:
        m = PumpModel(config, name)
        for rpm in speeds:
            inp = Inputs(rpm_to_rad_s(rpm), config.boundary.suction_pressure_pa,
                         bar_gauge_to_pa_abs(bar, config.fluid.atmospheric_pa))
            period = 2 * math.pi / inp.omega
            s, _ = m.advance(warm[rpm], m.step_size(inp.omega), inp)      # JIT / first-call warm-up
            t0 = time.perf_counter()
            m.advance(s, revolutions * period, inp)
            wall = (time.perf_counter() - t0) / revolutions
            if name == "mobility":
                base[rpm] = wall
            rows.append({"model": name, "rpm": rpm, "wall_s_per_rev": wall, "real_time_factor": period / wall})
    for r in rows:
        r["relative_to_mobility"] = r["wall_s_per_rev"] / base[r["rpm"]] if base.get(r["rpm"]) else None
        rel = f"{r['relative_to_mobility']:11.2f}" if r["relative_to_mobility"] else f"{'-':>11s}"
        out(f"  {r['model']:9s} {r['rpm']:5d} {r['wall_s_per_rev']:13.4f} {rel} {r['real_time_factor']:17.3g}")
    return rows
