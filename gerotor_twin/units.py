"""Unit conversions, used only at the edges (CLI, reports, config comments).

Inside the package everything is SI: rad, rad/s, Pa (absolute), m, m^3/s, s.
"""
from __future__ import annotations

import math

P_ATM = 101325.0  #: standard atmosphere [Pa]


def rpm_to_rad_s(rpm: float) -> float:
    """Shaft speed [rpm] -> [rad/s]."""
    return rpm * 2.0 * math.pi / 60.0


def rad_s_to_rpm(omega: float) -> float:
    """Shaft speed [rad/s] -> [rpm]."""
    return omega * 60.0 / (2.0 * math.pi)


def bar_gauge_to_pa_abs(bar: float, p_atm: float = P_ATM) -> float:
    """Gauge pressure [bar] -> absolute pressure [Pa]."""
    return bar * 1e5 + p_atm


def pa_abs_to_bar_gauge(pa: float, p_atm: float = P_ATM) -> float:
    """Absolute pressure [Pa] -> gauge pressure [bar]."""
    return (pa - p_atm) / 1e5


def m3s_to_lpm(q: float) -> float:
    """Flow [m^3/s] -> [L/min]."""
    return q * 60000.0


ZERO_CELSIUS_K = 273.15  #: 0 °C in kelvin [K]


def celsius_to_kelvin(t_c: float) -> float:
    """Temperature [°C] -> [K]."""
    return t_c + ZERO_CELSIUS_K


def kelvin_to_celsius(t_k: float) -> float:
    """Temperature [K] -> [°C]."""
    return t_k - ZERO_CELSIUS_K


def cst_to_m2_s(nu_cst: float) -> float:
    """Kinematic viscosity [cSt] = [mm²/s] -> [m²/s]."""
    return nu_cst * 1e-6


def m2_s_to_cst(nu: float) -> float:
    """Kinematic viscosity [m²/s] -> [cSt] = [mm²/s]."""
    return nu * 1e6
