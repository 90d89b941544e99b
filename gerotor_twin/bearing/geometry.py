"""Geometry and lubricant of the outer-gear journal bearing.

The outer gear of the Gerotor pump turns inside the pump housing like a
journal in a plain bearing [1]_.  This module holds the four numbers that
define that bearing and the paper's Table 1 instance.

Conventions
-----------
``diameter_m`` is the journal (outer gear) diameter ``D`` and
``radius_m = D / 2`` is used for every radius in the bearing models: the
area element of Eq. (5), the surface speed ``U = omega R`` and the scales of
the mobility method.  The paper's nomenclature is inconsistent about which of
``r1``/``r2`` is the journal; the difference is ``c / R = 0.19 %`` for
Table 1, below the accuracy of the thin-film Reynolds equation itself
(which neglects curvature terms of that order).

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear", sec. 2 and Table 1.
"""
from __future__ import annotations

from dataclasses import dataclass

from gerotor_twin.errors import InputError, check_range

__all__ = ["BearingGeometry", "TABLE1"]


@dataclass(frozen=True)
class BearingGeometry:
    """Plain journal bearing: size, radial clearance and lubricant viscosity.

    Parameters
    ----------
    length_m : float
        Axial length ``L`` of the bearing [m], > 0.
    diameter_m : float
        Journal diameter ``D`` [m], > 0.
    clearance_m : float
        Radial clearance ``c`` [m], 0 < c < D / 20 (thin film).
    viscosity_pa_s : float
        Dynamic viscosity ``mu`` of the lubricant [Pa s], > 0.

    Raises
    ------
    InputError
        Naming the offending field, its value and the allowed range.
    """

    length_m: float
    diameter_m: float
    clearance_m: float
    viscosity_pa_s: float

    def __post_init__(self) -> None:
        length = check_range("bearing.length_m", self.length_m, 0.0, None, lo_open=True, unit="m")
        diameter = check_range("bearing.diameter_m", self.diameter_m, 0.0, None, lo_open=True,
                               unit="m")
        clearance = check_range("bearing.clearance_m", self.clearance_m, 0.0, None, lo_open=True,
                                unit="m")
        if clearance >= diameter / 20.0:
            raise InputError("bearing.clearance_m", self.clearance_m,
                             f"(0, {diameter / 20.0:g}) m",
                             "a thin film needs c << D (c < D/20)")
        mu = check_range("bearing.viscosity_pa_s", self.viscosity_pa_s, 0.0, None, lo_open=True,
                         unit="Pa s")
        object.__setattr__(self, "length_m", length)
        object.__setattr__(self, "diameter_m", diameter)
        object.__setattr__(self, "clearance_m", clearance)
        object.__setattr__(self, "viscosity_pa_s", mu)

    @property
    def radius_m(self) -> float:
        """Journal radius ``R = D / 2`` [m]."""
        return 0.5 * self.diameter_m

    @property
    def length_to_diameter(self) -> float:
        """Slenderness ratio ``L / D`` [-]."""
        return self.length_m / self.diameter_m

    @property
    def clearance_ratio(self) -> float:
        """``c / R`` [-]."""
        return self.clearance_m / self.radius_m

    def with_length(self, length_m: float) -> "BearingGeometry":
        """Copy with another axial length ``L`` [m] (used for L/D sweeps)."""
        return BearingGeometry(length_m, self.diameter_m, self.clearance_m, self.viscosity_pa_s)


#: Paper Table 1: L = 17.2 mm, D = 101.55 mm, c = 0.0975 mm, mu = 0.0391 Pa s.
TABLE1 = BearingGeometry(17.2e-3, 101.55e-3, 0.0975e-3, 0.0391)
