"""A bench pump: how the emulated pump and its sensors differ from the twin in form
(``gerotor-twin synth-bench --bench-pump F``).

The file (read with :func:`gerotor_twin.yaml_safe.load_yaml_file`: size and alias expansion
bounded) is a mapping; every key is optional::

    name: worn_tips                 # letters, digits, _ and - (default: the file's stem)
    description: free text          # what it emulates and why
    pump:                           # deviations from the nominal pump (``--config``)
      clearance_factors: {tooth_tip: 1.4, lateral: 1.0, housing_radial: 1.0}   # × nominal [-]
      clearances: {lateral_opening_m_per_pa: 2.0e-11}   # lateral gaps opening with Δp [m/Pa] (2 µm/bar)
      orifice: {law: flow_number, cd_max: 0.62, lambda_crit: 1000, laminar_delta: 0.2}
      mixture: {air_fraction: 8.0e-3}            # free air at atmospheric pressure [-]
      leakage: {tip_dh: 0.15}                    # tooth-tip gap length law h* = h(1 + dh) [-]
      ports: {timing_offset_deg: 1.5}            # every kidney edge turned by this [deg]
    sensors:                        # bias, first-order lag, noise of each bench sensor (SI)
      speed: {bias_rad_s: 0.5, tau_s: 0.02, noise_rad_s: 0.1}
      delivery_pressure: {bias_pa: 5000, tau_s: 0.01, noise_pa: 2000}
      delivery_flow: {bias_m3s: 1.0e-6, tau_s: 0.2, noise_m3s: 1.0e-6, noise_rel: 0.003, at: atmospheric}
      oil_temperature: {bias_c: 0.5, tau_s: 3.0, noise_c: 0.05}

``pump``: clearance factors multiply the nominal config's ``clearances`` (tooth tip, lateral,
outer gear–housing); ``clearances.lateral_opening_m_per_pa`` (the plates deflecting,
:func:`gerotor_twin.model.params.lateral_gap`), ``orifice``, ``mixture.air_fraction`` and ``leakage.tip_dh``
replace the config's values; ``ports.timing_offset_deg`` adds to both kidneys' ``start_deg`` and ``end_deg``
(positive: in the direction of the chamber angles, each edge reached later).  A suction kidney
whose closing edge is cut to the chamber (``closing_edge: chamber``) keeps that edge at the dead
centre: the config describes it relative to the gear set.  A key left out keeps the nominal value.
The model has one tooth-tip clearance δ for every lobe (the kernel's gap law takes a scalar), so a
bench pump cannot give one lobe or tooth its own clearance.

``sensors``: each key replaces the emulator's default
(:class:`~gerotor_twin.bench_emulator.sensors.BenchSpec`); a bias adds to every recorded sample, a
lag filters the true value before it (y' = (u − y)/τ), noise is Gaussian with the given standard
deviation; ``delivery_flow.at`` says where the flow meter reads (``delivery``, default, or ``atmospheric``: a
meter in the return line, :mod:`gerotor_twin.hydraulics.meter`).

Every problem is one :class:`~gerotor_twin.errors.InputError` naming the file, the field, the value
and the allowed range.  :meth:`BenchPump.resolved` fills every field with the value used, which
``synth-bench`` records in the file's metadata.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from gerotor_twin.errors import InputError, check_range
from gerotor_twin.hydraulics.meter import FLOW_METERS
from gerotor_twin.hydraulics.orifice import ORIFICE_LAWS

from .profile_file import name_and_description
from .sensors import BenchSpec

__all__ = ["BenchPump", "PUMP_FIELDS", "SENSOR_FIELDS", "load_bench_pump", "parse_bench_pump"]

#: ``pump.<section>.<key>`` → (attribute of :class:`BenchPump`, allowed: (low, high, unit) or choices).
PUMP_FIELDS: dict[str, tuple[str, tuple]] = {
    "clearance_factors.tooth_tip": ("tooth_tip_factor", (0.5, 3.0, "x nominal")),
    "clearance_factors.lateral": ("lateral_factor", (0.5, 3.0, "x nominal")),
    "clearance_factors.housing_radial": ("housing_factor", (0.5, 3.0, "x nominal")),
    "clearances.lateral_opening_m_per_pa": ("lateral_opening", (0.0, 1e-9, "m/Pa")),
    "orifice.law": ("orifice_law", tuple(ORIFICE_LAWS)),
    "orifice.cd_max": ("cd_max", (0.3, 1.0, "")),
    "orifice.lambda_crit": ("lambda_crit", (10.0, 1.0e5, "")),
    "orifice.laminar_delta": ("laminar_delta", (0.05, 1.0, "")),
    "mixture.air_fraction": ("air_fraction", (1e-9, 0.1, "")),
    "leakage.tip_dh": ("tip_dh", (0.01, 2.0, "")),
    "ports.timing_offset_deg": ("port_timing_offset_deg", (-5.0, 5.0, "deg")),
}
#: ``sensors.<sensor>.<key>`` → (:class:`BenchSpec` field, (low, high, unit)).
SENSOR_FIELDS: dict[str, tuple[str, tuple]] = {
    "speed.bias_rad_s": ("speed_bias_rad_s", (-10.0, 10.0, "rad/s")),
    "speed.tau_s": ("speed_tau_s", (0.0, 10.0, "s")),
    "speed.noise_rad_s": ("speed_noise_rad_s", (0.0, 10.0, "rad/s")),
    "delivery_pressure.bias_pa": ("pressure_bias_pa", (-5.0e5, 5.0e5, "Pa")),
    "delivery_pressure.tau_s": ("pressure_tau_s", (0.0, 10.0, "s")),
    "delivery_pressure.noise_pa": ("pressure_noise_pa", (0.0, 1.0e5, "Pa")),
    "delivery_flow.bias_m3s": ("flow_bias_m3s", (-1.0e-4, 1.0e-4, "m^3/s")),
    "delivery_flow.tau_s": ("flow_tau_s", (0.0, 10.0, "s")),
    "delivery_flow.noise_m3s": ("flow_noise_m3s", (0.0, 1.0e-4, "m^3/s")),
    "delivery_flow.noise_rel": ("flow_noise_rel", (0.0, 0.1, "")),
    "delivery_flow.at": ("flow_meter", FLOW_METERS),
    "oil_temperature.bias_c": ("temperature_bias_c", (-20.0, 20.0, "K")),
    "oil_temperature.tau_s": ("temperature_tau_s", (0.0, 600.0, "s")),
    "oil_temperature.noise_c": ("temperature_noise_c", (0.0, 5.0, "K")),
}
#: Sections of ``pump`` whose keys replace the nominal config's keys of the same section and name.
_REPLACED_SECTIONS = ("clearances", "orifice", "mixture", "leakage")
_TOP_KEYS = ("name", "description", "pump", "sensors")
_MAX_DESCRIPTION = 400


@dataclass(frozen=True)
class BenchPump:
    """Deviations of the emulated pump and its sensors from the twin (format: module docstring).

    Attributes
    ----------
    name, description : str
        What it is called and what it emulates.
    tooth_tip_factor, lateral_factor, housing_factor : float
        Clearances of the emulated pump relative to the nominal config [-].
    lateral_opening : float or None
        Opening of the lateral gaps per unit delivery − suction pressure [m/Pa]; None: the nominal config's.
    orifice_law : str or None
        Orifice law at the ports (``merritt`` | ``flow_number``); None: the nominal config's.
    cd_max, lambda_crit, laminar_delta : float or None
        Orifice parameters [-]; None: the nominal config's.
    air_fraction : float or None
        Free air at atmospheric pressure [-]; None: the nominal config's.
    tip_dh : float or None
        Tooth-tip gap length law ``leakage.tip_dh`` [-]; None: the nominal config's.
    port_timing_offset_deg : float
        Turn of every kidney edge [deg].
    sensors : dict
        :class:`BenchSpec` field → value for the sensor settings the file sets (SI).
    source : str
        Text of the file ('' when built in code).
    """
    name: str = "bench_pump"
    description: str = ""
    tooth_tip_factor: float = 1.0
    lateral_factor: float = 1.0
    housing_factor: float = 1.0
    lateral_opening: float | None = None
    orifice_law: str | None = None
    cd_max: float | None = None
    lambda_crit: float | None = None
    laminar_delta: float | None = None
    air_fraction: float | None = None
    tip_dh: float | None = None
    port_timing_offset_deg: float = 0.0
    sensors: dict = field(default_factory=dict, hash=False)
    source: str = field(default="", compare=False, repr=False)

    def bench_spec(self, base: BenchSpec = BenchSpec()) -> BenchSpec:
        """``base`` with this pump's sensor settings and no common clearance factor (1.0)."""
        return replace(base, clearance_factor=1.0, **self.sensors)

    def emulated_raw(self, raw: dict) -> dict:
        """Apply the pump deviations to a config mapping (``PumpConfig.to_dict()``, changed in place)."""
        c = raw["clearances"]
        c["tooth_tip_m"] *= self.tooth_tip_factor
        c["lateral_m"] *= self.lateral_factor
        c["housing_radial_m"] *= self.housing_factor
        for (section, key), attr in _replaced().items():
            if getattr(self, attr) is not None:
                raw[section][key] = getattr(self, attr)
        for port in raw["ports"].values():
            port["start_deg"] += self.port_timing_offset_deg
            port["end_deg"] += self.port_timing_offset_deg
        return raw

    def resolved(self, nominal, spec: BenchSpec) -> "BenchPump":
        """Every field filled with the value used: the nominal config's (a ``PumpConfig``) where
        this pump leaves it out, and every sensor setting of ``spec``."""
        raw = nominal.to_dict()
        filled = {attr: raw[section][key] for (section, key), attr in _replaced().items()
                  if getattr(self, attr) is None}
        sensors = {attr: getattr(spec, attr) for attr, _ in SENSOR_FIELDS.values()}
        return replace(self, **filled, sensors=sensors)

    def as_dict(self) -> dict:
        """The file's structure (``name``, ``description``, ``pump``, ``sensors``) with every key set."""
        out: dict[str, Any] = {"name": self.name, "description": self.description, "pump": {}, "sensors": {}}
        for where, table, values in (("pump", PUMP_FIELDS, vars(self)), ("sensors", SENSOR_FIELDS, self.sensors)):
            for path, (attr, _) in table.items():
                if values.get(attr) is not None:
                    section, key = path.split(".")
                    out[where].setdefault(section, {})[key] = values[attr]
        return out


def _replaced() -> dict[tuple[str, str], str]:
    """(config section, key) → attribute, for the pump fields that replace the config's value of the
    same name (``orifice``, ``mixture``, ``leakage``)."""
    return {tuple(path.split(".")): attr for path, (attr, _) in PUMP_FIELDS.items()
            if path.split(".")[0] in _REPLACED_SECTIONS}


def _value(value, field_name: str, allowed: tuple):
    """One field checked against its allowed range or choices."""
    if isinstance(allowed[0], str):
        if not isinstance(value, str) or value not in allowed:
            raise InputError(field_name, value, " | ".join(allowed))
        return value
    lo, hi, unit = allowed
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(field_name, value, f"a number in [{lo:g}, {hi:g}]{' ' + unit if unit else ''}")
    return check_range(field_name, value, lo, hi, unit=unit)


def _mapping(raw, field_name: str, keys, key_prefix: str | None = None) -> dict:
    """``raw`` as a mapping whose keys are all in ``keys`` (an unknown key is named ``key_prefix`` + key,
    by default ``field_name.key``)."""
    keys = sorted(keys)
    if not isinstance(raw, dict):
        raise InputError(field_name, raw, f"a mapping with keys {', '.join(keys)}")
    unknown = sorted(str(k) for k in raw if k not in keys)
    if unknown:
        prefix = f"{field_name}." if key_prefix is None else key_prefix
        raise InputError(f"{prefix}{unknown[0]}", raw.get(unknown[0]), f"one of the keys {', '.join(keys)}",
                         "unknown key")
    return raw


def _section(raw, where: str, table: dict) -> dict:
    """``{attribute: value}`` of a ``pump`` or ``sensors`` section checked against ``table``."""
    out = {}
    if raw is None:
        return out
    groups = {path.split(".")[0] for path in table}
    for group, sub in _mapping(raw, where, groups).items():
        keys = {path.split(".")[1] for path in table if path.startswith(group + ".")}
        for key, value in _mapping(sub, f"{where}.{group}", keys).items():
            attr, allowed = table[f"{group}.{key}"]
            out[attr] = _value(value, f"{where}.{group}.{key}", allowed)
    return out


def parse_bench_pump(raw, name: str = "bench_pump", where: str = "", source: str = "") -> BenchPump:
    """A :class:`BenchPump` from the parsed YAML document ``raw``.

    Parameters
    ----------
    raw : Any
        The document (format: module docstring).
    name : str
        Name used when the document has none.
    where : str
        Prefix of the field names in errors (the file, ``"F.yaml: "``).
    source : str
        Text of the file, kept (and recorded in the bag's metadata).
    """
    raw = _mapping(raw, f"{where}(document)", _TOP_KEYS, where)
    name, description = name_and_description(raw, name, where, _MAX_DESCRIPTION)
    pump = _section(raw.get("pump"), f"{where}pump", PUMP_FIELDS)
    sensors = _section(raw.get("sensors"), f"{where}sensors", SENSOR_FIELDS)
    return BenchPump(name=name, description=description, **pump, sensors=sensors, source=source)


def load_bench_pump(path: str | Path) -> BenchPump:
    """Read a bench pump file (format: module docstring); named after its ``name`` or stem."""
    from gerotor_twin.yaml_safe import load_yaml_file

    p = Path(path)
    raw = load_yaml_file(p, "--bench-pump")
    stem = re.sub(r"[^A-Za-z0-9_-]", "_", p.stem)[:64] or "bench_pump"
    return parse_bench_pump(raw, stem, f"{p}: ", p.read_text(encoding="utf-8"))
