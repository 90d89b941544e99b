"""The package's import graph has no cycle, and the CLI's commands are registered in one list (behaviour).

Imports are read from the source (``ast``), module level and function level alike, so a cycle hidden in
a function (``sweep`` calling into ``sweep_bench`` which calls back into ``sweep``) counts too.  A
subpackage's ``__init__`` is left out: it re-exports its own modules, which is not a dependency.
"""
from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "gerotor_twin"


def _module_name(path: Path, package: Path) -> str:
    parts = path.relative_to(package.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imported(node: ast.AST, importer: str, is_package: bool) -> list[str]:
    """Dotted names an import statement may refer to (module, or module + imported name)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if not isinstance(node, ast.ImportFrom):
        return []
    base = node.module or ""
    if node.level:
        parts = importer.split(".") if is_package else importer.split(".")[:-1]
        parts = parts[:len(parts) - (node.level - 1)]
        base = ".".join(parts + ([node.module] if node.module else []))
    return [base] + [f"{base}.{a.name}" for a in node.names]


def import_graph(package: Path = PACKAGE) -> dict[str, set[str]]:
    """Module -> the package modules it imports anywhere in its source (``__init__`` modules left out)."""
    files = {_module_name(p, package): p for p in package.rglob("*.py")}
    modules = {name for name, p in files.items() if p.stem != "__init__"}
    graph = {}
    for name in modules:
        path = files[name]
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets.update(t for t in _imported(node, name, False) if t in modules)
        graph[name] = targets - {name}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan), each sorted."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_cycle_finder_sees_a_cycle_through_a_function_level_import(tmp_path):
    """Closed form: a → b at module level and b → a inside a function is one cycle; c alone is none."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("from .a import x\n")
    (pkg / "a.py").write_text("from .b import y\nx = 1\n")
    (pkg / "b.py").write_text("def y():\n    from .a import x\n    return x\n")
    (pkg / "c.py").write_text("import pkg.a\n")
    graph = import_graph(pkg)
    assert graph == {"pkg.a": {"pkg.b"}, "pkg.b": {"pkg.a"}, "pkg.c": {"pkg.a"}}
    assert cycles(graph) == [["pkg.a", "pkg.b"]]


def test_package_has_no_import_cycle():
    """No two modules of gerotor_twin import each other, directly or through others (behaviour)."""
    assert cycles(import_graph()) == []


def test_bench_sweep_is_still_a_bench_choice():
    """``gerotor-twin bench sweep`` and ``bench node`` are registered from the command list (behaviour)."""
    from gerotor_twin.cli import build_parser
    bench = build_parser()._subparsers._group_actions[0].choices["bench"]      # noqa: SLF001
    what = next(a for a in bench._actions if a.dest == "what")                  # noqa: SLF001
    assert {"realtime", "accuracy", "models", "node", "sweep"} <= set(what.choices)


def package_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """Subpackage -> the other subpackages its modules import (top-level modules left out)."""
    def package(name):
        parts = name.split(".")
        return parts[1] if len(parts) > 2 else None
    out: dict[str, set[str]] = {}
    for a, targets in graph.items():
        pa = package(a)
        if pa is None:
            continue
        out.setdefault(pa, set()).update(pb for pb in map(package, targets) if pb not in (None, pa))
    return out


def test_subpackages_import_one_way():
    """No two subpackages of gerotor_twin import each other, directly or through others: calibration reads the
    report's plateau detector, the report never reads calibration or offline (behaviour)."""
    graph = package_graph(import_graph())
    assert cycles(graph) == []
    assert "offline" not in graph["report"] and "calibration" not in graph["report"]
