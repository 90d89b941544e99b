"""Static report figures: readable (no text under 10 px, nothing clipped, fits the page), every
plateau drawn, chamber waveforms folded over revolutions correctly."""
import math

import numpy as np
import pytest

from gerotor_twin.report import figures as F
from gerotor_twin.report.analysis import Plateau
from gerotor_twin.report.build import build_report
from gerotor_twin.report.data import TwinData
from report_helpers import write_bench, write_twin

MIN_PX = 10.0


def _overlapping_ticks(ax, r) -> list[str]:
    out = []
    for axis in (ax.xaxis, ax.yaxis):
        lo, hi = sorted(axis.get_view_interval())
        boxes = [lab.get_window_extent(r) for loc, lab in zip(axis.get_majorticklocs(), axis.get_majorticklabels())
                 if lo <= loc <= hi and lab.get_visible() and lab.get_text()]
        for a, b in zip(boxes, boxes[1:]):
            if a.overlaps(b):
                out.append(f"tick labels overlap on {axis.axis_name} of {ax.get_title()!r}")
                break
    return out


def readability_problems(fig) -> list[str]:
    """Text under MIN_PX, any artist outside the canvas (clipped labels), tick labels on top of each
    other, wider than the page column."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    out = []
    for t in fig.findobj(lambda a: hasattr(a, "get_fontsize") and hasattr(a, "get_text")):
        if t.get_visible() and t.get_text().strip() and (t.axes is None or t.axes.get_visible()):
            px = t.get_fontsize() * fig.dpi / 72
            if px < MIN_PX:
                out.append(f"text {t.get_text()!r} is {px:.1f} px")
    for ax in fig.axes:
        if ax.get_visible():
            out += _overlapping_ticks(ax, r)
    tight = fig.get_tightbbox(r)                      # [in], every drawn artist
    w, h = fig.get_size_inches()
    if tight.x0 < -0.01 or tight.y0 < -0.01 or tight.x1 > w + 0.01 or tight.y1 > h + 0.01:
        out.append(f"artists reach outside the canvas: {tight} vs {w:.2f} x {h:.2f} in")
    if w * fig.dpi > F.MAX_WIDTH_IN * F.DPI + 1:
        out.append(f"{w * fig.dpi:.0f} px wide")
    return out


@pytest.fixture
def captured(monkeypatch):
    """Every figure the report renders, checked before it becomes a PNG."""
    seen = []
    png = F.figure_png

    def checking_png(fig):
        shown = [ax for ax in fig.axes if ax.get_visible()]
        seen.append(([ax.get_title() for ax in shown], readability_problems(fig),
                     [len(ax.get_lines()) for ax in shown]))
        return png(fig)
    monkeypatch.setattr(F, "figure_png", checking_png)
    return seen


def test_report_figures_are_readable(tmp_path, captured):
    """Behaviour: all figures of a two-twin report pass the readability check."""
    b = write_bench(tmp_path / "b.mcap")
    ts = [write_twin(tmp_path / f"t{i}.mcap", offset_m3s=o) for i, o in enumerate((1e-5, -2e-5))]
    build_report(b, ts, tmp_path / "r.html", labels=["model A", "model B"])
    assert len(captured) == 5
    assert [c[1] for c in captured] == [[]] * 5, captured


def _comp(label, n, shift):
    rows = [{"rpm": 1000 + 1000 * (k % 3), "bar": 5 + 7.5 * (k % 12 // 3), "eta_measured": 0.9 - 0.01 * (k % 12),
             "eta_predicted": 0.9 - 0.01 * (k % 12) + shift, "flow_error_m3s": {"bias": shift * 1e-4},
             "plateaus": k + 1} for k in range(n)]
    return {"label": label, "plateaus": rows}


@pytest.mark.parametrize("n", [12, 120])
def test_efficiency_map_and_verdict_chart_readable_at_size(captured, n):
    """Behaviour: 12 and 120 plateaus (12 points visited 10 times) and three twins (four map panels,
    wrapped) still fit and read. The map's x label was cut off before (issue 14)."""
    comps = [_comp(f"a long twin label {i}", n, 0.01 * i) for i in range(3)]
    ps = [Plateau(k + 1, 0, 1, k, k + 0.5, 1000, 5) for k in range(n)]
    verdicts = [[{"verdict": "pass" if k % 2 else "fail", "flow_tol_m3s": 1e-5, "eta_tol": 0.01}
                 for k in range(n)]] * 3
    assert F.fig_efficiency_map(comps) and F.fig_plateau_errors(ps, comps, verdicts)
    assert [c[1] for c in captured] == [[], []], captured


N, S = 7, 72


def _step(ang, rise_deg):
    """1 bar g from ``rise_deg`` for 120°, else 0 [Pa abs]."""
    d = (np.degrees(ang) - rise_deg) % 360
    return 101325.0 + np.where(d < 120, 1e5, 0.0)


def _rolled_twin(revs=9):
    """Chamber j of revolution r holds the waveform of chamber (j + r) mod N of revolution 0: the
    labels move by one chamber per revolution, as in a gerotor; chamber j rises at 30 + 50 j deg."""
    ang = np.arange(S) * 2 * math.pi / S
    base = np.column_stack([_step(ang, 30 + 50 * j) for j in range(N)])
    tabs = [np.column_stack([ang, np.roll(base, -r, axis=1)]) for r in range(revs)]
    t = 1.0 + 0.06 * np.arange(revs)
    return TwinData("x", "x", (t, np.zeros((revs, 4))), waveforms=(t, np.array(tabs))), ang


def test_folded_waveform_follows_one_chamber_place():
    """Closed form: folding picks, in every revolution, the chamber that rises nearest 90 deg
    (chamber 1 of revolution 0: 80 deg), so min = max = mean = that step."""
    tw, ang = _rolled_twin()
    a, mean, lo, hi, n, rise = F.folded_waveform(tw, Plateau(1, 0, 1, 0.9, 2.0, 1000, 1))
    assert n == 9 and rise == pytest.approx(80, abs=360 / S)
    want = _step(ang, 80)
    np.testing.assert_array_equal(lo, want)
    np.testing.assert_array_equal(hi, want)
    np.testing.assert_array_equal(mean, want)
    a, mean, *_ , rise = F.folded_waveform(tw, Plateau(1, 0, 1, 0.9, 2.0, 1000, 1), rise_deg=235)
    assert rise == pytest.approx(230, abs=360 / S)                 # chamber 4: 30 + 200 deg
    np.testing.assert_array_equal(mean, _step(ang, 230))


def test_every_plateau_gets_a_waveform_and_gap_panel(tmp_path, captured):
    """Behaviour: one small panel per operating point in both angle figures (not a chosen few);
    repeated visits of a point share its panel, every visit drawn."""
    from gerotor_twin.config import load_config
    from gerotor_twin.report.data import load_twin
    from report_helpers import T0
    tw = load_twin(write_twin(tmp_path / "t.mcap", duration=12.0), T0)
    ps = [Plateau(k + 1, 0, 1, 0.5 + k, 1.4 + k, 1000 + 500 * (k % 5), 10) for k in range(7)]
    assert F.fig_waveforms([tw], ps) and F.fig_gaps([tw], ps, load_config())
    (wave, p1, n1), (gaps, p2, n2) = captured
    assert p1 == p2 == []
    assert wave[2] == "#3: 2000 rpm, 10.0 bar, 15 rev"           # 15 waveforms logged in 2.5-3.4 s
    for titles in (wave, gaps):
        assert titles[0] == "#1, #6\n1000 rpm, 10.0 bar" and titles[1] == "#2, #7\n1500 rpm, 10.0 bar"
        assert [t.split(":")[0] for t in titles[2:]] == ["#3", "#4", "#5"]
    assert n1 == [2, 2, 1, 1, 1]                                  # one mean line per visit
    assert n2 == [8, 8, 7, 7, 7]                                  # + the 6 other gaps once per panel


def test_efficiency_map_shows_the_mean_of_repeated_visits(captured, monkeypatch):
    """Closed form: two visits of one point with η 90 % and 92 % are one marker labelled 91.0 (2×)."""
    rows = [{"rpm": 1000, "bar": 5.0, "eta_measured": 0.90, "eta_predicted": 0.90},
            {"rpm": 2000, "bar": 5.0, "eta_measured": 0.95, "eta_predicted": 0.95},
            {"rpm": 1005, "bar": 5.1, "eta_measured": 0.92, "eta_predicted": 0.92}]
    import matplotlib.axes
    texts, orig = [], matplotlib.axes.Axes.annotate

    def spy(self, text, *a, **k):
        texts.append(text)
        return orig(self, text, *a, **k)
    monkeypatch.setattr(matplotlib.axes.Axes, "annotate", spy)
    F.fig_efficiency_map([{"label": "t", "plateaus": rows}])
    assert texts == ["91.0 (2×)", "95.0"] * 2


def test_group_plateaus():
    """Behaviour: same point within 2 % speed and 0.5 bar, in order of first visit."""
    ps = [Plateau(1, 0, 1, 0, 1, 1000, 5.0), Plateau(2, 0, 1, 0, 1, 2000, 5.0), Plateau(3, 0, 1, 0, 1, 1015, 5.4),
          Plateau(4, 0, 1, 0, 1, 1030, 5.0), Plateau(5, 0, 1, 0, 1, 1000, 5.6)]
    assert [[p.index for p in g] for g in F.group_plateaus(ps)] == [[1, 3], [2], [4], [5]]
