"""The pump as the compiled kernels see it: named structures built from the config.

Three structures, each field named once with its unit, travel together as one
:class:`KernelModel`:

=====================  ==========================================================
:class:`KernelTables`  geometry over the shaft angle (rows = angle samples)
:class:`PumpConstants` clearances, conductances, orifice law, boundary, numerics
``StateEquation``      the oil's ln ρ ⇄ p (:mod:`gerotor_twin.hydraulics.state_equation`),
                       mixture or eq. (23) (config ``fluid_model``)
=====================  ==========================================================

:class:`Operating` holds what is constant over one ``advance`` call (speed,
port pressures and their log-densities) and :class:`Workspace` every scratch
array of the hot loop, allocated once per model so a step allocates nothing.
:func:`kernel_model` is the one place where config values become kernel values;
:func:`at_temperature` re-evaluates the oil-dependent ones at another oil temperature, :func:`at_load` the
lateral conductances at another delivery − suction pressure (a lateral gap that opens with it, :func:`lateral_gap`).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._jit import typed
from ..config import PumpConfig
from ..geometry.lateral import LateralGeometry
from ..geometry.tables import GeometryTables
from ..hydraulics.gaps import sector_circumferential_flow, sector_radial_flow
from ..hydraulics.orifice import ORIFICE_LAWS
from .gear_coupling import N_GEAR, N_ROWS
from ..hydraulics.state_equation import StateEquation, port_states, state_equation, with_liquid_modulus

__all__ = ["KernelTables", "PumpConstants", "KernelModel", "Operating", "Workspace", "kernel_model",
           "operating", "workspace", "at_temperature", "at_load", "lateral_gap", "N_FLOWS", "FL_DELIVERY", "FL_SUCTION", "FL_SUCTION_DELIVERY",
           "FL_DRAIN", "FL_RESTRICTION", "FL_MASS_IN", "FL_MASS_OUT", "ERROR_LOG_DENSITY", "ERROR_PRESSURE",
           "CT_SUBSTEP", "CT_FRESH", "FRESH_NONE", "FRESH_IN_F0", "FRESH_IN_F1", "CT_PENDING", "CT_CLOSING", "CT_RANGE", "CT_STATUS", "CT_BOUND",
           "CT_DEFECT_H", "CT_CMAT_END", "N_CTRL"]

#: Indices of the flow vector the right-hand side fills (and of the integrals ∫ flow dt):
#: delivered (net out of the delivery port, after the line leakages) [m³/s], in through the
#: suction port [m³/s], suction–delivery leakage (sec. 3.3) [m³/s], drain (sec. 3.4) [m³/s],
#: through the delivery restriction [m³/s], port mass flows / ρ₀ in and out [m³/s].
(FL_DELIVERY, FL_SUCTION, FL_SUCTION_DELIVERY, FL_DRAIN, FL_RESTRICTION, FL_MASS_IN,
 FL_MASS_OUT) = range(7)
N_FLOWS = 7

#: Error measures of the sub-step control: on ln(ρ/ρ₀) (absolute) or on the pressure,
#: relative to the error scale (``step_control.error_scale``).
ERROR_LOG_DENSITY, ERROR_PRESSURE = 0, 1

#: ``Workspace.ctrl`` entries: the proposed sub-step [s]; 1 if f0/jac hold the RHS at the current (y, θ), 2 if
#: f1/jac_end hold it (the defect check's at the sub-step it accepted: :data:`FRESH_IN_F1`), 0 if neither; the
#: pending sub-step [s]; how many ports close within the horizon; the chamber pressures' recent range [Pa]; why
#: the last output step was abandoned; the sub-step attempts an output step may take; the sub-step [s] above which
#: the defect check runs (``step_control.defect_threshold``); 1 if ``Workspace.cmat`` holds the gap expansions at
#: the end of the next output step (``gear_coupling.set_constraint``); 1 if ``Workspace.geo`` holds the table values
#: at the angle [rad] and of the table (its rows' address) in the next two slots (``flows.chamber_geometry``) (see
#: ``Workspace.ctrl``)
CT_SUBSTEP, CT_FRESH, CT_PENDING, CT_CLOSING, CT_RANGE, CT_STATUS, CT_BOUND, CT_DEFECT_H, CT_CMAT_END, \
    CT_GEO_OK, CT_GEO_THETA, CT_GEO_TABLE = range(12)
N_CTRL = 12
#: ``Workspace.ctrl[CT_FRESH]``: f0/jac hold the right-hand side and Jacobian at the current state (1), f1/jac_end
#: hold them (2: the defect check evaluated them at the sub-step it accepted), or neither (0)
FRESH_NONE, FRESH_IN_F0, FRESH_IN_F1 = 0.0, 1.0, 2.0


#: columns of ``Workspace.jac`` after ∂f/∂y: ∂f/∂t and the closing ports' shares (:mod:`.flows`, ``J_*``)
N_JAC_EXTRA = 6


class KernelTables(NamedTuple):
    """Geometry of chamber 0 / lobe 0 sampled over one chamber period (see geometry.tables)."""
    rows: np.ndarray    #: (M, len(COLUMNS)): one row per angle sample, columns as ``COLUMNS`` [SI]
    period: float       #: chamber period Θ = 2πN/(N−1) [rad]
    shift: float        #: lead of chamber j+1 over chamber j, 2π/(N−1) [rad]
    scale: float        #: M/Θ, samples per radian [1/rad]
    #: sec. 3.7 "no overlap" branch: turn the inner gear until one lobe touches (False: the gears keep
    #: their nominal angles; the fixed-centre model with ``micro_motion.fixed_centre_contact: none``)
    turn_inner: bool = True
    #: chamber volumes follow the outer gear (``micro_motion.chamber_volumes: displaced``,
    #: :mod:`gerotor_twin.model.volumes`); False: volumes of the centred gear set
    volumes_follow_gear: bool = True


class PumpConstants(NamedTuple):
    """Everything scalar the right-hand side and the stepper need (SI)."""
    n: int                      #: number of chambers N [-]
    width: float                #: gear width b = L [m]
    tip_clearance: float        #: δ, nominal tooth-tip clearance [m]
    tip_dh: float               #: dh of the equivalent gap length (sec. 3.1) [-]
    cd_max: float               #: turbulent discharge coefficient [-]
    lambda_crit: float          #: critical flow number of Cd(λ) [-]
    density: float             #: ρ₀ [kg/m³]
    viscosity: float            #: μ [Pa·s]
    g_lateral: float            #: lateral conductance across one lobe land, both faces [m³/(s·Pa)]
    g_suction_delivery: float   #: suction–delivery conductance (sec. 3.3) [m³/(s·Pa)]
    g_drain: float              #: delivery–drain conductance (sec. 3.4) [m³/(s·Pa)]
    housing_clearance: float    #: c, outer gear–housing radial clearance [m]
    journal_radius: float       #: outer-gear radius = journal radius [m]
    eps_max: float              #: largest eccentricity ratio before housing contact [-]
    restriction: bool           #: delivery volume is a state behind a restriction (sec. 4)
    line_volume: float          #: delivery line volume (restriction mode) [m³]
    restriction_area: float     #: restriction orifice area [m²]
    p_tank: float               #: pressure behind the restriction [Pa]
    tolerance: float            #: sub-step error tolerance (measure: ``error_measure``) [-]
    error_measure: int          #: ERROR_LOG_DENSITY or ERROR_PRESSURE
    log_density_tolerance: float  #: cap of the ln ρ error where β is small (ERROR_PRESSURE) [-]
    tip_flow_factor: float = 1.0  #: multiplies the tooth-tip flow, Eq. (22) (0: tips sealed; what-if runs) [-]
    orifice_law: int = 0          #: LAW_FLOW_NUMBER or LAW_MERRITT (hydraulics.orifice)
    laminar_delta: float = 0.2    #: Merritt's laminar flow coefficient δ (Cd = δ√Re) [-]
    closing_tolerance: float = 1.0  #: factor on ``tolerance`` where a delivery port is closing (numerics) [-]
    gear_in_stages: bool = False  #: the mobility gear's squeeze inside the ROS2 stages (numerics.gear_coupling) [-]
    gear_constrained: bool = False  #: the tooth contact as a constraint on the gear in the stages (gear_coupling) [-]


class KernelModel(NamedTuple):
    """The three structures the kernels take as one argument."""
    tab: KernelTables
    pc: PumpConstants
    eos: StateEquation


class Operating(NamedTuple):
    """Inputs held over one ``advance`` call, with what the kernels derive from them."""
    omega: float        #: shaft speed [rad/s]
    p_s: float          #: suction pressure, absolute [Pa]
    p_d: float          #: delivery pressure, absolute [Pa] (initial value in restriction mode)
    rho_s: float        #: ρ(p_s)/ρ₀ [-]
    s_d: float          #: ln(ρ(p_d)/ρ₀) [-]
    dp_ref: float       #: floor of the error measure's pressure scale, max(p_d − p_s, 1 bar) [Pa] (step_control.error_scale)
    beta_d: float = 0.0  #: β(p_d), bulk modulus at the delivery pressure [Pa]
    rho_d: float = 1.0   #: e^{s_d} = ρ(p_d)/ρ₀ [-]


class Workspace(NamedTuple):
    """Scratch arrays of the hot loop (one per model; not shared between threads)."""
    p: np.ndarray           #: (N+1,) pressures of the current RHS [Pa]
    beta: np.ndarray        #: (N+1,) bulk moduli [Pa]
    rho: np.ndarray         #: (N+1,) ρ/ρ₀ [-]
    acc: np.ndarray         #: (N+1,) Σ (ρ_up/ρ) Q into each volume [m³/s]
    geo: np.ndarray         #: (N, 10) V, dV/dθ, A_s, A_d, κ_rel, v_r/ω and four θ-slopes of each chamber (flows.G_*)
    f0: np.ndarray          #: (N+1,) RHS at the start of a sub-step [1/s]
    f1: np.ndarray          #: (N+1,) RHS at the second stage [1/s]
    k1: np.ndarray
    k2: np.ndarray
    y1: np.ndarray
    ynew: np.ndarray
    err: np.ndarray
    wt: np.ndarray          #: (N+1,) error weights [1/-]
    jac: np.ndarray         #: (N+1, N+7) ∂f/∂y [1/s], then ∂f/∂t [1/s²] and the closing ports' shares (flows.J_*)
    jac_end: np.ndarray     #: (N+1, N+7) ... at the end of a sub-step the defect check evaluates (kernel._defect_norm)
    lu: np.ndarray          #: (N+1, N+1) LU of I − γ h J
    piv: np.ndarray         #: (N+1,) pivots
    gaps0: np.ndarray       #: (N,) tooth-tip gaps at the sub-step start [m]
    gaps1: np.ndarray       #: (N,) ... at its end [m]
    gaps_start: np.ndarray  #: (N,) gaps at the start of the output step [m]
    gaps_end: np.ndarray    #: (N,) ... at its end, gear displacement frozen [m]
    cmat: np.ndarray        #: (N, 9) gap expansion coefficients per lobe
    pres: np.ndarray        #: (N+1,) pressures after an output step [Pa]
    flows: np.ndarray       #: (N_FLOWS,) flows of the last RHS [m³/s]
    flows_prev: np.ndarray  #: (N_FLOWS,) flows at the first stage of the current sub-step [m³/s]
    ctrl: np.ndarray        #: (N_CTRL,) proposed sub-step [s]; 1 if f0/jac hold the RHS at the current (y, θ);
                            #: length of the accepted sub-step whose flow integral is pending [s];
                            #: how many ports close within the horizon there (flows.closing_ports);
                            #: the chamber pressures' recent range, the error scale's (step_control.update_range) [Pa];
                            #: why the last output step was abandoned (kernel.STEP_*);
                            #: the sub-step attempts an output step may take (numerics.max_substep_attempts);
                            #: the sub-step above which the defect check runs (step_control.defect_threshold) [s];
                            #: 1 if ``cmat`` holds the next output step's end (gear_coupling.set_constraint)
    disp: np.ndarray        #: (4,) outer-gear displacement the chamber volumes are taken at [m] and the
                            #: velocity of its last move [m/s] (:mod:`.volumes`), set from the state at each
                            #: ``advance`` (``PumpState.eccentricity``, ``squeeze_velocity``) and returned in it
    peak: np.ndarray        #: (N,) max of each chamber's ln ρ over the current output step so far [-]
    gear: np.ndarray        #: (N_GEAR,) the outer gear's velocity in the stages (:mod:`.gear_coupling`, ``GC_*``)
    gear_rows: np.ndarray   #: (N, N_ROWS) per chamber ∂V/∂e [m³/m] and ∂F/∂p [N/Pa] of the coupled load, their θ-slopes (gear_coupling)


def lateral_gap(config: PumpConfig, dp_pa: float = 0.0) -> float:
    r"""Lateral clearance of each gear face under the pressure load, :math:`s = s_0 + c\,\max(Δp, 0)` [m].

    Parameters
    ----------
    config : PumpConfig
        Pump: :math:`s_0` = ``clearances.lateral_m`` [m], :math:`c` = ``clearances.lateral_opening_m_per_pa``
        [m/Pa].
    dp_pa : float
        Delivery minus suction pressure [Pa].

    Notes
    -----
    The delivery pressure acting on the side plates and the housing deflects them and opens the lateral gaps
    (the structural deformation that sets the lateral film, [1]); linear elasticity makes the opening
    proportional to the load, so the gaps' laminar leakage, ∝ s³, goes as :math:`Δp\,(1 + cΔp/s_0)^3` instead
    of Δp.  One opening for every lateral path (lobe, suction–delivery ring, drain), the whole face deflecting
    alike; a negative Δp (suction above delivery) does not close it.  A pressure-compensated plate, pressed
    closer as Δp rises (c < 0), is not represented.

    References
    ----------
    .. [1] Thiagarajan, D., Vacca, A. "Mixed Lubrication Effects in the Lateral Lubricating Interfaces of
       External Gear Machines: Modelling and Experimental Validation", Energies 10(1), 111, 2017 (the
       structural deformation of gears and plates under the pressure load sets the lateral film thickness and
       the leakage through it).
    """
    c = config.clearances
    return c.lateral_m + c.lateral_opening_m_per_pa * max(float(dp_pa), 0.0)


def _conductances(config: PumpConfig, lat: LateralGeometry, mu: float, dp_pa: float = 0.0) -> tuple[float, float, float]:
    """Lateral, suction–delivery and drain conductances [m³/(s·Pa)] at viscosity μ [Pa·s] and delivery − suction
    pressure Δp [Pa] (:func:`lateral_gap`): flows at a pressure difference of 1 Pa across the path, both faces
    (each ∝ s³/μ)."""
    h, faces = lateral_gap(config, dp_pa), 2.0
    g_lat = faces * sector_circumferential_flow(1.0, h, lat.chi_lobe, lat.lobe_r_in, lat.lobe_r_out, mu)[0]
    g_sd = faces * (sector_circumferential_flow(1.0, h, lat.chi1, lat.ring_r_in, lat.ring_r_out, mu)[0]
                    + sector_circumferential_flow(1.0, h, lat.chi2, lat.ring_r_in, lat.ring_r_out, mu)[0])
    g_dr = faces * sector_radial_flow(1.0, h, lat.chi3, lat.drain_r_in, lat.drain_r_out, mu)[0]
    return g_lat, g_sd, g_dr


def kernel_model(config: PumpConfig, tables: GeometryTables, lateral: LateralGeometry,
                 eps_max: float = 0.95, temperature_k: float | None = None) -> KernelModel:
    """Kernel view of a validated config at oil temperature T [K] (None: the config's reference temperature).

    The conductances of sec. 3.2–3.4 are evaluated once; the oil's μ, ρ₀ and β
    are those at T (:meth:`PumpConfig.fluid_at`), the state equation is the
    config's ``fluid_model``.
    """
    g, n = config.gears, config.numerics
    f = config.fluid_at(temperature_k)
    g_lat, g_sd, g_dr = _conductances(config, lateral, f.viscosity_pa_s)
    tab = KernelTables(rows=np.ascontiguousarray(tables.data.T), period=tables.period, shift=tables.shift,
                       scale=tables.size / tables.period)
    measure = ERROR_PRESSURE if n.error_measure == "pressure" else ERROR_LOG_DENSITY
    pc = PumpConstants(
        n=g.chambers, width=g.width, tip_clearance=g.tip_clearance, tip_dh=config.tip_dh,
        cd_max=config.orifice.cd_max, lambda_crit=config.orifice.lambda_crit, density=f.density_kg_m3,
        viscosity=f.viscosity_pa_s, g_lateral=g_lat, g_suction_delivery=g_sd, g_drain=g_dr,
        housing_clearance=config.clearances.housing_radial_m, journal_radius=g.outer_radius, eps_max=eps_max,
        restriction=config.boundary.mode == "restriction", line_volume=config.boundary.delivery_volume_m3,
        restriction_area=config.boundary.restriction_area_m2, p_tank=f.atmospheric_pa,
        tolerance=n.tolerance, error_measure=measure,
        log_density_tolerance=n.log_density_tolerance, closing_tolerance=n.closing_tolerance,
        orifice_law=ORIFICE_LAWS[config.orifice.law], laminar_delta=config.orifice.laminar_delta,
        gear_in_stages=n.gear_coupling in ("stages", "constrained"),
        gear_constrained=n.gear_coupling == "constrained")
    return typed(KernelModel(tab=tab, pc=pc, eos=state_equation(f, config.fluid_model, config.air)))


def at_temperature(km: KernelModel, config: PumpConfig, lateral: LateralGeometry,
                   temperature_k: float | None) -> KernelModel:
    """``km`` with the oil properties at T [K]: μ, ρ₀, the conductances (∝ 1/μ; the unloaded gaps: follow with
    :func:`at_load` for a gap that opens with pressure) and the state equation.

    The geometry tables are shared, not rebuilt; cost ≈ 1–3 ms (the state
    equation's table).  The state of a model must be converted with
    :func:`~gerotor_twin.hydraulics.state_equation.convert_log_density`.
    """
    f = config.fluid_at(temperature_k)
    g_lat, g_sd, g_dr = _conductances(config, lateral, f.viscosity_pa_s)
    pc = km.pc._replace(density=f.density_kg_m3, viscosity=f.viscosity_pa_s, g_lateral=g_lat,
                        g_suction_delivery=g_sd, g_drain=g_dr)
    return typed(KernelModel(tab=km.tab, pc=pc, eos=with_liquid_modulus(km.eos, f, config.fluid_model, config.air)))


def at_load(km: KernelModel, config: PumpConfig, lateral: LateralGeometry, dp_pa: float) -> KernelModel:
    """``km`` with its lateral, suction–delivery and drain conductances at the gap the delivery − suction
    pressure ``dp_pa`` [Pa] opens (:func:`lateral_gap`), at ``km``'s viscosity; nothing else changes (≈ µs)."""
    g_lat, g_sd, g_dr = _conductances(config, lateral, km.pc.viscosity, dp_pa)
    return typed(km._replace(pc=km.pc._replace(g_lateral=g_lat, g_suction_delivery=g_sd, g_drain=g_dr)))


def operating(km: KernelModel, omega: float, p_s: float, p_d: float) -> Operating:
    """The :class:`Operating` record of one ``advance`` call [rad/s, Pa].

    ``dp_ref`` is the floor of the sub-step error scale; the kernel takes the larger of it and the chamber
    pressures' recent range (:func:`.step_control.error_scale`).
    """
    omega, p_s, p_d = float(omega), float(p_s), float(p_d)     # every field a float: the cached specialisation
    s_s, s_d, beta_d, rho_d = port_states(p_s, p_d, km.eos)
    return Operating(omega=omega, p_s=p_s, p_d=p_d, rho_s=float(np.exp(s_s)), s_d=float(s_d),
                     dp_ref=max(p_d - p_s, 1e5), beta_d=float(beta_d), rho_d=float(rho_d))


def workspace(n: int) -> Workspace:
    """Scratch arrays for a pump of ``n`` chambers."""
    n1 = n + 1

    def v(k=n1):
        return np.zeros(k)

    return Workspace(p=v(), beta=v(), rho=v(), acc=v(), geo=np.zeros((n, 16)), f0=v(), f1=v(), k1=v(), k2=v(),
                     y1=v(), ynew=v(), err=v(), wt=v(), jac=np.zeros((n1, n1 + N_JAC_EXTRA)),
                     jac_end=np.zeros((n1, n1 + N_JAC_EXTRA)), lu=np.zeros((n1, n1)),
                     piv=np.zeros(n1, dtype=np.int64), gaps0=v(n), gaps1=v(n), gaps_start=v(n), gaps_end=v(n), cmat=np.zeros((n, 9)),
                     pres=v(), flows=v(N_FLOWS), flows_prev=v(N_FLOWS), ctrl=v(N_CTRL),
                     disp=v(4), peak=np.full(n, -np.inf), gear=v(N_GEAR),
                     gear_rows=np.zeros((n, N_ROWS)))
