"""``gerotor-twin calibrate``: plateaus of bench bags, or a pump's steady map → fitted pump config with provenance.

Steps: detect plateaus in every bag (or read the map's rows, :mod:`.pump_map`); hold out every k-th plateau, fit on the rest and
report the error on the held-out ones (prior vs fitted); refit on all plateaus; write
the pump YAML (the prior with the fitted values and a ``calibration`` block: bags, date,
parameters with 95 % intervals, identifiability, residuals), and optionally the full
result as JSON and a small HTML report.  See :mod:`.calibrate` for the fit.
"""
from __future__ import annotations

import datetime as _dt
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from .. import __version__
from ..config import load_config, parse_config
from ..errors import InputError, check_range
from ..units import m3s_to_lpm, rad_s_to_rpm
from . import fit as C
from ..hydraulics.meter import FLOW_METERS
from .fit_model import DISPLAY_UNITS, PARAMETERS, PLATEAU_RTOL, apply, parse_params
from .plateaus import DetectorSettings, bench_plateaus, split_by_envelope
from . import prediction as P
from . import selection as S
from .pump_map import MapLimits, PumpMapError, read_map

#: what ``--map`` may fit by default: the gaps, their opening with pressure, the effective displacement, the
#: bypass path and the filling loss growing with speed
MAP_PARAMS = ("tip", "lateral", "lateral_opening", "displacement", "bypass", "filling", "filling_margin")
#: the candidate sets ``--map`` compares by default (the prior besides): each loss alone and with the gaps (the
#: lateral gap's opening with pressure alone as well: over a narrow pressure range its Δp² is confused with the
#: gaps' Δp, and the identifiability analysis would keep it at its prior beside them); the filling loss with the
#: gaps, and with the gaps and the displacement (at two speeds or more its n³ and the displacement's n differ)
MAP_CANDIDATES = (("tip", "lateral"), ("displacement",), ("tip", "lateral", "displacement"),
                  ("tip", "lateral", "bypass"), ("tip", "lateral", "displacement", "bypass"),
                  ("lateral_opening",), ("lateral_opening", "displacement"), ("tip", "lateral", "lateral_opening"),
                  ("tip", "lateral", "filling"), ("tip", "lateral", "displacement", "filling"),
                  ("tip", "lateral", "filling", "filling_margin"))

#: the candidate sets ``--bench`` compares by default (the prior besides): the gaps, the effective displacement
#: alone and with the gaps (a pump that differs from the twin in form: free air, another port law, tolerances of
#: the profiles take a share of the flow at every speed that no clearance makes, docs/calibration_health.md),
#: and the gaps with their opening under pressure (:data:`OPENING_CANDIDATE`)
OPENING_CANDIDATE = ("tip", "lateral", "lateral_opening")   #: plates that deflect: leakage growing faster than Δp
BENCH_CANDIDATES = (("tip", "lateral"), ("displacement",), ("tip", "lateral", "displacement"), OPENING_CANDIDATE)
#: the largest flow meter lag ``--flow-sensor-tau`` accepts [s]
FLOW_SENSOR_TAU_MAX_S = 60.0

__all__ = ["calibrate_bags", "calibrate_map", "calibrate_records", "MAP_PARAMS", "BENCH_CANDIDATES", "OPENING_CANDIDATE",
           "fitted_config", "cmd_calibrate", "add_parser"]


def _fit_summary(fr: C.FitResult, raw: dict, records, displacement: float) -> dict:
    fitted = C.plateau_errors(records, fr.flow_model, displacement)
    prior = C.plateau_errors(records, fr.flow_prior, displacement)
    a = fr.analysis
    return {"parameters": C.parameter_table(fr, raw), "combinations": C.combinations(fr),
            "groups": a["groups"], "unseparable": [list(p) for p in a["unseparable"]],
            "insensitive": a["insensitive"], "fixed": a["fixed"], "correlation_at_prior": _nan_none(a["correlation"]),
            "singular_ratios": a["singular_ratios"].tolist(), "rcond": a["rcond"],
            "residual_variance_factor": fr.s2, "dof": fr.dof, "function_evaluations": fr.iterations,
            "cov_x": fr.cov_x.tolist(),
            "plateaus": fitted, "plateaus_prior": prior,
            "eta_error": C.summary_stats(fitted), "eta_error_prior": C.summary_stats(prior),
            "flow_error_m3s": C.summary_stats(fitted, "flow_error_m3s"),
            "flow_error_prior_m3s": C.summary_stats(prior, "flow_error_m3s")}


def _nan_none(a: np.ndarray) -> list:
    return [[None if not np.isfinite(v) else float(v) for v in row] for row in np.asarray(a)]


def _holdout(ev, names, train, held, raw, displacement, opts, say) -> dict:
    say(f"hold-out: fitting {len(train)} plateaus, {len(held)} held out")
    fr = C.fit(ev, names, train, **opts, progress=say)
    q_held = ev.flows(names, [fr.x, np.zeros(len(names))], held)
    after = C.plateau_errors(held, q_held[0], displacement)
    before = C.plateau_errors(held, q_held[1], displacement)
    return {"train": [r.label() for r in train], "held_out": [r.label() for r in held],
            "parameters": C.parameter_table(fr, raw), "plateaus": after, "plateaus_prior": before,
            "eta_error": C.summary_stats(after), "eta_error_prior": C.summary_stats(before)}


def calibrate_bags(bags, *, config_path=None, detector: DetectorSettings = DetectorSettings(), progress=None,
                   **fit_options) -> dict:
    """Fit to the plateaus of the bench recordings ``bags`` (see :func:`calibrate_records`)."""
    say = progress or (lambda s: None)
    records = []
    for b in bags:
        found = bench_plateaus(b, detector)
        say(f"{b}: {len(found)} plateaus")
        records += found
    records, outside = split_by_envelope(records, load_config(config_path))
    for r, why in outside:
        say(f"{r.label()}: outside the pump's input envelope, not used: {why}")
    if not records:
        raise InputError("--bench", ", ".join(map(str, bags)), "recordings with at least one steady plateau "
                         f"(≥ {detector.min_s + detector.settle_s:g} s of constant speed and pressure) inside the "
                         "pump's input envelope (its rated range + 10 %)")
    out = calibrate_records(records, [str(b) for b in bags], config_path=config_path, progress=progress,
                            **fit_options)
    out["detector"] = detector.__dict__
    out["excluded_plateaus"] = [{"plateau": r.label(), "reason": why} for r, why in outside]
    return out


def calibrate_map(path, *, config_path=None, progress=None, params=MAP_PARAMS, cv: str = "auto",
                  candidates=MAP_CANDIDATES, **fit_options) -> dict:
    """Fit to the operating points of a pump's steady map (CSV, :mod:`.pump_map`; see :func:`calibrate_records`);
    by default the parameter set is chosen by cross-validation among :data:`MAP_CANDIDATES`."""
    cfg = load_config(config_path)
    records = read_map(path, MapLimits.from_config(cfg))
    (progress or (lambda s: None))(f"{path}: {len(records)} operating points")
    out = calibrate_records(records, [str(path)], config_path=config_path, progress=progress, params=params,
                            cv=cv, candidates=candidates, **fit_options)
    out["kind"] = "map"
    return out


def calibrate_records(records, sources, *, config_path=None, params=("tip", "lateral"), model: str = "mobility",
                      holdout: int = 4, jobs: int | None = None, rcond: float = 0.1,
                      flow_floor: float = C.MODEL_FLOW_SD_REL, cv: str = "none", candidates=None,
                      flow_meter: str = "delivery", progress=None) -> dict:
    """Fit steady operating points (plateaus of recordings or rows of a map); the whole result.

    Parameters
    ----------
    records : list of PlateauRecord
        The operating points (SI).
    sources : list of str
        The files they came from (provenance).
    params : tuple of str
        The parameters to fit (``cv="none"``), or the largest candidate set (see ``candidates``).
    holdout : int
        ``cv="none"`` only: every k-th point held out, fitted on the others (0: none).
    cv : str
        ``"none"``: fit ``params``; ``"speed"`` / ``"point"`` / ``"auto"`` (speed when there are two or
        more): choose among candidate sets by that cross-validation (:mod:`.selection`).
    candidates : sequence of tuple of str, optional
        The candidate sets (the prior is always one); default :func:`.selection.candidate_sets` of ``params``.
    flow_meter : str
        Where the records' flows were measured (``hydraulics.meter.FLOW_METERS``): the twin's flows are
        compared as that meter reads them (:func:`.fit_model.at_meter`).
    """
    say = progress or (lambda s: None)
    cfg = load_config(config_path)
    raw = cfg.to_dict()
    raw.pop("calibration", None)
    displacement = cfg.gears.displacement_closed_form()
    opts = {"rcond": rcond, "flow_floor": flow_floor}
    plan = FitPlan(tuple(params), model, holdout, S.resolve_scheme(cv, records),
                   None if candidates is None else tuple(tuple(c) for c in candidates), flow_meter)
    (out, wall) = C.run_timed(_run, records, raw, plan, jobs, displacement, opts, say)
    out.update({"bags": list(sources), "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
                "prior_config": _display_path(cfg.source), "model": model, "holdout_every": holdout,
                "wall_time_s": wall, "software": f"gerotor_twin {__version__}", "flow_floor": flow_floor,
                "flow_meter": flow_meter,
                "plateau_records": [r.as_dict() for r in records]})
    out["config"] = apply(raw, out["params"], np.array([p["log_factor"] for p in out["fit"]["parameters"]]))
    return out


@dataclass(frozen=True)
class FitPlan:
    """What a calibration run fits and how it judges the result."""
    params: tuple[str, ...]      #: parameters fitted (``cv`` none) or the largest candidate set
    model: str                   #: outer-gear model of the twin
    holdout: int                 #: ``cv`` none: every k-th point held out (0: none)
    cv: str                      #: "none" | "speed" | "point"
    candidates: tuple | None     #: candidate sets; None: :func:`.selection.candidate_sets` of ``params``
    flow_meter: str = "delivery"  #: where the flows were measured (``hydraulics.meter.FLOW_METERS``)


def _display_path(path) -> str:
    """``path`` relative to the current directory when it lies below it (portable provenance)."""
    try:
        return str(Path(path).resolve().relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def _run(records, raw, plan: FitPlan, jobs, displacement, opts, say) -> dict:
    with C.Evaluator(raw, plan.model, jobs, progress=say, flow_meter=plan.flow_meter) as ev:
        if plan.cv == "none":
            train, held = C.split_holdout(records, plan.holdout)
            ho = _holdout(ev, plan.params, train, held, raw, displacement, opts, say) if held else None
            v = holdout_verdict(ho, plan.params)
            names = plan.params if v["calibrated"] else ()
            say(f"final fit on all {len(records)} plateaus" + ("" if names else " (nominal values kept)"))
            sel, fr = None, C.fit(ev, names, records, **opts, progress=say)
        else:
            ho = None
            sel, fr = _select(ev, records, raw, plan, displacement, opts, say)
            v = sel.pop("verdict")
        return {"holdout": ho, "selection": sel, "verdict": v, "params": list(fr.names),
                "fit": _fit_summary(fr, raw, records, displacement), "simulations": ev.simulated, "jobs": ev.jobs,
                "unsettled_simulations": len(ev.unsettled),
                "unsettled_worst_change": max(ev.unsettled, default=None)}


def _pt(v: float) -> str:
    return f"{100 * v:.2f}"


def holdout_verdict(ho: dict | None, names) -> dict:
    """Whether the fit of ``names`` on the training plateaus beats the nominal twin on the held-out ones (``--cv
    none``): its held-out η RMSE strictly below the nominal's, else the nominal values are kept."""
    if ho is None:
        return {"calibrated": True, "checked": False, "basis": "none", "chosen": list(names),
                "message": "calibration not checked: no plateau held out (--holdout 0 with --cv none); the fitted "
                           "values are written without evidence that they predict better than the nominal ones"}
    fit_e, nom_e = ho["eta_error"], ho["eta_error_prior"]
    fm, nm = (float(np.mean([abs(r["eta_error"]) for r in ho[k]])) for k in ("plateaus", "plateaus_prior"))
    ok = fit_e["rmse"] < nom_e["rmse"]
    figures = (f"held-out |η error| mean / RMSE: fitted {_pt(fm)} / {_pt(fit_e['rmse'])} pt, nominal {_pt(nm)} / "
               f"{_pt(nom_e['rmse'])} pt on {len(ho['held_out'])} plateaus")
    message = (f"calibration accepted: {'+'.join(names)} predicts the held-out plateaus better than the nominal "
               f"twin ({figures})" if ok else
               f"calibration refused: the fitted twin predicts the held-out plateaus no better than the nominal one "
               f"({figures}); the nominal values are kept")
    return {"calibrated": bool(ok), "checked": True, "basis": "holdout", "chosen": list(names) if ok else [],
            "nominal_heldout_rmse": nom_e["rmse"], "nominal_heldout_mean_abs": nm,
            "fitted_heldout_rmse": fit_e["rmse"], "fitted_heldout_mean_abs": fm, "message": message}


def selection_verdict(cands: list, pick, scheme: str, noise: float) -> dict:
    """Whether the chosen candidate is a fitted set (it then beats the nominal twin held out beyond the noise
    ``noise`` [-], :func:`.selection.choose`) or the prior (calibration refused, the nominal values kept)."""
    prior = next(c for c in cands if not c.names)
    fitted = [c for c in cands if c.names]
    best = min(fitted, key=lambda c: c.cv_rmse) if fitted else None
    mean_abs = lambda c: float(np.mean(np.abs(c.cv_errors)))          # noqa: E731
    nominal = f"nominal {_pt(mean_abs(prior))} / {_pt(prior.cv_rmse)} pt"
    where = f"leave one {scheme} out, {prior.cv_errors.size} held-out plateaus"
    if pick.names:
        message = (f"calibration accepted: {'+'.join(pick.names)} predicts the held-out plateaus better than the "
                   f"nominal twin (held-out |η error| mean / RMSE: fitted {_pt(mean_abs(pick))} / {_pt(pick.cv_rmse)} "
                   f"pt, {nominal}; {where})")
    else:
        other = (f", best fitted set {'+'.join(best.names)} {_pt(mean_abs(best))} / {_pt(best.cv_rmse)} pt"
                 if best is not None else "")
        better = best is not None and best.cv_rmse < prior.cv_rmse
        message = (f"calibration refused: no fitted parameter set predicts the held-out plateaus better than the "
                   f"nominal twin{' by more than the noise (' + _pt(noise) + ' pt)' if better else ''} (held-out "
                   f"|η error| mean / RMSE: {nominal}{other}; {where}); the nominal values are kept")
    return {"calibrated": bool(pick.names), "checked": True, "basis": f"cv-{scheme}", "chosen": list(pick.names),
            "nominal_heldout_rmse": prior.cv_rmse, "nominal_heldout_mean_abs": mean_abs(prior),
            "fitted_heldout_rmse": None if best is None else (pick if pick.names else best).cv_rmse,
            "fitted_heldout_mean_abs": None if best is None else mean_abs(pick if pick.names else best),
            "best_fitted": None if best is None else list(best.names), "message": message}


def _select(ev, records, raw, plan: FitPlan, displacement, opts, say) -> tuple[dict, C.FitResult]:
    """Cross-validate every candidate set, choose one (:func:`.selection.choose`), fit the empirical baseline."""
    fold_index = S.folds(records, plan.cv)
    say(f"cross-validation: leave one {plan.cv} out, {len(fold_index)} folds")
    sets = plan.candidates if plan.candidates is not None else S.candidate_sets(plan.params)
    sets = ([()] if () not in sets else []) + list(sets)
    runs = [S.cross_validate(ev, names, records, fold_index, displacement, opts, say) for names in sets]
    qth = np.array([displacement * r.omega / (2 * math.pi) for r in records])
    noise = float(np.sqrt(np.mean((C.sigmas(records, opts["flow_floor"]) / qth) ** 2)))
    pick, why = S.choose([c for c, _ in runs], noise)
    fr = next(f for c, f in runs if c is pick)
    base = S.baseline(records, fold_index, displacement, raw["boundary"]["suction_pressure_pa"])
    interval = _interval(ev, pick, fr, records, displacement)
    return {"cv": plan.cv, "folds": [[records[i].label() for i in f] for f in fold_index],
            "fold_rpm": [float(np.mean([records[i].rpm for i in f])) for f in fold_index],
            "chosen_fold_mean_abs": [float(np.mean(np.abs(pick.cv_errors[f]))) for f in fold_index],
            "plateau_labels": [r.label() for r in records],
            "candidates": [c.summary() for c, _ in runs], "chosen": list(pick.names), "reason": why,
            "eta_noise": noise, "cv_rmse": pick.cv_rmse, "cv_rmse_se": pick.cv_rmse_se,
            "cv_max_abs": float(np.abs(pick.cv_errors).max()),
            "prediction_band_eta": interval["typical_half_width_eta"], "prediction_interval": interval,
            "baseline": base, "baseline_better": bool(base["cv_rmse"] < pick.cv_rmse),
            "verdict": selection_verdict([c for c, _ in runs], pick, plan.cv, noise)}, fr


def _interval(ev, pick, fr: C.FitResult, records, displacement) -> dict:
    """The 95 % prediction interval of the chosen set's η and mean flow at every plateau (:mod:`.prediction`):
    its parts, and the RMS half-width over the plateaus (``typical_half_width_eta``)."""
    form = pick.model_form()
    pv = P.param_variance(P.eta_gradients(ev, fr.names, fr.x, records, displacement, fr.flow_model), fr.cov_x)
    mv = P.measurement_variance(records, displacement)
    hw = form.half_width(pv, mv)
    qth = np.array([displacement * r.omega / (2 * math.pi) for r in records])
    twin = form.half_width(pv)
    return {**form.as_dict(), "typical_half_width_eta": float(np.sqrt(np.mean(hw ** 2))),
            "twin_half_width_eta": float(np.sqrt(np.mean(twin ** 2))),
            "half_width_eta": hw.tolist(), "half_width_flow_m3s": (hw * qth).tolist(),
            "sd_param_eta": np.sqrt(np.clip(pv, 0, None)).tolist(), "sd_meas_eta": np.sqrt(mv).tolist()}


def provenance(result: dict) -> dict:
    """The ``calibration`` block of the written config (plain YAML types)."""
    f = result["fit"]
    ho = result["holdout"]
    block = {"tool": "gerotor-twin calibrate", "software": result["software"], "date": result["date"],
             "bags": result["bags"], "prior_config": result["prior_config"], "model": result["model"],
             "plateaus": len(result["plateau_records"]), "flow_meter": result.get("flow_meter", "delivery"),
             "parameters": {p["name"]: {"field": p["field"], "prior": p["prior"], "value": p["value"],
                                        "ci95": p["ci95"], "separately_identifiable": p["identifiable"]}
                            for p in f["parameters"]},
             "fitted_combinations": [{"combination": c["label"], "factor": c["factor"], "factor_ci95": c["factor_ci95"]}
                                     for c in f["combinations"]],
             "unseparable": f["unseparable"],
             "residuals": {"flow_rmse_m3s": f["flow_error_m3s"]["rmse"], "eta_rmse": f["eta_error"]["rmse"],
                           "eta_max_abs": f["eta_error"]["max_abs"],
                           "eta_rmse_prior": f["eta_error_prior"]["rmse"]}}
    v = result.get("verdict")
    if v:
        block["verdict"] = {k: v[k] for k in ("calibrated", "checked", "basis", "chosen", "message")}
    sel = result.get("selection")
    if sel:
        block["residuals"]["eta_rmse_heldout"] = sel["cv_rmse"]
        pi = sel.get("prediction_interval")
        if pi:
            block["prediction_interval"] = {"eta_half_width_twin": pi["twin_half_width_eta"],
                                            "eta_half_width_measured": pi["typical_half_width_eta"],
                                            "model_form_sd_eta": pi["model_form_sd_eta"], "level": pi["level"],
                                            "held_out": pi["held_out"]}
        block["selection"] = {"cv": sel["cv"], "chosen": sel["chosen"], "reason": sel["reason"],
                              "cv_rmse": sel["cv_rmse"], "prediction_band_eta": sel["prediction_band_eta"],
                              "candidates": [{"params": c["params"], "fit_rmse": c["fit_rmse"], "cv_rmse": c["cv_rmse"]}
                                             for c in sel["candidates"]],
                              "baseline": {k: sel["baseline"][k] for k in ("law", "a", "b_per_pa_s", "fit_rmse", "cv_rmse")},
                              "baseline_better": sel["baseline_better"]}
    if ho:
        block["holdout"] = {"held_out": ho["held_out"], "eta_max_abs": ho["eta_error"]["max_abs"],
                            "eta_max_abs_prior": ho["eta_error_prior"]["max_abs"]}
    return json.loads(json.dumps(block, default=float))


def fitted_config(result: dict) -> dict:
    """The pump config mapping to write: fitted values + provenance; validated by the loader."""
    raw = json.loads(json.dumps(result["config"]))
    raw["calibration"] = provenance(result)
    parse_config(raw, source="fitted config")       # what the loader will accept
    return raw




def print_summary(result: dict, out=None) -> None:
    """The figures a bench engineer looks at first."""
    out = out or sys.stdout
    f = result["fit"]
    kept = set(f["insensitive"]) | set(f.get("fixed", []))
    if result.get("flow_meter", "delivery") != "delivery":
        print(f"  the twin's flows compared as a flow meter at {result['flow_meter']} pressure reads them "
              "(the same mass flow, its volume at that pressure: --flow-meter)", file=out)
    for p in f["parameters"]:
        u, unit = DISPLAY_UNITS.get(p["unit"], (1.0, ""))
        note = ("" if p["identifiable"] else "  (kept at the prior)" if p["name"] in kept
                else "  (not separately identifiable: common factor of its group)")
        print(f"  {p['name']:15s} {p['prior'] * u:9.3f} → {p['value'] * u:9.3f} {unit:6s}  parameter 95 % CI "
              f"[{p['ci95'][0] * u:.3f}, {p['ci95'][1] * u:.3f}]{note}", file=out)
    for a, b in f["unseparable"]:
        print(f"  the data cannot separate {a} and {b}: fitted their combination, their ratio kept at the prior",
              file=out)
    if f["insensitive"]:
        print(f"  kept at the prior (the data do not see them): {', '.join(f['insensitive'])}", file=out)
    if f.get("fixed"):
        print(f"  kept at the prior (the data confuse them with the others): {', '.join(f['fixed'])}", file=out)
    _print_onset(f["parameters"], out)
    for c in (c for c in f["combinations"] if not c.get("linear")):
        print(f"  identifiable: {c['label']} → factor {c['factor']:.4f} (parameter 95 % CI {c['factor_ci95'][0]:.4f}"
              f"..{c['factor_ci95'][1]:.4f})", file=out)
    e, e0 = f["eta_error"], f["eta_error_prior"]
    print(f"  all {e['n']} {'map rows' if result.get('kind') == 'map' else 'plateaus'}: |η error| max {100 * e0['max_abs']:.2f} → {100 * e['max_abs']:.2f} pt, "
          f"RMSE {100 * e0['rmse']:.2f} → {100 * e['rmse']:.2f} pt; flow RMSE "
          f"{m3s_to_lpm(f['flow_error_prior_m3s']['rmse']):.3f} → {m3s_to_lpm(f['flow_error_m3s']['rmse']):.3f} L/min",
          file=out)
    if result.get("selection"):
        print_selection(result["selection"], out)
    ho = result["holdout"]
    if ho:
        print(f"  hold-out ({len(ho['held_out'])} plateaus, fitted on the other {len(ho['train'])}): |η error| max "
              f"{100 * ho['eta_error_prior']['max_abs']:.2f} → {100 * ho['eta_error']['max_abs']:.2f} pt", file=out)
    if f["parameters"]:
        print("  (a parameter interval says how well the data fix a parameter of this model's form, not how well "
              "the twin predicts)", file=out)
    if result.get("verdict"):
        print(result["verdict"]["message"], file=out)


def _print_onset(parameters: list[dict], out) -> None:
    """The filling onset speed, when the filling margin was fitted beside a filling loss."""
    from ..model.volumetric import filling_onset_rad_s
    by = {p["name"]: p for p in parameters}
    if "filling_margin" in by and "filling" in by and by["filling_margin"]["value"] > 0 and by["filling"]["value"] > 0:
        onset = filling_onset_rad_s(by["filling"]["value"], by["filling_margin"]["value"])
        print(f"  filling onset: chambers full up to {rad_s_to_rpm(onset):.0f} rpm "
              "(√(filling_margin / (filling · p_atm)) × 1000 rpm)", file=out)


def print_selection(sel: dict, out=None) -> None:
    """The candidate sets' fit and held-out errors side by side, the choice, the band and the baseline."""
    out = out or sys.stdout
    print(f"  parameter sets (η_v error, leave one {sel['cv']} out, {len(sel['folds'])} folds):", file=out)
    print(f"    {'set':34s} {'fit RMSE':>9s} {'held-out RMSE':>14s} {'held-out max':>13s}  [pt]", file=out)
    rows = [("+".join(c["params"]) or "prior (nothing fitted)", c) for c in sel["candidates"]]
    rows.append((f"empirical {sel['baseline']['law']}", sel["baseline"]))
    for name, c in rows:
        se = f" ± {100 * c['cv_rmse_se']:.2f}" if "cv_rmse_se" in c else ""
        print(f"    {name:34s} {100 * c['fit_rmse']:9.2f} {100 * c['cv_rmse']:7.2f}{se:>7s} "
              f"{100 * c['cv_max_abs']:13.2f}", file=out)
    for c in sel["candidates"]:
        if c.get("held_at_prior"):
            print(f"    ({'+'.join(c['params'])}: {', '.join(c['held_at_prior'])} kept at the prior by the "
                  f"identifiability analysis, --rcond {c.get('rcond', 0.1):g})", file=out)
    print(f"  chosen: {sel['reason']}", file=out)
    by_speed = S.held_out_by_speed(sel)
    if by_speed:
        print("  its held-out |η error| by speed (mean [pt]): "
              + ", ".join(f"{rpm:.0f} rpm {_pt(e)}" for rpm, e in by_speed) + f" ({S.BY_SPEED_NOTE})", file=out)
    pi = sel.get("prediction_interval")
    if pi:
        print(f"  prediction interval of η_v (95 %): ± {_pt(pi['twin_half_width_eta'])} pt for the twin (model-form "
              f"error {_pt(pi['model_form_sd_eta'])} pt sd from {pi['held_out']} held-out plateaus, parameters ≤ "
              f"{_pt(max(pi['sd_param_eta'], default=0))} pt sd); against plateaus measured like these (standard "
              f"error ≤ {_pt(max(pi['sd_meas_eta'], default=0))} pt) ± {_pt(pi['typical_half_width_eta'])} pt, of "
              f"their mean flow ± {m3s_to_lpm(float(np.sqrt(np.mean(np.square(pi['half_width_flow_m3s']))))):.3f} "
              f"L/min (RMS over the plateaus)", file=out)
    b = sel["baseline"]
    if sel["baseline_better"]:
        se = sel.get("cv_rmse_se", 0.0)
        close = sel["cv_rmse"] - b["cv_rmse"] < se
        digits = 3 if f"{100 * b['cv_rmse']:.2f}" == f"{100 * sel['cv_rmse']:.2f}" else 2
        print(f"  the empirical law predicts the held-out points better than the twin: held-out RMSE "
              f"{100 * b['cv_rmse']:.{digits}f} pt against {100 * sel['cv_rmse']:.{digits}f} pt"
              + (f" (less apart than the twin's held-out RMSE is uncertain, ± {_pt(se)} pt)" if close else ""),
              file=out)


def _candidates(args, names):
    """The candidate sets of the command line (the prior is always one besides): ``--candidates``; else without
    ``--params`` :data:`MAP_CANDIDATES` for a map, :data:`BENCH_CANDIDATES` for recordings; with it, for a map the
    subsets of ``--params``, for recordings ``--params`` as one set (fitted, or the nominal values kept)."""
    if args.candidates is not None:
        return [parse_params(c, "--candidates") for c in args.candidates.split(";") if c.strip()]
    if args.params is None:
        return MAP_CANDIDATES if args.map else BENCH_CANDIDATES
    return None if args.map else [names]


def cmd_calibrate(args) -> int:
    """The ``calibrate`` subcommand."""
    out = Path(args.output)
    if out.exists() and not args.overwrite:
        raise InputError("-o", str(out), "a file that does not exist yet", "pass --overwrite to replace it")
    if args.holdout != 0 and args.holdout < 2:
        raise InputError("--holdout", args.holdout, "0 (none) or an integer ≥ 2 (every k-th plateau held out)")
    if args.jobs is not None and args.jobs < 1:
        raise InputError("--jobs", args.jobs, "an integer ≥ 1")
    default = ",".join(MAP_PARAMS) if args.map else "tip,lateral"
    names = parse_params(default if args.params is None else args.params)
    cv = args.cv or "auto"
    candidates = _candidates(args, names)
    from ..model.pump import BEARING_MODELS
    if args.model not in BEARING_MODELS:
        raise InputError("--model", args.model, " | ".join(BEARING_MODELS))
    for flag, v in (("--settle-s", args.settle_s), ("--min-plateau-s", args.min_plateau_s)):
        if not (math.isfinite(v) and 0 <= v <= 600):
            raise InputError(flag, v, "[0, 600] s")
    if not (math.isfinite(args.flow_floor) and 0 <= args.flow_floor <= 0.1):
        raise InputError("--flow-floor", args.flow_floor, "[0, 0.1] (fraction of the plateau's mean flow)")
    if not (math.isfinite(args.rcond) and 0.01 <= args.rcond <= 0.5):
        raise InputError("--rcond", args.rcond, "[0.01, 0.5] (singular-value ratio)")
    say = None if args.quiet else (lambda s: print(s, file=sys.stderr, flush=True))
    from ..twin.settings import oil_sensor_tau_arg
    det = DetectorSettings(min_s=args.min_plateau_s, settle_s=args.settle_s,
                           oil_sensor_tau_s=oil_sensor_tau_arg(args.oil_sensor_tau),
                           flow_sensor_tau_s=check_range("--flow-sensor-tau", args.flow_sensor_tau, 0.0,
                                                         FLOW_SENSOR_TAU_MAX_S, unit="s"))
    fit_options = {"config_path": args.config, "params": names, "model": args.model, "holdout": args.holdout,
                   "jobs": args.jobs, "flow_floor": args.flow_floor, "progress": say, "cv": cv,
                   "candidates": candidates, "rcond": args.rcond, "flow_meter": args.flow_meter}
    if args.map:
        try:
            res = calibrate_map(args.map, **fit_options)
        except PumpMapError as exc:
            for line in exc.lines:
                print(f"error: {line}", file=sys.stderr)
            return 2
    else:
        res = calibrate_bags(args.bench, detector=det, **fit_options)
    raw = fitted_config(res)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("# pump config fitted by `gerotor-twin calibrate` (provenance in `calibration`)\n"
                   + yaml.safe_dump(raw, sort_keys=False, allow_unicode=True))
    print(f"wrote {out} ({res['simulations']} plateau simulations on {res['jobs']} processes, "
          f"{res['wall_time_s']:.1f} s)")
    print_summary(res)
    if res.get("unsettled_simulations"):
        print(f"note: {res['unsettled_simulations']} of {res['simulations']} plateau simulations stopped at their "
              f"revolution limit before settling (largest last change of the mean flow "
              f"{res['unsettled_worst_change']:.1e}, the test {PLATEAU_RTOL:g}); their flows carry an error of about "
              "that size")
    for row in res.get("excluded_plateaus", []):
        print(f"note: {row['plateau']} not used: outside the pump's input envelope ({row['reason']}); the pump "
              "config's `range` sets it")
    from .plateaus import thermometer_lag_note
    note = None if args.map else thermometer_lag_note(res["plateau_records"], det.oil_sensor_tau_s)
    if note:
        print(note)
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1, default=float))
        print(f"wrote {args.json}")
    if args.report:
        from .report import write_report
        write_report(res, args.report)
        print(f"wrote {args.report}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("calibrate", help="fit leakage clearances to bench recordings; write a pump config",
                       description="Detect steady plateaus in bench recordings, fit the chosen parameters to the "
                                   "measured mean delivery flow (least squares, identifiable combinations only), "
                                   "report hold-out errors and write a pump YAML with a provenance block.")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--bench", nargs="+", metavar="BAG", help="bench recordings (MCAP): their steady plateaus")
    src.add_argument("--map", metavar="FILE.csv",
                     help="a pump's steady map: speed, delivery pressure, oil temperature, flow or η_v, units in "
                          "the header (example: config/maps/example_map.csv)")
    p.add_argument("-o", "--output", required=True, help="pump YAML to write (usable with --config, pump_config)")
    p.add_argument("--params", default=None,
                   help="comma list of " + ", ".join(PARAMETERS) + ": fitted (--cv none) or the largest "
                        "candidate set (default with --bench: tip,lateral fitted with --cv none, else the default candidates of "
                        "--candidates; with --map " + ",".join(MAP_PARAMS) + ")")
    p.add_argument("--cv", choices=("auto", "speed", "point", "none"), default=None,
                   help="choose the parameter set by cross-validation: leave one speed (or point) out; auto: speed "
                        "when there are two speeds or more (default auto); none: fit --params, hold out every "
                        "--holdout-th plateau; either way the nominal values are kept when the fit predicts the "
                        "held-out plateaus no better")
    p.add_argument("--candidates", default=None, metavar="SETS",
                   help="candidate sets for --cv, ';'-separated (e.g. 'displacement;tip,lateral,displacement'); "
                        "the prior is always one (default with --map and no --params: "
                        + "; ".join(",".join(c) for c in MAP_CANDIDATES) + "; with --map and --params every "
                        "subset of --params up to 3 parameters, their prefixes beyond; with --bench and no --params: "
                        + "; ".join(",".join(c) for c in BENCH_CANDIDATES) + "; with --bench --params as one set)")
    p.add_argument("--config", help="prior pump YAML (default config/pump.yaml)")
    p.add_argument("--model", default="mobility", help="outer-gear model of the twin (default mobility)")
    p.add_argument("--holdout", type=int, default=4,
                   help="--cv none: hold out every k-th plateau of each bag (0: none; default 4)")
    p.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    p.add_argument("--settle-s", type=float, default=1.0, help="dropped at each plateau start [s] (default 1)")
    p.add_argument("--min-plateau-s", type=float, default=1.5, help="shortest plateau kept [s] (default 1.5)")
    p.add_argument("--oil-sensor-tau", type=float, default=0.0, metavar="S",
                   help="time constant of the bench's oil thermometer [s]: each plateau's oil temperature is "
                        "its mean reading + S × the readings' slope (default 0 = as read)")
    p.add_argument("--flow-sensor-tau", type=float, default=0.0, metavar="S",
                   help="time constant of the bench's flow meter [s] (first-order lag): each plateau's mean flow "
                        "with the lag undone, a trapezoid-weighted mean of reading − S × its weight's slope, exact "
                        "for such a lag (default 0 = as read)")
    p.add_argument("--flow-floor", type=float, default=C.MODEL_FLOW_SD_REL, metavar="REL",
                   help="model error of a plateau's mean flow, relative, added in quadrature to its standard "
                        f"error (default {C.MODEL_FLOW_SD_REL:g}; 0: noise only)")
    p.add_argument("--rcond", type=float, default=0.1, metavar="R",
                   help="identifiability: a parameter direction whose singular value is below R × the largest is "
                        "not fitted (kept at the prior, or fitted as a common factor with the one it is confused "
                        "with; default 0.1, for two parameters a correlation above 0.98). Lower it only for data "
                        "whose form you trust: it compares the directions with one another, not with the noise "
                        "(docs/calibration_health.md)")
    p.add_argument("--flow-meter", choices=FLOW_METERS, default="delivery",
                   help="where the flow was measured: at the delivery pressure (the twin's delivery flow, ISO 4409's "
                        "outlet flow; default) or at atmospheric pressure (a meter in the return line: the same mass, "
                        "its volume expanded back, ≈ 1.2 %% more at 170 bar)")
    p.add_argument("--json", metavar="F", help="write the whole result (per plateau, covariance) as JSON")
    p.add_argument("--report", metavar="F.html", help="write a one-page HTML report")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(func=cmd_calibrate)
