"""The distributed engine of ``sweep`` and ``batch``: Dask (``dask.distributed``).

:func:`dask_client` gives a client on an embedded :class:`distributed.LocalCluster`
(default: one single-threaded worker process per core, no server to start, no
dashboard) or on a running cluster (``--scheduler tcp://host:8786``).
:func:`run_tasks` submits one task per item not yet in the
:class:`~gerotor_twin.offline.results_store.ResultStore`, writes each record as it
arrives and shows a progress line with ETA.

Failures: a worker that dies takes its running tasks with it; the scheduler
reruns them on another worker (up to ``distributed.scheduler.allowed-failures``,
default 3, times; then the item is recorded as failed, "killed worker").  The
store keeps the first record per item id, so an item computed twice appears
once.  Tasks run our code, so a remote worker needs the same gerotor_twin
installed (the results do not depend on where a task runs: each builds its
model from the values it receives).
"""
from __future__ import annotations

import logging
import os
import re
import sys
import time
from contextlib import contextmanager
from typing import IO, Callable, Iterable

from ..errors import InputError, one_line
from .results_store import ResultStore

__all__ = ["dask_client", "run_tasks", "chunk_size", "Progress", "check_address", "check_engine_args",
           "add_engine_arguments", "discarded_if_unused", "warm_up_kernels"]

_ADDRESS = re.compile(r"^(tcp|tls|inproc|ws|wss)://[^\s/]+$")


def check_address(address: str) -> str:
    """``tcp://host:port`` (or tls://, ws://); else :class:`InputError` naming ``--scheduler``."""
    if not isinstance(address, str) or not _ADDRESS.match(address):
        raise InputError("--scheduler", address, "a Dask scheduler address such as tcp://host:8786")
    return address


def _cluster_workers(workers: int | None) -> int:
    n = (os.cpu_count() or 1) if workers is None else workers
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 512:
        raise InputError("--workers", workers, "an integer in [1, 512]")
    return n


def warm_up_kernels() -> None:
    """Compile (or load from numba's disk cache) the model kernels in this process, once.

    Called before an embedded cluster starts: its worker processes then load the compiled
    kernels from the cache instead of each compiling them (about 30 s of CPU per process after
    an install or a source change).  A remote cluster's workers use their own machine's cache.
    """
    from ..config import load_config
    from ..model.pump import PumpModel
    from ..model.steady import run_steady
    cfg = load_config()
    for model in ("fixed", "mobility"):
        run_steady(PumpModel(cfg, model), 2000, 10, max_revolutions=1, min_revolutions=1)


def add_engine_arguments(parser) -> None:
    """``--scheduler``, ``--workers`` and ``--quiet`` of the commands that run on this engine."""
    parser.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://host:8786 (default: embedded cluster)")
    parser.add_argument("--workers", type=int, help="worker processes of the embedded cluster (default: all cores)")
    parser.add_argument("--quiet", action="store_true", help="no progress line")


def check_engine_args(scheduler: str | None, workers: int | None) -> None:
    """The ``--scheduler`` / ``--workers`` pair, checked before anything is written."""
    if scheduler is not None:
        check_address(scheduler)
        if workers is not None:
            raise InputError("--workers", workers, "absent with --scheduler (the cluster has its own workers)")
    else:
        _cluster_workers(workers)


@contextmanager
def discarded_if_unused(out, names: tuple[str, ...], store_name: str):
    """Remove ``names`` from a directory this run created when it fails before storing any result.

    A run that cannot reach its scheduler leaves nothing behind (so the same command can simply
    be repeated); a run that stored results keeps them (``--resume``/rerun continues).
    """
    from pathlib import Path
    out = Path(out)
    fresh = not out.exists()
    try:
        yield
    except InputError:
        store = out / store_name
        if fresh and (not store.exists() or store.stat().st_size == 0):
            for name in names:
                (out / name).unlink(missing_ok=True)
            if out.is_dir() and not any(out.iterdir()):
                out.rmdir()
        raise


@contextmanager
def dask_client(scheduler: str | None = None, workers: int | None = None, timeout_s: float = 20.0):
    """A :class:`distributed.Client`: on ``scheduler`` if given, else on an embedded LocalCluster.

    Parameters
    ----------
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:8786``).
    workers : int, optional
        Worker processes of the embedded cluster (default: all cores); ignored with ``scheduler``.
    timeout_s : float
        Connection time-out [s].
    """
    from distributed import Client, LocalCluster
    check_engine_args(scheduler, workers)
    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=timeout_s)
        except (OSError, TimeoutError) as exc:
            raise InputError("--scheduler", scheduler, "the address of a running Dask scheduler",
                             f"cannot connect: {one_line(exc, 200)}") from None
        try:
            yield client
        finally:
            client.close()
        return
    n = _cluster_workers(workers)
    warm_up_kernels()
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=logging.ERROR)
    client = Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()


class Progress:
    """A one-line progress bar with rate and ETA on a text stream (``\\r`` updates, at most 2 per second)."""

    def __init__(self, label: str, total: int, done: int = 0, unit: str = "points",
                 stream: IO[str] | None = sys.stderr):
        self.label, self.total, self.unit, self.stream = label, total, unit, stream
        self.start_done = self.done = done
        self.failed = 0
        self.t0 = self._shown = time.monotonic()

    def line(self) -> str:
        frac = self.done / self.total if self.total else 1.0
        el = time.monotonic() - self.t0
        new = self.done - self.start_done
        rate = new / el if el > 0 else 0.0
        left = self.total - self.done
        eta = f"{left / rate:5.0f} s" if rate > 0 else "    ? s"
        bar = "#" * int(30 * frac)
        return (f"{self.label} [{bar:30s}] {self.done}/{self.total} {self.unit}"
                f"{f' ({self.failed} failed)' if self.failed else ''}, {rate:.2f}/s, "
                f"{el:.0f} s elapsed, ETA {eta}")

    def update(self, failed: bool = False, force: bool = False) -> None:
        self.done += 1
        self.failed += bool(failed)
        now = time.monotonic()
        if self.stream is not None and (force or now - self._shown >= 0.5 or self.done == self.total):
            self._shown = now
            print("\r" + self.line() + "  ", end="", file=self.stream, flush=True)

    def close(self) -> None:
        if self.stream is not None:
            print("\r" + self.line() + "  ", file=self.stream, flush=True)


def chunk_size(n_items: int, n_workers: int, limit: int = 32) -> int:
    """Items per task: as many as keep at least 8 tasks per worker (load balance), at most ``limit``.

    Cheap items (an operating point, ~0.05 s) then share one task's ~6 ms of engine overhead; a
    small study or a large cluster keeps one item per task.
    """
    return max(1, min(limit, n_items // (8 * max(1, n_workers))))


def _run_chunk(func: Callable, shared, items: list[dict]) -> list[dict]:
    """Several items in one task, one record each."""
    return [func(shared, it) for it in items]


def run_tasks(client, func: Callable, shared, items: Iterable[dict], store: ResultStore, *, key_prefix: str,
              progress: Progress | None = None, failure: Callable[[dict, str], dict] | None = None,
              chunk: int = 1) -> int:
    """Run ``func(shared, item)`` for every item whose ``id`` is not in ``store``; return how many were added.

    ``shared`` (small: settings, the raw config) goes with every task, so no task depends on data
    held by one worker.  ``chunk`` items go in one task (key ``<key_prefix>-<id>`` for one,
    ``<key_prefix>-<first id>..<last id>`` for several); each record is stored as its task
    returns.  A task that raises (or whose worker died too often) makes each of its items
    ``failure(item, reason)`` (default: ``{"id", "status": "failed", "reason"}``).
    """
    from distributed import as_completed
    todo = [it for it in items if it["id"] not in store]
    if not todo:
        return 0
    groups = [todo[i:i + max(1, chunk)] for i in range(0, len(todo), max(1, chunk))]
    futures = {}
    for g in groups:
        if len(g) == 1:
            fut = client.submit(func, shared, g[0], key=f"{key_prefix}-{g[0]['id']}", pure=False)
        else:
            fut = client.submit(_run_chunk, func, shared, g, key=f"{key_prefix}-{g[0]['id']}..{g[-1]['id']}",
                                pure=False)
        futures[fut] = g
    added = 0
    for fut in as_completed(futures):
        group = futures.pop(fut)
        try:
            recs = fut.result()
            recs = [recs] if len(group) == 1 else recs
        except Exception as exc:  # noqa: BLE001 - KilledWorker, an error inside the task: record it, go on
            reason = f"{type(exc).__name__}: {one_line(exc, 300)}"
            recs = [failure(it, reason) if failure else {"id": it["id"], "status": "failed", "reason": reason}
                    for it in group]
        for rec in recs:
            added += store.add(rec)
            if progress is not None:
                progress.update(failed=rec.get("status") != "ok")
        fut.release()
    return added
