"""Calibration on pumps that differ from the twin in form: held-out errors and interval coverage (a measurement).

``python -m gerotor_twin.offline.calibration_coverage [--pumps a,b] [--seeds 1,2,3] [--held-out 6] [--jobs 2]
[--config F] [--bags DIR] [--json F]``

For each shipped bench pump (``config/bench_pumps/*.yaml``) and seed:

1. **training plateaus**: a steady map of the bench pump (:mod:`gerotor_twin.calibration.bench_steady`: its
   emulated pump in periodic steady state, read through its sensors' biases and noise) at :data:`TRAIN_RPM` ×
   :data:`TRAIN_BAR`, the oil warming from 35 to 60 °C over the plateaus (:func:`train_points`) — the
   operating points of a map recording;
2. **calibration** as ``gerotor-twin calibrate --bench`` does it (its candidate sets,
   :data:`~gerotor_twin.calibration.command.BENCH_CANDIDATES`, or one set with ``--params``; chosen by
   leave-one-speed-out cross-validation, the nominal values kept when no set predicts the held-out speeds
   better), with its 95 % prediction interval (:mod:`gerotor_twin.calibration.prediction`);
3. **held-out plateaus**, never seen by the calibration: ``--held-out`` operating points drawn with the seed
   uniformly over 800–2950 rpm, 3–27 bar, 40–60 °C oil, with their own noise draws; on each the error of the
   nominal twin and of the calibrated twin, and whether the calibrated twin's 95 % interval holds its error.

``--config F`` takes another nominal pump (a pump of the family, ``config/pumps/``): the bench pumps' deviations
apply to it and the operating points are scaled to its range (``range.max_speed_rpm`` / 3000 rpm,
``range.max_delivery_bar`` / 27.5 bar).

``--bags DIR`` does the same on recordings (:func:`evaluate_bags`: the ``map`` profile's recording fitted by
``calibrate --bench`` with the bench pump's thermometer and flow-meter lags undone, the ``transient`` profile's
plateaus held out the same way; minutes per pump).

Prints one row per pump and seed and the pooled coverage (docs/calibration_health.md, "Calibration on
bench pumps that differ in form").  Seeds are fixed; nothing is asserted here (the tests,
``test/test_calibration_form.py``, run a smaller version).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..bench_emulator.bench_pump import load_bench_pump
from ..calibration import fit as C
from ..calibration import prediction as P
from ..calibration.bench_steady import SteadyBench, steady_plateaus
from ..calibration.command import BENCH_CANDIDATES, calibrate_records
from ..calibration.fit_model import parse_params
from ..config import load_config
from ..errors import InputError, check_range
from ..resources import resource_path

__all__ = ["TRAIN_RPM", "TRAIN_BAR", "shipped_pumps", "train_points", "held_out_points", "evaluate", "evaluate_bags",
           "judge", "run", "main"]

#: The operating points below are the default pump's (its range 3000 rpm, 27.5 bar); another pump's
#: (``--config``) are scaled by its ``range.max_speed_rpm`` / 3000 and ``range.max_delivery_bar`` / 27.5.
RANGE_RPM, RANGE_BAR = 3000.0, 27.5
TRAIN_RPM = (1000.0, 1900.0, 2800.0)     #: speeds of the training map [rpm]
TRAIN_BAR = (5.0, 14.0, 24.0)            #: delivery pressures of the training map, gauge [bar]
TRAIN_OIL_C = (35.0, 60.0)               #: oil temperature at the first and the last plateau of the map [°C]
HELD_RPM = (800.0, 2950.0)               #: range of the held-out speeds [rpm]
HELD_BAR = (3.0, 27.0)                   #: range of the held-out delivery pressures, gauge [bar]
HELD_OIL_C = (40.0, 60.0)                #: range of the held-out oil temperatures [°C]


def shipped_pumps() -> list[Path]:
    """The shipped bench pump files, sorted by name."""
    return sorted(resource_path("config", "bench_pumps").glob("*.yaml"))


def _scales(cfg) -> tuple[float, float]:
    """Speed and pressure scale of the pump ``cfg`` against the default pump's range [-] (module constants)."""
    return cfg.range.max_speed_rpm / RANGE_RPM, cfg.range.max_delivery_bar / RANGE_BAR


def train_points(cfg) -> list[tuple[float, float, float]]:
    """The training map of the pump ``cfg`` (:data:`TRAIN_RPM` × :data:`TRAIN_BAR` scaled to its range) in the order
    a recording runs it (pressures up at one speed, down at the next) with the oil warming linearly from the first
    plateau to the last: (speed [rad/s], delivery [Pa abs], oil [°C])."""
    sn, sp = _scales(cfg)
    p_atm = cfg.fluid.atmospheric_pa
    order = [(rpm, bar) for k, rpm in enumerate(TRAIN_RPM) for bar in (TRAIN_BAR if k % 2 == 0 else TRAIN_BAR[::-1])]
    oil = np.linspace(*TRAIN_OIL_C, len(order))
    return [(sn * rpm * math.pi / 30, p_atm + sp * bar * 1e5, float(t)) for (rpm, bar), t in zip(order, oil)]


def held_out_points(seed: int, n: int, cfg) -> list[tuple[float, float, float]]:
    """``n`` operating points of the pump ``cfg`` drawn with ``seed`` (:data:`HELD_RPM`, :data:`HELD_BAR` scaled to
    its range): (speed [rad/s], delivery [Pa abs], oil [°C])."""
    sn, sp = _scales(cfg)
    p_atm = cfg.fluid.atmospheric_pa
    rng = np.random.default_rng([seed, 28])
    return [(sn * rng.uniform(*HELD_RPM) * math.pi / 30, p_atm + sp * rng.uniform(*HELD_BAR) * 1e5,
             rng.uniform(*HELD_OIL_C)) for _ in range(n)]


@dataclass(frozen=True)
class Case:
    """One evaluation: a bench pump, a seed and the calibration's options."""
    pump: Path
    seed: int
    held_out: int = 6
    params: tuple = ("tip", "lateral")   #: the largest candidate set
    candidates: tuple | None = BENCH_CANDIDATES   #: None: ``params`` as one set (``calibrate --bench --params``)
    config: Path | None = None           #: the nominal pump the bench pump derives from (None: config/pump.yaml)


def evaluate(case: Case, jobs: int | None = None) -> dict:
    """Calibrate on the training map of ``case`` and judge it on its held-out plateaus (module doc)."""
    cfg = load_config(case.config)
    bench = SteadyBench.of(load_bench_pump(case.pump), config_path=case.config)
    name = bench.bench_pump.name
    train = steady_plateaus(bench, train_points(cfg), seed=case.seed, source=f"{name}-map")
    held = steady_plateaus(bench, held_out_points(case.seed, case.held_out, cfg), seed=case.seed + 10_000,
                           source=f"{name}-held-out")
    res = calibrate_records(train, [f"{name}-map"], config_path=case.config, params=case.params, cv="speed",
                            jobs=jobs, candidates=case.candidates if case.candidates is not None else (case.params,))
    return {"seed": case.seed, "config": str(case.config or "config/pump.yaml"),
            **judge(res, held, name, jobs, case.config)}


def judge(res: dict, held: list, name: str, jobs: int | None = None, config_path=None) -> dict:
    """The calibration result ``res`` (:func:`~gerotor_twin.calibration.command.calibrate_records`, cross-validated)
    on the held-out plateaus ``held`` of the pump ``config_path`` (None: the default): nominal and calibrated
    errors, the interval's coverage."""
    cfg = load_config(config_path)
    sel = res["selection"]
    chosen = next(c for c in sel["candidates"] if c["params"] == sel["chosen"])
    form = P.ModelFormError(chosen["model_form_sd_eta"], len(chosen["cv_errors"]))
    names = tuple(res["params"])
    x = np.array([p["log_factor"] for p in res["fit"]["parameters"]])
    cov = np.array(res["fit"]["cov_x"]) if names else np.zeros((0, 0))
    d = cfg.gears.displacement_closed_form()
    with C.Evaluator(cfg.to_dict(), res["model"], jobs) as ev:
        fitted = P.predict(ev, names, x, cov, held, d, form)
        nominal = P.predict(ev, (), np.zeros(0), np.zeros((0, 0)), held, d, form)
    e1 = np.array([r["eta_error"] for r in fitted])
    e0 = np.array([r["eta_error"] for r in nominal])
    return {"pump": name, "chosen": sel["chosen"], "verdict": res["verdict"]["message"],
            "calibrated": res["verdict"]["calibrated"],
            "parameters": {p["name"]: p["value"] for p in res["fit"]["parameters"]},
            "cv_nominal_rmse": res["verdict"]["nominal_heldout_rmse"], "cv_chosen_rmse": chosen["cv_rmse"],
            "model_form_sd_eta": form.sd,
            "nominal_mean_abs": float(np.mean(np.abs(e0))), "nominal_max_abs": float(np.max(np.abs(e0))),
            "fitted_mean_abs": float(np.mean(np.abs(e1))), "fitted_max_abs": float(np.max(np.abs(e1))),
            "covered": int(sum(r["covered"] for r in fitted)), "held_out": len(fitted),
            "half_width_rms": float(np.sqrt(np.mean([r["half_width_eta"] ** 2 for r in fitted]))),
            "plateaus": fitted, "plateaus_nominal": nominal, "simulations": res["simulations"]}


def evaluate_bags(pump: Path, seed: int, out: Path, jobs: int | None = None, config: Path | None = None) -> dict:
    """The same on recordings (minutes per pump): ``synth-bench --bench-pump`` makes the ``map`` profile's
    recording (seed ``seed``) and the ``transient`` profile's (seed ``seed`` + 1); ``calibrate --bench`` fits the
    map recording (its default candidates; the bench pump's thermometer and flow-meter lags undone,
    ``--oil-sensor-tau``, ``--flow-sensor-tau``), and the transient recording's plateaus are held out.  ``config``:
    the nominal pump the bench pump derives from (the profiles scaled to its range)."""
    from ..bench_emulator import BenchSpec, get_profile, synthesize
    from ..calibration.command import calibrate_bags
    from ..calibration.plateaus import DetectorSettings, bench_plateaus, split_by_envelope
    from dataclasses import replace
    bp = load_bench_pump(pump)
    spec = bp.bench_spec(BenchSpec(seed=seed))
    cfg = load_config(config)
    prefix = "" if config is None else f"{Path(config).stem}_"
    out.mkdir(parents=True, exist_ok=True)
    bags = {}
    for k, profile in enumerate(("map", "transient")):
        bags[profile] = out / f"{prefix}{bp.name}_{profile}_{seed + k}.mcap"
        if not bags[profile].exists():
            synthesize(get_profile(profile, cfg.range), bags[profile], replace(spec, seed=seed + k),
                       config=None if config is None else cfg, bench_pump=bp, progress=None)
    det = DetectorSettings(oil_sensor_tau_s=spec.temperature_tau_s, flow_sensor_tau_s=spec.flow_tau_s)
    res = calibrate_bags([bags["map"]], detector=det, config_path=config, params=("tip", "lateral"), cv="auto",
                         candidates=BENCH_CANDIDATES, jobs=jobs)
    held, outside = split_by_envelope(bench_plateaus(bags["transient"], det), cfg)
    return {"seed": seed, "held_out_outside_envelope": [why for _, why in outside], "config": str(config or "config/pump.yaml"), "bags": {k: str(v) for k, v in bags.items()},
            **judge(res, held, bp.name, jobs, config)}


def _pt(v: float) -> str:
    return f"{100 * v:.2f}"


def run(cases: list[Case], jobs: int | None = None, out=None, bags_dir: Path | None = None) -> dict:
    """Evaluate every case (on recordings in ``bags_dir`` when given: :func:`evaluate_bags`), printing a markdown
    row for each; the rows and the pooled coverage."""
    out = out or sys.stdout
    print("| bench pump | seed | chosen set | held-out mean \\|η err\\| nominal → calibrated (max) [pt] "
          "| 95 % interval, RMS half-width [pt] | held-out plateaus inside |", file=out)
    print("|---|---|---|---|---|---|", file=out)
    rows = []
    for case in cases:
        t0 = time.perf_counter()
        r = evaluate(case, jobs) if bags_dir is None else evaluate_bags(case.pump, case.seed, bags_dir, jobs,
                                                                        case.config)
        r["wall_s"] = time.perf_counter() - t0
        rows.append(r)
        on = "" if case.config is None else f" on {Path(case.config).stem}"
        print(f"| `{r['pump']}`{on} | {r['seed']} | {'+'.join(r['chosen']) or 'none (nominal kept)'} | "
              f"{_pt(r['nominal_mean_abs'])} ({_pt(r['nominal_max_abs'])}) → {_pt(r['fitted_mean_abs'])} "
              f"({_pt(r['fitted_max_abs'])}) | ± {_pt(r['half_width_rms'])} | {r['covered']}/{r['held_out']} |",
              file=out, flush=True)
    covered, total = sum(r["covered"] for r in rows), sum(r["held_out"] for r in rows)
    print(f"pooled: the 95 % interval holds {covered} of {total} held-out plateaus "
          f"({100 * covered / max(total, 1):.0f} %)", file=out)
    return {"rows": rows, "covered": covered, "held_out": total}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m gerotor_twin.offline.calibration_coverage", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--pumps", default=None, help="bench pump names, comma-separated (default: every shipped one)")
    p.add_argument("--seeds", default="1,2,3", help="seeds, comma-separated (default 1,2,3)")
    p.add_argument("--held-out", type=int, default=6, help="held-out plateaus per pump and seed (default 6)")
    p.add_argument("--params", default=None,
                   help="one parameter set to fit or keep nominal, as `calibrate --bench --params` (default: "
                        "calibrate --bench's candidate sets, " + "; ".join(",".join(c) for c in BENCH_CANDIDATES) + ")")
    p.add_argument("--candidates", default=None,
                   help="parameter sets to choose among, semicolon-separated, as `calibrate --candidates` "
                        "(default: calibrate --bench's, \"" + ";".join(",".join(c) for c in BENCH_CANDIDATES) + "\")")
    p.add_argument("--config", default=None, metavar="F",
                   help="the nominal pump the bench pumps derive from (default config/pump.yaml); the operating "
                        "points are scaled to its range")
    p.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    p.add_argument("--json", default=None, help="write every row (per plateau too) to this file")
    p.add_argument("--bags", default=None, metavar="DIR",
                   help="on recordings instead (made in DIR if absent: map profile fitted, transient held out; "
                        "minutes per pump and seed)")
    args = p.parse_args(argv)
    try:
        files = {f.stem: f for f in shipped_pumps()}
        names = list(files) if args.pumps is None else [s.strip() for s in args.pumps.split(",") if s.strip()]
        for n in names:
            if n not in files:
                raise InputError("--pumps", n, ", ".join(files))
        seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
        if not seeds:
            raise InputError("--seeds", args.seeds, "comma-separated integers")
        check_range("--held-out", args.held_out, 1, 1000)
        params = None if args.params is None else parse_params(args.params)
        if args.params is not None and args.candidates is not None:
            raise InputError("--candidates", args.candidates, "not with --params (one set)")
        sets = None if args.candidates is None else tuple(parse_params(c, "--candidates") for c in args.candidates.split(";")
                                                          if c.strip())
    except InputError as e:                  # before ValueError, which it derives from
        p.error(str(e))
    except ValueError:
        p.error(f"--seeds = {args.seeds!r} is invalid; allowed: comma-separated integers")
    t0 = time.perf_counter()
    config = None
    if args.config is not None:
        try:
            load_config(args.config)
            config = Path(args.config)
        except InputError as e:
            p.error(str(e))
    if sets is not None:
        params = tuple(dict.fromkeys(n for c in sets for n in c))
    cases = [Case(files[n], s, args.held_out, config=config) if params is None else
             Case(files[n], s, args.held_out, params, sets, config) for n in names for s in seeds]
    result = run(cases, args.jobs, bags_dir=None if args.bags is None else Path(args.bags))
    print(f"{len(cases)} cases in {time.perf_counter() - t0:.0f} s")
    if args.json:
        Path(args.json).write_text(json.dumps({"argv": sys.argv[1:] if argv is None else list(argv), **result},
                                              indent=1, default=float))
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
