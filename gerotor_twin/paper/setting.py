"""The pump as the paper's commands run it.

The clearances of ``config/pump.yaml`` were fitted to tables 3–5 of [1] with eq. (23) of [1],
kidneys ending at radial rays and the flow-number orifice law (docs/paper.md,
docs/calibration.json).  The twin's default pump is the oil–air–vapour mixture, a suction kidney
cut to the chamber outline (:mod:`gerotor_twin.geometry.ports`) and Merritt's orifice law
(:mod:`gerotor_twin.hydraulics.orifice`), so every section-4 command goes through
:func:`paper_setting` to reproduce what was calibrated; ``--fluid-model`` still chooses the oil.

References
----------
[1] The paper, ``../shared/paper/gerotor-micromotion-paper.md``.
"""
from __future__ import annotations

from dataclasses import replace

from ..config import PumpConfig

__all__ = ["paper_setting"]


def paper_setting(cfg: PumpConfig, fluid_model: str | None = "paper", suction_edge: str = "ray",
                  orifice_law: str = "flow_number") -> PumpConfig:
    """``cfg`` with the paper's state equation (eq. (23) of [1]; ``None`` keeps the config's), the
    suction kidney's closing edge ``suction_edge`` (``"ray"`` as calibrated, or ``"chamber"``), the
    delivery kidney closing at its ray and the orifice law ``orifice_law`` (``"flow_number"`` as
    calibrated, or ``"merritt"``)."""
    c = cfg if fluid_model is None else cfg.with_fluid_model(fluid_model)
    return replace(c, suction_port=replace(c.suction_port, closing_edge=suction_edge),
                   delivery_port=replace(c.delivery_port, closing_edge="ray"),
                   orifice=replace(c.orifice, law=orifice_law))
