"""Everything a report block may draw from, in one object (built once by :func:`build.build_report`)."""
from __future__ import annotations

from dataclasses import dataclass

from .acceptance import AcceptanceCriterion
from .analysis import Grid, Plateau
from .data import BenchData, TwinData

__all__ = ["ReportContext", "TWIN_COLORS", "TWIN_DASHES", "BENCH_RAW", "MEASURED"]

#: Line colours and dash patterns of the twin files, in --twin order (repeating).
TWIN_COLORS = ("#d62728", "#2b8a3e", "#7b3fb5", "#8c564b")
TWIN_DASHES = ((), (7, 3), (2, 2), (8, 3, 2, 3))
BENCH_RAW = "#8fb3e0"      #: raw bench samples (light, drawn under the means)
MEASURED = "#1f3f8f"       #: measured bench means on the grid


@dataclass(frozen=True)
class ReportContext:
    """Loaded files, the common grid, plateaus, metrics and verdicts of one report.

    ``comps[i]`` is :func:`analysis.compare` of ``twins[i]``; ``verdicts[i][k]`` the
    :func:`acceptance.verdict` of plateau ``k`` for that twin.  Times [s] from the first bench
    message; SI units (blocks convert for display).
    """
    bench: BenchData
    twins: tuple[TwinData, ...]
    grid: Grid
    plateaus: tuple[Plateau, ...]
    comps: tuple[dict, ...]
    verdicts: tuple[tuple[dict, ...], ...]
    config: object                 #: the first twin's pump configuration (config.PumpConfig)
    displacement_m3: float
    criterion: AcceptanceCriterion
    span: tuple[float, float]      #: common time span of bench and twins [s]
    stem: str                      #: file stem for the CSV downloads
    max_points: int

    @property
    def grid_dt(self) -> float:
        """Bin width of the common grid [s]."""
        return float(self.grid.t[1] - self.grid.t[0]) if self.grid.t.size > 1 else 0.1

    def twin_style(self, i: int) -> dict:
        """Colour and dash of twin ``i`` for :class:`panels.Trace`."""
        return {"color": TWIN_COLORS[i % len(TWIN_COLORS)], "dash": TWIN_DASHES[i % len(TWIN_DASHES)]}

    def in_span(self, t, v):
        """The samples of ``(t, v)`` inside the common span (raw traces are cut to it)."""
        s = (t >= self.span[0]) & (t <= self.span[1])
        return t[s], v[s]
