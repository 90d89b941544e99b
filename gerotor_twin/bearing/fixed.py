"""Fixed-centre outer gear: the reference case of sec. 4 of the paper.

The outer gear is held at its nominal position (or wherever it starts) by a
rigid support; its centre never moves.
"""
from __future__ import annotations

import numpy as np

from gerotor_twin._jit import njit
from gerotor_twin.bearing.base import KernelBearing, as_vector2
from gerotor_twin.bearing.geometry import BearingGeometry

__all__ = ["FixedBearing", "fixed_kernel"]


@njit
def fixed_kernel(ex, ey, fx, fy, omega, params):
    """``de/dt = 0`` [m/s] whatever the load."""
    return 0.0, 0.0


class FixedBearing(KernelBearing):
    """Outer gear with a fixed centre (rigid support, no film dynamics).

    Parameters
    ----------
    geometry : BearingGeometry
        Bearing [m, Pa s] (only the clearance is used, for the film thickness).
    """

    name = "fixed"

    def __init__(self, geometry: BearingGeometry):
        super().__init__(geometry)
        self.kernel = fixed_kernel
        self.params = (0.0,)

    def film_force(self, e: np.ndarray, e_dot: np.ndarray, omega: float) -> np.ndarray:
        """No film is modelled: zero [N].  The rigid support carries the load
        (``simulate`` reports that reaction, ``-load``, as the film force)."""
        as_vector2("e", e)
        as_vector2("e_dot", e_dot)
        return np.zeros(2)
