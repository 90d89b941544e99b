"""The parts of the split twin core on their own: revolution recorder and event log (no model run).

Tiers: closed form (flow summary of a known delivered volume, waveform of a
known pressure function) and behaviour (memory bound, rate limiting, worked
out by hand from the calls made).
"""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from gerotor_twin.twin.events import EventLog
from gerotor_twin.twin.outputs import CHAMBER_WAVEFORM, SUMMARY_FIELDS
from gerotor_twin.twin.revolution import Revolution, RevolutionRecorder

MS = 1_000_000


def state(t, vol, theta, n=3):
    """The fields of a PumpState the recorder reads: t [s], volumes[0] [m³], theta [rad], pressures [Pa]."""
    return SimpleNamespace(t=t, volumes=np.array([vol, 0.0]), theta=theta,
                           pressures=np.arange(1.0, n + 2.0) * 1e5)


def test_flow_summary_closed_form():
    """Closed form: 9 cm³ delivered in 0.04 s with 10 cm³/rev: q = 2.25e-4, qth = 2.5e-4 m³/s, η = 0.9."""
    r = Revolution.start(state(1.0, 5e-6, 2 * math.pi), 3)
    q, qth, leak, eta = r.flow_summary(state(1.04, 5e-6 + 9e-6, 4 * math.pi), 10e-6)
    assert q == pytest.approx(2.25e-4, rel=1e-12)
    assert qth == pytest.approx(2.5e-4, rel=1e-12)
    assert leak == pytest.approx(0.25e-4, rel=1e-9)
    assert eta == pytest.approx(0.9, rel=1e-12)
    assert r.flow_summary(state(1.0, 6e-6, 4 * math.pi), 10e-6) is None     # zero duration: no summary


def test_waveform_resamples_a_linear_pressure_exactly():
    """Closed form: p_j(φ) = (j + 1)·1e5 + 1e4·φ is linear, so interpolation on the grid is exact."""
    n, M = 3, 8
    r = Revolution.start(state(0.0, 0.0, 2 * math.pi, n), n)
    phi = np.linspace(0.05, 2 * math.pi, 200)
    r.append(2 * math.pi + phi, np.array([[(j + 1) * 1e5 + 1e4 * f for j in range(n)] for f in phi]))
    table = r.waveform_table(M)
    grid = np.arange(M) * 2 * math.pi / M
    assert np.allclose(table[:, 0], grid, rtol=0, atol=1e-15)
    for j in range(n):
        assert np.allclose(table[:, 1 + j], (j + 1) * 1e5 + 1e4 * grid, rtol=1e-12)
    assert Revolution.start(state(0.0, 0.0, 0.0), n).waveform_table(M) is None   # one row: no waveform


def test_very_long_revolution_keeps_memory_bounded():
    """Behaviour: more than 200 000 rows are thinned by 2, keeping the angle order."""
    r = Revolution.start(state(0.0, 0.0, 0.0, 1), 1)
    for k in range(5):
        ang = np.linspace(k, k + 1, 50_000, endpoint=False) * 1e-3
        r.append(ang, np.zeros((50_000, 1)))
    # 1 + 4 x 50 000 = 200 001 rows > 200 000: thinned to 100 001, then + 50 000
    assert r.rows == 150_001 == sum(map(len, r.theta)) == sum(map(len, r.p)) and len(r.theta) == 2
    assert np.all(np.diff(np.concatenate(r.theta)) >= 0)


def test_recorder_emits_summary_and_waveform_only_after_a_whole_revolution():
    """Behaviour: the first boundary starts a revolution (no messages); a dropped one gives none either."""
    rec = RevolutionRecorder(3, 10e-6, waveform_every=2, waveform_samples=16)
    assert rec.complete(state(0.0, 0.0, 2 * math.pi), 0) == []
    for k in (1, 2):
        rec.record(SimpleNamespace(theta=np.linspace(0.1, 6.2, 50) + 2 * math.pi * k,
                                   chamber_pressures=np.full((50, 3), 2e5)))
        msgs = rec.complete(state(0.04 * k, 9e-6 * k, 2 * math.pi * (k + 1)), k * 40 * MS)
        topics = [m.topic for m in msgs]
        assert (CHAMBER_WAVEFORM in topics) == (k == 2)
        assert all(m.stamp_ns == k * 40 * MS for m in msgs)
    assert dict(zip(SUMMARY_FIELDS, rec.last_summary))["volumetric_efficiency"] == pytest.approx(0.9)
    assert (rec.revolutions, rec.waveforms, rec.nonfinite_suppressed) == (2, 1, 0)
    rec.drop()
    assert rec.complete(state(0.2, 1e-5, 8 * math.pi), 200 * MS) == [] and rec.revolutions == 2


def test_event_log_rate_limits_per_key():
    """Behaviour: one event per (kind, reason) per period; the ones in between are counted in the next."""
    ev = EventLog(period_ns=1000 * MS)
    for k in range(5):
        ev.report("shaft_speed", "nonfinite", 1, "nan", k * 100 * MS)
    ev.report("shaft_speed", "negative", 1, "neg", 200 * MS)         # another key: not limited
    ev.report("model", "lag_skip", 2, "skip", 300 * MS)
    assert ev.pop() == [(1, "nan"), (1, "neg"), (2, "skip")]
    ev.report("shaft_speed", "nonfinite", 1, "nan", 1000 * MS)
    ev.report("shaft_speed", "nonfinite", 1, "nan", 500 * MS)        # clock went back: reported
    assert ev.pop() == [(1, "nan (+4 similar since the last report)"), (1, "nan")]
    assert ev.pop() == []
