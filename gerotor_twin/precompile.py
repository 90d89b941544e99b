"""Build the numba cache at install time: ``python -m gerotor_twin.precompile``.

The first model start compiles the stepper (46 specialisations, ≈ 30–36 s on the dev machine's two cores);
``make setup`` runs this module once so that no user waits for it.  It runs
what a first model start runs — a few output steps of the default pump with
each gear model given (default: ``mobility``, the twin's, and ``fixed``, which adds
nothing to it), an oil-temperature change, a zero-length call — so numba compiles
and caches exactly the specialisations a user hits.  The other gear models (Method 1
``short``, ``fdm``) add 9 and 5 small specialisations of their own, ≈ 5–6 s each: they
compile on their first use, announced by one line (:class:`announce_compilation`), and
are cached from then on; so does a ``numerics.gear_coupling`` other than the packaged config's (``stages``
or ``constrained``: a stepper of its own, ≈ 9 s, which serves the mobility method and the fixed centre alike).  The compiled code depends on the argument *types* only,
never on a pump's data (:func:`gerotor_twin._jit.typed` keeps the types the same for
every pump, table size and fluid model), so the cache serves any pump.  A second run,
or a run after an edit of a module the kernel does not use, compiles nothing and takes
a few seconds.

Prints one line: what was compiled and how long it took.  Exit status 0; 1 with
``--expect-cached`` when anything had to be compiled (the cache was cold or stale).
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import sys

from .compile_events import announce_compilation, compiled_during

__all__ = ["compiled_during", "announce_compilation", "warm_up", "main", "DEFAULT_MODELS"]

#: The gear models compiled at install: the twin's and the fixed centre (one compiled stepper, which
#: ``fixed`` shares with ``mobility``).  ``short`` and ``fdm`` compile on first use (docs/performance.md).
DEFAULT_MODELS = ("mobility", "fixed")


def warm_up(config=None, models=DEFAULT_MODELS) -> None:
    """Run the calls of a first model start for each gear model in ``models`` (compiling what is missing).

    Parameters
    ----------
    config : PumpConfig, optional
        Pump (default: the default pump, ``config/pump.yaml``).
    models : sequence of str
        Gear models (:data:`gerotor_twin.model.pump.BEARING_MODELS`; default :data:`DEFAULT_MODELS`).
    """
    from .config import load_config
    from .model.pump import Inputs, PumpModel

    cfg = config if config is not None else load_config()
    p_atm = cfg.fluid.atmospheric_pa
    inp = Inputs(omega=1000 * math.pi / 30, p_suction=p_atm, p_delivery=p_atm + 10e5)
    for k, name in enumerate(models):
        if k == 0 and cfg.fluid_model != "paper":                 # the other state equation's builder
            PumpModel(cfg.with_fluid_model("paper"), name)
        m = PumpModel(cfg, name)
        s, _ = m.advance(m.initial_state(inp), 4 * m.step_size(inp.omega), inp)
        s, _ = m.advance(s, 0.0, inp)                             # the zero-length path
        if cfg.oil is not None:                                   # the oil-temperature path
            warmer = dataclasses.replace(inp, oil_temperature=m.temperature_k + 1.0)
            m.advance(s, 2 * m.step_size(inp.omega), warmer)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m gerotor_twin.precompile", description=__doc__.splitlines()[0])
    ap.add_argument("--models", default=",".join(DEFAULT_MODELS),
                    help="comma-separated gear models to compile (default: %(default)s; "
                         "all four: mobility,fixed,short,fdm)")
    ap.add_argument("--expect-cached", action="store_true",
                    help="exit 1 if anything had to be compiled (a check that the cache is warm)")
    args = ap.parse_args(argv)
    from .errors import InputError
    from .model.pump import BEARING_MODELS
    models = [m.strip() for m in args.models.split(",") if m.strip()]
    for m in models:
        if m not in BEARING_MODELS:
            print(f"error: {InputError('--models', m, 'comma-separated ' + ' | '.join(BEARING_MODELS))}",
                  file=sys.stderr)
            return 2
    with compiled_during() as c:
        warm_up(models=models)
    what = f"compiled {len(c.functions)} specialisations" if c.functions else "numba cache warm, nothing compiled"
    print(f"gerotor_twin precompile ({', '.join(models)}): {what} in {c.seconds:.1f} s")
    return 1 if args.expect_cached and c.functions else 0


if __name__ == "__main__":
    sys.exit(main())
