"""Typed, validated pump configuration loaded from YAML (``config/pump.yaml``).

Every section maps to a frozen dataclass; unknown keys, missing keys, wrong
types, NaN and out-of-range values raise :class:`~gerotor_twin.errors.InputError`
naming the dotted field, the value and the allowed range.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from .errors import InputError, check_range
from .geometry.gerotor import GerotorGeometry
from .geometry.ports import Port
from .hydraulics.fluid import Fluid

__all__ = ["PumpConfig", "Orifice", "Boundary", "OperatingRange", "Numerics", "Clearances",
           "load_config", "default_config_path", "parse_config"]

DEFAULT_CONFIG = Path(__file__).resolve().parent.parent / "config" / "pump.yaml"


def default_config_path() -> Path:
    """The default pump (``config/pump.yaml`` of the source tree or the installed share)."""
    if DEFAULT_CONFIG.exists():
        return DEFAULT_CONFIG
    try:
        from ament_index_python.packages import get_package_share_directory
        return Path(get_package_share_directory("gerotor_twin")) / "config" / "pump.yaml"
    except Exception:  # noqa: BLE001 - fall back to the package copy
        return DEFAULT_CONFIG


@dataclass(frozen=True)
class Clearances:
    """Clearances [m]: tooth tip δ, lateral (per face), outer gear–housing radial c."""
    tooth_tip_m: float
    lateral_m: float
    housing_radial_m: float

    def __post_init__(self):
        check_range("clearances.tooth_tip_m", self.tooth_tip_m, 0.0, 5e-4, hi_open=True, unit="m")
        check_range("clearances.lateral_m", self.lateral_m, 0.0, 5e-4, hi_open=True, unit="m")
        check_range("clearances.housing_radial_m", self.housing_radial_m, 0.0, 1e-3, lo_open=True, unit="m")


@dataclass(frozen=True)
class Orifice:
    """Port orifice law: Cd(λ) = cd_max·tanh(2λ/λ_crit)."""
    cd_max: float = 0.7
    lambda_crit: float = 1000.0

    def __post_init__(self):
        check_range("orifice.cd_max", self.cd_max, 0.0, 1.0, lo_open=True)
        check_range("orifice.lambda_crit", self.lambda_crit, 0.0, 1e6, lo_open=True)


@dataclass(frozen=True)
class Boundary:
    """Port boundary conditions.

    ``imposed``: suction and delivery pressures are inputs (the twin on a bench).
    ``restriction``: the delivery line is a volume discharging to tank through a
    fixed orifice, as in sec. 4 of [1]; suction stays imposed.
    """
    mode: str = "imposed"
    suction_pressure_pa: float = 101325.0
    delivery_volume_m3: float = 2e-4
    restriction_area_m2: float = 2e-5

    def __post_init__(self):
        if self.mode not in ("imposed", "restriction"):
            raise InputError("boundary.mode", self.mode, "'imposed' or 'restriction'")
        check_range("boundary.suction_pressure_pa", self.suction_pressure_pa, 1e4, 1e6, unit="Pa")
        check_range("boundary.delivery_volume_m3", self.delivery_volume_m3, 0.0, 1.0, lo_open=True, unit="m^3")
        check_range("boundary.restriction_area_m2", self.restriction_area_m2, 0.0, 1e-2, lo_open=True,
                    unit="m^2")


@dataclass(frozen=True)
class OperatingRange:
    """Documented operating envelope: speed [rpm] and delivery gauge pressure [bar]."""
    max_speed_rpm: float = 3000.0
    max_delivery_bar: float = 27.5

    def __post_init__(self):
        check_range("range.max_speed_rpm", self.max_speed_rpm, 0.0, 20000.0, lo_open=True, unit="rpm")
        check_range("range.max_delivery_bar", self.max_delivery_bar, 0.0, 400.0, lo_open=True, unit="bar")


ERROR_MEASURES = ("pressure", "log_density")


@dataclass(frozen=True)
class Numerics:
    """Table resolution, output step (shaft angle [deg], time [s]) and sub-step error control.

    ``error_measure = "pressure"`` (default): a ROS2 sub-step is accepted when in
    every volume the error of the pressure is at most ``tolerance`` × (p_delivery −
    p_suction, at least 1 bar) and, where the oil is compressible (β small, below
    atmospheric pressure), the error of ln(ρ/ρ₀) at most ``log_density_tolerance``
    (≈ the mass error; it decides the filling, hence the volumetric efficiency).
    ``"log_density"``: the absolute error of ln(ρ/ρ₀) at most ``tolerance`` everywhere
    (the measure of versions ≤ 0.2: 5e-5 ≈ 75 kPa in the liquid, 75 Pa below p_atm).
    ``gerotor-twin bench accuracy`` measures the defaults against a tight reference.
    """
    table_points: int = 2048
    max_step_deg: float = 2.0
    max_step_s: float = 2e-4
    tolerance: float = 0.05
    error_measure: str = "pressure"
    log_density_tolerance: float = 2e-4

    def __post_init__(self):
        if int(self.table_points) != self.table_points or not 256 <= self.table_points <= 65536:
            raise InputError("numerics.table_points", self.table_points, "integer in [256, 65536]")
        check_range("numerics.max_step_deg", self.max_step_deg, 0.0, 5.0, lo_open=True, unit="deg")
        check_range("numerics.max_step_s", self.max_step_s, 0.0, 1e-2, lo_open=True, unit="s")
        check_range("numerics.tolerance", self.tolerance, 1e-12, 0.5)
        check_range("numerics.log_density_tolerance", self.log_density_tolerance, 1e-12, 1e-1)
        if self.error_measure not in ERROR_MEASURES:
            raise InputError("numerics.error_measure", self.error_measure, " | ".join(ERROR_MEASURES))


@dataclass(frozen=True)
class PumpConfig:
    """The whole pump: gear set, clearances, ports, fluid, laws, boundary, range, numerics."""
    gears: GerotorGeometry
    clearances: Clearances
    suction_port: Port
    delivery_port: Port
    fluid: Fluid
    orifice: Orifice
    tip_dh: float
    boundary: Boundary
    range: OperatingRange
    numerics: Numerics
    source: str = "<memory>"
    calibration: dict | None = field(default=None, compare=False, hash=False)  #: provenance of a fitted config (``gerotor-twin calibrate``), kept as written

    def to_dict(self) -> dict:
        """Back to the YAML structure (for logs and metadata)."""
        g = self.gears
        return {
            "gears": {"chambers": g.chambers, "eccentricity_m": g.eccentricity,
                      "lobe_centre_radius_m": g.lobe_centre_radius, "lobe_radius_m": g.lobe_radius,
                      "outer_root_radius_m": g.outer_root_radius, "outer_radius_m": g.outer_radius,
                      "inner_hole_radius_m": g.inner_hole_radius, "width_m": g.width},
            "clearances": _asdict(self.clearances),
            "ports": {"suction": {"start_deg": math.degrees(self.suction_port.start),
                                  "end_deg": math.degrees(self.suction_port.end)},
                      "delivery": {"start_deg": math.degrees(self.delivery_port.start),
                                   "end_deg": math.degrees(self.delivery_port.end)}},
            "fluid": _asdict(self.fluid),
            "orifice": _asdict(self.orifice),
            "leakage": {"tip_dh": self.tip_dh},
            "boundary": _asdict(self.boundary),
            "range": _asdict(self.range),
            "numerics": _asdict(self.numerics),
            **({"calibration": self.calibration} if self.calibration is not None else {}),
        }


def _asdict(obj) -> dict:
    return {f.name: getattr(obj, f.name) for f in fields(obj)}


_SECTIONS = {"gears", "clearances", "ports", "fluid", "orifice", "leakage", "boundary", "range", "numerics",
             "calibration"}


def _section(raw: dict, name: str, keys: set[str], required: bool = True) -> dict:
    sec = raw.get(name)
    if sec is None:
        if required:
            raise InputError(name, None, f"a mapping with keys {sorted(keys)}", "section missing")
        return {}
    if not isinstance(sec, dict):
        raise InputError(name, sec, "a mapping")
    unknown = set(sec) - keys
    if unknown:
        k = sorted(unknown)[0]
        raise InputError(f"{name}.{k}", sec[k], f"one of the keys {sorted(keys)}", "unknown key")
    for k, v in sec.items():
        if isinstance(v, bool) or (isinstance(v, float) and not math.isfinite(v)):
            raise InputError(f"{name}.{k}", v, "a finite number")
    return sec


def _num(sec: dict, section: str, key: str, default: Any = None) -> float:
    if key not in sec:
        if default is None:
            raise InputError(f"{section}.{key}", None, "a number", "missing key")
        return default
    v = sec[key]
    if isinstance(v, str):
        try:
            v = float(v)
        except ValueError:
            raise InputError(f"{section}.{key}", v, "a finite number") from None
    if not isinstance(v, (int, float)) or not math.isfinite(v):
        raise InputError(f"{section}.{key}", v, "a finite number")
    return v


def parse_config(raw: dict, source: str = "<memory>") -> PumpConfig:
    """Validate a raw mapping (the YAML document) into a :class:`PumpConfig`."""
    if not isinstance(raw, dict):
        raise InputError("config", type(raw).__name__, "a YAML mapping of sections")
    unknown = set(raw) - _SECTIONS
    if unknown:
        k = sorted(unknown)[0]
        raise InputError(k, raw[k], f"one of the sections {sorted(_SECTIONS)}", "unknown key")
    gk = {"chambers", "eccentricity_m", "lobe_centre_radius_m", "lobe_radius_m", "outer_root_radius_m",
          "outer_radius_m", "inner_hole_radius_m", "width_m"}
    gs = _section(raw, "gears", gk)
    cs = _section(raw, "clearances", {"tooth_tip_m", "lateral_m", "housing_radial_m"})
    clear = Clearances(*(_num(cs, "clearances", k) for k in ("tooth_tip_m", "lateral_m", "housing_radial_m")))
    chambers = _num(gs, "gears", "chambers")
    gears = GerotorGeometry(
        chambers=int(chambers) if float(chambers).is_integer() else chambers,
        eccentricity=_num(gs, "gears", "eccentricity_m"),
        lobe_centre_radius=_num(gs, "gears", "lobe_centre_radius_m"),
        lobe_radius=_num(gs, "gears", "lobe_radius_m"),
        outer_root_radius=_num(gs, "gears", "outer_root_radius_m"),
        outer_radius=_num(gs, "gears", "outer_radius_m"),
        inner_hole_radius=_num(gs, "gears", "inner_hole_radius_m"),
        width=_num(gs, "gears", "width_m"),
        tip_clearance=clear.tooth_tip_m,
    )
    ps = _section(raw, "ports", {"suction", "delivery"})
    ports = {}
    for name in ("suction", "delivery"):
        p = _section(ps, name, {"start_deg", "end_deg"}) if name in ps else None
        if p is None:
            raise InputError(f"ports.{name}", None, "a mapping with start_deg, end_deg", "missing key")
        a0 = _num(p, f"ports.{name}", "start_deg")
        a1 = _num(p, f"ports.{name}", "end_deg")
        check_range(f"ports.{name}.start_deg", a0, 0.0, 360.0, hi_open=True, unit="deg")
        ports[name] = Port(name, math.radians(a0), math.radians(a1))
    fk = {f.name for f in fields(Fluid)}
    fluid = Fluid(**{k: _num(_section(raw, "fluid", fk), "fluid", k) for k in _section(raw, "fluid", fk)})
    ok = {"cd_max", "lambda_crit"}
    orifice = Orifice(**{k: _num(_section(raw, "orifice", ok, False), "orifice", k)
                         for k in _section(raw, "orifice", ok, False)})
    ls = _section(raw, "leakage", {"tip_dh"}, False)
    tip_dh = check_range("leakage.tip_dh", _num(ls, "leakage", "tip_dh", 0.347), 0.0, 10.0, lo_open=True)
    bk = {"mode", "suction_pressure_pa", "delivery_volume_m3", "restriction_area_m2"}
    bs = _section(raw, "boundary", bk, False)
    boundary = Boundary(mode=bs.get("mode", "imposed"),
                        **{k: _num(bs, "boundary", k) for k in bk - {"mode"} if k in bs})
    rs = _section(raw, "range", {"max_speed_rpm", "max_delivery_bar"}, False)
    rng = OperatingRange(**{k: _num(rs, "range", k) for k in rs})
    ns = _section(raw, "numerics", {f.name for f in fields(Numerics)}, False)
    num = Numerics(**{k: (str(ns[k]) if k == "error_measure" else
                          int(_num(ns, "numerics", k)) if k == "table_points" else
                          _num(ns, "numerics", k)) for k in ns})
    _check_ports(ports["suction"], ports["delivery"])
    return PumpConfig(gears=gears, clearances=clear, suction_port=ports["suction"],
                      delivery_port=ports["delivery"], fluid=fluid, orifice=orifice, tip_dh=tip_dh,
                      boundary=boundary, range=rng, numerics=num, source=source,
                      calibration=_calibration_block(raw.get("calibration")))


def _calibration_block(sec) -> dict | None:
    """The optional ``calibration`` provenance block: a mapping, kept as written (not used by the model)."""
    if sec is None:
        return None
    if not isinstance(sec, dict):
        raise InputError("calibration", sec, "a mapping (the provenance written by `gerotor-twin calibrate`)")
    return sec


def _check_ports(s: Port, d: Port) -> None:
    """Ports must not overlap: delivery on the upper half, suction on the lower half."""
    if not (0 < d.start < d.end < math.pi):
        raise InputError("ports.delivery.start_deg", math.degrees(d.start), "0 < start < end < 180 deg",
                         "the delivery kidney lies where chambers shrink (upper half)")
    if not (math.pi < s.start < s.end < 2 * math.pi):
        raise InputError("ports.suction.start_deg", math.degrees(s.start), "180 < start < end < 360 deg",
                         "the suction kidney lies where chambers grow (lower half)")


def load_config(path: str | Path | None = None) -> PumpConfig:
    """Load and validate a pump YAML file (default: ``config/pump.yaml``).

    Read with :func:`gerotor_twin.yaml_safe.load_yaml_file` (size and alias
    expansion bounded); every problem raises one :class:`InputError`.
    """
    from .yaml_safe import load_yaml_file
    p = Path(path) if path is not None else default_config_path()
    raw = load_yaml_file(p, "--config")       # missing, directory, unreadable, bomb: one InputError
    return parse_config(raw, source=str(p))
