"""numba compile events of this package's functions, watched from Python: which compiled, and a progress line.

Apart from :mod:`gerotor_twin.precompile` (which imports the model) so that the model itself can announce
a first-use compile (:class:`announce_compilation`) without an import cycle.
"""
from __future__ import annotations

import sys
import time

__all__ = ["compiled_during", "announce_compilation"]


def _our_function(ev) -> str | None:
    """The qualified name of the function a numba compile event is about, if it is this package's."""
    f = ev.data["dispatcher"].py_func
    return f"{f.__module__}.{f.__qualname__}" if f.__module__.startswith("gerotor_twin") else None


class _CompileListener:
    """Base of the context managers below: a numba ``numba:compile`` listener registered inside the block,
    calling :meth:`started` / :meth:`finished` with the qualified name of each of this package's functions."""

    def started(self, name: str) -> None:
        pass

    def finished(self, name: str) -> None:
        pass

    def __enter__(self):
        from numba.core import event

        outer = self

        class _Listener(event.Listener):
            def on_start(inner, ev):  # noqa: N805 - numba's Listener API
                name = _our_function(ev)
                if name:
                    outer.started(name)

            def on_end(inner, ev):  # noqa: N805
                name = _our_function(ev)
                if name:
                    outer.finished(name)

        self._listener = _Listener()
        event.register("numba:compile", self._listener)
        return self

    def __exit__(self, *exc):
        from numba.core import event
        event.unregister("numba:compile", self._listener)
        return False


class compiled_during(_CompileListener):
    """Context manager that records every numba compilation of this package's functions inside it.

    ``.functions``: the qualified names, one per specialisation compiled (cache loads are not
    compilations); ``.seconds``: the wall time inside the block [s].
    """

    def __enter__(self):
        self.functions: list[str] = []
        self._t0 = time.perf_counter()
        return super().__enter__()

    def finished(self, name: str) -> None:
        self.functions.append(name)

    def __exit__(self, *exc):
        self.seconds = time.perf_counter() - self._t0
        return super().__exit__(*exc)


class announce_compilation(_CompileListener):
    """Context manager that prints ``message`` once (to ``stream``, default stderr) when numba starts compiling
    one of this package's functions inside it: the progress line of a first use that compiles (a gear model
    left out of :data:`DEFAULT_MODELS`); a start from the cache prints nothing.  ``.announced``: it printed."""

    def __init__(self, message: str, stream=None):
        self.message, self.stream, self.announced = message, stream, False

    def started(self, name: str) -> None:
        if not self.announced:
            self.announced = True
            print(self.message, file=self.stream or sys.stderr, flush=True)
