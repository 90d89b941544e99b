"""Where an output step's time goes: each part of the compiled stepper timed alone at a periodic state.

``gerotor-twin bench parts`` (printed figures, never asserted in tests).  At an operating point the model is
run to its periodic state; then each part below is called in a compiled loop at that state and timed (the
fastest of several batches, so another process on the machine inflates the figures less), the shaft angle one
output step further at each call, so that the calls read the table rows a revolution reads (at one angle the
rows would stay in the L1 cache), and the whole
output step is timed through :meth:`~.pump.PumpModel.advance` over a revolution with the counts of accepted
and rejected sub-steps per output step.  The parts are those the stepper calls (:mod:`.kernel`):

* ``rhs_jacobian``: the right-hand side with ∂f/∂(y, t) (:func:`.flows.rhs`), the first stage's core;
* ``rhs``: the right-hand side alone, the second stage's;
* ``first_stage``: :func:`.kernel._first_stage` (``rhs_jacobian``, the closing ports, the error weights, the
  peaks, the flow integrals), once per accepted sub-step;
* ``ros2_step``: :func:`.kernel.ros2_step` (W = I − γhJ, its LU, the two stage solves, the second stage's
  right-hand side, the error norm), once per attempted sub-step;
* ``lu``: the W build, its LU and two solves alone, part of ``ros2_step``;
* ``contact``: the tooth-tip gaps at the step's end (:func:`.contact.contact`), and ``linearise``: the
  mobility gear's velocity linearised for the next step (:func:`.gear_coupling.linearise`), once per output
  step each.

``accounted`` = accepted × ``first_stage`` + attempted × ``ros2_step`` per output step; the rest of the
output step (``other``) is the per-step work: the gear's move, the overlap check, the volumes, the records.
"""
from __future__ import annotations

import math
import time

import numba
import numpy as np

from ..units import bar_gauge_to_pa_abs, rpm_to_rad_s
from . import kernel as K
from .contact import contact
from .flows import rhs
from .gear_coupling import linearise
from .params import CT_PENDING, operating
from .pump import Inputs, PumpModel

__all__ = ["PARTS", "time_parts", "print_parts", "parts_markdown"]

#: The loops compile on each run, not cached: numba checks a cached function against its own file only, and a
#: cached loop would keep timing an old kernel; importing ``_jit`` instead would put this module into the kernel's
#: hashed sources, so that editing it would recompile the whole model (:mod:`gerotor_twin._jit`).
njit = numba.njit(error_model="numpy")

#: The timed parts, in the order they are printed.
PARTS = ("rhs_jacobian", "rhs", "first_stage", "ros2_step", "lu", "contact", "linearise")


@njit
def _loop_rhs(y, th, dth, km, op, ws, want_jac, reps):
    for r in range(reps):
        rhs(y, th + r * dth, ws.gaps0, km, op, ws, ws.f1, ws.jac, want_jac)


@njit
def _loop_first_stage(y, th, dth, km, op, ws, integrals, big_h, reps):
    for r in range(reps):
        ws.ctrl[CT_PENDING] = 0.0
        K._first_stage(y, th + r * dth, km, op, ws, integrals, big_h)


@njit
def _loop_ros2_step(y, th, h, km, op, ws, reps):
    en = 0.0
    for _ in range(reps):
        en += K.ros2_step(y, th + op.omega * h, h, km, op, ws)
    return en


@njit
def _loop_lu(h, ws, reps):
    n1 = ws.lu.shape[0]
    for _ in range(reps):
        for i in range(n1):
            for k in range(n1):
                ws.lu[i, k] = -K.GAMMA * h * ws.jac[i, k]
            ws.lu[i, i] += 1.0
        K.lu_factor(ws.lu, ws.piv)
        K.lu_solve(ws.lu, ws.piv, ws.f0, ws.k1)
        K.lu_solve(ws.lu, ws.piv, ws.f0, ws.k2)


@njit
def _loop_contact(th, dth, ex, ey, km, ws, reps):
    pc = km.pc
    for r in range(reps):
        contact(km.tab, pc.n, pc.tip_clearance, th + r * dth, ex, ey, ws.gaps_end, ws.cmat)


@njit
def _loop_linearise(th, dth, h, ex, ey, kc, km, op, ws, reps):
    for r in range(reps):
        linearise(ex, ey, th + r * dth, op.omega, h, kc, km, ws.pres, ws.gear, ws.gear_rows)


def _fastest(loop, args, reps: int, batches: int) -> float:
    """µs per call of ``loop(*args, reps)``: the fastest of ``batches`` batches."""
    loop(*args, 2)
    best = math.inf
    for _ in range(batches):
        t0 = time.perf_counter()
        loop(*args, reps)
        best = min(best, time.perf_counter() - t0)
    return 1e6 * best / reps


def time_parts(config, rpm: float, bar: float, model: str = "mobility", reps: int = 2000,
               batches: int = 7) -> dict:
    """Per-call cost of each of :data:`PARTS` [µs] and of the whole output step at (``rpm``, ``bar`` gauge).

    Returns a dict with ``us_per_call`` (part → µs), ``us_per_output_step``, ``accepted_per_step``,
    ``rejected_per_step``, ``accounted_us`` and ``chambers``.
    """
    from .steady import run_steady
    m = PumpModel(config, model)
    res = run_steady(m, rpm, bar, max_revolutions=6, min_revolutions=3, rtol=1e-4)
    omega = rpm_to_rad_s(rpm)
    inp = Inputs(omega, config.boundary.suction_pressure_pa, bar_gauge_to_pa_abs(bar, config.fluid.atmospheric_pa))
    span = 2.0 * math.pi / omega
    m.advance(res.state, span, inp)                                   # warm
    best, counts = math.inf, None
    for _ in range(batches):
        t0 = time.perf_counter()
        s, _ = m.advance(res.state, span, inp)
        wall = time.perf_counter() - t0
        if wall < best:
            best, counts = wall, {k: s.counts[k] - res.state.counts[k] for k in
                                  ("steps", "substeps", "rejected_substeps")}
    km, ws = m.kernel, m._ws
    op = operating(km, inp.omega, inp.p_suction, inp.p_delivery)
    y, th, h = s.log_density.copy(), s.theta, m.step_size(omega)
    ex, ey = float(s.eccentricity[0]), float(s.eccentricity[1])
    K.to_pressures(y, km, ws.pres)
    integrals = np.zeros(ws.flows.shape[0])
    dth = omega * h                    # each call one output step on: the table rows a revolution reads
    us = {"rhs_jacobian": _fastest(_loop_rhs, (y, th, dth, km, op, ws, True), reps, batches),
          "rhs": _fastest(_loop_rhs, (y, th, dth, km, op, ws, False), reps, batches),
          "first_stage": _fastest(_loop_first_stage, (y, th, dth, km, op, ws, integrals, h), reps, batches)}
    acc = counts["substeps"] / counts["steps"]
    rej = counts["rejected_substeps"] / counts["steps"]
    us["ros2_step"] = _fastest(_loop_ros2_step, (y, th, h * min(1.0, 1.0 / acc), km, op, ws), reps, batches)
    us["lu"] = _fastest(_loop_lu, (h / acc, ws), reps, batches)
    us["contact"] = _fastest(_loop_contact, (th, dth, ex, ey, km, ws), reps, batches)
    us["linearise"] = _fastest(_loop_linearise, (th, dth, h, ex, ey, 0, km, op, ws), reps, batches)
    per_step = 1e6 * best / counts["steps"]
    return {"chambers": km.pc.n, "rpm": rpm, "bar": bar, "model": model, "us_per_call": us,
            "us_per_output_step": per_step, "accepted_per_step": acc, "rejected_per_step": rej,
            "accounted_us": acc * us["first_stage"] + (acc + rej) * us["ros2_step"]}


def print_parts(points, out=print) -> list[dict]:
    """Run :func:`time_parts` at each ``(label, config, rpm, bar)`` of ``points`` and print one row each."""
    out("µs per call of each part of the stepper at a periodic state (fastest of 7 batches); per output step: "
        "accepted (acc) and rejected (rej) sub-steps, accounted = acc × first_stage + (acc + rej) × ros2_step")
    out(f"  {'pump':30s} {'N':>2s} {'rpm':>5s} {'bar':>5s} {'µs/step':>8s} {'acc':>5s} {'rej':>5s} "
        + " ".join(f"{p:>12s}" for p in PARTS) + f" {'accounted':>9s} {'other':>6s}")
    rows = []
    for label, cfg, rpm, bar in points:
        r = time_parts(cfg, rpm, bar)
        r["pump"] = label
        rows.append(r)
        u = r["us_per_call"]
        out(f"  {label:30s} {r['chambers']:2d} {rpm:5.0f} {bar:5.1f} {r['us_per_output_step']:8.2f} "
            f"{r['accepted_per_step']:5.2f} {r['rejected_per_step']:5.2f} "
            + " ".join(f"{u[p]:12.2f}" for p in PARTS)
            + f" {r['accounted_us']:9.2f} {r['us_per_output_step'] - r['accounted_us']:6.2f}")
    return rows


#: Column heads of :func:`parts_markdown`, per part.
_HEADS = {"rhs_jacobian": "RHS + Jacobian", "rhs": "RHS", "first_stage": "first stage", "ros2_step": "ROS2 step",
          "lu": "W, LU, 2 solves", "contact": "tip gaps", "linearise": "gear linearisation"}


def parts_markdown(rows, sentence: str) -> str:
    """The block ``bench parts`` writes into docs/performance.md: ``sentence`` (the run's provenance) and one table
    row per :func:`time_parts` result in ``rows`` (each with its ``pump`` label), between the markers of
    ``"bench parts"`` (:func:`.bench_all.markers`)."""
    from .bench_all import markers
    begin, end = markers("bench parts")
    lines = [begin, sentence, "",
             "| pump | N | rpm | bar | µs / output step | acc | rej | " + " | ".join(_HEADS[p] for p in PARTS)
             + " | accounted | other |", "|" + "---|" * (9 + len(PARTS))]
    for r in rows:
        u = r["us_per_call"]
        lines.append(f"| {r['pump']} | {r['chambers']} | {r['rpm']:g} | {r['bar']:g} | {r['us_per_output_step']:.2f} | "
                     f"{r['accepted_per_step']:.2f} | {r['rejected_per_step']:.2f} | "
                     + " | ".join(f"{u[p]:.2f}" for p in PARTS)
                     + f" | {r['accounted_us']:.2f} | {r['us_per_output_step'] - r['accounted_us']:.2f} |")
    lines.append(end)
    return "\n".join(lines) + "\n"
