"""``gerotor-twin synth-bench``: a synthetic bench recording (emulated pump + sensors) to MCAP.

:func:`add_parser` adds it to the project's sub-parsers (``cli.py`` lists every
command's module); the handler imports the emulator lazily.  Bad input raises
:class:`~gerotor_twin.errors.InputError` (printed as one line, exit 2).
"""
from __future__ import annotations

import json
import shlex
import sys
from pathlib import Path

from gerotor_twin.errors import InputError
from gerotor_twin.units import m3s_to_lpm

__all__ = ["add_parser"]


def _wear_args(spec) -> list[str]:
    """The wear options of the command line stored in the file (none without wear)."""
    if spec.wear_clearance_factor_end == 0:
        return []
    return ["--wear-to", f"{spec.wear_clearance_factor_end:g}", "--wear-start", f"{spec.wear_start_s:g}"]


def _fault_args(scenario) -> list[str]:
    """The fault options of the command line stored in the file, every value spelled out (none without faults)."""
    if not scenario:
        return []
    f = scenario.faults
    return ["--fault", ",".join(x.kind for x in f), "--fault-to", ",".join(f"{x.to:g}" for x in f),
            "--fault-start", ",".join(f"{x.start_s:g}" for x in f),
            "--fault-ramp", ",".join(f"{x.ramp_s:g}" for x in f)]


def _profile(args, config):
    """The built-in profile scaled to the pump's range, or the ``--profile-file`` (not both)."""
    from gerotor_twin.bench_emulator import get_profile
    from gerotor_twin.bench_emulator.profile_file import load_profile_file

    if args.profile_file is not None:
        if args.profile is not None:
            raise InputError("--profile-file", args.profile_file, "either --profile or --profile-file",
                             f"--profile {args.profile} given too")
        return load_profile_file(args.profile_file, config.range)
    return get_profile(args.profile or "transient", config.range)


def _spec(args, bench_pump):
    """The emulator settings of the command line; a bench pump's sensors and clearances on top."""
    from gerotor_twin.bench_emulator import BenchSpec

    if bench_pump is not None and args.clearance_factor is not None:
        raise InputError("--clearance-factor", args.clearance_factor, "not with --bench-pump",
                         "the bench pump's pump.clearance_factors set each path")
    factor = BenchSpec.clearance_factor if args.clearance_factor is None else args.clearance_factor
    spec = BenchSpec(seed=args.seed, bearing=args.bearing, clearance_factor=factor,
                     speed_rate_hz=args.speed_rate, pressure_rate_hz=args.pressure_rate,
                     flow_rate_hz=args.flow_rate, temperature_rate_hz=args.temperature_rate,
                     wear_clearance_factor_end=args.wear_to, wear_start_s=args.wear_start)
    return spec if bench_pump is None else bench_pump.bench_spec(spec)


def _command(args, spec, profile, out: Path, scenario) -> str:
    """The command line stored in the file: every setting spelled out."""
    which = ["--profile-file", args.profile_file] if args.profile_file is not None else ["--profile", profile.name]
    pump = (["--bench-pump", args.bench_pump] if args.bench_pump is not None
            else ["--clearance-factor", f"{spec.clearance_factor:g}"])
    command = shlex.join(["gerotor-twin", "synth-bench", *which, "-o", str(out),
                          "--seed", str(spec.seed), "--bearing", spec.bearing, *pump,
                          "--speed-rate", f"{spec.speed_rate_hz:g}", "--pressure-rate", f"{spec.pressure_rate_hz:g}",
                          "--flow-rate", f"{spec.flow_rate_hz:g}", "--temperature-rate",
                          f"{spec.temperature_rate_hz:g}"] + _wear_args(spec) + _fault_args(scenario))
    if args.config:
        command += " --config " + shlex.quote(args.config)
    return command


def cmd_synth_bench(args) -> int:
    from gerotor_twin.bench_emulator import synthesize
    from gerotor_twin.bench_emulator.bench_pump import load_bench_pump
    from gerotor_twin.bench_emulator.emulator import default_output_name
    from gerotor_twin.bench_emulator.faults import FAULT_KINDS, FaultScenario, parse_faults
    from gerotor_twin.config import load_config

    faults = parse_faults(args.fault, args.fault_to, args.fault_start, args.fault_ramp)
    config = load_config(args.config)
    profile = _profile(args, config)
    scenario = FaultScenario(faults, profile.duration_s)     # a start after the end refused before the output
    bench_pump = None if args.bench_pump is None else load_bench_pump(args.bench_pump)
    spec = _spec(args, bench_pump)
    out = Path(args.output) if args.output else default_output_name(profile)
    if out.exists() and not args.overwrite:
        raise InputError("--output", str(out), "a file that does not exist yet", "pass --overwrite to replace it")
    out.parent.mkdir(parents=True, exist_ok=True)
    command = _command(args, spec, profile, out, scenario)
    res = synthesize(profile, out, spec, config=config, overwrite=args.overwrite, command=command,
                     progress=None if args.quiet else sys.stderr, bench_pump=bench_pump, faults=faults)
    n = sum(res["message_counts"].values())
    print(f"wrote {out} ({out.stat().st_size / 1e6:.2f} MB, {n} messages, {res['duration_s']:.1f} s, "
          f"seed {spec.seed})")
    for row in res["truth"]:
        print(f"  truth {row['rpm']:6.0f} rpm {row['bar']:6.2f} bar: mean flow "
              f"{m3s_to_lpm(row['true_mean_flow_m3s']):7.3f} L/min, eta_v {row['true_volumetric_efficiency']:.4f}, "
              f"oil {row['oil_temperature_c']:.1f} °C"
              + (f", clearance factor {row['clearance_factor']:.4f}" if "clearance_factor" in row else ""))
    for f in scenario.faults:
        print(f"  fault {f.kind}: {f.to:g} ({FAULT_KINDS[f.kind].unit}) from {f.start_s:g} s, reached at "
              f"{f.start_s + f.ramp_s:g} s")
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=2))
        print(f"wrote {args.json}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("synth-bench", help="synthetic bench recording (emulated pump + sensors) to MCAP",
                       description="Run the bench emulator (a pump that differs from the twin on purpose, "
                                   "seen through bench sensors) along a profile and record the bench "
                                   "topics to a rosbag2-convention MCAP file. Same seed -> same bytes.")
    p.add_argument("--profile", help="built-in profile, scaled to the pump's range: map | transient | wear | diagnosis "
                                     "| test (default transient)")
    p.add_argument("--profile-file", metavar="F",
                   help="a profile YAML file instead (segments of duration_s, rpm, bar, optional ramp and "
                        "oil_temperature_c; docs/offline.md, config/profiles/example.yaml)")
    p.add_argument("-o", "--output", help="MCAP file (default bags/bench_<profile name>.mcap)")
    p.add_argument("--seed", type=int, default=20240601, help="noise seed (default 20240601)")
    p.add_argument("--bearing", default="short", help="outer-gear model of the emulated pump (default short)")
    p.add_argument("--clearance-factor", type=float, default=None,
                   help="tooth-tip and lateral clearances x nominal (default 1.10; not with --bench-pump)")
    p.add_argument("--bench-pump", metavar="F",
                   help="a bench pump YAML: how the emulated pump and its sensors differ from the twin in form "
                        "(per-path clearances, orifice law, air, tip-gap law, port timing, sensor bias/lag/noise; "
                        "docs/calibration_health.md, config/bench_pumps/)")
    p.add_argument("--speed-rate", type=float, default=100.0, help="shaft speed rate [Hz] (default 100)")
    p.add_argument("--pressure-rate", type=float, default=100.0, help="pressure rate [Hz] (default 100)")
    p.add_argument("--flow-rate", type=float, default=20.0, help="flow meter rate [Hz] (default 20)")
    p.add_argument("--temperature-rate", type=float, default=5.0, help="thermometer rate [Hz] (default 5)")
    p.add_argument("--wear-to", type=float, default=0.0,
                   help="wear scenario: clearance factor reached at the end of the run (0 = no wear; default 0)")
    p.add_argument("--wear-start", type=float, default=0.0, help="wear starts at this time of the run [s] (default 0)")
    p.add_argument("--fault", metavar="KIND[,KIND]",
                   help="fault scenarios: tip_wear, lateral_wear, housing_wear, air_ingress, suction_restriction, "
                        "pressure_offset, speed_dropout, flowmeter_drift (units, ranges: docs/calibration_health.md)")
    p.add_argument("--fault-to", metavar="X[,X]",
                   help="severity of each --fault kind, comma-separated (default per kind)")
    p.add_argument("--fault-start", metavar="S[,S]", help="start of each fault [s] (one for all or one per kind; "
                                                           "default 0)")
    p.add_argument("--fault-ramp", metavar="S[,S]",
                   help="time to reach the severity [s] (default: until the end of the run for wear, air, "
                        "restriction and drift; 0, a step, for pressure_offset and speed_dropout)")
    p.add_argument("--config", help="nominal pump YAML the emulated pump derives from (default config/pump.yaml)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing file")
    p.add_argument("--json", metavar="F", help="write counts and the ground truth per plateau to F")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(func=cmd_synth_bench)
