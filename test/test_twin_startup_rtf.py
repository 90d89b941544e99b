"""The start-up real-time check (gerotor_twin.twin.startup_rtf) and its status in the twin core (no ROS).

Tiers: behaviour; the real-time factor of the stub clocks below is closed form (a machine whose
wall clock runs a fixed multiple of the model time advanced).  No wall-clock time is asserted:
with the real clock only that the figures are finite and positive at the right points.
"""
import math
from pathlib import Path

import pytest

from gerotor_twin.errors import InputError
from gerotor_twin.io import messages as m
from gerotor_twin.twin import TwinCore, TwinSettings
from gerotor_twin.twin import startup_rtf as S

ROOT = Path(__file__).resolve().parent.parent
TOP_RPM, MAX_BAR = 4500.0, 25.0          # a family pump: not the packaged 3000 rpm / 27.5 bar
P_ATM = 101325.0


def family_config(tmp_path, suction_pa=None):
    """The packaged pump with another range (and optionally a pressurised suction)."""
    from gerotor_twin.config import load_config
    text = (ROOT / "config" / "pump.yaml").read_text()
    text = text.replace("max_speed_rpm: 3000.0", f"max_speed_rpm: {TOP_RPM}")
    text = text.replace("max_delivery_bar: 27.5", f"max_delivery_bar: {MAX_BAR}")
    if suction_pa is not None:
        text = text.replace("suction_pressure_pa: 101325.0", f"suction_pressure_pa: {suction_pa}")
    f = tmp_path / "family.yaml"
    f.write_text(text)
    cfg = load_config(f)
    assert (cfg.range.max_speed_rpm, cfg.range.max_delivery_bar) == (TOP_RPM, MAX_BAR)
    return cfg


@pytest.fixture(scope="module")
def family_model(tmp_path_factory):
    from gerotor_twin.model.pump import PumpModel
    return PumpModel(family_config(tmp_path_factory.mktemp("family")), "fixed")


class SlowMachine:
    """The model on a machine whose wall clock runs ``wall_per_sim`` s and CPU ``cpu_per_sim`` s per model second."""

    def __init__(self, model, wall_per_sim, cpu_per_sim):
        self._model, self._k, self._c = model, wall_per_sim, cpu_per_sim
        self.wall = self.cpu = 0.0
        self.calls = []

    def __getattr__(self, name):
        return getattr(self._model, name)

    def advance(self, st, dt, inputs):
        self.calls.append((inputs, dt))
        self.wall += self._k * dt
        self.cpu += self._c * dt
        return self._model.advance(st, dt, inputs)

    def measure(self, threshold, **kw):
        return S.measure(self, threshold, timer=lambda: self.wall, cpu_timer=lambda: self.cpu, **kw)


def test_points_are_top_speed_at_both_pressure_ends(family_model, tmp_path):
    w = TOP_RPM * 2 * math.pi / 60
    pts = S.operating_points(family_model)
    assert [p.omega for p in pts] == pytest.approx([w, w], rel=1e-12)
    # the family grid's pressure ends: 2 bar gauge (10 % of 25 bar is more) and the maximum
    assert [p.p_delivery for p in pts] == pytest.approx([P_ATM + 2e5, P_ATM + MAX_BAR * 1e5], rel=1e-12)
    from gerotor_twin.model.pump import PumpModel
    pressurised = PumpModel(family_config(tmp_path, suction_pa=4.0e5), "fixed")
    assert S.operating_points(pressurised)[0].p_delivery == pytest.approx(4.0e5)     # never below suction


def test_measured_figures_finite_at_the_family_range(family_model):
    """Real clocks: two finite, positive figures at 4500 rpm / 2 and 25 bar, the worst the lower."""
    res = S.measure(family_model, 1.5, budget_s=1.0)
    assert len(res.points) == 2
    for p, bar in zip(res.points, (2.0, MAX_BAR)):
        assert p.speed_rpm == pytest.approx(TOP_RPM) and p.delivery_bar == pytest.approx(bar, abs=1e-9)
        assert math.isfinite(p.rtf) and p.rtf > 0 and math.isfinite(p.cpu_rtf) and p.cpu_rtf > 0
        assert 0 < p.revolutions <= S.REVOLUTIONS + 1e-9 and p.settled_s > 0
    assert res.worst.rtf == min(p.rtf for p in res.points)
    v = res.values()
    assert v["startup_rtf"] == round(res.worst.rtf, 4) and v["startup_rtf_speed_rpm"] == pytest.approx(TOP_RPM)
    assert v["startup_rtf_speed_rad_s"] == pytest.approx(TOP_RPM * math.pi / 30, rel=1e-4)
    assert math.isfinite(v["startup_rtf_cost_s"]) and v["startup_rtf_bearing_model"] == "fixed"


def test_rtf_is_model_time_over_wall_time(family_model):
    """A machine at 2 s of wall and 4 s of CPU per model second: RTF 0.5, CPU RTF 0.25, at every point."""
    slow = SlowMachine(family_model, 2.0, 4.0)
    res = slow.measure(1.5, budget_s=1e3)
    period = 60 / TOP_RPM
    for p in res.points:
        assert p.rtf == pytest.approx(0.5, rel=1e-9) and p.cpu_rtf == pytest.approx(0.25, rel=1e-9)
        assert p.revolutions == pytest.approx(S.REVOLUTIONS, rel=1e-9)
        assert p.settled_s == pytest.approx(S.SETTLE_REVOLUTIONS * period, rel=1e-9)
    assert all(dt <= 0.005 + 1e-15 for _, dt in slow.calls)       # in cells of the twin's sample period
    assert res.below and "RTF 0.5 at 4500 rpm / " in res.message()
    assert "cannot keep real time" in res.message()
    assert res.status()["level"] == m.DIAG_WARN and res.status()["name"] == S.STATUS_NAME
    assert not slow.measure(0.4, budget_s=1e3).below
    ok = slow.measure(0.4, budget_s=1e3).status()
    assert ok["level"] == m.DIAG_OK and ok["message"].startswith("ok")


def test_between_one_and_the_threshold_says_margin_and_busy_machine(family_model):
    """RTF 1.33 (wall) but 5 on the CPU: below the 1.5 margin, and the message says the machine is busy."""
    res = SlowMachine(family_model, 0.75, 0.2).measure(1.5, budget_s=1e3)
    msg = res.message()
    assert res.below and "RTF 1.3 at 4500 rpm" in msg and "margin startup_rtf_threshold = 1.5" in msg
    assert "machine is busy" in msg and "cannot keep real time" not in msg


def test_budget_bounds_the_measurement(family_model):
    """A model 1000x slower than real time with a 1 s budget: one cell settled and one timed per point."""
    slow = SlowMachine(family_model, 1000.0, 1000.0)
    res = slow.measure(1.5, budget_s=1.0)
    assert len(slow.calls) == 4 and [p.simulated_s for p in res.points] == pytest.approx([0.005, 0.005])
    assert res.worst.rtf == pytest.approx(1e-3)


@pytest.mark.parametrize("threshold", [-1.0, 1001.0, float("nan")])
def test_bad_threshold_refused(family_model, threshold):
    with pytest.raises(InputError, match="startup_rtf_threshold"):
        S.measure(family_model, threshold)


def _real_time_statuses(diag):
    return [s for s in diag["status"] if s["name"] == S.STATUS_NAME]


def _feed_and_tick(core, t0_ms, t1_ms):
    w = 1500 * math.pi / 30
    for t in range(t0_ms, t1_ms, 5):
        t_ns = t * 1_000_000 + 1
        core.add_sample("shaft_speed", w, t_ns, t_ns)
        core.add_sample("delivery_pressure", P_ATM + 5e5, t_ns, t_ns)
        core.tick(t_ns)


def test_core_warns_with_the_figure_and_keeps_warning(family_model):
    """Threshold 1000 (never met): a WARN status with the measured figure in every /diagnostics, one event."""
    core = TwinCore(family_model, TwinSettings())
    res = core.measure_startup_rtf(1000.0, budget_s=0.5)
    events = core.pop_events()
    assert events == [(1, res.message())] and f"RTF {res.worst.rtf:.2g} at 4500 rpm / " in events[0][1]
    for k in range(3):                        # before the first tick, and after running: still WARN
        (st,) = _real_time_statuses(core.diagnostics(k * 200_000_000 + 1))
        vals = {kv["key"]: kv["value"] for kv in st["values"]}
        assert st["level"] == m.DIAG_WARN and f"RTF {res.worst.rtf:.2g}" in st["message"]
        assert float(vals["startup_rtf"]) == round(res.worst.rtf, 4) and float(vals["startup_rtf_speed_rpm"]) == TOP_RPM
        assert float(vals["startup_rtf_threshold"]) == 1000.0
        _feed_and_tick(core, k * 200, (k + 1) * 200)
    assert core.status == "running" and core.pop_events() == []     # the event once, the status throughout


def test_core_threshold_zero_measures_nothing(family_model):
    core = TwinCore(family_model, TwinSettings())
    assert core.measure_startup_rtf(0.0) is None
    assert _real_time_statuses(core.diagnostics(1)) == [] and core.pop_events() == []
