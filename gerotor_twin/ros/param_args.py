"""The parameters a command line gives a node: ``--params-file`` and ``-p``, read as rcl would (no rclpy).

Why the node reads them itself: rcl merges ``-p`` into the values of the
params files per name, and when the two differ in type the merged value keeps
both; rclpy then takes the first set one in the order bool, integer, double,
string.  So ``--params-file twin.yaml -p tick_rate_hz:=abc`` silently keeps the
file's ``100.0`` (the string loses), while ``-p tick_rate_hz:=200`` wins as an
integer and is refused by rclpy as the wrong type (checked on Jazzy, rclpy
7.1.6).  And rclpy ignores every override for which no parameter is declared,
so a typo is silently dropped.  :func:`overrides_from_args` gives the
effective values in rcl's precedence (files in order, then ``-p`` in order, a
later one wins), each with where it came from, so the node validates every one
of them the same way and passes the validated values explicitly.

Node-name rules follow rcl: a params-file section applies when its key
(``/**``, ``twin_node``, ``/ns/twin_node``, with ``*`` = one name token and
``**`` = any number) matches the node's fully qualified name; nested maps
give dotted parameter names; ``-p node:name:=value`` applies to that node only.
A section that does not apply but looks written for the node (a mistyped node
name) is named by :func:`unapplied_sections`: the node warns, since rcl skips it
silently.
"""
from __future__ import annotations

import difflib
import re
from dataclasses import dataclass
from typing import Any

from gerotor_twin.errors import MAX_ERROR_CHARS, InputError, clip
from gerotor_twin.yaml_safe import load_yaml, load_yaml_file

__all__ = ["Override", "RosArgs", "parse_ros_args", "overrides_from_args", "params_from_file", "file_sections",
           "unapplied_sections"]

_WITH_VALUE = {"--params-file", "-p", "--param", "-r", "--remap", "--log-level", "--log-config-file",
               "-e", "--enclave", "--log-file-name"}


@dataclass(frozen=True)
class Override:
    """One parameter value given to the node, and where it came from (for error messages)."""
    name: str
    value: Any
    source: str              #: ``--params-file config/twin.yaml`` or ``-p``


@dataclass(frozen=True)
class RosArgs:
    """What the ``--ros-args`` sections of a command line say about parameters and the node name."""
    params_files: tuple[str, ...] = ()
    params: tuple[tuple[str, str], ...] = ()     #: ``(name or node:name, value text)`` of each ``-p``
    node_name: str | None = None                 #: from ``-r __node:=``
    namespace: str | None = None                 #: from ``-r __ns:=``


def parse_ros_args(argv: list[str]) -> RosArgs:
    """The ``--ros-args ... [--]`` sections of ``argv`` (the rest is the program's own)."""
    files, params, node, ns = [], [], None, None
    inside, i = False, 0
    while i < len(argv):
        a = argv[i]
        if a == "--ros-args":
            inside = True
        elif a == "--" and inside:
            inside = False
        elif inside and a in _WITH_VALUE:
            if i + 1 >= len(argv):
                raise InputError(a, None, "a value after it", "the command line ends here")
            v = argv[i + 1]
            i += 1
            if a == "--params-file":
                files.append(v)
            elif a in ("-p", "--param"):
                if ":=" not in v:
                    raise InputError(a, v, "name:=value")
                params.append(tuple(v.split(":=", 1)))
            elif a in ("-r", "--remap") and ":=" in v:
                key, val = v.split(":=", 1)
                key = key.split(":", 1)[-1]
                node, ns = (val, ns) if key == "__node" else (node, val if key == "__ns" else ns)
        i += 1
    return RosArgs(tuple(files), tuple(params), node, ns)


def _key_regex(key: str) -> re.Pattern:
    """rcl's node-name key (``/**``, ``/ns/*``, ``name``) as a regex over fully qualified names."""
    key = key if key.startswith("/") else "/" + key
    parts = []
    for tok in key.strip("/").split("/"):
        if tok == "**":
            parts.append(r"(?:/[^/]+)*")
        else:
            parts.append("/" + re.escape(tok).replace(r"\*", "[^/]*"))
    return re.compile("^" + "".join(parts) + "$")


def _flatten(prefix: str, node: Any, out: dict[str, Any]) -> None:
    for k, v in node.items():
        name = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, dict):
            _flatten(name, v, out)
        else:
            out[name] = v


def file_sections(path: str) -> list[tuple[str, dict[str, Any]]]:
    """The ``ros__parameters`` sections of a params file: ``(node-name key, {name: value})`` in file order.

    The key is as written (``twin_node``, ``/ns/twin_node``, ``/**``; ``""`` for a
    top-level ``ros__parameters``); nested maps give dotted names.

    Raises
    ------
    InputError
        Missing, unreadable or malformed file, or a section without ``ros__parameters``.
    """
    doc = load_yaml_file(path, "--params-file", aliases=False)        # rcl refuses aliases too
    what = f"--params-file {path}"
    if not isinstance(doc, dict):
        raise InputError(what, type(doc).__name__, "a mapping of node names to {ros__parameters: {...}}")
    out: list[tuple[str, dict[str, Any]]] = []

    def walk(prefix: str, node: Any) -> None:
        if not isinstance(node, dict):
            raise InputError(f"{what}: {prefix}", node, "node sections <node name>: {ros__parameters: {...}}")
        for k, v in node.items():
            if k == "ros__parameters":
                if not isinstance(v, dict):
                    raise InputError(f"{what}: {prefix}.ros__parameters", v, "a mapping of parameter values")
                flat: dict[str, Any] = {}
                _flatten("", v, flat)
                out.append((prefix, flat))
            else:
                walk(f"{prefix}/{str(k).strip('/')}" if prefix else str(k), v)

    walk("", doc)
    return out


def _applies(key: str, node_fqn: str) -> bool:
    """Does the section ``key`` apply to the node ``node_fqn`` (rcl's matching)?"""
    return bool(_key_regex(key or "/").match(node_fqn))


def params_from_file(path: str, node_fqn: str) -> dict[str, Any]:
    """Parameters a params file gives the node ``node_fqn`` (``/twin_node``), in file order.

    Raises
    ------
    InputError
        Missing, unreadable or malformed file, or a section without ``ros__parameters``.
    """
    out: dict[str, Any] = {}
    for key, params in file_sections(path):
        if _applies(key, node_fqn):
            out.update(params)
    return out


def _node_fqn(ra: RosArgs, node_name: str, namespace: str) -> tuple[str, str]:
    """The node's (name, fully qualified name) after ``-r __node:=`` / ``__ns:=`` remaps."""
    name = ra.node_name or node_name
    ns = (ra.namespace or namespace or "/").rstrip("/")
    return name, f"{ns}/{name}" if ns.startswith("/") else f"/{ns}/{name}" if ns else f"/{name}"


def overrides_from_args(argv: list[str], node_name: str, namespace: str = "/") -> dict[str, Override]:
    """Effective parameter values for ``node_name`` from ``argv`` (rcl precedence: files, then ``-p``).

    ``-p`` values are typed as YAML scalars, as rcl does (``200`` integer,
    ``200.0`` double, ``true`` bool, anything else a string).
    """
    ra = parse_ros_args(argv)
    _, fqn = _node_fqn(ra, node_name, namespace)
    out: dict[str, Override] = {}
    for path in ra.params_files:
        for k, v in params_from_file(path, fqn).items():
            out[k] = Override(k, v, f"--params-file {path}")
    for key, text in ra.params:
        target, _, pname = key.rpartition(":")
        if target and not _key_regex(target).match(fqn):
            continue
        value = load_yaml(text, f"-p {pname}", max_bytes=100_000, max_nodes=10_000,
                          aliases=False) if text.strip() else ""
        out[pname] = Override(pname, value, "-p")
    return out


def unapplied_sections(argv: list[str], node_name: str, namespace: str = "/") -> list[str]:
    """Warnings, one line each, for params-file sections that do not apply to this node but look meant for it.

    rcl silently skips a section whose node name does not match (``twin_nod:``
    for ``twin_node``), so a typo in the name runs the node on its defaults.
    A section that does not apply is named when its last name token is close
    to the node's name (``difflib`` ratio >= 0.8) or more than half of its keys
    are parameters of the node (``use_sim_time`` and the like not counted);
    its keys are checked as the node would check them (unknown names, values
    it would refuse).  A file none of whose sections applies is named too, and
    so is a ``-p node:name:=value`` whose node part looks meant for the node.
    Files are read with :func:`file_sections` (errors as there).
    """
    ra = parse_ros_args(argv)
    name, fqn = _node_fqn(ra, node_name, namespace)
    out = []
    for path in ra.params_files:
        sections = file_sections(path)
        expected = f"sections that apply: {name}, {fqn}, /**"
        meant = [(k, p) for k, p in sections if not _applies(k, fqn) and _looks_meant(k, p, name)]
        for key, params in meant:
            out.append(clip(f"--params-file {path}: section '{key}' is not applied: it does not match this "
                            f"node's name {fqn} ({expected}); {_describe_keys(params, name)}", MAX_ERROR_CHARS))
        if sections and not meant and not any(_applies(k, fqn) for k, _ in sections):
            out.append(clip(f"--params-file {path} gives {fqn} no parameters: its sections are "
                            f"{', '.join(repr(k) for k, _ in sections)} ({expected})", MAX_ERROR_CHARS))
    for key, text in ra.params:                 # -p twin_nod:log_dir:=... is skipped the same way
        target, _, pname = key.rpartition(":")
        if target and not _key_regex(target).match(fqn) and _looks_meant(target, {pname: text}, name):
            out.append(clip(f"-p {key}:={text} is not applied: {target} does not match this node's name {fqn} "
                            f"(use -p {pname}:=... or -p {name}:{pname}:=...)", MAX_ERROR_CHARS))
    return out


def _looks_meant(key: str, params: dict[str, Any], node_name: str) -> bool:
    """A section probably written for ``node_name``: a close name, or mostly its parameters."""
    from gerotor_twin.ros.params import BUILTIN, PARAMETERS
    last = key.rstrip("/").rsplit("/", 1)[-1]
    if difflib.SequenceMatcher(None, last, node_name).ratio() >= 0.8:
        return True
    own = {p.name for p in PARAMETERS}
    keys = [k for k in params if k not in BUILTIN]
    return 2 * sum(k in own for k in keys) > len(keys)


def _describe_keys(params: dict[str, Any], node_name: str) -> str:
    """``its parameters are ignored: a, b (...)`` with the keys checked as the node would (first problem)."""
    from gerotor_twin.ros.params import check_value
    problems = []
    for k, v in params.items():
        try:
            check_value(k, v)
        except InputError as exc:
            problems.append(str(exc))
    text = f"its {len(params)} parameter(s) are ignored: {', '.join(params) or '(none)'}"
    if problems:
        text += f"; {len(problems)} of them would be refused too, e.g. {problems[0]}"
    return text
