"""Scale a running pump model's leakage clearances in place (wear in the emulator, ``adapt`` in the twin)."""
from __future__ import annotations

from dataclasses import replace

from ..config import PumpConfig

__all__ = ["scale_clearances", "scaled_config", "take_config"]


def scaled_config(base_config: PumpConfig, tip: float = 1.0, lateral: float = 1.0, housing: float = 1.0,
                  air_fraction: float | None = None) -> PumpConfig:
    """``base_config`` with its tooth-tip, lateral and housing radial clearances × ``tip``, ``lateral``,
    ``housing`` [-] and, if given, the free-air fraction ``air_fraction`` [-] (``mixture.air_fraction``).

    Raises
    ------
    InputError
        A scaled clearance or the air fraction outside the config's allowed range.
    """
    c = base_config.clearances
    clear = replace(c, tooth_tip_m=c.tooth_tip_m * tip, lateral_m=c.lateral_m * lateral,
                    housing_radial_m=c.housing_radial_m * housing)
    cfg = replace(base_config, clearances=clear, gears=replace(base_config.gears, tip_clearance=clear.tooth_tip_m))
    if air_fraction is not None and air_fraction != base_config.air.air_fraction:
        cfg = replace(cfg, air=replace(base_config.air, air_fraction=air_fraction))
    return cfg


def take_config(model, cfg: PumpConfig) -> None:
    """Give ``model`` the clearances and mixture of ``cfg`` (from :func:`scaled_config` of its config's
    source): the kernel's parameters and state equation change, the geometry tables are kept (δ enters the
    kernel's gap height directly and only shifts the inner profile in the tables by O(δ/R) ≈ 1e-3 of their
    values).  A changed state equation needs the state converted
    (:func:`~gerotor_twin.hydraulics.state_equation.convert_log_density`)."""
    model.rebuild_kernel(cfg, replace(model.tables, tip_clearance=cfg.clearances.tooth_tip_m))


def scale_clearances(model, base_config: PumpConfig, factor: float) -> None:
    """Give ``model`` the tooth-tip and lateral clearances of ``base_config`` × ``factor`` [-].

    The state stays valid (same chambers, same geometry); only the kernel's parameters
    change (:func:`take_config`).

    Raises
    ------
    InputError
        A scaled clearance outside the config's allowed range.
    """
    take_config(model, scaled_config(base_config, factor, factor))
