"""The config's oil: the ``oil`` and ``mixture`` sections and ``fluid_model`` (YAML → validated objects).

``oil`` (optional) gives the temperature-dependent properties
(:class:`~gerotor_twin.hydraulics.oil.OilProperties`); without it the
``fluid`` section's μ, ρ, β are constants (the form of versions ≤ 0.3, the
paper's oil).  With it, ``fluid`` must not set ``density_kg_m3``,
``viscosity_pa_s`` or ``bulk_modulus_pa``: they are the oil's at the
temperature of the moment (``reference_temperature_c`` when none is measured).

.. code-block:: yaml

    fluid_model: mixture          # mixture (default) | paper (eq. (23) of the paper)
    oil:
      grade: 46                   # ISO VG 32 | 46 | 68 preset, or:
      # viscosity_points: [[40.0, 46.0], [100.0, 6.8]]   # [°C, mm²/s] from the data sheet
      density_15_kg_m3: 879.0     # optional with a grade
      expansion_15_per_k: 7.1e-4  # optional: ASTM D1250 Table 54D from the density
      bulk_modulus_pa: 1.5e9      # β_L at bulk_modulus_temperature_c, atmospheric pressure
      bulk_modulus_temperature_c: 40.0
      bulk_modulus_temp_coeff_per_k: 2.866e-3   # β_L(T) = β(1 − k (T − T_β))
      reference_temperature_c: 40.0             # used while no oil temperature is measured
    mixture:
      air_fraction: 1.0e-3        # free air at atmospheric pressure [-]
      polytropic_index: 1.0
"""
from __future__ import annotations

import math
from dataclasses import fields, replace
from typing import Any

from .errors import InputError, check_range
from .hydraulics.fluid import Fluid
from .hydraulics.mixture import AirContent
from .hydraulics.oil import ISO_VG_PRESETS, T_MAX_K, T_MIN_K, OilProperties
from .hydraulics.state_equation import FLUID_MODELS
from .units import celsius_to_kelvin, kelvin_to_celsius

__all__ = ["OIL_KEYS", "OIL_SET_FLUID_KEYS", "parse_oil", "parse_air", "parse_fluid_model", "fluid_at",
           "oil_to_dict", "DEFAULT_REFERENCE_TEMPERATURE_K"]

OIL_KEYS = {"grade", "viscosity_points", "density_15_kg_m3", "expansion_15_per_k", "bulk_modulus_pa",
            "bulk_modulus_temperature_c", "bulk_modulus_temp_coeff_per_k", "reference_temperature_c", "name"}
#: ``fluid`` keys an ``oil`` section replaces.
OIL_SET_FLUID_KEYS = ("density_kg_m3", "viscosity_pa_s", "bulk_modulus_pa")
#: Reference temperature of a config without ``oil`` (the paper's oil, ISO VG46 near 40 °C) [K].
DEFAULT_REFERENCE_TEMPERATURE_K = 313.15
_T_RANGE_C = (kelvin_to_celsius(T_MIN_K), kelvin_to_celsius(T_MAX_K))


def _finite(field: str, v: Any) -> float:
    """``v`` as a finite float (numeric strings such as YAML 1.1's "1.5e9" accepted), else InputError."""
    if isinstance(v, str):
        try:
            v = float(v)
        except ValueError:
            raise InputError(field, v, "a finite number") from None
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise InputError(field, v, "a finite number")
    return float(v)


def _number(sec: dict, key: str, default: float | None = None) -> float | None:
    v = sec.get(key, default)
    return None if v is None else _finite(f"oil.{key}", v)


def _viscosity_points(sec: dict) -> tuple[tuple[float, float], tuple[float, float]]:
    pts = sec["viscosity_points"]
    shape = "two [temperature °C, kinematic viscosity mm²/s] pairs, e.g. [[40, 46], [100, 6.8]]"
    if not (isinstance(pts, (list, tuple)) and len(pts) == 2
            and all(isinstance(p, (list, tuple)) and len(p) == 2 for p in pts)):
        raise InputError("oil.viscosity_points", pts, shape)
    out = []
    for i, (t, nu) in enumerate(pts):
        t = _finite(f"oil.viscosity_points[{i}].temperature", t)
        nu = _finite(f"oil.viscosity_points[{i}].viscosity", nu)
        check_range(f"oil.viscosity_points[{i}].temperature", t, *_T_RANGE_C, unit="°C")
        out.append((float(t), float(nu)))
    return out[0], out[1]


def parse_oil(sec: dict) -> tuple[OilProperties, float]:
    """(oil, reference temperature [K]) of a validated ``oil`` section.

    Raises
    ------
    InputError
        Naming ``oil.<key>``, the value and the allowed range (unknown keys,
        grade and points both or neither, NaN, ranges of
        :class:`~gerotor_twin.hydraulics.oil.OilProperties`).
    """
    if not isinstance(sec, dict):
        raise InputError("oil", sec, "a mapping")
    unknown = set(sec) - OIL_KEYS
    if unknown:
        k = sorted(unknown)[0]
        raise InputError(f"oil.{k}", sec[k], f"one of the keys {sorted(OIL_KEYS)}", "unknown key")
    if ("grade" in sec) == ("viscosity_points" in sec):
        raise InputError("oil.grade", sec.get("grade"), "exactly one of 'grade' (32 | 46 | 68) or "
                         "'viscosity_points'", "the oil's viscosity needs a grade or two data-sheet points")
    kw: dict[str, Any] = {}
    if "name" in sec:
        kw["name"] = str(sec["name"])
    for key in ("density_15_kg_m3", "expansion_15_per_k", "bulk_modulus_temp_coeff_per_k"):
        if key in sec:
            kw[key] = _number(sec, key)
    if "bulk_modulus_pa" in sec:
        kw["bulk_modulus_ref_pa"] = _number(sec, "bulk_modulus_pa")
    if "bulk_modulus_temperature_c" in sec:
        t = check_range("oil.bulk_modulus_temperature_c", _number(sec, "bulk_modulus_temperature_c"),
                        *_T_RANGE_C, unit="°C")
        kw["bulk_modulus_temperature_k"] = celsius_to_kelvin(t)
    try:
        oil = _oil(sec, kw)
    except InputError as exc:          # name the YAML key, not the OilProperties field
        raise _yaml_error(exc) from None
    t_ref = check_range("oil.reference_temperature_c",
                        _number(sec, "reference_temperature_c", kelvin_to_celsius(DEFAULT_REFERENCE_TEMPERATURE_K)),
                        *_T_RANGE_C, unit="°C")
    return oil, celsius_to_kelvin(t_ref)


def _oil(sec: dict, kw: dict) -> OilProperties:
    if "grade" in sec:
        g = sec["grade"]
        if isinstance(g, bool) or g not in ISO_VG_PRESETS:
            raise InputError("oil.grade", g, " | ".join(str(k) for k in ISO_VG_PRESETS))
        return OilProperties.iso_vg(int(g), **kw)
    (ta, nua), (tb, nub) = _viscosity_points(sec)
    kw.setdefault("name", "oil of config")
    return OilProperties.from_viscosity_points(nua, ta, nub, tb, **kw)


#: OilProperties field → (YAML key, factor from SI to the YAML unit, YAML unit)
_YAML_KEYS = {"oil.bulk_modulus_ref_pa": ("oil.bulk_modulus_pa", 1.0, "Pa"),
              "oil.kinematic_viscosity_a_m2_s": ("oil.viscosity_points[0].viscosity", 1e6, "mm²/s"),
              "oil.kinematic_viscosity_b_m2_s": ("oil.viscosity_points[1].viscosity", 1e6, "mm²/s"),
              "oil.viscosity_temperature_b_k": ("oil.viscosity_points[1].temperature", 1.0, "K")}


def _yaml_error(exc: InputError) -> InputError:
    """``exc`` with the YAML key of the field and its value in the YAML unit."""
    if exc.field not in _YAML_KEYS:
        return exc
    key, f, unit = _YAML_KEYS[exc.field]
    value = exc.value * f if isinstance(exc.value, (int, float)) else exc.value
    allowed = exc.allowed if f == 1.0 else f"{exc.allowed} (in m²/s; the key is in {unit})"
    return InputError(key, value, allowed, exc.reason)


def parse_air(sec: dict) -> AirContent:
    """:class:`~gerotor_twin.hydraulics.mixture.AirContent` of a ``mixture`` section (may be empty)."""
    keys = {f.name for f in fields(AirContent)}
    unknown = set(sec) - keys
    if unknown:
        k = sorted(unknown)[0]
        raise InputError(f"mixture.{k}", sec[k], f"one of the keys {sorted(keys)}", "unknown key")
    return AirContent(**{k: _finite(f"mixture.{k}", v) for k, v in sec.items()})


def parse_fluid_model(value: Any) -> str:
    """``fluid_model`` checked: ``mixture`` or ``paper``."""
    if value not in FLUID_MODELS:
        raise InputError("fluid_model", value, " | ".join(FLUID_MODELS),
                         "mixture: oil + free air + vapour; paper: eq. (23) of the paper")
    return str(value)


def fluid_with_oil(fluid_sec: dict, fluid_kwargs: dict, oil: OilProperties | None, t_ref_k: float) -> Fluid:
    """The config's :class:`Fluid` at the reference temperature: the oil's μ, ρ, β if an oil is given."""
    if oil is None:
        return Fluid(**fluid_kwargs)
    for key in OIL_SET_FLUID_KEYS:
        if key in fluid_sec:
            raise InputError(f"fluid.{key}", fluid_sec[key], "absent when an 'oil' section is given",
                             "the oil section sets density, viscosity and bulk modulus versus temperature")
    return _oil_fluid(Fluid(**fluid_kwargs), oil, t_ref_k)


def fluid_at(fluid: Fluid, oil: OilProperties | None, t_ref_k: float, t_k: float) -> Fluid:
    r"""``fluid`` (the properties at T_ref) carried to oil temperature T [K] by the oil's laws.

    .. math::
        \mu(T) = \mu_{ref}\,\frac{\mu_{oil}(T)}{\mu_{oil}(T_{ref})},\quad
        \rho(T) = \rho_{ref}\,\frac{\rho_{oil}(T)}{\rho_{oil}(T_{ref})},\quad
        \beta_L(T) = \beta_{ref}\,\frac{\beta_{oil}(T)}{\beta_{oil}(T_{ref})}

    From a config, ``fluid`` holds the oil's own values at T_ref, so this is the
    oil at T; the ratio form keeps a ``fluid`` changed in code (e.g. a
    calibration or a test replacing μ) consistent at every temperature.
    Without an oil (or at T_ref) it returns ``fluid`` itself.
    """
    if oil is None or t_k == t_ref_k:
        return fluid
    return replace(fluid,
                   density_kg_m3=fluid.density_kg_m3 * oil.density(t_k) / oil.density(t_ref_k),
                   viscosity_pa_s=fluid.viscosity_pa_s * oil.viscosity(t_k) / oil.viscosity(t_ref_k),
                   bulk_modulus_pa=fluid.bulk_modulus_pa * oil.bulk_modulus(t_k) / oil.bulk_modulus(t_ref_k))


def _oil_fluid(fluid: Fluid, oil: OilProperties, t_k: float) -> Fluid:
    """``fluid`` with the oil's own ρ, μ, β_L at T [K]."""
    return replace(fluid, density_kg_m3=oil.density(t_k), viscosity_pa_s=oil.viscosity(t_k),
                   bulk_modulus_pa=oil.bulk_modulus(t_k))


def oil_to_dict(oil: OilProperties, t_ref_k: float) -> dict:
    """An ``oil`` section that parses back to ``oil`` (two viscosity points, every field explicit)."""
    return {"name": oil.name,
            "viscosity_points": [[kelvin_to_celsius(oil.viscosity_temperature_a_k),
                                  oil.kinematic_viscosity_a_m2_s * 1e6],
                                 [kelvin_to_celsius(oil.viscosity_temperature_b_k),
                                  oil.kinematic_viscosity_b_m2_s * 1e6]],
            "density_15_kg_m3": oil.density_15_kg_m3, "expansion_15_per_k": oil.expansion_15_per_k,
            "bulk_modulus_pa": oil.bulk_modulus_ref_pa,
            "bulk_modulus_temperature_c": kelvin_to_celsius(oil.bulk_modulus_temperature_k),
            "bulk_modulus_temp_coeff_per_k": oil.bulk_modulus_temp_coeff_per_k,
            "reference_temperature_c": kelvin_to_celsius(t_ref_k)}
