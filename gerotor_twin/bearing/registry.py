"""The outer-gear models by name: the factory (the one list of names is :mod:`gerotor_twin.bearing_names`'s).

Kept out of :mod:`gerotor_twin.bearing.base` (the interface the models import),
so that no module imports its own subclasses.
"""
from __future__ import annotations

from typing import Any

from gerotor_twin.bearing.base import BearingModel
from gerotor_twin.bearing.geometry import BearingGeometry
from gerotor_twin.bearing_names import MODEL_NAMES
from gerotor_twin.errors import InputError

__all__ = ["MODEL_NAMES", "make_bearing"]


def make_bearing(name: str, geometry: BearingGeometry, **options: Any) -> BearingModel:
    """Build a bearing model by name.

    Parameters
    ----------
    name : str
        ``"fixed"``, ``"mobility"``, ``"short"`` (Method 1) or ``"fdm"``.
    geometry : BearingGeometry
        Bearing [m, Pa s].
    **options
        Model options, e.g. ``nx=320, ny=40`` for ``"fdm"``,
        ``n_nodes=24`` for ``"short"``.

    Returns
    -------
    BearingModel
    """
    if name == "fixed":
        from gerotor_twin.bearing.fixed import FixedBearing as cls
    elif name == "mobility":
        from gerotor_twin.bearing.mobility import MobilityBearing as cls
    elif name == "short":
        from gerotor_twin.bearing.short_bearing import ShortBearing as cls
    elif name == "fdm":
        from gerotor_twin.bearing.reynolds_fd import FdmBearing as cls
    else:
        raise InputError("bearing_model", name, " | ".join(MODEL_NAMES))
    try:
        return cls(geometry, **options)
    except TypeError as exc:  # unknown option name
        raise InputError("bearing_options", sorted(options), f"options of the {name!r} model",
                         str(exc)) from None
