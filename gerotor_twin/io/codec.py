"""CDR encoding of messages given as dicts (or objects), without rclpy.

The encoder is ``mcap_ros2``'s dynamic CDR writer, driven by the same
``ros2msg`` text that goes into the MCAP schema, so the bytes always match
the embedded definition.  Before encoding, a message is checked and
normalised against the definition:

* an unknown field name raises :class:`~gerotor_twin.errors.InputError`
  (``mcap_ros2`` would silently write a default for a misspelt field);
* a missing field takes its ROS default (0, ``""``, empty array);
* NumPy arrays / scalars and tuples become plain lists / numbers.

(Do not use ``rclpy.serialization.serialize_message`` for JointState on this
Jazzy build: it pads string sequences with garbage bytes.)
"""
from __future__ import annotations

import functools
import struct
from dataclasses import dataclass
from types import SimpleNamespace
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from mcap_ros2._dynamic import serialize_dynamic
from mcap_ros2._vendor.rosidl_adapter.parser import parse_message_string

from gerotor_twin.errors import InputError
from gerotor_twin.io.schemas import message_definition

__all__ = ["encode", "encoder_for", "field_names", "split_definitions"]

_SPLIT = "\n" + "=" * 80 + "\nMSG: "


@dataclass(frozen=True)
class _Field:
    name: str
    nested: str | None  # "pkg/Type" of a message-typed field, None for primitives
    is_array: bool


def split_definitions(msgtype: str, text: str) -> dict[str, str]:
    """Split a ``ros2msg`` complete definition into ``{"pkg/Type": msg_text}``.

    The first (top-level) section is keyed by ``msgtype`` shortened to ``pkg/Type``.
    """
    parts = text.split(_SPLIT)
    pkg, *_, typ = msgtype.split("/")
    out = {f"{pkg}/{typ}": parts[0]}
    for part in parts[1:]:
        name, _, body = part.partition("\n")
        p, *_, t = name.strip().split("/")
        out[f"{p}/{t}"] = body
    return out


@functools.lru_cache(maxsize=None)
def _field_table(msgtype: str) -> dict[str, tuple[_Field, ...]]:
    """Fields of ``msgtype`` and of every type it uses, keyed by ``pkg/Type``."""
    table: dict[str, tuple[_Field, ...]] = {}
    for short, body in split_definitions(msgtype, message_definition(msgtype).text).items():
        pkg, typ = short.split("/")
        spec = parse_message_string(pkg, typ, body)
        table[short] = tuple(
            _Field(f.name, None if f.type.is_primitive_type() else f"{f.type.pkg_name}/{f.type.type}",
                   bool(f.type.is_array))
            for f in spec.fields)
    return table


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple):
        return list(value)
    return value


def _normalise(table: Mapping[str, tuple[_Field, ...]], short: str, msg: Any,
               path: str) -> SimpleNamespace:
    """Check ``msg`` against the fields of ``short``; return plain values as a namespace.

    A namespace, not a dict: ``mcap_ros2`` looks a missing key up as an attribute,
    and a dict has attributes ``values``, ``items``... (DiagnosticStatus.values).
    """
    fields = table[short]
    if isinstance(msg, Mapping):
        known = {f.name for f in fields}
        unknown = [k for k in msg if k not in known]
        if unknown:
            raise InputError(f"{path}.{unknown[0]}", msg[unknown[0]],
                             f"a field of {short}: {', '.join(sorted(known)) or '(none)'}")
        get = msg.get
    else:
        def get(name: str) -> Any:
            return getattr(msg, name, None)
    out: dict[str, Any] = {}
    for f in fields:
        v = get(f.name)
        if v is None:
            continue
        if f.nested is None:
            out[f.name] = _plain(v)
        elif f.is_array:
            out[f.name] = [_normalise(table, f.nested, item, f"{path}.{f.name}[{i}]")
                           for i, item in enumerate(v)]
        else:
            out[f.name] = _normalise(table, f.nested, v, f"{path}.{f.name}")
    return SimpleNamespace(**out)


@functools.lru_cache(maxsize=None)
def encoder_for(msgtype: str) -> Callable[[Any], bytes]:
    """A function ``msg -> CDR bytes`` for an installed type (cached).

    ``msg`` is a dict with field names (nested dicts for nested messages) or
    any object with those attributes (e.g. a decoded message).
    """
    definition = message_definition(msgtype)
    raw = serialize_dynamic(definition.msgtype, definition.text)[definition.msgtype]
    table = _field_table(definition.msgtype)
    pkg, _, typ = definition.msgtype.split("/")
    short = f"{pkg}/{typ}"

    def encode_one(msg: Any) -> bytes:
        plain = _normalise(table, short, msg, short)
        try:
            return raw(plain)
        except (TypeError, ValueError, OverflowError, struct.error) as exc:
            raise InputError(short, msg, f"a valid {definition.msgtype}", str(exc)) from None

    return encode_one


@functools.lru_cache(maxsize=None)
def field_names(msgtype: str) -> frozenset:
    """The names of the top-level fields of ``msgtype`` (cached per type)."""
    definition = message_definition(msgtype)
    pkg, _, typ = definition.msgtype.split("/")
    return frozenset(f.name for f in _field_table(definition.msgtype)[f"{pkg}/{typ}"])


def encode(msgtype: str, msg: Any) -> bytes:
    """Encode one message of ``msgtype`` (``pkg/msg/Type``) to CDR bytes (little endian)."""
    return encoder_for(msgtype)(msg)
