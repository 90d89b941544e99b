r"""``gerotor-twin bench maps``: calibration from steady maps built with physics the twin does not contain.

Each map is the twin's steady state at chosen parameters (:mod:`.map_synth`) with a loss added
that the twin's chamber model has no term for, or has only at its edge
(:mod:`gerotor_twin.model.volumetric`); the calibration (:func:`.calibration_run.calibrate_records`,
candidate sets :data:`.calibration_run.MAP_CANDIDATES`, leave one speed out) then reports its held-out
error beside the nominal twin's and the empirical law's.  The grid is :data:`SPEEDS_RPM` × :data:`BARS` at 50 °C
unless given (``--rpm``, ``--bar``): how many speeds a map has decides which speed laws its folds can tell apart
(docs/calibration_health.md).  Added losses (Δp = p_d − p_s [Pa],
n [rev/s], ``Q_th = D n``):

* ``filling``: incomplete filling growing with speed, :math:`ΔQ = 0.05\,(n/n_\max)^2\,Q_{th}`
  (the suction's pressure drop rising as n²; the twin's ``volumetric.filling_loss_at_1000rpm`` has this law);
* ``filling_onset``: a filling loss that sets in at a speed, the chambers full below n_c = n_max/3,
  :math:`ΔQ = 0.05\,(\max(0, n - n_c)/(n_\max - n_c))^2\,Q_{th}` (a suction margin used up at n_c; the twin's
  filling term with its margin ``volumetric.filling_margin_pa`` has an onset too, but grows as n² − n_c² beyond it);
* ``deforming_gap``: a laminar path of its own whose gap opens with pressure (plates and housing deflect),
  :math:`ΔQ = G\,Δp\,(1 + Δp/p^*)^3 μ_{40}/μ(T)`, G giving 1 % of Q_th at 1000 rpm and 5 bar at 40 °C,
  p* = 40 bar (the twin's ``clearances.lateral_opening_m_per_pa`` has this form, but on its lateral gaps,
  whose unloaded leakage is several times G Δp);
* the twin's own edge terms at known values (``deficit``: k_D = 0.96 and gaps × 1.1; ``bypass``: 0.5 mm²
  at two oil temperatures), as the recoverable reference.

Printed, never asserted (a benchmark: the figures are in docs/calibration_health.md).
"""
from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..config import load_config
from ..errors import InputError, check_range
from .command import MAP_CANDIDATES, MAP_PARAMS, calibrate_records
from .map_synth import synthetic_map

__all__ = ["MAPS", "MapCase", "SPEEDS_RPM", "BARS", "run", "add_parser"]

#: the maps' speeds [rpm]: five, a sixth of the default pump's top speed apart, as a maker's map often has them
#: (with three, a speed left out at either end is extrapolated over half the range)
SPEEDS_RPM = (1000.0, 1500.0, 2000.0, 2500.0, 3000.0)
#: the maps' delivery pressures [bar gauge]
BARS = (5.0, 12.5, 20.0)


@dataclass(frozen=True)
class MapCase:
    """One constructed map: the twin's parameters, the loss added and the operating points."""
    name: str
    description: str
    volumetric: dict             #: ``volumetric`` values of the twin's truth (k_D, bypass area)
    loss: Callable | None        #: (cfg, omega [rad/s], dp [Pa], T [°C]) -> flow lost [m³/s], or None
    gap_factor: float = 1.0      #: tip and lateral clearances × this [-]
    temperatures: tuple = (50.0,)  #: oil temperatures of the map [°C]


def _filling(cfg, omega, dp, t_c):
    n, n_max = omega / (2 * math.pi), cfg.range.max_speed_rpm / 60
    return 0.05 * (n / n_max) ** 2 * cfg.gears.displacement_closed_form() * n


def _filling_onset(cfg, omega, dp, t_c):
    n, n_max = omega / (2 * math.pi), cfg.range.max_speed_rpm / 60
    n_c = n_max / 3
    return 0.05 * (max(0.0, n - n_c) / (n_max - n_c)) ** 2 * cfg.gears.displacement_closed_form() * n


def _deforming_gap(cfg, omega, dp, t_c):
    mu = cfg.fluid_at(t_c + 273.15).viscosity_pa_s / cfg.fluid_at(313.15).viscosity_pa_s
    g = 0.01 * cfg.gears.displacement_closed_form() * (1000 / 60) / (5e5 * (1 + 5 / 40) ** 3)
    return g * dp * (1 + dp / 40e5) ** 3 / mu


MAPS = (
    MapCase("deficit", "k_D 0.96, gaps × 1.1 (in the twin)", {"displacement_factor": 0.96}, None, 1.1),
    MapCase("bypass", "bypass 0.5 mm², k_D 0.97, 30 and 60 °C (in the twin)",
            {"displacement_factor": 0.97, "bypass_area_m2": 0.5e-6}, None, 1.0, (30.0, 60.0)),
    MapCase("filling", "filling loss 5 % × (n/n_max)², gaps × 1.1 (the twin's filling term has the law)", {},
            _filling, 1.1),
    MapCase("filling_onset", "filling loss from n_max/3, 5 % × ((n − n_c)/(n_max − n_c))², gaps × 1.1 (the twin's "
                             "filling margin has an onset, with another law beyond it)", {}, _filling_onset, 1.1),
    MapCase("deforming_gap", "a path of its own whose gap opens with pressure, (1 + Δp/40 bar)³ (the twin's lateral "
                             "opening has the form on its own gaps)", {}, _deforming_gap),
)


def _raw(case: MapCase) -> dict:
    raw = load_config().to_dict()
    raw["clearances"]["tooth_tip_m"] *= case.gap_factor
    raw["clearances"]["lateral_m"] *= case.gap_factor
    raw["volumetric"].update(case.volumetric)
    return raw


def build(case: MapCase, speeds_rpm=SPEEDS_RPM, bars=BARS, noise: float = 0.0, seed: int = 1) -> list:
    """The map of ``case``: the twin's steady state at its truth, less its added loss; with ``noise`` > 0 each
    flow times (1 + ``noise``·z), z standard normal (numpy's generator seeded with ``seed`` and the map's name),
    as a test house's flow meter reads it."""
    from dataclasses import replace
    cfg = load_config()
    pts = [(rpm * math.pi / 30, cfg.fluid.atmospheric_pa + bar * 1e5, t)
           for rpm in speeds_rpm for bar in bars for t in case.temperatures]
    recs = synthetic_map(_raw(case), pts, source=f"{case.name}.csv")
    p_s = cfg.boundary.suction_pressure_pa
    if case.loss is not None:
        recs = [replace(r, flow_m3s=r.flow_m3s - case.loss(cfg, r.omega, r.p_delivery_pa - p_s, r.oil_temperature_c))
                for r in recs]
    if noise > 0:
        rng = np.random.default_rng([seed, *case.name.encode()])
        z = rng.standard_normal(len(recs))
        recs = [replace(r, flow_m3s=r.flow_m3s * (1.0 + noise * zi)) for r, zi in zip(recs, z)]
    return recs


def _row(case: MapCase, res: dict) -> dict:
    sel = res["selection"]
    cands = {"+".join(c["params"]): c for c in sel["candidates"]}
    chosen = cands["+".join(sel["chosen"])]
    mean_abs = lambda e: float(np.mean(np.abs(e)))            # noqa: E731
    return {"map": case.name, "what": case.description,
            "nominal_mean_abs": mean_abs(cands[""]["cv_errors"]), "chosen": "+".join(sel["chosen"]) or "prior",
            "fit_rmse": chosen["fit_rmse"], "cv_mean_abs": mean_abs(chosen["cv_errors"]),
            "cv_max_abs": chosen["cv_max_abs"], "band": sel["prediction_band_eta"],
            "covered": int(np.sum(np.abs(chosen["cv_errors"]) <= np.array(sel["prediction_interval"]["half_width_eta"]))),
            "points": len(chosen["cv_errors"]),
            "law_cv_mean_abs": mean_abs(sel["baseline"]["cv_errors"]),
            "law_cv_max_abs": sel["baseline"]["cv_max_abs"], "law_better": sel["baseline_better"],
            "cv_mean_abs_by_rpm": {round(r): e for r, e in sorted(zip(sel["fold_rpm"], sel["chosen_fold_mean_abs"]))}}


def run(names=None, jobs: int | None = None, out=None, speeds_rpm=SPEEDS_RPM, bars=BARS,
        noise: float = 0.0) -> list[dict]:
    """Build, calibrate and print each map (all of :data:`MAPS`, or those named) on the grid ``speeds_rpm`` [rpm]
    × ``bars`` [bar gauge], each flow with a relative error of standard deviation ``noise`` [-] (:func:`build`)."""
    out = out or sys.stdout
    rows = []
    print(f"grid: {', '.join(f'{v:g}' for v in speeds_rpm)} rpm × {', '.join(f'{v:g}' for v in bars)} bar"
          + (f"; flows with {100 * noise:g} % noise (sd)" if noise > 0 else ""), file=out)
    print("| map | nominal twin: held-out mean \\|η err\\| | chosen set | fit RMSE | held-out mean \\|η err\\| (max) "
          "| 95 % prediction interval, RMS half-width (held-out points inside) | empirical law: held-out mean (max) |", file=out)
    print("|---|---|---|---|---|---|---|", file=out)
    for case in MAPS:
        if names and case.name not in names:
            continue
        res = calibrate_records(build(case, speeds_rpm, bars, noise), [f"{case.name}.csv"], params=MAP_PARAMS,
                                cv="speed", candidates=MAP_CANDIDATES, jobs=jobs)
        r = _row(case, res)
        rows.append(r)
        pt = lambda v: f"{100 * v:.2f}"                        # noqa: E731
        print(f"| `{r['map']}`: {r['what']} | {pt(r['nominal_mean_abs'])} | {r['chosen']} | {pt(r['fit_rmse'])} | "
              f"{pt(r['cv_mean_abs'])} ({pt(r['cv_max_abs'])}) | ± {pt(r['band'])} ({r['covered']}/{r['points']}) | "
              f"{pt(r['law_cv_mean_abs'])} "
              f"({pt(r['law_cv_max_abs'])}){' **better**' if r['law_better'] else ''} |", file=out, flush=True)
    return rows


def grid(rpm_text: str | None, bar_text: str | None) -> dict:
    """``--rpm`` and ``--bar`` of ``bench maps`` → ``speeds_rpm``, ``bars`` (defaults :data:`SPEEDS_RPM`,
    :data:`BARS`); InputError naming the option when a value is outside the default pump's range or the grid
    has fewer than two speeds (leave one speed out needs two)."""
    from ..cli import _floats
    rng = load_config().range
    speeds = SPEEDS_RPM if rpm_text is None else _floats(rpm_text, "--rpm")
    bars = BARS if bar_text is None else _floats(bar_text, "--bar")
    if len(set(speeds)) < 2 or not all(0 < v <= rng.max_speed_rpm for v in speeds):
        raise InputError("--rpm", rpm_text, f"two speeds or more in (0, {rng.max_speed_rpm:g}] rpm")
    if not all(0 < v <= rng.max_delivery_bar for v in bars):
        raise InputError("--bar", bar_text, f"pressures in (0, {rng.max_delivery_bar:g}] bar gauge")
    return {"speeds_rpm": tuple(speeds), "bars": tuple(bars)}


def add_parser(subparsers) -> None:
    """Teach the ``bench`` sub-command the choice ``maps`` (registered in ``cli._COMMAND_MODULES``)."""
    from ..cli import extend_bench
    bench = extend_bench(subparsers, "maps")
    if bench is None:
        return
    bench.add_argument("--maps", help="bench maps: comma-separated map names (default all: "
                                      + ", ".join(c.name for c in MAPS) + ")")
    bench.add_argument("--jobs", type=int, default=None, help="bench maps: worker processes (default: all cores)")
    bench.add_argument("--noise", type=float, default=0.0,
                       help="bench maps: relative error of each map flow, standard deviation (e.g. 0.002; default 0)")
    previous = bench.get_default("func")

    def dispatch(args):
        if args.what != "maps":
            return previous(args)
        check_range("--noise", args.noise, 0.0, 0.1)
        rows = run(args.maps.split(",") if args.maps else None, args.jobs, **grid(args.rpm, args.bar),
                   noise=args.noise)
        if args.json:
            with open(args.json, "w", encoding="utf-8") as f:
                json.dump(rows, f, indent=1)
        return 0
    bench.set_defaults(func=dispatch)
