"""Issue 13 §3: chamber volumes and dV/dθ of the displaced outer gear (``micro_motion.chamber_volumes``)."""
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from gerotor_twin.config import MicroMotion
from gerotor_twin.geometry.chambers import chamber_polygon, ideal, polygon_area
from gerotor_twin.model.pump import PumpModel
from gerotor_twin.model.steady import reference_config, run_steady

D_E = 2e-6          # finite-difference displacement [m]


def _area(g, theta, e=(0.0, 0.0)):
    return abs(polygon_area(chamber_polygon(ideal(g), theta, 0, displacement=e)))


@pytest.fixture(scope="module")
def tables(fixed_model):
    return fixed_model.tables


@pytest.mark.parametrize("theta", [0.3, 1.0, 2.0, 3.0, 4.5, 6.0])
def test_volume_gradient_is_the_force_projection(cfg, tables, theta):
    """Independent geometry: ∂V/∂e of the displaced-profile polygon (outer gear moved, chamber closed at the
    exact minimum-gap lines) equals the tabulated (FX, FY) = eq. (24) force per unit pressure (virtual work)."""
    g, b = cfg.gears, cfg.gears.width
    for axis, col in ((0, "FX"), (1, "FY")):
        ep, em = [0.0, 0.0], [0.0, 0.0]
        ep[axis], em[axis] = D_E, -D_E
        dv = b * (_area(g, theta, ep) - _area(g, theta, em)) / (2 * D_E)
        ref = tables.column(col, theta)
        assert dv == pytest.approx(ref, rel=1e-3, abs=1e-3 * 4e-4), (col, dv, ref)


@pytest.mark.parametrize("theta", [1.0, 2.0, 4.5])
def test_dv_dtheta_of_the_displaced_gear(cfg, tables, theta):
    """Independent geometry: dV/dθ of the displaced polygon (central difference in θ) = DV + (DFX, DFY)·e."""
    g, b, dth = cfg.gears, cfg.gears.width, 1e-4
    for e in ((5e-6, 0.0), (0.0, -5e-6)):
        dvdth = b * (_area(g, theta + dth, e) - _area(g, theta - dth, e)) / (2 * dth)
        model = tables.column("DV", theta) + tables.column("DFX", theta) * e[0] + tables.column("DFY", theta) * e[1]
        nominal = b * (_area(g, theta + dth) - _area(g, theta - dth)) / (2 * dth)
        # the displacement term is resolved to 2 % (it is ~1e-4 of dV/dθ)
        assert (dvdth - nominal) == pytest.approx(model - tables.column("DV", theta), rel=0.02, abs=1e-12)


def test_displacement_grows_along_o1_o2(cfg, fixed_model, tables):
    """Independent geometry: displacement (N−1)·b·(A_max − A_min) of the displaced-profile polygon at the two dead
    centres, ±2 µm along O1→O2 and across: +0.0224 %/µm along x (the issue: ≈ 0.022 %), ≈ 0 across;
    the tabulated first-order form (N−1)(FX(θ_max) − FX(θ_min)) agrees to 0.5 %."""
    g = cfg.gears
    n, b = g.chambers, g.width
    th = tables.angles()
    v = tables.data[0]
    t_max, t_min = th[v.argmax()], th[v.argmin()]

    def displacement(e):
        a_max = -minimize_scalar(lambda t: -_area(g, t, e), bounds=(t_max - 0.02, t_max + 0.02),
                                 method="bounded", options={"xatol": 1e-8}).fun
        a_min = minimize_scalar(lambda t: _area(g, t, e), bounds=(t_min - 0.02, t_min + 0.02),
                                method="bounded", options={"xatol": 1e-8}).fun
        return (n - 1) * b * (a_max - a_min)

    d0 = displacement((0.0, 0.0))
    assert d0 == pytest.approx(fixed_model.displacement, rel=5e-5)     # polygon of 400 + 3·80 points
    per_um = (displacement((D_E, 0.0)) - displacement((-D_E, 0.0))) / (2 * D_E) * 1e-6 / d0
    across = (displacement((0.0, D_E)) - displacement((0.0, -D_E))) / (2 * D_E) * 1e-6 / d0
    fx = tables.data[4]
    table = (n - 1) * (fx[v.argmax()] - fx[v.argmin()]) * 1e-6 / d0
    assert per_um == pytest.approx(2.24e-4, rel=0.01)
    assert table == pytest.approx(per_um, rel=0.005)
    assert abs(across) < 1e-3 * per_um


def test_mass_balance_holds_with_moving_volumes(cfg):
    """Behaviour: with the volumes following the mobility gear (and its squeeze flow), suction-port mass in =
    delivery-port mass out over a periodic revolution, the residual falling with the tolerance as for the
    fixed gear (without the squeeze term a moving gear would create mass).  Measured with the chamber-cut
    suction kidney: 1.5e-4 → 1.9e-5 → 6.0e-7 for 2e-6 → 2e-7 → 2e-8; at 2e-10 it is still 4.2e-7, the
    same with the periodic-state criterion rtol 1e-9 (with the ray-edge kidney 1.1e-4 → 7.5e-6 → 9.7e-8
    for 2e-6 → 2e-8 → 2e-10).  Below 2e-8 it falls only slowly (fixed centre: 3.3e-7 at 2e-10, 1.0e-7 at
    2e-12), whatever the output step, table size or stepper's h_min: a low-order error source not yet
    traced, so the test stops at 2e-8."""
    c = replace(cfg, micro_motion=MicroMotion(chamber_volumes="displaced"))
    res = []
    for tol in (2e-6, 2e-8):
        m = PumpModel(reference_config(c, tolerance=tol, max_step_deg=0.5), "mobility")
        o = run_steady(m, 1000.0, 27.5, rtol=1e-7, max_revolutions=60).outputs
        res.append(abs(o.port_mass_in - o.port_mass_out) / o.port_mass_in)
    assert res[1] < 1e-5 and res[0] / res[1] > 5, res


def test_displaced_volumes_change_only_the_moving_gear(cfg):
    """Behaviour: the fixed centre (e = 0) is bit-identical under both settings; the mobility model moves by a
    few tenths of a point (measured −0.07 pt at 1000 rpm / 27.5 bar, −0.4 pt at 3000 rpm / 5 bar)."""
    eta = {}
    for vol in ("nominal", "displaced"):
        c = replace(cfg, micro_motion=MicroMotion(chamber_volumes=vol))
        for name in ("fixed", "mobility"):
            m = PumpModel(c, name)
            eta[vol, name] = [run_steady(m, rpm, bar).volumetric_efficiency for rpm, bar in ((1000, 27.5), (3000, 5))]
    assert eta["nominal", "fixed"] == eta["displaced", "fixed"]
    d = np.array(eta["displaced", "mobility"]) - np.array(eta["nominal", "mobility"])
    assert np.all(np.abs(d) < 0.006) and np.all(np.abs(d) > 2e-4), d
