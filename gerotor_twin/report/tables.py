"""Tables of the report (``ReportContext -> Table | list[Table]``) and their CSV text.

Every :class:`panels.Table` on the page is offered as a CSV download (same columns, units in
the header, numbers in the table's format), so a table added to :data:`layout.PAGE` is exported
without further code.  The aligned-series CSV (:func:`aligned_csv`) is built from the time plots'
traces that lie on the report grid.
"""
from __future__ import annotations

import csv
import io
import re
import urllib.parse

import numpy as np

from .acceptance import FAIL, NO_DATA, PASS, tally
from .context import ReportContext
from .panels import Column, Table, TimeSeries

__all__ = ["plateau_tables", "summary_table", "comparison_table", "table_csv", "aligned_csv", "csv_data_uri", "slug"]

LPM = 6e4
HEADING = "Per-plateau metrics and acceptance verdict"


def slug(text: str) -> str:
    """A file-name-safe form of a label."""
    return re.sub(r"[^A-Za-z0-9]+", "_", text).strip("_").lower() or "x"


def _pct(v):
    return None if v is None else v * 100


def _lpm(v):
    return None if v is None else v * LPM


PLATEAU_COLUMNS = (
    Column("plateau", "{:d}"), Column("verdict", "{}", True), Column("t [s]", "{}", csv=False),
    Column("t start [s]", "{:.1f}", html=False), Column("t end [s]", "{:.1f}", html=False),
    Column("speed [rpm]", "{:.0f}"), Column("delivery p [bar g]", "{:.2f}"),
    Column("oil [°C]", "{:.1f}"),
    Column("flow measured [L/min]"), Column("flow predicted [L/min]"), Column("flow bias [L/min]", "{:+.3f}"),
    Column("flow RMSE [L/min]"), Column("flow max |err| [L/min]"), Column("flow tolerance ± [L/min]"),
    Column("eta_v measured [%]", "{:.2f}"), Column("eta_v predicted [%]", "{:.2f}"),
    Column("eta_v error [%-pt]", "{:+.2f}"), Column("eta_v tolerance ± [%-pt]", "{:.2f}"),
    Column("reason", "{}", True, html=False),
)


def _verdict_text(v: dict) -> str:
    return v["verdict"].upper() + (f" ({', '.join(v['failed'])})" if v["failed"] else "")


def _plateau_row(r: dict, v: dict) -> tuple:
    d = None if r["eta_predicted"] is None or r["eta_measured"] is None else r["eta_predicted"] - r["eta_measured"]
    fe = r["flow_error_m3s"]
    return (r["plateau"], _verdict_text(v),
            f"{r['t0_s']:.1f}–{r['t1_s']:.1f}", r["t0_s"], r["t1_s"], r["rpm"], r["bar"], r.get("oil_temperature_c"),
            _lpm(r["flow_measured_m3s"]),
            _lpm(r["flow_predicted_m3s"]), _lpm(fe["bias"]), _lpm(fe["rmse"]), _lpm(fe["max_abs"]),
            _lpm(v["flow_tol_m3s"]), _pct(r["eta_measured"]), _pct(r["eta_predicted"]), _pct(d),
            _pct(v["eta_tol"]), "; ".join(v["reasons"]))


def plateau_tables(ctx: ReportContext) -> list[Table]:
    """One table per twin file: plateau means, error statistics, tolerances and the verdict."""
    out = []
    for i, c in enumerate(ctx.comps):
        rows = tuple(_plateau_row(r, v) for r, v in zip(c["plateaus"], ctx.verdicts[i]))
        classes = tuple({PASS: "pass", FAIL: "fail", NO_DATA: "nodata"}[v["verdict"]] for v in ctx.verdicts[i])
        out.append(Table(f"tab-plateaus-{i + 1}", HEADING, PLATEAU_COLUMNS, rows,
                         f"{ctx.stem}_plateaus_{slug(c['label'])}.csv",
                         f"Acceptance criterion: {ctx.criterion.describe()}.", c["label"], classes))
    return out


def summary_table(ctx: ReportContext) -> Table:
    """Per twin: verdict counts and the pooled error statistics."""
    cols = (Column("twin", "{}", True), Column("plateaus", "{:d}"), Column("pass", "{:d}"), Column("fail", "{:d}"),
            Column("no data", "{:d}"), Column("flow bias [L/min]", "{:+.3f}"), Column("flow RMSE [L/min]"),
            Column("flow max |err| [L/min]"), Column("eta_v bias [%-pt]", "{:+.2f}"),
            Column("eta_v RMSE [%-pt]", "{:.2f}"), Column("whole-run flow RMSE [L/min]"))
    rows = []
    for c, vs in zip(ctx.comps, ctx.verdicts):
        fe, ee, w = c["overall"]["flow_error_m3s"], c["overall"]["eta_error"], c["whole_run"]["flow_error_m3s"]
        n = tally(vs)
        rows.append((c["label"], len(vs), n[PASS], n[FAIL], n[NO_DATA], _lpm(fe["bias"]), _lpm(fe["rmse"]),
                     _lpm(fe["max_abs"]), _pct(ee["bias"]), _pct(ee["rmse"]), _lpm(w["rmse"])))
    return Table("tab-summary", HEADING, cols, tuple(rows), f"{ctx.stem}_summary.csv",
                 "Error statistics pool every 0.1 s bin of every plateau; 'whole run' also the transitions.",
                 "All plateaus")


def comparison_table(ctx: ReportContext) -> Table | None:
    """With two or more twin files: per plateau the measurement and each twin's prediction and verdict, side by
    side (``None`` for one twin: its plateau table says it all)."""
    if len(ctx.comps) < 2:
        return None
    cols = [Column("plateau", "{:d}"), Column("speed [rpm]", "{:.0f}"), Column("delivery p [bar g]", "{:.2f}"),
            Column("flow measured [L/min]", "{:.2f}"), Column("eta_v measured [%]", "{:.2f}")]
    for c in ctx.comps:
        cols += [Column(f"flow {c['label']} [L/min]", "{:.2f}"), Column(f"eta_v {c['label']} [%]", "{:.2f}"),
                 Column(f"verdict {c['label']}", "{}", True)]
    rows = []
    for k, r in enumerate(ctx.comps[0]["plateaus"]):
        row = [r["plateau"], r["rpm"], r["bar"], _lpm(r["flow_measured_m3s"]), _pct(r["eta_measured"])]
        for c, vs in zip(ctx.comps, ctx.verdicts):
            row += [_lpm(c["plateaus"][k]["flow_predicted_m3s"]), _pct(c["plateaus"][k]["eta_predicted"]),
                    _verdict_text(vs[k])]
        rows.append(tuple(row))
    return Table("tab-compare", HEADING, tuple(cols), tuple(rows), f"{ctx.stem}_verdicts_side_by_side.csv",
                 f"Plateau means, measured and predicted by each twin file, with each twin's verdict. Acceptance "
                 f"criterion: {ctx.criterion.describe()}.", "Verdicts side by side")


def cell(col: Column, v) -> str:
    """A value as text in the column's format ('' for missing, 'nan' never shown)."""
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return ""
    try:
        return col.fmt.format(v)
    except (ValueError, TypeError):
        return str(v)


def table_csv(table: Table) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([c.name for c in table.columns if c.csv])
    for row in table.rows:
        w.writerow([cell(c, v) for c, v in zip(table.columns, row) if c.csv])
    return buf.getvalue()


def _on_grid(t: np.ndarray, grid_t: np.ndarray) -> bool:
    return t is grid_t or (t.shape == grid_t.shape and bool(np.array_equal(t, grid_t)))


def aligned_csv(ctx: ReportContext, panels: list[TimeSeries], plateau_index: np.ndarray) -> str:
    """Every grid trace of the time plots as one CSV: ``time [s]``, ``plateau`` (0: none), then the columns.

    Values at full grid resolution (no decimation), 6 significant digits; empty cell: no value.
    """
    cols, names = [], []
    for p in panels:
        for tr in p.traces:
            if tr.csv and tr.csv not in names and _on_grid(tr.t, ctx.grid.t):
                names.append(tr.csv)
                cols.append(np.asarray(tr.y, float))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["time [s]", "plateau"] + names)
    for k, t in enumerate(ctx.grid.t):
        w.writerow([f"{t:.3f}", int(plateau_index[k])]
                   + [f"{c[k]:.6g}" if np.isfinite(c[k]) else "" for c in cols])
    return buf.getvalue()


def csv_data_uri(text: str) -> str:
    """``data:text/csv`` URI, percent-encoded (digits, commas, dots stay as they are: ≈ the CSV's size)."""
    return "data:text/csv;charset=utf-8," + urllib.parse.quote(text, safe=",.-+:;/_=()[]|")
