"""Figures of the pump model (matplotlib, Agg backend; files only)."""
from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..geometry.chambers import chamber_polygon, contact_points  # noqa: E402
from ..geometry.gerotor import GerotorGeometry  # noqa: E402
from ..geometry.ports import closing_cut  # noqa: E402
from ..units import m3s_to_lpm, pa_abs_to_bar_gauge  # noqa: E402

__all__ = ["plot_geometry", "plot_steady", "plot_efficiency_map"]


def _save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_geometry(g: GerotorGeometry, path, theta: float = 0.35, ports=None):
    """Gears, chambers (numbered) and ports at shaft angle θ [rad]."""
    fig, ax = plt.subplots(figsize=(6.4, 6.4))
    N = g.chambers
    u = np.linspace(0, 2 * math.pi, 3000)
    x, y = g.inner_profile(u)
    c, s = math.cos(theta), math.sin(theta)
    O2 = g.outer_centre
    ax.add_patch(plt.Circle(O2, g.outer_radius, color="#d9c29d", label=f"outer gear ({N} lobes)"))
    ax.add_patch(plt.Circle(O2, g.outer_root_radius, color="white"))
    ax.fill(c * x - s * y, s * x + c * y, color="#9db4d6", label=f"inner gear ({N - 1} teeth)", zorder=3)
    ax.add_patch(plt.Circle((0, 0), g.inner_hole_radius, color="white", zorder=4))
    for k, C in enumerate(g.lobe_centres(theta)):
        ax.add_patch(plt.Circle(C, g.lobe_radius, color="#d9c29d"))
    cmap = plt.get_cmap("tab10")
    for j in range(N):
        poly = chamber_polygon(g, theta, j)
        ax.fill(poly[:, 0], poly[:, 1], color=cmap(j % 10), alpha=0.45, zorder=5)
        m = poly.mean(axis=0)
        ax.text(m[0], m[1], str(j + 1), ha="center", va="center", fontsize=9, zorder=6)
    X, _ = contact_points(g, theta)
    ax.plot(X[:, 0], X[:, 1], "k.", ms=4, label="sealing points", zorder=7)
    if ports:
        rr = g.outer_root_radius + g.eccentricity + 2e-3
        for port, col in zip(ports, ("tab:blue", "tab:red")):
            a = np.linspace(port.start, port.end, 100)
            ax.plot(rr * np.cos(a), rr * np.sin(a), color=col, lw=3, label=f"{port.name} port")
            far, cut = closing_cut(g, port)
            if cut is not None:                 # the closing edge cut to the dead-centre chamber
                ax.fill(cut[:, 0], cut[:, 1], facecolor="none", edgecolor=col, hatch="///", lw=1, zorder=6,
                        label=f"{port.name} kidney stops at this chamber outline")
    ax.plot(*g.pitch_point, "k+", ms=10, label="pitch point", zorder=7)
    lim = g.outer_radius * 1.15
    ax.set_xlim(-lim + g.eccentricity, lim + g.eccentricity)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"Gerotor {N}/{N - 1}, θ = {math.degrees(theta):.0f}°")
    ax.legend(loc="upper right", fontsize=7)
    return _save(fig, path)


def plot_steady(result, path):
    """Chamber-1 pressure vs shaft angle (fig. 14 of [1]) with its peak between output angles, delivery flow
    and tooth-tip gaps vs angle."""
    o = result.outputs
    ang = np.degrees(o.theta - o.theta[0] + (o.theta[1] - o.theta[0]))
    fig, (a1, a2, a3) = plt.subplots(3, 1, figsize=(7.5, 8.5), sharex=True)
    p_atm = result.p_atm
    a1.plot(ang, pa_abs_to_bar_gauge(o.chamber_pressures[:, 0], p_atm), label="chamber 1")
    a1.step(ang, pa_abs_to_bar_gauge(o.chamber_peak_pressures[:, 0], p_atm), where="pre", lw=0.6, alpha=0.8,
            label="chamber 1, peak within each output step")
    a1.plot(ang, pa_abs_to_bar_gauge(o.delivery_pressure, p_atm), "k--", lw=0.8, label="delivery")
    a1.set_ylabel("gauge pressure [bar]")
    a1.legend(fontsize=8)
    a1.set_title(f"{result.model}: {result.rpm:g} rpm, {result.bar:g} bar, "
                 f"η_v = {100 * result.volumetric_efficiency:.2f} %")
    a2.plot(ang, m3s_to_lpm(o.delivery_flow), label="delivery flow")
    a2.axhline(m3s_to_lpm(result.theoretical_flow_m3s), color="k", ls=":", label="theoretical")
    a2.set_ylabel("flow [L/min]")
    a2.legend(fontsize=8)
    a3.plot(ang, o.gaps[:, 0] * 1e6, label="tooth 1 gap")
    a3.plot(ang, o.gaps.min(axis=1) * 1e6, lw=0.6, label="min gap")
    a3.set_ylabel("gap [µm]")
    a3.set_xlabel("shaft angle over the revolution [deg]")
    a3.legend(fontsize=8)
    return _save(fig, path)


def plot_efficiency_map(points, path, paper=None):
    """Volumetric efficiency vs delivery pressure, one line per speed (tables 3–5 of [1])."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    by_speed = {}
    for p in points:
        by_speed.setdefault((p["model"], p["rpm"]), []).append(p)
    for (model, rpm), pts in sorted(by_speed.items()):
        pts.sort(key=lambda q: q["bar"])
        ax.plot([q["bar"] for q in pts], [100 * q["volumetric_efficiency"] for q in pts], "o-",
                label=f"{model} {rpm:g} rpm")
    if paper:
        for (model, rpm), vals in paper.items():
            ax.plot([v[0] for v in vals], [100 * v[1] for v in vals], "x:", color="gray")
    ax.set_xlabel("delivery pressure [bar gauge]")
    ax.set_ylabel("volumetric efficiency [%]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, path)
