"""Matplotlib figures of the comparison report; each function returns PNG bytes.

Units on the axes: time [s], speed [rpm], pressure [bar gauge], flow [L/min],
efficiency [%], displacement and gaps [µm], angle [deg].
"""
from __future__ import annotations

import io
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..units import P_ATM, pa_abs_to_bar_gauge, rad_s_to_rpm  # noqa: E402
from .analysis import Grid, Plateau, revolution_phase  # noqa: E402
from .data import BenchData, TwinData  # noqa: E402

__all__ = ["fig_operating", "fig_flow", "fig_efficiency_map", "fig_waveforms", "fig_trajectory",
           "fig_gaps", "choose_plateaus", "gap_profile"]

LPM = 6e4          # m³/s -> L/min
_STYLES = ("-", "--", ":", "-.")
_COLORS = ("tab:red", "tab:green", "tab:purple", "tab:brown")


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()


def _shade(ax, plateaus: list[Plateau], labels: bool = False) -> None:
    for p in plateaus:
        ax.axvspan(p.t0, p.t1, color="0.9", zorder=0)
        if labels:
            ax.text(0.5 * (p.t0 + p.t1), 1.0, str(p.index), transform=ax.get_xaxis_transform(),
                    ha="center", va="bottom", fontsize=7)


def choose_plateaus(plateaus: list[Plateau], k: int = 3) -> list[Plateau]:
    """Up to ``k`` representative plateaus: lowest load, highest pressure at low and at high speed."""
    if not plateaus:
        return []
    lo = min(plateaus, key=lambda p: (round(p.bar), p.rpm))
    top = max(round(p.bar) for p in plateaus)
    hi = [p for p in plateaus if round(p.bar) == top]
    picks = [lo, min(hi, key=lambda p: p.rpm), max(hi, key=lambda p: p.rpm)]
    out = []
    for p in picks:
        if all(p.index != q.index for q in out):
            out.append(p)
    return out[:k]


def fig_operating(bench: BenchData, grid: Grid, plateaus: list[Plateau]) -> bytes:
    """Shaft speed, delivery pressure (and oil temperature if recorded) over time, plateaus shaded and numbered."""
    rows = 3 if bench.temperature is not None else 2
    fig, axes = plt.subplots(rows, 1, figsize=(10, 2.3 * rows), sharex=True)
    a1, a2 = axes[0], axes[1]
    t, w = bench.speed
    a1.plot(t, rad_s_to_rpm(w), lw=0.6, color="tab:blue", label="bench (raw)")
    a1.plot(grid.t, rad_s_to_rpm(grid.omega), lw=1.2, color="k", label=f"{grid.t[1] - grid.t[0]:g} s mean")
    a1.set_ylabel("speed [rpm]")
    a1.legend(loc="lower right", fontsize=8)
    t, p = bench.delivery_pressure
    a2.plot(t, pa_abs_to_bar_gauge(p, P_ATM), lw=0.4, color="tab:orange", label="bench (raw)")
    a2.plot(grid.t, pa_abs_to_bar_gauge(grid.p_delivery, P_ATM), lw=1.2, color="k", label="grid mean")
    a2.set_ylabel("delivery p [bar g]")
    if rows == 3:
        _temperature_axis(axes[2], bench, plateaus)
    axes[-1].set_xlabel("time [s]")
    _shade(a1, plateaus, labels=True)
    _shade(a2, plateaus)
    fig.tight_layout()
    return _png(fig)


def _temperature_axis(ax, bench: BenchData, plateaus: list[Plateau]) -> None:
    """Bench oil temperature [°C] (the twin runs at it; see docs/fluid.md)."""
    t, temp = bench.temperature
    ax.plot(t, temp, lw=0.8, color="tab:red", label="bench oil temperature")
    ax.set_ylabel("oil [°C]")
    ax.legend(loc="lower right", fontsize=8)
    _shade(ax, plateaus)


def fig_flow(grid: Grid, plateaus: list[Plateau], comps: list[dict]) -> bytes:
    """Measured vs predicted mean delivery flow, and the residual (predicted − measured)."""
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(10, 5), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    a1.plot(grid.t, grid.q_meas * LPM, color="tab:blue", lw=1.2, label="measured (flow meter)")
    for i, c in enumerate(comps):
        a1.plot(grid.t, c["q_pred"] * LPM, _STYLES[i % 4], color=_COLORS[i % 4], lw=1.0,
                label=f"predicted: {c['label']}")
        a2.plot(grid.t, (c["q_pred"] - grid.q_meas) * LPM, _STYLES[i % 4], color=_COLORS[i % 4], lw=0.8)
    a1.set_ylabel("mean delivery flow [L/min]")
    a1.legend(fontsize=8)
    a2.axhline(0, color="k", lw=0.5)
    a2.set_ylabel("pred − meas [L/min]")
    a2.set_xlabel("time [s]")
    _shade(a1, plateaus, labels=True)
    _shade(a2, plateaus)
    fig.tight_layout()
    return _png(fig)


def fig_efficiency_map(comps: list[dict]) -> bytes:
    """Volumetric efficiency per plateau over (speed, pressure): measured and each prediction."""
    n = 1 + len(comps)
    fig, axes = plt.subplots(1, n, figsize=(3.8 * n, 3.6), sharey=True, squeeze=False)
    rows = comps[0]["plateaus"] if comps else []
    panels = [("measured", [r["eta_measured"] for r in rows])]
    panels += [(c["label"], [r["eta_predicted"] for r in c["plateaus"]]) for c in comps]
    vals = [v for _, vs in panels for v in vs if v is not None]
    vmin, vmax = (min(vals) * 100, max(vals) * 100) if vals else (0, 100)
    sc = None
    for ax, (title, vs) in zip(axes[0], panels):
        x = [r["rpm"] for r in rows]
        y = [r["bar"] for r in rows]
        z = [np.nan if v is None else v * 100 for v in vs]
        sc = ax.scatter(x, y, c=z, s=260, cmap="viridis", vmin=vmin, vmax=vmax, edgecolor="k")
        temps = [r.get("oil_temperature_c") for r in rows]
        for xi, yi, zi, tc in zip(x, y, z, temps):
            label = f"{zi:.1f}" if tc is None else f"{zi:.1f}\n{tc:.0f} °C"
            ax.annotate(label, (xi, yi), textcoords="offset points", xytext=(0, 11), ha="center",
                        fontsize=7)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("speed [rpm]")
        ax.margins(0.15)
    axes[0][0].set_ylabel("delivery p [bar g]")
    if sc is not None:
        fig.colorbar(sc, ax=list(axes[0]), label="volumetric efficiency [%]", shrink=0.9)
    return _png(fig)


def _nearest(t: np.ndarray, target: float, lo: float, hi: float) -> int | None:
    ok = np.flatnonzero((t >= lo) & (t <= hi))
    if ok.size == 0:
        return None
    return int(ok[np.argmin(np.abs(t[ok] - target))])


def fig_waveforms(twins: list[TwinData], chosen: list[Plateau]) -> bytes | None:
    """Predicted chamber-1 pressure vs shaft angle (one revolution) at the chosen plateaus."""
    if not chosen or not any(tw.waveforms is not None for tw in twins):
        return None
    fig, axes = plt.subplots(1, len(chosen), figsize=(3.6 * len(chosen), 3.4), sharey=True, squeeze=False)
    for ax, p in zip(axes[0], chosen):
        for i, tw in enumerate(twins):
            if tw.waveforms is None:
                continue
            t, w = tw.waveforms
            k = _nearest(t, 0.5 * (p.t0 + p.t1), p.t0, p.t1)
            if k is None:
                continue
            tab = w[k]
            ax.plot(np.degrees(tab[:, 0]), pa_abs_to_bar_gauge(tab[:, 1], P_ATM), _STYLES[i % 4], color=_COLORS[i % 4],
                    lw=1.0, label=tw.label)
        ax.set_title(f"#{p.index}: {p.rpm:.0f} rpm, {p.bar:.1f} bar", fontsize=9)
        ax.set_xlabel("shaft angle [deg]")
        ax.set_xticks(range(0, 361, 90))
    axes[0][0].set_ylabel("chamber 1 pressure [bar g]")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    return _png(fig)


def fig_trajectory(twins: list[TwinData], plateaus: list[Plateau], clearance_m: float) -> bytes | None:
    """Outer-gear centre displacement in the clearance circle, coloured by plateau."""
    if not any(tw.eccentricity is not None for tw in twins):
        return None
    fig, axes = plt.subplots(1, 2, figsize=(9.6, 4.6))
    c = clearance_m * 1e6
    ang = np.linspace(0, 2 * math.pi, 361)
    cmap = plt.get_cmap("viridis")
    pts = []
    for ax in axes:
        ax.plot(c * np.cos(ang), c * np.sin(ang), "k-", lw=1.0, label=f"clearance c = {c:.1f} µm")
        for i, tw in enumerate(twins):
            if tw.eccentricity is None:
                continue
            t, e = tw.eccentricity
            ax.plot(e[:, 0] * 1e6, e[:, 1] * 1e6, _STYLES[i % 4], color="0.6", lw=0.4)
            for p in plateaus:
                s = (t >= p.t0) & (t <= p.t1)
                ax.plot(e[s, 0] * 1e6, e[s, 1] * 1e6, ".", ms=2 if i == 0 else 1,
                        color=cmap((p.index - 1) / max(1, len(plateaus) - 1)))
            ax.plot([], [], _STYLES[i % 4], color="0.6", label=tw.label)
            if np.any(e != 0):          # a fixed-centre twin would only pin the zoom to the origin
                pts.append(e * 1e6)
        ax.set_aspect("equal")
        ax.set_xlabel("e_x [µm]")
        ax.set_ylabel("e_y [µm]")
    axes[0].legend(fontsize=7, loc="upper right")
    axes[0].set_title("in the clearance circle (dots: plateaus, dark→light)", fontsize=9)
    allp = np.concatenate(pts) if pts else np.zeros((1, 2))
    lo, hi = np.nanmin(allp, axis=0), np.nanmax(allp, axis=0)
    mid, half = 0.5 * (lo + hi), 0.6 * max(float(np.max(hi - lo)), 0.02 * c)
    axes[1].set_xlim(mid[0] - half, mid[0] + half)
    axes[1].set_ylim(mid[1] - half, mid[1] + half)
    axes[1].set_title("zoom on the trajectory", fontsize=9)
    fig.tight_layout()
    return _png(fig)


def gap_profile(tw: TwinData, p: Plateau, config, angles: np.ndarray) -> np.ndarray | None:
    """Tooth-tip gap heights (len(angles), N) [m] over one revolution at a plateau.

    The twin logs the eccentricity at its publish rate; each sample's angle within the
    revolution comes from the revolution stamps (:func:`revolution_phase`).  The samples of
    the plateau are folded onto one revolution and averaged in 10° bins, and the gaps are
    computed from the pump geometry (:meth:`PumpModel.gaps`: the same overlap check as the
    model) at that angle and displacement.
    """
    from gerotor_twin.model.pump import PumpModel

    if tw.eccentricity is None:
        return None
    t, e = tw.eccentricity
    s = (t >= p.t0) & (t <= p.t1)
    disp = config.gears.displacement_closed_form()
    ph = revolution_phase(tw, disp, t[s])
    ok = np.isfinite(ph)
    if ok.sum() < 3:
        return None
    edges = np.linspace(0, 2 * math.pi, 37)
    centres = 0.5 * (edges[:-1] + edges[1:])
    idx = np.clip(np.searchsorted(edges, ph[ok], side="right") - 1, 0, 35)
    ex = np.zeros(2)
    fold = np.zeros((36, 2))
    for j in range(2):
        ssum = np.bincount(idx, weights=e[s][ok, j], minlength=36)
        cnt = np.bincount(idx, minlength=36)
        good = cnt > 0
        fold[good, j] = ssum[good] / cnt[good]
        fold[~good, j] = np.interp(centres[~good], centres[good], fold[good, j], period=2 * math.pi)
    pump = PumpModel(config, "fixed")
    out = np.empty((angles.size, pump.N))
    for i, a in enumerate(angles):
        ex[0] = np.interp(a, centres, fold[:, 0], period=2 * math.pi)
        ex[1] = np.interp(a, centres, fold[:, 1], period=2 * math.pi)
        out[i] = pump.gaps(float(a), ex)[0]
    return out


def fig_gaps(twins: list[TwinData], chosen: list[Plateau], config) -> bytes | None:
    """Tooth-tip gap height vs shaft angle at the chosen plateaus (gap 1 bold, others thin)."""
    if not chosen or not any(tw.eccentricity is not None for tw in twins):
        return None
    angles = np.radians(np.arange(0, 360, 1.0))
    fig, axes = plt.subplots(1, len(chosen), figsize=(3.6 * len(chosen), 3.4), sharey=True, squeeze=False)
    drawn = False
    for ax, p in zip(axes[0], chosen):
        for i, tw in enumerate(twins):
            h = gap_profile(tw, p, config, angles)
            if h is None:
                continue
            drawn = True
            deg = np.degrees(angles)
            if i == 0:
                ax.plot(deg, h[:, 1:] * 1e6, color="0.75", lw=0.5)
            ax.plot(deg, h[:, 0] * 1e6, _STYLES[i % 4], color=_COLORS[i % 4], lw=1.2, label=f"gap 1, {tw.label}")
        ax.set_title(f"#{p.index}: {p.rpm:.0f} rpm, {p.bar:.1f} bar", fontsize=9)
        ax.set_xlabel("shaft angle [deg]")
        ax.set_xticks(range(0, 361, 90))
    if not drawn:
        plt.close(fig)
        return None
    axes[0][0].set_ylabel("tooth-tip gap height [µm]")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    return _png(fig)
