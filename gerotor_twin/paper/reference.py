"""Published values of section 4 of [1] that gerotor_twin is compared with.

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the micro-movements of the
   external gear" (``../shared/paper/gerotor-micromotion-paper.md``), tables 3–5.
"""
from __future__ import annotations

import numpy as np

__all__ = ["SPEEDS_RPM", "PRESSURES_BAR", "PAPER_EFFICIENCY", "paper_efficiency", "slope_per_bar"]

#: Shaft speeds of tables 3, 4, 5 [rpm].
SPEEDS_RPM = (1000.0, 2000.0, 3000.0)
#: Delivery pressures of the table columns [bar gauge].
PRESSURES_BAR = (5.0, 10.0, 15.0, 20.0, 25.0, 27.5)

#: Volumetric efficiency [-] of tables 3–5 of [1]: (model, rpm) -> one value per pressure.
#: ``fixed`` = "Fix centre" row, ``mobility`` = "MM" row.
PAPER_EFFICIENCY = {
    ("fixed", 1000.0): (0.9197, 0.8577, 0.7956, 0.7335, 0.6715, 0.6404),
    ("mobility", 1000.0): (0.9332, 0.8724, 0.8116, 0.7508, 0.6900, 0.6596),
    ("fixed", 2000.0): (0.9504, 0.9115, 0.8886, 0.8578, 0.8269, 0.8115),
    ("mobility", 2000.0): (0.9673, 0.9373, 0.9073, 0.8773, 0.8473, 0.8323),
    ("fixed", 3000.0): (0.9614, 0.9406, 0.9199, 0.8991, 0.8783, 0.8679),
    ("mobility", 3000.0): (0.9762, 0.9567, 0.9371, 0.9175, 0.8979, 0.8881),
}


def paper_efficiency(model: str, rpm: float, bar: float) -> float:
    """Volumetric efficiency [-] of tables 3–5 of [1] at a tabulated point; KeyError otherwise."""
    row = PAPER_EFFICIENCY[(model, float(rpm))]
    return row[PRESSURES_BAR.index(float(bar))]


def slope_per_bar(bar, eta) -> float:
    """Least-squares slope of efficiency against delivery pressure [1/bar].

    A straight line through all the points of a row (the paper's 2000 rpm row has an
    irregular 10→15 bar step, so two-point slopes would depend on which points are taken).
    """
    return float(np.polyfit(np.asarray(bar, float), np.asarray(eta, float), 1)[0])
