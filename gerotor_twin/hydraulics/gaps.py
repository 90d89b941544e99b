"""Laminar leakage through thin gaps: tooth tips, lateral gaps, drain (sec. 3.1–3.4 of [1]).

All gap flows are lubrication-theory (Poiseuille + Couette) flows in a film of
height h much smaller than its other dimensions, with constant viscosity.

==========================================  =====================================
name                                        content
==========================================  =====================================
:func:`slot_flow`                           plane Poiseuille slot (sec. 3.3–3.4)
:func:`tooth_tip_flow`                      one tooth-tip gap, Eq. (22) of [1]
:func:`sector_circumferential_flow`         lateral gap, pressure drop along θ [2]
:func:`sector_couette_flow`                 lateral gap, shear by a rotating face [2]
:func:`sector_radial_flow`                  lateral gap, pressure drop along r [2]
==========================================  =====================================

Every flow kernel with a pressure difference returns ``(q, dq_ddp)``: the flow
from side "a" to side "b" [m³/s] (positive when dp = p_a − p_b > 0) and its
analytic derivative with respect to dp [m³/(s·Pa)].  A gap of height h ≤ 0
(closed, or gears in contact) carries no flow: ``(0.0, 0.0)``.

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear", sections 3.1–3.4, Eq. (22)
   (``/work/shared/paper/gerotor-micromotion-paper.md``).
.. [2] P. J. Gamez-Montero, E. Codina, "Flow characteristics of a
   trochoidal-gear pump using bond graphs and experimental measurement",
   Parts 1 and 2, Proc. IMechE Part I: J. Systems and Control Engineering,
   2007 (lateral-gap leakage as Poiseuille + Couette flow in annular sectors).
.. [3] H. E. Merritt, *Hydraulic Control Systems*, Wiley, 1967, ch. 3
   (laminar flow through clearances between parallel plates).
"""
from __future__ import annotations

import math

from gerotor_twin._jit import njit

__all__ = [
    "slot_flow",
    "tooth_tip_flow",
    "sector_circumferential_flow",
    "sector_couette_flow",
    "sector_radial_flow",
    "GAP_LENGTH_MIN",
    "GAP_ANGLE_MIN",
    "GAP_RADIUS_MIN",
]

#: Floor of gap lengths (l, le, r_out − r_in of a radial gap) [m].  The caller
#: guarantees positive lengths where h > 0; the floor only keeps kernels finite.
GAP_LENGTH_MIN = 1e-9
#: Floor of the angular extent χ of a circumferential sector [rad].
GAP_ANGLE_MIN = 1e-9
#: Floor of the inner radius of a sector [m] (r_in = 0 makes ln(r_out/r_in) infinite).
GAP_RADIUS_MIN = 1e-9
_MU_MIN = 1e-12  # [Pa·s] floor of the viscosity (caller guarantees μ > 0)


@njit
def slot_flow(dp, h, width, length, mu):
    r"""Plane Poiseuille flow through a parallel-plate slot.

    Parameters
    ----------
    dp : float
        Pressure difference across the slot, Δp = p_a − p_b [Pa].
    h : float
        Gap height [m]; h ≤ 0 means closed.
    width : float
        Slot width w, normal to the flow and to h [m]; w ≤ 0 means no slot.
    length : float
        Slot length l in the flow direction [m]; must be > 0
        (floored at :data:`GAP_LENGTH_MIN`).
    mu : float
        Dynamic viscosity μ [Pa·s]; must be > 0.

    Returns
    -------
    q : float
        Flow from a to b [m³/s].
    dq_ddp : float
        dQ/dΔp = w h³/(12 μ l) [m³/(s·Pa)].

    Notes
    -----
    Plane Poiseuille flow [3], used for the delivery→suction and drain
    leakages of sections 3.3–3.4 of [1]:

    .. math::
        Q = \frac{w\, h^3}{12\,\mu\, l}\,\Delta p

    Validity: laminar film, h ≪ l and h ≪ w (side and entrance effects
    neglected), constant μ.
    """
    if not (h > 0.0 and width > 0.0):
        return 0.0, 0.0
    l_eff = length if length > GAP_LENGTH_MIN else GAP_LENGTH_MIN
    m = mu if mu > _MU_MIN else _MU_MIN
    g = width * h * h * h / (12.0 * m * l_eff)
    return g * dp, g


@njit(inline="always")
def tooth_tip_flow(dp, h, le, v_r, width, mu):
    r"""Leakage through one tooth-tip gap: Poiseuille + Couette, Eq. (22) of [1].

    Parameters
    ----------
    dp : float
        Pressure difference Δp = p_a − p_b between the two chambers the gap
        separates [Pa].
    h : float
        Minimum gap height between the tips of the inner and outer gear [m];
        h ≤ 0 (contact) means no flow.
    le : float
        Equivalent gap length [m] (distance between the points where the gap
        height is h(1 + dh), sec. 3.1 of [1]); the caller guarantees le > 0
        when h > 0 (floored at :data:`GAP_LENGTH_MIN` otherwise).
    v_r : float
        Signed relative speed of the two gear surfaces at the minimum gap,
        measured along the gap in the direction a → b [m/s].
    width : float
        Axial width of the gears b [m].
    mu : float
        Dynamic viscosity μ [Pa·s]; must be > 0.

    Returns
    -------
    q : float
        Flow from chamber a to chamber b [m³/s].
    dq_ddp : float
        dQ/dΔp = b h³/(12 μ le) [m³/(s·Pa)] (the Couette part does not depend on Δp).

    Notes
    -----
    One gap's share of Eq. (22) of [1]:

    .. math::
        Q = \frac{b\, h^3}{12\,\mu\, l_e}\,\Delta p + \frac{v_r}{2}\, b\, h

    The first term is plane Poiseuille flow over the equivalent length, the
    second Couette flow: one wall moving at v_r relative to the other drags a
    linear velocity profile of mean v_r/2 [3].  In Eq. (22) chamber j receives
    this flow from gap j−1 (a = j−1, b = j) and loses it to gap j (a = j,
    b = j+1), which gives the ± signs of the printed equation.

    Validity: laminar flow in the gap (the paper's hypothesis), h ≪ le.
    Not possible in a kernel: raising on le ≤ 0; the caller must guarantee it.
    """
    if not (h > 0.0 and width > 0.0):
        return 0.0, 0.0
    l_eff = le if le > GAP_LENGTH_MIN else GAP_LENGTH_MIN
    m = mu if mu > _MU_MIN else _MU_MIN
    g = width * h * h * h / (12.0 * m * l_eff)
    return g * dp + 0.5 * v_r * width * h, g


@njit
def _log_radius_ratio(r_in, r_out):
    """max(ln(r_out/r_in), 0) as log1p((r_out − r_in)/r_in) (accurate as r_out/r_in → 1)."""
    ri = r_in if r_in > GAP_RADIUS_MIN else GAP_RADIUS_MIN
    if not r_out > ri:
        return 0.0
    return math.log1p((r_out - ri) / ri)


@njit
def sector_circumferential_flow(dp, h, chi, r_in, r_out, mu):
    r"""Circumferential Poiseuille flow through a lateral gap shaped as an annular sector.

    Parameters
    ----------
    dp : float
        Pressure difference Δp = p_a − p_b between the sector's two radial
        edges, a at θ = 0 and b at θ = χ [Pa].
    h : float
        Lateral gap height (axial clearance between gear face and housing) [m];
        h ≤ 0 means closed.
    chi : float
        Angular extent χ of the sector, i.e. the angular length of the gap
        [rad]; must be > 0 (floored at :data:`GAP_ANGLE_MIN`).
    r_in : float
        Inner radius of the sector [m] (floored at :data:`GAP_RADIUS_MIN`).
    r_out : float
        Outer radius of the sector [m]; r_out ≤ r_in means no gap.
    mu : float
        Dynamic viscosity μ [Pa·s]; must be > 0.

    Returns
    -------
    q : float
        Flow from edge a to edge b [m³/s].
    dq_ddp : float
        dQ/dΔp [m³/(s·Pa)].

    Notes
    -----
    Lateral-gap model of Gamez-Montero and Codina [2], used in sec. 3.2 of [1].
    Derivation: in a film of height h the pressure depends only on θ and
    falls linearly from p_a to p_b over χ, so ∂p/∂θ = −Δp/χ.  The plane
    Poiseuille flow per unit radial width at radius r, driven by the gradient
    along the arc −(1/r)∂p/∂θ, is q'(r) = h³Δp/(12 μ χ r).  Integrating over
    the sector's radial width:

    .. math::
        Q = \int_{r_{in}}^{r_{out}} \frac{h^3 \Delta p}{12\,\mu\,\chi\, r}\,dr
          = \frac{h^3\, \Delta p}{12\,\mu\,\chi}\,\ln\frac{r_{out}}{r_{in}}

    As r_out/r_in → 1 with w = r_out − r_in and l = χ r_in fixed,
    ln(r_out/r_in) → w/r_in and Q → w h³Δp/(12 μ l), the plane slot
    (:func:`slot_flow`).  ln(r_out/r_in) is evaluated with ``log1p`` so the
    limit is accurate.

    Validity: laminar film, h ≪ r_out − r_in and h ≪ χ r_in, constant μ.
    """
    if not (h > 0.0 and r_out > r_in):
        return 0.0, 0.0
    c = chi if chi > GAP_ANGLE_MIN else GAP_ANGLE_MIN
    m = mu if mu > _MU_MIN else _MU_MIN
    g = h * h * h * _log_radius_ratio(r_in, r_out) / (12.0 * m * c)
    return g * dp, g


@njit
def sector_couette_flow(h, omega, r_in, r_out):
    r"""Couette flow through a lateral gap sector dragged by a rotating gear face.

    Parameters
    ----------
    h : float
        Lateral gap height [m]; h ≤ 0 means closed.
    omega : float
        Angular speed ω of the rotating face relative to the stationary one
        (housing) [rad/s]; positive in the direction of increasing θ.
    r_in : float
        Inner radius of the sector [m].
    r_out : float
        Outer radius of the sector [m]; r_out ≤ r_in means no gap.

    Returns
    -------
    q : float
        Flow across a radial line of the sector in the direction of rotation
        [m³/s] (independent of the pressure difference, so no derivative).

    Notes
    -----
    Couette term of the lateral-gap model of [2] (sec. 3.2 of [1]).  At radius
    r the moving wall has speed ω r and the linear velocity profile across the
    film has mean ω r/2; the flow per unit radial width is h ω r/2, hence

    .. math::
        Q = \int_{r_{in}}^{r_{out}} \frac{h\,\omega\, r}{2}\,dr
          = \frac{h\,\omega\,(r_{out}^2 - r_{in}^2)}{4}

    As r_out/r_in → 1 with w = r_out − r_in and U = ω r_in it tends to the
    plane Couette flow U h w/2.  Computed as (r_out − r_in)(r_out + r_in) to
    avoid cancellation.
    """
    if not (h > 0.0 and r_out > r_in):
        return 0.0
    return 0.25 * h * omega * (r_out - r_in) * (r_out + r_in)


@njit
def sector_radial_flow(dp, h, chi, r_in, r_out, mu):
    r"""Radial Poiseuille flow through a lateral gap shaped as an annular sector.

    Parameters
    ----------
    dp : float
        Pressure difference Δp = p_a − p_b, a at the inner radius r_in and b at
        the outer radius r_out [Pa].
    h : float
        Lateral gap height [m]; h ≤ 0 means closed.
    chi : float
        Angular extent χ of the sector (the gap's width as an angle) [rad];
        χ ≤ 0 means no gap.
    r_in : float
        Inner radius of the sector [m] (floored at :data:`GAP_RADIUS_MIN`).
    r_out : float
        Outer radius of the sector [m]; the caller guarantees
        r_out − r_in > 0 (floored at :data:`GAP_LENGTH_MIN`).
    mu : float
        Dynamic viscosity μ [Pa·s]; must be > 0.

    Returns
    -------
    q : float
        Flow from the inner to the outer radius [m³/s].
    dq_ddp : float
        dQ/dΔp [m³/(s·Pa)].

    Notes
    -----
    Lateral-gap model of [2] (drain and suction/delivery leakages across a
    gear face, sec. 3.2–3.4 of [1]).  Derivation: the total radial flow Q
    crosses every arc of length χ r, so the flow per unit arc length is
    Q/(χ r) = −h³/(12 μ) dp/dr; integrating dp/dr = −12 μ Q/(χ h³ r) from
    r_in to r_out:

    .. math::
        Q = \frac{\chi\, h^3\, \Delta p}{12\,\mu\,\ln(r_{out}/r_{in})}

    As r_out/r_in → 1 with l = r_out − r_in and w = χ r_in fixed,
    ln(r_out/r_in) → l/r_in and Q → w h³Δp/(12 μ l), the plane slot
    (:func:`slot_flow`).

    Validity: laminar film, h ≪ r_out − r_in, constant μ.
    """
    if not (h > 0.0 and chi > 0.0):
        return 0.0, 0.0
    ri = r_in if r_in > GAP_RADIUS_MIN else GAP_RADIUS_MIN
    dr = r_out - ri
    if dr < GAP_LENGTH_MIN:
        dr = GAP_LENGTH_MIN
    m = mu if mu > _MU_MIN else _MU_MIN
    g = chi * h * h * h / (12.0 * m * math.log1p(dr / ri))
    return g * dp, g
