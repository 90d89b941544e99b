"""The ``gerotor-twin`` command.

Subcommands: ``geometry``, ``simulate``, ``demo``, ``bench`` here, every other one from the
``add_parser`` of its owning module listed in ``_COMMAND_MODULES``; a command line imports only the module of its
command (``_COMMAND_OF``, :func:`command_modules`), the top-level help every one.  User errors print one line
``error: <field> = <value> is invalid; allowed: <range>`` and exit with 2,
for every command: :class:`~gerotor_twin.errors.InputError`, unreadable MCAP
input and any ``OSError`` on a path the user gave (a directory, no
permission) are caught here, the line bounded in length.
"""
from __future__ import annotations

import argparse
import contextlib
import importlib
import json
import math
import os
import sys
import time
from pathlib import Path

from .bearing_names import MODEL_NAMES
from .errors import InputError, one_line, one_line_warnings, path_error_line
from .io.reader import McapReadError
from .units import celsius_to_kelvin, kelvin_to_celsius, m3s_to_lpm, pa_abs_to_bar_gauge

__all__ = ["main", "build_parser"]


def _write_json(path, obj):
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text(json.dumps(obj, indent=2))
    print(f"wrote {path}")


def _progress(prefix):
    def cb(n, change):
        print(f"\r{prefix}: revolution {n}, settling {change:.1e}   ", end="", file=sys.stderr, flush=True)
    return cb


# ----------------------------------------------------------------- geometry
def cmd_geometry(args) -> int:
    from .config import load_config
    from .geometry.tables import cached_tables

    cfg = load_config(args.config)
    g = cfg.gears
    tab = cached_tables(g, cfg.suction_port, cfg.delivery_port, cfg.numerics.table_points)
    vol = tab.data[0]
    info = {
        "chambers": g.chambers, "inner_teeth": g.chambers - 1,
        "eccentricity_m": g.eccentricity, "lobe_centre_radius_m": g.lobe_centre_radius,
        "lobe_radius_m": g.lobe_radius, "outer_root_radius_m": g.outer_root_radius,
        "outer_radius_m": g.outer_radius, "inner_hole_radius_m": g.inner_hole_radius, "width_m": g.width,
        "tooth_tip_clearance_m": g.tip_clearance,
        "inner_tip_radius_m": g.inner_tip_radius, "inner_root_radius_m": g.inner_root_radius,
        "displacement_m3_per_rev": g.displacement_closed_form(),
        "min_chamber_volume_m3": float(vol.min()), "max_chamber_volume_m3": float(vol.max()),
        "min_convex_curvature_radius_m": g.min_convex_curvature_radius(),
        "suction_port_deg": [round(math.degrees(v), 4) for v in (cfg.suction_port.start, cfg.suction_port.end)],
        "delivery_port_deg": [round(math.degrees(v), 4) for v in (cfg.delivery_port.start, cfg.delivery_port.end)],
        "suction_closing_edge": cfg.suction_port.closing_edge,
        **_port_timing_info(cfg),
    }
    print(f"Gerotor {g.chambers}/{g.chambers - 1} from {cfg.source}")
    for k, v in info.items():
        print(f"  {k:32s} {v}")
    print(f"  displacement                     {info['displacement_m3_per_rev'] * 1e6:.3f} cm³/rev")
    if args.json:
        _write_json(args.json, info)
    if args.plot:
        from .model.plots import plot_geometry
        plot_geometry(g, args.plot, ports=(cfg.suction_port, cfg.delivery_port))
        print(f"wrote {args.plot}")
    return 0


def _port_timing_info(cfg) -> dict:
    """Sealing lands of the dead-centre chambers, the kidneys' margins over them and the relief grooves [deg, m]."""
    from .geometry.ports import port_timing, sealing_lands
    g = cfg.gears
    lands = sealing_lands(g)
    out = {"dead_centre_chamber_extent_deg": [round(math.degrees(lands.max_land), 4),
                                              round(math.degrees(lands.min_land), 4)]}
    for k, v in port_timing(g, cfg.suction_port, cfg.delivery_port).items():
        out[f"{k}_deg"] = round(math.degrees(v), 4)
    for p in (cfg.suction_port, cfg.delivery_port):
        for edge in ("opening", "closing"):
            n = getattr(p, f"{edge}_notch")
            if n is not None:
                out[f"{p.name}_{edge}_notch"] = {"length_deg": round(math.degrees(n.length), 4), "width_m": n.width,
                                                 "depth_m": n.depth, "radius_m": round(n.radius, 7), "shape": n.shape}
    return out


# ----------------------------------------------------------------- simulate
def cmd_simulate(args) -> int:
    from .config import load_config
    from .model.pump import PumpModel
    from .model.steady import SETTLE_ETOL, SETTLE_RTOL, run_steady

    cfg = load_config(args.config)
    if args.fluid_model:
        cfg = cfg.with_fluid_model(args.fluid_model)
    model = PumpModel(cfg, bearing=args.model)
    t0 = time.perf_counter()
    res = run_steady(model, args.rpm, args.bar, max_revolutions=args.revolutions,
                     progress=_progress(f"{args.rpm:g} rpm {args.bar:g} bar"), **_oil_temp(args))
    print(file=sys.stderr)
    s = res.summary()
    s["wall_time_s"] = time.perf_counter() - t0
    print(f"{args.model} model, {args.rpm:g} rpm, {args.bar:g} bar gauge ({s['revolutions']} revolutions "
          f"{'to periodic state' if res.settled else 'and not settled'}, {s['wall_time_s']:.2f} s)")
    print(f"  oil                     {kelvin_to_celsius(model.temperature_k):9.1f} °C, "
          f"μ {1e3 * model.kernel.pc.viscosity:.2f} mPa·s, fluid model {cfg.fluid_model}")
    print(f"  theoretical flow        {m3s_to_lpm(s['theoretical_flow_m3s']):9.3f} L/min")
    print(f"  mean delivery flow      {m3s_to_lpm(s['mean_delivery_flow_m3s']):9.3f} L/min")
    print(f"  volumetric efficiency   {100 * s['volumetric_efficiency']:9.2f} %")
    print(f"  delivery flow ripple    {100 * s['delivery_flow_ripple']:9.2f} %")
    p_atm = cfg.fluid.atmospheric_pa
    print(f"  chamber pressure        {pa_abs_to_bar_gauge(s['min_chamber_pressure_pa'], p_atm):9.3f} .. "
          f"{pa_abs_to_bar_gauge(s['max_chamber_pressure_pa'], p_atm):.3f} bar gauge")
    ex, ey = s["mean_eccentricity_m"]
    print(f"  mean eccentricity       ({ex * 1e6:.2f}, {ey * 1e6:.2f}) µm")
    print(f"  min tooth-tip gap       {s['min_tooth_gap_m'] * 1e6:9.3f} µm "
          f"(lobes not in contact: {s['min_open_tooth_gap_m'] * 1e6:.3f} µm; effective ⟨h³⟩^(1/3) "
          f"{s['effective_tooth_gap_m'] * 1e6:.2f} µm)")
    if not res.settled:
        last = "one revolution, none to compare it with" if math.isnan(res.periodicity_error) else \
            f"the last changed the mean flow by {res.periodicity_error:.1e}"
        print(f"  warning: not settled in {res.revolutions} revolutions ({last}; the test: {SETTLE_RTOL:g} on the "
              f"mean flow, {100 * SETTLE_ETOL:g} % of the housing clearance on the gear's mean position): not the "
              f"periodic state; raise --revolutions", file=sys.stderr)
    c = s["counts"]
    if c.get("housing_contact"):
        print(f"  warning: the outer gear reached the housing-film limit (ε = 0.95) in {c['housing_contact']} "
              f"steps: metal contact in reality; the eccentricity was held at the limit", file=sys.stderr)
    if c.get("solver_failures"):
        print(f"  warning: {c['solver_failures']} solver failures", file=sys.stderr)
    if args.json:
        _write_json(args.json, s)
    if args.plot:
        from .model.plots import plot_steady
        plot_steady(res, args.plot)
        print(f"wrote {args.plot}")
    return 0


def _oil_temp(args) -> dict:
    """``run_steady`` keyword for ``--oil-temp`` [°C → K] (none if not given)."""
    if args.oil_temp is None:
        return {}
    from .model.records import check_oil_temperature
    try:
        return {"oil_temperature": check_oil_temperature(celsius_to_kelvin(args.oil_temp))}
    except InputError:
        raise InputError("--oil-temp", args.oil_temp, "[-40, 200] °C") from None


# --------------------------------------------------------------------- demo
def cmd_demo(args) -> int:
    """For now: the default pump at 1000/2000/3000 rpm × 5–27.5 bar, table and plots."""
    from .config import load_config
    from .model.plots import plot_efficiency_map, plot_geometry, plot_steady
    from .model.pump import PumpModel
    from .model.steady import run_steady

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cfg = load_config(args.config)
    t0 = time.perf_counter()
    print("building geometry tables (cached after the first run) ...", flush=True)
    model = PumpModel(cfg, bearing=args.model)
    print(f"  ready in {time.perf_counter() - t0:.1f} s; displacement "
          f"{model.displacement * 1e6:.3f} cm³/rev, model '{args.model}'")
    plot_geometry(cfg.gears, out / "geometry.png", ports=(cfg.suction_port, cfg.delivery_port))
    speeds = (1000, 2000, 3000)
    pressures = (5, 10, 15, 20, 25, 27.5)
    points = []
    print(f"\nvolumetric efficiency [%] ({args.model} outer-gear model)")
    print("  rpm  " + "".join(f"{p:>8g} bar" for p in pressures))
    for rpm in speeds:
        row = []
        for bar in pressures:
            res = run_steady(model, rpm, bar)
            s = res.summary()
            points.append(s)
            row.append(100 * s["volumetric_efficiency"])
            if bar == 27.5:
                plot_steady(res, out / f"steady_{rpm}rpm_{bar:g}bar.png")
        print(f"  {rpm:5d}" + "".join(f"{v:12.2f}" for v in row), flush=True)
    plot_efficiency_map(points, out / "efficiency.png")
    _write_json(out / "efficiency.json", {"points": points})
    print(f"\nplots: {out}/geometry.png, {out}/efficiency.png, {out}/steady_*rpm_27.5bar.png "
          f"({time.perf_counter() - t0:.1f} s)")
    return 0


# -------------------------------------------------------------------- bench
def _floats(text: str, name: str) -> tuple[float, ...]:
    try:
        vals = tuple(float(v) for v in str(text).split(","))
    except ValueError:
        raise InputError(name, text, "comma-separated numbers") from None
    return vals


def cmd_bench(args) -> int:
    from .config import load_config
    from .model.bench import realtime

    if args.what == "parts":
        return _bench_parts(args)
    if args.family is not None and args.what in ("realtime", "accuracy"):
        return _bench_family(args)
    if args.what == "all":
        return _bench_all(args)
    cfg = _with_numerics(load_config(args.config), args.numerics)
    if args.what == "realtime":
        speeds = tuple(int(round(v)) for v in _floats(args.rpm or "1000,2000,3000", "--rpm"))
        if not all(0 < v <= cfg.range.max_speed_rpm for v in speeds):
            raise InputError("--rpm", args.rpm, f"speeds in (0, {cfg.range.max_speed_rpm:g}] rpm")
        (bar,) = _floats(args.bar or "27.5", "--bar")[:1]
        rows = realtime(cfg, models=tuple((args.models or "fixed,mobility").split(",")), speeds=speeds, bar=bar,
                        seconds=args.seconds, repeats=args.repeats, call_s=_call_s(args))
        if args.json:
            _write_json(args.json, {"realtime": rows})
    elif args.what == "accuracy":
        from .model.accuracy import print_accuracy
        from .model.bench_all import accuracy_markdown, provenance
        prov = provenance(_bench_command(args))
        rows = print_accuracy(cfg, rpms=_floats(args.rpm or "3000", "--rpm"), bars=_floats(args.bar or "27.5", "--bar"),
                              models=tuple((args.models or "mobility").split(",")),
                              check_reference=args.check_reference, cache=_reference_cache(args),
                              coupled=args.coupled_reference)
        if args.json:
            _write_json(args.json, rows[0] if len(rows) == 1 else {"points": rows})
        if args.markdown or args.write_doc:
            _write_block(args, accuracy_markdown(rows, prov.finish()), "bench accuracy")
        return 0 if all(r["within_budget"] for r in rows) else 1
    elif args.what == "models":
        from .model.bench import models_cost
        rows = models_cost(cfg, models=tuple((args.models or "fixed,mobility,short,fdm").split(",")),
                           revolutions=args.repeats)
        if args.json:
            _write_json(args.json, {"models": rows})
    return 0


def _with_numerics(cfg, text):
    """``cfg`` with the numerics fields of ``--numerics KEY=VALUE[,...]`` replaced (validated by
    :class:`~gerotor_twin.config.Numerics` itself); ``text`` None: ``cfg``."""
    import dataclasses
    if not text:
        return cfg
    fields = {f.name: f.type for f in dataclasses.fields(cfg.numerics)}
    changes = {}
    for item in str(text).split(","):
        key, _, value = item.partition("=")
        key = key.strip()
        if key not in fields or not value:
            raise InputError("--numerics", item, f"KEY=VALUE with KEY one of {', '.join(fields)}")
        current = getattr(cfg.numerics, key)
        try:
            changes[key] = type(current)(value) if not isinstance(current, str) else value.strip()
        except ValueError:
            raise InputError("--numerics", item, f"a {type(current).__name__} for {key}") from None
    return dataclasses.replace(cfg, numerics=dataclasses.replace(cfg.numerics, **changes))


def _reference_cache(args):
    """The reference cache directory of ``bench accuracy`` (None with ``--no-reference-cache``)."""
    if args.no_reference_cache:
        return None
    from .model.reference_cache import default_directory
    return args.reference_cache or default_directory()


def _bench_parts(args) -> int:
    """``bench parts``: where an output step's time goes (model/bench_parts.py), at ``--rpm``/``--bar`` of the pump
    (default 3000 rpm / 27.5 bar), or with ``--family`` at each pump's top speed and lowest pressure."""
    from .config import load_config
    from .compile_events import announce_compilation
    from .model.bench_parts import print_parts
    from .model.bench_all import provenance
    from .model.bench_parts import parts_markdown
    cfg = _with_numerics(load_config(args.config), args.numerics)
    points = [(args.config or "default", cfg, rpm, bar) for rpm in _floats(args.rpm or "3000", "--rpm")
              for bar in _floats(args.bar or "27.5", "--bar")]
    if args.family is not None:                     # and each family pump at its top speed, lowest pressure
        from .model.family import family_pumps, pressure_extremes, speed_extremes
        points += [(p.name, _with_numerics(p.config, args.numerics), speed_extremes(p.config)[1],
                    pressure_extremes(p.config)[0]) for p in family_pumps(args.family or None, args.pumps)]
    prov = provenance(_bench_command(args))
    with announce_compilation("compiling the part benchmarks (about a minute)"):
        rows = print_parts(points)
    if args.json:
        _write_json(args.json, {"parts": rows})
    if args.markdown or args.write_doc:
        _write_block(args, parts_markdown(rows, prov.finish().sentence()), "bench parts")
    return 0


def _call_s(args) -> float | None:
    """``bench realtime --call-ms``: model time per ``advance`` call [s] (None: the run in one call)."""
    if args.call_ms is None:
        return None
    if not (math.isfinite(args.call_ms) and 0.0 < args.call_ms <= 1e3 * args.seconds):
        raise InputError("--call-ms", args.call_ms, f"(0, {1e3 * args.seconds:g}] ms (at most --seconds)")
    return 1e-3 * args.call_ms


def _bench_family(args) -> int:
    """``bench accuracy|realtime --family [DIR]``: every pump of the family on its own grid (model/family.py)."""
    from .model.family import family_grid, family_pumps
    pumps = family_pumps(args.family or None, args.pumps)
    models = tuple((args.models or "mobility").split(","))
    out, ok = {}, True
    for pump in pumps:
        cfg = _with_numerics(pump.config, args.numerics)
        if args.what == "accuracy":
            from .model.accuracy import print_accuracy
            rpms, bars = family_grid(cfg)
            rows = print_accuracy(cfg, rpms=rpms, bars=bars, models=models, check_reference=args.check_reference,
                                  label=f"{pump.name} ({pump.path})", cache=_reference_cache(args),
                                  coupled=args.coupled_reference)
            ok &= all(r["within_budget"] for r in rows)
            print(f"{pump.name}: {sum(r['within_budget'] for r in rows)} of {len(rows)} points within budget",
                  flush=True)
        else:
            from .model.bench import family_realtime
            print(f"{pump.name} ({pump.path}):", flush=True)
            rows = family_realtime(cfg, models=models, seconds=args.seconds, repeats=args.repeats,
                                   call_s=_call_s(args))
        out[pump.name] = {"config": str(pump.path), "points": rows}
    if args.json:
        _write_json(args.json, {"family": out})
    return 0 if ok else 1


def _bench_command(args) -> str:
    """The ``bench all|accuracy|parts`` command line that reproduces ``args`` (written into its markdown block)."""
    import shlex
    words = ["gerotor-twin", "bench", args.what]
    if args.what == "all":
        words += ["--seconds", f"{args.seconds:g}", "--repeats", str(args.repeats)] + (["--compile"] * args.compile)
        options = ("--config", args.config), ("--family", args.family or None), ("--pumps", args.pumps)
    elif args.what == "parts":
        words += ["--family"] * (args.family is not None) + ([shlex.quote(args.family)] if args.family else [])
        options = ("--rpm", args.rpm), ("--bar", args.bar), ("--config", args.config), ("--pumps", args.pumps)
    else:
        options = (("--rpm", args.rpm or "3000"), ("--bar", args.bar or "27.5"), ("--models", args.models or "mobility"),
                   ("--config", args.config))
    for flag, value in (*options, ("--numerics", args.numerics), ("--write-doc", args.write_doc)):
        words += [flag, shlex.quote(str(value))] if value else []
    return " ".join(words)


def _write_block(args, block: str, name: str) -> None:
    """Print the markdown ``block`` and write it to ``--markdown F`` and into ``--write-doc F`` (block ``name``)."""
    from .model.bench_all import write_doc
    print(block, end="")
    if args.markdown:
        Path(args.markdown).parent.mkdir(parents=True, exist_ok=True)
        Path(args.markdown).write_text(block, encoding="utf-8")
        print(f"wrote {args.markdown}")
    if args.write_doc:
        write_doc(args.write_doc, block, name)
        print(f"updated {args.write_doc}")


def _bench_all(args) -> int:
    """``bench all``: the figures of docs/performance.md (model/bench_all.py) printed as one markdown block, in
    JSON with ``--json F``, in ``--markdown F`` and, with ``--write-doc F``, in place between the markers of ``F``."""
    import dataclasses
    from .config import load_config
    from .model.bench_all import markdown, run_all
    from .model.family import family_pumps

    cfg = _with_numerics(load_config(args.config), args.numerics)
    result = run_all(cfg, family_pumps(args.family or None, args.pumps), seconds=args.seconds, repeats=args.repeats,
                     with_compile=args.compile, command=_bench_command(args))
    if args.json:
        _write_json(args.json, dataclasses.asdict(result))
    _write_block(args, markdown(result, args.seconds, args.repeats), "bench all")
    return 0


# ------------------------------------------------------------------- parser
#: The commands each module of :data:`_COMMAND_MODULES` adds, so that a command line imports only its command's
#: module (the modules import the model, numba and scipy: ≈ 1.3 s); ``bench`` takes the modules that extend it.
#: ``test/test_cli_commands.py`` checks this table against what the modules register.
_COMMAND_OF = {"bearing-steady": "gerotor_twin.bearing.cli_commands", "bearing-benchmark": "gerotor_twin.bearing.cli_commands",
               "paper": "gerotor_twin.paper.cli_commands", "synth-bench": "gerotor_twin.bench_emulator.cli_commands",
               "report": "gerotor_twin.report.build", "run-bag": "gerotor_twin.offline.run_bag",
               "calibrate": "gerotor_twin.calibration.command", "health": "gerotor_twin.offline.health_log",
               "replay": "gerotor_twin.ros.replay", "node": "gerotor_twin.ros.cli_commands",
               "log": "gerotor_twin.io.cli_commands", "sweep": "gerotor_twin.offline.sweep",
               "batch": "gerotor_twin.offline.batch"}
#: The modules that add a choice to ``bench`` (``extend_bench``).
_BENCH_MODULES = ("gerotor_twin.ros.cli_commands", "gerotor_twin.offline.sweep_bench", "gerotor_twin.calibration.map_bench")

#: Every command beyond the model's own (geometry, simulate, demo, bench) comes from the
#: ``add_parser(subparsers)`` of its owning module, registered here in the order of the help.
_COMMAND_MODULES = (
    "gerotor_twin.bearing.cli_commands",          # bearing-steady, bearing-benchmark
    "gerotor_twin.paper.cli_commands",            # paper efficiency | figures | calibrate
    "gerotor_twin.bench_emulator.cli_commands",   # synth-bench
    "gerotor_twin.report.build",                  # report
    "gerotor_twin.offline.run_bag",               # run-bag
    "gerotor_twin.calibration.command",           # calibrate
    "gerotor_twin.offline.health_log",            # health
    "gerotor_twin.ros.replay",                    # replay (imports rclpy only when run)
    "gerotor_twin.ros.cli_commands",              # node; teaches `bench` the choice `node`
    "gerotor_twin.io.cli_commands",               # log recover
    "gerotor_twin.offline.sweep",                 # sweep
    "gerotor_twin.offline.sweep_bench",           # teaches `bench` the choice `sweep`
    "gerotor_twin.calibration.map_bench",         # teaches `bench` the choice `maps`
    "gerotor_twin.offline.batch",                 # batch
)


def extend_bench(subparsers, what: str, help_text: str | None = None):
    """The ``bench`` sub-parser with the choice ``what`` added (and ``help_text`` appended to its help), for a
    module of :data:`_COMMAND_MODULES` that brings its own benchmark; None when there is no ``bench``."""
    bench = subparsers.choices.get("bench")
    if bench is None:
        return None
    for action in bench._actions:                                    # noqa: SLF001 - extend choices
        if action.dest == "what" and action.choices is not None:
            action.choices = tuple(action.choices) + (what,)
            if help_text:
                action.help = (action.help or "") + help_text
    return bench


#: The commands :func:`build_parser` defines itself.
_BUILT_IN = ("geometry", "simulate", "demo", "bench")


def command_modules(argv=None) -> tuple:
    """The modules of :data:`_COMMAND_MODULES` a parser for the command line ``argv`` needs: its command's (and for
    ``bench`` those that extend it), none for the commands defined here; every one without a command (the top-level
    help) or with one not known here (argparse then lists the choices)."""
    first = next((a for a in argv or () if not a.startswith("-")), None)
    if argv is None or first is None:
        return _COMMAND_MODULES
    if first == "bench":
        return _BENCH_MODULES
    if first in _COMMAND_OF:
        return (_COMMAND_OF[first],)
    return () if first in _BUILT_IN else _COMMAND_MODULES


def build_parser(argv=None) -> argparse.ArgumentParser:
    """The command-line parser; with ``argv``, only with the commands that command line needs
    (:func:`command_modules`)."""
    p = argparse.ArgumentParser(prog="gerotor-twin", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)

    g = sub.add_parser("geometry", help="gear set, chambers, displacement; picture")
    g.add_argument("--config", help="pump YAML (default config/pump.yaml)")
    g.add_argument("--json", help="write the geometry figures to this JSON file")
    g.add_argument("--plot", help="write a picture of the gears and chambers (PNG)")
    g.set_defaults(func=cmd_geometry)

    s = sub.add_parser("simulate", help="run one operating point to periodic steady state")
    s.add_argument("--rpm", type=float, required=True, help="shaft speed [rpm]")
    s.add_argument("--bar", type=float, required=True, help="delivery pressure [bar gauge]")
    s.add_argument("--revolutions", type=int, default=30,
                   help="at most this many revolutions to periodic state, the recorded one included")
    s.add_argument("--model", default="mobility", choices=MODEL_NAMES,
                   help="outer-gear model (default: mobility, the twin's)")
    s.add_argument("--config", help="pump YAML (default config/pump.yaml)")
    s.add_argument("--json", help="write the results to this JSON file")
    s.add_argument("--plot", help="write chamber-1 pressure and delivery flow vs angle (PNG)")
    s.add_argument("--oil-temp", type=float, help="oil temperature [°C] (default: the config's reference "
                   "temperature; no effect without an oil section)")
    s.add_argument("--fluid-model", choices=("mixture", "paper"), help="override the config's fluid_model")
    s.set_defaults(func=cmd_simulate)

    d = sub.add_parser("demo", help="the main job of `make demo`")
    d.add_argument("--out", default="out/demo", help="output directory")
    d.add_argument("--model", default="mobility", choices=MODEL_NAMES)
    d.add_argument("--config", help="pump YAML")
    d.set_defaults(func=cmd_demo)

    b = sub.add_parser("bench", help="benchmarks (printed figures)")
    b.add_argument("what", choices=("realtime", "accuracy", "models", "parts", "all"),
                   help="realtime: model real-time factor (default 1000/2000/3000 rpm, 27.5 bar); "
                        "all: the figures of docs/performance.md (real time of the default pump and the family, "
                        "the four gear models' cost; --compile: the first compile), as one markdown block; "
                        "accuracy: default numerics against a tight reference (exit 1 outside the error budget); "
                        "models: wall time per revolution of the four outer-gear models at 1000/3000 rpm; "
                        "parts: where an output step's time goes (each part of the stepper timed alone)")
    b.add_argument("--rpm", default=None, help="shaft speed(s) [rpm], comma-separated (realtime: default "
                                               "1000,2000,3000; accuracy: default 3000; maps: the maps' speeds, "
                                               "default 1000,1500,2000,2500,3000)")
    b.add_argument("--bar", default=None, help="delivery pressure(s) [bar gauge], comma-separated (default 27.5; "
                                               "realtime uses the first; node: the first, default the pump's "
                                               "range.max_delivery_bar; maps: the maps' pressures, default "
                                               "5,12.5,20)")
    b.add_argument("--models", help="comma-separated outer-gear models "
                                     "(default fixed,mobility for realtime; all four for models)")
    b.add_argument("--seconds", type=float, default=1.0, help="simulated seconds per run")
    b.add_argument("--repeats", type=int, default=3)
    b.add_argument("--call-ms", type=float, default=None,
                   help="realtime: advance in calls of this much model time [ms], as the node does once per input "
                        "sample (e.g. 1 at 1 kHz), so the figure includes each call's own cost (default: one call)")
    b.add_argument("--config", help="pump YAML")
    b.add_argument("--family", nargs="?", const="", default=None, metavar="DIR",
                   help="accuracy / realtime: every pump YAML of DIR (default config/pumps/) on its own range "
                        "(accuracy: speeds low/mid/top x pressures low/top; realtime: top speed at both pressures)")
    b.add_argument("--pumps", help="with --family: comma-separated pump names (file stems) to run")
    b.add_argument("--check-reference", action="store_true",
                   help="accuracy: also show how far the reference moves against one with half its tolerance and "
                        "twice its output-step refinement (largest budget figure, as a fraction of its budget)")
    b.add_argument("--coupled-reference", action="store_true",
                   help="accuracy: also compare the mobility model with the independent reference that integrates "
                        "the pressures and the gear position together (Radau; minutes per point, cached)")
    b.add_argument("--numerics", metavar="KEY=VALUE[,...]",
                   help="accuracy / realtime: override numerics fields of every pump (e.g. tolerance=0.02,"
                        "closing_tolerance=1), to compare step-control settings on the same references")
    b.add_argument("--reference-cache", metavar="DIR", default=None,
                   help="accuracy: directory of cached reference revolutions (default $GEROTOR_TWIN_CACHE/references "
                        "or ~/.cache/gerotor_twin/references; keyed by the pump, the point, the model and the code)")
    b.add_argument("--no-reference-cache", action="store_true", help="accuracy: compute every reference afresh")
    b.add_argument("--json", help="write the figures to this JSON file")
    b.add_argument("--markdown", metavar="F", help="all / accuracy / parts: write the figures as a markdown block to F")
    b.add_argument("--write-doc", metavar="F", help="all / accuracy / parts: replace the block between '<!-- bench WHAT: begin "
                                                    "-->' and '<!-- bench WHAT: end -->' of the markdown file F")
    b.add_argument("--compile", action="store_true",
                   help="all: also time the first compile on an empty numba cache (minutes)")
    b.set_defaults(func=cmd_bench)

    for name in command_modules(argv):
        importlib.import_module(name).add_parser(sub)
    return p


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = build_parser(argv).parse_args(argv)
    try:
        with one_line_warnings():
            return int(args.func(args) or 0)
    except (InputError, McapReadError) as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr)
        return 2
    except BrokenPipeError:       # the reader of our output left (`| head`): stop quietly, as cat does
        with contextlib.suppress(OSError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141                # 128 + SIGPIPE
    except OSError as exc:        # a path the user gave: directory, permission, missing (one line, exit 2)
        print(path_error_line(exc), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
