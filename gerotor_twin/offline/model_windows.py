"""Settled windows made by the twin's own steady model with a fault in full (no ROS): the classifier's behaviour
tests' windows, ``diagnosis_bench --model-windows`` (what one speed or one operating point can tell apart) and
``--separability`` (:mod:`.separability`)."""
from __future__ import annotations

import math

import numpy as np

from ..twin.diagnosis import WindowRecord
from ..twin.health import fault_text

__all__ = ["P_ATM", "OIL_K", "POINTS", "MODEL_CASES", "model_records", "model_windows_table"]

P_ATM = 101325.0                   #: [Pa]
OIL_K = 323.15                     #: [K]
#: operating points of the bags and of :func:`model_records` [rpm, bar]
POINTS = ((1000, 5), (1000, 25), (2500, 25), (2500, 5))
#: kind → (scaled_config keywords or ``offset_pa`` [Pa], flow-meter gain [-]) for :func:`model_records`
MODEL_CASES = {"healthy": ({}, 0.0), "tip_wear": ({"tip": 2.0}, 0.0), "lateral_wear": ({"lateral": 1.15}, 0.0),
               "air_ingress": ({"air_fraction": 0.03}, 0.0), "pressure_offset": ({"offset_pa": 1e5}, 0.0),
               "flowmeter_drift": ({}, 0.05)}


def _flow(cfg, rpm, bar, p_suction=P_ATM, **fault):
    from ..model.clearance_scale import scaled_config
    from ..model.pump import PumpModel
    from ..model.steady import run_steady
    off = fault.pop("offset_pa", 0.0)
    model = PumpModel(scaled_config(cfg, **fault) if fault else cfg)
    return run_steady(model, rpm, bar - off / 1e5, p_suction=p_suction, oil_temperature=OIL_K)


def model_records(cfg, fault: dict, gain: float = 0.0, rel_sd: float = 0.003, seed: int = 0, windows: int = 3,
                  restriction_pa: float | None = None, points=POINTS) -> list[WindowRecord]:
    """Settled windows of the pump ``cfg`` with ``fault`` applied in full (:func:`scaled_config` keywords, or
    ``offset_pa`` [Pa]: the transducer reads that much high) and a flow-meter gain ``gain`` [-], ``windows``
    per operating point of ``points`` [rpm, bar] at 50 °C, flow noise ``rel_sd`` × flow; the predictions are
    the configured twin's steady state.  With ``restriction_pa`` [Pa] a suction sensor reads a line drop of
    5 kPa at 3000 rpm ∝ speed² plus the restriction at 68.3 L/min ∝ flow² (100 Pa noise)."""
    rng = np.random.default_rng(seed)
    out, t = [], 0.0
    for rpm, bar in points:
        p_s = P_ATM
        if restriction_pa is not None:
            q0 = _flow(cfg, rpm, bar).mean_delivery_flow_m3s
            p_s = P_ATM - 5e3 * (rpm / 3000) ** 2 - restriction_pa * (q0 / 68.3 * 6e4) ** 2
        pred = _flow(cfg, rpm, bar, p_s)
        true = _flow(cfg, rpm, bar, p_s, **dict(fault)).mean_delivery_flow_m3s
        for _ in range(windows):
            t += 0.5
            q_meas = true * (1 + gain) + rng.normal(0.0, rel_sd * true)
            p_read = p_s + (0.0 if restriction_pa is None else rng.normal(0.0, 100.0))
            out.append(WindowRecord(t, rpm * math.pi / 30, P_ATM + bar * 1e5, p_read, OIL_K, q_meas,
                                    pred.mean_delivery_flow_m3s, pred.theoretical_flow_m3s, rel_sd * q_meas))
    return out


def model_windows_table() -> str:
    """Markdown table: per set of operating points and true kind, the named kind (a tentative naming: ``kind or
    rival``), its closest rival with their separation, and the probabilities > 0.05."""
    from ..config import load_config
    from ..twin.diagnosis import SteadySignatures, classify
    cfg = load_config()
    sig = SteadySignatures(cfg)
    lines = ["| operating points [rpm / bar] | true | named (probability) | closest rival (separation) | other kinds > 0.05 |",
             "|---|---|---|---|---|"]
    for pts in (POINTS, POINTS[:2], POINTS[2:], POINTS[1:2]):
        for kind, (fault, gain) in MODEL_CASES.items():
            recs = model_records(cfg, fault, gain, points=pts)
            d = classify(recs, [sig(r) for r in recs], relinearise=sig.relinearised)
            other = ", ".join(f"{k} {p:.2f}" for k, p in d.probability.items() if p > 0.05 and k != d.kind)
            named = fault_text(d.kind, d.confidence, d.rival if d.tentative else None)
            rival = f"{d.rival} ({d.separation:.1f})" if d.rival else "–"
            lines.append(f"| {', '.join(f'{r}/{b}' for r, b in pts)} | {kind} | {named} | {rival} | {other} |")
    return "\n".join(lines)
