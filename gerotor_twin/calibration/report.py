"""One self-contained HTML page for a calibration result (``calibrate --report F.html``).

Parameter table with 95 % intervals, identifiability verdicts, per-plateau flow and
η_v errors before and after (fit and hold-out), and one figure (PNG inlined).
"""
from __future__ import annotations

import base64
import html
import io
from pathlib import Path

from ..units import m3s_to_lpm
from .fit_model import display_value
from .selection import BY_SPEED_NOTE, held_out_by_speed

__all__ = ["write_report"]


def _figure(result: dict) -> str:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    f = result["fit"]
    fig, ax = plt.subplots(figsize=(8, 3.6), dpi=110)
    k = range(1, len(f["plateaus"]) + 1)
    ax.plot(k, [100 * r["eta_error"] for r in f["plateaus_prior"]], "o-", label="prior config")
    ax.plot(k, [100 * r["eta_error"] for r in f["plateaus"]], "s-", label="fitted config")
    ho = result.get("holdout") or {}
    held = set(ho.get("held_out", []))
    for i, r in enumerate(f["plateaus"]):
        if r["plateau"] in held:
            ax.axvline(i + 1, color="0.8", lw=6, zorder=0)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("plateau [-] (grey: held out in the hold-out fit)")
    ax.set_ylabel("η_v error, model − bench [%-pt]")
    ax.legend(fontsize=10)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode()


def _table(head: list[str], rows: list[list]) -> str:
    h = "".join(f"<th>{html.escape(c)}</th>" for c in head)
    b = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{h}</tr>{b}</table>"


_scaled = display_value


def _verdict(p: dict, f: dict) -> str:
    """Whether the data determined a parameter alone, with others as one factor, or not (kept at the prior)."""
    if p["identifiable"]:
        return "yes"
    kept = set(f["insensitive"]) | set(f.get("fixed", []))
    return "no: kept at the prior" if p["name"] in kept else "no (common factor of its group)"


def _selection(sel: dict | None) -> str:
    """The candidate sets' fit and held-out errors, the choice and the empirical baseline ('' without selection)."""
    if not sel:
        return ""
    rows = [["+".join(c["params"]) or "prior (nothing fitted)", f"{100 * c['fit_rmse']:.2f}",
             f"{100 * c['cv_rmse']:.2f} ± {100 * c['cv_rmse_se']:.2f}", f"{100 * c['cv_max_abs']:.2f}"]
            for c in sel["candidates"]]
    b = sel["baseline"]
    rows.append([f"empirical {b['law']}", f"{100 * b['fit_rmse']:.2f}", f"{100 * b['cv_rmse']:.2f}",
                 f"{100 * b['cv_max_abs']:.2f}"])
    verdict = ("<p><b>The empirical law predicts the held-out points better than the twin.</b></p>"
               if sel["baseline_better"] else "")
    pi = sel.get("prediction_interval")
    band = (f"<p>95 % prediction interval of a predicted η_v: ± {100 * pi['typical_half_width_eta']:.2f} pt (RMS over "
            f"the plateaus): model-form error {100 * pi['model_form_sd_eta']:.2f} pt sd from {pi['held_out']} held-out "
            f"plateaus, with the parameters' and the measurement's parts per plateau (table below).</p>") if pi else ""
    speeds = held_out_by_speed(sel)
    by_speed = ("<p>Its held-out |η_v error| by speed (mean): "
                + ", ".join(f"{rpm:.0f} rpm {100 * e:.2f} pt" for rpm, e in speeds)
                + f" ({BY_SPEED_NOTE}).</p>") if speeds else ""
    return (f"<h2>Parameter set (leave one {html.escape(sel['cv'])} out, {len(sel['folds'])} folds)</h2>"
            + _table(["set", "fit RMSE [pt]", "held-out RMSE [pt]", "held-out max [pt]"], rows)
            + f"<p>Chosen: {html.escape(sel['reason'])}.</p>{by_speed}{band}{verdict}" + _heldout(sel))


def _heldout(sel: dict) -> str:
    """Per plateau: the nominal twin's and the chosen set's held-out η error side by side, and the chosen set's
    95 % prediction interval at it."""
    by = {tuple(c["params"]): c for c in sel["candidates"]}
    nominal, chosen = by.get(()), by.get(tuple(sel["chosen"]))
    pi = sel.get("prediction_interval")
    if nominal is None or chosen is None or not pi or "plateau_labels" not in sel:
        return ""
    index = {lab: k for k, lab in enumerate(sel["plateau_labels"])}
    rows = [[lab, f"{100 * nominal['cv_errors'][index[lab]]:+.2f}", f"{100 * chosen['cv_errors'][index[lab]]:+.2f}",
             f"± {100 * pi['half_width_eta'][index[lab]]:.2f}"] for fold in sel["folds"] for lab in fold]
    return ("<h3>Held-out η_v error per plateau, nominal and calibrated side by side</h3>"
            + _table(["plateau (by fold)", "nominal [pt]", "+".join(sel["chosen"]) + " [pt]"
                      if sel["chosen"] else "chosen: nominal [pt]", "95 % interval [pt]"], rows))


def write_report(result: dict, path) -> Path:
    """Write the page; returns its path."""
    f = result["fit"]
    params = _table(["parameter", "config field", "prior", "fitted", "parameter 95 % CI (not the twin's accuracy)",
                     "separately identifiable"],
                    [[p["name"], p["field"], _scaled(p["prior"], p["unit"]), _scaled(p["value"], p["unit"]),
                      f"{_scaled(p['ci95'][0], p['unit'])} … {_scaled(p['ci95'][1], p['unit'])}",
                      _verdict(p, f)] for p in f["parameters"]])
    combos = _table(["identifiable combination", "factor", "95 % CI"],
                    [[c["label"], f"{c['factor']:.4f}", f"{c['factor_ci95'][0]:.4f} … {c['factor_ci95'][1]:.4f}"]
                     for c in f["combinations"] if not c.get("linear")])
    rows = [[r["plateau"], f"{r['rpm']:.0f}", f"{(r['p_delivery_pa'] - 101325) / 1e5:.2f}",
             f"{m3s_to_lpm(r['flow_measured_m3s']):.3f}", f"{m3s_to_lpm(r0['flow_model_m3s']):.3f}",
             f"{m3s_to_lpm(r['flow_model_m3s']):.3f}", f"{100 * r0['eta_error']:+.2f}", f"{100 * r['eta_error']:+.2f}"]
            for r, r0 in zip(f["plateaus"], f["plateaus_prior"])]
    plateaus = _table(["plateau", "speed [rpm]", "delivery [bar g]", "measured [L/min]", "prior [L/min]",
                       "fitted [L/min]", "η err prior [pt]", "η err fitted [pt]"], rows)
    notes = "".join(f"<p><b>The data cannot separate {html.escape(a)} and {html.escape(b)}</b>: their combination "
                    f"was fitted, their ratio kept at the prior.</p>" for a, b in f["unseparable"])
    ho = result.get("holdout")
    hold = (f"<p>Hold-out: fitted on {len(ho['train'])} plateaus; on the {len(ho['held_out'])} held out "
            f"({html.escape(', '.join(ho['held_out']))}) |η error| max {100 * ho['eta_error_prior']['max_abs']:.2f} pt "
            f"(prior) → {100 * ho['eta_error']['max_abs']:.2f} pt (fitted).</p>") if ho else ""
    v = result.get("verdict")
    verdict = f"<p><b>{html.escape(v['message'])}</b></p>" if v else ""
    page = f"""<!DOCTYPE html><html><head><meta charset="utf-8"><title>gerotor_twin calibration</title>
<style>body{{font-family:sans-serif;font-size:14px;margin:2em}} table{{border-collapse:collapse;margin:1em 0}}
td,th{{border:1px solid #bbb;padding:3px 8px;text-align:right}}</style></head><body>
<h1>Calibration from bench recordings or a steady map</h1>
<p>Data: {html.escape(', '.join(result['bags']))}; prior config {html.escape(result['prior_config'])}; model
{html.escape(result['model'])}; {len(result['plateau_records'])} plateaus;
flow meter at the {html.escape(result.get('flow_meter', 'delivery'))} pressure; {result['date']};
{html.escape(result['software'])}.</p>
{verdict}{params}{combos}{notes}{hold}{_selection(result.get("selection"))}
<img alt="efficiency error per plateau" src="data:image/png;base64,{_figure(result)}">
{plateaus}
<p>Residual variance factor s² = {f['residual_variance_factor']:.3g} (intervals are widened by √s² when the
scatter exceeds the measurement noise); degrees of freedom {f['dof']}.</p></body></html>"""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(page)
    return p
