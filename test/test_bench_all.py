"""``gerotor-twin bench all``: its markdown block and the in-place update of a doc (a fake result, no benchmark)."""
from __future__ import annotations

import pytest

from gerotor_twin.cli import _bench_all_command, build_parser
from gerotor_twin.model.bench_all import BEGIN, END, BenchAll, Machine, machine, markdown, replace_block, write_doc

COLUMNS = "| pump | model | rpm | bar | RTF | CPU RTF | sub-steps/rev | µs/sub-step |"


def _row(pump, model, rpm, bar):
    return {"pump": pump, "model": model, "rpm": rpm, "bar": bar, "wall_s": 0.1, "real_time_factor": 10.0,
            "cpu_real_time_factor": 11.0, "substeps_per_revolution": 450.0, "us_per_substep": 3.5}


def _fake(load=(0.2, 0.3), compile_=None) -> BenchAll:
    return BenchAll(date="2026-12-04 21:00", commit="abc1234", command="gerotor-twin bench all --seconds 1",
                    machine=Machine(cpu="Some CPU", cores=2, system="Linux 6.1", python="3.11.2", numba="0.60.0"),
                    load=load, default_rows=[_row("default (config/pump.yaml)", "mobility", 3000, 27.5)],
                    family_rows=[_row("04_motorcycle_engine_oil", "mobility", 7000, 0.6),
                                 _row("04_motorcycle_engine_oil", "mobility", 7000, 6.0)],
                    compile=compile_)


def test_markdown_is_one_table_with_provenance_between_the_markers():
    lines = markdown(_fake(), seconds=1.0, repeats=3).splitlines()
    assert lines[0] == BEGIN and lines[-1] == END
    header = lines.index(COLUMNS)
    assert set(lines[header + 1].replace("|", "")) == {"-"}
    rows = lines[header + 2:-1]
    assert len(rows) == 3 and all(r.count("|") == COLUMNS.count("|") for r in rows)
    assert rows[0].startswith("| default (config/pump.yaml) | mobility | 3000 | 27.5 |")
    assert rows[1].startswith("| 04_motorcycle_engine_oil | mobility | 7000 | 0.6 |")
    text = "\n".join(lines)
    for fact in ("2026-12-04 21:00 UTC", "abc1234", "`gerotor-twin bench all --seconds 1`", "Some CPU",
                 "2 logical cores", "Python 3.11.2", "numba 0.60.0", "median of 3 runs of 1 s"):
        assert fact in text
    assert "loaded machine" not in text


def test_markdown_says_when_the_machine_was_loaded_and_what_the_compile_took():
    text = markdown(_fake(load=(3.5, 4.2), compile_={"seconds": 212.4, "line": "compiled 39 in 212 s."}), 1.0, 3)
    assert "loaded machine" in text
    assert "212 s (compiled 39 in 212 s)" in text


def test_replace_block_replaces_only_the_block_and_a_rerun_is_stable(tmp_path):
    doc = tmp_path / "performance.md"
    doc.write_text(f"# Title\n\nintro\n\n{BEGIN}\nold table\n{END}\n\n## Next\ntext\n", encoding="utf-8")
    block = markdown(_fake(), 1.0, 3)
    write_doc(doc, block)
    once = doc.read_text(encoding="utf-8")
    assert once == f"# Title\n\nintro\n\n{block}\n## Next\ntext\n"
    assert "old table" not in once
    write_doc(doc, block)
    assert doc.read_text(encoding="utf-8") == once


@pytest.mark.parametrize("text", ["no markers", f"{END}\n{BEGIN}\n", f"{BEGIN}\n{END}\n{BEGIN}\n{END}\n"])
def test_replace_block_refuses_a_doc_without_one_pair_of_markers(text):
    with pytest.raises(ValueError, match="bench all: begin"):
        replace_block(text, "x")


def test_machine_names_the_cpu_and_the_versions():
    m = machine()
    assert m.cpu and m.cores >= 1 and m.python.count(".") == 2 and m.numba


def test_the_command_line_in_the_block_reproduces_the_options():
    args = build_parser().parse_args(["bench", "all", "--seconds", "2", "--repeats", "5", "--write-doc",
                                      "docs/performance.md"])
    assert _bench_all_command(args) == ("gerotor-twin bench all --seconds 2 --repeats 5 "
                                        "--write-doc docs/performance.md")
