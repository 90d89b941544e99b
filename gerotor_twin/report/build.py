"""``gerotor-twin report``: bench recording vs one or more twin logs -> HTML page and JSON metrics."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from gerotor_twin.errors import InputError, one_line

from . import figures as F
from .analysis import add_temperatures, compare, find_plateaus, make_grid, plateau_temperatures
from .data import load_bench, load_twin, overlap, pump_config
from .html import figure, render

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
    "the bins of a plateau; 'all plateau samples' pools every plateau bin; 'whole run' uses every bin, "
    "transitions included (there the flow meter's own lag shows). Chamber pressure vs angle: the twin's "
    "once-per-revolution waveform nearest the middle of the plateau. Tooth-gap heights: the twin's logged "
    "outer-gear displacement folded onto one revolution (angle from the revolution stamps of "
    "twin/flow_summary), gaps computed from the pump geometry with the model's own contact routine.")


def _json_ready(comp: dict) -> dict:
    return {k: v for k, v in comp.items() if not isinstance(v, np.ndarray)}


def build_report(bench_path, twin_paths, output, json_path=None, labels=None, title=None) -> dict:
    """Write the HTML report (and JSON metrics); return the metrics dict.

    Parameters
    ----------
    bench_path : path
        Bench recording (MCAP with the bench topics).
    twin_paths : list of path
        One or more twin logs (node MCAP or ``run-bag`` output).
    output : path
        HTML file to write.
    json_path : path, optional
        JSON metrics file (SI units; key names carry them).
    labels : list of str, optional
        Legend label per twin file (default: its bearing model or file stem).

    Raises
    ------
    McapReadError
        A file is missing, truncated beyond its header, corrupt, lacks a required topic, has a
        wrong type, or does not overlap the bench in time.
    """
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
    span = overlap(bench, twins)
    grid = make_grid(bench, span)
    cfg = pump_config(twins[0])
    plateaus = find_plateaus(grid, p_atm=cfg.fluid.atmospheric_pa)
    disp = cfg.gears.displacement_closed_form()
    temps = plateau_temperatures(bench, grid, plateaus)
    comps = [add_temperatures(compare(grid, plateaus, tw, disp), temps) for tw in twins]
    chosen = F.choose_plateaus(plateaus)

    notes = [w for w in bench.warnings] + [w for tw in twins for w in tw.warnings]
    for tw in twins:
        if tw.missing:
            notes.append(f"{tw.path}: optional topics absent, their figures are skipped: {', '.join(tw.missing)}")
        if not tw.pump_config_yaml:
            notes.append(f"{tw.path}: no pump configuration in the metadata; config/pump.yaml is assumed")
    if not plateaus:
        notes.append("no steady plateau found: per-plateau metrics and angle plots are empty")
    synthetic = bench.meta.get("gerotor_twin.bench_emulator", {}).get("synthetic") == "true"
    if synthetic:
        notes.append(f"{bench.path} is a SYNTHETIC recording made by `gerotor-twin synth-bench` "
                     "(bench emulator, see bags/README.md), not measured data.")
    why = "no twin file has the topic"
    figs = [
        figure(F.fig_operating(bench, grid, plateaus), "fig-operating",
               "Bench shaft speed and delivery pressure; grey: detected plateaus (numbered)."),
        figure(F.fig_flow(grid, plateaus, comps), "fig-flow",
               "Mean delivery flow, measured (flow meter) vs predicted (twin revolution means), and residual."),
        figure(F.fig_efficiency_map(comps) if plateaus else None, "fig-eta-map",
               "Volumetric efficiency per plateau [%]: measured and predicted, with the plateau's mean oil "
               "temperature (the twin's properties follow it).", "no plateaus"),
        figure(F.fig_waveforms(twins, chosen), "fig-waveform",
               "Predicted chamber-1 pressure over one revolution at chosen plateaus.",
               "no plateaus" if not chosen else f"{why} /twin/chamber_waveform"),
        figure(F.fig_trajectory(twins, plateaus, cfg.clearances.housing_radial_m), "fig-trajectory",
               "Predicted outer-gear centre displacement inside the radial clearance circle.",
               f"{why} /twin/eccentricity"),
        figure(F.fig_gaps(twins, chosen, cfg), "fig-gaps",
               "Tooth-tip gap heights over one revolution at chosen plateaus (bold: gap 1).",
               "no plateaus" if not chosen else f"{why} /twin/eccentricity"),
    ]
    headline = []
    for c in comps:
        o = c["overall"]
        fe, ee = o["flow_error_m3s"], o["eta_error"]
        if fe["n"]:
            headline.append(f"{c['label']}: {len(c['plateaus'])} plateaus; mean-flow error bias "
                            f"{fe['bias'] * LPM:+.3f} L/min, RMSE {fe['rmse'] * LPM:.3f} L/min, max "
                            f"{fe['max_abs'] * LPM:.3f} L/min; volumetric efficiency bias {ee['bias'] * 100:+.2f} "
                            f"%-pt, RMSE {ee['rmse'] * 100:.2f} %-pt")
        else:
            headline.append(f"{c['label']}: no plateau samples to compare")
    files = [{"role": "bench", "path": bench.path,
              "info": f"{len(bench.speed[0])} speed, {len(bench.delivery_pressure[0])} pressure, "
                      f"{len(bench.flow[0])} flow samples; {bench.span[1] - bench.span[0]:.1f} s"
                      + (" (synthetic)" if synthetic else "")}]
    files += [{"role": f"twin: {tw.label}", "path": tw.path,
               "info": f"{len(tw.summary[0])} revolution summaries; {tw.span[1] - tw.span[0]:.1f} s"} for tw in twins]
    page = render(title or f"Twin vs bench: {Path(bench.path).name}", files, notes, headline, figs, comps,
                  DEFINITIONS)
    Path(output).parent.mkdir(parents=True, exist_ok=True)
    Path(output).write_text(page, encoding="utf-8")
    result = {"bench": bench.path, "span_s": list(span), "displacement_m3": disp,
              "plateaus": [p.__dict__ for p in plateaus], "twins": [_json_ready(c) for c in comps],
              "headline": headline, "notes": notes, "figures_drawn": sum('class="report-figure"' in f for f in figs)}
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
    try:
        res = build_report(args.bench, args.twin, args.output, args.json, args.label)
    except McapReadError as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr)
        return 2
    print(f"wrote {args.output}" + (f" and {args.json}" if args.json else ""))
    for n in res["notes"]:
        print(f"note: {n}", file=sys.stderr)
    for h in res["headline"]:
        print(h)
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("report", help="HTML comparison report: bench recording vs twin log(s)",
                       description="Align bench and twin series by time, detect steady plateaus, compute "
                                   "error metrics and write one self-contained HTML page.")
    p.add_argument("--bench", required=True, help="bench recording (MCAP)")
    p.add_argument("--twin", required=True, action="append",
                   help="twin log (node MCAP or run-bag output); give twice to compare models")
    p.add_argument("--label", action="append", help="legend label per --twin (same order)")
    p.add_argument("-o", "--output", required=True, help="HTML file to write")
    p.add_argument("--json", metavar="F", help="also write the metrics to this JSON file (SI units)")
    p.set_defaults(func=cmd_report)

