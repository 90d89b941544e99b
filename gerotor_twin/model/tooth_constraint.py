r"""The outer gear on the inner gear's teeth: the tooth contact as a unilateral constraint on the gear's velocity.

The mobility method has no inertia (sec. 2.2 of [1]): the outer gear's velocity is an algebraic function of its
position and load, :math:`\dot{\mathbf e} = \mathbf M(\mathbf e, \mathbf F)`.  The tooth-tip gap of lobe k,
:math:`g_k(\mathbf e, \theta) \ge 0` (:mod:`.contact`), bounds the position.  A contact reaction
:math:`\lambda \ge 0` [N] acts along the gap's normal :math:`\mathbf n = \nabla_{\mathbf e} g_k` (it pushes the
gears apart), and the film answers a force along :math:`\mathbf n` with the velocity :math:`G\mathbf n`, G the
mobility's velocity per force at that state (:mod:`.gear_coupling`).  With the gap's rate at fixed position
:math:`r` [m/s] (the shaft's turn) this is Moreau's sweeping process [2]:

.. math::
    \dot{\mathbf e} = \dot{\mathbf e}_{free} + \lambda\,G\mathbf n,\qquad
    \lambda = \max\!\Big(0,\; -\frac{\mathbf n\cdot\dot{\mathbf e}_{free} + r}{\mathbf n^{T} G\,\mathbf n}\Big)

so in contact :math:`\dot g = \mathbf n\cdot\dot{\mathbf e} + r = 0`, and a load that turns away
(:math:`\mathbf n\cdot\dot{\mathbf e}_{free} + r > 0`) gives :math:`\lambda = 0`: the gear leaves.  The film
carries the load and the reactions together, ė = M(e, F + λn): the form above is its first order about the
load G is taken at.  A reaction comparable with the load turns it, where the mobility is far from linear (13 at
1000 rpm / 2 bar: the peak 8.7 % apart, docs/numerics.md), so where a step starts on the teeth the twin takes ė₀
and G at the load the film carries there, the reactions solved through the full mobility
(:func:`.gear_coupling.linearise_in_contact`), and the form above is exact at the step's start.  The symmetric
part of G is positive definite for a dissipative film, so :math:`\mathbf n^T G \mathbf n > 0` and nothing is
singular.  Over a step of h from the position :math:`\mathbf e` the time-stepping form of [2] (sec. 3) takes
:math:`r = g_k(\mathbf e, \theta + \omega h)/h`: the gap at the step's end, linearised in the move, is held at
zero; a gap the free motion does not close within the step leaves :math:`\lambda = 0`.  The stepper takes it per
ROS2 sub-step, from where the stages have moved the gear (:func:`.gear_coupling.substep_rates`), so a contact that
passes from one lobe to the next inside an output step passes where the gaps say it does.  The velocity is linear in the load where
:math:`\lambda > 0`, with the projected mobility

.. math::
    G_c = G - \frac{G\mathbf n\,\mathbf n^{T} G}{\mathbf n^{T} G\,\mathbf n},\qquad
    \mathbf n^{T} G_c = 0

(the Jacobian of the constrained velocity in the load).  The outer gear sits between two teeth of the inner gear,
and two lobes can hold it at once: the reactions of the two lobes that close first are one small linear
complementarity problem (:func:`reactions`); with both holding, the velocity is set by the two gaps' rates alone
(:math:`G_c = 0`).  With one lobe only, a gear that slides off it runs into the next one within the step, is
pulled back along that lobe's normal and slides back: measured on the pump with new-pump clearances, it
alternated between two lobes at every output step (the delivery flow rough at the sample).  What the step
leaves of an overlap (the gaps' curvature) is taken back by the same rule with the gaps for rates
(:func:`pull_back_along`): one rule inside the step and in the check.

References
----------
.. [1] The paper, sec. 2.2 and 3.7 (``../shared/paper``).
.. [2] J.J. Moreau, "Numerical aspects of the sweeping process", Comput. Methods Appl. Mech. Engrg. 177 (1999)
   329–349.
.. [3] R.W. Cottle, J.-S. Pang, R.E. Stone, *The Linear Complementarity Problem*, Academic Press 1992, sec. 3.3
   (P-matrices: a unique solution for every s).
"""
from __future__ import annotations

import numpy as np

from .._jit import njit
from .contact import gap_value

__all__ = ["reactions", "reaction", "constrained_velocity", "projected_mobility", "gap_normal", "contact_pair",
           "two_smallest", "pull_back_along"]


@njit(inline="always")
def reactions(s1, s2, a11, a12, a21, a22):
    r"""Reactions (λ₁, λ₂) ≥ 0 [N] of two contacts: the linear complementarity problem

    .. math::
        \mathbf w = A\boldsymbol\lambda + \mathbf s \ge 0,\quad \boldsymbol\lambda \ge 0,\quad
        \mathbf w\cdot\boldsymbol\lambda = 0,\qquad A_{kl} = \mathbf n_k^T G\,\mathbf n_l

    ``s``: each gap's rate under the free motion [m/s]; A [m/(s·N)].  A = NᵀG N has a positive definite symmetric
    part where G has one and the normals are independent, so it is a P-matrix and the solution is unique [3]; it
    is found by enumerating the four active sets.  Parallel normals (det A ≈ 0) hold with one contact.
    """
    if s1 >= 0.0 and s2 >= 0.0:
        return 0.0, 0.0
    if s1 < 0.0:
        l1 = -s1 / a11
        if a21 * l1 + s2 >= 0.0:
            return l1, 0.0
    if s2 < 0.0:
        l2 = -s2 / a22
        if a12 * l2 + s1 >= 0.0:
            return 0.0, l2
    det = a11 * a22 - a12 * a21
    if det > 1e-12 * a11 * a22:
        l1 = (-s1 * a22 + s2 * a12) / det
        l2 = (-s2 * a11 + s1 * a21) / det
        if l1 >= 0.0 and l2 >= 0.0:
            return l1, l2
    return (-s1 / a11, 0.0) if s1 * a22 < s2 * a11 else (0.0, -s2 / a22)


@njit(inline="always")
def reaction(vx, vy, nx, ny, gnx, gny, rate):
    r"""Reaction λ [N] of one contact that holds its gap's rate at zero, or 0 where the free motion opens it.

    .. math::
        \lambda = \max\big(0,\, -(\mathbf n\cdot\dot{\mathbf e}_{free} + r)/(\mathbf n^T G\mathbf n)\big)

    ``vx, vy``: the free velocity ė_free [m/s]; ``nx, ny``: the gap's normal ∇_e g [-]; ``gnx, gny``: G n
    [m/(s·N)]; ``rate``: r, the gap's rate at fixed position [m/s].
    """
    s = nx * vx + ny * vy + rate
    return 0.0 if s >= 0.0 else -s / (nx * gnx + ny * gny)


@njit(inline="always")
def constrained_velocity(vx, vy, c):
    """The gear's velocity [m/s] under the reactions of the two contacts ``c`` (:func:`reactions`), and λ₁, λ₂ [N].

    ``c``: (n₁ₓ, n₁ᵧ, n₂ₓ, n₂ᵧ [-], (G n₁)ₓ, (G n₁)ᵧ, (G n₂)ₓ, (G n₂)ᵧ [m/(s·N)], r₁, r₂ [m/s]) as set by
    :func:`contact_pair`; (vx, vy): the free velocity [m/s].
    """
    s1 = c[0] * vx + c[1] * vy + c[8]
    s2 = c[2] * vx + c[3] * vy + c[9]
    a11 = c[0] * c[4] + c[1] * c[5]
    a12 = c[0] * c[6] + c[1] * c[7]
    a21 = c[2] * c[4] + c[3] * c[5]
    a22 = c[2] * c[6] + c[3] * c[7]
    l1, l2 = reactions(s1, s2, a11, a12, a21, a22)
    return vx + l1 * c[4] + l2 * c[6], vy + l1 * c[5] + l2 * c[7], l1, l2


@njit(inline="always")
def projected_mobility(gxx, gxy, gyx, gyy, nx, ny):
    """G_c = G − G n nᵀG / (nᵀG n) [m/(s·N)], row-major: the constrained velocity's derivative in the load where one
    contact holds (nᵀG_c = 0); where two independent contacts hold the velocity is set by them alone (G_c = 0)."""
    gnx = gxx * nx + gxy * ny
    gny = gyx * nx + gyy * ny
    ngx = nx * gxx + ny * gyx               # nᵀG
    ngy = nx * gxy + ny * gyy
    d = nx * gnx + ny * gny
    return gxx - gnx * ngx / d, gxy - gnx * ngy / d, gyx - gny * ngx / d, gyy - gny * ngy / d


@njit(inline="always")
def gap_normal(c, ex, ey):
    """∇_e g [-] of the gap expansion ``c`` (:func:`.contact.gap_value`, inner gear unturned) at (ex, ey) [m]."""
    return c[0] + c[3] * ex + c[4] * ey, c[1] + c[4] * ex + c[5] * ey


@njit(inline="always")
def contact_pair(gxx, gxy, gyx, gyy, n1x, n1y, n2x, n2y, r1, r2, out):
    """The two contacts' data of :func:`constrained_velocity` into ``out`` (10,) from G (row-major) [m/(s·N)], the
    normals [-] and the rates [m/s]."""
    out[0], out[1], out[2], out[3] = n1x, n1y, n2x, n2y
    out[4], out[5] = gxx * n1x + gxy * n1y, gyx * n1x + gyy * n1y
    out[6], out[7] = gxx * n2x + gxy * n2y, gyx * n2x + gyy * n2y
    out[8], out[9] = r1, r2


@njit(inline="always")
def two_smallest(cmat, delta, ex, ey):
    """Lobes (k₁, k₂) with the smallest gaps (inner gear unturned) at (ex, ey) [m], and those gaps [m]."""
    k1, k2, g1, g2 = 0, 0, np.inf, np.inf
    for k in range(cmat.shape[0]):
        g = gap_value(cmat[k], delta, ex, ey, 0.0)
        if g < g1:
            k2, g2 = k1, g1
            k1, g1 = k, g
        elif g < g2:
            k2, g2 = k, g
    return k1, k2, g1, g2


@njit
def pull_back_along(cmat, delta, ex, ey, gxx, gxy, gyx, gyy, c):
    """Displacement [m] moved back onto every gap ≥ 0 by reactions of the two most overlapped lobes (the same rule
    as inside the step: Δe = G (μ₁ n₁ + μ₂ n₂), μ from :func:`reactions` with the gaps for rates), Newton-iterated
    on the quadratic gaps.

    ``cmat``: (N, 9) gap expansions at the angle (:func:`.contact.gap_coefficients`); ``delta``: nominal tip
    clearance [m]; (ex, ey): the proposed displacement [m]; G row-major [m/(s·N)]; ``c``: (10,) scratch.  Returns
    (ex, ey, True) with every gap ≥ −1e-9 δ, the
    input where no gap is negative; (ex, ey, False) where four iterations leave an overlap above 1e-4 δ (the
    caller falls back to the check's pull-back along **e**).
    """
    for _ in range(4):
        k1, k2, g1, g2 = two_smallest(cmat, delta, ex, ey)
        if g1 >= -1e-9 * delta:
            return ex, ey, True
        n1x, n1y = gap_normal(cmat[k1], ex, ey)
        n2x, n2y = gap_normal(cmat[k2], ex, ey)
        contact_pair(gxx, gxy, gyx, gyy, n1x, n1y, n2x, n2y, g1, g2, c)
        dx, dy, _m1, _m2 = constrained_velocity(0.0, 0.0, c)    # Δe = G (μ₁n₁ + μ₂n₂), n·Δe = −g where held
        ex += dx
        ey += dy
    k1, k2, g1, g2 = two_smallest(cmat, delta, ex, ey)
    return ex, ey, g1 >= -1e-4 * delta
