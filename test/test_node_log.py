"""The node's log policy without ROS: decimation, status levels, resume after a write error (behaviour)."""
from __future__ import annotations

import io
import logging
import time

import pytest

from gerotor_twin.errors import InputError
from gerotor_twin.io import messages as m
from gerotor_twin.io.background import BackgroundMcapLog, Reopen
from gerotor_twin.io.mcap_log import McapLog
from gerotor_twin.io.reader import open_mcap
from gerotor_twin.ros.node_log import NodeLogFiles, log_directory
from gerotor_twin.ros.params import PARAMETERS

PRM = {p.name: p.default for p in PARAMETERS}
TOPIC = "/twin/delivery_flow"


def policy(**over):
    return NodeLogFiles(dict(PRM, **over), logging.getLogger("test"), dict)


def test_decimation():
    pol = policy(log_outputs_every=5, log_waveform_every=3, log_diagnostics_every=4)
    assert [pol.due("twin/delivery_flow") for _ in range(10)] == [True, False, False, False, False] * 2
    assert all(pol.due("twin/flow_summary") for _ in range(7))                 # every revolution
    assert [pol.due("twin/chamber_waveform") for _ in range(6)] == [True, False, False] * 2
    assert not pol.due("twin/flow_summary/volumetric_efficiency")              # off by default
    assert policy(log_summary_values=True).due("twin/flow_summary/volumetric_efficiency")
    assert not policy(log_waveforms=False).due("twin/chamber_waveform")
    # the named, stamped topics: per-chamber and twin/sample decimated like the arrays, the residual always,
    # the repeats (twin/revolution = twin/flow_summary, twin/health_update = twin/health,
    # twin/flow_residual/<name>) only with log_summary_values
    for topic in ("twin/chambers/chamber_01/pressure", "twin/chambers/chamber_13/pressure", "twin/sample"):
        assert [pol.due(topic) for _ in range(10)] == [True, False, False, False, False] * 2, topic
    assert all(pol.due("twin/flow_residual") for _ in range(7))
    for topic in ("twin/revolution", "twin/health_update", "twin/flow_residual/delivery_residual_m3s"):
        assert not pol.logged(topic) and not pol.due(topic), topic
        assert policy(log_summary_values=True).due(topic), topic

    def diag(level):
        return m.diagnostic_array(1, [m.diagnostic_status(0, "a"), m.diagnostic_status(level, "b")])
    levels = [0, 0, 0, 2, 2, 2, 2, 2, 0, 0]
    # every 4th, plus each change of the highest level
    assert [pol.due("/diagnostics", diag(lv)) for lv in levels] == \
        [True, False, False, True, True, False, False, False, True, False]


def test_log_directory_expands_and_refuses_unset(monkeypatch, tmp_path):
    monkeypatch.setenv("GT_TEST_DIR", str(tmp_path))
    monkeypatch.delenv("GT_UNSET_DIR", raising=False)
    assert log_directory("$GT_TEST_DIR/logs") == tmp_path / "logs"
    assert str(log_directory("~/x")).startswith(str(tmp_path.home()))
    with pytest.raises(InputError, match=r"log_dir = '\$GT_UNSET_DIR/x' is invalid"):
        log_directory("$GT_UNSET_DIR/x")


class FullDisk(McapLog):
    """Fails every write with ENOSPC, as a full disk does."""

    def write_raw(self, *args, **kwargs):
        raise OSError(28, "No space left on device")


def test_write_error_then_resume_in_a_new_file(caplog):
    failing = io.BytesIO()
    new = []
    free = {"bytes": 0}

    class Reopen0(Reopen):
        def free_bytes(self):
            return free["bytes"]

    def factory():
        new.append(io.BytesIO())
        return McapLog(new[-1])
    bg = BackgroundMcapLog(FullDisk(failing), reopen=Reopen0(factory, None, min_free_bytes=1000, retry_s=0.05),
                           poll_s=0.005)
    bg.add_topic(TOPIC, m.FLOAT64)
    pol = policy()
    assert bg.write(TOPIC, m.float64(1.0), 1)
    deadline = time.monotonic() + 10
    while bg.error is None:
        assert time.monotonic() < deadline
    level, msg, values = pol.status(bg)
    assert level == m.DIAG_ERROR and "No space left" in msg and "1 message(s) lost" in msg
    assert bg.write(TOPIC, m.float64(2.0), 2)                        # counted as lost, not queued forever
    time.sleep(0.3)
    assert not new                                                    # no space yet: no new file
    free["bytes"] = 10_000
    while not new or bg.error is not None:
        assert time.monotonic() < deadline
    for k in range(3, 6):
        assert bg.write(TOPIC, m.float64(float(k)), k)
    stats = bg.close()
    assert stats.resumed == 1 and stats.lost == 2 and "No space left" in stats.last_error
    level, msg, _ = pol.status(bg)
    assert level == m.DIAG_WARN and "resumed after" in msg
    f = open_mcap(new[0])
    assert f.complete and f.topic_types() == {TOPIC: m.FLOAT64} and f.message_count == 3


@pytest.fixture
def read_only_dir(tmp_path):
    """A read-only tmpfs (EROFS, as on a read-only mount); None where it cannot be mounted."""
    import subprocess
    mnt = tmp_path / "ro"
    mnt.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(mnt)], capture_output=True)
    if r.returncode != 0:
        yield None
        return
    try:
        yield mnt
    finally:
        subprocess.run(["umount", "-l", str(mnt)], check=False)


@pytest.mark.parametrize("case", ["file in the way", "read-only file system"])
def test_log_dir_that_cannot_be_written_is_one_line_naming_log_dir(tmp_path, read_only_dir, case):
    """Behaviour: a log_dir the node cannot write is one line naming log_dir, its value and the reason
    (not a raw ``[Errno 30] ...``)."""
    if case == "file in the way":
        (tmp_path / "f").write_text("x")
        value, reason = str(tmp_path / "f" / "logs"), "not a directory"
    else:
        if read_only_dir is None:
            pytest.skip("cannot mount a read-only tmpfs here")
        value, reason = str(read_only_dir / "logs"), "read-only file system"
    with pytest.raises(InputError) as ei:
        policy(log_dir=value).open([(TOPIC, m.FLOAT64, "reliable")])
    msg = str(ei.value)
    assert msg.startswith(f"log_dir = '{value}' is invalid; allowed: a directory this process can create")
    assert reason in msg and "Errno" not in msg and "\n" not in msg
