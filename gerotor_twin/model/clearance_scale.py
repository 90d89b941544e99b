"""Scale a running pump model's leakage clearances in place (wear in the emulator, ``adapt`` in the twin)."""
from __future__ import annotations

from dataclasses import replace

from ..config import PumpConfig

__all__ = ["scale_clearances"]


def scale_clearances(model, base_config: PumpConfig, factor: float) -> None:
    """Give ``model`` the tooth-tip and lateral clearances of ``base_config`` × ``factor`` [-].

    The state stays valid (same chambers, same geometry); only the kernel's parameters
    change.  The geometry tables are kept: δ enters the kernel's gap height directly and
    only shifts the inner profile in the tables by O(δ/R) ≈ 1e-3 of their values.

    Raises
    ------
    InputError
        A scaled clearance outside the config's allowed range.
    """
    c = base_config.clearances
    clear = replace(c, tooth_tip_m=c.tooth_tip_m * factor, lateral_m=c.lateral_m * factor)
    cfg = replace(base_config, clearances=clear, gears=replace(base_config.gears, tip_clearance=clear.tooth_tip_m))
    tables = replace(model.tables, tip_clearance=clear.tooth_tip_m)
    model.rebuild_kernel(cfg, tables)
