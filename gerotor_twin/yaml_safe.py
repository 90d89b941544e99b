"""The one YAML loader of the project: bounded input size, bounded expansion, one-line errors.

Every YAML the project reads goes through :func:`load_yaml` (pump config,
node parameter files, the pump config and QoS profiles stored in MCAP
metadata).  PyYAML's ``safe_load`` resolves aliases to shared objects, so a
small file with nested anchors ("billion laughs") becomes a structure whose
expanded size is gigabytes: anything that walks or prints it (validation,
``repr`` in an error) runs out of memory.  Here the document is composed to a
node graph first, its *expanded* size (every alias counted as a full copy of
what it names) is computed in linear time, and a document beyond
``max_nodes`` nodes, or with a recursive alias, is refused before any Python
object is built.

Scalars are resolved as in YAML 1.2 for numbers in exponent form without a
dot (``1e-3`` is a float, as rcl and most YAML 1.2 parsers read it; PyYAML's
YAML 1.1 rules would make it a string).
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml

from gerotor_twin.errors import InputError

__all__ = ["load_yaml", "load_yaml_file", "MAX_YAML_BYTES", "MAX_YAML_NODES"]

#: Largest YAML text accepted [bytes] (the pump config is ~2 kB, a params file ~2 kB).
MAX_YAML_BYTES = 1_000_000
#: Largest document accepted, counted with every alias expanded [nodes].
MAX_YAML_NODES = 100_000


class _Loader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 exponent floats (``1e-3``)."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"))


def _expanded_size(root: yaml.Node, limit: int, what: str, aliases: bool = True) -> int:
    """Nodes in the document with aliases expanded; refuses recursion, sizes over ``limit``, aliases if asked."""
    size: dict[int, int] = {}
    active: set[int] = set()
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, done = stack.pop()
        key = id(node)
        if done:
            active.discard(key)
            if isinstance(node, yaml.SequenceNode):
                children = node.value
            elif isinstance(node, yaml.MappingNode):
                children = [n for kv in node.value for n in kv]
            else:
                children = []
            total = 1 + sum(size[id(c)] for c in children)
            if total > limit:
                raise InputError(what, f"a YAML document of more than {limit} nodes with aliases expanded",
                                 f"at most {limit} nodes", "alias/anchor expansion bomb or an oversized file")
            size[key] = total
            continue
        if key in size:
            if not aliases:
                raise InputError(what, "a YAML alias (*name)", "plain values (no anchors/aliases)",
                                 "rcl refuses aliases in parameter files")
            continue
        if key in active:
            raise InputError(what, "a recursive YAML alias", "a finite document (no alias inside its own anchor)")
        active.add(key)
        stack.append((node, True))
        if isinstance(node, yaml.SequenceNode):
            stack.extend((c, False) for c in node.value)
        elif isinstance(node, yaml.MappingNode):
            stack.extend((c, False) for kv in node.value for c in kv)
    return size.get(id(root), 0)


def load_yaml(text: str | bytes, what: str = "YAML", *, max_bytes: int = MAX_YAML_BYTES,
              max_nodes: int = MAX_YAML_NODES, aliases: bool = True) -> Any:
    """Parse one YAML document safely.

    Parameters
    ----------
    text : str or bytes
        The YAML text.
    what : str
        Name of the source for error messages (a file path, ``--params-file`` ...).
    max_bytes, max_nodes : int
        Size limits: text length [bytes] and expanded document size [nodes].
    aliases : bool
        False: refuse any alias (what rcl does with parameter files).

    Returns
    -------
    Any
        The document (``None`` for an empty one).

    Raises
    ------
    InputError
        Text too long, invalid YAML (first line of the parser's message), a
        recursive alias, or an expansion beyond ``max_nodes`` (every message
        is one bounded line).
    """
    if isinstance(text, bytes):
        if len(text) > max_bytes:
            raise InputError(what, f"{len(text)} bytes", f"at most {max_bytes} bytes of YAML")
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise InputError(what, "(binary data)", "UTF-8 YAML text", f"{exc.reason} at byte {exc.start}") from None
    if len(text.encode("utf-8", "surrogatepass")) > max_bytes:
        raise InputError(what, f"{len(text)} characters", f"at most {max_bytes} bytes of YAML")
    loader = _Loader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _expanded_size(node, max_nodes, what, aliases)
        return loader.construct_document(node)
    except yaml.YAMLError as exc:
        first = (str(exc).strip().splitlines() or ["invalid YAML"])[0]
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        raise InputError(what, "(file content)", "valid YAML", f"{first}{where}") from None
    except RecursionError:
        raise InputError(what, "(file content)", "YAML nested at most a few hundred levels deep",
                         "nesting too deep") from None
    finally:
        loader.dispose()


def load_yaml_file(path: str | Path, what: str | None = None, *, max_bytes: int = MAX_YAML_BYTES,
                   max_nodes: int = MAX_YAML_NODES, aliases: bool = True) -> Any:
    """Read and parse a YAML file; every problem is one :class:`InputError` line.

    ``what`` names the option the path came from (``--config``, ``--params-file``);
    default: the path.  A missing file, a directory, an unreadable or
    oversized file are refused before parsing.
    """
    p = Path(path)
    what = what or str(p)
    if not p.exists():
        raise InputError(what, str(p), "an existing YAML file", "file not found")
    if p.is_dir():
        raise InputError(what, str(p), "a YAML file", "it is a directory")
    try:
        with p.open("rb") as fh:
            data = fh.read(max_bytes + 1)
    except OSError as exc:
        raise InputError(what, str(p), "a readable YAML file", exc.strerror or type(exc).__name__) from None
    if len(data) > max_bytes:
        raise InputError(what, str(p), f"a YAML file of at most {max_bytes} bytes", "file too large")
    return load_yaml(data, f"{what} {p}" if what != str(p) else what, max_bytes=max_bytes,
                     max_nodes=max_nodes, aliases=aliases)
