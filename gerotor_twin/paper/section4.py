"""The operating point of section 4 of [1], run with the four outer-gear models.

Sec. 4 of [1]: low speed, high discharge pressure, "the delivery load was obtained by
inserting a restriction on the delivery line with the same diameter for all models".
Here the restriction (an orifice to tank, Eq. (21) of [1]) is sized once so that the
fixed-centre model delivers at ``bar`` on average, and the same area is used for every
model; the delivery line is a control volume (``boundary.delivery_volume_m3``).

References
----------
.. [1] Paper of ``../shared/paper/gerotor-micromotion-paper.md``, sec. 4, figs. 13–16.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import brentq

from ..bearing.registry import MODEL_NAMES
from ..config import PumpConfig
from ..hydraulics.orifice import ORIFICE_LAWS, port_orifice_flow
from ..model.pump import Inputs, Outputs, PumpModel
from ..model.steady import SteadyResult, run_steady
from ..units import bar_gauge_to_pa_abs, rpm_to_rad_s
from .setting import paper_setting

__all__ = ["SECTION4_RPM", "SECTION4_BAR", "restriction_area", "run_section4", "chamber_cycle"]

SECTION4_RPM = 1000.0   #: shaft speed of the figs. 13–16 runs [rpm] ("low rotational speed")
SECTION4_BAR = 27.5     #: mean delivery pressure the restriction is sized for [bar gauge]


def restriction_area(cfg: PumpConfig, rpm: float = SECTION4_RPM, bar: float = SECTION4_BAR,
                     fluid_model: str = "paper") -> float:
    """Orifice area [m²] that passes the fixed-centre pump's net delivery at ``bar`` gauge.

    The net flow to the restriction is the revolution-mean delivered flow (port flow
    minus the suction–delivery and drain leakages) of the periodic state at imposed pressure; the area follows from Eq. (21) of [1] with the
    configured Cd(λ) law (solved with :func:`scipy.optimize.brentq`).
    """
    imposed = replace(paper_setting(cfg, fluid_model), boundary=replace(cfg.boundary, mode="imposed"))
    res = run_steady(PumpModel(imposed, "fixed"), rpm, bar)
    o = res.outputs
    q = float(np.mean(o.delivery_flow))
    f, orf = cfg.fluid, cfg.orifice
    dp = bar * 1e5
    return brentq(lambda a: port_orifice_flow(dp, a, ORIFICE_LAWS[orf.law], orf.cd_max, orf.lambda_crit,
                                              orf.laminar_delta, f.density_kg_m3, f.viscosity_pa_s)[0] - q,
                  1e-10, 1e-2, xtol=1e-14)


def run_section4(cfg: PumpConfig, models=MODEL_NAMES, rpm: float = SECTION4_RPM,
                 bar: float = SECTION4_BAR, progress=None, fluid_model: str = "paper") -> dict[str, SteadyResult]:
    """Periodic state of each model on the same restricted delivery line.

    ``short`` and ``fdm`` start from the mobility model's periodic state (they would
    reach the same state from rest, only slower).

    Returns
    -------
    dict
        model name -> :class:`~gerotor_twin.model.steady.SteadyResult`; the area [m²] is
        under the key ``"restriction_area_m2"``, and ``"cycles"`` maps each model to its
        :func:`chamber_cycle` outputs.
    """
    cfg = paper_setting(cfg, fluid_model)     # the paper's eq. (23) unless asked otherwise
    area = restriction_area(cfg, rpm, bar, fluid_model)
    rcfg = replace(cfg, boundary=replace(cfg.boundary, mode="restriction", restriction_area_m2=area))
    out: dict = {"restriction_area_m2": area, "cycles": {}}
    warm = None
    order = sorted(models, key=lambda m: {"fixed": 0, "mobility": 1}.get(m, 2))
    for name in order:
        if progress is not None:
            progress(f"  sec. 4 point ({rpm:g} rpm, restriction {area * 1e6:.3f} mm²): {name} model ...")
        start = warm if name in ("short", "fdm") else None
        model = PumpModel(rcfg, name)
        res = run_steady(model, rpm, bar, state=start, max_revolutions=60)
        if name == "mobility":
            warm = res.state
        out[name] = res
        out["cycles"][name] = chamber_cycle(model, res)
    return out


def chamber_cycle(model: PumpModel, result: SteadyResult) -> Outputs:
    """Outputs over one chamber cycle after a periodic state, starting at a cycle boundary.

    A chamber turns with the outer gear (ω₂ = ω (N−1)/N), so its history repeats every
    2πN/(N−1) of shaft angle (420° for N = 7), not every revolution.  The run first
    advances to the next multiple of that period, so that θ mod period = 0 is the
    position of fig. 11 of [1] (chamber 1 on the +x axis), then records one period.
    """
    cfg = model.config
    omega = rpm_to_rad_s(result.rpm)
    inp = Inputs(omega, cfg.boundary.suction_pressure_pa, bar_gauge_to_pa_abs(result.bar, cfg.fluid.atmospheric_pa))
    period = model.tables.period
    state = result.state
    lead = (-state.theta) % period
    if lead > 1e-9:
        state, _ = model.advance(state, lead / omega, inp)
    _, out = model.advance(state, period / omega, inp)
    return out
