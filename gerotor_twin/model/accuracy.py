"""Accuracy of the default numerics against a tight reference (``gerotor-twin bench accuracy``).

Both runs start from the same state and reach periodic steady state on their
own; one revolution of each is then compared sample by sample (the default
output step is a multiple of the reference's, so the samples coincide in
shaft angle).  Figures, all fractions (not percent):

``rms_pressure_error``
    RMS over samples and chambers of (p − p_ref) / (p_delivery − p_suction).
``max_pressure_error``
    max |p − p_ref| / (p_delivery − p_suction).
``peak_pressure_error``
    (max p − max p_ref) / (max p_ref − p_suction): the pressure peak, relative.
``efficiency_error``
    (η − η_ref) / η_ref, volumetric efficiency over the revolution, relative.
``flow_rms_error``
    RMS of (q − q_ref) / mean q_ref, instantaneous delivery flow.
``rtf``
    Real-time factor of the default numerics at this point (simulated / wall time).
"""
from __future__ import annotations

import math
import time
import numpy as np

from .pump import PumpModel
from .steady import reference_config, run_steady

__all__ = ["accuracy", "print_accuracy", "within_budget", "reference_numerics", "BUDGET"]

#: The budget of the default numerics (issue 10): RMS ≤ 1 %, |η error| ≤ 0.3 % relative, peak ≤ 2 %.
BUDGET = {"rms_pressure_error": 0.01, "efficiency_error": 0.003, "peak_pressure_error": 0.02}


REFERENCE_TOLERANCE = 1e-8   #: sub-step tolerance of the reference, on ln(ρ/ρ₀) [-]
REFERENCE_REFINEMENT = 8     #: reference output steps per default output step (2° → 0.25°)


def reference_numerics(cfg, rpm: float, tolerance: float = REFERENCE_TOLERANCE,
                       refinement: int = REFERENCE_REFINEMENT):
    """The same pump with tight numerics at ``rpm``: an output step ``refinement`` times finer
    than the default's there (so the samples coincide), log-density error control at ``tolerance``."""
    n = cfg.numerics
    h_deg = min(n.max_step_deg, math.degrees(n.max_step_s * rpm * math.pi / 30))
    steps = math.ceil(360.0 / h_deg - 1e-9)                 # default output steps per revolution
    return reference_config(cfg, tolerance=tolerance, max_step_deg=360.0 / (steps * refinement), max_step_s=1e-2)


def _rtf(model: PumpModel, state, rpm: float, bar: float, revolutions: int) -> tuple[float, float]:
    """(real-time factor, accepted ROS2 sub-steps per revolution) over ``revolutions`` from ``state``."""
    from .pump import Inputs
    inp = Inputs(rpm * math.pi / 30, model.config.boundary.suction_pressure_pa,
                 model.config.fluid.atmospheric_pa + bar * 1e5)
    span = revolutions * 60.0 / rpm
    t0 = time.perf_counter()
    new, _ = model.advance(state, span, inp)
    wall = time.perf_counter() - t0
    return span / wall, (new.counts["substeps"] - state.counts["substeps"]) / revolutions


def accuracy(cfg, rpm: float = 3000.0, bar: float = 27.5, model: str = "mobility", reference=None,
             rtf_revolutions: int = 20) -> dict:
    """Compare the default numerics of ``cfg`` with :func:`reference_numerics` at one operating point.

    Parameters
    ----------
    cfg : PumpConfig
        Pump with the numerics under test.
    rpm, bar : float
        Operating point [rpm, bar gauge].
    model : str
        Outer-gear model.
    reference : SteadyResult, optional
        A precomputed reference revolution (same point), to compare several numerics cheaply.
    """
    ref = reference if reference is not None else run_steady(PumpModel(reference_numerics(cfg, rpm), model), rpm,
                                                             bar, max_revolutions=40, rtol=1e-6)
    test_model = PumpModel(cfg, model)
    res = run_steady(test_model, rpm, bar, max_revolutions=40, rtol=1e-6)
    a, b = res.outputs, ref.outputs
    step = round(len(b) / len(a))
    ia = np.arange(len(a))
    ib = (ia + 1) * step - 1                    # reference row at the same shaft angle
    if ib[-1] >= len(b) or not np.allclose(np.mod(a.theta - b.theta[ib] + math.pi, 2 * math.pi) - math.pi, 0,
                                           atol=1e-9):
        raise ValueError("the reference samples do not coincide with the default ones")
    ps = cfg.boundary.suction_pressure_pa
    dp = cfg.fluid.atmospheric_pa + bar * 1e5 - ps
    # chambers turn with the outer gear (period 2πN/(N−1)): after k more shaft revolutions
    # chamber j sits where chamber j − k was
    k = round((a.theta[0] - b.theta[ib[0]]) / (2 * math.pi))
    n = test_model.N
    p_ref = b.chamber_pressures[ib][:, [(j - k) % n for j in range(n)]]
    err = (a.chamber_pressures - p_ref) / dp
    q_ref = b.delivery_flow[ib]
    peak_ref = b.chamber_pressures.max()
    rtf, substeps = _rtf(test_model, res.state, rpm, bar, rtf_revolutions)
    return {
        "rpm": rpm, "bar": bar, "model": model,
        "numerics": {k: getattr(cfg.numerics, k) for k in ("max_step_deg", "tolerance", "error_measure")},
        "rms_pressure_error": float(np.sqrt(np.mean(err ** 2))),
        "max_pressure_error": float(np.abs(err).max()),
        "peak_pressure_error": float((a.chamber_pressures.max() - peak_ref) / (peak_ref - ps)),
        "efficiency_error": float((res.volumetric_efficiency - ref.volumetric_efficiency)
                                  / ref.volumetric_efficiency),
        "flow_rms_error": float(np.sqrt(np.mean((a.delivery_flow - q_ref) ** 2)) / abs(q_ref.mean())),
        "mean_flow_error": float((res.mean_delivery_flow_m3s - ref.mean_delivery_flow_m3s)
                                 / ref.mean_delivery_flow_m3s),
        "volumetric_efficiency": res.volumetric_efficiency,
        "reference_volumetric_efficiency": ref.volumetric_efficiency,
        "substeps_per_revolution": substeps,
        "rtf": rtf,
    }


def within_budget(row: dict) -> bool:
    """True if a row of :func:`accuracy` meets :data:`BUDGET` (absolute values)."""
    return all(abs(row[k]) <= v for k, v in BUDGET.items())


def print_accuracy(cfg, rpms=(3000.0,), bars=(27.5,), models=("mobility",), out=print) -> list[dict]:
    """Run :func:`accuracy` over a grid of points and print one line each, budget verdict included."""
    n = cfg.numerics
    out(f"default numerics (output step {n.max_step_deg:g}° / {n.max_step_s * 1e6:g} µs, tolerance {n.tolerance:g} "
        f"on {n.error_measure}) against the reference (tolerance "
        f"{REFERENCE_TOLERANCE:g} on log_density, output step {REFERENCE_REFINEMENT}× finer)")
    out(f"  budget: RMS ≤ {BUDGET['rms_pressure_error']:.1%}, |η error| ≤ {BUDGET['efficiency_error']:.1%} "
        f"relative, |peak error| ≤ {BUDGET['peak_pressure_error']:.0%}")
    out(f"  {'model':9s} {'rpm':>5s} {'bar':>5s} {'RMS p':>7s} {'max p':>7s} {'peak':>7s} {'η err':>8s} "
        f"{'flow RMS':>8s} {'sub/rev':>7s} {'RTF':>6s}  verdict")
    rows = []
    for model in models:
        for rpm in rpms:
            for bar in bars:
                r = accuracy(cfg, rpm, bar, model)
                r["within_budget"] = within_budget(r)
                rows.append(r)
                out(f"  {model:9s} {rpm:5.0f} {bar:5.1f} {r['rms_pressure_error']:7.2%} {r['max_pressure_error']:7.2%} "
                    f"{r['peak_pressure_error']:+7.2%} {r['efficiency_error']:+8.3%} {r['flow_rms_error']:8.2%} "
                    f"{r['substeps_per_revolution']:7.0f} {r['rtf']:6.1f}  "
                    f"{'ok' if r['within_budget'] else 'OUTSIDE BUDGET'}")
    return rows
