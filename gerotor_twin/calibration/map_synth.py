"""A steady map made with the twin at chosen parameters (a synthetic truth for recovery tests and examples).

The map is what a pump's maker publishes (speed, delivery pressure, oil temperature, flow),
computed by the twin's periodic steady state (:func:`.fit_model.plateau_flow`) for a pump
config given as a raw mapping, so any config value (clearances, the effective displacement of
``volumetric.displacement_factor``) can be set to a known value first.  Written as a CSV that
:func:`.pump_map.read_map` reads.
"""
from __future__ import annotations

import math
from pathlib import Path

from ..config import parse_config
from .fit_model import PlateauTask, plateau_flow
from .plateaus import PlateauRecord

__all__ = ["synthetic_map", "write_map"]


def synthetic_map(raw_config: dict, points, *, bearing: str = "mobility", source: str = "synthetic") -> list[PlateauRecord]:
    """The twin's steady delivery flow at each operating point.

    Parameters
    ----------
    raw_config : dict
        Pump config mapping (``PumpConfig.to_dict()`` form) with the true values set.
    points : iterable of (float, float, float)
        (speed [rad/s], delivery pressure [Pa abs], oil temperature [°C]).
    bearing : str
        Outer-gear model.
    source : str
        Name recorded as each point's origin.
    """
    cfg = parse_config(raw_config, source="synthetic map")
    out = []
    for k, (omega, p_d, t_c) in enumerate(points, start=1):
        res = plateau_flow(PlateauTask(raw_config, cfg.clearances.tooth_tip_m, bearing, omega, math.nan, p_d, t_c))
        out.append(PlateauRecord(bag=source, index=k, t0_s=math.nan, t1_s=math.nan, omega=omega, p_delivery_pa=p_d,
                                 p_suction_pa=math.nan, oil_temperature_c=t_c, flow_m3s=float(res["flow_m3s"]),
                                 flow_sem_m3s=math.nan, bins=1))
    return out


def write_map(path, records: list[PlateauRecord], p_atm_pa: float, comments: str = "", digits: int = 3) -> Path:
    """Write ``records`` as a map CSV: ``speed [rpm]``, ``p_delivery [bar]`` (gauge), ``T_oil [degC]``, ``Q [l/min]``.

    ``comments`` (lines) go first, each prefixed ``# ``; flows are rounded to ``digits`` decimals [L/min].
    """
    lines = [f"# {c}".rstrip() for c in comments.splitlines()]
    lines.append("speed [rpm],p_delivery [bar],T_oil [degC],Q [l/min]")
    for r in records:
        lines.append(f"{r.rpm:.6g},{r.bar(p_atm_pa):.6g},{r.oil_temperature_c:.6g},{r.flow_m3s * 6e4:.{digits}f}")
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return p
