"""Self-contained HTML summary of a design study: efficiency map, ripple vs a parameter, parallel coordinates.

Figures are matplotlib PNGs embedded as base64 (the report's own helpers); the
page needs no other file.  Units on the page: rpm, bar gauge, %, µm; parameter
values as the SPEC gives them.
"""
from __future__ import annotations

import html
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..report.figures import figure_png  # noqa: E402
from ..report.html import PAGE_CSS, figure  # noqa: E402

__all__ = ["sweep_page", "numeric_params"]

_OPERATING_FIRST = ("operating.speed_rpm", "operating.delivery_bar")


def _e(x) -> str:
    return html.escape(str(x))


def numeric_params(records: list[dict], names: list[str]) -> list[str]:
    """Parameters with numeric values and more than one distinct value (speed and pressure first)."""
    out = []
    for n in names:
        vals = {r["params"][n] for r in records}
        if len(vals) > 1 and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
            out.append(n)
    return sorted(out, key=lambda n: (n not in _OPERATING_FIRST, _OPERATING_FIRST.index(n)
                                      if n in _OPERATING_FIRST else 0))


def slice_at_middle(ok: list[dict], keep: list[str], names: list[str], least: int = 4) -> tuple[list[dict], str]:
    """The points where every varying parameter not in ``keep`` is at its middle value (a grid slice).

    Returns the points and a text naming the slice; all points (and "") when the slice would hold
    fewer than ``least`` points (a Latin hypercube or Sobol' sample has no slices).
    """
    fixed = {}
    for n in names:
        vals = sorted({r["params"][n] for r in ok}, key=lambda v: (isinstance(v, str), v))
        if n not in keep and len(vals) > 1:
            fixed[n] = vals[(len(vals) - 1) // 2]
    sel = [r for r in ok if all(r["params"][n] == v for n, v in fixed.items())]
    if not fixed or len(sel) < least:
        return ok, ""
    return sel, "; at " + ", ".join(f"{n} = {v}" for n, v in fixed.items())


def _col(records, name) -> np.ndarray:
    return np.array([r["params"][name] if name in r["params"] else r["outputs"].get(name, np.nan)
                     for r in records], dtype=float)


def fig_efficiency_map(ok: list[dict], x: str, y: str) -> bytes:
    """Volumetric efficiency [%] over two parameters (points coloured; contours where the points allow)."""
    fig, ax = plt.subplots(figsize=(7, 5))
    X, Y, Z = _col(ok, x), _col(ok, y), 100 * _col(ok, "volumetric_efficiency")
    if len(ok) >= 6 and np.ptp(X) > 0 and np.ptp(Y) > 0:
        try:
            cs = ax.tricontourf(X, Y, Z, levels=12, cmap="viridis", alpha=0.6)
        except (ValueError, RuntimeError):   # collinear points: no triangulation
            cs = None
    else:
        cs = None
    sc = ax.scatter(X, Y, c=Z, cmap="viridis", edgecolors="k", zorder=3)
    fig.colorbar(cs if cs is not None else sc, ax=ax, label="volumetric efficiency [%]")
    if len(ok) <= 40:
        for xi, yi, zi in zip(X, Y, Z):
            ax.annotate(f"{zi:.1f}", (xi, yi), textcoords="offset points", xytext=(4, 4), fontsize=7)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.grid(alpha=0.3)
    return figure_png(fig)


def fig_ripple(ok: list[dict], x: str, group: str | None) -> bytes:
    """Delivery-flow ripple [%] against one parameter, one line per value of a second one."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    keys = sorted({r["params"][group] for r in ok}, key=str) if group else [None]
    for k in keys[:12]:
        sel = [r for r in ok if group is None or r["params"][group] == k]
        X, R = _col(sel, x), 100 * _col(sel, "delivery_flow_ripple")
        o = np.argsort(X)
        ax.plot(X[o], R[o], "o-", ms=4, label=None if group is None else f"{group} = {k}")
    ax.set_xlabel(x)
    ax.set_ylabel("delivery-flow ripple (max-min)/mean [%]")
    if group:
        ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    return figure_png(fig)


def fig_parallel(ok: list[dict], params: list[str], outputs: list[str]) -> bytes:
    """Parallel coordinates: each point a line through its normalised parameters and outputs."""
    cols = params + [o for o in outputs if o not in params]
    data = np.column_stack([_col(ok, c) for c in cols])
    lo, hi = np.nanmin(data, axis=0), np.nanmax(data, axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    norm = (data - lo) / span
    eta = _col(ok, "volumetric_efficiency")
    cmap = plt.get_cmap("viridis")
    e0, e1 = np.nanmin(eta), np.nanmax(eta)
    fig, ax = plt.subplots(figsize=(max(7, 1.3 * len(cols)), 4.8))
    for row, e in zip(norm, eta):
        ax.plot(range(len(cols)), row, color=cmap((e - e0) / (e1 - e0) if e1 > e0 else 0.5), alpha=0.6, lw=1)
    ax.set_xticks(range(len(cols)))
    ax.set_xticklabels([f"{c}\n[{lo[i]:.3g}, {hi[i]:.3g}]" for i, c in enumerate(cols)], fontsize=7, rotation=20)
    ax.set_yticks([0, 1])
    ax.set_yticklabels(["min", "max"])
    ax.set_title("parallel coordinates (colour: volumetric efficiency)", fontsize=9)
    fig.tight_layout()
    return figure_png(fig)


def _fmt(v) -> str:
    if isinstance(v, float):
        return "–" if not math.isfinite(v) else f"{v:.6g}"
    return "–" if v is None else str(v)


def _table(records: list[dict], params: list[str], outputs: list[str], limit: int = 500) -> str:
    head = "".join(f"<th>{_e(c)}</th>" for c in ["id", "status"] + params + outputs)
    rows = []
    for r in records[:limit]:
        cells = [r["id"], r["status"]] + [r["params"].get(p) for p in params] + \
                [r["outputs"].get(o) for o in outputs]
        rows.append("<tr>" + "".join(f"<td>{_e(_fmt(c))}</td>" for c in cells) + "</tr>")
    more = f"<p>… {len(records) - limit} more rows in results.csv</p>" if len(records) > limit else ""
    return f"<table><tr>{head}</tr>{''.join(rows)}</table>{more}"


def sweep_page(title: str, records: list[dict], params: list[str], outputs: list[str], info: list[str]) -> str:
    """The HTML page of a finished (or partial) study; ``records`` sorted by index."""
    ok = [r for r in records if r["status"] == "ok"]
    failed = [r for r in records if r["status"] != "ok"]
    num = numeric_params(ok, params) if ok else []
    figs = []
    if len(num) >= 2:
        sel, where = slice_at_middle(ok, num[:2], params)
        figs.append(("Volumetric efficiency map", figure(fig_efficiency_map(sel, num[0], num[1]), "fig-eta-map",
                     f"Volumetric efficiency [%] over {num[0]} and {num[1]}{where or ' (all points)'}.")))
    if num:
        x = num[1] if num[0] == "operating.delivery_bar" and len(num) > 1 else num[0]
        others = [p for p in params if p != x and p != "operating.delivery_bar"
                  and len({r["params"][p] for r in ok}) > 1]
        if "operating.delivery_bar" in num and x != "operating.delivery_bar":
            others.append("operating.delivery_bar")
        group = others[0] if others else None
        sel, where = slice_at_middle(ok, [x] + ([group] if group else []), params, least=2)
        figs.append(("Delivery-flow ripple", figure(fig_ripple(sel, x, group), "fig-ripple",
                     f"Delivery-flow ripple [%] against {x}{where or ' (all points)'}.")))
    if len(params) >= 2 and num and len(ok) >= 2:
        figs.append(("Parallel coordinates", figure(fig_parallel(ok, num, list(outputs)[:6]),
                     "fig-parallel", "Every point through its parameters and outputs (normalised per axis).")))
    if not ok:
        figs.append(("Figures", "<p class='warn'>No point succeeded: no figure.</p>"))
    fail_html = "".join(f"<tr><td class='l'>{_e(r['id'])}</td><td class='l'>{_e(r['params'])}</td>"
                        f"<td class='l'>{_e(r['reason'])}</td></tr>" for r in failed[:200])
    body = "".join(f"<h2>{_e(h)}</h2>{f}" for h, f in figs)
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{_e(title)}</title><style>{PAGE_CSS}</style></head>
<body><h1>{_e(title)}</h1>
<div class="headline">{'<br>'.join(_e(i) for i in info)}</div>
{body}
<h2>Failed points ({len(failed)})</h2>
{f"<table><tr><th class='l'>id</th><th class='l'>parameters</th><th class='l'>reason</th></tr>{fail_html}</table>"
 if failed else "<p>none</p>"}
<h2>All points</h2>{_table(records, params, list(outputs))}
</body></html>
"""
