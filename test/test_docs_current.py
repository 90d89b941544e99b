"""The docs describe the product as it is, and docs/architecture.md names every module (behaviour).

A figure or heading is labelled by the date and commit it was measured at, never by the numbered
period of work that produced it; history lives in git.  The map of the package,
``docs/architecture.md``, names every module of ``gerotor_twin`` so that a newcomer finds each one.
"""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "gerotor_twin"

# Built from pieces so that this file does not match its own pattern.
PERIOD_LABEL = re.compile("se" + r"[s]sions?[ -]?[0-9]+" + "|the mor" + "ning", re.IGNORECASE)

_FENCE = re.compile(r"^\s*(```|~~~)")
_INLINE_CODE = re.compile(r"`([^`\n]+)`")
_TOKEN = re.compile(r"[A-Za-z_]\w*(?:[./][A-Za-z_]\w*)*")


def checked_files(root: Path = ROOT) -> list[Path]:
    """README.md, bags/README.md, docs/*.md, the package's, the tests' and the launch files' Python."""
    files = [root / "README.md", root / "bags" / "README.md", *sorted((root / "docs").glob("*.md")),
             *sorted((root / "gerotor_twin").rglob("*.py")), *sorted((root / "test").rglob("*.py")),
             *sorted((root / "launch").glob("*.py"))]
    return [f for f in files if f.is_file()]


def period_labels(paths: list[Path], root: Path = ROOT) -> list[str]:
    """Each line that labels something with a period of work, as 'file:line: match'."""
    found = []
    for path in paths:
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
            for m in PERIOD_LABEL.finditer(line):
                found.append(f"{path.relative_to(root).as_posix()}:{number}: {m.group(0)}")
    return found


def package_modules(package: Path = PACKAGE) -> list[str]:
    """Dotted names (relative to the package) of every module but ``__init__`` / ``__main__``."""
    names = []
    for path in sorted(package.rglob("*.py")):
        if path.stem in ("__init__", "__main__"):
            continue
        names.append(".".join(path.relative_to(package).with_suffix("").parts))
    return names


def _code_text(markdown: str) -> list[str]:
    """The text of inline code spans and fenced blocks: where a doc names a module."""
    spans, fenced = [], False
    for line in markdown.splitlines():
        if _FENCE.match(line):
            fenced = not fenced
            continue
        spans.extend([line] if fenced else _INLINE_CODE.findall(line))
    return spans


def named_modules(markdown: str) -> set[str]:
    """Dotted names a doc writes in code: ``gerotor_twin.a.b``, ``a.b.attr``, ``a/b.py``, ``gerotor_twin/a/b.py``."""
    names = set()
    for span in _code_text(markdown):
        for token in _TOKEN.findall(span):
            token = re.sub(r"\.py$", "", token).replace("/", ".")
            token = re.sub(r"^gerotor_twin\.", "", token)
            parts = token.split(".")
            names.update(".".join(parts[:k]) for k in range(1, len(parts) + 1))
    return names


def unnamed_modules(markdown: str, modules: list[str]) -> list[str]:
    """The modules of ``modules`` that ``markdown`` does not name in code."""
    named = named_modules(markdown)
    return [m for m in modules if m not in named]


def test_period_label_pattern_finds_labels_and_not_dates(tmp_path):
    """The checker reports a period label with file and line and leaves dates and commits alone (behaviour)."""
    doc = tmp_path / "a.md"
    doc.write_text("measured 2026-12-01 at d0653f5\n" + "Se" + "ssion 13: faster\nfiles of the " + "morning\n",
                   encoding="utf-8")
    assert period_labels([doc], root=tmp_path) == ["a.md:2: " + "Se" + "ssion 13", "a.md:3: the " + "morning"]


def test_docs_and_code_carry_no_period_labels():
    """No figure, heading or note in the docs, the package or the tests is labelled with a period of work (behaviour)."""
    found = period_labels(checked_files())
    assert found == [], "label it with its date and commit instead:\n" + "\n".join(found)


def test_module_names_are_read_from_code_only():
    """A module counts as named in code (dotted, as a path, with an attribute), not as a prose word (behaviour)."""
    text = ("The errors of the units.\n\n| `twin/input_book.py` | `io.reader.open_mcap` |\n"
            "```\n gerotor_twin.model.kernel → ros.node\n```\n")
    modules = ["errors", "units", "twin.input_book", "io.reader", "model.kernel", "ros.node", "cli"]
    assert unnamed_modules(text, modules) == ["errors", "units", "cli"]


def test_architecture_names_every_module():
    """docs/architecture.md names every module of the package tree, so the map stays complete (behaviour)."""
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    missing = unnamed_modules(text, package_modules())
    assert missing == [], "docs/architecture.md does not name: " + ", ".join(missing)
