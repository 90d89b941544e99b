"""ROS 2 message definitions from the installed interface packages (no rclpy).

rosbag2 stores, for every topic type, a ``ros2msg`` *complete message
definition*: the top-level ``.msg`` text, then for every type it uses
(transitively, each once) a delimiter line of 80 ``=``, a line
``MSG: <pkg>/<Type>`` and that type's ``.msg`` text.  This module rebuilds
that text exactly as ``rosbag2_cpp::LocalMessageDefinitionSource`` does
(same dependency regex, same sorted depth-first order, same separators), and
reads the REP-2011 type hash (``RIHS01_...``) from the ``.json`` that
``rosidl`` installs next to each ``.msg``.

Search order for ``share/<pkg>/msg/<Type>.msg``: every entry of
``AMENT_PREFIX_PATH``, then ``sys.prefix`` (a venv with the PyPI ROS wheels).
Results are cached per process; :func:`clear_cache` forgets them (tests).
"""
from __future__ import annotations

import functools
import json
import os
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from gerotor_twin.errors import InputError

__all__ = [
    "SCHEMA_ENCODING",
    "MessageDefinition",
    "UnknownMessageType",
    "normalize_msgtype",
    "message_definition",
    "share_dirs",
    "clear_cache",
]

#: MCAP schema encoding of a rosbag2 ``.msg`` complete definition.
SCHEMA_ENCODING = "ros2msg"
#: Delimiter line between definitions (exactly 80 ``=``).
_SEPARATOR = "=" * 80 + "\n"
# rosbag2_cpp MSG_FIELD_TYPE_REGEX: the first token of a line ("foo_msgs/Bar" in "foo_msgs/Bar[] bar").
_FIELD_TYPE_RE = re.compile(r"(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+")
_PRIMITIVES = frozenset({
    "bool", "byte", "char", "float32", "float64", "int8", "uint8",
    "int16", "uint16", "int32", "uint32", "int64", "uint64", "string", "wstring"})
_NAME = r"[a-zA-Z][a-zA-Z0-9_]*"
_TYPE_RE = re.compile(rf"^({_NAME})/(?:({_NAME})/)?({_NAME})$")


class UnknownMessageType(InputError):
    """A message type name is malformed or its definition is not installed."""


@dataclass(frozen=True)
class MessageDefinition:
    """Everything an MCAP writer needs about one ROS 2 message type.

    Attributes
    ----------
    msgtype : str
        Canonical name ``pkg/msg/Type`` (the MCAP schema name rosbag2 uses).
    text : str
        Complete ``ros2msg`` definition (top level + nested types).
    type_hash : str
        REP-2011 hash ``RIHS01_<64 hex>`` (channel metadata ``topic_type_hash``).
    msg_path : Path
        The top-level ``.msg`` file used.
    """

    msgtype: str
    text: str
    type_hash: str
    msg_path: Path


def normalize_msgtype(name: str) -> str:
    """Return ``pkg/msg/Type`` for ``pkg/Type`` or ``pkg/msg/Type``.

    Raises
    ------
    UnknownMessageType
        If ``name`` is not of either form.
    """
    m = _TYPE_RE.match(name) if isinstance(name, str) else None
    if m is None:
        raise UnknownMessageType("msgtype", name, "'pkg/msg/Type' or 'pkg/Type'")
    pkg, ns, typ = m.groups()
    return f"{pkg}/{ns or 'msg'}/{typ}"


def share_dirs() -> tuple[Path, ...]:
    """Directories searched for ``<pkg>/msg/<Type>.msg``, in order [-]."""
    prefixes = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    prefixes.append(sys.prefix)
    out: list[Path] = []
    for p in prefixes:
        d = Path(p) / "share"
        if d not in out:
            out.append(d)
    return tuple(out)


def _find(pkg: str, ns: str, typ: str, ext: str) -> Path:
    dirs = share_dirs()
    for d in dirs:
        f = d / pkg / ns / f"{typ}{ext}"
        if f.is_file():
            return f
    what = f"{pkg}/{ns}/{typ}"
    reason = f"no {pkg}/{ns}/{typ}{ext} under {', '.join(str(d) for d in dirs)}"
    raise UnknownMessageType("msgtype", what, "an installed ROS 2 message type", reason)


@functools.lru_cache(maxsize=None)
def _msg_text(dep: str) -> tuple[str, frozenset[str]]:
    """Text of one ``.msg`` (``dep`` as written: ``pkg/Type`` or ``pkg/msg/Type``) and its deps."""
    pkg, ns, typ = normalize_msgtype(dep).split("/")
    text = _find(pkg, ns, typ, ".msg").read_text(encoding="utf-8")
    deps = set()
    for m in _FIELD_TYPE_RE.finditer(text):
        t = m.group(1)
        if t in _PRIMITIVES:
            continue
        deps.add(t if "/" in t else f"{pkg}/{t}")
    return text, frozenset(deps)


def _complete_text(msgtype: str) -> str:
    """rosbag2 ``get_full_text``: depth-first, dependencies in sorted order, each once."""
    seen: set[str] = set()

    def append(name: str, depth: int) -> str:
        if depth <= 0:
            raise UnknownMessageType("msgtype", msgtype, "a non-recursive message type",
                                     "maximum nesting depth reached")
        try:
            text, deps = _msg_text(name)
        except UnknownMessageType as exc:
            if name == msgtype:
                raise
            raise UnknownMessageType("msgtype", msgtype, exc.allowed,
                                     f"it uses {name}: {exc.reason}") from None
        out = text
        for dep in sorted(deps):
            if dep not in seen:
                seen.add(dep)
                out += "\n" + _SEPARATOR + f"MSG: {dep}\n" + append(dep, depth - 1)
        return out

    return append(msgtype, 50)


def _type_hash(msgtype: str) -> str:
    pkg, ns, typ = msgtype.split("/")
    path = _find(pkg, ns, typ, ".json")
    try:
        hashes = json.loads(path.read_text(encoding="utf-8"))["type_hashes"]
        return next(h["hash_string"] for h in hashes if h["type_name"] == msgtype)
    except (ValueError, KeyError, TypeError, StopIteration):
        raise UnknownMessageType("msgtype", msgtype, "a type with a RIHS01 hash",
                                 f"{path} has no type_hashes entry for it") from None


@functools.lru_cache(maxsize=None)
def message_definition(msgtype: str) -> MessageDefinition:
    """Complete definition and type hash of an installed message type (cached).

    Parameters
    ----------
    msgtype : str
        ``pkg/msg/Type`` or ``pkg/Type``.

    Returns
    -------
    MessageDefinition

    Raises
    ------
    UnknownMessageType
        If the name is malformed, or the type (or a type it uses) is not installed.
    """
    canonical = normalize_msgtype(msgtype)
    if canonical != msgtype:
        return message_definition(canonical)
    pkg, ns, typ = canonical.split("/")
    return MessageDefinition(canonical, _complete_text(canonical), _type_hash(canonical),
                             _find(pkg, ns, typ, ".msg"))


def clear_cache() -> None:
    """Forget cached definitions (after changing ``AMENT_PREFIX_PATH``)."""
    message_definition.cache_clear()
    _msg_text.cache_clear()
