"""README.md and docs/*.md: every relative link resolves, and the README stays short (behaviour).

A relative link (``[text](path)``, ``![alt](path)``, optionally ``path#anchor`` or just
``#anchor``) must name an existing file of the repository; an anchor into a Markdown file must
match one of its headings, slugged the way GitHub does (lower case, punctuation other than
``-``/``_`` dropped, spaces to ``-``, ``-1``, ``-2`` … for repeated headings). Links inside
fenced code blocks and inline code are not links and are ignored; ``http(s)://`` and ``mailto:``
links are not checked (no network).
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README_MAX_LINES = 150

_LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
_FENCE = re.compile(r"^\s*(```|~~~)")
_INLINE_CODE = re.compile(r"`[^`\n]*`")
_HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")


def _markdown_files() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _prose_lines(text: str) -> list[tuple[int, str]]:
    """Lines outside fenced code blocks, with their 1-based numbers."""
    out, fenced = [], False
    for number, line in enumerate(text.splitlines(), start=1):
        if _FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            out.append((number, line))
    return out


def github_slug(heading: str) -> str:
    """Anchor GitHub gives a heading: markup dropped, lower case, punctuation removed, spaces → '-'."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links keep their text
    text = text.replace("`", "").replace("*", "").strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    seen: dict[str, int] = {}
    result = set()
    for _, line in _prose_lines(path.read_text(encoding="utf-8")):
        m = _HEADING.match(line)
        if not m:
            continue
        slug = github_slug(m.group(2))
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        result.add(slug if n == 0 else f"{slug}-{n}")
    return result


def broken_links(path: Path) -> list[str]:
    """Each broken relative link of one Markdown file, as 'file:line: target (reason)'."""
    problems = []
    for number, line in _prose_lines(path.read_text(encoding="utf-8")):
        for target in _LINK.findall(_INLINE_CODE.sub("", line)):
            if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target):
                continue  # http:, https:, mailto: ...
            file_part, _, anchor = target.partition("#")
            dest = (path.parent / file_part).resolve() if file_part else path
            where = f"{path.relative_to(ROOT)}:{number}: {target}"
            if not dest.exists():
                problems.append(f"{where} (no such file)")
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                problems.append(f"{where} (no heading with anchor #{anchor} in {dest.name})")
    return problems


def test_slug_rules_match_github_examples():
    """The slug function reproduces GitHub anchors of headings of this repository (closed form)."""
    assert github_slug("Section 4 of the paper: calibration, tables 3–5, figs. 12–16") == \
        "section-4-of-the-paper-calibration-tables-35-figs-1216"
    assert github_slug("`gerotor-twin bench node`") == "gerotor-twin-bench-node"
    assert github_slug("Threads, input accounting, performance") == "threads-input-accounting-performance"


def test_checker_finds_broken_links(tmp_path, monkeypatch):
    """The checker reports a missing file and a missing anchor, and ignores code (behaviour)."""
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    (tmp_path / "a.md").write_text("# Title\n\n[ok](#title) [bad](#nope) [gone](missing.md)\n"
                                   "`[code](missing.md)`\n```\n[fenced](missing.md)\n```\n",
                                   encoding="utf-8")
    problems = broken_links(tmp_path / "a.md")
    assert len(problems) == 2
    assert "#nope" in problems[0] and "missing.md" in problems[1]


@pytest.mark.parametrize("path", _markdown_files(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_relative_links_resolve(path):
    """Every relative link and anchor in README.md and docs/*.md points at something (behaviour)."""
    assert broken_links(path) == []


def test_readme_stays_short():
    """The README keeps to what a newcomer needs first; the rest lives in docs/ (behaviour)."""
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= README_MAX_LINES, f"README.md has {len(lines)} lines (at most {README_MAX_LINES})"


def test_readme_links_every_doc():
    """Every docs/*.md is reachable from the README (behaviour)."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    missing = [p.name for p in sorted((ROOT / "docs").glob("*.md")) if f"(docs/{p.name}" not in readme]
    assert missing == []


def test_node_parameter_table_names_every_parameter():
    """docs/node.md's parameter table names every parameter twin_node declares, and no other (behaviour)."""
    from gerotor_twin.ros.params import PARAMETERS

    text = (ROOT / "docs" / "node.md").read_text(encoding="utf-8")
    section = text.split("\n### Parameters\n", 1)[1].split("\n### ", 1)[0]
    first_cells = [row.split("|")[1] for row in section.splitlines() if row.startswith("| `")]
    tabled = {name for cell in first_cells for name in re.findall(r"`([a-z_]+)`", cell)}
    declared = {p.name for p in PARAMETERS}
    assert declared - tabled == set(), "parameters missing from the table"
    assert tabled - declared == set(), "table rows naming no declared parameter"
