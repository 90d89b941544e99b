"""Outer gear of the Gerotor pump as a journal bearing under dynamic load (sec. 2 of [1]_).

Four interchangeable models behind one interface (:class:`BearingModel`):

==============  ==============================================================
``"fixed"``     fixed centre (reference case of sec. 4)
``"mobility"``  Booker's mobility method, short bearing, Eq. (9) corrected
``"short"``     Method 1: Ocvirk pressure with squeeze, positive part, Newton
``"fdm"``       full Reynolds equation by finite differences (DST + cyclic
                tridiagonal solves), negative pressure clipped
==============  ==============================================================

>>> from gerotor_twin.bearing import TABLE1, make_bearing, simulate
>>> model = make_bearing("mobility", TABLE1)
>>> traj = simulate(model, [1e-5, 0.0], lambda t: [0.0, -1000.0], 52.36, 1e-4, 0.12)

The pump model's compiled time loop calls :func:`mobility_velocity` directly.
See ``docs/bearing.md`` for conventions, the benchmark and the validation.

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear" (``../shared/paper``).
"""
from gerotor_twin.bearing.base import BearingModel
from gerotor_twin.bearing.registry import MODEL_NAMES, make_bearing
from gerotor_twin.bearing.geometry import TABLE1, BearingGeometry
from gerotor_twin.bearing.mobility import mobility_velocity
from gerotor_twin.bearing.simulate import (EPS_CONTACT, BearingTrajectory, ContactEvent, settle,
                                           simulate, steady_state)

__all__ = ["BearingGeometry", "TABLE1", "BearingModel", "make_bearing", "MODEL_NAMES",
           "mobility_velocity", "simulate", "BearingTrajectory", "ContactEvent", "steady_state",
           "settle", "EPS_CONTACT"]
