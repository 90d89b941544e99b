"""Tests of gerotor_twin.hydraulics.gaps — CLOSED-FORM tests.

References: the plane Poiseuille slot w·h³·Δp/(12μl) and plane Couette flow
U·h·w/2 written out here; the annular-sector formulas must tend to them as
r_out/r_in → 1 (closed-form limit, error O((r_out − r_in)/r_in)); exact h³
scaling, linearity in Δp, Couette independent of Δp, derivatives against
central finite differences, and finite results for degenerate geometry.
"""
from __future__ import annotations

import itertools
import math

import pytest

from gerotor_twin.hydraulics.gaps import (
    sector_circumferential_flow,
    sector_couette_flow,
    sector_radial_flow,
    slot_flow,
    tooth_tip_flow,
)

MU = 0.0391
H = 20e-6
W = 0.017


def poiseuille(dp, h, w, l, mu=MU):
    return w * h**3 * dp / (12 * mu * l)


def check_linear_flow(fun, args_after_dp, h_index=0):
    """Linearity in Δp, exact h³ scaling, derivative = FD, odd in Δp."""
    q1, g1 = fun(1e5, *args_after_dp)
    q2, g2 = fun(3e5, *args_after_dp)
    assert q2 == pytest.approx(3 * q1, rel=1e-14) and g1 == g2
    fd = (fun(1e5 + 1.0, *args_after_dp)[0] - fun(1e5 - 1.0, *args_after_dp)[0]) / 2.0
    assert g1 == pytest.approx(fd, rel=1e-7)
    assert fun(-1e5, *args_after_dp)[0] == -q1
    assert fun(0.0, *args_after_dp)[1] == g1  # derivative independent of Δp
    scaled = list(args_after_dp)
    scaled[h_index] = 2 * scaled[h_index]
    assert fun(1e5, *scaled)[0] == pytest.approx(8 * q1, rel=1e-14)


def test_slot_flow():
    q, g = slot_flow(1e5, H, W, 2e-3, MU)
    assert q == pytest.approx(poiseuille(1e5, H, W, 2e-3), rel=1e-15)
    assert g == pytest.approx(W * H**3 / (12 * MU * 2e-3), rel=1e-15)
    check_linear_flow(slot_flow, (H, W, 2e-3, MU))
    assert slot_flow(1e5, 0.0, W, 2e-3, MU) == (0.0, 0.0)
    assert slot_flow(1e5, -1e-6, W, 2e-3, MU) == (0.0, 0.0)
    assert slot_flow(1e5, H, 0.0, 2e-3, MU) == (0.0, 0.0)


def test_tooth_tip_flow():
    le, vr = 1.5e-3, 2.3
    q, g = tooth_tip_flow(1e5, H, le, vr, W, MU)
    assert q == pytest.approx(poiseuille(1e5, H, W, le) + vr * W * H / 2, rel=1e-14)
    assert g == pytest.approx(W * H**3 / (12 * MU * le), rel=1e-15)
    # Couette only at Δp = 0, signed with v_r; derivative independent of v_r
    assert tooth_tip_flow(0.0, H, le, vr, W, MU)[0] == pytest.approx(vr * W * H / 2, rel=1e-15)
    assert tooth_tip_flow(0.0, H, le, -vr, W, MU)[0] == -tooth_tip_flow(0.0, H, le, vr, W, MU)[0]
    assert tooth_tip_flow(1e5, H, le, -vr, W, MU)[1] == g
    # without Couette it is the slot
    assert tooth_tip_flow(1e5, H, le, 0.0, W, MU) == slot_flow(1e5, H, W, le, MU)
    # Poiseuille part: linear, h³, FD
    check_linear_flow(tooth_tip_flow, (H, le, 0.0, W, MU))
    fd = (tooth_tip_flow(1e5 + 1, H, le, vr, W, MU)[0]
          - tooth_tip_flow(1e5 - 1, H, le, vr, W, MU)[0]) / 2
    assert g == pytest.approx(fd, rel=1e-6)
    # contact / degenerate gap
    assert tooth_tip_flow(1e5, 0.0, le, vr, W, MU) == (0.0, 0.0)
    assert tooth_tip_flow(1e5, -1e-6, le, vr, W, MU) == (0.0, 0.0)
    q0, g0 = tooth_tip_flow(1e5, H, 0.0, vr, W, MU)  # caller error: floored, finite
    assert math.isfinite(q0) and math.isfinite(g0) and g0 > 0


@pytest.mark.parametrize("fun", [sector_circumferential_flow, sector_radial_flow])
def test_sector_flows_finite_on_degenerate_geometry(fun):
    for h, chi, r_in, r_out, mu in itertools.product(
            (0.0, -1e-6, 1e-6), (0.0, -0.1, 1e-12, 0.5), (0.0, -0.01, 0.02), (0.0, 0.02, 0.05),
            (0.0, MU)):
        for dp in (0.0, 1e5, -1e7):
            q, g = fun(dp, h, chi, r_in, r_out, mu)
            assert math.isfinite(q) and math.isfinite(g) and g >= 0.0
    assert fun(1e5, 0.0, 0.5, 0.02, 0.03, MU) == (0.0, 0.0)


def test_sector_circumferential_flow():
    chi, r_in, r_out = 0.4, 0.021, 0.034
    q, g = sector_circumferential_flow(1e5, H, chi, r_in, r_out, MU)
    assert q == pytest.approx(H**3 * 1e5 * math.log(r_out / r_in) / (12 * MU * chi), rel=1e-14)
    check_linear_flow(sector_circumferential_flow, (H, chi, r_in, r_out, MU))
    # slot limit: w = r_out - r_in and l = χ r_in fixed, r_in → ∞
    w, l = 3e-3, 4e-3
    errs = []
    for r in (1e-1, 1.0, 10.0, 1e3):
        qs = sector_circumferential_flow(1e5, H, l / r, r, r + w, MU)[0]
        errs.append(abs(qs / poiseuille(1e5, H, w, l) - 1.0))
        assert errs[-1] == pytest.approx(w / (2 * r), rel=0.02)  # ln(1+ε)/ε = 1 - ε/2 + ...
    assert errs == sorted(errs, reverse=True) and errs[-1] < 2e-6
    assert sector_circumferential_flow(1e5, H, chi, r_out, r_in, MU) == (0.0, 0.0)


def test_sector_couette_flow():
    r_in, r_out, om = 0.021, 0.034, 314.0
    assert sector_couette_flow(H, om, r_in, r_out) == pytest.approx(
        H * om * (r_out**2 - r_in**2) / 4, rel=1e-14)
    # signed with ω, linear in h (Couette: no dependence on Δp, it is not an argument)
    assert sector_couette_flow(H, -om, r_in, r_out) == -sector_couette_flow(H, om, r_in, r_out)
    assert sector_couette_flow(2 * H, om, r_in, r_out) == pytest.approx(
        2 * sector_couette_flow(H, om, r_in, r_out), rel=1e-15)
    # the Couette part of the same gap is what a Poiseuille+Couette gap adds at any Δp:
    # plane limit U h w / 2 with U = ω r_in, w = r_out - r_in, as r_in → ∞
    w, U = 3e-3, 5.0
    for r in (1.0, 1e3):
        qc = sector_couette_flow(H, U / r, r, r + w)
        assert qc == pytest.approx(U * H * w / 2 * (1 + w / (2 * r)), rel=1e-12)
    assert sector_couette_flow(H, U / 1e6, 1e6, 1e6 + w) == pytest.approx(U * H * w / 2, rel=1e-8)
    assert sector_couette_flow(0.0, om, r_in, r_out) == 0.0
    assert sector_couette_flow(H, om, r_out, r_in) == 0.0


def test_sector_radial_flow():
    chi, r_in, r_out = 0.9, 0.012, 0.019
    q, g = sector_radial_flow(1e5, H, chi, r_in, r_out, MU)
    assert q == pytest.approx(chi * H**3 * 1e5 / (12 * MU * math.log(r_out / r_in)), rel=1e-14)
    check_linear_flow(sector_radial_flow, (H, chi, r_in, r_out, MU))
    # slot limit: l = r_out - r_in and w = χ r_in fixed, r_in → ∞
    w, l = 6e-3, 2e-3
    errs = []
    for r in (1e-1, 1.0, 10.0, 1e3):
        qs = sector_radial_flow(1e5, H, w / r, r, r + l, MU)[0]
        errs.append(abs(qs / poiseuille(1e5, H, w, l) - 1.0))
        assert errs[-1] == pytest.approx(l / (2 * r), rel=0.02)  # ε/ln(1+ε) = 1 + ε/2 + ...
    assert errs == sorted(errs, reverse=True) and errs[-1] < 2e-6
    assert sector_radial_flow(1e5, H, 0.0, r_in, r_out, MU) == (0.0, 0.0)
