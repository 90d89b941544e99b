"""The SPEC of a design study (YAML): base pump, what varies, how it is sampled, what is reported.

Example (``config/sweep_demo.yaml`` is a complete one)::

    title: eccentricity x speed            # optional
    base_config: pump.yaml                 # relative to the SPEC file; default: the default pump
    model: mobility                        # outer-gear model (unless bearing_model is varied)
    revolutions: 30                        # at most this many to periodic state, the recorded one included [1, 1000]
    min_revolutions: 3                     # at least this many, the recorded (settled) one included [1, revolutions]
    set: {numerics.table_points: 1024}     # config fields held at one value for the whole study
    operating: {speed_rpm: 1500, delivery_bar: 10}   # the operating point when not varied
    parameters:                            # what varies; each a list or a range
      operating.speed_rpm: [1000, 2000, 3000]
      gears.eccentricity_m: {min: 3.3e-3, max: 3.7e-3, num: 5}    # linspace ({step: s} also; log: true)
      bearing_model: [fixed, mobility]
    design: grid                           # grid (full factorial) | lhs | sobol
    samples: 16                            # lhs/sobol: points drawn over the ranges without num/step
    seed: 1                                # lhs/sobol (scipy.stats.qmc, scrambled)
    outputs: [volumetric_efficiency, delivery_flow_ripple]   # CSV columns and plots (default: all)
    cavitation_threshold_bar_abs: 0.9      # optional; default p_atm minus the Eq. (23) switch band

A parameter is ``bearing_model``, ``operating.<field>`` (:data:`OPERATING_FIELDS`) or the
dotted path of any field of the pump YAML (``gears.eccentricity_m``, ``clearances.tooth_tip_m``,
``ports.suction.start_deg``, ``fluid.viscosity_pa_s`` ...).  With ``lhs``/``sobol`` the
ranges without ``num``/``step`` are sampled (``samples`` points, log-uniform with ``log: true``,
rounded when both bounds are integers) and crossed with the lists.  Every mistake raises one
:class:`InputError` naming the field, the value and the allowed range.  Values that only some
combinations make invalid (an undercut gear set) are not SPEC errors: those points are run and
recorded as failed with the reason.
"""
from __future__ import annotations

import hashlib
import itertools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..bearing.registry import MODEL_NAMES
from ..config import default_config_path
from ..errors import InputError
from ..yaml_safe import load_yaml_file
from .sweep_point import OPERATING_FIELDS, OUTPUTS, apply_overrides, point_config, temperature_keyword

__all__ = ["Axis", "SweepSpec", "load_spec", "parse_spec", "DESIGNS", "MAX_POINTS"]

DESIGNS = ("grid", "lhs", "sobol")
MAX_POINTS = 1_000_000
_KEYS = {"title", "base_config", "model", "revolutions", "min_revolutions", "set", "operating", "parameters",
         "design", "samples", "seed", "outputs", "cavitation_threshold_bar_abs"}
_DEFAULT_OPERATING = {"speed_rpm": 1500.0, "delivery_bar": 10.0, "suction_bar_abs": None, "oil_temperature_c": None}
_NON_GEOMETRY_CHECK = ("gears.", "clearances.tooth_tip_m")   # valid or not only in combination: per point


@dataclass(frozen=True)
class Axis:
    """One varied parameter: explicit ``values``, or a continuous range ``lo``..``hi`` (sampled by lhs/sobol)."""
    name: str
    values: tuple = ()
    lo: float | None = None
    hi: float | None = None
    log: bool = False
    integer: bool = False

    @property
    def continuous(self) -> bool:
        return not self.values

    def from_unit(self, u: np.ndarray) -> list:
        """Map samples in [0, 1) onto the range (log-uniform if ``log``; rounded if ``integer``)."""
        if self.log:
            v = np.exp(np.log(self.lo) + u * (np.log(self.hi) - np.log(self.lo)))
        else:
            v = self.lo + u * (self.hi - self.lo)
        return [int(round(x)) for x in v] if self.integer else [float(x) for x in v]


@dataclass(frozen=True)
class SweepSpec:
    """A validated SPEC (see the module docstring); :meth:`points` lists the design."""
    source: str
    title: str
    base_config: dict = field(repr=False)
    base_source: str = ""
    model: str = "mobility"
    revolutions: int = 30
    min_revolutions: int = 3
    set: dict = field(default_factory=dict)
    operating: dict = field(default_factory=dict)
    axes: tuple[Axis, ...] = ()
    design: str = "grid"
    samples: int = 0
    seed: int = 0
    outputs: tuple[str, ...] = OUTPUTS
    cavitation_threshold_pa: float | None = None

    def points(self) -> list[dict]:
        """Every point: ``{"id": "p000000", "index": i, "params": {name: value}}`` in a fixed order."""
        lists = [a for a in self.axes if not a.continuous]
        cont = [a for a in self.axes if a.continuous]
        sampled = [{}]
        if cont:
            u = _unit_sample(self.design, len(cont), self.samples, self.seed)
            cols = [a.from_unit(u[:, k]) for k, a in enumerate(cont)]
            sampled = [{a.name: cols[k][i] for k, a in enumerate(cont)} for i in range(u.shape[0])]
        combos = itertools.product(*[[(a.name, v) for v in a.values] for a in lists])
        out = []
        for i, (combo, s) in enumerate(itertools.product(combos, sampled)):
            params = dict(combo)
            params.update(s)
            out.append({"id": f"p{i:06d}", "index": i, "params": {a.name: params[a.name] for a in self.axes}})
        return out

    def task(self) -> dict:
        """The settings every point needs, by value (sent to the workers with each point)."""
        return {"base_config": self.base_config, "source": self.base_source, "set": dict(self.set),
                "operating": dict(self.operating), "model": self.model, "revolutions": self.revolutions,
                "min_revolutions": self.min_revolutions, "cavitation_threshold_pa": self.cavitation_threshold_pa,
                "non_config": [a.name for a in self.axes if not _is_config(a.name)]}

    def digest(self) -> str:
        """SHA-256 of everything that decides the results (a resumed run must match it)."""
        body = {"task": self.task(), "points": self.points()}
        return hashlib.sha256(json.dumps(body, sort_keys=True, default=str).encode()).hexdigest()


def _unit_sample(design: str, dims: int, n: int, seed: int) -> np.ndarray:
    from scipy.stats import qmc
    if design == "sobol":
        return qmc.Sobol(dims, scramble=True, rng=seed).random(n)
    if design == "lhs":
        return qmc.LatinHypercube(dims, rng=seed).random(n)
    raise InputError("design", design, "lhs | sobol when a parameter is a range without num/step")


def _is_config(name: str) -> bool:
    return name != "bearing_model" and not name.startswith("operating.")


def _finite(fieldname: str, v, allowed: str = "a finite number") -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise InputError(fieldname, v, allowed)
    return v


def _int(fieldname: str, v, lo: int, hi: int) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise InputError(fieldname, v, f"an integer in [{lo}, {hi}]")
    return v


def _range_axis(name: str, spec: dict, design: str) -> Axis:
    fld = f"parameters.{name}"
    unknown = set(spec) - {"min", "max", "num", "step", "log"}
    if unknown:
        k = sorted(unknown)[0]
        raise InputError(f"{fld}.{k}", spec[k], "keys min, max and one of num | step (optional log: true)")
    for k in ("min", "max"):
        if k not in spec:
            raise InputError(f"{fld}.{k}", None, "a finite number", "missing key")
        _finite(f"{fld}.{k}", spec[k])
    lo, hi, log = spec["min"], spec["max"], spec.get("log", False)
    if not isinstance(log, bool):
        raise InputError(f"{fld}.log", log, "true | false")
    if not lo < hi:
        raise InputError(f"{fld}.max", hi, f"> min = {lo:g}")
    if log and lo <= 0:
        raise InputError(f"{fld}.min", lo, "(0, inf) with log: true")
    integer = isinstance(lo, int) and isinstance(hi, int) and not log
    if "num" in spec and "step" in spec:
        raise InputError(f"{fld}.step", spec["step"], "absent when num is given (one of num | step)")
    if "num" in spec:
        n = _int(f"{fld}.num", spec["num"], 2, 100_000)
        v = np.geomspace(lo, hi, n) if log else np.linspace(lo, hi, n)
    elif "step" in spec:
        st = _finite(f"{fld}.step", spec["step"])
        if not 0 < st <= hi - lo or log:
            raise InputError(f"{fld}.step", st, f"(0, {hi - lo:g}] (and no log: true)")
        n = int(math.floor((hi - lo) / st * (1 + 1e-12))) + 1
        v = lo + st * np.arange(n)
    else:
        if design == "grid":
            raise InputError(f"{fld}", spec, "a list, or min/max with num or step (design: grid); "
                             "min/max alone needs design: lhs | sobol")
        return Axis(name, lo=float(lo), hi=float(hi), log=log, integer=integer)
    whole = integer and bool(np.all(v == np.round(v)))      # integer bounds and integral spacing: ints
    vals = tuple(int(round(x)) for x in v) if whole else tuple(float(x) for x in v)
    return Axis(name, values=vals)


def _axis(name, spec, design: str) -> Axis:
    if not isinstance(name, str) or not name:
        raise InputError("parameters", name,
                         "parameter names: bearing_model, operating.<field> or a dotted config path")
    if isinstance(spec, dict):
        return _range_axis(name, spec, design)
    if not isinstance(spec, list) or not spec:
        raise InputError(f"parameters.{name}", spec, "a non-empty list, or a mapping {min, max, num | step}")
    if name == "bearing_model":
        for v in spec:
            if v not in MODEL_NAMES:
                raise InputError("parameters.bearing_model", v, " | ".join(MODEL_NAMES))
    elif name.startswith("operating."):
        for v in spec:
            _finite(f"parameters.{name}", v)
    else:
        for v in spec:
            if not isinstance(v, str):
                _finite(f"parameters.{name}", v, "a finite number (or a string for a text field)")
    if len(set(map(repr, spec))) != len(spec):
        raise InputError(f"parameters.{name}", spec, "distinct values (a repeated value would run twice)")
    return Axis(name, values=tuple(spec))


def _axis_extremes(a: Axis) -> list:
    return [a.lo, a.hi] if a.continuous else list(a.values)


def _check_operating(name: str, values: list, cfg, where: str) -> None:
    """Operating values inside the base pump's envelope (the one-line error of the SPEC)."""
    rng = cfg.range
    limits = {"speed_rpm": (0.0, rng.max_speed_rpm, True, f"(0, {rng.max_speed_rpm:g}] rpm"),
              "delivery_bar": (0.0, rng.max_delivery_bar, False, f"[0, {rng.max_delivery_bar:g}] bar gauge"),
              "suction_bar_abs": (0.1, 5.0, False, "[0.1, 5] bar absolute"),
              "oil_temperature_c": (-40.0, 200.0, False, "[-40, 200] degC")}
    if name not in limits:
        raise InputError(where, values[0] if values else None,
                         "a field of operating: " + " | ".join(OPERATING_FIELDS), "unknown field")
    lo, hi, lo_open, allowed = limits[name]
    for v in values:
        if v is None and name in ("suction_bar_abs", "oil_temperature_c"):
            continue
        _finite(where, v, allowed)
        if v < lo or v > hi or (lo_open and v == lo):
            raise InputError(where, v, allowed)
    if name == "oil_temperature_c" and any(v is not None for v in values) and temperature_keyword() is None:
        raise InputError(where, values[0], "unset: this build's model has no oil-temperature input "
                                           "(issue 13 adds it)")


def _check_config_axis(name: str, values: list, raw: dict, source: str) -> None:
    """A config path must exist; a value the config refuses on its own (not by combination) is a SPEC error."""
    for v in values:
        try:
            point_config(raw, {name: v}, source)
        except InputError as exc:
            if exc.reason == "unknown key" or exc.field in ("config",):
                raise InputError(f"parameters.{name}", v, exc.allowed, f"not a config field: {exc}") from None
            if exc.field == name and not name.startswith(_NON_GEOMETRY_CHECK):
                raise InputError(f"parameters.{name}", v, exc.allowed) from None


def _mapping(raw: dict, key: str) -> dict:
    v = raw.get(key) or {}
    if not isinstance(v, dict):
        raise InputError(key, v, "a mapping")
    return v


def _base(raw: dict, spec_path: Path) -> tuple[dict, str]:
    p = raw.get("base_config")
    if p is None:
        path = default_config_path()
    else:
        if not isinstance(p, str):
            raise InputError("base_config", p, "a path to a pump YAML (relative to the SPEC file)")
        path = (spec_path.parent / p) if not Path(p).is_absolute() else Path(p)
    return load_yaml_file(path, "base_config"), str(path)


def parse_spec(raw: dict, spec_path: str | Path = "<memory>") -> SweepSpec:
    """Validate a SPEC mapping into a :class:`SweepSpec` (one :class:`InputError` per problem)."""
    if not isinstance(raw, dict):
        raise InputError("SPEC", type(raw).__name__, "a YAML mapping")
    unknown = set(raw) - _KEYS
    if unknown:
        k = sorted(unknown)[0]
        raise InputError(k, raw[k], f"one of the keys {sorted(_KEYS)}", "unknown key")
    spec_path = Path(spec_path)
    base, base_source = _base(raw, spec_path)
    sets = _mapping(raw, "set")
    for name, v in sets.items():
        if not _is_config(name):
            raise InputError(f"set.{name}", v, "a dotted config path (operating point: use operating:)")
    try:
        cfg = point_config(base, sets, base_source)
    except InputError as exc:
        raise InputError(f"set.{exc.field}" if exc.field in sets else f"base_config: {exc.field}", exc.value,
                         exc.allowed, exc.reason) from None
    model = raw.get("model", "mobility")
    if model not in MODEL_NAMES:
        raise InputError("model", model, " | ".join(MODEL_NAMES))
    revs = _int("revolutions", raw.get("revolutions", 30), 1, 1000)
    min_revs = _int("min_revolutions", raw.get("min_revolutions", 3), 1, revs)
    design = raw.get("design", "grid")
    if design not in DESIGNS:
        raise InputError("design", design, " | ".join(DESIGNS))
    operating = dict(_DEFAULT_OPERATING)
    for k, v in _mapping(raw, "operating").items():
        _check_operating(k, [v], cfg, f"operating.{k}")
        operating[k] = v
    params = _mapping(raw, "parameters")
    axes = tuple(_axis(name, s, design) for name, s in params.items())
    for a in axes:
        if a.name.startswith("operating."):
            _check_operating(a.name.split(".", 1)[1], _axis_extremes(a), cfg, f"parameters.{a.name}")
        elif _is_config(a.name):
            _check_config_axis(a.name, _axis_extremes(a), apply_overrides(base, sets), base_source)
    samples, seed = _sampling(raw, design, axes)
    outputs = _outputs(raw.get("outputs"))
    thr = raw.get("cavitation_threshold_bar_abs")
    if thr is not None:
        thr = _finite("cavitation_threshold_bar_abs", thr, "[0.001, 10] bar absolute") * 1e5
        if not 1e2 <= thr <= 1e6:
            raise InputError("cavitation_threshold_bar_abs", thr / 1e5, "[0.001, 10] bar absolute")
    title = raw.get("title", spec_path.stem)
    spec = SweepSpec(source=str(spec_path), title=str(title), base_config=base, base_source=base_source,
                     model=model, revolutions=revs, min_revolutions=min_revs, set=sets, operating=operating,
                     axes=axes, design=design, samples=samples, seed=seed, outputs=outputs,
                     cavitation_threshold_pa=thr)
    n = _count(spec)
    if n > MAX_POINTS:
        raise InputError("parameters", f"{n} points", f"at most {MAX_POINTS} points per study")
    return spec


def _sampling(raw: dict, design: str, axes) -> tuple[int, int]:
    seed = _int("seed", raw.get("seed", 0), 0, 2**32 - 1)
    if design == "grid":
        if "samples" in raw:
            raise InputError("samples", raw["samples"], "absent with design: grid (lhs | sobol draw samples)")
        return 0, seed
    if not any(a.continuous for a in axes):
        raise InputError("design", design, "grid, unless a parameter is a range without num/step (sampled)")
    n = _int("samples", raw.get("samples"), 1, MAX_POINTS)
    if design == "sobol" and n & (n - 1):
        raise InputError("samples", n, "a power of 2 for design: sobol (2, 4, 8, ...: keeps its balance)")
    return n, seed


def _outputs(value) -> tuple[str, ...]:
    if value is None:
        return OUTPUTS
    if not isinstance(value, list) or not value:
        raise InputError("outputs", value, "a non-empty list of: " + ", ".join(OUTPUTS))
    for v in value:
        if v not in OUTPUTS:
            raise InputError("outputs", v, ", ".join(OUTPUTS))
    return tuple(value)


def _count(spec: SweepSpec) -> int:
    n = 1
    for a in spec.axes:
        if not a.continuous:
            n *= len(a.values)
    return n * (spec.samples if any(a.continuous for a in spec.axes) else 1)


def load_spec(path: str | Path) -> SweepSpec:
    """Read and validate a SPEC YAML file (size-bounded safe YAML; one :class:`InputError` per problem)."""
    return parse_spec(load_yaml_file(path, "SPEC"), path)
