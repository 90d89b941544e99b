"""Where the tooth-tip gaps are open: mean gap over the suction and the delivery port arcs.

The overlap check of sec. 3.7 of [1] turns a centred gear set (fixed centre,
``micro_motion.fixed_centre_contact: rotate``) to one contact, which closes the
gaps on the suction side and opens those on the delivery side: the same pattern
the mobility model reaches by moving the outer gear (docs/bearing.md).

References
----------
.. [1] The paper, sec. 3.7 (``../shared/paper``).
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["gap_point_angles", "gap_pattern", "fixed_centre_gap_pattern"]


def gap_point_angles(model, theta) -> np.ndarray:
    """Angle of every lobe's gap point about the inner-gear centre O1 [rad in [0, 2π)], shape (len(θ), N)."""
    tab = model.tables
    th = np.atleast_1d(np.asarray(theta, float))
    px = np.column_stack([tab.column("PX", th, k) for k in range(model.N)])
    py = np.column_stack([tab.column("PY", th, k) for k in range(model.N)])
    return np.mod(np.arctan2(py, px), 2 * math.pi)


def gap_pattern(model, theta, gaps) -> dict:
    """Mean tooth-tip gap [m] of the lobes whose gap point lies over each port arc.

    Parameters
    ----------
    model : PumpModel
    theta : array (M,)
        Shaft angles [rad].
    gaps : array (M, N)
        Gap heights [m] at those angles (e.g. ``Outputs.gaps``).

    Returns
    -------
    dict
        ``suction_m``, ``delivery_m``: mean gap over the suction / delivery port arc [m].
    """
    a = gap_point_angles(model, theta)
    g = np.asarray(gaps, float)
    out = {}
    for name, port in (("suction_m", model.config.suction_port), ("delivery_m", model.config.delivery_port)):
        sel = (a > port.start) & (a < port.end)
        out[name] = float(g[sel].mean())
    return out


def fixed_centre_gap_pattern(model, samples: int = 420) -> dict:
    """:func:`gap_pattern` of a centred outer gear under the model's contact rule, over one chamber period."""
    th = np.arange(samples) * model.tables.period / samples
    gaps = np.array([model.gaps(t, (0.0, 0.0))[0] for t in th])
    return gap_pattern(model, th, gaps)
