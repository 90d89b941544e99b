"""``gerotor-twin report``: bench recording vs one or more twin logs -> HTML page, CSV and JSON metrics."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from gerotor_twin.errors import InputError, check_range, one_line

from . import layout
from .acceptance import PASS, AcceptanceCriterion, add_arguments, criterion_from_args, tally_text, verdict
from .analysis import add_temperatures, compare, find_plateaus, make_grid, meter_expansion, plateau_temperatures
from ..hydraulics.meter import FLOW_METERS
from .context import ReportContext
from .data import load_bench, load_twin, overlap, pump_config
from .html import render
from .interactive import panel_data
from .panels import DEFAULT_MAX_POINTS, Table, TimeSeries
from .provenance import provenance
from .tables import aligned_csv, table_csv
from .timeseries import plateau_index

__all__ = ["build_report", "add_parser", "DEFINITIONS"]

LPM = 6e4
DEFINITIONS = (
    "Times are MCAP log times relative to the first bench message. Bench and twin series are averaged "
    "in 0.1 s bins. Plateaus: bench speed and delivery pressure (0.5 s moving mean) change by less than "
    "15 rpm/s and 0.3 bar/s; the first 1 s of such a stretch (drive, valve and flow-meter settling) is "
    "dropped and at least 1.5 s must remain. Errors are predicted minus measured. Flow: the twin's revolution-mean delivery flow "
    "(twin/flow_summary) against the bench flow meter. Measured volumetric efficiency = measured flow / "
    "(displacement x measured speed / 2 pi), displacement from the twin's pump configuration; predicted = "
    "the twin's. Bias = mean error, RMSE = root mean square error, max |err| = largest absolute error over "
    "the bins of a plateau; 'all plateaus' pools every plateau bin; 'whole run' uses every bin, "
    "transitions included (there the flow meter's own lag shows). Verdict: a plateau passes when its mean "
    "errors lie inside the tolerances of the acceptance criterion stated above the tables (defaults in "
    "docs/offline.md; set with --tol-flow-lpm, --tol-flow-rel, --tol-eta-pts or --acceptance F.yaml); "
    "'no data' when too few of its bins have a prediction. Interactive plots: traces longer than the point "
    "budget (--max-points) are drawn as the minimum and maximum of equal-time buckets; the CSV files hold "
    "the full 0.1 s grid. Chamber pressure vs angle: every once-per-revolution waveform the twin logged "
    "inside the plateau, folded onto one revolution (mean and min-max). Tooth-gap heights: the twin's logged "
    "outer-gear displacement folded onto one revolution (angle from the revolution stamps of "
    "twin/flow_summary), gaps computed from the pump geometry with the model's own contact routine.")


def _json_ready(comp: dict) -> dict:
    return {k: v for k, v in comp.items() if not isinstance(v, np.ndarray)}


def _load(bench_path, twin_paths, labels):
    if not twin_paths:
        raise InputError("--twin", [], "one or more twin MCAP files")
    if labels and len(labels) != len(twin_paths):
        raise InputError("--label", labels, f"{len(twin_paths)} labels (one per --twin)")
    bench = load_bench(bench_path)
    twins = [load_twin(p, bench.t0_ns, labels[i] if labels else None) for i, p in enumerate(twin_paths)]
    seen = {}
    for i, tw in enumerate(twins):
        if tw.label in seen:
            tw.label = f"{tw.label} [{i + 1}]"
        seen[tw.label] = i
    return bench, twins


def make_context(bench, twins, criterion: AcceptanceCriterion, stem: str,
                 max_points: int = DEFAULT_MAX_POINTS, flow_sensor_tau_s: float = 0.0,
                 flow_meter: str = "delivery") -> ReportContext:
    """Grid, plateaus, metrics and verdicts of a bench recording against twin logs (the twins' flow read through
    the bench flow meter's lag ``flow_sensor_tau_s`` [s] when > 0, and at its pressure, ``flow_meter``:
    :func:`.analysis.compare`)."""
    span = overlap(bench, twins)
    grid = make_grid(bench, span)
    cfg = pump_config(twins[0])
    plateaus = find_plateaus(grid, p_atm=cfg.fluid.atmospheric_pa)
    disp = cfg.gears.displacement_closed_form()
    temps = plateau_temperatures(bench, grid, plateaus)
    expand = meter_expansion(grid, plateaus, temps, cfg) if flow_meter == "atmospheric" else None
    comps = [add_temperatures(compare(grid, plateaus, tw, disp, flow_sensor_tau_s, expand), temps) for tw in twins]
    verdicts = tuple(tuple(verdict(r, criterion) for r in c["plateaus"]) for c in comps)
    return ReportContext(bench, tuple(twins), grid, tuple(plateaus), tuple(comps), verdicts, cfg, disp, criterion,
                         span, stem, max_points)


def _notes(ctx: ReportContext) -> list[str]:
    notes = list(ctx.bench.warnings) + [w for tw in ctx.twins for w in tw.warnings]
    for tw in ctx.twins:
        if tw.missing:
            notes.append(f"{tw.path}: optional topics absent, their figures are skipped: {', '.join(tw.missing)}")
        if not tw.pump_config_yaml:
            notes.append(f"{tw.path}: no pump configuration in the metadata; config/pump.yaml is assumed")
    if not ctx.plateaus:
        notes.append("no steady plateau found: per-plateau metrics, verdicts and angle plots are empty")
    if ctx.bench.meta.get("gerotor_twin.bench_emulator", {}).get("synthetic") == "true":
        notes.append(f"{ctx.bench.path} is a SYNTHETIC recording made by `gerotor-twin synth-bench` "
                     "(bench emulator, see bags/README.md), not measured data.")
    return notes


def _headline(ctx: ReportContext) -> list[str]:
    """Per twin: verdict counts and pooled errors; with two or more twins first their verdicts side by side."""
    out = []
    if len(ctx.comps) > 1:
        out.append(f"{len(ctx.plateaus)} plateaus — "
                   + "; ".join(f"{c['label']}: {tally_text(vs)}" for c, vs in zip(ctx.comps, ctx.verdicts)))
    for c, vs in zip(ctx.comps, ctx.verdicts):
        fe, ee = c["overall"]["flow_error_m3s"], c["overall"]["eta_error"]
        count = f"{len(vs)} plateaus: {tally_text(vs)}"
        if fe["n"]:
            out.append(f"{c['label']}: {count}; mean-flow error bias {fe['bias'] * LPM:+.3f} L/min, RMSE "
                       f"{fe['rmse'] * LPM:.3f} L/min, max {fe['max_abs'] * LPM:.3f} L/min; volumetric efficiency "
                       f"bias {ee['bias'] * 100:+.2f} %-pt, RMSE {ee['rmse'] * 100:.2f} %-pt")
        else:
            out.append(f"{c['label']}: no plateau samples to compare")
    out.append(f"Acceptance criterion: {ctx.criterion.describe()}.")
    return out


def _downloads(ctx: ReportContext, blocks: list) -> list[tuple[str, str, str]]:
    panels = [b for b in blocks if isinstance(b, TimeSeries)]
    out = [(f"{ctx.stem}_aligned.csv", aligned_csv(ctx, panels, plateau_index(ctx)),
            f"every series on the common {ctx.grid_dt:g} s grid, plateau number per row")]
    out += [(t.csv_name, table_csv(t), f"table: {t.title or t.heading}") for t in blocks if isinstance(t, Table)]
    return out


def build_report(bench_path, twin_paths, output, json_path=None, labels=None, title=None,
                 criterion: AcceptanceCriterion | None = None, max_points: int = DEFAULT_MAX_POINTS,
                 csv_dir=None, flow_sensor_tau_s: float = 0.0, flow_meter: str = "delivery") -> dict:
    """Write the HTML report (and JSON metrics, and optionally the CSV files); return the metrics dict.

    Parameters
    ----------
    bench_path : path
        Bench recording (MCAP with the bench topics).
    twin_paths : list of path
        One or more twin logs (node MCAP or ``run-bag`` output).
    output : path
        HTML file to write (self-contained; its CSV downloads are embedded as data: URIs).
    json_path : path, optional
        JSON metrics file (SI units; key names carry them).
    labels : list of str, optional
        Legend label per twin file (default: its bearing model or file stem).
    criterion : AcceptanceCriterion, optional
        Tolerances of the per-plateau verdict (default: :class:`AcceptanceCriterion` defaults).
    max_points : int
        Point budget per trace of the interactive plots (longer traces become min/max envelopes).
    csv_dir : path, optional
        Also write the CSV files (the page's downloads) into this directory.
    flow_sensor_tau_s : float
        Time constant of the bench's flow meter [s] (first-order lag, 0: none): the twins' flow is compared as
        that meter reads it (:func:`.analysis.read_through_lag`).
    flow_meter : str
        Where the bench's flow meter reads (``hydraulics.meter.FLOW_METERS``): ``atmospheric`` (a return-line
        meter) compares the twins' flow as the same mass's volume at atmospheric pressure
        (:func:`.analysis.meter_expansion`).

    Raises
    ------
    McapReadError
        A file is missing, truncated beyond its header, corrupt, lacks a required topic, has a
        wrong type, or does not overlap the bench in time.
    InputError
        Bad labels or ``max_points``.
    """
    if not isinstance(max_points, int) or max_points < 100:
        raise InputError("--max-points", max_points, "an integer >= 100")
    check_range("--flow-sensor-tau", flow_sensor_tau_s, 0.0, 60.0, unit="s")
    bench, twins = _load(bench_path, twin_paths, labels)
    ctx = make_context(bench, twins, criterion or AcceptanceCriterion(), Path(output).stem, max_points,
                       flow_sensor_tau_s, flow_meter)
    blocks = layout.blocks(ctx)
    specs = [panel_data(b, max_points) for b in blocks if isinstance(b, TimeSeries)]
    downloads = _downloads(ctx, blocks)
    notes, headline = _notes(ctx), _headline(ctx)
    if flow_sensor_tau_s > 0:
        notes.append(f"the twins' flow is compared as the bench's flow meter reads it, through a first-order lag of "
                     f"{flow_sensor_tau_s:g} s (--flow-sensor-tau)")
    if flow_meter == "atmospheric":
        notes.append("the twins' flow is compared as a flow meter at atmospheric pressure reads it, the same mass's "
                     "volume there (--flow-meter atmospheric)")
    page = render(title or f"Twin vs bench: {Path(bench.path).name}", headline, notes, blocks, specs,
                  ctx.plateaus, ctx.span, provenance(ctx), downloads, DEFINITIONS)
    Path(output).parent.mkdir(parents=True, exist_ok=True)
    Path(output).write_text(page, encoding="utf-8")
    if csv_dir:
        Path(csv_dir).mkdir(parents=True, exist_ok=True)
        for name, text, _ in downloads:
            (Path(csv_dir) / name).write_text(text, encoding="utf-8")
    result = {"bench": bench.path, "span_s": list(ctx.span), "displacement_m3": ctx.displacement_m3,
              "plateaus": [p.__dict__ for p in ctx.plateaus], "twins": [_json_ready(c) for c in ctx.comps],
              "acceptance": ctx.criterion.as_dict(), "flow_sensor_tau_s": flow_sensor_tau_s, "flow_meter": flow_meter,
              "verdicts": [[dict(v, plateau=p.index) for v, p in zip(vs, ctx.plateaus)] for vs in ctx.verdicts],
              "headline": headline, "notes": notes, "downloads": [n for n, _, _ in downloads],
              "figures_drawn": sum(1 for b in blocks if getattr(b, "png", None) is not None),
              "interactive_plots": len(specs), "html_bytes": len(page.encode("utf-8"))}
    if json_path:
        Path(json_path).parent.mkdir(parents=True, exist_ok=True)
        Path(json_path).write_text(json.dumps(result, indent=2, default=_num))
    return result


def _num(v):
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    raise TypeError(type(v).__name__)


def cmd_report(args) -> int:
    import sys
    from gerotor_twin.io import McapReadError
    crit = criterion_from_args(args)
    try:
        res = build_report(args.bench, args.twin, args.output, args.json, args.label, criterion=crit,
                           max_points=args.max_points, csv_dir=args.csv_dir, flow_sensor_tau_s=args.flow_sensor_tau,
                           flow_meter=args.flow_meter)
    except McapReadError as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr)
        return 2
    print(f"wrote {args.output}" + (f" and {args.json}" if args.json else "")
          + (f"; CSV in {args.csv_dir}" if args.csv_dir else ""))
    for n in res["notes"]:
        print(f"note: {n}", file=sys.stderr)
    for h in res["headline"]:
        print(h)
    failed = any(v["verdict"] != PASS for vs in res["verdicts"] for v in vs)
    return 1 if args.check and (failed or not res["plateaus"]) else 0


def add_parser(sub) -> None:
    p = sub.add_parser("report", help="HTML comparison report: bench recording vs twin log(s)",
                       description="Align bench and twin series by time, detect steady plateaus, compute "
                                   "error metrics and a pass/fail verdict per plateau, and write one "
                                   "self-contained, interactive HTML page (works offline; CSV downloads inside).")
    p.add_argument("--bench", required=True, help="bench recording (MCAP)")
    p.add_argument("--twin", required=True, action="append",
                   help="twin log (node MCAP or run-bag output); give twice to compare models")
    p.add_argument("--label", action="append", help="legend label per --twin (same order)")
    p.add_argument("-o", "--output", required=True, help="HTML file to write")
    p.add_argument("--json", metavar="F", help="also write the metrics to this JSON file (SI units)")
    p.add_argument("--csv-dir", metavar="DIR", help="also write the page's CSV files into DIR")
    p.add_argument("--max-points", type=int, default=DEFAULT_MAX_POINTS, metavar="N",
                   help=f"points per trace in the interactive plots; longer traces are drawn as min/max "
                        f"envelopes (default {DEFAULT_MAX_POINTS})")
    p.add_argument("--flow-sensor-tau", type=float, default=0.0, metavar="S",
                   help="time constant of the bench's flow meter [s] (first-order lag): the twin's flow is compared "
                        "as that meter reads it (default 0 = as predicted)")
    p.add_argument("--flow-meter", choices=FLOW_METERS, default="delivery",
                   help="where the bench's flow meter reads: at the delivery pressure (default) or at atmospheric "
                        "pressure (a return-line meter: the twins' flow compared as the same mass's volume there)")
    p.add_argument("--check", action="store_true",
                   help="exit with status 1 unless every plateau passes the acceptance criterion")
    add_arguments(p)
    p.set_defaults(func=cmd_report)
