"""Counterparts of figs. 12–16 of [1] (matplotlib, PNG).

========  ================================================================  ===========
figure    content                                                           run
========  ================================================================  ===========
fig12     tooth-1 gap height vs angle, mobility model, 2 speeds × 3 bar     imposed p
fig13     outer-gear centre trajectories, four models                       sec. 4 point
fig14     chamber-1 pressure vs shaft angle, four models                    sec. 4 point
fig15     delivery pressure vs shaft angle, four models                     sec. 4 point
fig16     tooth-1 gap height (a) and equivalent length (b) vs angle         sec. 4 point
========  ================================================================  ===========

"Chamber 1" / "tooth 1" are chamber 0 / lobe 0 of this package (the chamber that starts
on the +x axis at θ = 0, fig. 11 of [1]).  Curves against the inner-gear angle span one
chamber cycle, 2πN/(N−1) (420° for N = 7): a chamber turns with the outer gear.

References
----------
.. [1] Paper of ``../shared/paper/gerotor-micromotion-paper.md``, figs. 11–16.
"""
from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..bearing.registry import MODEL_NAMES  # noqa: E402
from ..config import PumpConfig  # noqa: E402
from ..model.pump import PumpModel  # noqa: E402
from ..model.steady import run_steady  # noqa: E402
from .section4 import chamber_cycle, run_section4  # noqa: E402
from .setting import paper_setting  # noqa: E402

__all__ = ["write_figures", "equivalent_length"]

STYLE = {"fixed": ("k", "-"), "mobility": ("C0", "-"), "short": ("C1", "--"), "fdm": ("C2", ":")}


def equivalent_length(model: PumpModel, theta, gap, k: int = 0):
    """Equivalent length of tooth-tip gap k [m] (sec. 3.1 of [1]).

    .. math:: l_e = 2\\sqrt{2 h\\, d_h / \\kappa_{rel}}

    the length over which the film is thinner than h* = h(1 + d_h) for two cylinders of
    relative curvature κ_rel (same rule as the model kernel).
    """
    krel = model.tables.column("KREL", np.asarray(theta), k)
    return 2.0 * np.sqrt(2.0 * np.asarray(gap) * model.config.tip_dh / krel)


def _sorted(theta, *ys, period=2 * math.pi):
    a = np.degrees(np.mod(theta, period))
    i = np.argsort(a)
    return (a[i],) + tuple(np.asarray(y)[i] for y in ys)


def _models(runs):
    return [k for k in runs["cycles"]]


def fig12(cfg: PumpConfig, path, speeds=(1000.0, 3000.0), pressures=(5.0, 15.0, 27.5)) -> Path:
    """Tooth-1 gap height vs angle, mobility model, at several speeds and pressures (eq. (23) oil)."""
    model = PumpModel(paper_setting(cfg), "mobility")
    period = model.tables.period
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for ls, rpm in zip(("-", "--", ":"), speeds):
        for col, bar in zip(("C0", "C1", "C3"), pressures):
            o = chamber_cycle(model, run_steady(model, rpm, bar))
            a, h = _sorted(o.theta, o.gaps[:, 0], period=period)
            ax.plot(a, h * 1e6, color=col, ls=ls, lw=1.2, label=f"{rpm:g} rpm, {bar:g} bar")
    ax.set(xlabel="inner-gear angle [deg]", ylabel="tooth-1 gap height [µm]", xlim=(0, math.degrees(period)),
           title="Fig. 12: tooth gap, mobility model, vs pressure and speed")
    ax.legend(fontsize=8, ncol=2)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def fig13(runs, cfg, path) -> Path:
    """Outer-gear centre trajectories in the housing clearance, four models."""
    c = cfg.clearances.housing_radial_m * 1e6
    fig, axs = plt.subplots(1, 2, figsize=(10, 4.6))
    t = np.linspace(0, 2 * math.pi, 200)
    axs[0].plot(c * np.cos(t), c * np.sin(t), color="0.6", lw=1, label="housing clearance c")
    for name in _models(runs):
        e = runs["cycles"][name].eccentricity * 1e6
        col, ls = STYLE.get(name, ("C4", "-"))
        for ax in axs:
            ax.plot(e[:, 0], e[:, 1], color=col, ls=ls, lw=1.4, label=name)
    axs[0].set(aspect="equal", xlabel="x [µm]", ylabel="y [µm]", title="in the clearance circle")
    axs[1].set(xlabel="x [µm]", ylabel="y [µm]", title="zoom")
    axs[1].set_aspect("equal", adjustable="datalim")
    for ax in axs:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Fig. 13: outer-gear centre trajectory (x toward O2, delivery at y > 0)")
    return _save(fig, path)


def _vs_angle(runs, period, title, ylabel, value, scale=1.0):
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for name in _models(runs):
        o = runs["cycles"][name]
        a, v = _sorted(o.theta, value(o), period=period)
        col, ls = STYLE.get(name, ("C4", "-"))
        ax.plot(a, v * scale, color=col, ls=ls, lw=1.3, label=name)
    ax.set(xlabel="inner-gear angle [deg]", ylabel=ylabel, xlim=(0, math.degrees(period)), title=title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return fig, ax


def fig14(runs, period, p_atm, path) -> Path:
    fig, _ = _vs_angle(runs, period, "Fig. 14: pressure in chamber 1", "pressure [bar gauge]",
                       lambda o: o.chamber_pressures[:, 0] - p_atm, 1e-5)
    return _save(fig, path)


def fig15(runs, period, p_atm, path) -> Path:
    fig, _ = _vs_angle(runs, period, "Fig. 15: delivery pressure (restricted line)", "pressure [bar gauge]",
                       lambda o: o.delivery_pressure - p_atm, 1e-5)
    return _save(fig, path)


def fig16(runs, model_for_tables: PumpModel, path) -> Path:
    period = model_for_tables.tables.period
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.2))
    for name in _models(runs):
        o = runs["cycles"][name]
        a, h, th = _sorted(o.theta, o.gaps[:, 0], o.theta, period=period)
        le = equivalent_length(model_for_tables, th, h)
        col, ls = STYLE.get(name, ("C4", "-"))
        axs[0].plot(a, h * 1e6, color=col, ls=ls, lw=1.3, label=name)
        axs[1].plot(a, le * 1e3, color=col, ls=ls, lw=1.3, label=name)
    axs[0].set(xlabel="inner-gear angle [deg]", ylabel="gap height [µm]", title="a: tooth-1 gap height")
    axs[1].set(xlabel="inner-gear angle [deg]", ylabel="equivalent length [mm]",
               title="b: tooth-1 gap equivalent length")
    for ax in axs:
        ax.set_xlim(0, math.degrees(period))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Fig. 16")
    return _save(fig, path)


def _save(fig, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_figures(cfg: PumpConfig, out_dir, models=MODEL_NAMES, progress=print):
    """Write figs. 12–16 as PNG files into ``out_dir``; returns their paths."""
    out = Path(out_dir)
    runs = run_section4(cfg, models, progress=progress)
    progress(f"  restriction area {runs['restriction_area_m2'] * 1e6:.4f} mm²; fig. 12 sweep ...")
    tables_model = PumpModel(paper_setting(cfg), "fixed")
    period, p_atm = tables_model.tables.period, cfg.fluid.atmospheric_pa
    return [fig12(cfg, out / "fig12_gap_vs_pressure_speed.png"),
            fig13(runs, cfg, out / "fig13_trajectories.png"),
            fig14(runs, period, p_atm, out / "fig14_chamber1_pressure.png"),
            fig15(runs, period, p_atm, out / "fig15_delivery_pressure.png"),
            fig16(runs, tables_model, out / "fig16_gap_height_length.png")]
