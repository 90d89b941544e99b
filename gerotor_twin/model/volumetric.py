r"""Losses at the edge of the chamber model: the effective displacement, a filling loss growing with speed and a
turbulent bypass path.

The chamber model delivers what its ideal (conjugate) profiles sweep, less the laminar leakage
of its gaps (tooth tips, lateral faces, drain: flow ∝ Δp h³/μ).  A real pump shows three more
kinds of loss that no clearance can make, each a physical parameter of the pump config's
``volumetric`` section:

* **Effective displacement** ``k_D`` (``displacement_factor``, 1 = the ideal profiles): the
  pump delivers less per revolution than its ideal profiles sweep, whatever the pressure —
  profile and assembly tolerances, chamber filling that ends before the suction kidney
  closes, dead volume re-expanded into the suction.  A deficit proportional to speed.
* **Filling loss** ``k_f`` (``filling_loss_at_1000rpm``, 0 = none): the chambers fill short by a
  fraction that grows as the square of the speed — the oil accelerating through the suction
  kidney takes a dynamic pressure ∝ ρ v² ∝ n² from the suction pressure, and the air that
  comes out of solution in that depression takes the chambers' room.  In the small-loss limit
  the unfilled fraction is that pressure drop over the suction pressure,
  :math:`k_f (ω/ω_1)^2 p_{atm}/p_s`, ``k_f`` its value at ω₁ = 1000 rpm and atmospheric suction.
  The chamber model has no such term: its liquid fills every chamber whatever the port's pressure
  drop, down to the vapour pressure (:mod:`gerotor_twin.hydraulics.mixture` leaves dissolved air
  out).  A deficit proportional to speed³ at a given suction pressure.  With a **filling margin**
  Δp_m (``filling_margin_pa``, 0 = none) the chambers absorb that much of the inlet's pressure drop before
  they fill short — the suction pressure's margin over the pressure at which air comes out of solution —
  and the unfilled fraction is the drop beyond it, :math:`\max(0, k_f p_{atm} (ω/ω_1)^2 - Δp_m)/p_s`: full
  chambers up to the onset speed :math:`ω_c = ω_1 \sqrt{Δp_m / (k_f p_{atm})}`.  Δp_m is a fixed pressure, the
  margin at the suction pressure it was fitted at; how the margin moves with another suction pressure is left out.
* **Bypass** ``A_b`` (``bypass_area_m2``, effective area C_d·A, 0 = none): a short,
  turbulent path from delivery to suction (a worn land of the valve plate, a weeping relief
  valve, a housing path): orifice flow, ∝ √Δp, independent of viscosity and speed — unlike
  the gaps' laminar leakage.

.. math::
    Q_\mathrm{delivered} = Q_\mathrm{model}
        - \Big(1 - k_D + \min\Big(1, \frac{\max(0,\ k_f p_{atm} (\omega/\omega_1)^2 - \Delta p_m)}{p_s}\Big)\Big)
          D \,\frac{\omega}{2\pi}
        - A_b \sqrt{\frac{2\, \max(p_d - p_s, 0)}{\rho}}

with ``D`` [m³/rev] the ideal profiles' displacement, ω [rad/s] the shaft speed, p_d, p_s
[Pa] the delivery and suction pressures (absolute), ω₁ = 1000 rpm, p_atm = 101 325 Pa and ρ
[kg/m³] the oil's density at the config's reference temperature (the path's flow goes as ρ^{-1/2}: about
1.5 % over 40 K, left out; the filling loss's dynamic pressure goes as ρ: its change with temperature is
left out too).  The filling law is the small-loss limit; it is clipped at the whole displacement and is not a
model of a pump running beyond its speed limit (where the flow saturates).  All three are applied to the
delivery flow after each model step (the steady state, the twin's instantaneous and per-revolution flows); the chamber pressures and the gaps' leakage are
the model's own, and the theoretical flow stays ``D ω / 2π``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["EdgeLosses", "displacement_deficit", "filling_deficit", "filling_onset_rad_s", "bypass_flow",
           "FILLING_REFERENCE_RAD_S", "FILLING_REFERENCE_PA"]

#: ω₁, the speed at which the filling loss is given: 1000 rpm [rad/s]
FILLING_REFERENCE_RAD_S = 1000.0 * math.pi / 30.0
#: the suction pressure at which the filling loss is given: atmospheric [Pa abs]
FILLING_REFERENCE_PA = 101325.0


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


def filling_deficit(omega: float, p_suction_pa: float, displacement_m3: float, k_fill: float,
                    margin_pa: float = 0.0) -> float:
    r"""Flow the chambers do not take in because they fill short at speed [m³/s].

    .. math::
        ΔQ = \min\Big(1,\ \frac{\max(0,\ k_f\, p_{atm} (ω/ω_1)^2 - Δp_m)}{p_s}\Big)\, D\, \frac{ω}{2π}

    Parameters
    ----------
    omega : float
        Shaft speed [rad/s].
    p_suction_pa : float
        Suction pressure [Pa abs]; at or below 0 the whole displacement is lost.
    displacement_m3 : float
        Displacement of the ideal profiles [m³/rev].
    k_fill : float
        Unfilled fraction at ω₁ = 1000 rpm and atmospheric suction, k_f [-].
    margin_pa : float
        Filling margin Δp_m: the inlet's pressure drop the chambers absorb before they fill short [Pa].

    Notes
    -----
    The small-loss limit of a filling short by the inlet's dynamic pressure (beyond the margin) over the
    suction pressure (module doc); meaningful while the fraction is a few per cent.
    """
    if k_fill <= 0.0:
        return 0.0
    drop = k_fill * FILLING_REFERENCE_PA * (omega / FILLING_REFERENCE_RAD_S) ** 2       # inlet's pressure drop [Pa]
    fraction = max(0.0, drop - margin_pa) / max(p_suction_pa, 1e-9)
    return min(1.0, fraction) * displacement_m3 * omega / (2.0 * math.pi)


def filling_onset_rad_s(k_fill: float, margin_pa: float) -> float:
    r"""The speed up to which the chambers fill fully, :math:`ω_c = ω_1 \sqrt{Δp_m / (k_f\, p_{atm})}` [rad/s]
    (0 without a margin; infinite without a filling loss).

    Parameters
    ----------
    k_fill : float
        Unfilled fraction at ω₁ = 1000 rpm and atmospheric suction, k_f [-].
    margin_pa : float
        Filling margin Δp_m [Pa].
    """
    if margin_pa <= 0.0:
        return 0.0
    if k_fill <= 0.0:
        return math.inf
    return FILLING_REFERENCE_RAD_S * math.sqrt(margin_pa / (k_fill * FILLING_REFERENCE_PA))


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
    filling_loss: float = 0.0    #: k_f, unfilled fraction at 1000 rpm and atmospheric suction [-]
    filling_margin_pa: float = 0.0   #: Δp_m, the inlet's pressure drop absorbed before the chambers fill short [Pa]

    @classmethod
    def of(cls, cfg, displacement_m3: float) -> "EdgeLosses":
        """From a :class:`~gerotor_twin.config.PumpConfig` and its displacement [m³/rev]."""
        return cls(displacement_m3, cfg.displacement_factor, cfg.bypass_area_m2, cfg.fluid.density_kg_m3,
                   cfg.filling_loss_at_1000rpm, cfg.filling_margin_pa)

    def flow(self, omega: float, p_delivery_pa: float, p_suction_pa: float) -> float:
        """The flow lost at the edge [m³/s] at speed ``omega`` [rad/s] and the two pressures [Pa abs]."""
        return (displacement_deficit(omega, self.displacement_m3, self.displacement_factor)
                + filling_deficit(omega, p_suction_pa, self.displacement_m3, self.filling_loss, self.filling_margin_pa)
                + bypass_flow(p_delivery_pa - p_suction_pa, self.bypass_area_m2, self.density_kg_m3))
