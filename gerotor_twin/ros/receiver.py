"""The receiving loop of ``twin_node``: one rcl wait set on the input subscriptions only.

rclpy's ``SingleThreadedExecutor`` costs ≈ 150–250 µs of Python per message (it
rebuilds the wait set from every entity of its nodes, makes a task per callback);
at 1 kHz on two inputs that was ≈ 30 % of a core (docs/node.md).  This loop
waits on the input subscriptions and a wake-up guard condition only, and when a
subscription is ready empties its history (``take_message`` until nothing is
left, at most ``batch`` per wake-up), with the message info (publication
sequence numbers) that Jazzy's EventsExecutor cannot give.

It looks like an executor to ``twin_node.main`` (``spin_once``, ``wake``,
``shutdown``, ``add_node``), so the shutdown drain works the same way.
"""
from __future__ import annotations

import time
from typing import Callable

from rclpy.guard_condition import GuardCondition
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

__all__ = ["InputReceiver"]


class InputReceiver:
    """Wait on ``subs`` and call ``callbacks[kind](data, info)`` for every message taken.

    Parameters
    ----------
    context : rclpy.Context
        The node's context.
    subs : dict
        kind -> rclpy Subscription (``raw=True``), not added to any executor.
    callbacks : dict
        kind -> callable ``(bytes, info dict)``.
    batch : int
        Most messages taken from one subscription per wake-up [messages].
    coalesce_s : float
        After a wake-up, wait this long before taking [s], so that one wake-up takes
        the messages of both inputs that arrive meanwhile (``input_coalesce_s``).

    Notes
    -----
    Each wake-up of a thread costs far more than its few µs of Python on the dev
    VM (a thread that sleeps between small pieces of work pays ≈ 1.5–2× per
    piece, docs/performance.md); at 2 × 1 kHz most wake-ups carried one message.
    Waiting 2 ms took the receiving thread from ≈ 10 % to 5–7 % of a core.
    """

    def __init__(self, context, subs: dict, callbacks: dict[str, Callable], batch: int = 256,
                 coalesce_s: float = 0.0):
        self._coalesce_s = float(coalesce_s)
        self._context = context
        self._subs = list(subs.items())
        self._callbacks = callbacks
        self._batch = max(1, int(batch))
        self._gc = GuardCondition(None, None, context=context)
        self._ws = _rclpy.WaitSet(len(self._subs), 1, 0, 0, 0, 0, context.handle)

    def add_node(self, _node) -> None:
        """Executor interface: the subscriptions were given at construction."""

    def wake(self) -> None:
        """Leave a wait now (safe from a signal handler: triggers a guard condition)."""
        self._gc.trigger()

    def spin_once(self, timeout_sec: float | None = None) -> None:
        """Wait up to ``timeout_sec`` [s] for inputs and take every message waiting."""
        ws = self._ws
        ws.clear_entities()
        for _, sub in self._subs:
            ws.add_subscription(sub.handle)
        ws.add_guard_condition(self._gc.handle)
        ws.wait(-1 if timeout_sec is None else int(timeout_sec * 1e9))
        ready = ws.get_ready_entities("subscription")
        if not ready:
            return
        waited = self._coalesce_s > 0.0
        if waited:
            time.sleep(self._coalesce_s)      # what arrives meanwhile, on any input, is taken below
        for kind, sub in self._subs:
            if waited or sub.handle.pointer in ready:
                self._take(kind, sub)

    def _take(self, kind: str, sub) -> None:
        cb = self._callbacks[kind]
        for _ in range(self._batch):
            with sub.handle:
                got = sub.handle.take_message(sub.msg_type, True)
            if got is None:
                return
            cb(got[0], got[1])

    def shutdown(self, timeout_sec: float | None = None) -> bool:
        """Executor interface: release the guard condition."""
        self._gc.destroy()
        return True
