"""One self-contained HTML page: inline CSS/JS (uPlot), embedded data, PNGs and CSVs as data: URIs.

Nothing is fetched: the page opens from a file, offline, and can be mailed or archived alone.
"""
from __future__ import annotations

import base64
import html

from .interactive import assets, data_script, panel_div
from .panels import Image, Table, TimeSeries
from .tables import cell, csv_data_uri, table_csv

__all__ = ["render", "figure", "table_html", "download_link", "PAGE_CSS"]

#: The stylesheet every HTML page of the project shares (report, sweep, batch).
PAGE_CSS = """
body{font-family:system-ui,sans-serif;font-size:15px;margin:1.5em auto;max-width:1100px;padding:0 12px;color:#222}
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ccc}h3{font-size:1.05em}
table{border-collapse:collapse;font-size:13px;margin:0.5em 0}
td,th{border:1px solid #bbb;padding:2px 5px;text-align:right;vertical-align:top}th{background:#eee}
td.verdict{white-space:nowrap}
td.l,th.l{text-align:left}figure{margin:0.8em 0}figcaption,.caption{font-size:13px;color:#444}
.warn{background:#fff3cd;border:1px solid #e0c36a;padding:0.4em 0.8em}
.headline{font-size:15px;background:#eef5ff;border:1px solid #9bc;padding:0.5em 0.9em}
img{max-width:100%;border:1px solid #ddd}
tr.pass td{background:#e6f4ea}tr.fail td{background:#fde7e7}tr.nodata td{background:#f2f2f2}
.verdict-pass{color:#14672a;font-weight:bold}.verdict-fail{color:#a4161a;font-weight:bold}
.ts-panel{width:100%;min-height:60px}.uplot{font-family:system-ui,sans-serif}.u-legend{font-size:12px}
.tools{font-size:13px;color:#444;margin:0.3em 0}.tools button{font-size:13px}
.prov td.l:first-child{white-space:nowrap;color:#333}.prov td{font-size:12px;word-break:break-word}
nav.toc{font-size:13px;columns:2}.scroll{overflow-x:auto}table.metrics td{white-space:nowrap}a.csv-link{font-size:13px}
"""


def _e(x) -> str:
    return html.escape(str(x))


def figure(png: bytes | None, fig_id: str, caption: str, missing: str = "") -> str:
    """An embedded PNG with caption, or a note saying why it is absent."""
    if png is None:
        return f'<p class="warn" id="{fig_id}-missing">Figure not drawn: {_e(missing)}</p>'
    b64 = base64.b64encode(png).decode("ascii")
    return (f'<figure><img class="report-figure" id="{fig_id}" alt="{_e(caption)}" '
            f'src="data:image/png;base64,{b64}"><figcaption>{_e(caption)}</figcaption></figure>')


def download_link(name: str, text: str, what: str) -> str:
    """A link that saves ``text`` as ``name`` (CSV data: URI)."""
    return (f'<a class="csv-link" download="{_e(name)}" href="{csv_data_uri(text)}">{_e(name)}</a> '
            f'<span class="caption">({_e(what)}, {len(text.splitlines()) - 1} rows)</span>')


def table_html(t: Table) -> str:
    shown = [k for k, c in enumerate(t.columns) if c.html]
    head = "".join(f"<th{' class=l' if t.columns[k].align_left else ''}>{_e(t.columns[k].name)}</th>" for k in shown)
    body = []
    for i, row in enumerate(t.rows):
        cls = f" class='{t.row_classes[i]}'" if i < len(t.row_classes) else ""
        cells = []
        for k in shown:
            c = t.columns[k]
            text = cell(c, row[k]) or "–"
            word = text.split(" ")[0]
            extra = (" verdict" + (f" verdict-{word.lower()}" if word in ("PASS", "FAIL") else "")
                     if c.name.startswith("verdict") else "")
            cells.append(f"<td class='{'l' if c.align_left else ''}{extra}'>{_e(text)}</td>")
        body.append(f"<tr{cls}>{''.join(cells)}</tr>")
    title = f"<h3>{_e(t.title)}</h3>" if t.title else ""
    hidden = [c.name for c in t.columns if not c.html]
    more = f" (the CSV also has: {', '.join(hidden)})" if hidden else ""
    link = download_link(t.csv_name, table_csv(t), "this table")
    return (f"{title}<div class='scroll'><table class='metrics' id='{t.id}'><tr>{head}</tr>{''.join(body)}</table>"
            f"</div><p class='caption'>{_e(t.caption)} CSV{_e(more)}: {link}</p>")


def _block(b, decimation: dict[str, list[str]]) -> str:
    if isinstance(b, TimeSeries):
        notes = decimation.get(b.id, [])
        extra = (" Decimated for drawing: " + "; ".join(notes) + ".") if notes else ""
        return f'<figure>{panel_div(b.id)}<figcaption>{_e(b.caption + extra)}</figcaption></figure>'
    if isinstance(b, Table):
        return table_html(b)
    if isinstance(b, Image):
        return figure(b.png, b.id, b.caption, b.missing)
    raise TypeError(f"report block of unknown type {type(b).__name__}")


_TOOLS = ('<p class="tools">Time plots: drag to zoom to a time span, mouse wheel to zoom about the cursor, '
          'shift+drag (or middle button) to pan, double-click for the whole run; the legend under each plot '
          'shows the values under the cursor; all time plots follow each other. '
          '<button type="button" class="reset-zoom">whole run</button></p>')


def _sections(blocks: list, decimation: dict) -> tuple[str, list[tuple[str, str]]]:
    """The blocks grouped under their headings; and the (anchor, heading) list for the contents."""
    out, toc, last, tools = [], [], None, False
    for b in blocks:
        if b.heading != last:
            anchor = f"sec-{len(toc) + 1}"
            toc.append((anchor, b.heading))
            out.append(f'<h2 id="{anchor}">{_e(b.heading)}</h2>')
            last = b.heading
        if isinstance(b, TimeSeries) and not tools:
            out.append(_TOOLS)
            tools = True
        out.append(_block(b, decimation))
    return "\n".join(out), toc


def _prov_html(prov: list[tuple[str, list[tuple[str, str]]]]) -> str:
    parts = []
    for title, rows in prov:
        body = "".join(f"<tr><td class='l'>{_e(k)}</td><td class='l'>{_e(v)}</td></tr>" for k, v in rows)
        parts.append(f"<h3>{_e(title)}</h3><table class='prov'>{body}</table>")
    return "".join(parts)


def render(title: str, headline: list[str], notes: list[str], blocks: list, panel_specs: list[dict],
           plateaus, span, provenance: list, downloads: list[tuple[str, str, str]], definitions: str) -> str:
    """The whole page.

    ``panel_specs``: :func:`interactive.panel_data` of the time series blocks; ``downloads``:
    (file name, CSV text, description) offered at the top besides the per-table links.
    """
    css, js = assets()
    decimation = {p["id"]: p["decimation"] for p in panel_specs}
    body, toc = _sections(blocks, decimation)
    toc = [("sec-downloads", "Downloads (CSV)"), ("sec-provenance", "Provenance")] + toc + \
          [("sec-definitions", "Definitions")]
    toc_html = "".join(f'<li><a href="#{a}">{_e(h)}</a></li>' for a, h in toc)
    dl = "".join(f"<li>{download_link(n, text, what)}</li>" for n, text, what in downloads)
    notes_html = "".join(f"<p class='warn'>{_e(n)}</p>" for n in notes)
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>{_e(title)}</title><style>{css}</style><style>{PAGE_CSS}</style></head>
<body>
<h1>{_e(title)}</h1>
<div class="headline">{'<br>'.join(_e(h) for h in headline)}</div>
{notes_html}
<nav class="toc"><ul>{toc_html}</ul></nav>
<h2 id="sec-downloads">Downloads (CSV)</h2><ul>{dl}</ul>
<h2 id="sec-provenance">Provenance</h2>{_prov_html(provenance)}
{body}
<h2 id="sec-definitions">Definitions</h2><p>{_e(definitions)}</p>
{data_script(panel_specs, plateaus, span)}
<script>{js}</script>
</body></html>
"""
