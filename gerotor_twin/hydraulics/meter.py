r"""Where a flow is measured: at the delivery pressure, or at atmospheric pressure (a meter in the return line).

A flow meter reads a volume flow at its own pressure.  The twin's delivery flow is stated at the delivery pressure
(as ISO 4409 states a pump's outlet flow); a meter in the return line, where many benches put their turbine or gear
meter, reads the same mass flow expanded back to atmospheric pressure, ρ(p_d)/ρ(p_atm) times more volume:

.. math:: Q_{atm} = Q_d\,\frac{\rho(p_d)}{\rho(p_{atm})} \approx Q_d\left(1 + \frac{p_d - p_{atm}}{\beta}\right)

(≈ 1.2 % at 170 bar with β ≈ 1.5 GPa; 0.2 % at 27.5 bar), a difference that grows with the pressure and not with
the speed: compared as if it were the outlet's, it reads as leakage that does not scale like leakage.  Isothermal:
a meter behind a cooler reads the cooled oil's volume, which this leaves out.

A meter also reads late: a first-order lag of time constant τ (:func:`lag_step`), which the twin's flows are read
through to be compared with the meter's readings while they settle (``report --flow-sensor-tau``, the health
monitor's ``flow_sensor_tau_s``).
"""
from __future__ import annotations

import math

__all__ = ["FLOW_METERS", "expansion", "oil_state_equation", "lag_step"]

#: Where a measured flow was read: ``delivery`` (at the delivery pressure: the twin's delivery flow) or
#: ``atmospheric`` (in the return line).  ``calibrate --flow-meter``, the twin's ``flow_meter`` setting.
FLOW_METERS = ("delivery", "atmospheric")


def expansion(p_from: float, p_to: float, eos) -> float:
    """ρ(p_from)/ρ(p_to) of the oil of the state equation ``eos`` [-]: a volume flow read at ``p_from`` [Pa abs]
    times this is the same mass's volume flow at ``p_to`` [Pa abs]."""
    from .state_equation import log_density_of       # numba: imported on first use, not with the setting's name
    return math.exp(log_density_of(p_from, eos) - log_density_of(p_to, eos))


def oil_state_equation(config, t_k: float | None = None):
    """The state equation of the oil of a pump ``config`` at T = ``t_k`` [K] (None: its reference temperature),
    built as the twin builds it (≈ 1–3 ms), for :func:`expansion`."""
    from .state_equation import state_equation
    return state_equation(config.fluid_at(t_k), config.fluid_model, config.air)


def lag_step(y: float, v: float, dt_s: float, tau_s: float) -> float:
    r"""A first-order-lag sensor's reading after ``dt_s`` [s] of the input ``v`` held, from the reading ``y``:

    .. math:: y' = v + (y - v)\, e^{-\Delta t/\tau}

    exact for :math:`\tau \dot y = v - y` with v constant over the interval; ``tau_s`` ≤ 0: ``v`` (no lag).
    Units: those of the signal; ``dt_s``, ``tau_s`` [s]."""
    if not tau_s > 0:
        return v
    return v + (y - v) * math.exp(-max(dt_s, 0.0) / tau_s)
