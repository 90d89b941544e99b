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
from ..errors import InputError
from ..units import m3s_to_lpm
from . import fit as C
from .fit_model import apply, parse_params
from .plateaus import DetectorSettings, bench_plateaus
from . import selection as S
from .pump_map import MapLimits, PumpMapError, read_map

#: what ``--map`` may fit by default: the gaps, the effective displacement and the bypass path
MAP_PARAMS = ("tip", "lateral", "displacement", "bypass")
#: the candidate sets ``--map`` compares by default (the prior besides): each loss alone and with the gaps
MAP_CANDIDATES = (("tip", "lateral"), ("displacement",), ("tip", "lateral", "displacement"),
                  ("tip", "lateral", "bypass"), ("tip", "lateral", "displacement", "bypass"))

__all__ = ["calibrate_bags", "calibrate_map", "calibrate_records", "MAP_PARAMS", "fitted_config", "cmd_calibrate", "add_parser"]


def _fit_summary(fr: C.FitResult, raw: dict, records, displacement: float) -> dict:
    fitted = C.plateau_errors(records, fr.flow_model, displacement)
    prior = C.plateau_errors(records, fr.flow_prior, displacement)
    a = fr.analysis
    return {"parameters": C.parameter_table(fr, raw), "combinations": C.combinations(fr),
            "groups": a["groups"], "unseparable": [list(p) for p in a["unseparable"]],
            "insensitive": a["insensitive"], "fixed": a["fixed"], "correlation_at_prior": _nan_none(a["correlation"]),
            "singular_ratios": a["singular_ratios"].tolist(), "rcond": a["rcond"],
            "residual_variance_factor": fr.s2, "dof": fr.dof, "function_evaluations": fr.iterations,
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
    if not records:
        raise InputError("--bench", ", ".join(map(str, bags)), "recordings with at least one steady plateau "
                         f"(≥ {detector.min_s + detector.settle_s:g} s of constant speed and pressure)")
    out = calibrate_records(records, [str(b) for b in bags], config_path=config_path, progress=progress,
                            **fit_options)
    out["detector"] = detector.__dict__
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
                      progress=None) -> dict:
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
    """
    say = progress or (lambda s: None)
    cfg = load_config(config_path)
    raw = cfg.to_dict()
    raw.pop("calibration", None)
    displacement = cfg.gears.displacement_closed_form()
    opts = {"rcond": rcond, "flow_floor": flow_floor}
    plan = FitPlan(tuple(params), model, holdout, S.resolve_scheme(cv, records),
                   None if candidates is None else tuple(tuple(c) for c in candidates))
    (out, wall) = C.run_timed(_run, records, raw, plan, jobs, displacement, opts, say)
    out.update({"bags": list(sources), "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
                "prior_config": _display_path(cfg.source), "model": model, "holdout_every": holdout,
                "wall_time_s": wall, "software": f"gerotor_twin {__version__}", "flow_floor": flow_floor,
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


def _display_path(path) -> str:
    """``path`` relative to the current directory when it lies below it (portable provenance)."""
    try:
        return str(Path(path).resolve().relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def _run(records, raw, plan: FitPlan, jobs, displacement, opts, say) -> dict:
    with C.Evaluator(raw, plan.model, jobs, progress=say) as ev:
        if plan.cv == "none":
            train, held = C.split_holdout(records, plan.holdout)
            ho = _holdout(ev, plan.params, train, held, raw, displacement, opts, say) if held else None
            say(f"final fit on all {len(records)} plateaus")
            sel, fr = None, C.fit(ev, plan.params, records, **opts, progress=say)
        else:
            ho = None
            sel, fr = _select(ev, records, raw, plan, displacement, opts, say)
        return {"holdout": ho, "selection": sel, "params": list(fr.names),
                "fit": _fit_summary(fr, raw, records, displacement), "simulations": ev.simulated, "jobs": ev.jobs}


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
    return {"cv": plan.cv, "folds": [[records[i].label() for i in f] for f in fold_index],
            "candidates": [c.summary() for c, _ in runs], "chosen": list(pick.names), "reason": why,
            "eta_noise": noise, "cv_rmse": pick.cv_rmse, "cv_max_abs": float(np.abs(pick.cv_errors).max()),
            "prediction_band_eta": S.prediction_band(pick), "baseline": base,
            "baseline_better": bool(base["cv_rmse"] < pick.cv_rmse)}, fr


def provenance(result: dict) -> dict:
    """The ``calibration`` block of the written config (plain YAML types)."""
    f = result["fit"]
    ho = result["holdout"]
    block = {"tool": "gerotor-twin calibrate", "software": result["software"], "date": result["date"],
             "bags": result["bags"], "prior_config": result["prior_config"], "model": result["model"],
             "plateaus": len(result["plateau_records"]),
             "parameters": {p["name"]: {"field": p["field"], "prior": p["prior"], "value": p["value"],
                                        "ci95": p["ci95"], "separately_identifiable": p["identifiable"]}
                            for p in f["parameters"]},
             "fitted_combinations": [{"combination": c["label"], "factor": c["factor"], "factor_ci95": c["factor_ci95"]}
                                     for c in f["combinations"]],
             "unseparable": f["unseparable"],
             "residuals": {"flow_rmse_m3s": f["flow_error_m3s"]["rmse"], "eta_rmse": f["eta_error"]["rmse"],
                           "eta_max_abs": f["eta_error"]["max_abs"],
                           "eta_rmse_prior": f["eta_error_prior"]["rmse"]}}
    sel = result.get("selection")
    if sel:
        block["residuals"]["eta_rmse_heldout"] = sel["cv_rmse"]
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


#: unit of a fitted parameter → (scale, unit) it is printed in
DISPLAY_UNITS = {"m": (1e6, "µm"), "m²": (1e6, "mm²")}


def print_summary(result: dict, out=None) -> None:
    """The figures a bench engineer looks at first."""
    out = out or sys.stdout
    f = result["fit"]
    kept = set(f["insensitive"]) | set(f.get("fixed", []))
    for p in f["parameters"]:
        u, unit = DISPLAY_UNITS.get(p["unit"], (1.0, ""))
        note = ("" if p["identifiable"] else "  (kept at the prior)" if p["name"] in kept
                else "  (not separately identifiable: common factor of its group)")
        print(f"  {p['name']:12s} {p['prior'] * u:9.3f} → {p['value'] * u:9.3f} {unit:3s}  95 % CI "
              f"[{p['ci95'][0] * u:.3f}, {p['ci95'][1] * u:.3f}]{note}", file=out)
    for a, b in f["unseparable"]:
        print(f"  the data cannot separate {a} and {b}: fitted their combination, their ratio kept at the prior",
              file=out)
    if f["insensitive"]:
        print(f"  kept at the prior (the data do not see them): {', '.join(f['insensitive'])}", file=out)
    if f.get("fixed"):
        print(f"  kept at the prior (the data confuse them with the others): {', '.join(f['fixed'])}", file=out)
    for c in (c for c in f["combinations"] if not c.get("linear")):
        print(f"  identifiable: {c['label']} → factor {c['factor']:.4f} (95 % CI {c['factor_ci95'][0]:.4f}"
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
    print(f"  chosen: {sel['reason']}; a predicted η_v holds ± {100 * sel['prediction_band_eta']:.2f} pt "
          f"(95 %, from the held-out errors)", file=out)
    b = sel["baseline"]
    if sel["baseline_better"]:
        print(f"  the empirical law predicts the held-out points better than the twin: held-out RMSE "
              f"{100 * b['cv_rmse']:.2f} pt against {100 * sel['cv_rmse']:.2f} pt", file=out)


def _candidates(args):
    """The candidate sets of the command line: ``--candidates``, else :data:`MAP_CANDIDATES` for a map without
    ``--params``, else None (the subsets of ``--params``)."""
    if args.candidates is not None:
        return [parse_params(c) for c in args.candidates.split(";") if c.strip()]
    return MAP_CANDIDATES if args.map and args.params is None else None


def cmd_calibrate(args) -> int:
    """The ``calibrate`` subcommand."""
    out = Path(args.output)
    if out.exists() and not args.overwrite:
        raise InputError("-o", str(out), "a file that does not exist yet", "pass --overwrite to replace it")
    if args.jobs is not None and args.jobs < 1:
        raise InputError("--jobs", args.jobs, "an integer ≥ 1")
    default = ",".join(MAP_PARAMS) if args.map else "tip,lateral"
    names = parse_params(default if args.params is None else args.params)
    cv = args.cv or ("auto" if args.map else "none")
    candidates = _candidates(args)
    from ..model.pump import BEARING_MODELS
    if args.model not in BEARING_MODELS:
        raise InputError("--model", args.model, " | ".join(BEARING_MODELS))
    for flag, v in (("--settle-s", args.settle_s), ("--min-plateau-s", args.min_plateau_s)):
        if not (math.isfinite(v) and 0 <= v <= 600):
            raise InputError(flag, v, "[0, 600] s")
    if not (math.isfinite(args.flow_floor) and 0 <= args.flow_floor <= 0.1):
        raise InputError("--flow-floor", args.flow_floor, "[0, 0.1] (fraction of the plateau's mean flow)")
    say = None if args.quiet else (lambda s: print(s, file=sys.stderr, flush=True))
    from ..twin.settings import oil_sensor_tau_arg
    det = DetectorSettings(min_s=args.min_plateau_s, settle_s=args.settle_s,
                           oil_sensor_tau_s=oil_sensor_tau_arg(args.oil_sensor_tau))
    fit_options = {"config_path": args.config, "params": names, "model": args.model, "holdout": args.holdout,
                   "jobs": args.jobs, "flow_floor": args.flow_floor, "progress": say, "cv": cv,
                   "candidates": candidates}
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
                   help="comma list of tip, lateral, cd, tip_dh, displacement: fitted (--cv none) or the largest "
                        "candidate set (default tip,lateral; with --map tip,lateral,displacement,bypass)")
    p.add_argument("--cv", choices=("auto", "speed", "point", "none"), default=None,
                   help="choose the parameter set by cross-validation: leave one speed (or point) out; auto: speed "
                        "when there are two speeds or more (default: auto with --map, none with --bench)")
    p.add_argument("--candidates", default=None, metavar="SETS",
                   help="candidate sets for --cv, ';'-separated (e.g. 'displacement;tip,lateral,displacement'); "
                        "the prior is always one (default with --map and no --params: the gaps, the displacement, "
                        "the gaps with each of displacement and bypass, and all four; else every subset of "
                        "--params up to 3 parameters, their prefixes beyond)")
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
    p.add_argument("--flow-floor", type=float, default=C.MODEL_FLOW_SD_REL, metavar="REL",
                   help="model error of a plateau's mean flow, relative, added in quadrature to its standard "
                        f"error (default {C.MODEL_FLOW_SD_REL:g}; 0: noise only)")
    p.add_argument("--json", metavar="F", help="write the whole result (per plateau, covariance) as JSON")
    p.add_argument("--report", metavar="F.html", help="write a one-page HTML report")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(func=cmd_calibrate)
