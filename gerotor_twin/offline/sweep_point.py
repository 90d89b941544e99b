"""One design-study point on a worker: pump config + operating point -> periodic steady state -> record.

Runs where the engine puts it (a process of the local cluster or a remote
``dask worker``), so it takes everything by value: the raw base configuration
(the YAML mapping, not a path), the dotted overrides of the point, the
operating point and the outer-gear model.  The steady state and its summary are
the ``simulate`` command's own (:func:`gerotor_twin.model.steady.run_steady`,
:meth:`SteadyResult.summary`); this module only flattens that summary into
named scalar outputs and adds the cavitation share.  An invalid point (undercut
or otherwise impossible geometry, a value outside a config range, a solver
failure) returns a record with ``status = "failed"`` and the one-line reason; it
never raises, so one bad point cannot stop a sweep.
"""
from __future__ import annotations

import copy
import inspect
import math
import time

import numpy as np

from ..config import parse_config
from ..errors import InputError, one_line
from ..model.pump import PumpModel
from ..model.steady import run_steady
from ..units import bar_gauge_to_pa_abs, celsius_to_kelvin

__all__ = ["OPERATING_FIELDS", "OUTPUTS", "evaluate_point", "apply_overrides", "point_config",
           "temperature_keyword", "cavitation_share", "flatten_summary"]

#: operating-point fields a SPEC may set or vary (name -> unit, edge units as in the CLI)
OPERATING_FIELDS = {
    "speed_rpm": "rpm",
    "delivery_bar": "bar gauge",
    "suction_bar_abs": "bar absolute",
    "oil_temperature_c": "degC",
}

#: outputs a SPEC may ask for (all are stored; ``outputs`` picks the CSV columns and plots).  SI, efficiency 0–1.
OUTPUTS = (
    "volumetric_efficiency", "delivery_flow_ripple", "min_chamber_pressure_pa", "max_chamber_pressure_pa",
    "cavitation_share", "mean_eccentricity_abs_m", "mean_eccentricity_x_m", "mean_eccentricity_y_m",
    "min_tooth_gap_m", "min_open_tooth_gap_m", "effective_tooth_gap_m", "theoretical_flow_m3s", "mean_delivery_flow_m3s", "mean_delivery_pressure_pa",
    "revolutions", "periodicity_error", "counts.housing_contact", "counts.solver_failures",
    "counts.cavitation_clamps",
)

#: names the oil-temperature input [K] may have in :func:`run_steady` (issue 13 adds ``oil_temperature``)
_TEMPERATURE_KEYWORDS = ("oil_temperature", "oil_temperature_k", "temperature_k")


def temperature_keyword() -> str | None:
    """The keyword of :func:`run_steady` that takes the oil temperature [K], or None in builds without it."""
    params = inspect.signature(run_steady).parameters
    return next((k for k in _TEMPERATURE_KEYWORDS if k in params), None)


def apply_overrides(raw: dict, overrides: dict) -> dict:
    """A deep copy of the raw config mapping with ``{"section.key": value}`` set (missing levels created)."""
    out = copy.deepcopy(raw)
    for path, value in overrides.items():
        node = out
        parts = path.split(".")
        for part in parts[:-1]:
            nxt = node.get(part)
            if not isinstance(nxt, dict):
                nxt = node[part] = {}
            node = nxt
        node[parts[-1]] = value
    return out


def point_config(raw: dict, overrides: dict, source: str):
    """The validated :class:`~gerotor_twin.config.PumpConfig` of one point (raises :class:`InputError`)."""
    return parse_config(apply_overrides(raw, overrides), source=source)


def cavitation_share(chamber_pressures: np.ndarray, threshold_pa: float) -> float:
    """Share of the chamber samples (all chambers × steps of one revolution) below ``threshold_pa`` [-]."""
    p = np.asarray(chamber_pressures)
    return float((p < threshold_pa).mean()) if p.size else float("nan")


def flatten_summary(summary: dict) -> dict:
    """:meth:`SteadyResult.summary` as flat scalars: vectors -> ``_x``/``_y``, ``counts`` -> ``counts.<name>``."""
    flat = {}
    for key, value in summary.items():
        if key in ("rpm", "bar", "model"):
            continue
        if key == "counts":
            flat.update({f"counts.{k}": v for k, v in value.items()})
        elif key == "mean_eccentricity_m":
            flat["mean_eccentricity_x_m"], flat["mean_eccentricity_y_m"] = value
            flat["mean_eccentricity_abs_m"] = float(math.hypot(*value))
        elif isinstance(value, (int, float)):
            flat[key] = value
    return flat


def _operating(op: dict, cfg) -> dict:
    """run_steady keywords of the operating point (CLI units -> SI)."""
    kw = {"rpm": float(op["speed_rpm"]), "bar": float(op["delivery_bar"])}
    if op.get("suction_bar_abs") is not None:
        kw["p_suction"] = float(op["suction_bar_abs"]) * 1e5
    if op.get("oil_temperature_c") is not None:
        name = temperature_keyword()
        if name is None:
            raise InputError("operating.oil_temperature_c", op["oil_temperature_c"],
                             "unset: this build's model has no oil-temperature input")
        kw[name] = celsius_to_kelvin(float(op["oil_temperature_c"]))
    return kw


def _solve(task: dict, point: dict) -> dict:
    params = point["params"]
    overrides = {**task["set"], **{k: v for k, v in params.items() if k not in task["non_config"]}}
    cfg = point_config(task["base_config"], overrides, task["source"])
    op = {**task["operating"], **{k.split(".", 1)[1]: v for k, v in params.items() if k.startswith("operating.")}}
    model = PumpModel(cfg, bearing=params.get("bearing_model", task["model"]))
    res = run_steady(model, max_revolutions=task["revolutions"], min_revolutions=task["min_revolutions"],
                     **_operating(op, cfg))
    out = flatten_summary(res.summary())
    fl = cfg.fluid
    threshold = task["cavitation_threshold_pa"]
    if threshold is None:     # fully inside the cavitating branch of Eq. (23): below p_atm minus its switch band
        threshold = fl.atmospheric_pa - getattr(fl, "switch_band_pa", 0.0)
    out["cavitation_share"] = cavitation_share(res.outputs.chamber_pressures, threshold)
    out["delivery_pressure_pa"] = bar_gauge_to_pa_abs(op["delivery_bar"], fl.atmospheric_pa)
    if not all(math.isfinite(v) for v in (out["volumetric_efficiency"], out["min_chamber_pressure_pa"])):
        raise FloatingPointError("non-finite steady-state result")
    return out


def _worker_address() -> str:
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return "local"


def evaluate_point(task: dict, point: dict) -> dict:
    """Record of one point: ``id``, ``index``, ``params``, ``status`` ("ok"/"failed"), ``reason``, ``outputs``.

    Parameters
    ----------
    task : dict
        Shared settings of the study (see :meth:`SweepSpec.task`): ``base_config`` (raw mapping),
        ``source``, ``set``, ``operating``, ``model``, ``revolutions``, ``min_revolutions``,
        ``cavitation_threshold_pa`` [Pa] or None, ``non_config`` (parameter names that are not config paths).
    point : dict
        ``id``, ``index`` and ``params`` (name -> value) of this point.
    """
    t0 = time.perf_counter()
    rec = {"id": point["id"], "index": point["index"], "params": point["params"], "status": "ok", "reason": "",
           "outputs": {}}
    try:
        rec["outputs"] = _solve(task, point)
    except (InputError, FloatingPointError, ZeroDivisionError, ValueError) as exc:
        rec["status"], rec["reason"] = "failed", one_line(exc)
    rec["worker"] = _worker_address()
    rec["compute_s"] = time.perf_counter() - t0
    return rec
