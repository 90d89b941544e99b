"""Interactive time plots in the self-contained page: the vendored uPlot, inlined, and the panel data.

Why uPlot (``vendor/uplot/VENDORED.md``): MIT-licensed, no dependencies, ~51 KB minified, draws
10⁵ points on a canvas fast, and has what a test engineer needs built in (drag-zoom, cursor
sync across plots, live legend with the values under the cursor, filled bands).  Plotly
(~3.5 MB) would dominate the page's size; a home-made plotter would be code to maintain.
Wheel zoom, shift-drag pan and the plateau shading are small plugins in ``report.js``.
"""
from __future__ import annotations

import json
import math
from importlib import resources

import numpy as np

from .panels import DEFAULT_MAX_POINTS, TimeSeries, envelope

__all__ = ["UPLOT_VERSION", "assets", "panel_data", "data_script", "panel_div"]

UPLOT_VERSION = "1.6.32"


def _read(name: str) -> str:
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")


def assets() -> tuple[str, str]:
    """(CSS, JavaScript) to inline: uPlot's stylesheet and library with its licence, then ``report.js``."""
    lic = _read("vendor/uplot/LICENSE").replace("*/", "* /")
    css = _read("vendor/uplot/uPlot.min.css")
    js = (f"/* uPlot {UPLOT_VERSION} (https://github.com/leeoniya/uPlot), vendored unmodified.\n{lic}*/\n"
          + _read("vendor/uplot/uPlot.iife.min.js") + "\n" + _read("report.js"))
    return css, js.replace("</script", "<\\/script")


def _nums(v: np.ndarray, sig: int = 6) -> list:
    """Floats rounded to ``sig`` significant digits; NaN/inf -> None (a gap in the plot)."""
    out = []
    for x in np.asarray(v, float).tolist():
        out.append(float(f"{x:.{sig}g}") if math.isfinite(x) else None)
    return out


def _series(label, t, y, color, width, dash, dec) -> dict:
    return {"label": label, "x": _nums(t, 9), "y": _nums(y), "color": color, "width": width,
            "dash": list(dash), "dec": dec}


def _lighten(color: str, alpha: float) -> str:
    """``#rrggbb`` -> ``rgba(r,g,b,alpha)`` (other colour strings unchanged)."""
    if color.startswith("#") and len(color) == 7:
        r, g, b = (int(color[i:i + 2], 16) for i in (1, 3, 5))
        return f"rgba({r},{g},{b},{alpha})"
    return color


def panel_data(panel: TimeSeries, max_points: int = DEFAULT_MAX_POINTS) -> dict:
    """The JSON-ready spec of one panel; long traces become min/max envelopes (see :mod:`.panels`)."""
    series, bands, notes = [], [], []
    for tr in panel.traces:
        d = envelope(tr.t, tr.y, max_points)
        if not d.decimated:
            series.append(_series(tr.label, d.t, d.lo, tr.color, tr.width, tr.dash, tr.decimals))
            continue
        i = len(series) + 1
        series.append(_series(f"{tr.label}, max", d.t, d.hi, tr.color, min(tr.width, 1.0), tr.dash, tr.decimals))
        series.append(_series(f"{tr.label}, min", d.t, d.lo, tr.color, min(tr.width, 1.0), tr.dash, tr.decimals))
        bands.append([i, i + 1, _lighten(tr.color, 0.35)])
        notes.append(f"{tr.label}: {tr.t.size} samples drawn as min/max of ~{d.per_point} per point")
    for b in panel.bands:
        i = len(series) + 1
        series.append(_series(f"{b.label}, upper", b.t, b.hi, b.edge, 1.0, (4, 3), 3))
        series.append(_series(f"{b.label}, lower", b.t, b.lo, b.edge, 1.0, (4, 3), 3))
        bands.append([i, i + 1, b.color])
    return {"id": panel.id, "ylabel": panel.y_label, "height": panel.height, "zero": panel.zero_line,
            "series": series, "bands": bands, "decimation": notes,
            "intervals": [[float(iv.t0), float(iv.t1), iv.label, iv.color] for iv in panel.intervals]}


def data_script(panels: list[dict], plateaus, span: tuple[float, float]) -> str:
    """The ``<script type="application/json">`` element ``report.js`` reads."""
    spec = {"panels": panels, "span": [float(span[0]), float(span[1])],
            "plateaus": [[p.t0, p.t1, f"#{p.index}"] for p in plateaus]}
    text = json.dumps(spec, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    return f'<script type="application/json" id="report-data">{text}</script>'


def panel_div(panel_id: str) -> str:
    return f'<div class="ts-panel" id="{panel_id}"></div>'
