"""The tooth contact as a unilateral constraint on the inertia-free gear (model/tooth_constraint.py).

Tier: CLOSED FORM.  Moreau's sweeping process under a constant load: against a straight boundary the
gear approaches with ė = G F, slides with ė = G F − (n·G F)/(nᵀG n) G n (reaction λ = −(n·G F)/(nᵀG n) ≥ 0
along n), and leaves with ė = G F' when the load turns away; the time-stepping of the kernel is exact there.
On a circle |e| = R with an isotropic mobility μ I the angle obeys dφ/dt = (μ|F|/R) sin(ψ − φ), whose solution
tan((ψ − φ)/2) = tan((ψ − φ₀)/2) exp(−μ|F|t/R) the stepped-and-projected motion must approach at first order.
"""
import math

import numpy as np
import pytest

from gerotor_twin.model.contact import gap_value
from gerotor_twin.model.tooth_constraint import (constrained_velocity, contact_pair, gap_normal, projected_mobility,
                                                 pull_back_along, reaction, reactions, two_smallest)

#: a journal bearing's mobility is not symmetric; its symmetric part is positive definite [m/(s·N)]
G_BEARING = np.array([[2.0e-6, 0.7e-6], [-0.4e-6, 1.2e-6]])


def _straight(*normals):
    """Gap expansions (one row of 9 per boundary) of straight boundaries g = δ + n·e."""
    c = np.zeros((len(normals), 9))
    for k, n in enumerate(normals):
        c[k, 0], c[k, 1] = n
    return c


def _circle(radius):
    """Gap expansion of the disc |e| ≤ R: g = (R² − |e|²)/(2R) (δ = R/2), zero on the circle, ∇g = −e/R there."""
    c = np.zeros((1, 9))
    c[0, 3] = c[0, 5] = -1.0 / radius
    return c, 0.5 * radius


def _pair(g, c, delta, e, h, out):
    """The kernel's constraint data (gear_coupling.set_constraint) for a step of h [s] from e [m] (static gaps)."""
    k1, k2, g1, g2 = two_smallest(c, delta, e[0], e[1])
    contact_pair(*g.ravel(), *gap_normal(c[k1], *e), *gap_normal(c[k2], *e), g1 / h, g2 / h, out)
    return out


def _stepped(c, delta, g, e0, loads, h):
    """The kernel's time-stepping: per step the reactions holding the two smallest gaps ≥ 0 at the step's end at
    first order (rates g/h), then the pull-back by the same rule.  ``loads``: one load [N] per step.  Returns
    positions and the reactions (λ₁, λ₂) per step."""
    e = np.array(e0, dtype=float)
    path, lams, scratch = [e.copy()], [], np.empty(10)
    for f in loads:
        vx, vy, l1, l2 = constrained_velocity(*(g @ f), _pair(g, c, delta, e, h, np.empty(10)))
        ex, ey, ok = pull_back_along(c, delta, e[0] + h * vx, e[1] + h * vy, *g.ravel(), scratch)
        assert ok
        e = np.array([ex, ey])
        path.append(e.copy())
        lams.append((l1, l2))
    return np.array(path), np.array(lams)


def test_reaction_holds_the_gap_and_never_pulls():
    """Closed form: λ = −(n·ė_free + r)/(nᵀG n) where that is positive, else 0; in contact n·ė + r = 0."""
    n = np.array([0.6, -0.8])
    gn = G_BEARING @ n
    for v, rate in (([1e-3, 2e-3], 0.0), ([-1e-3, 3e-3], 1e-4), ([2e-3, -1e-3], 0.0), ([0.0, 0.0], -1e-4)):
        one = np.empty(10)
        contact_pair(*G_BEARING.ravel(), *n, 0.0, 0.0, rate, 1.0, one)         # a second contact far open
        vx, vy, lam, lam2 = constrained_velocity(v[0], v[1], one)
        assert lam2 == 0.0
        expected = max(0.0, -(n @ v + rate) / (n @ gn))
        assert lam == pytest.approx(expected, rel=1e-12, abs=1e-300) and lam >= 0.0
        assert lam == reaction(v[0], v[1], n[0], n[1], gn[0], gn[1], rate)
        if lam > 0.0:
            assert n @ [vx, vy] + rate == pytest.approx(0.0, abs=1e-15)
            assert np.allclose([vx - v[0], vy - v[1]], lam * gn, rtol=1e-12)     # the reaction acts along n
        else:
            assert (vx, vy) == (v[0], v[1])


def test_projected_mobility_is_the_derivative_of_the_constrained_velocity():
    """Closed form: nᵀG_c = 0, and G_c is the Jacobian of the constrained velocity in the load (λ > 0)."""
    n = np.array([0.3, 0.9])
    gc = np.array(projected_mobility(*G_BEARING.ravel(), n[0], n[1])).reshape(2, 2)
    assert np.allclose(n @ gc, 0.0, atol=4 * np.finfo(float).eps * np.abs(gc).max())   # zero to round-off
    gn = G_BEARING @ n
    f0 = np.array([-300.0, -500.0])               # into the contact: λ > 0
    one = np.empty(10)
    contact_pair(*G_BEARING.ravel(), *n, 0.0, 0.0, 0.0, 1.0, one)

    def v(f):
        return np.array(constrained_velocity(*(G_BEARING @ f), one)[:2])
    assert reaction(*(G_BEARING @ f0), n[0], n[1], gn[0], gn[1], 0.0) > 0.0
    jac = np.column_stack([(v(f0 + d) - v(f0 - d)) / 2.0 for d in np.eye(2)])
    assert np.allclose(jac, gc, rtol=1e-9, atol=1e-20)


def test_straight_boundary_approach_slide_and_leave_are_exact():
    """Closed form: a constant load into g = δ + n·e ≥ 0 (G not symmetric): the gear approaches with G F, hits at
    t* = δ/(−n·G F), slides along the boundary with G F − (n·G F)/(nᵀG n) G n (not the orthogonal projection of
    G F) under the reaction −(n·G F)/(nᵀG n) > 0, and leaves with G F' once the load turns away."""
    delta, n = 10e-6, np.array([0.6, -0.8])
    c = _straight(n)
    f_in, f_out = np.array([-1000.0, 2000.0]), np.array([500.0, -800.0])
    assert n @ G_BEARING @ f_in < 0.0 < n @ G_BEARING @ f_out
    h, k_in, k_out = 1e-4, 200, 30
    path, lams = _stepped(c, delta, G_BEARING, (0.0, 0.0), [f_in] * k_in + [f_out] * k_out, h)
    v_free, gn = G_BEARING @ f_in, G_BEARING @ n
    t_hit = delta / -(n @ v_free)
    v_slide = v_free - (n @ v_free) / (n @ gn) * gn
    t_in = k_in * h
    assert t_hit < t_in / 3
    e_in = v_free * t_hit + v_slide * (t_in - t_hit)
    assert np.allclose(path[k_in], e_in, rtol=0, atol=1e-18)
    assert gap_value(c[0], delta, *path[k_in], 0.0) == pytest.approx(0.0, abs=1e-18)
    lam_slide = -(n @ v_free) / (n @ gn)
    lams = lams[:, 0]
    sliding = np.arange(k_in) * h >= t_hit                  # steps that start on the boundary
    assert np.allclose(lams[:k_in][sliding], lam_slide, rtol=1e-9) and np.all(lams >= 0.0)
    assert np.all(lams[:int(t_hit / h)] == 0.0)             # free until the step that reaches it
    ortho = v_free - (n @ v_free) / (n @ n) * n            # a frictionless projection would slide here instead
    assert np.linalg.norm(ortho - v_slide) > 0.1 * np.linalg.norm(v_slide)
    assert np.all(lams[k_in:] == 0.0)                                      # the load turned away: it leaves
    assert np.allclose(path[-1], e_in + G_BEARING @ f_out * k_out * h, rtol=0, atol=1e-18)


def _circle_error(h, radius=20e-6, mu=1e-6, fmag=400.0, psi=math.radians(80.0), t_end=0.02):
    """Angle error [rad] of the stepped slide on |e| = R at t_end [s] against the closed form, and the swept angle."""
    c, delta = _circle(radius)
    f = fmag * np.array([math.cos(psi), math.sin(psi)])
    path, lams = _stepped(c, delta, mu * np.eye(2), (radius, 0.0), [f] * round(t_end / h), h)
    assert np.allclose(np.hypot(path[:, 0], path[:, 1]), radius, rtol=1e-9)   # on the circle after every step
    assert np.all(lams[:, 0] > 0.0)                                           # pushed into it throughout
    exact = psi - 2.0 * math.atan(math.tan(0.5 * psi) * math.exp(-mu * fmag * t_end / radius))
    return math.atan2(path[-1, 1], path[-1, 0]) - exact, exact


def test_circle_slide_converges_to_the_closed_form():
    """Closed form: on |e| = R with mobility μ I and a constant load at angle ψ (outward), tan((ψ−φ)/2) =
    tan((ψ−φ₀)/2) e^{−μ|F|t/R}; the stepped motion, projected back along G n, stays on the circle and converges
    to it at first order (μ|F|t/R = 0.4: measured 0.033 % of the swept angle at h = 1e-4 s)."""
    err2, swept = _circle_error(2e-4)
    err1, _ = _circle_error(1e-4)
    assert abs(err1) < 1e-3 * swept
    assert 1.7 < err2 / err1 < 2.3
def test_pull_back_moves_along_g_n_onto_the_boundary():
    """Closed form: an overlap (g < 0) is taken back onto g = 0 along G n of the overlapped lobe, not along e."""
    c, delta = _circle(20e-6)
    e = np.array([21e-6, 5e-6])
    assert gap_value(c[0], delta, *e, 0.0) < 0.0
    ex, ey, ok = pull_back_along(c, delta, e[0], e[1], *G_BEARING.ravel(), np.empty(10))
    assert ok and -1e-9 * delta <= gap_value(c[0], delta, ex, ey, 0.0) < 1e-12 * delta
    d = G_BEARING @ np.array(gap_normal(c[0], *e))
    move = np.array([ex, ey]) - e
    assert abs(move[0] * d[1] - move[1] * d[0]) < 1e-3 * np.linalg.norm(move) * np.linalg.norm(d)
    assert move @ d > 0.0
    assert pull_back_along(c, delta, 1e-6, 2e-6, *G_BEARING.ravel(), np.empty(10)) == (1e-6, 2e-6, True)


def test_reactions_solve_the_two_contact_complementarity_problem():
    """Closed form: λ ≥ 0, w = Aλ + s ≥ 0, λ·w = 0 for each of the four active sets (A = NᵀG N, a P-matrix)."""
    nmat = np.array([[0.6, -0.8], [-0.7, -0.7]]).T
    a = nmat.T @ G_BEARING @ nmat
    for s in ([1e-3, 2e-3], [-1e-3, 5e-3], [4e-3, -1e-3], [-1e-3, -1e-3], [-2e-3, 1e-4]):
        lam = np.array(reactions(s[0], s[1], *a.ravel()))
        w = a @ lam + s
        assert np.all(lam >= 0.0) and np.all(w >= -1e-15) and abs(lam @ w) < 1e-15 * (1 + np.abs(lam).sum())
    assert reactions(-1e-3, -1e-3, *a.ravel())[1] > 0.0 and reactions(-1e-3, -1e-3, *a.ravel())[0] > 0.0


def test_load_into_a_wedge_stops_in_its_corner():
    """Closed form: two straight boundaries g_k = δ + n_k·e meet at the corner e* (n_k·e* = −δ); the load
    F = −λ*(n₁ + n₂) brings the gear there and is held by the reactions λ₁ = λ₂ = λ* (ė = 0); a load along one face
    slides along it away from the other (λ₂ = 0).  With one contact only, the gear alternated between the faces."""
    delta, n1, n2 = 10e-6, np.array([0.0, -1.0]), np.array([-0.8, -0.6])
    c = _straight(n1, n2)
    corner = np.linalg.solve(np.array([n1, n2]), [-delta, -delta])
    h = 1e-4
    path, lams = _stepped(c, delta, G_BEARING, (0.0, 0.0), [np.array([800.0, 1600.0])] * 300, h)
    assert np.allclose(path[-1], corner, rtol=0, atol=1e-15)
    assert np.allclose(lams[-50:], 1000.0, rtol=1e-9)          # the load −1000 N (n₁ + n₂) is held by λ = 1000 N each
    assert np.abs(np.diff(path[-50:], axis=0)).max() < 1e-18                # at rest in the corner
    path, lams = _stepped(c, delta, G_BEARING, corner, [np.array([-3000.0, 500.0])] * 50, h)
    assert np.all(lams[:, 1] == 0.0) and np.all(lams[:, 0] > 0.0)          # slides along face 1, away from face 2
    assert np.allclose(path[:, 1], corner[1], rtol=0, atol=1e-15) and path[-1, 0] < corner[0] - 1e-6
