"""Matplotlib figures of the comparison report; each function returns PNG bytes.

Units on the axes: time [s], speed [rpm], pressure [bar gauge], flow [L/min],
efficiency [%], displacement and gaps [µm], angle [deg].
"""
from __future__ import annotations

import functools
import io
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..units import P_ATM, pa_abs_to_bar_gauge  # noqa: E402
from .analysis import Plateau, revolution_phase  # noqa: E402
from .data import TwinData  # noqa: E402

__all__ = ["figure_png", "fig_efficiency_map", "fig_plateau_errors", "fig_waveforms", "fig_trajectory", "fig_gaps",
           "gap_profile", "group_points", "group_plateaus", "folded_waveform", "RC", "DPI", "MAX_WIDTH_IN"]

LPM = 6e4          # m³/s -> L/min
_STYLES = ("-", "--", ":", "-.")
_COLORS = ("tab:red", "tab:green", "tab:purple", "tab:brown")
DPI = 90           #: PNG resolution [px/in]; the page shows PNGs at this size (1 pt = 1.25 px)
MAX_WIDTH_IN = 11.8  #: widest figure [in] (1062 px: fits the page's 1100 px column unscaled)
#: Style of every report figure: no text under 9 pt (11 px), layout that keeps labels inside.
RC = {"font.size": 10, "axes.titlesize": 10, "axes.labelsize": 10, "xtick.labelsize": 9, "ytick.labelsize": 9,
      "legend.fontsize": 9, "figure.titlesize": 11, "figure.constrained_layout.use": True, "figure.dpi": DPI}
NCOLS = 4          #: small multiples per row (one per plateau)


def _styled(fn):
    """Run a figure function under :data:`RC` (matplotlib's global style is left alone)."""
    @functools.wraps(fn)
    def wrapper(*args, **kw):
        with plt.rc_context(RC):
            return fn(*args, **kw)
    return wrapper


def figure_png(fig) -> bytes:
    """The figure as PNG bytes (the report's DPI, no software tag, so files are reproducible); closes it."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()


def _figure_legend(fig, axes, twins=(), visits: bool = False) -> None:
    """One legend under the figure for the labelled lines of all ``axes`` (each label once); with
    ``visits`` (panels of repeated visits, coloured by time) also one black line style per twin."""
    handles = {lab: h for ax in axes for h, lab in zip(*ax.get_legend_handles_labels())}
    if visits:
        for i, tw in enumerate(twins):
            handles.setdefault(f"{tw.label} (several visits: dark → light in time)",
                               plt.Line2D([], [], color="k", linestyle=_STYLES[i % 4]))
    if handles:
        fig.legend(handles.values(), handles.keys(), loc="outside lower center", ncols=min(3, len(handles)))


def _multiples(n: int, height_in: float = 2.5):
    """``n`` small axes in rows of :data:`NCOLS`, shared axes; unused ones hidden."""
    ncols = min(NCOLS, max(1, n))
    nrows = max(1, math.ceil(n / ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(min(MAX_WIDTH_IN, 2.9 * ncols), 0.6 + height_in * nrows),
                             sharex=True, sharey=True, squeeze=False)
    flat = list(axes.flat)
    for ax in flat[n:]:
        ax.set_visible(False)
    return fig, flat[:n], axes


@_styled
def fig_efficiency_map(comps: list[dict]) -> bytes:
    """Volumetric efficiency per operating point over (speed, pressure): measured and each prediction.

    Repeated visits of a point (:func:`group_points`) are shown as their mean, labelled ``(n×)``.
    """
    n = 1 + len(comps)
    ncols = min(n, 3)
    nrows = math.ceil(n / ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(min(MAX_WIDTH_IN, 3.5 * ncols + 1.2), 3.7 * nrows),
                             sharex=True, sharey=True, squeeze=False)
    rows = comps[0]["plateaus"] if comps else []
    groups = group_points([r["rpm"] for r in rows], [r["bar"] for r in rows])

    def means(vals):
        out = []
        for g in groups:
            v = [vals[i] for i in g if vals[i] is not None]
            out.append(float(np.mean(v)) if v else None)
        return out
    panels = [("measured", means([r["eta_measured"] for r in rows]))]
    panels += [(f"predicted: {c['label']}", means([r["eta_predicted"] for r in c["plateaus"]])) for c in comps]
    vals = [v for _, vs in panels for v in vs if v is not None]
    vmin, vmax = (min(vals) * 100, max(vals) * 100) if vals else (0, 100)
    sc = None
    flat = list(axes.flat)
    for ax in flat[n:]:
        ax.set_visible(False)
    for ax, (title, vs) in zip(flat, panels):
        x = [np.mean([rows[i]["rpm"] for i in g]) for g in groups]
        y = [np.mean([rows[i]["bar"] for i in g]) for g in groups]
        z = [np.nan if v is None else v * 100 for v in vs]
        sc = ax.scatter(x, y, c=z, s=200, cmap="viridis", vmin=vmin, vmax=vmax, edgecolor="k")
        temps = [rows[g[0]].get("oil_temperature_c") for g in groups]
        for xi, yi, zi, g, tc in zip(x, y, z, groups, temps):
            label = f"{zi:.1f}" + (f" ({len(g)}×)" if len(g) > 1 else "") + ("" if tc is None else f"\n{tc:.0f} °C")
            ax.annotate(label, (xi, yi), textcoords="offset points", xytext=(0, 9), ha="center", fontsize=9)
        ax.set_title(title)
        ax.margins(0.15, 0.2)
        ax.set_xlabel("speed [rpm]")
    for ax in axes[:, 0]:
        ax.set_ylabel("delivery p [bar g]")
    if sc is not None:
        fig.colorbar(sc, ax=flat[:n], label="volumetric efficiency [%]", shrink=0.9)
    return figure_png(fig)


@_styled
def fig_plateau_errors(plateaus: list[Plateau], comps: list[dict], verdicts: list) -> bytes | None:
    """Mean flow error and η_v error per plateau with the tolerance band; filled marker = pass."""
    if not plateaus or not comps:
        return None
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(min(MAX_WIDTH_IN, max(7.5, 4 + 0.45 * len(plateaus))), 5.4),
                                 sharex=True)
    idx = np.array([p.index for p in plateaus], float)
    v0 = verdicts[0]
    ftol = np.array([np.nan if v["flow_tol_m3s"] is None else v["flow_tol_m3s"] * LPM for v in v0])
    etol = np.array([np.nan if v["eta_tol"] is None else v["eta_tol"] * 100 for v in v0])
    for ax, tol in ((a1, ftol), (a2, etol)):
        if np.isfinite(tol).any():
            ax.bar(idx, 2 * tol, bottom=-tol, width=0.7, color=(0.16, 0.63, 0.24, 0.18), edgecolor=(0.16, 0.63, 0.24),
                   linewidth=0.8, label="tolerance")
        ax.axhline(0, color="k", lw=0.6)
    width = 0.5 / max(1, len(comps))
    for i, (c, vs) in enumerate(zip(comps, verdicts)):
        x = idx + (i - (len(comps) - 1) / 2) * width
        fe = [np.nan if r["flow_error_m3s"]["bias"] is None else r["flow_error_m3s"]["bias"] * LPM
              for r in c["plateaus"]]
        ee = [np.nan if r["eta_predicted"] is None or r["eta_measured"] is None
              else (r["eta_predicted"] - r["eta_measured"]) * 100 for r in c["plateaus"]]
        ok = np.array([v["verdict"] == "pass" for v in vs])
        color = _COLORS[i % 4]
        for ax, y in ((a1, np.array(fe)), (a2, np.array(ee))):
            ax.plot(x[ok], y[ok], "o", color=color, ms=7, label=f"{c['label']}: pass")
            ax.plot(x[~ok], y[~ok], "X", color=color, mfc="white", ms=8, mew=1.5, label=f"{c['label']}: fail / no data")
    a1.set_ylabel("mean flow error [L/min]")
    a2.set_ylabel("η$_v$ error [%-pt]")
    a2.set_xlabel("plateau")
    if len(idx) <= 30:
        a2.set_xticks(idx)
    else:
        a2.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(nbins=20, integer=True))
    fig.legend(*a1.get_legend_handles_labels(), loc="outside lower center", ncols=min(3, 1 + 2 * len(comps)))
    return figure_png(fig)


def group_points(rpm: list[float], bar: list[float], rpm_rel: float = 0.02, bar_abs: float = 0.5) -> list[list[int]]:
    """Indices of the same operating point (speed within ``rpm_rel`` [-], pressure within ``bar_abs``
    [bar] of the group's first visit), in order of first visit; each group keeps its order."""
    groups: list[list[int]] = []
    for i, (r, b) in enumerate(zip(rpm, bar)):
        for g in groups:
            if abs(r - rpm[g[0]]) <= rpm_rel * max(abs(rpm[g[0]]), 1.0) and abs(b - bar[g[0]]) <= bar_abs:
                g.append(i)
                break
        else:
            groups.append([i])
    return groups


def group_plateaus(plateaus: list[Plateau]) -> list[list[Plateau]]:
    """Plateaus grouped by operating point (:func:`group_points`)."""
    return [[plateaus[i] for i in g] for g in group_points([p.rpm for p in plateaus], [p.bar for p in plateaus])]


def _group_title(ax, group: list[Plateau], extra: str = "") -> None:
    """``#k: rpm, bar`` for one visit; the visits on a first line for several."""
    q = group[0]
    point = f"{q.rpm:.0f} rpm, {q.bar:.1f} bar"
    if len(group) == 1:
        ax.set_title(f"#{q.index}: {point}{extra}")
        return
    visits = (", ".join(f"#{p.index}" for p in group) if len(group) <= 4
              else f"#{q.index} … #{group[-1].index} ({len(group)} visits)")
    ax.set_title(f"{visits}\n{point}")


def _visit_style(i_twin: int, k: int, n: int) -> dict:
    """Line style of twin ``i_twin`` at visit ``k`` of ``n``: twin colours for one visit, else dark→light."""
    color = _COLORS[i_twin % 4] if n == 1 else plt.get_cmap("viridis")(0.85 * k / max(1, n - 1))
    return {"color": color, "linestyle": _STYLES[i_twin % 4]}


def _rise_angles(ang: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Angle [rad] of the steepest pressure rise of each chamber column of ``P`` (samples, N)."""
    return ang[(np.argmax(np.diff(P, axis=0, append=P[:1]), axis=0) + 1) % len(ang)]


def folded_waveform(tw: TwinData, p: Plateau, rise_deg: float | None = None
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, float] | None:
    """The pressure of one chamber over one revolution, folded over every logged revolution of a plateau.

    A chamber turns with the outer gear ((N−1)/N of the shaft speed), so a given chamber is in
    a different place at the start of each revolution, while the set of chamber places is the
    same (revolutions start at whole turns).  The chamber shown is, in the revolution nearest the
    plateau middle, the one whose steepest pressure rise (opening to delivery) lies nearest
    ``rise_deg`` [deg] (default: nearest 90°); in every other revolution it is the chamber in the
    same place: the shift of the N columns that best matches the reference (least squares).

    Returns
    -------
    tuple or None
        (angle [rad], mean, min, max [Pa abs], number of revolutions, rise angle [deg]), or None
        without waveforms in the plateau.
    """
    if tw.waveforms is None:
        return None
    t, w = tw.waveforms
    k = np.flatnonzero((t >= p.t0) & (t <= p.t1))
    if k.size == 0:
        return None
    ang = w[k[0]][:, 0]
    P = w[k][:, :, 1:]                                   # (revolutions, samples, N)
    ref = P[int(np.argmin(np.abs(t[k] - 0.5 * (p.t0 + p.t1))))]
    rise = np.degrees(_rise_angles(ang, ref))
    target = 90.0 if rise_deg is None else rise_deg
    j = int(np.argmin(np.abs((rise - target + 180.0) % 360.0 - 180.0)))
    cost = np.stack([((np.roll(P, -s, axis=2) - ref) ** 2).sum(axis=(1, 2)) for s in range(P.shape[2])], axis=1)
    cols = (cost.argmin(axis=1) + j) % P.shape[2]
    p1 = P[np.arange(k.size), :, cols]                   # (revolutions, samples)
    return ang, p1.mean(axis=0), p1.min(axis=0), p1.max(axis=0), int(k.size), float(rise[j])


@_styled
def fig_waveforms(twins: list[TwinData], plateaus: list[Plateau]) -> bytes | None:
    """Predicted chamber pressure vs shaft angle at every plateau: mean over its revolutions, min–max band.

    The same chamber place in every plateau (:func:`folded_waveform`): the one opening to
    delivery nearest the angle found at the first plateau with waveforms.  Repeated visits of
    one operating point share a panel (:func:`group_plateaus`), dark → light in time order.
    """
    if not plateaus or not any(tw.waveforms is not None for tw in twins):
        return None
    groups = group_plateaus(plateaus)
    fig, axes, grid = _multiples(len(groups), 2.7 if any(len(g) > 1 for g in groups) else 2.5)
    rise = None
    for ax, group in zip(axes, groups):
        counts = []
        for k, p in enumerate(group):
            for i, tw in enumerate(twins):
                f = folded_waveform(tw, p, rise)
                if f is None:
                    continue
                ang, mean, lo, hi, n, r = f
                rise = r if rise is None else rise
                st = _visit_style(i, k, len(group))
                deg = np.degrees(ang)
                ax.fill_between(deg, pa_abs_to_bar_gauge(lo, P_ATM), pa_abs_to_bar_gauge(hi, P_ATM), color=st["color"],
                                alpha=0.2, lw=0)
                ax.plot(deg, pa_abs_to_bar_gauge(mean, P_ATM), lw=1.1, label=tw.label if len(group) == 1 else None,
                        **st)
                counts.append(str(n))
        _group_title(ax, group, f", {'/'.join(counts) or 0} rev")
        ax.set_xticks(range(0, 361, 90))
    for ax in grid[-1]:
        ax.set_xlabel("shaft angle [deg]")
    for ax in grid[:, 0]:
        ax.set_ylabel("chamber p [bar g]")
    _figure_legend(fig, axes, twins, any(len(g) > 1 for g in groups))
    return figure_png(fig)


@_styled
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
    axes[0].legend(loc="upper right")
    axes[0].set_title("in the clearance circle (dots: plateaus, dark→light)")
    allp = np.concatenate(pts) if pts else np.zeros((1, 2))
    lo, hi = np.nanmin(allp, axis=0), np.nanmax(allp, axis=0)
    mid, half = 0.5 * (lo + hi), 0.6 * max(float(np.max(hi - lo)), 0.02 * c)
    axes[1].set_xlim(mid[0] - half, mid[0] + half)
    axes[1].set_ylim(mid[1] - half, mid[1] + half)
    axes[1].set_title("zoom on the trajectory")
    return figure_png(fig)


def gap_profile(tw: TwinData, p: Plateau, config, angles: np.ndarray, pump=None) -> np.ndarray | None:
    """Tooth-tip gap heights (len(angles), N) [m] over one revolution at a plateau.

    The twin logs the eccentricity at its publish rate; each sample's angle within the
    revolution comes from the revolution stamps (:func:`revolution_phase`).  The samples of
    the plateau are folded onto one revolution and averaged in 10° bins, and the gaps are
    computed from the pump geometry (:meth:`PumpModel.gaps`: the same overlap check as the
    model) at that angle and displacement.  ``pump``: a ``PumpModel`` of ``config`` to reuse.
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
    pump = pump or PumpModel(config, "fixed")
    out = np.empty((angles.size, pump.N))
    for i, a in enumerate(angles):
        ex[0] = np.interp(a, centres, fold[:, 0], period=2 * math.pi)
        ex[1] = np.interp(a, centres, fold[:, 1], period=2 * math.pi)
        out[i] = pump.gaps(float(a), ex)[0]
    return out


@_styled
def fig_gaps(twins: list[TwinData], plateaus: list[Plateau], config) -> bytes | None:
    """Tooth-tip gap height vs shaft angle at every plateau (gap 1 bold, the others thin grey);
    repeated visits of one operating point share a panel, dark → light in time order."""
    from gerotor_twin.model.pump import PumpModel

    if not plateaus or not any(tw.eccentricity is not None for tw in twins):
        return None
    angles = np.radians(np.arange(0, 360, 2.0))
    deg = np.degrees(angles)
    pump = PumpModel(config, "fixed")
    groups = group_plateaus(plateaus)
    fig, axes, grid = _multiples(len(groups), 2.7 if any(len(g) > 1 for g in groups) else 2.5)
    drawn = False
    for ax, group in zip(axes, groups):
        for k, p in enumerate(group):
            for i, tw in enumerate(twins):
                h = gap_profile(tw, p, config, angles, pump)
                if h is None:
                    continue
                if i == 0 and k == 0:
                    ax.plot(deg, h[:, 1:] * 1e6, color="0.75", lw=0.5)
                drawn = True
                ax.plot(deg, h[:, 0] * 1e6, lw=1.2, label=f"gap 1, {tw.label}" if len(group) == 1 else None,
                        **_visit_style(i, k, len(group)))
        _group_title(ax, group)
        ax.set_xticks(range(0, 361, 90))
    if not drawn:
        plt.close(fig)
        return None
    for ax in grid[-1]:
        ax.set_xlabel("shaft angle [deg]")
    for ax in grid[:, 0]:
        ax.set_ylabel("tip gap [µm]")
    _figure_legend(fig, axes, twins, any(len(g) > 1 for g in groups))
    return figure_png(fig)
