"""The error budget's normalisation and the family grid of ``bench accuracy|realtime --family``.

Tiers: CLOSED FORM (the budget figures of hand-made revolutions: a constant offset, a scaled spike) and
BEHAVIOUR (the grid follows each pump's range; the pumps are found, an unknown one is named).
"""
import math
import subprocess
import sys

import numpy as np
import pytest

from gerotor_twin.errors import InputError
from gerotor_twin.model.accuracy import BUDGET, Revolution, compare, within_budget
from gerotor_twin.model.family import family_dir, family_grid, family_pumps, pressure_extremes, speed_extremes

P_ATM = 101325.0


def _revolution(p, q=None, peak=None):
    """A one-chamber revolution of n samples over (0, 2π] with pressures p [Pa]."""
    n = p.size
    theta = 2 * math.pi * np.arange(1, n + 1) / n
    q = np.full(n, 1e-4) if q is None else q
    return Revolution(theta, p.reshape(n, 1).copy(), q, 0.9, float(q.mean()), float(p.max() if peak is None else peak))


def test_rms_is_relative_to_the_reference_range_and_the_peak_to_its_gauge_pressure():
    """Closed form: a reference from 1 bar to a 50-bar spike at 2 bar delivery; the test 0.5 bar above it
    everywhere: RMS / range = 0.5 / 49, peak error 0.5 / 49 (gauge peak 49 bar), RMS of Δp = 0.5 / 1."""
    n = 360
    p = np.full(n, P_ATM + 2e5)
    p[:180] = P_ATM
    p[200] = P_ATM + 49e5                             # the trapped spike
    ref = _revolution(p)
    test = _revolution(p + 0.5e5)
    e = compare(test, ref, P_ATM, P_ATM + 1e5, P_ATM)
    assert e["pressure_range"] == pytest.approx(49e5)
    assert e["rms_pressure_error_of_range"] == pytest.approx(0.5 / 49)
    assert e["max_pressure_error_of_range"] == pytest.approx(0.5 / 49)
    assert e["peak_pressure_error_gauge"] == pytest.approx(0.5 / 49)
    assert e["rms_pressure_error"] == pytest.approx(0.5)
    assert e["flow_rms_error"] == 0.0


def test_the_reference_peak_between_samples_sets_the_range():
    """Closed form: a reference peak above every sample (from the solver's sub-steps) widens the range."""
    p = np.linspace(P_ATM, P_ATM + 10e5, 100)
    ref = _revolution(p, peak=P_ATM + 20e5)
    e = compare(_revolution(p), ref, P_ATM, P_ATM + 10e5, P_ATM)
    assert e["pressure_range"] == pytest.approx(20e5)
    assert e["peak_pressure_error_gauge"] == pytest.approx((10e5 - 20e5) / 20e5)


def test_budget_has_the_four_figures_and_judges_each():
    """Behaviour: the verdict fails on any one figure outside its bound, flow RMS included."""
    assert set(BUDGET) == {"rms_pressure_error_of_range", "peak_pressure_error_gauge", "efficiency_error",
                           "flow_rms_error"}
    row = {k: 0.5 * v for k, v in BUDGET.items()}
    assert within_budget(row)
    for k, v in BUDGET.items():
        assert not within_budget({**row, k: -1.01 * v})


def test_flow_scale_note_restates_the_flow_figures_where_the_mean_flow_vanishes():
    """Closed form: where the reference delivers less than half its theoretical flow the line restates the η and
    flow figures (relative to the mean flow) on the theoretical flow, each times |η_ref|: a worn pump at low speed
    and high pressure delivering −7.9 % reads a flow RMS of 17.27 % of its mean flow, 1.36 % of the theoretical;
    a pump delivering 90 % gets no line."""
    from gerotor_twin.model.accuracy import SMALL_EFFICIENCY, flow_scale_note
    row = {"reference_volumetric_efficiency": -0.079, "efficiency_error": 0.00474, "flow_rms_error": 0.1727}
    note = flow_scale_note(row)
    assert "-7.9%" in note and "flow RMS 1.36%" in note and "η +0.037 pt" in note
    assert flow_scale_note({**row, "reference_volumetric_efficiency": 0.9}) is None
    assert flow_scale_note({**row, "reference_volumetric_efficiency": SMALL_EFFICIENCY}) is None


def test_family_grid_follows_each_pumps_range():
    """Behaviour: every pump of config/pumps/ is found; its grid spans its own range (speeds low / middle /
    top, pressures low / top), the low speed being ``min_speed_rpm`` where given."""
    pumps = family_pumps()
    assert len(pumps) >= 8 and family_dir().name == "pumps"
    for pump in pumps:
        cfg = pump.config
        rpms, bars = family_grid(cfg)
        assert rpms[-1] == cfg.range.max_speed_rpm and bars[-1] == cfg.range.max_delivery_bar
        assert 0 < rpms[0] < rpms[1] < rpms[2] and 0 < bars[0] < bars[1]
        assert speed_extremes(cfg) == (rpms[0], rpms[2]) and pressure_extremes(cfg) == bars
        if cfg.range.min_speed_rpm:
            assert rpms[0] == cfg.range.min_speed_rpm
        assert bars[0] == min(2.0, 0.1 * cfg.range.max_delivery_bar)


def test_unknown_family_pump_is_named():
    """Behaviour: ``--pumps`` with a name not in the family is one error naming it and the choices."""
    names = [p.name for p in family_pumps()]
    assert [p.name for p in family_pumps(names=names[0])] == names[:1]
    with pytest.raises(InputError, match="nosuchpump"):
        family_pumps(names="nosuchpump")
    r = subprocess.run([sys.executable, "-m", "gerotor_twin.cli", "bench", "accuracy", "--family", "--pumps", "nosuch"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "--pumps" in r.stderr and names[0] in r.stderr
