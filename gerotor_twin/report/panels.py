"""Specs of the blocks a report page is made of, and the decimation of long series.

A page is a list of blocks, each rendered by :mod:`.html`:

* :class:`TimeSeries`: an interactive plot over time (uPlot in the page: zoom, pan,
  hover values; all time plots share the cursor and the x range) built from
  :class:`Trace` objects, with optional tolerance :class:`Band` s and shaded
  :class:`Interval` s (e.g. alarm intervals).
* :class:`Table`: columns with units; every table gets a CSV download link.
* :class:`Image`: a static matplotlib PNG (or the reason it is absent).

Long series are decimated for the interactive plots: a trace of more than
``max_points`` samples becomes ``max_points // 2`` buckets of equal time, each
drawn as its minimum and maximum (an envelope, so spikes and noise amplitude
stay visible at any length); the CSV export is not decimated.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Trace", "Band", "Interval", "TimeSeries", "Table", "Column", "Image", "envelope", "DEFAULT_MAX_POINTS"]

#: Largest number of points per trace in an interactive plot (default of ``--max-points``).
DEFAULT_MAX_POINTS = 4000


@dataclass(frozen=True)
class Trace:
    """One line of a time plot, in display units.

    ``csv``: column name with unit (``"speed mean [rpm]"``) when the trace lies on the report's
    common 0.1 s grid and belongs in the aligned-series CSV; ``None`` otherwise (raw traces).
    ``raw``: drawn thin and light, under the means.
    """
    label: str
    t: np.ndarray                 #: [s]
    y: np.ndarray                 #: display units (NaN: gap)
    color: str = "#222"
    width: float = 1.5
    dash: tuple[int, ...] = ()
    raw: bool = False
    csv: str | None = None
    decimals: int = 3             #: shown in the hover legend


@dataclass(frozen=True)
class Band:
    """A filled band between ``lo`` and ``hi`` (NaN: no band there), e.g. a tolerance band."""
    label: str
    t: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    color: str = "rgba(40,160,60,0.18)"     #: fill
    edge: str = "rgba(40,160,60,0.7)"       #: dashed edge lines


@dataclass(frozen=True)
class Interval:
    """A shaded time span of one plot (e.g. an alarm), labelled at its top."""
    t0: float                     #: [s]
    t1: float                     #: [s]
    label: str = ""
    color: str = "rgba(220,50,40,0.15)"


@dataclass(frozen=True)
class TimeSeries:
    """An interactive time plot."""
    id: str
    heading: str                  #: section heading (blocks in a row with the same heading share it)
    y_label: str                  #: quantity [unit]
    traces: tuple[Trace, ...]
    caption: str = ""
    bands: tuple[Band, ...] = ()
    height: int = 260             #: [px]
    zero_line: bool = False
    intervals: tuple[Interval, ...] = ()   #: shaded spans of this plot (the plateaus are shaded in every plot)


@dataclass(frozen=True)
class Column:
    name: str                     #: header, unit in brackets
    fmt: str = "{:.3f}"           #: HTML and CSV format of a number
    align_left: bool = False
    html: bool = True             #: shown on the page (False: CSV only, e.g. long text)
    csv: bool = True              #: in the CSV (False: page only, e.g. a compact form of other columns)


@dataclass(frozen=True)
class Table:
    """A table shown on the page and offered as CSV (``csv_name``: file name of the download)."""
    id: str
    heading: str
    columns: tuple[Column, ...]
    rows: tuple[tuple, ...]
    csv_name: str
    caption: str = ""
    title: str = ""               #: sub-heading (e.g. the twin's label)
    row_classes: tuple[str, ...] = ()   #: CSS class per row ("pass", "fail", "nodata"), optional


@dataclass(frozen=True)
class Image:
    """A static figure: PNG bytes, or ``None`` and the reason in ``missing``."""
    id: str
    heading: str
    png: bytes | None
    caption: str
    missing: str = ""


@dataclass(frozen=True)
class Decimated:
    """A trace reduced for drawing: ``lo == hi`` when not decimated."""
    t: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    per_point: int = 1            #: samples per bucket (1: not decimated)

    @property
    def decimated(self) -> bool:
        return self.per_point > 1


def envelope(t: np.ndarray, y: np.ndarray, max_points: int = DEFAULT_MAX_POINTS) -> Decimated:
    """Min/max envelope of ``y(t)`` in ``max_points // 2`` equal-time buckets (unchanged if short enough).

    Buckets without samples give NaN (a gap).  ``per_point`` is the mean number of samples per
    non-empty bucket.
    """
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    if t.size <= max_points or t.size < 2:
        return Decimated(t, y, y, 1)
    nb = max(1, max_points // 2)
    edges = np.linspace(t[0], t[-1], nb + 1)
    idx = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, nb - 1)
    lo = np.full(nb, np.inf)
    hi = np.full(nb, -np.inf)
    ok = np.isfinite(y)
    np.minimum.at(lo, idx[ok], y[ok])
    np.maximum.at(hi, idx[ok], y[ok])
    empty = ~np.isfinite(lo)
    lo[empty] = np.nan
    hi[empty] = np.nan
    filled = int((~empty).sum())
    return Decimated(0.5 * (edges[:-1] + edges[1:]), lo, hi, max(2, math.ceil(ok.sum() / max(1, filled))))


#: Offset of the gap marker after a plateau [s] (a gap needs its own time; the report grid is 0.1 s).
GAP_S = 0.01


def plateau_steps(plateaus, values: list[float | None]) -> tuple[np.ndarray, np.ndarray]:
    """A piecewise-constant series: ``values[k]`` over plateau k, gaps (NaN) between plateaus."""
    t, y = [], []
    for p, v in zip(plateaus, values):
        v = np.nan if v is None else v
        t += [p.t0, p.t1, p.t1 + GAP_S]
        y += [v, v, np.nan]
    return np.array(t, float), np.array(y, float)
