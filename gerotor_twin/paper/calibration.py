"""Calibration of the clearances against the fixed-centre rows of tables 3–5 of [1].

Only the tooth-tip clearance δ and the lateral clearance (per face) are fitted — nothing
else — by least squares on the 18 differences between the model's fixed-centre volumetric
efficiency and the "Fix centre" rows of tables 3–5 (1000/2000/3000 rpm × 5–27.5 bar):

.. math::
    \\min_{\\ln\\delta,\\ \\ln s}\\ \\sum_{n,p} \\left(\\eta_{fixed}(n, p; \\delta, s)
    - \\eta_{paper}(n, p)\\right)^2

Acceptance (issue 4): every point within ±2 percentage points, and the least-squares slope
of efficiency against pressure within 10 % of the paper's at each speed.  The mobility
model is *not* used here; its efficiencies with these clearances are a prediction.

Notes
-----
Leakage through both gaps is Poiseuille-dominated (∝ h³ Δp), so the two clearances are
nearly interchangeable along a valley of the objective; what separates them is how the
tooth-tip leakage scales with speed (it acts only while a gap separates chambers at
different pressures, and carries a Couette term), visible in the slope ratio between
1000 and 3000 rpm.  The result therefore says as much about the split as the paper's
tables allow, and the valley is reported (``valley`` in the result) so nobody mistakes
the split for a measurement.

References
----------
.. [1] Paper of ``../shared/paper/gerotor-micromotion-paper.md``, tables 3–5.
"""
from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from ..config import PumpConfig
from .efficiency import efficiency_points, row_slopes, with_clearances

__all__ = ["calibrate", "evaluate", "acceptance", "refit_lateral", "DEFAULT_RESULT_PATH"]

#: Where ``gerotor-twin paper calibrate`` keeps its result (committed with the repo).
DEFAULT_RESULT_PATH = Path(__file__).resolve().parents[2] / "docs" / "calibration.json"
POINT_TOLERANCE = 0.02      #: ±2 percentage points [-]
SLOPE_TOLERANCE = 0.10      #: ±10 % on the slope [-]


def evaluate(cfg: PumpConfig, tooth_tip_m: float, lateral_m: float) -> dict:
    """Fixed-centre efficiency points and row slopes for one pair of clearances [m]."""
    pts = efficiency_points(with_clearances(cfg, tooth_tip_m, lateral_m), models=("fixed",))
    return {"tooth_tip_m": tooth_tip_m, "lateral_m": lateral_m, "points": pts, "slopes": row_slopes(pts)}


def acceptance(points: list[dict], slopes: list[dict]) -> dict:
    """The two criteria of issue 4 on a set of fixed-centre points."""
    worst = max(abs(p["difference"]) for p in points)
    worst_slope = max(abs(s["relative_difference"]) for s in slopes)
    return {"max_point_difference": worst, "point_tolerance": POINT_TOLERANCE,
            "max_slope_relative_difference": worst_slope, "slope_tolerance": SLOPE_TOLERANCE,
            "passed": bool(worst <= POINT_TOLERANCE and worst_slope <= SLOPE_TOLERANCE)}


def refit_lateral(cfg: PumpConfig, tooth_tip_m: float, start_lateral_m: float, max_nfev: int = 15) -> dict:
    """Best lateral clearance [m] at a given tooth-tip clearance δ [m] (least squares on the 18 fixed points).

    Returns
    -------
    dict
        ``tooth_tip_m``, ``lateral_m``, ``rms_difference`` [-], ``acceptance`` (:func:`acceptance`),
        ``slopes``, ``points``, ``evaluations``.
    """
    calls = []

    def residuals(x):
        r = evaluate(cfg, tooth_tip_m, 1e-6 * math.exp(x[0]))
        calls.append(r)
        return np.array([p["difference"] for p in r["points"]])

    one = least_squares(residuals, [math.log(start_lateral_m * 1e6)], diff_step=0.005, x_scale=0.1,
                        xtol=1e-3, ftol=1e-4, max_nfev=max_nfev)
    lat = 1e-6 * float(math.exp(one.x[0]))
    best = evaluate(cfg, tooth_tip_m, lat)
    d = np.array([p["difference"] for p in best["points"]])
    return {"tooth_tip_m": float(tooth_tip_m), "lateral_m": lat, "rms_difference": float(np.sqrt(np.mean(d ** 2))),
            "acceptance": acceptance(best["points"], best["slopes"]), "slopes": best["slopes"],
            "points": best["points"], "evaluations": len(calls) + 1}


def calibrate(cfg: PumpConfig, start=(31.4e-6, 134.8e-6), progress=print) -> dict:
    """Fit δ and the lateral clearance [m] to the fixed-centre rows of tables 3–5.

    Parameters
    ----------
    cfg : PumpConfig
        The pump; its clearances are replaced.
    start : (float, float)
        Starting tooth-tip and lateral clearance [m].
    progress : callable
        Receives one line per evaluation.

    Returns
    -------
    dict
        ``tooth_tip_m``, ``lateral_m``, ``rms_difference``, ``acceptance``, ``points``,
        ``slopes``, ``valley`` (best lateral clearance and objective at other δ),
        ``evaluations``, ``wall_time_s``.
    """
    t0 = time.perf_counter()
    history = []

    def residuals(x):                       # x = ln(clearance / 1 µm)
        tip, lat = 1e-6 * math.exp(x[0]), 1e-6 * math.exp(x[1])
        r = evaluate(cfg, tip, lat)
        d = np.array([p["difference"] for p in r["points"]])
        history.append((tip, lat, float(np.sqrt(np.mean(d ** 2)))))
        progress(f"  δ = {tip * 1e6:7.3f} µm, lateral = {lat * 1e6:7.3f} µm: rms {100 * history[-1][2]:.3f} pt, "
                 f"max {100 * np.abs(d).max():.3f} pt")
        return d

    sol = least_squares(residuals, np.log(np.asarray(start, float) * 1e6), diff_step=0.005, x_scale=0.1,
                        xtol=1e-3, ftol=1e-4, max_nfev=40)
    tip, lat = (1e-6 * float(v) for v in np.exp(sol.x))
    best = evaluate(cfg, tip, lat)
    valley = []
    for f in (0.6, 0.8, 1.25):   # how well-determined is the split: refit lateral only at other δ
        one = refit_lateral(cfg, tip * f, lat)
        valley.append({k: one[k] for k in ("tooth_tip_m", "lateral_m", "rms_difference")})
        progress(f"  valley: δ = {tip * f * 1e6:.2f} µm → best lateral {valley[-1]['lateral_m'] * 1e6:.2f} µm, "
                 f"rms {100 * valley[-1]['rms_difference']:.3f} pt")
    d = np.array([p["difference"] for p in best["points"]])
    return {"tooth_tip_m": tip, "lateral_m": lat, "rms_difference": float(np.sqrt(np.mean(d ** 2))),
            "acceptance": acceptance(best["points"], best["slopes"]), "points": best["points"],
            "slopes": best["slopes"], "valley": valley,
            "evaluations": [{"tooth_tip_m": a, "lateral_m": b, "rms_difference": c} for a, b, c in history],
            "wall_time_s": time.perf_counter() - t0, "config_source": cfg.source,
            "method": "scipy.optimize.least_squares (TRF) on ln(δ/1µm), ln(s/1µm); 18 fixed-centre points of tables 3-5; efficiency = net delivered flow (ports − suction–delivery − drain leaks) / theoretical"}


def save(result: dict, path=DEFAULT_RESULT_PATH) -> Path:
    """Write a calibration result as JSON."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result, indent=1))
    return path
