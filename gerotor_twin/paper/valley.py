"""The calibration valley: what tables 3–5 of [1] can and cannot decide about the leakage split.

For each tooth-tip clearance δ of a grid (18–100 µm) the lateral clearance is refitted to the
18 fixed-centre points (:func:`.calibration.refit_lateral`); each row then gives

* the fit: rms and worst point difference [pt], the relative slope error at each speed,
  and whether the issue-4 criteria (±2 pt, slopes ±10 %) hold;
* the loss split at one operating point by path, in percentage points of the theoretical flow:
  drain (sec. 3.4) and suction–delivery (sec. 3.3) are the revolution-mean flows of those
  paths; tips (Eq. 22) and lateral (sec. 3.2, across the lobe lands) are the rise of η when
  that path alone is closed; filling is 1 − η with every leakage path closed (compressibility,
  cavitation); ``interaction`` is what the five do not add up to (the paths share pressures);
* MM − fixed [pt] at 5 and 27.5 bar for each speed, driven by the gaps alone (nominal chamber
  volumes), with the fixed-centre contact rule ``rotate`` and ``none``
  (:class:`~gerotor_twin.config.MicroMotion`).

References
----------
.. [1] Paper of ``../shared/paper/gerotor-micromotion-paper.md``, tables 3–5, sec. 3.
"""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ..config import MicroMotion, PumpConfig
from ..model.pump import PumpModel
from ..model.steady import run_steady
from .calibration import refit_lateral
from .efficiency import with_clearances
from .reference import SPEEDS_RPM
from .setting import paper_setting

__all__ = ["DEFAULT_DELTAS_UM", "PATHS", "closed_paths", "loss_split", "mm_minus_fixed", "valley_row", "valley"]

#: Tooth-tip clearances of ``paper calibrate --valley`` [µm].
DEFAULT_DELTAS_UM = (18.0, 25.0, 31.4, 45.0, 60.0, 80.0, 100.0)
#: Leakage paths of the loss split, in print order.
PATHS = ("drain", "lateral", "suction_delivery", "tips", "filling")
SPLIT_POINT = (1000.0, 27.5)          #: (rpm, bar) of the loss split: the paper's worst point
GAIN_PRESSURES = (5.0, 27.5)          #: delivery pressures of MM − fixed [bar]


def closed_paths(model: PumpModel, tips: bool = False, lateral: bool = False, lines: bool = False) -> PumpModel:
    """The same model with leakage paths closed (what-if runs; the model object is changed and returned).

    ``tips``: Eq. (22) flow × 0; ``lateral``: the lobe-land conductance of sec. 3.2 = 0;
    ``lines``: the suction–delivery and drain conductances (sec. 3.3–3.4) = 0.
    """
    pc = model.kernel.pc
    pc = pc._replace(tip_flow_factor=0.0 if tips else pc.tip_flow_factor,
                     g_lateral=0.0 if lateral else pc.g_lateral,
                     g_drain=0.0 if lines else pc.g_drain,
                     g_suction_delivery=0.0 if lines else pc.g_suction_delivery)
    model.kernel = model.kernel._replace(pc=pc)
    return model


def loss_split(cfg: PumpConfig, rpm: float, bar: float, bearing: str = "fixed") -> dict:
    """Lost percentage points of the theoretical flow by path at one operating point (module docstring)."""
    base = run_steady(PumpModel(cfg, bearing), rpm, bar)
    o = base.outputs
    eta = base.volumetric_efficiency

    def eta_closed(**kw):
        return run_steady(closed_paths(PumpModel(cfg, bearing), **kw), rpm, bar).volumetric_efficiency

    split = {"drain": float(np.mean(o.leak_drain)) / o.theoretical_flow,
             "suction_delivery": float(np.mean(o.leak_suction_delivery)) / o.theoretical_flow,
             "tips": eta_closed(tips=True) - eta,
             "lateral": eta_closed(lateral=True) - eta,
             "filling": 1.0 - eta_closed(tips=True, lateral=True, lines=True)}
    out = {k: 100.0 * split[k] for k in PATHS}
    out["lost"] = 100.0 * (1.0 - eta)
    out["interaction"] = out["lost"] - sum(out[k] for k in PATHS)
    return out


def mm_minus_fixed(cfg: PumpConfig, rpm: float, bar: float, rule: str = "rotate",
                   volumes: str = "nominal") -> float:
    """η(mobility) − η(fixed) [pt] with the fixed-centre contact ``rule`` and chamber ``volumes``."""
    c = replace(cfg, micro_motion=MicroMotion(fixed_centre_contact=rule, chamber_volumes=volumes))
    eta = {m: run_steady(PumpModel(c, m), rpm, bar).volumetric_efficiency for m in ("mobility", "fixed")}
    return 100.0 * (eta["mobility"] - eta["fixed"])


def valley_row(cfg: PumpConfig, tooth_tip_m: float, start_lateral_m: float, progress=None) -> dict:
    """One row of the valley table at δ [m] (module docstring); ``progress`` gets one line per stage."""
    say = progress or (lambda _line: None)
    t0 = time.perf_counter()
    say(f"δ = {tooth_tip_m * 1e6:6.1f} µm: refitting the lateral clearance ...")
    fit = refit_lateral(cfg, tooth_tip_m, start_lateral_m)
    c = with_clearances(paper_setting(cfg, None), tooth_tip_m, fit["lateral_m"])   # the kidneys as calibrated
    say(f"δ = {tooth_tip_m * 1e6:6.1f} µm: lateral {fit['lateral_m'] * 1e6:.1f} µm, rms "
        f"{100 * fit['rms_difference']:.2f} pt ({fit['evaluations']} evaluations); loss split, MM − fixed ...")
    slopes = {s["rpm"]: s["relative_difference"] for s in fit["slopes"]}
    gains = {rule: {f"{rpm:g}/{bar:g}": mm_minus_fixed(c, rpm, bar, rule) for rpm in SPEEDS_RPM
                    for bar in GAIN_PRESSURES} for rule in ("rotate", "none")}
    row = {"tooth_tip_m": float(tooth_tip_m), "lateral_m": fit["lateral_m"],
           "rms_difference_pt": 100 * fit["rms_difference"],
           "max_point_difference_pt": 100 * fit["acceptance"]["max_point_difference"],
           "slope_relative_error": {f"{k:g}": v for k, v in slopes.items()},
           "passed": fit["acceptance"]["passed"],
           "loss_split_pt": loss_split(c, *SPLIT_POINT), "loss_split_point": {"rpm": SPLIT_POINT[0],
                                                                            "bar": SPLIT_POINT[1]},
           "mm_minus_fixed_pt": gains, "wall_time_s": time.perf_counter() - t0}
    return row


def valley(cfg: PumpConfig, deltas_um=DEFAULT_DELTAS_UM, progress=None) -> dict:
    """The whole table: one :func:`valley_row` per δ [µm], each started from the previous lateral clearance."""
    rows = []
    lat = cfg.clearances.lateral_m
    for d in deltas_um:
        rows.append(valley_row(cfg, 1e-6 * float(d), lat, progress))
        lat = rows[-1]["lateral_m"]
    return {"rows": rows, "config_source": cfg.source, "split_point": {"rpm": SPLIT_POINT[0], "bar": SPLIT_POINT[1]},
            "micro_motion_of_config": {"fixed_centre_contact": cfg.micro_motion.fixed_centre_contact,
                                       "chamber_volumes": cfg.micro_motion.chamber_volumes},
            "note": "MM - fixed with nominal chamber volumes (gap-driven); loss split of the fixed-centre model"}
