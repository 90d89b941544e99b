"""Chamber volumes of the displaced outer gear (``micro_motion.chamber_volumes: displaced``).

Moving the outer gear by **e** changes chamber j's volume, to first order, by

.. math::
    V_j(θ, \\mathbf e) = V_j(θ) + \\mathbf f_j(θ)·\\mathbf e,\\qquad
    \\frac{dV_j}{dθ}(θ, \\mathbf e) = \\frac{dV_j}{dθ}(θ) + \\mathbf f_j'(θ)·\\mathbf e,

where **f**_j = (FX, FY) is the pressure force on the outer gear per unit chamber
pressure (eq. 24 of [1], already tabulated): by virtual work p dV = **F**·d**e**,
so ∂V/∂**e** = **F**/p.  A polygon of the displaced geometry agrees to 1e-4
(``test/test_model_volumes.py``); along O1→O2 the displacement grows by
0.0224 % per µm.  The remainder is O(|e|²).

The kernel freezes **e** over an output step and moves the gear between steps.
The gear motion also squeezes the chambers, dV/dt ⊃ **f**·ė: over the step after a
move by Δ**e** the chamber loses **f**·Δ**e**/h of volume flow, so its mass is the
same as if the volume had followed the gear (to O(|Δe|²)); the move itself leaves
ln ρ unchanged, so no pressure spike appears in a small, closed chamber.

References
----------
.. [1] The paper, sec. 3.6 (``../shared/paper``).
"""
from __future__ import annotations

from .._jit import njit

__all__ = ["volumes_moved", "displace_chamber", "move_volumes", "PLACEMENT_TOLERANCE"]

#: A placement closer than this to the current position [m] is the same state (the overlap check of sec. 3.7
#: re-projects a gear at contact by round-off when it is called again on the same state, e.g. at every
#: output step of :func:`.kernel.integrate_external`).
PLACEMENT_TOLERANCE = 1e-15


@njit(inline="always")
def volumes_moved(disp):
    """True when the gear is off centre or moved in the last step (``disp`` as in :func:`displace_chamber`)."""
    return disp[0] != 0.0 or disp[1] != 0.0 or disp[2] != 0.0 or disp[3] != 0.0


@njit(inline="always")
def displace_chamber(fx, fy, dfx, dfy, j, disp, geo, acc, c_v, c_dv):
    """Displacement terms of chamber j's V (column ``c_v`` of ``geo``), dV/dθ (``c_dv``) and squeeze flow (``acc``).

    ``fx, fy``: the chamber's FX, FY [m³/m] and ``dfx, dfy`` their θ-derivatives [m³/(m·rad)] at its angle (the
    tables' values); ``disp`` (4,): displacement (ex, ey) [m] and the velocity of its last move
    (vx, vy) [m/s] (all zero with nominal volumes: see :func:`volumes_moved`).
    """
    geo[j, c_v] += fx * disp[0] + fy * disp[1]
    geo[j, c_dv] += dfx * disp[0] + dfy * disp[1]
    acc[j] -= fx * disp[2] + fy * disp[3]                 # squeeze by the gear's last move [m³/s]


@njit(forceinline=True)     # per output step, two sites: compiled once, inlined by LLVM
def move_volumes(tab, disp, ex, ey, h):
    """The chamber volumes follow the gear to (ex, ey) [m], moved over the last step h [s] (0: placed).

    A placement (h = 0) at another position than the current one (a new state) clears the
    squeeze velocity; at the same position (within :data:`PLACEMENT_TOLERANCE`) it is kept
    (``advance`` calls in sequence).
    Nothing happens with nominal volumes (``tab.volumes_follow_gear`` False).
    """
    if not tab.volumes_follow_gear:
        return
    if h > 0.0:
        disp[2] = (ex - disp[0]) / h
        disp[3] = (ey - disp[1]) / h
    elif abs(ex - disp[0]) + abs(ey - disp[1]) > PLACEMENT_TOLERANCE:
        disp[2] = 0.0
        disp[3] = 0.0
    disp[0] = ex
    disp[1] = ey
