r"""The effective displacement: a flow deficit proportional to speed, applied where the delivery flow leaves the model.

The chamber model delivers what its ideal (conjugate) profiles sweep, less the leakage of its
gaps.  A real pump delivers less per revolution than its ideal profiles sweep, whatever the
pressure: profile and assembly tolerances, chamber filling that ends before the suction
kidney closes, dead volume re-expanded into the suction.  That deficit is proportional to the
volume swept, so it is carried by one factor on the displacement, ``k_D``
(``volumetric.displacement_factor`` of the pump config, 1 = the ideal profiles):

.. math::
    Q_\mathrm{delivered} = Q_\mathrm{model} - (1 - k_D)\, D \,\frac{\omega}{2\pi},
    \qquad
    \eta_v = \eta_{v,\mathrm{model}} - (1 - k_D)

with ``D`` [m³/rev] the ideal profiles' displacement and ω [rad/s] the shaft speed.  It is
applied to the model's delivery flow after each step (the chamber pressures and the gaps'
leakage are the model's own); the theoretical flow stays ``D ω / 2π``.
"""
from __future__ import annotations

import math

__all__ = ["displacement_deficit"]


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
