"""The benchmarks' markdown blocks and the in-place update of a doc (fake results, no benchmark is run)."""
from __future__ import annotations

import pytest

from gerotor_twin.cli import _bench_command, build_parser
from gerotor_twin.model.bench_all import (BEGIN, END, BenchAll, Machine, Provenance, accuracy_markdown, machine,
                                          markdown, markers, replace_block, write_doc)

COLUMNS = "| pump | model | rpm | bar | RTF | CPU RTF | sub-steps/rev | µs/sub-step |"
ACCURACY_COLUMNS = ("| model | rpm | bar | range | RMS | max | peak | sampled (solver + grid) | η | flow RMS | "
                    "sub-steps/rev | verdict |")


def _prov(load=(0.2, 0.3)) -> Provenance:
    return Provenance(date="2026-12-04 21:00", commit="abc1234", command="gerotor-twin bench all --seconds 1",
                      machine=Machine(cpu="Some CPU", cores=2, system="Linux 6.1", python="3.11.2", numba="0.60.0"),
                      load=load)


def _row(pump, model, rpm, bar):
    return {"pump": pump, "model": model, "rpm": rpm, "bar": bar, "wall_s": 0.1, "real_time_factor": 10.0,
            "cpu_real_time_factor": 11.0, "substeps_per_revolution": 450.0, "us_per_substep": 3.5}


MODELS_COLUMNS = "| gear model | rpm | wall time / rev | × mobility | RTF |"


def _fake(load=(0.2, 0.3), compile_=None) -> BenchAll:
    return BenchAll(provenance=_prov(load),
                    model_rows=[{"model": m, "rpm": 1000, "wall_s_per_rev": w, "real_time_factor": 0.06 / w,
                                 "relative_to_mobility": w / 0.002} for m, w in (("mobility", 0.002), ("fdm", 0.17))],
                    default_rows=[_row("default (config/pump.yaml)", "mobility", 3000, 27.5)],
                    family_rows=[_row("04_motorcycle_engine_oil", "mobility", 7000, 0.6),
                                 _row("04_motorcycle_engine_oil", "mobility", 7000, 6.0)],
                    compile=compile_)


def _table(lines, columns):
    """The data rows of the table whose header is ``columns``, each checked to have its cells."""
    header = lines.index(columns)
    assert set(lines[header + 1].replace("|", "")) == {"-"}
    rows = []
    for line in lines[header + 2:]:
        if not line.startswith("|"):
            break
        assert line.count("|") == columns.count("|")
        rows.append(line)
    return rows


def test_markdown_is_one_table_with_provenance_between_the_markers():
    lines = markdown(_fake(), seconds=1.0, repeats=3).splitlines()
    assert lines[0] == BEGIN and lines[-1] == END
    rows = _table(lines, COLUMNS)
    assert len(rows) == 3
    assert rows[0].startswith("| default (config/pump.yaml) | mobility | 3000 | 27.5 |")
    assert rows[1].startswith("| 04_motorcycle_engine_oil | mobility | 7000 | 0.6 |")
    assert _table(lines, MODELS_COLUMNS) == ["| mobility | 1000 | 2.00 ms | 1.00 | 30 |",
                                             "| fdm | 1000 | 170.00 ms | 85.00 | 0.353 |"]
    text = "\n".join(lines)
    for fact in ("2026-12-04 21:00 UTC", "abc1234", "`gerotor-twin bench all --seconds 1`", "Some CPU",
                 "2 logical cores", "Python 3.11.2", "numba 0.60.0", "median of 3 runs of 1 s"):
        assert fact in text
    assert "loaded machine" not in text


def test_markdown_says_when_the_machine_was_loaded_and_what_the_compile_took():
    text = markdown(_fake(load=(3.5, 4.2), compile_={"seconds": 212.4, "line": "compiled 39 in 212 s"}), 1.0, 3)
    assert "loaded machine" in text
    assert "212 s of wall time; it printed `compiled 39 in 212 s`" in text


def test_accuracy_markdown_has_a_row_per_point_in_percent():
    row = {"model": "mobility", "rpm": 3000.0, "bar": 27.5, "pressure_range": 29.4e5,
           "rms_pressure_error_of_range": 0.0025, "max_pressure_error_of_range": 0.021,
           "peak_pressure_error_gauge": -0.002, "sampled_peak_error": -0.002, "peak_numerics_error": -0.0017,
           "peak_sampling_error": -0.0003, "efficiency_error": -0.00022, "flow_rms_error": 0.0031,
           "substeps_per_revolution": 420.0, "within_budget": True}
    lines = accuracy_markdown([row, dict(row, model="fixed", within_budget=False)], _prov()).splitlines()
    assert (lines[0], lines[-1]) == markers("bench accuracy")
    rows = _table(lines, ACCURACY_COLUMNS)
    assert rows[0] == ("| mobility | 3000 | 27.5 | 29.4 bar | 0.25 % | 2.1 % | -0.20 % | -0.20 % (-0.17 % -0.03 %) "
                       "| -0.022 % | 0.31 % | 420 | ok |")
    assert rows[1].startswith("| fixed |") and rows[1].endswith("| outside |")
    assert "abc1234" in lines[1]


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


def test_two_named_blocks_in_one_doc_are_replaced_each_on_its_own(tmp_path):
    acc_begin, acc_end = markers("bench accuracy")
    doc = tmp_path / "numerics.md"
    doc.write_text(f"{BEGIN}\na\n{END}\nmiddle\n{acc_begin}\nb\n{acc_end}\n", encoding="utf-8")
    write_doc(doc, f"{acc_begin}\nnew\n{acc_end}\n", "bench accuracy")
    assert doc.read_text(encoding="utf-8") == f"{BEGIN}\na\n{END}\nmiddle\n{acc_begin}\nnew\n{acc_end}\n"


@pytest.mark.parametrize("text", ["no markers", f"{END}\n{BEGIN}\n", f"{BEGIN}\n{END}\n{BEGIN}\n{END}\n"])
def test_replace_block_refuses_a_doc_without_one_pair_of_markers(text):
    with pytest.raises(ValueError, match="bench all: begin"):
        replace_block(text, "x")


def test_machine_names_the_cpu_and_the_versions():
    m = machine()
    assert m.cpu and m.cores >= 1 and m.python.count(".") == 2 and m.numba


@pytest.mark.parametrize("argv,command", [
    (["bench", "all", "--seconds", "2", "--repeats", "5", "--write-doc", "docs/performance.md"],
     "gerotor-twin bench all --seconds 2 --repeats 5 --write-doc docs/performance.md"),
    (["bench", "accuracy", "--rpm", "1000,3000", "--models", "mobility,fixed", "--json", "F"],
     "gerotor-twin bench accuracy --rpm 1000,3000 --bar 27.5 --models mobility,fixed"),
])
def test_the_command_line_in_the_block_reproduces_the_options(argv, command):
    assert _bench_command(build_parser().parse_args(argv)) == command
