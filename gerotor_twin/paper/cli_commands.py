"""``gerotor-twin paper efficiency | figures | calibrate`` (section 4 of the paper)."""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from gerotor_twin.bearing.registry import MODEL_NAMES as MODELS

__all__ = ["add_parser"]


def _progress(done, total, pt):
    print(f"\r  {done}/{total}: {pt['model']} {pt['rpm']:g} rpm {pt['bar']:g} bar   ",
          end="", file=sys.stderr, flush=True)


def print_efficiency_tables(points: list[dict], slopes: list[dict], out=print) -> None:
    """Tables 3–5 side by side: model, paper, difference [percentage points]."""
    by = {(p["model"], p["rpm"], p["bar"]): p for p in points}
    models = list(dict.fromkeys(p["model"] for p in points))
    speeds = sorted({p["rpm"] for p in points})
    bars = sorted({p["bar"] for p in points})
    sl = {(s["model"], s["rpm"]): s for s in slopes}
    for rpm in speeds:
        out(f"\nvolumetric efficiency [%] at {rpm:g} rpm (paper: table {3 + speeds.index(rpm)} of [1])")
        out(f"  {'':22s}" + "".join(f"{b:>8g} bar" for b in bars) + "   slope [%/bar]")
        for m in models:
            row = [by.get((m, rpm, b)) for b in bars]
            s = sl.get((m, rpm))
            out(f"  {m + ' (this model)':22s}" + "".join(f"{100 * p['volumetric_efficiency']:12.2f}" for p in row)
                + f"   {100 * s['slope_per_bar']:8.3f}")
            if all(p["paper"] is not None for p in row):
                out(f"  {m + ' (paper)':22s}" + "".join(f"{100 * p['paper']:12.2f}" for p in row)
                    + f"   {100 * s['paper_slope_per_bar']:8.3f}")
                out(f"  {'  difference [pt]':22s}" + "".join(f"{100 * p['difference']:+12.2f}" for p in row)
                    + f"   {100 * s['relative_difference']:+7.1f} %")
        if "fixed" in models and "mobility" in models:
            gain = [100 * (by[("mobility", rpm, b)]["volumetric_efficiency"]
                           - by[("fixed", rpm, b)]["volumetric_efficiency"]) for b in bars]
            out(f"  {'mobility − fixed [pt]':22s}" + "".join(f"{g:+12.2f}" for g in gain))
            if all(by[(m, rpm, b)]["paper"] is not None for m in ("fixed", "mobility") for b in bars):
                pg = [100 * (by[("mobility", rpm, b)]["paper"] - by[("fixed", rpm, b)]["paper"]) for b in bars]
                out(f"  {'  in the paper [pt]':22s}" + "".join(f"{g:+12.2f}" for g in pg))


def cmd_efficiency(args) -> int:
    from ..config import load_config
    from .efficiency import efficiency_points, row_slopes

    cfg = load_config(args.config)
    models = tuple(args.models.split(","))
    for m in models:
        if m not in MODELS:
            from ..errors import InputError
            raise InputError("--models", m, " | ".join(MODELS))
    t0 = time.perf_counter()
    points = efficiency_points(cfg, models=models, progress=_progress, fluid_model=args.fluid_model,
                               suction_edge=args.suction_edge, orifice_law=args.orifice_law)
    print(f"\r  {len(points)} points in {time.perf_counter() - t0:.1f} s" + " " * 30, file=sys.stderr)
    slopes = row_slopes(points)
    print(f"pump {cfg.source}: tooth-tip clearance {cfg.clearances.tooth_tip_m * 1e6:.2f} µm, "
          f"lateral {cfg.clearances.lateral_m * 1e6:.2f} µm (calibrated to the fixed rows, docs/calibration.json)")
    print_efficiency_tables(points, slopes)
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps({"points": points, "slopes": slopes}, indent=1))
        print(f"\nwrote {args.json}")
    return 0


def cmd_figures(args) -> int:
    from ..config import load_config
    from .figures import write_figures

    cfg = load_config(args.config)
    t0 = time.perf_counter()
    paths = write_figures(cfg, args.out, models=tuple(args.models.split(",")), progress=print)
    for p in paths:
        print(f"wrote {p}")
    print(f"({time.perf_counter() - t0:.1f} s)")
    return 0


def print_valley(res: dict, out=print) -> None:
    """The three tables of ``paper calibrate --valley``: fit, loss split, MM − fixed."""
    rows = res["rows"]
    out("\nfit to the fixed-centre rows of tables 3–5 (lateral clearance refitted at each δ; criteria ±2 pt, "
        "slopes ±10 %)")
    out(f"  {'δ [µm]':>7s} {'lateral [µm]':>13s} {'rms [pt]':>9s} {'max [pt]':>9s}   slope error 1000/2000/3000 rpm")
    for r in rows:
        s = r["slope_relative_error"]
        out(f"  {r['tooth_tip_m'] * 1e6:7.1f} {r['lateral_m'] * 1e6:13.1f} {r['rms_difference_pt']:9.2f} "
            f"{r['max_point_difference_pt']:9.2f}   " + " ".join(f"{100 * s[k]:+6.1f} %" for k in ("1000", "2000", "3000"))
            + ("   pass" if r["passed"] else "   FAIL"))
    sp = res["split_point"]
    out(f"\nlost points by path, fixed centre, {sp['rpm']:g} rpm / {sp['bar']:g} bar [pt of the theoretical flow]")
    out(f"  {'δ [µm]':>7s} {'lost':>7s} {'drain':>7s} {'lateral':>8s} {'suc–del':>8s} {'tips':>7s} {'filling':>8s} "
        f"{'interaction':>12s}")
    for r in rows:
        ls = r["loss_split_pt"]
        out(f"  {r['tooth_tip_m'] * 1e6:7.1f} {ls['lost']:7.2f} {ls['drain']:7.2f} {ls['lateral']:8.2f} "
            f"{ls['suction_delivery']:8.2f} {ls['tips']:7.2f} {ls['filling']:8.2f} {ls['interaction']:12.2f}")
    keys = list(rows[0]["mm_minus_fixed_pt"]["rotate"])
    out("\nMM − fixed [pt], gap-driven (nominal chamber volumes), fixed-centre contact rule rotate | none "
        "(paper: +1.35 … +2.08 at 5 bar, +1.92 … +2.08 at 27.5 bar)")
    out(f"  {'δ [µm]':>7s} {'rule':>6s} " + " ".join(f"{k + ' rpm/bar':>16s}" for k in keys))
    for r in rows:
        for rule in ("rotate", "none"):
            g = r["mm_minus_fixed_pt"][rule]
            out(f"  {r['tooth_tip_m'] * 1e6:7.1f} {rule:>6s} " + " ".join(f"{g[k]:+16.2f}" for k in keys))


def cmd_valley(args) -> int:
    from ..config import load_config
    from ..errors import InputError
    from .valley import valley

    cfg = load_config(args.config)
    try:
        deltas = [float(v) for v in args.deltas.split(",")]
    except ValueError:
        raise InputError("--deltas", args.deltas, "comma-separated tooth-tip clearances in (0, 500) µm") from None
    for d in deltas:
        if not 0.0 < d < 500.0:
            raise InputError("--deltas", d, "(0, 500) µm")
    t0 = time.perf_counter()
    res = valley(cfg, deltas, progress=lambda line: print("  " + line, file=sys.stderr, flush=True))
    res["wall_time_s"] = time.perf_counter() - t0
    print(f"pump {cfg.source}; {len(deltas)} tooth-tip clearances in {res['wall_time_s']:.0f} s")
    print_valley(res)
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(res, indent=1))
        print(f"\nwrote {args.json}")
    return 0


def cmd_calibrate(args) -> int:
    from ..config import load_config
    from .calibration import calibrate, save

    if args.valley:
        return cmd_valley(args)
    cfg = load_config(args.config)
    print("fitting the tooth-tip and lateral clearances to the fixed-centre rows of tables 3–5 ...")
    res = calibrate(cfg, start=(args.start_tip_um * 1e-6, args.start_lateral_um * 1e-6))
    acc = res["acceptance"]
    print(f"\nbest: tooth-tip δ = {res['tooth_tip_m'] * 1e6:.2f} µm, lateral = {res['lateral_m'] * 1e6:.2f} µm; "
          f"rms {100 * res['rms_difference']:.2f} pt, max {100 * acc['max_point_difference']:.2f} pt "
          f"(≤ 2), worst slope {100 * acc['max_slope_relative_difference']:.1f} % (≤ 10): "
          f"{'PASS' if acc['passed'] else 'FAIL'}  ({res['wall_time_s']:.0f} s)")
    print(f"wrote {save(res, args.out)}; put the two values into the pump YAML (clearances).")
    return 0 if acc["passed"] else 1


def add_parser(sub) -> None:
    """Add ``paper`` with its three sub-commands to the ``gerotor-twin`` parser."""
    from .calibration import DEFAULT_RESULT_PATH
    from .valley import DEFAULT_DELTAS_UM

    p = sub.add_parser("paper", help="reproduce section 4 of the paper (tables 3–5, figs. 12–16)")
    ps = p.add_subparsers(dest="paper_command", required=True)
    e = ps.add_parser("efficiency", help="tables 3–5: model vs paper, side by side")
    e.add_argument("--models", default="fixed,mobility", help="comma-separated outer-gear models")
    e.add_argument("--json", help="write {points: [{rpm, bar, model, volumetric_efficiency, paper}, ...]}")
    e.add_argument("--fluid-model", default="paper", choices=("paper", "mixture"),
                   help="oil state equation: paper = eq. (23), as calibrated (default); mixture = oil + air + vapour")
    e.add_argument("--suction-edge", default="ray", choices=("ray", "chamber"),
                   help="suction kidney's closing edge: ray, as calibrated (default); chamber = the twin's default pump")
    e.add_argument("--orifice-law", default="flow_number", choices=("flow_number", "merritt"),
                   help="port orifice law: flow_number, as calibrated (default); merritt = the twin's default pump")
    e.add_argument("--config", help="pump YAML (default config/pump.yaml)")
    e.set_defaults(func=cmd_efficiency)
    f = ps.add_parser("figures", help="counterparts of figs. 12–16 (PNG)")
    f.add_argument("--out", default="out/paper", help="output directory")
    f.add_argument("--models", default=",".join(MODELS), help="outer-gear models for figs. 13–16")
    f.add_argument("--config", help="pump YAML")
    f.set_defaults(func=cmd_figures)
    c = ps.add_parser("calibrate", help="fit δ and the lateral clearance to the fixed rows (≈ 2 min)")
    c.add_argument("--start-tip-um", type=float, default=31.4, help="initial tooth-tip clearance [µm]")
    c.add_argument("--start-lateral-um", type=float, default=134.8, help="initial lateral clearance [µm]")
    c.add_argument("--out", default=str(DEFAULT_RESULT_PATH), help="result JSON")
    c.add_argument("--config", help="pump YAML")
    c.add_argument("--valley", action="store_true",
                   help="instead of fitting: for each δ of --deltas refit the lateral clearance and print fit, "
                        "loss split by path and MM − fixed (≈ 5–25 s per δ)")
    c.add_argument("--deltas", default=",".join(f"{d:g}" for d in DEFAULT_DELTAS_UM),
                   help="tooth-tip clearances of --valley [µm], comma-separated")
    c.add_argument("--json", help="--valley: write the table as JSON (docs/valley.json is the recorded one)")
    c.set_defaults(func=cmd_calibrate)
