"""``gerotor-twin`` subcommands of the bearing part: ``bearing-steady``, ``bearing-benchmark``.

:func:`add_parser` adds them to the project's argparse sub-parsers; each
handler is ``(args) -> int`` and raises :class:`~gerotor_twin.errors.InputError`
on bad input (the main CLI prints it without a traceback).
"""
from __future__ import annotations

import argparse
import json
import math

import numpy as np

from gerotor_twin.bearing.registry import make_bearing
from gerotor_twin.bearing.benchmark import (BENCH_EPS0, BENCH_METHODS, compare_with_ross,
                                            format_table, plot_trajectories, run_benchmark)
from gerotor_twin.bearing.closed_form import ocvirk_attitude_angle, ocvirk_eccentricity
from gerotor_twin.bearing.geometry import TABLE1
from gerotor_twin.bearing.reynolds_fd import parse_grid
from gerotor_twin.bearing.simulate import settle
from gerotor_twin.errors import InputError, check_range, one_line

__all__ = ["add_parser", "cmd_bearing_steady", "cmd_bearing_benchmark", "main"]

STEADY_METHODS = ("mobility", "short", "fdm")


def add_parser(subparsers) -> None:
    """Add ``bearing-steady`` and ``bearing-benchmark`` to an argparse sub-parser set.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        From ``parser.add_subparsers()``.
    """
    p = subparsers.add_parser(
        "bearing-steady",
        help="outer-gear bearing (paper Table 1) under a constant load: settled position",
        description="Run the Table 1 journal bearing under a constant load until the centre "
                    "settles; compare with the Ocvirk short-bearing closed form.")
    p.add_argument("--method", default="mobility", help="mobility | short | fdm")
    p.add_argument("--load-n", required=True, help="load magnitude [N]")
    p.add_argument("--rpm", default="500", help="journal speed [rpm] (default 500)")
    p.add_argument("--load-angle-deg", default="-90",
                   help="load direction [deg] from +x, counter-clockwise (default -90)")
    p.add_argument("--grid", default="320x40", help="FDM grid NXxNY (default 320x40)")
    p.add_argument("--json", metavar="F", help="write the result to this JSON file")
    p.set_defaults(func=cmd_bearing_steady)

    b = subparsers.add_parser(
        "bearing-benchmark",
        help="paper sec. 2.4: mobility vs Method 1 vs FDM on a dynamic load, timed",
        description="Run the three journal-bearing models on the benchmark load (Table 1 "
                    "bearing, 500 rpm, dt = 1e-4 s), time one revolution (1200 steps), "
                    "compare trajectories and print a Table-2-like summary.")
    b.add_argument("--methods", default=",".join(BENCH_METHODS),
                   help="comma-separated subset of mobility,short,fdm")
    b.add_argument("--grid", default="320x40", help="FDM grid NXxNY (default 320x40)")
    b.add_argument("--repeats", default="3", help="timed runs per method (median reported)")
    b.add_argument("--revolutions", default="3", help="length of the trajectory runs [rev]")
    b.add_argument("--json", metavar="F", help="write the summary to this JSON file")
    b.add_argument("--plot", metavar="F", help="save load + trajectory figure (PNG/PDF/SVG)")
    b.add_argument("--ross", action="store_true",
                   help="also compare one static FDM solve with ross-rotordynamics (optional)")
    b.set_defaults(func=cmd_bearing_benchmark)


def _write_json(path: str, data: dict) -> None:
    try:
        with open(path, "w", encoding="utf-8") as fh:
            json.dump(data, fh, indent=2)
            fh.write("\n")
    except OSError as exc:
        raise InputError("json", path, "a writable file path", str(exc)) from None


def _int(field: str, text: str, lo: int, hi: int) -> int:
    try:
        v = int(str(text))
    except ValueError:
        raise InputError(field, text, f"integer in [{lo}, {hi}]") from None
    if not lo <= v <= hi:
        raise InputError(field, text, f"integer in [{lo}, {hi}]")
    return v


def cmd_bearing_steady(args: argparse.Namespace) -> int:
    """Handler of ``bearing-steady``: settle under a constant load, print + JSON."""
    method = str(args.method)
    if method not in STEADY_METHODS:
        raise InputError("method", method, " | ".join(STEADY_METHODS))
    load_n = check_range("load_n", _float(args.load_n, "load_n"), 0.0, 1e7, unit="N")
    rpm = check_range("rpm", _float(args.rpm, "rpm"), 0.0, 1e5, lo_open=True, unit="rpm")
    angle_deg = check_range("load_angle_deg", _float(args.load_angle_deg, "load_angle_deg"),
                            -360.0, 360.0, unit="deg")
    nx, ny = parse_grid(args.grid)
    opts = {"nx": nx, "ny": ny} if method == "fdm" else {}
    geometry = TABLE1
    model = make_bearing(method, geometry, **opts)
    omega = rpm * 2.0 * math.pi / 60.0
    ang = math.radians(angle_deg)
    load = load_n * np.array([math.cos(ang), math.sin(ang)])
    c = geometry.clearance_m
    res = settle(model, load, omega, c * np.asarray(BENCH_EPS0))
    e = res.e
    eps = float(math.hypot(e[0], e[1]) / c)
    att = math.degrees(math.atan2(e[1], e[0]) - ang)
    att = (att + 180.0) % 360.0 - 180.0
    eps_cf = ocvirk_eccentricity(load_n, geometry, omega)
    att_cf = math.degrees(ocvirk_attitude_angle(eps_cf)) if eps_cf > 0 else 90.0
    out = {
        "method": method, "load_n": load_n, "rpm": rpm, "load_angle_deg": angle_deg,
        "eccentricity_ratio": eps, "attitude_angle_deg": float(att) if eps > 0 else 90.0,
        "closed_form_eccentricity_ratio": eps_cf, "closed_form_attitude_angle_deg": att_cf,
        "eccentricity_m": [float(e[0]), float(e[1])],
        "min_film_thickness_m": float(c - math.hypot(e[0], e[1])),
        "settle_time_s": res.t_settle, "settled_by_time_marching": res.settled,
        "grid": [nx, ny] if method == "fdm" else None,
    }
    print(f"bearing-steady ({method}, Table 1 bearing, {rpm:g} rpm, {load_n:g} N at "
          f"{angle_deg:g} deg):")
    print(f"  eccentricity ratio   {eps:.6f}   (Ocvirk closed form {eps_cf:.6f})")
    print(f"  attitude angle [deg] {out['attitude_angle_deg']:.4f}   "
          f"(Ocvirk closed form {att_cf:.4f}; from the load, in the sense of rotation)")
    print(f"  min film thickness   {out['min_film_thickness_m'] * 1e6:.3f} um; "
          f"settled after {res.t_settle:.3g} s simulated")
    if args.json:
        _write_json(args.json, out)
    return 0


def _float(text, field: str) -> float:
    try:
        return float(str(text))
    except ValueError:
        raise InputError(field, text, "a number") from None


def cmd_bearing_benchmark(args: argparse.Namespace) -> int:
    """Handler of ``bearing-benchmark``: run, print the table, JSON, plot."""
    grid = parse_grid(args.grid)
    repeats = _int("repeats", args.repeats, 1, 50)
    revolutions = check_range("revolutions", _float(args.revolutions, "revolutions"), 0.0, 100.0,
                              lo_open=True, unit="rev")
    result = run_benchmark(args.methods, grid=grid, repeats=repeats, revolutions=revolutions)
    print(format_table(result))
    summary = result.to_dict()
    if getattr(args, "ross", False):
        cmp = compare_with_ross(grid)
        if cmp is not None:
            print(cmp)
            summary["ross"] = {"eps": cmp.eps, "grid": list(cmp.grid),
                               "ours_radial_tangential_magnitude_n": list(cmp.ours_n),
                               "ross_radial_tangential_magnitude_n": list(cmp.ross_n),
                               "load_difference": cmp.load_difference,
                               "ours_s": cmp.ours_s, "ross_s": cmp.ross_s}
        else:
            summary["ross"] = "ross-rotordynamics not installed"
    if args.plot:
        try:
            plot_trajectories(result, args.plot)
        except (OSError, ValueError) as exc:
            raise InputError("plot", args.plot, "a writable .png/.pdf/.svg path", str(exc)) \
                from None
        print(f"figure written to {args.plot}")
    if args.json:
        _write_json(args.json, summary)
    return 0


def main(argv=None) -> int:
    """Stand-alone entry (``python -m gerotor_twin.bearing.cli_commands ...``) until the
    subcommands are wired into ``gerotor-twin``; prints InputError without a traceback."""
    import sys

    parser = argparse.ArgumentParser(prog="python -m gerotor_twin.bearing.cli_commands")
    add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except InputError as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
