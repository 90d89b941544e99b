"""What a calibration can fit, and the model evaluated at one plateau (in a worker process).

Parameters are fitted as log-factors ``x = ln(value / prior)`` so that clearances of
tens of µm and a discharge coefficient near 0.7 share one scale; ``x = 0`` is the prior
(the pump config given).  A parameter whose prior may be 0 (the bypass area) is fitted as
``x = (value − prior) / step`` instead, ``step`` its typical size (:attr:`FitParameter.step`).

Fittable parameters (``--params``):

=========  ============================  ===========================================
name       config field                  what it scales
=========  ============================  ===========================================
tip        clearances.tooth_tip_m        tooth-tip leakage (≈ δ³ Poiseuille + Couette)
lateral    clearances.lateral_m          lateral, suction–delivery and drain leakage (≈ s³)
lateral_   clearances.lateral_opening_   the lateral gap opening with the pressure load,
opening    m_per_pa                      s₀ + c·Δp: leakage ∝ Δp(1 + cΔp/s₀)³ (fitted
                                         linearly, step 1e-11 m/Pa = 1 µm/bar)
cd         orifice.cd_max                port orifices (filling at high speed)
tip_dh     leakage.tip_dh                equivalent length of the tooth-tip gap
air        mixture.air_fraction          free air at atmospheric pressure: the chambers'
                                         compression and the filling at low pressure
displace-  volumetric.displacement_      effective displacement k_D: a flow deficit
ment       factor                        (1 − k_D)·D·n at every pressure and speed
bypass     volumetric.bypass_area_m2     a turbulent delivery → suction path, ∝ √Δp
                                         (fitted linearly, step 1 mm²)
filling    volumetric.filling_loss_      chambers filling short at speed: a deficit
           at_1000rpm                    k_f·(n/1000 rpm)²·(p_atm/p_s)·D·n (fitted
                                         linearly, step 0.001)
filling_   volumetric.filling_margin_pa  the inlet's pressure drop the chambers absorb
margin                                   before they fill short: full chambers up to an
                                         onset speed (fitted linearly, step 100 Pa;
                                         acts through ``filling``)
=========  ============================  ===========================================

A parameter that acts only through another (``gate``: the filling margin through the filling loss) has no
effect while that one is at zero; where the gate's prior is zero the identifiability analysis looks at the
Jacobian with the gate one step in (:func:`.fit.analysis_point`).

Each starts at its prior, the value of the pump config given (``displacement``: 1, the ideal
profiles, ``lateral_opening`` and ``filling``: 0, rigid plates and full chambers, unless the config says otherwise), and is fitted only when the identifiability
analysis finds the data determine it (:mod:`.identifiability`); otherwise it stays there.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace

import numpy as np

from ..config import PumpConfig, parse_config
from ..errors import InputError
from ..geometry.tables import cached_tables
from ..units import celsius_to_kelvin, pa_abs_to_bar_gauge, rad_s_to_rpm

__all__ = ["FitParameter", "PARAMETERS", "DISPLAY_UNITS", "display_value", "parse_params", "apply", "PlateauTask", "plateau_flow", "without_edge_losses",
           "with_edge_losses"]


@dataclass(frozen=True)
class FitParameter:
    """One fittable config value: where it lives and its physical bounds."""
    name: str
    section: str
    key: str
    lower: float                 #: lowest value allowed [unit of the field]
    upper: float                 #: highest value allowed
    unit: str
    description: str
    step: float = 0.0            #: 0: fitted as ln(value / prior); > 0: as (value − prior) / step [unit]
    gate: str = ""               #: the parameter it acts through ("": none): no effect while that one is 0

    def value(self, prior: float, x: float) -> float:
        """The value at fitted coordinate ``x`` (unclipped) [unit]."""
        return prior + self.step * x if self.step > 0 else prior * math.exp(x)

    def x_bounds(self, prior: float, limit: float = 1.5) -> tuple[float, float]:
        """The coordinates of the physical bounds, within ±``limit`` for a log-factor [-]."""
        if self.step > 0:
            return (self.lower - prior) / self.step, (self.upper - prior) / self.step
        return max(-limit, math.log(self.lower / prior)), min(limit, math.log(self.upper / prior))


PARAMETERS = {p.name: p for p in (
    FitParameter("tip", "clearances", "tooth_tip_m", 1e-6, 4.9e-4, "m", "tooth-tip clearance δ"),
    FitParameter("lateral", "clearances", "lateral_m", 1e-6, 4.9e-4, "m", "lateral clearance per face"),
    FitParameter("lateral_opening", "clearances", "lateral_opening_m_per_pa", 0.0, 1e-9, "m/Pa",
                 "opening of the lateral gap per unit delivery − suction pressure (plates deflecting)", step=1e-11),
    FitParameter("cd", "orifice", "cd_max", 0.1, 1.0, "-", "turbulent discharge coefficient of the ports"),
    FitParameter("tip_dh", "leakage", "tip_dh", 0.01, 10.0, "-", "dh of the tooth-tip gap's equivalent length"),
    FitParameter("air", "mixture", "air_fraction", 1e-6, 0.2, "-",
                 "free (undissolved) air at atmospheric pressure (fluid_model: mixture)"),
    FitParameter("displacement", "volumetric", "displacement_factor", 0.5, 1.1, "-",
                 "effective displacement / ideal profiles' (filling, tolerances)"),
    FitParameter("bypass", "volumetric", "bypass_area_m2", 0.0, 1e-4, "m²",
                 "effective area of a turbulent delivery → suction path", step=1e-6),
    FitParameter("filling", "volumetric", "filling_loss_at_1000rpm", 0.0, 0.2, "-",
                 "chambers' unfilled fraction at 1000 rpm and atmospheric suction (grows as speed²)", step=1e-3),
    FitParameter("filling_margin", "volumetric", "filling_margin_pa", 0.0, 1e5, "Pa",
                 "inlet pressure drop the chambers absorb before they fill short (an onset speed)", step=100.0,
                 gate="filling"),
)}


#: unit of a fitted parameter → (scale, unit) it is shown in (the command's summary, the HTML report)
DISPLAY_UNITS = {"m": (1e6, "µm"), "m²": (1e6, "mm²"), "m/Pa": (1e11, "µm/bar"), "Pa": (1e-2, "mbar")}


def display_value(v: float, unit: str) -> str:
    """``v`` [``unit``] as shown to a user: ``"34.506 µm"``, ``"0.507 µm/bar"``, ``"0.9600"`` (unitless)."""
    if unit in DISPLAY_UNITS:
        scale, shown = DISPLAY_UNITS[unit]
        return f"{v * scale:.3f} {shown}"
    return f"{v:.4f}"


def parse_params(text: str, option: str = "--params") -> tuple[str, ...]:
    """``"tip,lateral"`` → ``("tip", "lateral")``; InputError naming ``option`` and the unknown one."""
    names = tuple(s.strip() for s in str(text).split(",") if s.strip())
    if not names:
        raise InputError(option, text, "a comma-separated list of " + ", ".join(PARAMETERS))
    for n in names:
        if n not in PARAMETERS:
            raise InputError(option, n, ", ".join(PARAMETERS))
    if len(set(names)) != len(names):
        raise InputError(option, text, "each parameter once")
    return names


def prior_values(raw: dict, names) -> np.ndarray:
    """The prior value of each named parameter in a raw config mapping."""
    return np.array([float(raw.get(PARAMETERS[n].section, {}).get(PARAMETERS[n].key, 0.0)) for n in names])


def apply(raw: dict, names, x) -> dict:
    """A copy of the raw config mapping with each parameter at coordinate x (:meth:`FitParameter.value`),
    clipped to its bounds."""
    out = json.loads(json.dumps(raw))
    for n, xi in zip(names, x):
        p = PARAMETERS[n]
        v = p.value(float(raw.get(p.section, {}).get(p.key, 0.0)), float(xi))
        out.setdefault(p.section, {})[p.key] = min(max(v, p.lower), p.upper)
    return out


@dataclass(frozen=True)
class PlateauTask:
    """One model evaluation: a config, an outer-gear model and a plateau's measured inputs (SI)."""
    raw_config: dict             #: the pump config mapping (``PumpConfig.to_dict()`` form)
    table_tip_m: float           #: δ of the geometry tables to reuse (the prior's) [m]
    bearing: str
    omega: float                 #: [rad/s]
    p_suction_pa: float          #: [Pa abs]; NaN: the config's suction pressure
    p_delivery_pa: float         #: [Pa abs]
    oil_temperature_c: float     #: plateau mean oil temperature [°C] (NaN: none recorded)


#: A plateau run's settling test (:func:`plateau_flow`): the revolution mean's relative change [-], and the
#: revolutions at most
PLATEAU_RTOL = 1e-6
PLATEAU_MAX_REVOLUTIONS = 60

_TABLES: dict[str, object] = {}


def _tables(cfg: PumpConfig, table_tip_m: float):
    """Geometry tables of the prior δ, memoised per process, relabelled with ``cfg``'s δ.

    δ enters the kernel's tooth-tip gap height directly (``tip_clearance + …``); in the
    tables it only shifts the inner profile by δ (columns change by O(δ/R) ≈ 1e-3 of
    themselves), so a trial δ reuses the prior's tables instead of a 6 s rebuild.
    """
    g = replace(cfg.gears, tip_clearance=table_tip_m)
    key = repr((g, cfg.suction_port, cfg.delivery_port, cfg.numerics.table_points))
    if key not in _TABLES:
        _TABLES[key] = cached_tables(g, cfg.suction_port, cfg.delivery_port, cfg.numerics.table_points)
    return replace(_TABLES[key], tip_clearance=cfg.gears.tip_clearance)


def plateau_flow(task: PlateauTask) -> dict:
    """Periodic steady state of the model at one plateau's measured inputs.

    Returns
    -------
    dict
        ``flow_m3s`` (revolution-mean delivery [m³/s]), ``theoretical_m3s``, ``revolutions``,
        ``periodicity_error``, ``settled`` (:class:`~gerotor_twin.model.steady.SteadyResult`); and what
        :func:`with_edge_losses` needs to put another ``volumetric`` section on the same run: ``edge_free_m3s``
        (the chamber model's delivery before the edge losses [m³/s]),
        ``displacement_m3`` [m³/rev], ``density_kg_m3``, ``p_delivery_pa``, ``p_suction_pa`` (as run) [Pa abs];
        ``expansion_to_atm``, ρ(p_d)/ρ(p_atm) of the oil at the plateau's temperature [-] (:func:`at_meter`).

    Notes
    -----
    The plateau is simulated at its mean oil temperature ``task.oil_temperature_c`` (the
    config's reference temperature when the bag has none).
    """
    from ..hydraulics.meter import expansion
    from ..model.pump import PumpModel
    from ..model.steady import run_steady

    cfg = parse_config(task.raw_config, source="calibration trial")
    model = PumpModel(cfg, task.bearing, tables=_tables(cfg, task.table_tip_m))
    p_atm = cfg.fluid.atmospheric_pa
    ps = None if not math.isfinite(task.p_suction_pa) else task.p_suction_pa
    t_c = task.oil_temperature_c
    t_oil = celsius_to_kelvin(t_c) if t_c is not None and math.isfinite(t_c) else None
    res = run_steady(model, rad_s_to_rpm(task.omega), pa_abs_to_bar_gauge(task.p_delivery_pa, p_atm),
                     max_revolutions=PLATEAU_MAX_REVOLUTIONS, rtol=PLATEAU_RTOL, p_suction=ps, oil_temperature=t_oil)
    p_d = float(np.mean(res.outputs.delivery_pressure))
    eos = model.kernel.eos                                  # at the plateau's temperature (run_steady set it)
    return {"flow_m3s": res.mean_delivery_flow_m3s, "theoretical_m3s": res.theoretical_flow_m3s,
            "revolutions": res.revolutions, "periodicity_error": res.periodicity_error, "settled": res.settled,
            "edge_free_m3s": float(res.outputs.volumetric_efficiency * res.theoretical_flow_m3s),
            "displacement_m3": model.displacement, "density_kg_m3": cfg.fluid.density_kg_m3,
            "p_delivery_pa": p_d,
            "p_suction_pa": cfg.boundary.suction_pressure_pa if ps is None else ps,     # as run_steady takes them
            "expansion_to_atm": expansion(p_d, p_atm, eos)}


def without_edge_losses(raw: dict) -> dict:
    """The raw config mapping with its ``volumetric`` section at the ideal pump (k_D = 1, no bypass, full chambers): the edge
    losses are applied after the chamber model (:mod:`gerotor_twin.model.volumetric`), so every ``volumetric``
    section shares one run of it (:func:`with_edge_losses`)."""
    out = dict(raw)
    out["volumetric"] = {"displacement_factor": 1.0, "bypass_area_m2": 0.0, "filling_loss_at_1000rpm": 0.0,
                         "filling_margin_pa": 0.0}
    return out


def at_meter(run: dict, flow_m3s: float, meter: str) -> float:
    """The twin's delivery flow ``flow_m3s`` [m³/s] of :func:`plateau_flow`'s ``run`` as a meter at ``meter``
    (:data:`~gerotor_twin.hydraulics.meter.FLOW_METERS`) reads it: the same mass flow at that pressure's volume
    (:mod:`gerotor_twin.hydraulics.meter`; the twin's state equation at the plateau's oil temperature)."""
    return flow_m3s * run["expansion_to_atm"] if meter == "atmospheric" else flow_m3s


def with_edge_losses(run: dict, raw: dict, omega: float) -> float:
    """The mean delivery flow [m³/s] of :func:`plateau_flow`'s ``run`` (of any ``volumetric`` section) with the
    edge losses of the raw config mapping ``raw``'s ``volumetric`` section at speed ``omega`` [rad/s]
    (:class:`~gerotor_twin.model.volumetric.EdgeLosses`, applied as :func:`~gerotor_twin.model.steady.run_steady`
    applies them)."""
    from ..model.volumetric import EdgeLosses
    vs = raw.get("volumetric", {})
    edge = EdgeLosses(run["displacement_m3"], float(vs.get("displacement_factor", 1.0)),
                      float(vs.get("bypass_area_m2", 0.0)), run["density_kg_m3"],
                      float(vs.get("filling_loss_at_1000rpm", 0.0)), float(vs.get("filling_margin_pa", 0.0)))
    return run["edge_free_m3s"] - edge.flow(omega, run["p_delivery_pa"], run["p_suction_pa"])
