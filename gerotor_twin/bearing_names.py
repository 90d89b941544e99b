"""The outer-gear models by name, without the models: what the command line needs to list them.

:mod:`gerotor_twin.bearing.registry` builds a model from its name; importing anything of the ``bearing`` package
imports the compiled models (numba), which the parser of a command that does not run a model need not wait for.
"""
from __future__ import annotations

__all__ = ["MODEL_NAMES"]

#: The outer-gear models, by name: fixed centre, mobility method, short bearing (Method 1), FDM.
MODEL_NAMES = ("fixed", "mobility", "short", "fdm")
