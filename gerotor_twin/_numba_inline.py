"""numba's ``inline="always"`` without its two defensive copies of a callee that is used once.

numba inlines a function marked ``inline="always"`` at its IR level
(``InlineInlinables``): for every call site it builds the callee's IR afresh from
the bytecode (``InlineWorker.run_untyped_passes``, which inlines the callee's own
callees the same way) and then ``InlineWorker.inline_ir`` deep-copies that IR
twice, block by block, before splicing it in: once because the splice mutates it,
once more to return an unmutated copy [1]_.  Each block's deep copy also copies the
block's scope, that is every variable of the function, so a callee of B blocks and
V variables costs B·V variable copies, twice, at every call site, and the nested
helpers of the stepper make those callees large: two thirds of the first compile
of the model went to ``copy.deepcopy`` (cProfile of ``python -m
gerotor_twin.precompile``, 2026-12-05, numba 0.68.1).

Here the IR that :func:`inline_function` hands to ``inline_ir`` was built for this
call site alone and nobody else holds it, so neither copy protects anything: each
of its blocks answers a deep copy with itself while ``inline_ir`` runs (an
instance ``__deepcopy__``, removed again afterwards), and ``inline_ir`` itself is
numba's, unchanged.  The copy it returns as "unmutated" is then the mutated IR;
numba's only caller of ``inline_function`` (``InlineInlinables``) discards it.  The
same two copies are what numba issue #8989 [2]_ and numba-cuda pull request #689
[3]_ remove.  The compiled code is the same: the model's outputs bit for bit, both
gear models, two operating points (docs/performance.md); the first compile about
halves.

Applied by :mod:`gerotor_twin._jit` on import, to the numba versions it was checked
on (:data:`CHECKED_NUMBA`); with any other it does nothing and numba inlines as it
always has.

References
----------
.. [1] numba 0.68.1, ``numba/core/inline_closurecall.py``, ``InlineWorker.inline_function``
   and ``InlineWorker.inline_ir`` (``copy_ir``).
.. [2] numba issue #8989, "Spurious deep copies in inlining", https://github.com/numba/numba/issues/8989
.. [3] numba-cuda pull request #689, "perf: Reduce copy overhead in inline passes",
   https://github.com/NVIDIA/numba-cuda/pull/689
"""
from __future__ import annotations

import numba

__all__ = ["CHECKED_NUMBA", "apply", "applied", "inline_function"]

#: numba releases whose ``InlineWorker`` this was read against (major, minor).
CHECKED_NUMBA = ((0, 68),)


def _itself(block):
    """A ``__deepcopy__`` for ``block`` that returns ``block``."""
    return lambda memo: block


def inline_function(self, caller_ir, block, i, function, arg_typs=None):
    """``InlineWorker.inline_function`` (numba) with the callee's fresh IR spliced in without copying it.

    Same arguments and result as numba's; the first item of the result (numba: an unmutated copy of the
    callee's IR) is the IR as spliced.
    """
    callee_ir = self.run_untyped_passes(function)             # built for this call site alone
    blocks = list(callee_ir.blocks.values())
    for b in blocks:
        b.__deepcopy__ = _itself(b)
    try:
        return self.inline_ir(caller_ir, block, i, callee_ir, function.__code__.co_freevars, arg_typs=arg_typs)
    finally:
        for b in blocks:
            b.__dict__.pop("__deepcopy__", None)


def _version() -> tuple[int, int]:
    major, minor = numba.__version__.split(".")[:2]
    return int(major), int(minor)


def apply() -> bool:
    """Install :func:`inline_function` on numba's ``InlineWorker`` if numba is a :data:`CHECKED_NUMBA`
    release; returns :func:`applied`."""
    from numba.core import inline_closurecall as icc
    worker = getattr(icc, "InlineWorker", None)
    if worker is not None and _version() in CHECKED_NUMBA and hasattr(worker, "inline_ir") and \
            hasattr(worker, "run_untyped_passes"):
        worker.inline_function = inline_function
    return applied()


def applied() -> bool:
    """True if numba's ``InlineWorker.inline_function`` is this module's."""
    from numba.core import inline_closurecall as icc
    return getattr(getattr(icc, "InlineWorker", None), "inline_function", None) is inline_function
