"""Hydraulic correlations of the lumped-parameter model (sections 3–3.5 of [1]).

Small numba-compiled SCALAR kernels (``gerotor_twin._jit.njit``, cached) that the
pump model's time loop calls; with ``NUMBA_DISABLE_JIT=1`` they run as plain
Python (the reference path).  SI units everywhere, pressures ABSOLUTE [Pa].

Every flow kernel returns ``(q, dq_ddp)``: the volume flow [m³/s], positive
from side "a" to side "b" when ``dp = p_a - p_b > 0``, and its analytic
derivative with respect to ``dp`` [m³/(s·Pa)] for the implicit integrator.
No kernel returns NaN/inf for finite input (dp = 0, area = 0, h = 0 included).

==================  ==============================================================
module              content
==================  ==============================================================
``fluid``           :class:`Fluid` (validated properties, ``kernel_params()``,
                    ``FP_*`` indices); ``bulk_modulus`` β(p) — Eq. (23) of [1],
                    C¹-smoothed, with vapour floor; ``log_density`` ln(ρ/ρ₀) =
                    ∫dp/β; ``density_ratio``
``state_equation``  :class:`StateEquation` for the kernels, mixture (default) or
                    Eq. (23): ``pressure_of`` p(ln ρ) (Hermite tables), ``state_of``
                    (p, β), ``log_density_of``, ``convert_log_density``
``oil``             :class:`OilProperties` vs temperature: ASTM D341 viscosity,
                    density with thermal expansion, β_L(T) (docs/fluid.md)
``mixture``         oil + free air + vapour barotropic mixture: closed-form
                    s(p), β(p), inverse; :class:`AirContent` (docs/fluid.md)
``orifice``         Eq. (21) of [1]: ``laminar_turbulent_flow`` (Merritt's laminar
                    Cd = δ√Re and turbulent Cd in series),
                    ``orifice_flow`` with ``discharge_coefficient``
                    Cd = Cd_max·tanh(2λ/λ_crit) (flow-number law, default),
                    ``port_orifice_flow`` (the configured one)
``gaps``            ``slot_flow`` (plane Poiseuille, sec. 3.3–3.4);
                    ``tooth_tip_flow`` — Eq. (22) of [1], Poiseuille + Couette;
                    lateral gaps as annular sectors (Gamez-Montero & Codina):
                    ``sector_circumferential_flow``, ``sector_couette_flow``,
                    ``sector_radial_flow``
==================  ==============================================================

Kernel signatures (argument order is part of the interface)::

    bulk_modulus(p, beta_star, ratio, p_atm, band, p_vap) -> (beta, dbeta_dp)
    log_density(p, beta_star, ratio, p_atm, band, p_vap) -> s
    density_ratio(p_up, p_down, beta_star, ratio, p_atm, band, p_vap) -> r
    discharge_coefficient(flow_number, cd_max, lambda_crit) -> cd
    orifice_flow(dp, area, cd_max, lambda_crit, rho, mu) -> (q, dq_ddp)
    laminar_turbulent_flow(dp, area, cd, delta, rho, mu) -> (q, dq_ddp)
    slot_flow(dp, h, width, length, mu) -> (q, dq_ddp)
    tooth_tip_flow(dp, h, le, v_r, width, mu) -> (q, dq_ddp)
    sector_circumferential_flow(dp, h, chi, r_in, r_out, mu) -> (q, dq_ddp)
    sector_couette_flow(h, omega, r_in, r_out) -> q
    sector_radial_flow(dp, h, chi, r_in, r_out, mu) -> (q, dq_ddp)

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear" (``/work/shared/paper``).
"""
from gerotor_twin.hydraulics.fluid import (
    FP_ATMOSPHERIC,
    FP_BULK_MODULUS,
    FP_CAVITATION_RATIO,
    FP_DENSITY,
    FP_SWITCH_BAND,
    FP_VAPOUR,
    FP_VISCOSITY,
    N_FLUID_PARAMS,
    Fluid,
    bulk_modulus,
    density_ratio,
    log_density,
)
from gerotor_twin.hydraulics.gaps import (
    sector_circumferential_flow,
    sector_couette_flow,
    sector_radial_flow,
    slot_flow,
    tooth_tip_flow,
)
from gerotor_twin.hydraulics.orifice import discharge_coefficient, orifice_flow

__all__ = [
    "Fluid",
    "FP_DENSITY",
    "FP_VISCOSITY",
    "FP_BULK_MODULUS",
    "FP_CAVITATION_RATIO",
    "FP_ATMOSPHERIC",
    "FP_VAPOUR",
    "FP_SWITCH_BAND",
    "N_FLUID_PARAMS",
    "bulk_modulus",
    "log_density",
    "density_ratio",
    "discharge_coefficient",
    "orifice_flow",
    "slot_flow",
    "tooth_tip_flow",
    "sector_circumferential_flow",
    "sector_couette_flow",
    "sector_radial_flow",
]
