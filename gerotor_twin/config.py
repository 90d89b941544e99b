"""Typed, validated pump configuration loaded from YAML (``config/pump.yaml``).

Every section maps to a frozen dataclass; unknown keys, missing keys, wrong
types, NaN and out-of-range values raise :class:`~gerotor_twin.errors.InputError`
naming the dotted field, the value and the allowed range.  A number far from
its key's default, a key whose meaning changed and a removed key are not
errors but notes (:mod:`gerotor_twin.config_notes`, :attr:`PumpConfig.notes`),
said by :func:`load_config`.
"""
from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any, Callable

from .errors import InputError, check_range
from .geometry.gerotor import GerotorGeometry
from .geometry.ports import FACES_MAX, NOTCH_SHAPES, Notch, Port, geometry_port_angles, port_timing, sealing_lands
from .config_notes import drop_removed_keys, far_from_default
from .config_oil import (DEFAULT_REFERENCE_TEMPERATURE_K, OIL_SET_FLUID_KEYS, fluid_at, fluid_with_oil,
                         oil_to_dict, parse_air, parse_fluid_model, parse_oil)
from .hydraulics.fluid import Fluid
from .hydraulics.mixture import AirContent
from .hydraulics.oil import OilProperties
from .resources import resource_path

__all__ = ["PumpConfig", "Orifice", "Boundary", "OperatingRange", "Numerics", "Clearances", "MicroMotion",
           "load_config", "default_config_path", "parse_config"]

def default_config_path() -> Path:
    """The default pump: ``config/pump.yaml`` of the package's data (:func:`gerotor_twin.resources.share_dir`)."""
    return resource_path("config", "pump.yaml")


@dataclass(frozen=True)
class Clearances:
    """Clearances [m]: tooth tip δ, lateral (per face), outer gear–housing radial c; and the lateral gap's
    opening with pressure [m/Pa] (:func:`gerotor_twin.model.params.lateral_gap`)."""
    tooth_tip_m: float
    lateral_m: float
    housing_radial_m: float
    #: opening of each lateral gap per unit of delivery − suction pressure, ds/dΔp [m/Pa] (the plates' and
    #: housing's elastic deflection; 1e-11 m/Pa = 1 µm per bar; 0: rigid)
    lateral_opening_m_per_pa: float = 0.0

    def __post_init__(self):
        check_range("clearances.tooth_tip_m", self.tooth_tip_m, 0.0, 5e-4, hi_open=True, unit="m")
        check_range("clearances.lateral_m", self.lateral_m, 0.0, 5e-4, hi_open=True, unit="m")
        check_range("clearances.housing_radial_m", self.housing_radial_m, 0.0, 1e-3, lo_open=True, unit="m")
        check_range("clearances.lateral_opening_m_per_pa", self.lateral_opening_m_per_pa, 0.0, 1e-9, unit="m/Pa")


@dataclass(frozen=True)
class Orifice:
    """Port orifice law (:mod:`gerotor_twin.hydraulics.orifice`).

    ``law: merritt`` (default): Merritt's laminar (Cd = δ√Re, ``laminar_delta``) and turbulent
    (``cd_max``) orifice laws in series; ``law: flow_number``: Cd(λ) = cd_max·tanh(2λ/λ_crit), the
    law the paper's clearances were calibrated with (docs/paper.md, "Orifice law").
    """
    cd_max: float = 0.7
    lambda_crit: float = 1000.0
    law: str = "merritt"
    laminar_delta: float = 0.2

    def __post_init__(self):
        from .hydraulics.orifice import ORIFICE_LAWS
        check_range("orifice.cd_max", self.cd_max, 0.0, 1.0, lo_open=True)
        check_range("orifice.lambda_crit", self.lambda_crit, 0.0, 1e6, lo_open=True)
        if self.law not in ORIFICE_LAWS:
            raise InputError("orifice.law", self.law, " | ".join(ORIFICE_LAWS))
        check_range("orifice.laminar_delta", self.laminar_delta, 0.0, 1.0, lo_open=True)


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
    """Documented operating envelope: speed [rpm] and delivery gauge pressure [bar].

    ``max_speed_rpm`` bounds the speeds the model accepts; ``min_speed_rpm`` (optional) is the lowest
    speed the maker rates the pump for: the bench emulator's built-in profiles start there instead of
    at a third of ``max_speed_rpm`` (:mod:`gerotor_twin.bench_emulator.profiles`) and the family grid of
    ``bench accuracy --family`` (:mod:`gerotor_twin.model.family`) does too; the model and the twin
    still accept 0 (a pump starts from rest).
    """
    max_speed_rpm: float = 3000.0
    max_delivery_bar: float = 27.5
    min_speed_rpm: float | None = None

    def __post_init__(self):
        check_range("range.max_speed_rpm", self.max_speed_rpm, 0.0, 20000.0, lo_open=True, unit="rpm")
        check_range("range.max_delivery_bar", self.max_delivery_bar, 0.0, 400.0, lo_open=True, unit="bar")
        if self.min_speed_rpm is not None:
            check_range("range.min_speed_rpm", self.min_speed_rpm, 0.0, self.max_speed_rpm, hi_open=True,
                        unit="rpm (below range.max_speed_rpm)")

    def to_dict(self) -> dict:
        """The ``range`` section (``min_speed_rpm`` only when set)."""
        out = {"max_speed_rpm": self.max_speed_rpm, "max_delivery_bar": self.max_delivery_bar}
        return out if self.min_speed_rpm is None else {**out, "min_speed_rpm": self.min_speed_rpm}


ERROR_MEASURES = ("pressure", "log_density")
#: How the mobility method's outer gear meets the pressure step (``numerics.gear_coupling``, model/gear_coupling.py)
GEAR_COUPLINGS = ("stages", "partitioned", "constrained")

FIXED_CENTRE_CONTACT_RULES = ("rotate", "none")
CHAMBER_VOLUME_MODES = ("displaced", "nominal")


@dataclass(frozen=True)
class MicroMotion:
    """How the outer-gear position enters the gear set (docs/bearing.md, "Contact and volumes").

    ``fixed_centre_contact``: for the fixed-centre model only, ``rotate`` applies the
    "no overlap" branch of sec. 3.7 of [1] (the inner gear is turned, ≈ 1.55 mrad here,
    until one lobe touches: gaps ≈ 6 µm on the suction side, ≈ 56 µm on the delivery side
    at δ = 31.4 µm) or ``none`` (gears at their nominal angles: every gap = δ).  Moving-gear
    models always apply sec. 3.7 (the contact carries part of the load).
    ``chamber_volumes``: ``displaced`` takes V and dV/dθ of the displaced outer gear (first
    order in **e**, exact to O(|e|²)), ``nominal`` the centred gear set for every model (as in [1]).
    """
    fixed_centre_contact: str = "rotate"
    chamber_volumes: str = "displaced"

    def __post_init__(self):
        if self.fixed_centre_contact not in FIXED_CENTRE_CONTACT_RULES:
            raise InputError("micro_motion.fixed_centre_contact", self.fixed_centre_contact,
                             " | ".join(FIXED_CENTRE_CONTACT_RULES))
        if self.chamber_volumes not in CHAMBER_VOLUME_MODES:
            raise InputError("micro_motion.chamber_volumes", self.chamber_volumes,
                             " | ".join(CHAMBER_VOLUME_MODES))


@dataclass(frozen=True)
class Numerics:
    """Table resolution, output step (shaft angle [deg], time [s]) and sub-step error control.

    ``error_measure = "pressure"`` (default): a ROS2 sub-step is accepted when in
    every volume the error of the pressure is at most ``tolerance`` × Δp_ref, the error scale:
    the larger of p_delivery − p_suction and the chamber pressures' range over about the last
    revolution (highest − lowest sample), at least 1 bar; and, where the oil is compressible
    (β small, below atmospheric pressure), the error of ln(ρ/ρ₀) at most ``log_density_tolerance``
    (≈ the mass error; it decides the filling, hence the volumetric efficiency).
    ``"log_density"``: the absolute error of ln(ρ/ρ₀) at most ``tolerance`` everywhere
    (5e-5 ≈ 75 kPa in the liquid, 75 Pa below p_atm).
    ``closing_tolerance`` multiplies ``tolerance`` for a chamber whose delivery port closes within
    eight output steps (linear extrapolation of its open area) or opened within the last one: the
    pressure spikes of the throttled, compressed chamber and of a chamber refilled from the delivery
    kidney form there, and the embedded error estimate under-reads them (default 0.15; 1: no change;
    pressure measure only).  ``rate_fraction`` and ``top_tolerance`` of older pump files are ignored
    with a notice (:mod:`gerotor_twin.config_notes`).
    ``gear_coupling = "constrained"`` (default): the outer gear's velocity (any bearing model), linearised
    in the load over the output step, squeezes the chambers inside the ROS2 stages (implicitly), with the
    tooth contact as a unilateral constraint on that velocity inside the step and the overlap check's
    pull-back along the same direction (model/tooth_constraint.py, docs/numerics.md); ``"stages"``: the
    same without the constraint (the free velocity runs into the teeth and the check pulls the gear back
    after the step); ``"partitioned"``: the gear is moved after each output step by Heun's method and its
    squeeze spread over the next step (kept for comparison, docs/numerics.md).
    ``max_substep_attempts``: the sub-step attempts (accepted and rejected) one output step may take; past
    it the step is abandoned and reported (``model.pump.SolverFailure``): the bound on one call's work the
    node relies on (default 2000, ≈ 10 ms; the pump family takes 2–10; the tight references take 1e6).
    ``gerotor-twin bench accuracy`` measures the defaults against a tight reference.
    """
    table_points: int = 2048
    max_step_deg: float = 1.5
    max_step_s: float = 2e-4
    tolerance: float = 0.03
    error_measure: str = "pressure"
    log_density_tolerance: float = 1e-3
    closing_tolerance: float = 0.15
    gear_coupling: str = "constrained"
    max_substep_attempts: int = 2000

    def __post_init__(self):
        if int(self.max_substep_attempts) != self.max_substep_attempts or \
                not 10 <= self.max_substep_attempts <= 10_000_000:
            raise InputError("numerics.max_substep_attempts", self.max_substep_attempts, "integer in [10, 1e7]")
        if int(self.table_points) != self.table_points or not 256 <= self.table_points <= 65536:
            raise InputError("numerics.table_points", self.table_points, "integer in [256, 65536]")
        check_range("numerics.max_step_deg", self.max_step_deg, 0.0, 5.0, lo_open=True, unit="deg")
        check_range("numerics.max_step_s", self.max_step_s, 0.0, 1e-2, lo_open=True, unit="s")
        check_range("numerics.tolerance", self.tolerance, 1e-12, 0.5)
        check_range("numerics.log_density_tolerance", self.log_density_tolerance, 1e-12, 1e-1)
        check_range("numerics.closing_tolerance", self.closing_tolerance, 1e-3, 1.0)
        if self.error_measure not in ERROR_MEASURES:
            raise InputError("numerics.error_measure", self.error_measure, " | ".join(ERROR_MEASURES))
        if self.gear_coupling not in GEAR_COUPLINGS:
            raise InputError("numerics.gear_coupling", self.gear_coupling, " | ".join(GEAR_COUPLINGS))


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
    micro_motion: MicroMotion = MicroMotion()
    #: oil properties versus temperature (None: μ, ρ, β of ``fluid`` are constants)
    oil: OilProperties | None = None
    #: oil temperature used while none is measured [K]; ``fluid`` holds the properties there
    reference_temperature_k: float = 313.15
    #: state equation of the oil: "mixture" (oil + free air + vapour) or "paper" (eq. (23))
    fluid_model: str = "mixture"
    #: free air content and polytropic index of the mixture
    air: AirContent = AirContent()
    #: effective displacement / that of the ideal profiles, k_D [-] (:mod:`gerotor_twin.model.volumetric`)
    displacement_factor: float = 1.0
    #: effective area C_d·A of a turbulent delivery → suction path [m²] (:mod:`gerotor_twin.model.volumetric`)
    bypass_area_m2: float = 0.0
    #: chambers' unfilled fraction at 1000 rpm and atmospheric suction, k_f [-] (:mod:`gerotor_twin.model.volumetric`)
    filling_loss_at_1000rpm: float = 0.0
    #: the inlet's pressure drop the chambers absorb before they fill short, Δp_m [Pa] (:mod:`gerotor_twin.model.volumetric`)
    filling_margin_pa: float = 0.0

    def with_fluid_model(self, model: str) -> "PumpConfig":
        """The same pump with another fluid model (``"paper"`` or ``"mixture"``)."""
        return replace(self, fluid_model=parse_fluid_model(model))

    def fluid_at(self, t_k: float | None) -> Fluid:
        """The fluid at oil temperature T [K] (the reference temperature for None; constant without oil)."""
        t_ref = self.reference_temperature_k
        return fluid_at(self.fluid, self.oil, t_ref, t_ref if t_k is None else t_k)
    calibration: dict | None = field(default=None, compare=False, hash=False)  #: provenance of a fitted config (``gerotor-twin calibrate``), kept as written
    #: one-line notes on the file's keys (a value far from its default, a changed or removed key;
    #: :mod:`gerotor_twin.config_notes`), said by :func:`load_config`
    notes: tuple[str, ...] = field(default=(), compare=False, hash=False)

    def to_dict(self) -> dict:
        """Back to the YAML structure (for logs and metadata)."""
        g = self.gears
        return {
            "gears": {"chambers": g.chambers, "eccentricity_m": g.eccentricity,
                      "lobe_centre_radius_m": g.lobe_centre_radius, "lobe_radius_m": g.lobe_radius,
                      "outer_root_radius_m": g.outer_root_radius, "outer_radius_m": g.outer_radius,
                      "inner_hole_radius_m": g.inner_hole_radius, "width_m": g.width},
            "clearances": _asdict(self.clearances),
            "ports": {p.name: _port_dict(p) for p in (self.suction_port, self.delivery_port)},
            "fluid": _fluid_dict(self),
            **_oil_dict(self),
            "orifice": _asdict(self.orifice),
            "leakage": {"tip_dh": self.tip_dh},
            "volumetric": {"displacement_factor": self.displacement_factor, "bypass_area_m2": self.bypass_area_m2,
                           "filling_loss_at_1000rpm": self.filling_loss_at_1000rpm,
                           "filling_margin_pa": self.filling_margin_pa},
            "boundary": _asdict(self.boundary),
            "range": self.range.to_dict(),
            "numerics": _asdict(self.numerics),
            "micro_motion": _asdict(self.micro_motion),
            **({"calibration": self.calibration} if self.calibration is not None else {}),
        }


def _port_dict(p: Port) -> dict:
    """One port in the explicit form (resolved angles, grooves with their resolved radius)."""
    d = {"start_deg": math.degrees(p.start), "end_deg": math.degrees(p.end), "closing_edge": p.closing_edge}
    for key in ("opening_notch", "closing_notch"):
        n = getattr(p, key)
        if n is not None:
            d[key] = {"length_deg": math.degrees(n.length), "width_m": n.width, "depth_m": n.depth,
                      "shape": n.shape, "radius_m": n.radius}
    return d


def _asdict(obj) -> dict:
    return {f.name: getattr(obj, f.name) for f in fields(obj)}


def _fluid_dict(cfg: PumpConfig) -> dict:
    """The ``fluid`` section (without the keys an ``oil`` section sets)."""
    d = _asdict(cfg.fluid)
    return d if cfg.oil is None else {k: v for k, v in d.items() if k not in OIL_SET_FLUID_KEYS}


def _oil_dict(cfg: PumpConfig) -> dict:
    """``fluid_model``, ``mixture`` and (if any) ``oil`` sections."""
    out = {"fluid_model": cfg.fluid_model, "mixture": _asdict(cfg.air)}
    if cfg.oil is not None:
        out["oil"] = oil_to_dict(cfg.oil, cfg.reference_temperature_k)
    return out


_SECTIONS = {"gears", "clearances", "ports", "fluid", "orifice", "leakage", "boundary", "range", "numerics",
             "micro_motion", "oil", "mixture", "fluid_model", "calibration", "volumetric"}


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
    raw, notes = drop_removed_keys(raw)
    unknown = set(raw) - _SECTIONS
    if unknown:
        k = sorted(unknown)[0]
        raise InputError(k, raw[k], f"one of the sections {sorted(_SECTIONS)}", "unknown key")
    gk = {"chambers", "eccentricity_m", "lobe_centre_radius_m", "lobe_radius_m", "outer_root_radius_m",
          "outer_radius_m", "inner_hole_radius_m", "width_m"}
    gs = _section(raw, "gears", gk)
    cs = _section(raw, "clearances", {"tooth_tip_m", "lateral_m", "housing_radial_m", "lateral_opening_m_per_pa"})
    clear = Clearances(*(_num(cs, "clearances", k) for k in ("tooth_tip_m", "lateral_m", "housing_radial_m")),
                       _num(cs, "clearances", "lateral_opening_m_per_pa", 0.0))
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
    ports = _ports(raw, gears)
    fluid, oil, t_ref = _fluid_and_oil(raw)
    ok = {"cd_max", "lambda_crit", "law", "laminar_delta"}
    osec = _section(raw, "orifice", ok, False)
    orifice = Orifice(**{k: (str(osec[k]) if k == "law" else _num(osec, "orifice", k)) for k in osec})
    ls = _section(raw, "leakage", {"tip_dh"}, False)
    tip_dh = check_range("leakage.tip_dh", _num(ls, "leakage", "tip_dh", 0.347), 0.0, 10.0, lo_open=True)
    vs = _section(raw, "volumetric", {"displacement_factor", "bypass_area_m2", "filling_loss_at_1000rpm",
                                      "filling_margin_pa"}, False)
    k_d = check_range("volumetric.displacement_factor", _num(vs, "volumetric", "displacement_factor", 1.0), 0.5, 1.1)
    a_b = check_range("volumetric.bypass_area_m2", _num(vs, "volumetric", "bypass_area_m2", 0.0), 0.0, 1e-4, unit="m²")
    k_f = check_range("volumetric.filling_loss_at_1000rpm", _num(vs, "volumetric", "filling_loss_at_1000rpm", 0.0),
                      0.0, 0.2)
    dp_m = check_range("volumetric.filling_margin_pa", _num(vs, "volumetric", "filling_margin_pa", 0.0), 0.0, 1e5,
                       unit="Pa")
    bk = {"mode", "suction_pressure_pa", "delivery_volume_m3", "restriction_area_m2"}
    bs = _section(raw, "boundary", bk, False)
    boundary = Boundary(mode=bs.get("mode", "imposed"),
                        **{k: _num(bs, "boundary", k) for k in bk - {"mode"} if k in bs})
    rs = _section(raw, "range", {"max_speed_rpm", "max_delivery_bar", "min_speed_rpm"}, False)
    rng = OperatingRange(**{k: _num(rs, "range", k) for k in rs})
    ns = _section(raw, "numerics", {f.name for f in fields(Numerics)}, False)
    num = Numerics(**{k: (str(ns[k]) if k in ("error_measure", "gear_coupling") else
                          int(_num(ns, "numerics", k)) if k in ("table_points", "max_substep_attempts") else
                          _num(ns, "numerics", k)) for k in ns})
    return PumpConfig(gears=gears, clearances=clear, suction_port=ports["suction"],
                      delivery_port=ports["delivery"], fluid=fluid, orifice=orifice, tip_dh=tip_dh,
                      boundary=boundary, range=rng, numerics=num, source=source, oil=oil,
                      reference_temperature_k=t_ref, fluid_model=parse_fluid_model(raw.get("fluid_model", "mixture")),
                      air=parse_air(_section(raw, "mixture", {f.name for f in fields(AirContent)}, False)),
                      micro_motion=_micro_motion(raw), displacement_factor=k_d, bypass_area_m2=a_b,
                      filling_loss_at_1000rpm=k_f, filling_margin_pa=dp_m,
                      calibration=_calibration_block(raw.get("calibration")),
                      notes=tuple(notes + far_from_default("numerics", ns, num)
                                  + _bridge_notes(gears, ports["suction"], ports["delivery"])))


def _micro_motion(raw: dict) -> MicroMotion:
    """The optional ``micro_motion`` section (two choices, each a string)."""
    sec = _section(raw, "micro_motion", {f.name for f in fields(MicroMotion)}, False)
    return MicroMotion(**{k: v if isinstance(v, str) else repr(v) for k, v in sec.items()})


def _fluid_and_oil(raw: dict) -> tuple[Fluid, OilProperties | None, float]:
    """The ``fluid`` and optional ``oil`` sections: (fluid at the reference temperature, oil, T_ref [K])."""
    fk = {f.name for f in fields(Fluid)}
    fs = _section(raw, "fluid", fk)
    kwargs = {k: _num(fs, "fluid", k) for k in fs}
    oil, t_ref = (None, DEFAULT_REFERENCE_TEMPERATURE_K) if raw.get("oil") is None else parse_oil(raw["oil"])
    return fluid_with_oil(fs, kwargs, oil, t_ref), oil, t_ref


def _calibration_block(sec) -> dict | None:
    """The optional ``calibration`` provenance block: a mapping, kept as written (not used by the model)."""
    if sec is None:
        return None
    if not isinstance(sec, dict):
        raise InputError("calibration", sec, "a mapping (the provenance written by `gerotor-twin calibrate`)")
    return sec


PORT_TIMINGS = ("degrees", "geometry")
_NOTCH_KEYS = {"length_deg", "width_m", "depth_m", "shape", "radius_m"}


def _ports(raw: dict, gears: GerotorGeometry) -> dict[str, Port]:
    """The ``ports`` section: kidneys in degrees (``timing: degrees``, the form without the key) or from
    the gear set (``timing: geometry``, :func:`~gerotor_twin.geometry.ports.geometry_port_angles`),
    each with an optional ``closing_edge`` and relief grooves ``opening_notch`` / ``closing_notch``."""
    ps = _section(raw, "ports", {"suction", "delivery", "timing"})
    timing = ps.get("timing", "degrees")
    if timing not in PORT_TIMINGS:
        raise InputError("ports.timing", timing, " | ".join(PORT_TIMINGS))
    explicit = timing == "degrees"
    keys = {"closing_edge", "opening_notch", "closing_notch"} | ({"start_deg", "end_deg"} if explicit else set())
    secs, notches = {}, {}
    for name in ("suction", "delivery"):
        if name not in ps:
            raise InputError(f"ports.{name}", None, "a mapping with start_deg, end_deg" if explicit else
                             "a mapping (may be empty: {})", "missing key")
        p = ps[name] if ps[name] is not None or explicit else {}
        if not explicit and isinstance(p, dict) and ({"start_deg", "end_deg"} & set(p)):
            k = sorted({"start_deg", "end_deg"} & set(p))[0]
            raise InputError(f"ports.{name}.{k}", p[k], "no angle with ports.timing: geometry",
                             "the kidney edges come from the gear set; remove the angle or set timing: degrees")
        secs[name] = _section({f"ports.{name}": p}, f"ports.{name}", keys)
        for edge in ("opening", "closing"):
            if secs[name].get(f"{edge}_notch") is not None:
                notches[(name, edge)] = _notch(secs[name][f"{edge}_notch"], f"ports.{name}.{edge}_notch",
                                               gears, name, edge)
    if explicit:
        angles = {}
        for name in ("suction", "delivery"):
            a0 = _num(secs[name], f"ports.{name}", "start_deg")
            a1 = _num(secs[name], f"ports.{name}", "end_deg")
            check_range(f"ports.{name}.start_deg", a0, 0.0, 360.0, hi_open=True, unit="deg")
            angles[name] = (math.radians(a0), math.radians(a1))
    else:
        angles = geometry_port_angles(gears, notches)
    ports = {name: Port(name, *angles[name], str(secs[name].get("closing_edge", "ray")),
                        notches.get((name, "opening")), notches.get((name, "closing")))
             for name in ("suction", "delivery")}
    _check_ports(ports["suction"], ports["delivery"])
    return ports


#: a sealing land or relief groove may reach this far past the chamber at its dead centre before it is named [deg]
#: (the kidneys of ``timing: geometry`` sit on it to round-off; angles given to 0.01° within 0.01°)
BRIDGE_TOLERANCE_DEG = 0.05

_DEAD_CENTRE = {"land_margin_max": "maximum", "land_margin_min": "minimum"}


def _bridge_notes(gears: GerotorGeometry, suction: Port, delivery: Port) -> list[str]:
    """One note per sealing land or relief groove through which the chamber at a dead centre sees both kidneys
    (:func:`~gerotor_twin.geometry.ports.port_timing`'s margin below −:data:`BRIDGE_TOLERANCE_DEG`): a leak path
    from delivery to suction through the chamber, legal but rarely meant (kidney angles taken from another gear
    set, say)."""
    out = []
    for key, margin in port_timing(gears, suction, delivery).items():
        deg = math.degrees(margin)
        if deg >= -BRIDGE_TOLERANCE_DEG:
            continue
        if key in _DEAD_CENTRE:
            out.append(f"ports: the land at the {_DEAD_CENTRE[key]}-volume dead centre is {-deg:.2f} deg narrower than "
                       f"the chamber there, which opens the delivery kidney to the suction kidney (a leak path through "
                       f"the chamber); ports.timing: geometry makes each land the chamber's width")
        else:
            port, edge = key.split("_")[:2]
            out.append(f"ports.{port}.{edge}_notch: its tip reaches {-deg:.2f} deg past the chamber at the dead centre, "
                       f"which is still open to the other kidney (a leak path through the groove)")
    return out


def _notch(sec, field: str, gears: GerotorGeometry, port: str, edge: str) -> Notch:
    """One relief groove mapping: length_deg, width_m, depth_m, shape (tapered), radius_m (auto)."""
    if not isinstance(sec, dict):
        raise InputError(field, sec, f"a mapping with keys {sorted(_NOTCH_KEYS)}")
    unknown = set(sec) - _NOTCH_KEYS
    if unknown:
        k = sorted(unknown)[0]
        raise InputError(f"{field}.{k}", sec[k], f"one of the keys {sorted(_NOTCH_KEYS)}", "unknown key")
    length = check_range(f"{field}.length_deg", _num(sec, field, "length_deg"), 0.0, 30.0, lo_open=True,
                         unit="deg")
    width = check_range(f"{field}.width_m", _num(sec, field, "width_m"), 0.0, 0.02, lo_open=True, unit="m")
    depth = check_range(f"{field}.depth_m", _num(sec, field, "depth_m"), 0.0, 0.01, lo_open=True, unit="m")
    shape = sec.get("shape", "tapered")
    if shape not in NOTCH_SHAPES:
        raise InputError(f"{field}.shape", shape, " | ".join(NOTCH_SHAPES))
    r_lo = gears.inner_root_radius
    r_hi = gears.outer_root_radius + gears.eccentricity
    if sec.get("radius_m", "auto") == "auto":
        lands = sealing_lands(gears)
        radius = lands.max_radius if FACES_MAX[(port, edge)] else lands.min_radius
    else:
        radius = check_range(f"{field}.radius_m", _num(sec, field, "radius_m"), r_lo, r_hi, unit="m")
    if width >= r_hi - r_lo:
        raise InputError(f"{field}.width_m", width, f"(0, {r_hi - r_lo:g}) m", "wider than the chamber band")
    return Notch(length=math.radians(length), width=width, depth=depth, radius=radius, shape=shape)


def _check_ports(s: Port, d: Port) -> None:
    """Ports must not overlap: delivery on the upper half, suction on the lower half (relief grooves
    included)."""
    if not (0 < d.start < d.end < math.pi):
        raise InputError("ports.delivery.start_deg", math.degrees(d.start), "0 < start < end < 180 deg",
                         "the delivery kidney lies where chambers shrink (upper half)")
    if not (math.pi < s.start < s.end < 2 * math.pi):
        raise InputError("ports.suction.start_deg", math.degrees(s.start), "180 < start < end < 360 deg",
                         "the suction kidney lies where chambers grow (lower half)")
    for p, lo, hi in ((d, 0.0, math.pi), (s, math.pi, 2 * math.pi)):
        for key, tip in (("opening_notch", p.start - (p.opening_notch.length if p.opening_notch else 0.0)),
                         ("closing_notch", p.end + (p.closing_notch.length if p.closing_notch else 0.0))):
            if getattr(p, key) is not None and not lo < tip < hi:
                raise InputError(f"ports.{p.name}.{key}.length_deg", math.degrees(getattr(p, key).length),
                                 f"a groove tip inside ({math.degrees(lo):g}, {math.degrees(hi):g}) deg",
                                 f"the tip would be at {math.degrees(tip):.2f} deg, past the dead centre")


def _warn(text: str) -> None:
    """Say a config note on stderr (through :mod:`logging`, logger ``gerotor_twin.config``)."""
    logging.getLogger(__name__).warning("warning: %s", text)


def load_config(path: str | Path | None = None, what: str = "--config",
                warn: Callable[[str], None] | None = _warn) -> PumpConfig:
    """Load and validate a pump YAML file (default: ``config/pump.yaml``).

    Read with :func:`gerotor_twin.yaml_safe.load_yaml_file` (size and alias
    expansion bounded); every problem raises one :class:`InputError`.

    Parameters
    ----------
    path : path, optional
        The pump YAML (default :func:`default_config_path`).
    what : str
        The option or parameter the path came from, named in the errors about
        the file itself (``--config`` on the command line, ``pump_config`` in the node).
    warn : callable or None
        Called with each of the config's :attr:`PumpConfig.notes` (one line each; default: a
        logging WARNING, on stderr when logging is not configured); None: silent.
    """
    from .yaml_safe import load_yaml_file
    p = Path(path) if path is not None else default_config_path()
    raw = load_yaml_file(p, what)       # missing, directory, unreadable, bomb: one InputError
    if not isinstance(raw, dict):
        raise InputError(what, str(p), f"a YAML mapping of the sections {sorted(_SECTIONS)}",
                         "the file is empty" if raw is None else f"the file holds a {type(raw).__name__}")
    cfg = parse_config(raw, source=str(p))
    for note in cfg.notes if warn is not None else ():
        warn(f"{what} {p}: {note}")
    return cfg
