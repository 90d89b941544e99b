"""Oil properties as functions of temperature, from the data a user has.

Viscosity from two data-sheet points through the ASTM D341 (Walther) chart
equation [1], density from the density at 15 °C and the thermal expansion
coefficient with the volume-correction form of ASTM D1250 / API MPMS 11.1 [2],
and the liquid's bulk modulus falling linearly with temperature, the zero-pressure
limit of the Tait equation of state used for mineral oils [3], [4].
Temperatures are in kelvin inside; °C, cSt only at the edges
(:mod:`gerotor_twin.units`).

======================================  ==============================================
name                                    content
======================================  ==============================================
:class:`OilProperties`                  validated oil (SI); ``viscosity(T)``,
                                        ``kinematic_viscosity(T)``, ``density(T)``,
                                        ``bulk_modulus(T)``; presets ``iso_vg(32|46|68)``,
                                        ``from_viscosity_points(...)``
:func:`walther_z`                       Z(ν) of ASTM D341 (with its low-ν term)
:func:`walther_nu`                      ν(Z), the inverse (ASTM formula + Newton)
:func:`walther_fit`                     (A, B) through two (T, ν) points
:func:`walther_kinematic_viscosity`     ν(T) [m²/s] from (A, B), numba kernel
:func:`expansion_coefficient_d1250`     α₁₅ = K₀/ρ₁₅² + K₁/ρ₁₅ (lubricating oils)
======================================  ==============================================

References
----------
.. [1] ASTM D341, *Standard Practice for Viscosity-Temperature Equations and
   Charts for Liquid Petroleum or Hydrocarbon Products* (Walther equation
   log log Z = A − B log T, Z = ν + 0.7 + exp(−1.47 − 1.84ν − 0.51ν²), inverse
   ν = (Z − 0.7) − exp(−0.7487 − 3.295(Z − 0.7) + 0.6119(Z − 0.7)² − 0.3193(Z − 0.7)³),
   ν in mm²/s, T in K), as reproduced in the Technical Toolboxes Pipeline
   Toolbox guide "ASTM D 341 Viscosity – Temperature Relations for Hydrocarbons",
   https://help.technicaltoolboxes.com/wiki/pipeline-hub-user-resources/pipeline-toolbox-user-guides/pipeline-miscellaneous-2/astm-d-341-viscosity-temperature-relations-for-hydrocarbons
.. [2] ASTM D1250-80 / API MPMS Chapter 11.1 (1980), Table 54D (lubricating
   oils): volume correction factor VCF = exp(−α₁₅ΔT(1 + 0.8 α₁₅ΔT)),
   α₁₅ = K₀/ρ₁₅² + K₁/ρ₁₅ with K₀ = 0, K₁ = 0.6278 kg/(m³·K).  Checked
   (2026-11-30) against an independent public implementation of the
   D1250-80 tables (an oil volume-correction calculator on GitHub whose
   "Table 54D, lube" case uses K₀ = 0, K₁ = 0.6278 with the same VCF form);
   the 60 °F Table 6D constant K₁ = 0.34878 /°F is the same value per kelvin
   (× 1.8).  The standard itself was not accessible.
.. [3] H. Gholizadeh, R. Burton, G. Schoenau, "Fluid bulk modulus: a literature
   survey", Int. J. Fluid Power 12(3), 2011, pp. 5–15 (isothermal tangent vs
   secant bulk modulus; it falls with temperature and rises with pressure;
   Tait-type equations of state for hydraulic oils).
.. [4] Maha Fluid Power Research Center (Purdue University), FSTI gap-flow
   code, fluid model ``HLP32_oil`` (file ``oil.cpp``, public copy in
   github.com/mitgandhi/PRJ_FSTI): Tait equation
   ρ = ρ_T/(1 − a₁ ln((a₂ + a₃T + p)/(a₂ + a₃T))), ρ_T = ρ_s(1 − α_s T),
   ρ_s = 1047.03 kg/m³, α_s = 5.761668e-4 1/K, a₁ = 0.0732965,
   a₂ = 1965.02 bar, a₃ = −2.96813 bar/K (T in K); its tangent bulk modulus at
   p = 0 is β_L = (a₂ + a₃T)/a₁, linear in T; viscosity
   μ = 1.702e-2·exp(5.428(50 − ϑ)/(94.72 + ϑ)) Pa·s at p = 0 (ϑ in °C).
.. [5] ISO 3448 (viscosity grades: ν at 40 °C = VG ± 10 %).  The presets'
   ν100 and ρ15 are values commonly listed for VI ≈ 100 mineral HM oils; they
   were first written from memory as "Shell Tellus S2 M typical values" and
   could not be verified against the data sheet: use the data sheet of the
   bench's oil (``oil.viscosity_points`` in the config).
.. [6] G. W. Stachowiak, A. W. Batchelor, *Engineering Tribology*, Table 2.3
   (dynamic viscosity of 13 mineral oils at 30 / 60 / 100 °C): a Walther fit
   through 30 and 100 °C predicts 60 °C with median error 1.8 %, 12 of 13
   within 5.5 %, one oil +12 % (test_hydraulics_oil).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from gerotor_twin._jit import njit
from gerotor_twin.errors import InputError, check_finite, check_range
from gerotor_twin.units import celsius_to_kelvin, cst_to_m2_s, m2_s_to_cst

__all__ = [
    "OilProperties",
    "walther_z",
    "walther_nu",
    "walther_fit",
    "walther_kinematic_viscosity",
    "expansion_coefficient_d1250",
    "ISO_VG_PRESETS",
    "D341_NU_MIN_CST",
    "T_MIN_K",
    "T_MAX_K",
]

#: Lowest kinematic viscosity covered by the D341 low-viscosity term [mm²/s].
D341_NU_MIN_CST = 0.21
#: Temperature range accepted by :class:`OilProperties` methods [K] (−40…200 °C).
T_MIN_K = 233.15
T_MAX_K = 473.15
#: Table 54D (lubricating oils) constants of ASTM D1250-80 [2].
D1250_K0 = 0.0       # [kg²/(m⁶·K)]
D1250_K1 = 0.6278    # [kg/(m³·K)]
_T15_K = 288.15      # 15 °C [K]

#: ISO VG presets [5]: (ν40 [cSt], ν100 [cSt], ρ15 [kg/m³]), typical VI ≈ 100 mineral HM
#: oils (not verified against a data sheet); the grade itself (ISO 3448) fixes only ν40 ± 10 %.
ISO_VG_PRESETS = {
    32: (32.0, 5.4, 875.0),
    46: (46.0, 6.8, 879.0),
    68: (68.0, 8.6, 886.0),
}


# ==========================================================================
# Walther / ASTM D341
# ==========================================================================
@njit
def walther_z(nu_cst):
    r"""Z(ν) of ASTM D341 [1]: Z = ν + 0.7 + exp(−1.47 − 1.84ν − 0.51ν²).

    Parameters
    ----------
    nu_cst : float
        Kinematic viscosity [mm²/s] (cSt), ≥ 0.21 for the low-ν term to be valid.

    Returns
    -------
    z : float
        Walther's Z [mm²/s].

    Notes
    -----
    The exponential term (added to D341 for 0.21–2 mm²/s) is < 1e-3 above
    2 mm²/s and < 1e-16 above 6 mm²/s: for hydraulic oils Z = ν + 0.7, the
    classical Walther form.
    """
    return nu_cst + 0.7 + math.exp(-1.47 - 1.84 * nu_cst - 0.51 * nu_cst * nu_cst)


@njit
def walther_nu(z):
    r"""Inverse of :func:`walther_z`: ν [mm²/s] from Z [mm²/s].

    Notes
    -----
    Starts from the explicit inverse of D341 [1],

    .. math::
        \nu_0 = (Z - 0.7) - \exp(-0.7487 - 3.295 y + 0.6119 y^2 - 0.3193 y^3),
        \quad y = Z - 0.7,

    then three Newton steps on Z(ν) − Z = 0 (dZ/dν = 1 − (1.84 + 1.02ν)·exp(…)
    ≥ 0.86 on ν ≥ 0), so that ``walther_nu(walther_z(nu)) == nu`` to
    round-off and a Walther fit returns its data points exactly.
    """
    y = z - 0.7
    nu = y - math.exp(-0.7487 - 3.295 * y + 0.6119 * y * y - 0.3193 * y * y * y)
    for _ in range(3):
        e = math.exp(-1.47 - 1.84 * nu - 0.51 * nu * nu)
        nu -= (nu + 0.7 + e - z) / (1.0 - (1.84 + 1.02 * nu) * e)
    return nu


def walther_fit(t1_k: float, nu1_cst: float, t2_k: float, nu2_cst: float) -> tuple[float, float]:
    r"""Walther constants (A, B) through two points (ASTM D341 [1]).

    Parameters
    ----------
    t1_k, t2_k : float
        Temperatures of the two data points [K], distinct.
    nu1_cst, nu2_cst : float
        Kinematic viscosities at those temperatures [mm²/s].

    Returns
    -------
    a, b : float
        Constants of log₁₀ log₁₀ Z = A − B log₁₀ T [-].

    Notes
    -----
    .. math::
        B = \frac{\log\log Z_1 - \log\log Z_2}{\log T_2 - \log T_1},\qquad
        A = \log\log Z_1 + B \log T_1
    """
    w1 = math.log10(math.log10(walther_z(nu1_cst)))
    w2 = math.log10(math.log10(walther_z(nu2_cst)))
    b = (w1 - w2) / (math.log10(t2_k) - math.log10(t1_k))
    return w1 + b * math.log10(t1_k), b


@njit
def walther_kinematic_viscosity(t_k, a, b):
    r"""Kinematic viscosity ν(T) [m²/s] of the Walther equation (numba kernel).

    Parameters
    ----------
    t_k : float
        Temperature [K] (> 0).
    a, b : float
        Walther constants of :func:`walther_fit` [-].

    Returns
    -------
    nu : float
        Kinematic viscosity [m²/s].

    Notes
    -----
    .. math::
        Z = 10^{10^{A - B\log_{10} T}},\qquad \nu = \nu(Z)\ \text{(:func:`walther_nu`)}
    """
    z = 10.0 ** (10.0 ** (a - b * math.log10(t_k)))
    return walther_nu(z) * 1e-6


def expansion_coefficient_d1250(density_15_kg_m3: float) -> float:
    r"""Thermal expansion coefficient at 15 °C of a lubricating oil [1/K], Table 54D [2].

    .. math::
        \alpha_{15} = \frac{K_0}{\rho_{15}^2} + \frac{K_1}{\rho_{15}},\quad
        K_0 = 0,\ K_1 = 0.6278\ \mathrm{kg/(m^3\,K)}

    (≈ 7.1e-4 1/K at 879 kg/m³).
    """
    return D1250_K0 / density_15_kg_m3 ** 2 + D1250_K1 / density_15_kg_m3


# ==========================================================================
# User-facing container
# ==========================================================================
@dataclass(frozen=True)
class OilProperties:
    r"""Validated properties of a hydraulic oil versus temperature (SI, kelvin).

    Parameters
    ----------
    viscosity_temperature_a_k : float
        Temperature of the first viscosity point [K]. Default 313.15 (40 °C).
    kinematic_viscosity_a_m2_s : float
        Kinematic viscosity at that temperature [m²/s]. Default 46e-6 (VG46).
    viscosity_temperature_b_k : float
        Temperature of the second viscosity point [K]. Default 373.15 (100 °C).
    kinematic_viscosity_b_m2_s : float
        Kinematic viscosity there [m²/s]; lower than point a if T_b > T_a.
        Default 6.8e-6.
    density_15_kg_m3 : float
        Density at 15 °C and atmospheric pressure [kg/m³]. Default 879.
    expansion_15_per_k : float or None
        Thermal expansion coefficient α₁₅ at 15 °C [1/K]; None: Table 54D of
        ASTM D1250 [2] from ``density_15_kg_m3`` (≈ 7.1e-4).
    bulk_modulus_ref_pa : float
        Isothermal tangent bulk modulus of the air-free liquid at
        ``bulk_modulus_temperature_k`` and atmospheric pressure [Pa].
        Default 1.5e9 (the paper's β at its 40 °C oil).
    bulk_modulus_temperature_k : float
        Temperature of ``bulk_modulus_ref_pa`` [K]. Default 313.15.
    bulk_modulus_temp_coeff_per_k : float
        k_β = −(dβ_L/dT)/β_ref [1/K]. Default 2.866e-3: the HLP32 Tait model of
        [4], −a₃/(a₂ + a₃·313.15 K).  Must keep β_L ≥ 0.1 β_ref up to 473.15 K.
    name : str
        Label (e.g. ``"ISO VG46"``).

    Raises
    ------
    InputError
        Naming ``oil.<field>``, the value and the allowed range.

    Notes
    -----
    Kinematic viscosity (ASTM D341 [1], T in K, ν in mm²/s):

    .. math::
        \log_{10}\log_{10} Z(\nu) = A - B\log_{10} T

    with A, B through the two points (:func:`walther_fit`); dynamic
    viscosity μ(T) = ρ(T) ν(T).  Density [2]:

    .. math::
        \rho(T) = \rho_{15}\exp\left(-\alpha_{15}\Delta T\,(1 + 0.8\,\alpha_{15}\Delta T)\right),
        \quad \Delta T = T - 288.15\ \mathrm{K}

    Bulk modulus of the liquid (isothermal tangent, p → 0) [3], [4]:

    .. math::
        \beta_L(T) = \beta_{ref}\,\left(1 - k_\beta (T - T_{ref})\right)

    Validity: T in [233.15, 473.15] K (−40…200 °C); D341 holds for
    ν ≥ 0.21 mm²/s and for mineral oils without VI improver shear effects
    (Newtonian); its typical interpolation error between the two points is
    1.8 % (median over the 13 oils of [6]; up to 5.5 %, one oil 12 %) and grows
    on extrapolation.  Pressure effects on μ (Barus) and on
    β_L (the Tait model of [4] gives +2.7 % at 30 bar, 40 °C) are not included.  The
    default k_β (β_L −11.5 % from 40 to 80 °C) is one mineral HLP oil's; two
    other published fits in [4] (Mobil DTE 10 Excel 32, MIL-PRF-87257) fall
    by 4.6e-3 and 3.5e-3 1/K (relative, 25–80 °C): set k_β from a
    measurement of the bench oil when one exists.
    """

    viscosity_temperature_a_k: float = 313.15
    kinematic_viscosity_a_m2_s: float = 46e-6
    viscosity_temperature_b_k: float = 373.15
    kinematic_viscosity_b_m2_s: float = 6.8e-6
    density_15_kg_m3: float = 879.0
    expansion_15_per_k: float | None = None
    bulk_modulus_ref_pa: float = 1.5e9
    bulk_modulus_temperature_k: float = 313.15
    bulk_modulus_temp_coeff_per_k: float = 2.866e-3
    name: str = "ISO VG46"

    def __post_init__(self) -> None:
        def put(name, value):
            object.__setattr__(self, name, value)

        for f in ("viscosity_temperature_a_k", "viscosity_temperature_b_k",
                  "bulk_modulus_temperature_k"):
            put(f, check_range(f"oil.{f}", getattr(self, f), T_MIN_K, T_MAX_K, unit="K"))
        nu_min = cst_to_m2_s(D341_NU_MIN_CST)
        for f in ("kinematic_viscosity_a_m2_s", "kinematic_viscosity_b_m2_s"):
            put(f, check_range(f"oil.{f}", getattr(self, f), nu_min, 1.0, unit="m^2/s"))
        ta, tb = self.viscosity_temperature_a_k, self.viscosity_temperature_b_k
        if abs(tb - ta) < 1.0:
            raise InputError("oil.viscosity_temperature_b_k", tb, f"at least 1 K away from {ta:g} K",
                             reason="two distinct temperatures are needed for the Walther fit")
        hot_nu, cold_nu = ((self.kinematic_viscosity_b_m2_s, self.kinematic_viscosity_a_m2_s)
                           if tb > ta else
                           (self.kinematic_viscosity_a_m2_s, self.kinematic_viscosity_b_m2_s))
        if not hot_nu < cold_nu:
            field = "oil.kinematic_viscosity_b_m2_s" if tb > ta else "oil.kinematic_viscosity_a_m2_s"
            raise InputError(field, hot_nu, f"(0.21e-6, {cold_nu:g}) m^2/s",
                             reason="viscosity must fall as temperature rises")
        put("density_15_kg_m3", check_range("oil.density_15_kg_m3", self.density_15_kg_m3,
                                            500.0, 2000.0, unit="kg/m^3"))
        if self.expansion_15_per_k is None:
            put("expansion_15_per_k", expansion_coefficient_d1250(self.density_15_kg_m3))
        put("expansion_15_per_k", check_range("oil.expansion_15_per_k", self.expansion_15_per_k,
                                              0.0, 2e-3, unit="1/K"))
        put("bulk_modulus_ref_pa", check_range("oil.bulk_modulus_ref_pa", self.bulk_modulus_ref_pa,
                                               1e8, 1e10, unit="Pa"))
        k_max = 0.9 / (T_MAX_K - self.bulk_modulus_temperature_k) \
            if self.bulk_modulus_temperature_k < T_MAX_K else 0.05
        put("bulk_modulus_temp_coeff_per_k",
            check_range("oil.bulk_modulus_temp_coeff_per_k", self.bulk_modulus_temp_coeff_per_k,
                        0.0, min(k_max, 0.05), unit="1/K"))
        a, b = walther_fit(ta, m2_s_to_cst(self.kinematic_viscosity_a_m2_s),
                           tb, m2_s_to_cst(self.kinematic_viscosity_b_m2_s))
        put("_walther_a", a)
        put("_walther_b", b)

    # ---------------------------------------------------------------- builders
    @classmethod
    def from_viscosity_points(cls, nu_a_cst: float, t_a_c: float, nu_b_cst: float, t_b_c: float,
                              **kwargs) -> "OilProperties":
        """Oil from two data-sheet points in cSt and °C (the units of a data sheet).

        Parameters
        ----------
        nu_a_cst, nu_b_cst : float
            Kinematic viscosities [mm²/s].
        t_a_c, t_b_c : float
            Their temperatures [°C].
        **kwargs
            Other :class:`OilProperties` fields (SI).
        """
        return cls(viscosity_temperature_a_k=celsius_to_kelvin(check_finite("oil.t_a_c", t_a_c)),
                   kinematic_viscosity_a_m2_s=cst_to_m2_s(check_finite("oil.nu_a_cst", nu_a_cst)),
                   viscosity_temperature_b_k=celsius_to_kelvin(check_finite("oil.t_b_c", t_b_c)),
                   kinematic_viscosity_b_m2_s=cst_to_m2_s(check_finite("oil.nu_b_cst", nu_b_cst)),
                   **kwargs)

    @classmethod
    def iso_vg(cls, grade: int, **kwargs) -> "OilProperties":
        """Preset of an ISO VG 32/46/68 mineral hydraulic oil (HM), typical values (see [5]).

        Parameters
        ----------
        grade : int
            32, 46 or 68.
        **kwargs
            Overrides of other fields (e.g. ``bulk_modulus_ref_pa``).
        """
        if grade not in ISO_VG_PRESETS:
            raise InputError("oil.grade", grade, "one of 32, 46, 68")
        nu40, nu100, rho15 = ISO_VG_PRESETS[grade]
        kwargs.setdefault("name", f"ISO VG{grade}")
        return cls.from_viscosity_points(nu40, 40.0, nu100, 100.0, density_15_kg_m3=rho15, **kwargs)

    # ----------------------------------------------------------------- queries
    def _temperature(self, t_k: float) -> float:
        return check_range("oil_temperature_k", t_k, T_MIN_K, T_MAX_K, unit="K")

    @property
    def walther_constants(self) -> tuple[float, float]:
        """(A, B) of log₁₀ log₁₀ Z = A − B log₁₀ T [-] (T in K)."""
        return self._walther_a, self._walther_b

    def kinematic_viscosity(self, t_k: float) -> float:
        """Kinematic viscosity ν(T) [m²/s] (ASTM D341), T [K]."""
        return walther_kinematic_viscosity(self._temperature(t_k), self._walther_a, self._walther_b)

    def density(self, t_k: float) -> float:
        """Density ρ(T) at atmospheric pressure [kg/m³] (ASTM D1250 form), T [K]."""
        dt = self._temperature(t_k) - _T15_K
        a = self.expansion_15_per_k
        return self.density_15_kg_m3 * math.exp(-a * dt * (1.0 + 0.8 * a * dt))

    def viscosity(self, t_k: float) -> float:
        """Dynamic viscosity μ(T) = ρ(T)·ν(T) [Pa·s], T [K]."""
        return self.density(t_k) * self.kinematic_viscosity(t_k)

    def bulk_modulus(self, t_k: float) -> float:
        """Isothermal bulk modulus of the air-free liquid β_L(T) [Pa], T [K]."""
        dt = self._temperature(t_k) - self.bulk_modulus_temperature_k
        return self.bulk_modulus_ref_pa * (1.0 - self.bulk_modulus_temp_coeff_per_k * dt)
