"""One self-contained HTML page: figures as base64 PNG ``<img>``, tables, notes (no external files)."""
from __future__ import annotations

import base64
import html

__all__ = ["render"]

LPM = 6e4

_CSS = """
body{font-family:system-ui,sans-serif;margin:1.5em auto;max-width:1100px;color:#222}
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ccc}
table{border-collapse:collapse;font-size:0.85em;margin:0.5em 0}
td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}th{background:#eee}
td.l,th.l{text-align:left}figure{margin:0.8em 0}figcaption{font-size:0.85em;color:#555}
.warn{background:#fff3cd;border:1px solid #e0c36a;padding:0.4em 0.8em}
.headline{font-size:1.05em;background:#eef5ff;border:1px solid #9bc;padding:0.5em 0.9em}
img{max-width:100%;border:1px solid #ddd}
"""


def _e(x) -> str:
    return html.escape(str(x))


def _f(v, scale=1.0, fmt="{:.3f}") -> str:
    return "–" if v is None else fmt.format(v * scale)


def figure(png: bytes | None, fig_id: str, caption: str, missing: str = "") -> str:
    """An embedded PNG with caption, or a note saying why it is absent."""
    if png is None:
        return f'<p class="warn" id="{fig_id}-missing">Figure not drawn: {_e(missing)}</p>'
    b64 = base64.b64encode(png).decode("ascii")
    return (f'<figure><img class="report-figure" id="{fig_id}" alt="{_e(caption)}" '
            f'src="data:image/png;base64,{b64}"><figcaption>{_e(caption)}</figcaption></figure>')


def _stats_cells(s: dict, scale: float, fmt: str) -> str:
    return "".join(f"<td>{_f(s[k], scale, fmt)}</td>" for k in ("bias", "rmse", "max_abs"))


def plateau_table(comp: dict) -> str:
    head = ("<tr><th>#</th><th>t [s]</th><th>speed [rpm]</th><th>p [bar g]</th><th>oil [°C]</th>"
            "<th>flow meas [L/min]</th><th>flow pred [L/min]</th>"
            "<th>bias [L/min]</th><th>RMSE [L/min]</th><th>max |err| [L/min]</th>"
            "<th>η<sub>v</sub> meas [%]</th><th>η<sub>v</sub> pred [%]</th><th>Δη<sub>v</sub> [%-pt]</th></tr>")
    rows = []
    for r in comp["plateaus"]:
        d = None if r["eta_predicted"] is None or r["eta_measured"] is None else r["eta_predicted"] - r["eta_measured"]
        rows.append(f"<tr><td>{r['plateau']}</td><td>{r['t0_s']:.1f}–{r['t1_s']:.1f}</td><td>{r['rpm']:.0f}</td>"
                    f"<td>{r['bar']:.2f}</td><td>{_f(r.get('oil_temperature_c'), 1, '{:.1f}')}</td>"
                    f"<td>{_f(r['flow_measured_m3s'], LPM)}</td>"
                    f"<td>{_f(r['flow_predicted_m3s'], LPM)}</td>"
                    + _stats_cells(r["flow_error_m3s"], LPM, "{:.3f}")
                    + f"<td>{_f(r['eta_measured'], 100, '{:.2f}')}</td><td>{_f(r['eta_predicted'], 100, '{:.2f}')}</td>"
                    f"<td>{_f(d, 100, '{:+.2f}')}</td></tr>")
    o, w = comp["overall"], comp["whole_run"]
    rows.append(f"<tr><th class='l' colspan='7'>all plateau samples</th>"
                + _stats_cells(o["flow_error_m3s"], LPM, "{:.3f}")
                + f"<td colspan='2'>η<sub>v</sub> RMSE [%-pt]</td><td>{_f(o['eta_error']['rmse'], 100, '{:.2f}')}</td></tr>")
    rows.append(f"<tr><th class='l' colspan='7'>whole run (transients included)</th>"
                + _stats_cells(w["flow_error_m3s"], LPM, "{:.3f}") + "<td colspan='3'></td></tr>")
    return f"<table class='metrics'>{head}{''.join(rows)}</table>"


def render(title: str, files: list[dict], notes: list[str], headline: list[str],
           figures: list[str], comps: list[dict], definitions: str) -> str:
    """The whole page (strings of already-rendered figure blocks)."""
    files_html = "".join(f"<tr><td class='l'>{_e(f['role'])}</td><td class='l'>{_e(f['path'])}</td>"
                         f"<td class='l'>{_e(f['info'])}</td></tr>" for f in files)
    notes_html = "".join(f"<p class='warn'>{_e(n)}</p>" for n in notes)
    tables = "".join(f"<h3>{_e(c['label'])}</h3>{plateau_table(c)}" for c in comps)
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{_e(title)}</title><style>{_CSS}</style></head>
<body>
<h1>{_e(title)}</h1>
<div class="headline">{'<br>'.join(_e(h) for h in headline)}</div>
{notes_html}
<h2>Files</h2><table><tr><th class='l'>role</th><th class='l'>file</th><th class='l'>content</th></tr>{files_html}</table>
<h2>Operating points</h2>{figures[0]}
<h2>Delivery flow: measured vs predicted</h2>{figures[1]}
<h2>Volumetric efficiency and error metrics per plateau</h2>{tables}{figures[2]}
<h2>Predicted chamber pressure vs shaft angle</h2>{figures[3]}
<h2>Outer-gear trajectory in the clearance circle</h2>{figures[4]}
<h2>Tooth-tip gap height vs shaft angle</h2>{figures[5]}
<h2>Definitions</h2><p>{_e(definitions)}</p>
</body></html>
"""
