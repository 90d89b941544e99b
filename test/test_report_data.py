"""Report input loading: every bad file gives a clear error naming the file and the problem."""
import warnings

import pytest

from gerotor_twin.cli import main
from gerotor_twin.io import McapReadError, TruncatedMcapWarning
from gerotor_twin.io import messages as m
from gerotor_twin.report.data import load_bench, load_twin, overlap
from report_helpers import T0, write_bench, write_twin


def test_loads_bench_and_twin(tmp_path):
    b = load_bench(write_bench(tmp_path / "b.mcap"))
    assert b.t0_ns == T0 and len(b.speed[0]) == 600
    tw = load_twin(write_twin(tmp_path / "t.mcap"), b.t0_ns)
    assert tw.label == "twin (fixed)" and tw.summary[1].shape[1] == 4
    assert tw.eccentricity[1].shape[1] == 2 and tw.waveforms[1].shape[2] == 8
    lo, hi = overlap(b, [tw])
    assert 0 < lo < 0.1 and 11.5 < hi < 12.0


def test_missing_and_corrupt_files(tmp_path):
    with pytest.raises(McapReadError, match="does not exist") as e:
        load_bench(tmp_path / "nope.mcap")
    assert "nope.mcap" in str(e.value)
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"#ROSBAG V2.0\n" + b"\0" * 100)
    with pytest.raises(McapReadError, match="not an MCAP file"):
        load_bench(bad)


def test_missing_topic_and_wrong_type(tmp_path):
    p = write_bench(tmp_path / "b.mcap", skip=("/bench/delivery_flow",))
    with pytest.raises(McapReadError, match=r"/bench/delivery_flow \(std_msgs/msg/Float64\) is missing") as e:
        load_bench(p)
    assert str(p) in str(e.value) and "topics present" in str(e.value)
    p2 = write_bench(tmp_path / "b2.mcap", types={"/bench/delivery_flow": m.FLUID_PRESSURE})
    with pytest.raises(McapReadError, match="is sensor_msgs/msg/FluidPressure, expected std_msgs/msg/Float64"):
        load_bench(p2)
    with pytest.raises(McapReadError, match="/twin/flow_summary"):
        load_twin(p2, T0)


def test_truncated_file_read_with_warning(tmp_path):
    p = write_bench(tmp_path / "b.mcap", duration=60.0, rate=100.0)
    data = p.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.7)])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        b = load_bench(cut)
    assert any(issubclass(w.category, TruncatedMcapWarning) for w in caught)
    assert b.warnings and "cut.mcap" in b.warnings[0]
    assert 0 < len(b.speed[0]) < 6000


def test_no_time_overlap(tmp_path):
    b = load_bench(write_bench(tmp_path / "b.mcap"))
    tw = load_twin(write_twin(tmp_path / "t.mcap", shift_s=1000.0), b.t0_ns)
    with pytest.raises(McapReadError, match="no time overlap") as e:
        overlap(b, [tw])
    assert "t.mcap" in str(e.value) and "b.mcap" in str(e.value)


def test_cli_reports_bad_input(tmp_path, capsys):
    b = write_bench(tmp_path / "b.mcap")
    rc = main(["report", "--bench", str(b), "--twin", str(tmp_path / "missing.mcap"), "-o", str(tmp_path / "r.html")])
    assert rc == 2
    err = capsys.readouterr().err
    assert "missing.mcap" in err and "does not exist" in err
    assert not (tmp_path / "r.html").exists()
