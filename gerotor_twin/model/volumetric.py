r"""Losses at the edge of the chamber model: the effective displacement and a turbulent bypass path.

The chamber model delivers what its ideal (conjugate) profiles sweep, less the laminar leakage
of its gaps (tooth tips, lateral faces, drain: flow ∝ Δp h³/μ).  A real pump shows two more
kinds of loss that no clearance can make, each a physical parameter of the pump config's
``volumetric`` section:

* **Effective displacement** ``k_D`` (``displacement_factor``, 1 = the ideal profiles): the
  pump delivers less per revolution than its ideal profiles sweep, whatever the pressure —
  profile and assembly tolerances, chamber filling that ends before the suction kidney
  closes, dead volume re-expanded into the suction.  A deficit proportional to speed.
* **Bypass** ``A_b`` (``bypass_area_m2``, effective area C_d·A, 0 = none): a short,
  turbulent path from delivery to suction (a worn land of the valve plate, a weeping relief
  valve, a housing path): orifice flow, ∝ √Δp, independent of viscosity and speed — unlike
  the gaps' laminar leakage.

.. math::
    Q_\mathrm{delivered} = Q_\mathrm{model} - (1 - k_D)\, D \,\frac{\omega}{2\pi}
                           - A_b \sqrt{\frac{2\, \max(p_d - p_s, 0)}{\rho}}

with ``D`` [m³/rev] the ideal profiles' displacement, ω [rad/s] the shaft speed, p_d, p_s
[Pa] the delivery and suction pressures and ρ [kg/m³] the oil's density at the config's
reference temperature (the path's flow goes as ρ^{-1/2}: about 1.5 % over 40 K, left out).
Both are applied to the delivery flow after each model step (the steady state, the twin's
instantaneous and per-revolution flows); the chamber pressures and the gaps' leakage are
the model's own, and the theoretical flow stays ``D ω / 2π``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["EdgeLosses", "displacement_deficit", "bypass_flow"]


def displacement_deficit(omega: float, displacement_m3: float, factor: float) -> float:
    """Flow the ideal profiles sweep that the pump does not deliver, :math:`(1 - k_D) D ω / 2π` [m³/s].

    Parameters
    ----------
    omega : float
        Shaft speed [rad/s].
    displacement_m3 : float
        Displacement of the ideal profiles [m³/rev].
    factor : float
        Effective displacement factor k_D [-].
    """
    return (1.0 - factor) * displacement_m3 * omega / (2.0 * math.pi)


def bypass_flow(dp_pa: float, area_m2: float, density_kg_m3: float) -> float:
    """Turbulent flow from delivery to suction, :math:`A_b \\sqrt{2 \\max(Δp, 0)/ρ}` [m³/s].

    Parameters
    ----------
    dp_pa : float
        Delivery minus suction pressure [Pa].
    area_m2 : float
        Effective area C_d·A of the path [m²].
    density_kg_m3 : float
        Oil density [kg/m³].
    """
    return area_m2 * math.sqrt(2.0 * max(dp_pa, 0.0) / density_kg_m3) if area_m2 > 0 else 0.0


@dataclass(frozen=True)
class EdgeLosses:
    """The ``volumetric`` losses of one pump, ready to apply (module doc)."""
    displacement_m3: float       #: D, ideal profiles [m³/rev]
    displacement_factor: float   #: k_D [-]
    bypass_area_m2: float        #: A_b, effective area C_d·A [m²]
    density_kg_m3: float         #: ρ at the reference temperature [kg/m³]

    @classmethod
    def of(cls, cfg, displacement_m3: float) -> "EdgeLosses":
        """From a :class:`~gerotor_twin.config.PumpConfig` and its displacement [m³/rev]."""
        return cls(displacement_m3, cfg.displacement_factor, cfg.bypass_area_m2, cfg.fluid.density_kg_m3)

    def flow(self, omega: float, p_delivery_pa: float, p_suction_pa: float) -> float:
        """The flow lost at the edge [m³/s] at speed ``omega`` [rad/s] and the two pressures [Pa abs]."""
        return (displacement_deficit(omega, self.displacement_m3, self.displacement_factor)
                + bypass_flow(p_delivery_pa - p_suction_pa, self.bypass_area_m2, self.density_kg_m3))
