"""A real Dask cluster on loopback for the tests: ``dask scheduler`` + N ``dask worker`` processes.

Started with the venv's ``dask`` command exactly as docs/sweep.md tells a user, on 127.0.0.1 and
free ports, each worker single-threaded without a nanny (so that killing its PID kills the worker,
nothing restarts it).  Every process is stopped by its PID on exit (SIGTERM, then SIGKILL).
"""
from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

DASK = str(Path(sys.executable).parent / "dask")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def stop(proc: subprocess.Popen, timeout: float = 10.0) -> None:
    """Stop one process we started, by its PID: SIGTERM, then SIGKILL."""
    if proc.poll() is None:
        os.kill(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait(timeout)


@contextlib.contextmanager
def loopback_cluster(tmp: Path, workers: int = 2, env: dict | None = None, timeout: float = 90.0):
    """Yield ``(address, {worker name: Popen})`` of a scheduler and ``workers`` workers on 127.0.0.1."""
    from distributed import Client
    env = {**os.environ, **(env or {})}
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    logs = tmp / "dask_logs"
    logs.mkdir(parents=True, exist_ok=True)
    procs = []
    try:
        procs.append(subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port", str(port),
                                       "--no-dashboard"], env=env, stdout=subprocess.DEVNULL,
                                      stderr=open(logs / "scheduler.log", "w")))
        named = {}
        for i in range(workers):
            name = f"w{i + 1}"
            p = subprocess.Popen([DASK, "worker", address, "--host", "127.0.0.1", "--nthreads", "1", "--no-nanny",
                                  "--name", name, "--no-dashboard", "--local-directory", str(tmp / name),
                                  "--death-timeout", "60"], env=env, stdout=subprocess.DEVNULL,
                                 stderr=open(logs / f"{name}.log", "w"))
            procs.append(p)
            named[name] = p
        t0 = time.monotonic()
        while True:
            try:
                with Client(address, timeout=5) as c:
                    c.wait_for_workers(workers, timeout=max(1.0, timeout - (time.monotonic() - t0)))
                break
            except OSError:
                if time.monotonic() - t0 > timeout:
                    raise
                time.sleep(0.5)
        yield address, named
    finally:
        for p in reversed(procs):
            stop(p)
