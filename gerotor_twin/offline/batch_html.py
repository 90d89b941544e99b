"""The fleet summary page: one row per recording, linked to its report; one bar chart of the errors."""
from __future__ import annotations

import html
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..report.figures import figure_png  # noqa: E402
from ..report.html import PAGE_CSS, figure  # noqa: E402

__all__ = ["fleet_page"]

LPM = 6e4


def _e(x) -> str:
    return html.escape(str(x))


def _n(v, scale=1.0, fmt="{:.2f}") -> str:
    return "–" if v is None else fmt.format(v * scale)


def _rng(r, fmt="{:.0f}") -> str:
    return "–" if not r else f"{fmt.format(r[0])}–{fmt.format(r[1])}"


def fig_errors(ok: list[dict]) -> bytes:
    """Flow bias and RMSE [L/min] and efficiency bias [%-pt] per recording."""
    names = [r["name"] for r in ok]
    x = np.arange(len(ok))
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(max(6, 0.6 * len(ok) + 3), 5.5), sharex=True)
    val = lambda k, s: np.array([np.nan if r.get(k) is None else r[k] * s for r in ok])  # noqa: E731
    a1.bar(x - 0.2, val("flow_bias_m3s", LPM), 0.4, label="bias")
    a1.bar(x + 0.2, val("flow_rmse_m3s", LPM), 0.4, label="RMSE")
    a1.set_ylabel("flow error [L/min]")
    a1.legend(fontsize=8)
    a2.bar(x, val("eta_bias", 100), 0.5, color="tab:green")
    a2.set_ylabel("η_v bias [%-pt]")
    a2.set_xticks(x)
    a2.set_xticklabels(names, rotation=30, ha="right", fontsize=7)
    for a in (a1, a2):
        a.axhline(0, color="k", lw=0.6)
        a.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    return figure_png(fig)


def _row(out: Path, r: dict) -> str:
    link = os.path.relpath(r["report"], out) if r.get("report") and r["status"] == "ok" else None
    name = f"<a href='{_e(link)}'>{_e(r['name'])}</a>" if link else _e(r["name"])
    if r["status"] != "ok":
        return (f"<tr><td class='l'>{name}</td><td class='l'>failed</td>"
                f"<td class='l' colspan='9'>{_e(r['reason'])}</td></tr>")
    fit = _fit_cell(r.get("calibration"))
    return (f"<tr><td class='l'>{name}</td><td class='l'>ok</td><td class='l'>{_e(r['date_utc'])}</td>"
            f"<td>{r['duration_s']:.1f}</td><td>{_rng(r['speed_range_rpm'])}</td>"
            f"<td>{_rng(r['delivery_range_bar'], '{:.1f}')}</td><td>{r['plateaus']}</td>"
            f"<td>{_n(r['flow_bias_m3s'], LPM, '{:+.3f}')} / {_n(r['flow_rmse_m3s'], LPM, '{:.3f}')}</td>"
            f"<td>{_n(r['eta_bias'], 100, '{:+.2f}')} / {_n(r['eta_rmse'], 100)}</td>"
            f"<td class='l'>{_health_cell(r.get('health'))}</td>{fit}"
            f"<td class='l'>{_e('; '.join(r.get('notes') or [])[:300])}</td></tr>")


def _health_cell(h: dict | None) -> str:
    """Last health level with the leakage factor ± 1σ, the fault named, and the alarm intervals (s from the start)."""
    if not h:
        return "n/a (no health update: no measured flow or never steady)"
    alarms = ", ".join(f"{a[0]} {a[1]:.0f}–{a[2]:.0f} s" for a in h.get("alarms", []))
    return (f"<b>{_e(h['level'])}</b>: k = {h['leakage_factor']:.3f} ± {h['leakage_factor_sd']:.3f}, "
            f"η<sub>v,ref</sub> {100 * h['reference_efficiency']:.1f} %" + _fault_html(h)
            + (f"<br>{_e(alarms)}" if alarms else ""))


def _fault_html(h: dict) -> str:
    """``, fault: <kind> (p)`` when the log's last update names one (older logs: nothing)."""
    from ..twin.health import fault_text
    text = fault_text(h.get("fault"), h.get("fault_confidence"), h.get("fault_rival"))
    return "" if text == "-" else f", fault: {_e(text)}"


def _fit_cell(cal: dict | None) -> str:
    """Fitted clearance combination with its 95 % interval (only in a fleet run with --calibrate)."""
    if cal is None:
        return ""
    if "error" in cal:
        return f"<td class='l'>not fitted: {_e(cal['error'])}</td>"
    if cal.get("calibrated") is False:
        return f"<td class='l'>nominal kept: {_e(cal['verdict'])}</td>"
    c = cal["combinations"][0] if cal["combinations"] else None
    if c is None:
        return "<td class='l'>nothing identifiable</td>"
    lo, hi = c["factor_ci95"]
    note = f"<br><span class='warn'>{_e(cal['note'])}</span>" if cal.get("note") else ""
    return (f"<td class='l'>{_e(c['label'])} × {c['factor']:.3f} [{lo:.3f}, {hi:.3f}]; "
            f"|η err| ≤ {100 * cal['eta_max_abs']:.2f} pt{note}</td>")


def fleet_page(out: Path, rows: list[dict], info: list[str]) -> str:
    """The HTML page (self-contained; links to the per-recording reports are relative to ``out``)."""
    ok = [r for r in rows if r["status"] == "ok"]
    fig = "<p class='warn'>No recording reported.</p>"
    if ok:
        fig = figure(fig_errors(ok), "fig-fleet-errors", "Mean-flow error (bias, RMSE) and volumetric-efficiency "
                     "bias per recording, over its steady plateaus.")
    fitted = any(r.get("calibration") is not None for r in ok)
    head = ("<tr><th class='l'>recording</th><th class='l'>status</th><th class='l'>date (UTC)</th>"
            "<th>duration [s]</th><th>speed [rpm]</th><th>delivery [bar g]</th><th>plateaus</th>"
            "<th>flow bias / RMSE [L/min]</th><th>η<sub>v</sub> bias / RMSE [%-pt]</th>"
            "<th class='l'>health (last update)</th>"
            + ("<th class='l'>fitted clearance factor [95 %]</th>" if fitted else "") + "<th class='l'>notes</th></tr>")
    body = "".join(_row(out, r) for r in rows)
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>Fleet summary</title><style>{PAGE_CSS}</style></head>
<body><h1>Fleet summary: twin vs bench, one row per recording</h1>
<div class="headline">{'<br>'.join(_e(i) for i in info)}</div>
<table>{head}{body}</table>
<h2>Errors per recording</h2>{fig}
<p>Errors are predicted minus measured over the steady plateaus of each recording (definitions in each
report). Speed and delivery ranges are the bench's over the whole recording.</p>
</body></html>
"""
