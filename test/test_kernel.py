"""The compiled kernel: Jacobian, state equation, pure-Python path (closed form / behaviour tiers)."""
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gerotor_twin.hydraulics.fluid import log_density
from gerotor_twin.hydraulics.state_equation import log_density_of, pressure_of
from gerotor_twin.model import flows as F
from gerotor_twin.model import kernel as K
from gerotor_twin.model import step_control as SC
from gerotor_twin.model.params import CT_GEO_OK, CT_GEO_THETA, operating
from gerotor_twin.model.pump import Inputs, PumpModel

ROOT = Path(__file__).resolve().parent.parent
P_ATM = 101325.0


@pytest.fixture(scope="module")
def warm(cfg):
    """Mobility model at its periodic state, 3000 rpm / 27.5 bar."""
    m = PumpModel(cfg, "mobility")
    inp = Inputs(3000 * math.pi / 30, P_ATM, P_ATM + 27.5e5)
    s, _ = m.advance(m.initial_state(inp), 0.1, inp)
    return m, inp, s


def _rhs(m, op, y, theta, gaps, km=None):
    """(f, ∂f/∂y, ∂f/∂t) of the kernel's right-hand side (∂f/∂t: ``jac``'s column N+1 and the closing ports'
    shares, in full as for a sub-step shorter than their time to close)."""
    ws = m._ws
    f = np.empty(m.N + 1)
    jac = np.empty((m.N + 1, m.N + 1 + F.N_JAC_EXTRA))
    F.rhs(y, theta, gaps, m.kernel if km is None else km, op, ws, f, jac, True)
    F.closing_ports((m.kernel if km is None else km).pc, op, ws.p, ws.rho, ws.geo, jac, 1.0)      # every closing port
    ws.jac[:] = jac
    f_t = np.empty(m.N + 1)
    F.closing_share(m.N, 1e-30, ws.jac, f_t)
    return f, jac[:, :m.N + 1].copy(), f_t


def _fd_jacobian(m, op, y, theta, gaps):
    n1 = m.N + 1
    fd = np.empty((n1, n1))
    for k in range(n1):
        d = 1e-9                  # ≈ 1.5 Pa in the liquid, 1.5 mPa where β is small
        yp, ym = y.copy(), y.copy()
        yp[k] += d
        ym[k] -= d
        fd[:, k] = (_rhs(m, op, yp, theta, gaps)[0] - _rhs(m, op, ym, theta, gaps)[0]) / (2 * d)
    return fd


def _check_jacobian(m, op, y, theta, gaps):
    """Analytic ∂f/∂y vs central differences, entry by entry relative to the row's largest entry.

    The analytic Jacobian is exact (flows and density ratios, flows.transfer); what is left is
    the difference quotient's own error, far below the bound 1e-4 of the row scale.
    """
    _, jac, _ = _rhs(m, op, y, theta, gaps)
    fd = _fd_jacobian(m, op, y, theta, gaps)
    rows = range(m.N + 1) if m.restriction_mode else range(m.N)
    for j in rows:
        scale = np.abs(fd[j]).max()
        assert scale > 0
        assert np.abs(jac[j] - fd[j]).max() <= 1e-4 * scale, (j, jac[j], fd[j])
    return jac, fd


def test_jacobian_matches_finite_differences_in_the_liquid_and_at_port_edges(warm):
    """Behaviour: the Jacobian of the running pump at several angles, among them port edges."""
    m, inp, s = warm
    op = operating(m.kernel, inp.omega, inp.p_suction, inp.p_delivery)
    gaps, _, _ = m.gaps(s.theta, s.eccentricity)
    tab = m.tables
    edge_seen = False
    for theta in np.linspace(s.theta, s.theta + tab.shift, 9):
        areas = [(tab.column("AS", theta, j), tab.column("AD", theta, j)) for j in range(m.N)]
        amax = tab.data[2].max()
        edge_seen |= any(0 < a < 0.05 * amax for pair in areas for a in pair)
        _check_jacobian(m, op, s.log_density, theta, m.gaps(theta, s.eccentricity)[0])
    assert edge_seen, "no angle with a port edge (open area < 5 % of its maximum) was checked"


@pytest.mark.parametrize("law", ["flow_number", "merritt"])
def test_area_derivative_of_the_orifice_laws_matches_central_differences(law):
    """Closed form: ∂Q/∂A = (Q/2 + Δp ∂Q/∂Δp)/A (both laws: Q(Δp/s², s²A) = s Q(Δp, A)) against central
    differences in A, laminar to turbulent and both flow directions; 0 for a closed port."""
    from gerotor_twin.hydraulics.orifice import ORIFICE_LAWS, port_orifice_flow
    lw = ORIFICE_LAWS[law]

    def q(dp, a):
        return port_orifice_flow(dp, a, lw, 0.7, 1000.0, 0.2, 870.0, 0.04)

    for area in (1e-10, 1e-8, 1e-6, 2e-5):
        for dp in (-27e5, -3e3, 1.0, 50.0, 1e4, 27e5):
            qq, dq = q(dp, area)
            h = 1e-6 * area
            fd = (q(dp, area + h)[0] - q(dp, area - h)[0]) / (2 * h)
            assert F.area_derivative(qq, dq, dp, area) == pytest.approx(fd, rel=1e-6, abs=1e-12 * abs(qq) / area)
    assert F.area_derivative(0.0, 0.0, 1e5, 0.0) == 0.0


def test_time_derivative_matches_finite_differences_in_shaft_angle(warm):
    """Behaviour: ∂f/∂t (column N+1 of ``jac`` and the closing ports' shares, non-autonomous ROS2) against ω·(f(θ+δ) − f(θ−δ))/2δ at
    fixed state and gaps, at several angles among them port edges, each chamber inside one table cell.

    Exact there when what ∂f/∂t leaves out is switched off: the θ-dependence of the tooth-tip flows
    (``tip_flow_factor`` 0, lateral leakage kept) and of the displaced-volume terms (centred gear).
    Closing ports are among those checked (their share in full, as for a sub-step shorter than their
    time to close)."""
    m, inp, s = warm
    km = m.kernel._replace(pc=m.kernel.pc._replace(tip_flow_factor=0.0))
    op = operating(km, inp.omega, inp.p_suction, inp.p_delivery)
    disp = m._ws.disp.copy()
    m._ws.disp[:] = 0.0
    tab = m.tables
    cell = tab.period / tab.size
    gaps = m.gaps(s.theta, s.eccentricity)[0]
    edges = closing = 0
    try:
        for theta in np.linspace(s.theta, s.theta + tab.shift, 23):
            x = [((theta + j * tab.shift) % tab.period) / cell % 1.0 for j in range(m.N)]
            if min(x) < 0.01 or max(x) > 0.99:
                continue                       # a chamber on a table node: the slope jumps there
            d = 1e-3 * cell                    # truncation ≲ 1e-8; 1e-4 let round-off reach 1e-5 in the delivery row
            f_t = _rhs(m, op, s.log_density, theta, gaps, km)[2]
            fd = inp.omega * (_rhs(m, op, s.log_density, theta + d, gaps, km)[0]
                              - _rhs(m, op, s.log_density, theta - d, gaps, km)[0]) / (2 * d)
            scale = np.abs(fd[:m.N]).max()                   # chambers [1/s²]; the delivered volume [m³/s²]
            assert np.abs(f_t[:m.N] - fd[:m.N]).max() <= 1e-5 * scale, (theta, f_t, fd)
            assert abs(f_t[m.N] - fd[m.N]) <= 1e-5 * abs(fd[m.N]) + 1e-12, (theta, f_t[m.N], fd[m.N])
            edges += any(0 < tab.column(c, theta, j) < 0.05 * tab.data[2].max()
                         for j in range(m.N) for c in ("AS", "AD"))
            closing += int(np.count_nonzero(m._ws.jac[:m.N, [m.N + 1 + F.J_TCS, m.N + 1 + F.J_TCD]] > 0))
    finally:
        m._ws.disp[:] = disp
    assert edges, "no angle with a port edge (open area < 5 % of its maximum) was checked"
    assert closing, "no closing port was checked"


def test_the_tables_are_read_once_per_angle_and_never_stale(warm):
    """Behaviour: the right-hand side keeps the geometry tables' values of the angle it last read in ``ws.geo`` (a
    sub-step's second stage and the next first stage are at one angle: ``flows.chamber_geometry``). After a
    revolution of output steps they are the last first stage's, bit for bit what a fresh read gives; at another
    angle, with another table at the same angle, or with the gear moved, the right-hand side gives what a fresh
    read gives, never the kept values."""
    m, inp, s = warm
    op = operating(m.kernel, inp.omega, inp.p_suction, inp.p_delivery)
    ws = m._ws
    s, _ = m.advance(s, 2 * math.pi / inp.omega, inp)
    assert ws.ctrl[CT_GEO_OK] == 1.0 and ws.ctrl[CT_GEO_THETA] == s.theta
    gaps = m.gaps(s.theta, s.eccentricity)[0]

    def fresh(theta, km):
        ws.ctrl[CT_GEO_OK] = 0.0
        out = _rhs(m, op, s.log_density, theta, gaps, km)[0]
        return out, ws.geo.copy()

    kept = ws.geo.copy()
    f_fresh, geo_fresh = fresh(s.theta, m.kernel)
    assert np.array_equal(kept, geo_fresh)
    other = m.kernel._replace(tab=m.kernel.tab._replace(rows=m.kernel.tab.rows * 1.01))
    cases = [(s.theta + 1e-3, m.kernel, None), (s.theta, other, None), (s.theta, m.kernel, 1e-6)]
    for theta, km, move in cases:
        fresh(s.theta, m.kernel)                            # the kept values: those of s.theta, m's tables
        if move is not None:
            ws.disp[0] += move
        f, _j, _t = _rhs(m, op, s.log_density, theta, gaps, km)
        got = ws.geo.copy()
        f_ref, geo_ref = fresh(theta, km)
        assert np.array_equal(got, geo_ref) and np.array_equal(f, f_ref)
        assert not np.array_equal(f, f_fresh)
        if move is not None:
            ws.disp[0] -= move


def test_closing_port_share_stops_at_the_closing_angle(warm):
    """Closed form: a closing port's share of ∂f/∂t is taken in full for a sub-step shorter than its time to
    close t_c = A / (−dA/dθ · ω) and scaled by t_c/h for a longer one, so that its linearised flow stops at
    zero area instead of running on through a negative one."""
    m, inp, s = warm
    op = operating(m.kernel, inp.omega, inp.p_suction, inp.p_delivery)
    ws, tab, n = m._ws, m.tables, m.N
    c = n + 1                                   # first column after ∂f/∂y
    for theta in np.linspace(s.theta, s.theta + tab.shift, 23):
        _rhs(m, op, s.log_density, theta, m.gaps(theta, s.eccentricity)[0])
        g = ws.jac
        closing = [j for j in range(n) if g[j, c + F.J_TCD] > 0 and g[j, c + F.J_CD] != 0 and g[j, c + F.J_TCS] == 0]
        if closing:
            break
    assert closing, "no closing delivery port with flow in a chamber period"
    j = closing[0]
    tc = g[j, c + F.J_TCD]
    assert tc == pytest.approx(tab.column("AD", theta, j) / (-ws.geo[j, F.G_DAD] * inp.omega), rel=1e-9)
    base = g[:, c + F.J_FT].copy()
    short, long = np.empty(n + 1), np.empty(n + 1)
    F.closing_share(n, 0.5 * tc, ws.jac, short)
    F.closing_share(n, 4.0 * tc, ws.jac, long)
    assert short[j] - base[j] == pytest.approx(g[j, c + F.J_CD], rel=1e-12)
    assert long[j] - base[j] == pytest.approx(0.25 * g[j, c + F.J_CD], rel=1e-12)
    tcd = g[:n, c + F.J_TCD]                   # 0: not closing within the horizon, no share moved
    share = np.where(tcd > 0, np.minimum(1.0, tcd / (4 * tc)), 0.0)
    assert long[n] - base[n] == pytest.approx(np.sum(np.where(tcd > 0, g[:n, c + F.J_CDN], 0.0) * share),
                                              rel=1e-12)


def test_error_weights_tighter_on_a_chamber_whose_delivery_port_closes_or_suction_port_seals(warm):
    """Closed form: with the pressure measure the weight of volume i is max(β_i / (tol·Δp_ref), 1/tol_lnρ),
    Δp_ref = max(p_d − p_s, 1 bar, the chamber pressures' recent range carried in the state);
    for a chamber whose delivery port is closing within the horizon H or has just opened (within H/4: its age
    A_d / (ω dA_d/dθ), the time to close backwards in time) tol is multiplied by
    ``numerics.closing_tolerance`` (0.15 in the packaged config) and β_i replaced by max(β_i, β(p_d)) (its ln ρ
    error counts as it will at delivery pressure), elsewhere not; a chamber whose suction port closes within H
    is weighed with max(β_i, β(p_d)) at tol (it is sealed next and then filled to delivery pressure).  The flags
    are computed here from the port areas and slopes, apart from the code under test (``step_control.port_event``,
    ``flows.time_to_close``)."""
    m, inp, s = warm
    km = m.kernel
    pc = km.pc
    assert pc.closing_tolerance == m.config.numerics.closing_tolerance == 0.15
    op = operating(km, inp.omega, inp.p_suction, inp.p_delivery)
    ws, n = m._ws, m.N
    horizon = 1.0                                            # [s]: every closing port counts; opened: 0.25 s
    ws.ctrl[K.CT_RANGE] = s.pressure_range                  # the error scale of the state's next step
    scale = max(inp.p_delivery - inp.p_suction, 1e5, s.pressure_range)
    assert s.pressure_range > inp.p_delivery - inp.p_suction          # the range is the scale here
    seen = {True: 0, False: 0}
    for theta in np.linspace(s.theta, s.theta + m.tables.shift, 23):
        _rhs(m, op, s.log_density, theta, m.gaps(theta, s.eccentricity)[0])     # ws.geo: areas and slopes
        SC.error_weights(km, op, ws, horizon)
        for j in range(n):
            a, slope = ws.geo[j, F.G_AD], ws.geo[j, F.G_DAD]
            closes = a > 0 and slope < 0 and a / (-slope * op.omega) < horizon
            opened = a > 0 and slope > 0 and a / (slope * op.omega) < 0.25 * horizon
            closing = closes or opened
            a_s, slope_s = ws.geo[j, F.G_AS], ws.geo[j, F.G_DAS]
            sealing = not closing and a_s > 0 and slope_s < 0 and a_s / (-slope_s * op.omega) < horizon
            if opened:
                seen["opened"] = seen.get("opened", 0) + 1
            if sealing:
                seen["sealing"] = seen.get("sealing", 0) + 1
            tol = pc.tolerance * (pc.closing_tolerance if closing else 1.0)
            beta = max(ws.beta[j], op.beta_d) if closing or sealing else ws.beta[j]
            want = max(beta / (tol * scale), 1.0 / pc.log_density_tolerance)
            assert ws.wt[j] == pytest.approx(want, rel=1e-12), (theta, j, closing)
            seen[closing] += beta / (tol * scale) > 1.0 / pc.log_density_tolerance
            if closing and ws.beta[j] < 0.5 * op.beta_d:                 # a just-opened chamber, still soft
                seen["soft"] = seen.get("soft", 0) + 1
    assert seen[True] and seen[False] and seen["opened"] and seen["soft"] and seen["sealing"], seen


def test_defect_threshold_is_the_smallest_sub_step_over_which_a_closing_port_needs_the_check(warm):
    """Closed form: at a first stage ``step_control.defect_threshold`` sets the sub-step above which the defect check
    runs to min over the chambers' suction and delivery ports that close within two output steps H (t_c = A /
    (−ω dA/dθ) < 2H; no sub-step is longer than H) of max(t_c / 2, 1 / (γ |∂Q/∂Δp| β / V)): the area halves within
    the sub-step and the port holds its chamber stiff on its scale; ∞ where no port closes so soon.  Computed here
    from the port areas, slopes, pressures and the orifice law apart from the code under test."""
    from gerotor_twin.hydraulics.orifice import port_orifice_flow
    from gerotor_twin.model.params import CT_DEFECT_H
    m, inp, s = warm
    km = m.kernel
    pc = km.pc
    op = operating(km, inp.omega, inp.p_suction, inp.p_delivery)
    ws, n = m._ws, m.N
    big_h = m.step_size(inp.omega)
    gamma = 1.0 + 1.0 / math.sqrt(2.0)
    seen = {"finite": 0, "none": 0}
    for theta in np.linspace(s.theta, s.theta + m.tables.shift, 41):
        _rhs(m, op, s.log_density, theta, m.gaps(theta, s.eccentricity)[0])
        SC.defect_threshold(km, op, ws, big_h)
        want = math.inf
        for j in range(n):
            for a, slope, dp in ((ws.geo[j, F.G_AS], ws.geo[j, F.G_DAS], op.p_s - ws.p[j]),
                                 (ws.geo[j, F.G_AD], ws.geo[j, F.G_DAD], ws.p[n] - ws.p[j])):
                if a > 0 and slope < 0 and a / (-slope * op.omega) < 2.0 * big_h:
                    _q, dq = port_orifice_flow(dp, a, pc.orifice_law, pc.cd_max, pc.lambda_crit, pc.laminar_delta,
                                               pc.density, pc.viscosity)
                    rate = abs(dq) * ws.beta[j] / ws.geo[j, F.G_V]
                    want = min(want, max(0.5 * a / (-slope * op.omega), 1.0 / (gamma * rate)))
        got = ws.ctrl[CT_DEFECT_H]
        if math.isinf(want):
            assert math.isinf(got), theta
            seen["none"] += 1
        else:
            assert got == pytest.approx(want, rel=1e-12), theta
            seen["finite"] += 1
            assert SC.port_filtered(ws, 1.01 * got) and not SC.port_filtered(ws, 0.99 * got)
    assert seen["finite"] and seen["none"], seen


@pytest.fixture(scope="module")
def warm_paper(cfg):
    """As ``warm`` with the paper's fluid model (eq. (23))."""
    m = PumpModel(cfg.with_fluid_model("paper"), "mobility")
    inp = Inputs(3000 * math.pi / 30, P_ATM, P_ATM + 27.5e5)
    s, _ = m.advance(m.initial_state(inp), 0.1, inp)
    return m, inp, s


def test_jacobian_matches_finite_differences_inside_the_switch_band(warm_paper):
    """Behaviour: suction chambers placed inside the β switch band (p_atm ± band/2) and on the floor."""
    m, inp, s = warm_paper
    eos = m.kernel.eos
    op = operating(m.kernel, inp.omega, inp.p_suction, inp.p_delivery)
    y = s.log_density.copy()
    theta = s.theta
    suction = [j for j in range(m.N) if m.tables.column("AS", theta, j) > 0]
    assert suction
    for target in (eos.p_atm - 0.3 * eos.band, eos.p_atm + 0.2 * eos.band, eos.p_lo - 20e3):
        for j in suction:
            y[j] = log_density_of(target, eos)
        _check_jacobian(m, op, y, theta, m.gaps(theta, s.eccentricity)[0])


def test_jacobian_in_restriction_mode(cfg):
    """Behaviour: the delivery volume is a state behind the restriction (sec. 4): its row too."""
    from dataclasses import replace
    c = replace(cfg, boundary=replace(cfg.boundary, mode="restriction"))
    m = PumpModel(c, "fixed")
    inp = Inputs(1000 * math.pi / 30, P_ATM, P_ATM)
    s, _ = m.advance(m.initial_state(inp), 0.05, inp)
    op = operating(m.kernel, inp.omega, inp.p_suction, inp.p_delivery)
    _check_jacobian(m, op, s.log_density, s.theta, m.gaps(s.theta, s.eccentricity)[0])


def test_delivery_flow_keeps_the_line_mass_balance_in_restriction_mode(cfg):
    """Closed form (the delivery line's mass balance): in restriction mode (sec. 4) the line's ln ρ is a state, so
    over a revolution of a periodic state what the ports deliver (less the leakages: ``delivery_flow``) leaves
    through the restriction, and the two flows' means over the output rows agree.  The recorded delivery flow is
    the line's rate from the stepper's stages plus the restriction's flow (``kernel._delivery_flow``): 2e-5
    apart (default pump, mobility, 2000 rpm, 2e-5 m² to atmosphere, 2026-12-07).  Sampled from the right-hand side
    at each output step's end it was 1.1e-3 apart: the chambers open to the delivery port carry their pressure
    error into it multiplied by the port's conductance (docs/numerics.md, "The delivery flow at the output
    points"); so was the delivered volume (η), the trapezoid of those samples, until it was taken from the line's
    state: its volume times the change of its ln ρ plus the restriction's outflow."""
    from dataclasses import replace
    c = replace(cfg, boundary=replace(cfg.boundary, mode="restriction"))
    m = PumpModel(c, "mobility")
    inp = Inputs(2000 * math.pi / 30, P_ATM, P_ATM)
    period = 2 * math.pi / inp.omega
    s, _ = m.advance(m.initial_state(inp), 30 * period, inp)
    s, o = m.advance(s, period, inp)
    assert o.delivery_pressure.mean() > P_ATM + 5e5                      # the restriction holds a pressure
    assert o.delivery_flow.mean() == pytest.approx(o.restriction_flow.mean(), rel=2e-4)
    # and the delivered volume (η) is what the line stored and passed on, not the trapezoid of the samples (1.1e-3)
    assert o.volumetric_efficiency * o.theoretical_flow == pytest.approx(o.restriction_flow.mean(), rel=2e-4)


def test_jacobian_matches_finite_differences_in_the_mixture_at_low_pressure(warm):
    """Behaviour: suction chambers of the mixture model in its table (0.3 bar) and below it (Newton, 5 kPa)."""
    m, inp, s = warm
    eos = m.kernel.eos
    assert eos.kind == 1          # the default fluid model is the mixture
    op = operating(m.kernel, inp.omega, inp.p_suction, inp.p_delivery)
    y = s.log_density.copy()
    theta = s.theta
    suction = [j for j in range(m.N) if m.tables.column("AS", theta, j) > 0]
    for target in (0.3e5, 5e3):
        for j in suction:
            y[j] = log_density_of(target, eos)
        _check_jacobian(m, op, y, theta, m.gaps(theta, s.eccentricity)[0])


def test_pressure_of_inverts_the_mixture(cfg):
    """Closed form: p(s) of the kernel (Hermite table / Newton) against the closed-form s(p) of the mixture,
    and β of state_of against the closed-form β(p)."""
    from gerotor_twin.hydraulics.mixture import mixture_bulk_modulus, mixture_log_density
    from gerotor_twin.hydraulics.state_equation import state_of
    eos = PumpModel(cfg, "fixed").kernel.eos
    args = (eos.beta_liquid, eos.air_fraction, eos.polytropic_index, eos.p_vap, eos.p_atm)
    rng = np.random.default_rng(3)
    pressures = np.concatenate([eos.p_vap + np.geomspace(1e-3, 8e3, 50),      # Newton below p_vap + 300 Pa, table above
                                rng.uniform(1e4, 3e5, 200),                     # around atmospheric
                                rng.uniform(3e5, 4e6, 100), [6e7, 2e8]])        # delivery, above the table
    for p in pressures:
        s = mixture_log_density(p, *args)
        assert abs(pressure_of(s, eos) - p) <= 0.02, p       # stated table error: ≤ 0.011 Pa measured
        pk, bk = state_of(s, eos)
        assert bk == pytest.approx(mixture_bulk_modulus(pk, *args)[0], rel=3e-6), p   # ≤ 2.1e-6 measured
        assert log_density_of(p, eos) == s
    assert pressure_of(-1e3, eos) >= eos.p_vap


def test_pressure_of_inverts_the_exact_state_equation(cfg):
    """Closed form: p(s) of the kernel against bisection on the exact s(p) (quadrature), all regions."""
    from gerotor_twin.model.params import kernel_model
    m = PumpModel(cfg.with_fluid_model("paper"), "fixed")
    eos = m.kernel.eos
    f = cfg.fluid
    args = (f.bulk_modulus_pa, f.cavitation_ratio, f.atmospheric_pa, f.switch_band_pa, f.vapour_pressure_pa)
    rng = np.random.default_rng(7)
    pressures = np.concatenate([rng.uniform(eos.p_lo, eos.p_hi, 300),          # switch band
                                rng.uniform(f.vapour_pressure_pa + 10, eos.p_lo, 100),   # vapour floor
                                rng.uniform(eos.p_hi, 40e5, 100)])            # liquid
    for p in pressures:
        s = log_density(p, *args)
        assert abs(pressure_of(s, eos) - p) <= 2e-4 + 1e-12 * p, p   # stated: Hermite table error ≤ 2e-4 Pa
        assert log_density_of(p, eos) == pytest.approx(s, abs=1e-15)
    assert kernel_model  # the structure builder is importable on its own


def test_hermite_coefficients():
    """Closed form: the table's per-interval cubic interpolates p and dp/ds at the nodes and reproduces any cubic
    p(s) exactly (a Hermite cubic is exact for cubics), p and dp/ds, with the table's lookup (``state_of``)."""
    from gerotor_twin.hydraulics.state_equation import MIXTURE, StateEquation, hermite_coefficients, state_of
    s_lo, s_hi, n = -0.2, 0.05, 11
    nodes = np.linspace(s_lo, s_hi, n)

    def cubic(s):
        return 2e5 + 3e7 * s - 4e8 * s ** 2 + 9e9 * s ** 3, 3e7 - 8e8 * s + 27e9 * s ** 2

    p, dp = cubic(nodes)
    c = hermite_coefficients(p, dp, (s_hi - s_lo) / (n - 1))
    assert c.shape == (n - 1, 4)
    assert np.allclose(c[:, 0], p[:-1], rtol=1e-15)                                     # t = 0
    assert np.allclose(c.sum(axis=1), p[1:], rtol=1e-12)                                # t = 1
    eos = StateEquation(beta_liquid=1.5e9, ratio=1.0, p_atm=1e5, band=0.0, p_vap=1e3, p_lo=1e3, p_hi=5e7,
                        s_lo=s_lo, s_hi=s_hi, band_c=c, inv_ds=(n - 1) / (s_hi - s_lo), kind=MIXTURE,
                        air_fraction=1e-3, polytropic_index=1.0)
    for s in np.linspace(s_lo, s_hi, 97):
        want_p, want_dp = cubic(s)
        got_p, got_dp = state_of(s, eos)
        assert got_p == pytest.approx(want_p, rel=1e-12, abs=1e-6)
        assert got_dp == pytest.approx(want_dp, rel=1e-9)


_NOJIT = r"""
import json, math, sys
from gerotor_twin.config import load_config
from gerotor_twin.model.pump import Inputs, PumpModel
out = {}
for name in ("fixed", "mobility"):
    m = PumpModel(load_config(), name)
    inp = Inputs(3000 * math.pi / 30, 101325.0, 101325.0 + 27.5e5)
    s, o = m.advance(m.initial_state(inp), 12 * m.step_size(inp.omega), inp)
    out[name] = {"p": o.chamber_pressures.tolist(), "e": o.eccentricity.tolist(), "q": o.delivery_flow.tolist(),
                 "y": s.log_density.tolist(), "eta": o.volumetric_efficiency,
                 "peak": o.chamber_peak_pressures.tolist()}
json.dump(out, sys.stdout)
"""


@pytest.mark.slow
def test_pure_python_path_equals_the_compiled_one():
    """Behaviour: ``advance`` with NUMBA_DISABLE_JIT=1 (plain Python/NumPy) gives the compiled results.

    Same operations in the same order; only libm vs LLVM intrinsics differ: 1e-9 relative.
    """
    runs = {}
    for flag in ("0", "1"):
        env = dict(os.environ, NUMBA_DISABLE_JIT=flag, PYTHONPATH=str(ROOT))
        r = subprocess.run([sys.executable, "-c", _NOJIT], env=env, cwd=ROOT, capture_output=True, text=True,
                           timeout=600)
        assert r.returncode == 0, r.stderr[-2000:]
        runs[flag] = json.loads(r.stdout)
    for name in ("fixed", "mobility"):
        a, b = runs["0"][name], runs["1"][name]
        for key in ("p", "q", "y", "e", "peak"):
            x, y = np.asarray(a[key]), np.asarray(b[key])
            assert np.allclose(x, y, rtol=1e-9, atol=1e-9 * np.abs(x).max() + 1e-300), (name, key)
        assert a["eta"] == pytest.approx(b["eta"], rel=1e-9)


def _ros2_peak(y0, h, f, jac, f_t, start=None):
    """kernel._track_peak after one ROS2 step of a scalar ODE y' = f(t, y) with ∂f/∂y = jac, ∂f/∂t = f_t
    constant (linear); the stages are those of kernel.ros2_step, written out for one variable.
    Returns (the running peak, the step's end)."""
    from gerotor_twin.model.params import workspace
    g = K.GAMMA
    k1 = (f(0.0, y0) + g * h * f_t) / (1.0 - g * h * jac)
    k2 = (f(h, y0 + h * k1) - 2.0 * k1 - g * h * f_t) / (1.0 - g * h * jac)
    ws = workspace(1)
    ws.k1[0], ws.k2[0] = k1, k2
    y1 = y0 + 1.5 * h * k1 + 0.5 * h * k2
    ws.peak[0] = y0 if start is None else start
    K._track_peak(np.array([y1, 0.0]), h, 1, ws)
    return ws.peak[0], y1


@pytest.mark.parametrize("t_star", [0.1e-3, 1.0e-3, 1.9e-3])
def test_track_peak_finds_the_maximum_of_a_parabola_exactly(t_star):
    """Closed form: ROS2 and its continuous extension are exact for y' = c (t* − t) (y a parabola), so the
    tracked peak over a sub-step of h = 2 ms that contains t* is y₀ + c t*²/2, not the larger end."""
    c, y0, h = 3.0e3, 0.25, 2e-3
    peak, y1 = _ros2_peak(y0, h, lambda t, y: c * (t_star - t), 0.0, -c)
    assert y1 == pytest.approx(y0 + c * (t_star * h - h * h / 2), rel=1e-13)        # the step itself: exact
    assert peak == pytest.approx(y0 + c * t_star ** 2 / 2, rel=1e-13)
    assert peak > max(y0, y1)


def test_track_peak_does_not_overshoot_a_stiff_approach():
    """Closed form: a stiff chamber relaxing up to its equilibrium, y' = λ(y − y_eq), λh = −10⁶, has no
    maximum inside the step; the tracked peak is the end (≤ y_eq), where a Hermite cubic through the end
    rates would overshoot.  A falling step and an earlier, higher peak leave the running peak as it is."""
    lam, y_eq, h = -1e9, 1.0, 1e-3
    peak, y1 = _ros2_peak(0.0, h, lambda t, y: lam * (y - y_eq), lam, 0.0)
    assert peak == y1 and 0.99 < peak <= y_eq + 1e-12
    peak, _ = _ros2_peak(2.0, h, lambda t, y: lam * (y - y_eq), lam, 0.0)
    assert peak == 2.0                                                       # falling: the start stays
    peak, _ = _ros2_peak(0.0, 2e-3, lambda t, y: 3e3 * (1e-3 - t), 0.0, -3e3, start=9.0)
    assert peak == 9.0


@pytest.mark.parametrize("name", ["fixed", "mobility"])
def test_state_pressures_are_those_of_the_state(cfg, name):
    """Behaviour: ``PumpState.pressures`` (taken from the stepper's last output step, not recomputed) is
    p(ln ρ) of the state, element for element, after an advance and after an empty one; the peak output
    of every step is at least the pressures at both of its ends."""
    m = PumpModel(cfg, name)
    inp = Inputs(2500 * math.pi / 30, 101325.0, 101325.0 + 12e5)
    st0 = m.initial_state(inp)
    st, o = m.advance(st0, 0.004, inp)
    for s in (st, m.advance(st, 0.0, inp)[0]):
        p = np.empty_like(s.log_density)
        K.to_pressures(s.log_density, m.kernel, p)
        assert np.array_equal(p, s.pressures)
    assert np.all(o.chamber_peak_pressures >= o.chamber_pressures)
    assert np.all(o.chamber_peak_pressures[0] >= st0.pressures[:m.N])
    assert np.all(o.chamber_peak_pressures[1:] >= o.chamber_pressures[:-1])


def test_lu_factor_and_solve_match_numpy():
    """Independent tool: the stepper's LU with partial pivoting (its diagonal holding 1/u_kk) solves W x = b as
    numpy.linalg.solve does, for W = I − γhJ of a stiff random J and for a matrix that needs pivoting."""
    from gerotor_twin.model.kernel import lu_factor, lu_solve
    rng = np.random.default_rng(3)
    for n in (1, 2, 8, 15):
        for w in (np.eye(n) - 1.7 * rng.normal(size=(n, n)) * 10.0 ** rng.uniform(-3, 3, size=(n, 1)),
                  np.roll(np.eye(n), 1, axis=0) + 1e-3 * rng.normal(size=(n, n))):
            b = rng.normal(size=n)
            lu, piv, x = w.copy(), np.zeros(n, np.int64), np.zeros(n)
            lu_factor(lu, piv)
            lu_solve(lu, piv, b, x)
            assert np.allclose(x, np.linalg.solve(w, b), rtol=1e-9, atol=1e-12 * np.abs(x).max())
            lu_solve(lu, piv, b.copy(), b)                  # x may alias b
            assert np.array_equal(b, x)
