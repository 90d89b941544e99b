"""Tooth-tip gaps of the displaced gear set and the overlap check of sec. 3.7 of [1].

The gap at lobe k is the second-order expansion of the exact gap about the
nominal position (:mod:`gerotor_twin.geometry.tables`):

.. math::
    h_k ≈ δ + \\mathbf g_k·\\mathbf z + \\tfrac12 \\mathbf z^T \\mathbf H_k \\mathbf z,
    \\qquad \\mathbf z = (e_x, e_y, γ)

with e the outer-gear displacement [m] and γ the inner-gear rotation [rad].
:func:`contact` applies the rule of sec. 3.7 of [1]: gears that would overlap
are pulled back along **e**; gears that would not touch have the inner gear
turned forward until one lobe touches (the driving contact).

References
----------
.. [1] The paper, sec. 3.7 (``../shared/paper``).
"""
from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..geometry.tables import GX

__all__ = ["locate", "column", "gap_coefficients", "gap_value", "gap_unturned", "contact"]

N_GAP_COEFFS = 9    # gx, gy, gγ, hxx, hxy, hyy, hxγ, hyγ, hγγ (columns GX..HGG, consecutive)


@njit(inline="always")
def locate(tab, theta):
    """Row pair and weight (i0, i1, f) of shaft angle θ [rad] in the periodic table."""
    m = tab.rows.shape[0]
    x = theta * tab.scale
    x -= m * math.floor(x / m)                  # periodic: 0 ≤ x ≤ m (no fmod call)
    i0 = int(x)
    f = x - i0
    if i0 >= m or i0 < 0:                       # x rounded up to m (or θ not finite): row 0
        i0 = 0
    i1 = i0 + 1                                 # branches, not ``%``: an integer division costs ≈ 40 cycles
    if i1 == m:
        i1 = 0
    return i0, i1, f


@njit(inline="always")
def column(tab, col, i0, i1, f):
    """Linear interpolation of column ``col`` between rows i0 and i1 (weight f of i1)."""
    return tab.rows[i0, col] * (1.0 - f) + tab.rows[i1, col] * f


@njit(inline="always")
def gap_coefficients(tab, theta, k, out):
    """Expansion coefficients of the gap of lobe k at shaft angle θ into ``out`` (9,)."""
    i0, i1, f = locate(tab, theta + k * tab.shift)
    for i in range(N_GAP_COEFFS):
        out[i] = column(tab, GX + i, i0, i1, f)


@njit(inline="always")
def gap_value(c, delta, ex, ey, g):
    """Gap height [m] of the expansion ``c`` at displacement (ex, ey) [m] and rotation g [rad]."""
    return (delta + c[0] * ex + c[1] * ey + c[2] * g
            + 0.5 * (c[3] * ex * ex + 2.0 * c[4] * ex * ey + c[5] * ey * ey
                     + 2.0 * c[6] * ex * g + 2.0 * c[7] * ey * g + c[8] * g * g))


@njit(inline="always")
def gap_unturned(tab, theta, k, delta, ex, ey):
    """Gap height [m] of lobe k at shaft angle θ [rad] and displacement (ex, ey) [m], the inner gear unturned
    (:func:`gap_value` at γ = 0, from the five coefficients it needs)."""
    i0, i1, f = locate(tab, theta + k * tab.shift)
    cx = column(tab, GX, i0, i1, f)
    cy = column(tab, GX + 1, i0, i1, f)
    hxx = column(tab, GX + 3, i0, i1, f)
    hxy = column(tab, GX + 4, i0, i1, f)
    hyy = column(tab, GX + 5, i0, i1, f)
    return delta + cx * ex + cy * ey + 0.5 * (hxx * ex * ex + 2.0 * hxy * ex * ey + hyy * ey * ey)


@njit
def _smallest_positive_root(a, b, c):
    """Smallest root > 0 of a x² + b x + c, or +inf."""
    best = np.inf
    if abs(a) < 1e-300 or abs(a * c) < 1e-12 * b * b:
        if b != 0.0:
            x = -c / b
            if x > 0.0:
                best = x
        return best
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return best
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))     # numerically stable pair
    for x in (q / a, c / q if q != 0.0 else np.inf):
        if 0.0 < x < best:
            best = x
    return best


@njit
def _rotation_to_touch(cmat, h, ex, ey):
    """Smallest forward inner-gear rotation γ > 0 [rad] that closes one gap (0 if none closes)."""
    best = np.inf
    for k in range(h.shape[0]):
        c = cmat[k]
        b = c[2] + c[6] * ex + c[7] * ey
        if b < 0.0:
            x = _smallest_positive_root(0.5 * c[8], b, h[k])
            if x < best:
                best = x
    return best if best < np.inf else 0.0


@njit
def _pull_back(cmat, h, ex, ey):
    """Displacement after pulling the outer gear back along **e** until no gap is negative [m]."""
    en = math.hypot(ex, ey)
    ux, uy = ex / en, ey / en
    s = 0.0
    for k in range(h.shape[0]):
        if h[k] < 0.0:
            c = cmat[k]
            gx = c[0] + c[3] * ex + c[4] * ey
            gy = c[1] + c[4] * ex + c[5] * ey
            b = -(gx * ux + gy * uy)
            a = 0.5 * (c[3] * ux * ux + 2.0 * c[4] * ux * uy + c[5] * uy * uy)
            x = _smallest_positive_root(a, b, h[k])
            if x == np.inf:
                x = en
            s = max(s, x)
    s = min(s, en)
    return ex - s * ux, ey - s * uy


@njit
def contact(tab, n, delta, theta, ex, ey, h_out, cmat, reuse=False):
    """Overlap check of sec. 3.7 of [1] on the tabulated gap expansion.

    Parameters
    ----------
    tab : KernelTables
    n : int
        Number of lobes N.
    delta : float
        Nominal tooth-tip clearance δ [m].
    theta : float
        Shaft angle [rad].
    ex, ey : float
        Proposed outer-gear displacement [m].
    h_out : ndarray (N,)
        Receives the N gap heights [m] (≥ 0).
    cmat : ndarray (N, 9)
        The expansion coefficients of every lobe at θ (filled here).
    reuse : bool
        ``cmat`` already holds the coefficients at this θ (a second call at the
        same angle with another displacement): they are not interpolated again.
        The stepper passes ``bool(...)``, never a literal or nothing: each of those is a type of its own
        and a compile of its own (:func:`.flows.rhs`, Notes).

    Returns
    -------
    ex, ey : float
        Displacement taken [m] (pulled back along **e** if the gears would overlap).
    gamma : float
        Inner-gear rotation [rad] (forward until one contact if they would not touch and
        ``tab.turn_inner``; 0 otherwise: the gaps stay those of the displaced, unturned gears).
    kc : int
        Index of the lobe in contact (smallest gap).
    """
    for k in range(n):
        if not reuse:
            gap_coefficients(tab, theta, k, cmat[k])
        h_out[k] = gap_value(cmat[k], delta, ex, ey, 0.0)
    gamma = 0.0
    lowest = h_out[0]
    for k in range(1, n):               # not np.min: its empty-array error compiles for nothing (0.5 s)
        lowest = min(lowest, h_out[k])
    if lowest >= 0.0:
        if tab.turn_inner:
            gamma = _rotation_to_touch(cmat, h_out, ex, ey)
    else:
        ex, ey = _pull_back(cmat, h_out, ex, ey)
    kc = 0
    for k in range(n):
        h_out[k] = max(gap_value(cmat[k], delta, ex, ey, gamma), 0.0)
        if h_out[k] < h_out[kc]:
            kc = k
    return ex, ey, gamma, kc
