"""The outer gear riding on the teeth (model/gear_coupling.py ``hold_contact``).

Tiers: CLOSED FORM (the held velocity keeps the gap of the lobe it presses on at zero to the step's
end, its load gain moves the gear along the contact only, a velocity away from the contact is left
alone; each against the gap expansion evaluated here by central differences, not by the kernel's
gradient) and BEHAVIOUR (the default gear set with new-pump clearances, where the gear rides on the
teeth at every output step, within the peak budget against a fresh tight reference).
"""
import math
from dataclasses import replace

import numpy as np
import pytest

from gerotor_twin.model import gear_coupling as GC
from gerotor_twin.model.accuracy import BUDGET, Revolution, compare, reference_revolution
from gerotor_twin.model.contact import contact, gap_coefficients, gap_value
from gerotor_twin.model.pump import Inputs, PumpModel
from gerotor_twin.model.steady import run_steady

P_ATM = 101325.0
H = 1e-4            # output step [s]


@pytest.fixture(scope="module")
def tight(cfg):
    """The default gear set with the clearances of a new pump (tip 15 µm, lateral 25 µm)."""
    return replace(cfg, clearances=replace(cfg.clearances, tooth_tip_m=15e-6, lateral_m=25e-6))


@pytest.fixture(scope="module")
def on_contact(tight):
    """A mobility model, its coupling set up at a position the overlap check has pulled back onto a lobe."""
    m = PumpModel(tight, "mobility")
    km, ws, n = m.kernel, m._ws, m.N
    inp = Inputs(1000 * math.pi / 30, P_ATM, P_ATM + 20e5)
    s, _ = m.advance(m.initial_state(inp), 0.02, inp)
    theta = 0.3
    gaps, cmat = np.empty(n), np.empty((n, 9))
    e_far = 3.0 * np.asarray(s.eccentricity) + np.array([0.0, 40e-6])     # well into the inner gear
    ex, ey, gam, kc = contact(km.tab, n, km.pc.tip_clearance, theta, e_far[0], e_far[1], gaps, cmat)
    assert (ex, ey) != tuple(e_far) and gam == 0.0                          # pulled back, inner gear unturned
    pres = np.asarray(s.pressures, dtype=float).copy()
    GC.linearise(ex, ey, theta, inp.omega, H, kc, km, pres, ws.gear, ws.gear_rows)
    return m, inp, theta, ex, ey


def _gap(m, theta, k, ex, ey):
    c = np.empty(9)
    gap_coefficients(m.kernel.tab, theta, k, c)
    return gap_value(c, m.kernel.pc.tip_clearance, ex, ey, 0.0)


def _gradient(m, theta, k, ex, ey, d=1e-9):
    return np.array([(_gap(m, theta, k, ex + d, ey) - _gap(m, theta, k, ex - d, ey)) / (2 * d),
                     (_gap(m, theta, k, ex, ey + d) - _gap(m, theta, k, ex, ey - d)) / (2 * d)])


def _press_into_contact(m, theta, ex, ey, speed):
    """Set ė₀ to ``speed`` [m/s] along ê (outwards: into the inner gear) and return the lobe it closes first."""
    gc = m._ws.gear
    u = np.array([ex, ey]) / math.hypot(ex, ey)
    gc[GC.GC_V0X], gc[GC.GC_V0Y] = speed * u
    dth = 1000 * math.pi / 30 * H                                         # ωH of the fixture's speed
    end = [_gap(m, theta, k, ex, ey) + (_gap(m, theta + dth, k, ex, ey) - _gap(m, theta, k, ex, ey))
           + H * _gradient(m, theta, k, ex, ey) @ (speed * u) for k in range(m.N)]
    return int(np.argmin(end)), u, dth


def test_held_velocity_closes_the_pressed_gap_at_the_step_end(on_contact):
    """Closed form: after ``hold_contact`` the gap of the lobe the free velocity presses into reaches zero at
    the end of the step, h_k + H(∇h_k·ė₀ + ∂h_k/∂t) = 0, the change of ė₀ is along ê (the check's direction),
    and ∇h_kᵀG = 0: no change of load presses the gear into that lobe."""
    m, inp, theta, ex, ey = on_contact
    k, u, dth = _press_into_contact(m, theta, ex, ey, 0.05)
    gc = m._ws.gear
    v_free = np.array([gc[GC.GC_V0X], gc[GC.GC_V0Y]])
    GC.hold_contact(gc, m.kernel.tab, m.N, m.kernel.pc.tip_clearance, ex, ey, theta, dth, H)
    v = np.array([gc[GC.GC_V0X], gc[GC.GC_V0Y]])
    grad = _gradient(m, theta, k, ex, ey)
    g0, g1 = _gap(m, theta, k, ex, ey), _gap(m, theta + dth, k, ex, ey)
    assert abs(g0 + H * (grad @ v + (g1 - g0) / H)) < 1e-4 * abs(H * grad @ v_free)
    dv = v - v_free
    assert abs(dv[0] * u[1] - dv[1] * u[0]) < 1e-9 * np.linalg.norm(dv)        # along ê
    assert np.linalg.norm(dv) > 0.1 * np.linalg.norm(v_free)
    G = np.array([[gc[GC.GC_GXX], gc[GC.GC_GXY]], [gc[GC.GC_GYX], gc[GC.GC_GYY]]])
    assert np.linalg.norm(grad @ G) < 1e-6 * np.linalg.norm(grad) * np.linalg.norm(G)
    assert (gc[GC.GC_VX], gc[GC.GC_VY]) == (v[0], v[1])


def test_a_gear_leaving_the_contact_moves_freely(on_contact):
    """Closed form: a velocity that opens every gap is not changed, nor is G."""
    m, inp, theta, ex, ey = on_contact
    _k, _u, dth = _press_into_contact(m, theta, ex, ey, -0.05)
    gc = m._ws.gear
    before = gc.copy()
    GC.hold_contact(gc, m.kernel.tab, m.N, m.kernel.pc.tip_clearance, ex, ey, theta, dth, H)
    assert np.array_equal(gc, before)


@pytest.mark.slow
def test_tight_clearances_within_the_peak_budget(tight):
    """Behaviour: with tip 15 µm / lateral 25 µm the gear rides on the teeth: the overlap check corrects its
    position after 78 % of the output steps (after every one with the free velocity in the stages).  Measured 2026-12-02 at 1000 rpm / 27.5 bar against a fresh
    reference: peak −1.34 % with the gear held on the contact inside the step, −12.0 % with the free velocity
    in the stages and the overlap taken back after each step (the lag this fixes)."""
    rpm, bar = 1000.0, 27.5
    ref = reference_revolution(tight, rpm, bar, "mobility")
    res = run_steady(PumpModel(tight, "mobility"), rpm, bar, max_revolutions=40, rtol=1e-6)
    assert res.state.counts["gear_contact_corrections"] >= 0.5 * res.state.counts["steps"]
    err = compare(Revolution.of(res), ref, P_ATM, P_ATM + bar * 1e5, P_ATM)
    assert abs(err["peak_pressure_error_gauge"]) <= BUDGET["peak_pressure_error_gauge"], err
    assert err["rms_pressure_error_of_range"] <= BUDGET["rms_pressure_error_of_range"], err
