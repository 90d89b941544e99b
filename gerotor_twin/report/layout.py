"""What the report page shows, in order: :data:`PAGE`, a list of block functions.

Each entry is a function ``ReportContext -> block | list of blocks | None`` returning the
:mod:`.panels` specs (:class:`~.panels.TimeSeries`, :class:`~.panels.Table`, :class:`~.panels.Image`);
blocks in a row with the same ``heading`` share one section.  To add a plot or a table to
the report, write one such function (in its own module if it is large) and insert it here:
the page, its table of contents, the CSV downloads and the Chromium test pick it up.
"""
from __future__ import annotations

from . import figures as F
from . import health_panels as H
from . import tables as T
from . import timeseries as TS
from .context import ReportContext
from .panels import Image

__all__ = ["PAGE", "blocks"]

WHY = "no twin file has the topic"
VERDICT = T.HEADING


def img_plateau_errors(ctx: ReportContext) -> Image:
    return Image("fig-verdict", VERDICT, F.fig_plateau_errors(list(ctx.plateaus), list(ctx.comps),
                                                                list(ctx.verdicts)),
                 "Plateau-mean errors (predicted − measured) against the tolerance band (green); filled circle: "
                 "pass, open cross: fail or no data.", "no plateaus")


def img_efficiency_map(ctx: ReportContext) -> Image:
    return Image("fig-eta-map", "Volumetric efficiency map",
                 F.fig_efficiency_map(list(ctx.comps)) if ctx.plateaus else None,
                 "Volumetric efficiency per plateau [%] over speed and delivery pressure: measured and predicted.",
                 "no plateaus")


def img_waveforms(ctx: ReportContext) -> Image:
    return Image("fig-waveform", "Predicted chamber pressure vs shaft angle, every plateau",
                 F.fig_waveforms(list(ctx.twins), list(ctx.plateaus)),
                 "Pressure of one chamber over one shaft revolution, folded over every revolution the twin logged "
                 "in each plateau (line: mean, band: min–max). A chamber turns with the outer gear, so the one "
                 "shown is, in every revolution and plateau, the chamber in the same place: the one that opens "
                 "to delivery at the same shaft angle.",
                 "no plateaus" if not ctx.plateaus else f"{WHY} /twin/chamber_waveform")


def img_trajectory(ctx: ReportContext) -> Image:
    return Image("fig-trajectory", "Outer-gear trajectory in the clearance circle",
                 F.fig_trajectory(list(ctx.twins), list(ctx.plateaus), ctx.config.clearances.housing_radial_m),
                 "Predicted outer-gear centre displacement inside the radial clearance circle.",
                 f"{WHY} /twin/eccentricity")


def img_gaps(ctx: ReportContext) -> Image:
    return Image("fig-gaps", "Tooth-tip gap height vs shaft angle, every plateau",
                 F.fig_gaps(list(ctx.twins), list(ctx.plateaus), ctx.config),
                 "Tooth-tip gap heights over one revolution at each plateau, from the logged outer-gear "
                 "displacement folded onto one revolution (bold: gap 1, grey: the others).",
                 "no plateaus" if not ctx.plateaus else f"{WHY} /twin/eccentricity")


#: The page, top to bottom (after the headline, downloads and provenance).
PAGE = [
    TS.ts_speed,
    TS.ts_pressure,
    TS.ts_oil_temperature,
    TS.ts_flow,
    TS.ts_residual,
    TS.ts_efficiency,
    H.ts_health_efficiency,
    H.ts_health_leakage,
    H.fault_timeline,
    T.summary_table,
    T.comparison_table,
    T.plateau_tables,
    img_plateau_errors,
    img_efficiency_map,
    img_waveforms,
    img_trajectory,
    img_gaps,
]


def blocks(ctx: ReportContext, page=None) -> list:
    """Evaluate the page's block functions (``page``: default :data:`PAGE`), flattened, ``None`` dropped."""
    out = []
    for fn in page if page is not None else PAGE:
        b = fn(ctx)
        if b is None:
            continue
        out.extend(b if isinstance(b, (list, tuple)) else [b])
    return out
