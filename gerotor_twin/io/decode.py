"""CDR bytes -> message namespace without rclpy, for the bench input types.

The bench inputs and the node's own outputs go through
:mod:`gerotor_twin.io.fastcdr` (``struct`` at fixed offsets, tested equal to
the generic path); every other type, and any buffer the fast path does not
accept, through ``mcap_ros2``'s dynamic decoder driven by the installed
``.msg`` definitions (the same text :mod:`gerotor_twin.io.schemas` writes into
MCAP schemas), so the node decodes its ``raw=True`` subscriptions exactly as a
reader of its log would, and a malformed buffer gets that decoder's error.
"""
from __future__ import annotations

import functools
from typing import Any, Callable

from mcap_ros2._dynamic import generate_dynamic

from gerotor_twin.errors import InputError
from gerotor_twin.io import cdr_arrays
from gerotor_twin.io.fastcdr import decode_fast
from gerotor_twin.io.schemas import message_definition

__all__ = ["decoder_for", "decode"]

cdr_arrays.apply()            # the same array readers as a reader of the log (io.reader)


@functools.lru_cache(maxsize=None)
def decoder_for(msgtype: str) -> Callable[[bytes], Any]:
    """A cached function ``CDR bytes -> namespace`` for ``pkg/msg/Type``."""
    d = message_definition(msgtype)
    return generate_dynamic(d.msgtype, d.text)[d.msgtype]


def decode(msgtype: str, data: bytes) -> Any:
    """Decode one CDR message; :class:`InputError` if the bytes do not fit the type."""
    msg = decode_fast(msgtype, data)
    if msg is not None:
        return msg
    try:
        return decoder_for(msgtype)(bytes(data))
    except InputError:
        raise
    except Exception as exc:  # struct.error, IndexError, UnicodeDecodeError, ... from a bad buffer
        raise InputError(msgtype, f"{len(data)} bytes", f"a CDR-encoded {msgtype}",
                         f"{type(exc).__name__}: {exc}") from None
