"""The one interface shared by the four outer-gear bearing models.

Every model answers the same question: given where the journal (outer gear)
centre is, the external load on it and the journal speed, how fast does the
centre move?  The journal is massless, so the film force balances the load
at every instant (Eqs. (6), (19) of [1]_):

.. math::

    \\mathbf F_{film}(\\mathbf e, \\dot{\\mathbf e}, \\omega) + \\mathbf F_{est} = \\mathbf 0 .

Conventions (all models)
------------------------
* Housing-fixed frame, SI units, angles counter-clockwise from +x.
* ``e`` [m] is the journal-centre displacement from the housing centre; the
  film is thinnest at the angle of ``e``: ``h = c - e_x cos(theta) - e_y sin(theta)``.
* ``omega`` [rad/s] is the journal speed, > 0 counter-clockwise; the housing
  is stationary.
* ``load`` [N] is the external force *on the journal*: a load pushes the
  journal towards the load.  Under a steady load the centre settles at the
  Ocvirk attitude angle from the load direction, rotated in the sense of
  rotation (counter-clockwise for ``omega > 0``).
* ``film_force`` [N] is the hydrodynamic force *on the journal*.

For speed, every model also exposes a numba kernel
``kernel(ex, ey, fx, fy, omega, params) -> (dex, dey)`` and its ``params``
tuple; :func:`gerotor_twin.bearing.simulate.simulate` integrates with them
without leaving compiled code.

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear", sec. 2 (``../shared/paper``).
"""
from __future__ import annotations

import math
from typing import Any, Callable, Protocol, runtime_checkable

import numpy as np

from gerotor_twin._jit import njit
from gerotor_twin.bearing.geometry import BearingGeometry
from gerotor_twin.errors import InputError, check_finite

__all__ = ["BearingModel", "KernelBearing", "as_vector2", "EPS_KERNEL_CAP", "cap_eccentricity"]

#: Kernels evaluate the film at most at this eccentricity ratio (a state
#: beyond it is scaled back radially).  Only a NaN guard for intermediate
#: integrator stages; the physical contact limit is ``simulate(eps_max=...)``.
EPS_KERNEL_CAP = 0.9999


@runtime_checkable
class BearingModel(Protocol):
    """What the pump model and the benchmark need from a bearing model."""

    name: str
    geometry: BearingGeometry

    def velocity(self, e: np.ndarray, load: np.ndarray, omega: float) -> np.ndarray:
        """``de/dt`` [m/s] of the journal centre (housing frame) that balances ``load``."""
        ...

    def film_force(self, e: np.ndarray, e_dot: np.ndarray, omega: float) -> np.ndarray:
        """Hydrodynamic force on the journal [N]."""
        ...

    def min_film_thickness(self, e: np.ndarray) -> float:
        """``c - |e|`` [m]."""
        ...


@njit
def cap_eccentricity(ex, ey, c):
    """Scale ``(ex, ey)`` back radially to ``|e| <= EPS_KERNEL_CAP c`` [m]."""
    r = math.sqrt(ex * ex + ey * ey)
    rmax = EPS_KERNEL_CAP * c
    if r > rmax:
        s = rmax / r
        return ex * s, ey * s
    return ex, ey


def as_vector2(field: str, value: Any) -> np.ndarray:
    """Validate a finite 2-vector; return it as ``float64`` array of shape (2,)."""
    try:
        v = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(field, value, "a finite 2-vector") from None
    if v.shape != (2,) or not np.all(np.isfinite(v)):
        raise InputError(field, value, "a finite 2-vector")
    return v


class KernelBearing:
    """Common implementation: validation around a numba velocity kernel.

    Subclasses set ``name``, ``kernel`` (numba function
    ``(ex, ey, fx, fy, omega, params) -> (dex, dey)``), ``params`` and
    implement :meth:`film_force`.
    """

    name: str = ""
    kernel: Callable
    params: tuple

    def __init__(self, geometry: BearingGeometry):
        if not isinstance(geometry, BearingGeometry):
            raise InputError("geometry", geometry, "a BearingGeometry")
        self.geometry = geometry

    def _film_args(self, e: Any, e_dot: Any, omega: Any) -> tuple[np.ndarray, np.ndarray, float]:
        """Validated ``(e [m], e_dot [m/s], omega [rad/s])`` of a film-force call."""
        return self._check_e(e), as_vector2("e_dot", e_dot), check_finite("omega", omega)

    def _check_e(self, e: Any) -> np.ndarray:
        v = as_vector2("e", e)
        c = self.geometry.clearance_m
        if math.hypot(v[0], v[1]) >= c:
            raise InputError("e", value=v.tolist(), allowed=f"|e| < c = {c:g} m",
                             reason="eccentricity ratio must be < 1 (metal contact)")
        return v

    def velocity(self, e: np.ndarray, load: np.ndarray, omega: float) -> np.ndarray:
        """Journal-centre velocity that makes the film carry ``load``.

        Parameters
        ----------
        e : array_like, shape (2,)
            Journal-centre displacement [m], ``|e| < c``.
        load : array_like, shape (2,)
            External load on the journal [N].
        omega : float
            Journal angular speed [rad/s].

        Returns
        -------
        numpy.ndarray, shape (2,)
            ``de/dt`` [m/s] in the housing frame.
        """
        ev = self._check_e(e)
        f = as_vector2("load", load)
        w = check_finite("omega", omega)
        dx, dy = self.kernel(ev[0], ev[1], f[0], f[1], w, self.params)
        return np.array([dx, dy])

    def film_force(self, e: np.ndarray, e_dot: np.ndarray, omega: float) -> np.ndarray:
        raise NotImplementedError

    def min_film_thickness(self, e: np.ndarray) -> float:
        """Minimum film thickness ``c - |e|`` [m] (negative means overlap)."""
        v = as_vector2("e", e)
        return self.geometry.clearance_m - math.hypot(v[0], v[1])

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, geometry={self.geometry!r})"
