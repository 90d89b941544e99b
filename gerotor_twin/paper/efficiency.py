"""Volumetric-efficiency tables of section 4 of [1] (tables 3–5) from the model.

Each point is the periodic steady state of :func:`gerotor_twin.model.steady.run_steady`
with the delivery pressure imposed (the tables are labelled by delivery pressure).

References
----------
.. [1] Paper of ``../shared/paper/gerotor-micromotion-paper.md``, tables 3–5.
"""
from __future__ import annotations

from dataclasses import replace

from ..config import PumpConfig
from ..model.pump import PumpModel
from ..model.steady import run_steady
from .setting import paper_setting
from .reference import PRESSURES_BAR, SPEEDS_RPM, paper_efficiency, slope_per_bar

__all__ = ["with_clearances", "efficiency_points", "row_slopes"]


def with_clearances(cfg: PumpConfig, tooth_tip_m: float, lateral_m: float) -> PumpConfig:
    """The same pump with another tooth-tip clearance δ [m] and lateral clearance [m]."""
    clear = replace(cfg.clearances, tooth_tip_m=float(tooth_tip_m), lateral_m=float(lateral_m))
    return replace(cfg, clearances=clear, gears=replace(cfg.gears, tip_clearance=float(tooth_tip_m)))


def efficiency_points(cfg: PumpConfig, models=("fixed", "mobility"), speeds=SPEEDS_RPM,
                      pressures=PRESSURES_BAR, progress=None, model_cache: dict | None = None,
                      fluid_model: str = "paper", suction_edge: str = "ray",
                      orifice_law: str = "flow_number") -> list[dict]:
    """Volumetric efficiency of every (model, speed, pressure) point.

    Parameters
    ----------
    cfg : PumpConfig
        The pump (imposed delivery pressure is used whatever ``boundary.mode`` says).
    models : sequence of str
        Outer-gear models (``fixed``, ``mobility``, ``short``, ``fdm``).
    speeds : sequence of float
        Shaft speeds [rpm].
    pressures : sequence of float
        Delivery pressures [bar gauge].
    progress : callable, optional
        Called as ``progress(done, total, point)`` after each point.
    fluid_model : {"paper", "mixture"}
        State equation of the oil: eq. (23) of [1] (default, as calibrated) or the mixture.
    suction_edge : {"ray", "chamber"}
        Closing edge of the suction kidney: the ray, as calibrated (default), or the chamber outline
        of the twin's default pump (:mod:`gerotor_twin.geometry.ports`).
    orifice_law : {"flow_number", "merritt"}
        Port orifice law: the flow-number law, as calibrated (default), or Merritt's, the twin's
        default (:mod:`gerotor_twin.hydraulics.orifice`).

    Returns
    -------
    list of dict
        ``rpm``, ``bar``, ``model``, ``volumetric_efficiency`` [-], ``paper`` [-] (None where
        the paper has no value), ``difference`` [-] (model − paper), ``mean_eccentricity_m``,
        ``min_tooth_gap_m``, ``revolutions``, ``counts``.
    """
    cfg = replace(paper_setting(cfg, fluid_model, suction_edge, orifice_law), boundary=replace(cfg.boundary, mode="imposed"))
    cache = {} if model_cache is None else model_cache
    total = len(models) * len(speeds) * len(pressures)
    points = []
    for name in models:
        if name not in cache:
            cache[name] = PumpModel(cfg, bearing=name)
        model = cache[name]
        for rpm in speeds:
            for bar in pressures:
                s = run_steady(model, rpm, bar).summary()
                try:
                    ref = paper_efficiency(name, rpm, bar)
                except (KeyError, ValueError):
                    ref = None
                eta = s["volumetric_efficiency"]
                pt = {"rpm": float(rpm), "bar": float(bar), "model": name, "volumetric_efficiency": eta,
                      "paper": ref, "difference": None if ref is None else eta - ref,
                      "mean_eccentricity_m": s["mean_eccentricity_m"], "min_tooth_gap_m": s["min_tooth_gap_m"],
                      "revolutions": s["revolutions"], "counts": s["counts"]}
                points.append(pt)
                if progress is not None:
                    progress(len(points), total, pt)
    return points


def row_slopes(points: list[dict]) -> list[dict]:
    """Least-squares slope of efficiency vs pressure [1/bar] per (model, speed), model and paper."""
    rows = {}
    for p in points:
        rows.setdefault((p["model"], p["rpm"]), []).append(p)
    out = []
    for (name, rpm), pts in rows.items():
        bars = [p["bar"] for p in pts]
        s_model = slope_per_bar(bars, [p["volumetric_efficiency"] for p in pts])
        have_ref = all(p["paper"] is not None for p in pts) and len(pts) > 1
        s_paper = slope_per_bar(bars, [p["paper"] for p in pts]) if have_ref else None
        out.append({"model": name, "rpm": rpm, "slope_per_bar": s_model, "paper_slope_per_bar": s_paper,
                    "relative_difference": None if s_paper is None else s_model / s_paper - 1.0})
    return out
