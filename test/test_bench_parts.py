"""``gerotor-twin bench parts``' table (behaviour; the timings themselves are benchmarks, never asserted)."""
from gerotor_twin.model import bench_parts


def test_print_parts_prints_one_row_per_point_with_the_unaccounted_rest(monkeypatch):
    """Each point's row carries every part's µs per call, and ``other`` = µs per output step − accounted, where
    accounted = accepted × first_stage + (accepted + rejected) × ros2_step per output step."""
    def fake(cfg, rpm, bar):
        us = {p: float(i + 1) for i, p in enumerate(bench_parts.PARTS)}
        acc, rej = 2.0, 0.5
        return {"chambers": 7, "rpm": rpm, "bar": bar, "model": "mobility", "us_per_call": us,
                "us_per_output_step": 20.0, "accepted_per_step": acc, "rejected_per_step": rej,
                "accounted_us": acc * us["first_stage"] + (acc + rej) * us["ros2_step"]}
    monkeypatch.setattr(bench_parts, "time_parts", fake)
    lines = []
    rows = bench_parts.print_parts([("a", None, 3000.0, 27.5), ("b", None, 7000.0, 0.8)], out=lines.append)
    assert [r["pump"] for r in rows] == ["a", "b"]
    assert all(p in lines[1] for p in bench_parts.PARTS)
    body = [ln.split() for ln in lines[2:]]
    assert [b[0] for b in body] == ["a", "b"]
    accounted = 2.0 * 3.0 + 2.5 * 4.0                     # first_stage is part 3, ros2_step part 4
    assert float(body[0][-2]) == accounted and float(body[0][-1]) == 20.0 - accounted


def test_parts_markdown_is_a_block_that_replaces_its_markers():
    """Behaviour: the block has the provenance line, a head naming every part, one row per result, and it replaces
    the text between the ``bench parts`` markers of a document, leaving the rest as it was."""
    from gerotor_twin.model.bench_all import replace_block
    us = {p: 1.0 for p in bench_parts.PARTS}
    r = {"pump": "default", "chambers": 7, "rpm": 3000.0, "bar": 27.5, "us_per_call": us, "us_per_output_step": 8.0,
         "accepted_per_step": 1.5, "rejected_per_step": 0.5, "accounted_us": 3.5}
    block = bench_parts.parts_markdown([r, dict(r, pump="08")], "Measured now.")
    lines = block.splitlines()
    assert lines[0] == "<!-- bench parts: begin -->" and lines[-1] == "<!-- bench parts: end -->"
    assert lines[1] == "Measured now." and lines[3].count("|") == lines[4].count("|") == lines[5].count("|")
    assert lines[5].startswith("| default | 7 | 3000 | 27.5 | 8.00 |") and lines[5].endswith("| 3.50 | 4.50 |")
    doc = "head\n<!-- bench parts: begin -->\nold\n<!-- bench parts: end -->\ntail\n"
    assert replace_block(doc, block, "bench parts") == "head\n" + block + "tail\n"
