"""Private ``ROS_DOMAIN_ID`` for tests, benchmarks and the demo (no rclpy import).

Processes that start DDS participants of their own (tests, ``bench node``,
``make demo``) must not hear each other, even when several run at once on one
machine (two test sessions, CI next to a developer).  :func:`claim_domain`
returns a domain ID in the range that is safe on Linux, 0–101 [1]_, that

* no other caller of :func:`claim_domain` holds (an exclusive ``flock`` on
  ``$TMPDIR/gerotor_twin_domains/<id>.lock``, held until the process exits or
  :func:`release_domain` is called), and
* has no DDS participant bound right now (no UDP socket on the domain's
  unicast discovery ports, read from ``/proc/net/udp``; Fast DDS and the
  RTPS specification use port 7400 + 250·d + 10 + 2·p for participant p [2]_).

References
----------
.. [1] ROS 2 documentation, "The ROS_DOMAIN_ID" (concepts/about-domain-id):
   0–101 is the range that never collides with the Linux ephemeral ports.
.. [2] OMG DDS-RTPS 2.5, sec. 9.6.1.1 (default port mapping: PB 7400, DG 250,
   PG 2, d1 10).
"""
from __future__ import annotations

import fcntl
import os
import random
import tempfile
from pathlib import Path

__all__ = ["claim_domain", "release_domain", "DOMAIN_RANGE"]

DOMAIN_RANGE = (0, 101)      #: inclusive, safe on Linux
_PARTICIPANTS_CHECKED = 20   # unicast ports of participants 0..19 of a domain
_held: dict[int, int] = {}   # domain -> open lock-file descriptor


def _bound_udp_ports() -> set[int]:
    ports: set[int] = set()
    for name in ("/proc/net/udp", "/proc/net/udp6"):
        try:
            lines = Path(name).read_text().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            local = line.split()[1]
            ports.add(int(local.rsplit(":", 1)[1], 16))
    return ports


def _in_use(domain: int, bound: set[int]) -> bool:
    base = 7400 + 250 * domain + 10
    return any(base + 2 * p in bound for p in range(_PARTICIPANTS_CHECKED))


def claim_domain(avoid: tuple[int, ...] = (0,), seed: int | None = None) -> int:
    """A free ``ROS_DOMAIN_ID`` in 0–101, held by this process until it exits.

    Parameters
    ----------
    avoid : tuple of int
        IDs never returned (0, the default domain of every ROS 2 user, by default).
    seed : int, optional
        Seed of the random probe order (random by default, so that concurrent
        callers rarely probe the same ID first).

    Raises
    ------
    RuntimeError
        If every ID in the range is held or in use.
    """
    lo, hi = DOMAIN_RANGE
    order = [d for d in range(lo, hi + 1) if d not in avoid and d not in _held]
    random.Random(seed).shuffle(order)
    lock_dir = Path(tempfile.gettempdir()) / "gerotor_twin_domains"
    lock_dir.mkdir(parents=True, exist_ok=True)
    bound = _bound_udp_ports()
    for d in order:
        if _in_use(d, bound):
            continue
        fd = os.open(lock_dir / f"{d}.lock", os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            continue
        _held[d] = fd
        return d
    raise RuntimeError(f"no free ROS_DOMAIN_ID in {lo}-{hi}: all held by other runs or in use")


def release_domain(domain: int) -> None:
    """Give a claimed domain back (optional: process exit releases it too)."""
    fd = _held.pop(domain, None)
    if fd is not None:
        fcntl.flock(fd, fcntl.LOCK_UN)
        os.close(fd)
