"""twin_node parameters: every value given is validated the same way (file or -p), unknown names refused
with a suggestion, bad files one line, and no parameter changes at run time (each refusal has a reason).

Tiers: behaviour.  The pure parts (gerotor_twin.ros.param_args, gerotor_twin.ros.params.check_overrides)
are tested without ROS; the node's refusals through its ``main`` in this process (they come before
``rclpy.init``) and, with the rest, in real processes (marked slow)."""
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from gerotor_twin.errors import MAX_ERROR_CHARS, InputError
from gerotor_twin.ros.param_args import overrides_from_args, params_from_file, unapplied_sections
from gerotor_twin.ros.params import PARAMETERS, check_overrides, fixed_reason, refuse_change

ROOT = Path(__file__).resolve().parent.parent
TWIN_YAML = str(ROOT / "config" / "twin.yaml")


def effective(*ros_args, name="twin_node"):
    return check_overrides(overrides_from_args(["twin_node", "--ros-args", *ros_args], name))


def test_packaged_params_file_is_valid_and_complete():
    v = effective("--params-file", TWIN_YAML)
    assert set(v) == {p.name for p in PARAMETERS}


@pytest.mark.parametrize("args,needle", [
    (("-p", "tick_rat_hz:=200.0"), "did you mean tick_rate_hz"),
    (("-p", "bearing_modle:=fdm"), "did you mean bearing_model"),
    (("-p", "tick_rate_hz:=abc"), "tick_rate_hz = 'abc' is invalid; allowed: a double"),
    (("-p", "tick_rate_hz:=5000.0"), "tick_rate_hz = 5000.0 is invalid; allowed: [1, 1000] Hz"),
    (("-p", "waveform_every:=1.5"), "waveform_every = 1.5 is invalid; allowed: an integer"),
    (("-p", "bearing_model:=7"), "quote it"),
    (("-p", "use_sim_time:=maybe"), "use_sim_time = 'maybe' is invalid; allowed: a bool"),
    (("-p", "log_compression:=gzip"), "zstd | lz4 | none"),
    (("-p", "input_coalesce_s:=0.1"), "input_coalesce_s = 0.1 is invalid; allowed: [0, 0.05] s"),
    (("-p", "startup_rtf_threshold:=-1.0"), "startup_rtf_threshold = -1.0 is invalid; allowed: [0, 1000]"),
    (("-p", "startup_rtf_threshold:=1e9"), "startup_rtf_threshold = 1000000000.0 is invalid; allowed: [0, 1000]"),
    (("-p", "startup_rtf_threshold:=fast"), "startup_rtf_threshold = 'fast' is invalid; allowed: a double"),
])
def test_p_overrides_validated_like_the_file(args, needle):
    """Behaviour: the -p value wins over the file (rcl precedence) and is validated, whatever its type."""
    with pytest.raises(InputError) as ei:
        effective("--params-file", TWIN_YAML, *args)
    assert needle in str(ei.value) and str(ei.value).startswith("-p: ")


def test_p_overrides_win_in_rcl_order_and_int_for_double_is_accepted():
    v = effective("--params-file", TWIN_YAML, "-p", "tick_rate_hz:=200", "-p", "tick_rate_hz:=300",
                  "-p", "bearing_model:=fdm", "-p", "other_node:log_dir:=x", "-p", "twin_node:log_queue:=1000")
    assert v["tick_rate_hz"] == 300.0 and isinstance(v["tick_rate_hz"], float)
    packaged = effective("--params-file", TWIN_YAML)["log_dir"]        # other_node's -p does not apply
    assert v["bearing_model"] == "fdm" and v["log_dir"] == packaged != "x" and v["log_queue"] == 1000


def test_params_file_sections_and_typos(tmp_path):
    f = tmp_path / "p.yaml"
    f.write_text("/**:\n  ros__parameters:\n    tick_rate_hz: 50.0\n"
                 "other_node:\n  ros__parameters:\n    anything: 1\n"
                 "/twin_node:\n  ros__parameters:\n    stale_timeout: 1.0\n")
    assert params_from_file(str(f), "/twin_node") == {"tick_rate_hz": 50.0, "stale_timeout": 1.0}
    assert params_from_file(str(f), "/ns/other_node") == {"tick_rate_hz": 50.0}
    with pytest.raises(InputError, match=r"--params-file .*p\.yaml: stale_timeout .*did you mean stale_timeout_s"):
        effective("--params-file", str(f))
    # remapped node name: the other section applies
    with pytest.raises(InputError, match="anything"):
        effective("--params-file", str(f), "-r", "__node:=other_node")


def unapplied(*ros_args, name="twin_node"):
    return unapplied_sections(["twin_node", "--ros-args", *ros_args], name)


def test_section_under_a_mistyped_node_name_is_named(tmp_path):
    """Behaviour: a params file whose section is under a mistyped node name (rcl skips it silently) gives a
    warning naming the section, the node name expected and the ignored keys, the keys checked as the node
    would (an unknown name, a value it would refuse)."""
    f = tmp_path / "p.yaml"
    f.write_text("twin_nod:\n  ros__parameters:\n    log_dir: /data/twin\n    tick_rate_hz: 5000.0\n"
                 "    colour: red\n")
    assert effective("--params-file", str(f)) == {}                    # rcl's rule: nothing applies
    (w,) = unapplied("--params-file", str(f))
    assert w.startswith(f"--params-file {f}: section 'twin_nod' is not applied: it does not match this "
                        "node's name /twin_node (sections that apply: twin_node, /twin_node, /**)"), w
    assert "its 3 parameter(s) are ignored: log_dir, tick_rate_hz, colour" in w
    assert "2 of them would be refused too, e.g. tick_rate_hz = 5000.0 is invalid; allowed: [1, 1000] Hz" in w
    # a section of mostly twin_node parameters under another name, and the remapped node name
    f.write_text("/bench/twin:\n  ros__parameters:\n    log_dir: /x\n    bearing_model: fdm\n")
    assert "section '/bench/twin' is not applied" in unapplied("--params-file", str(f))[0]
    assert unapplied("--params-file", str(f), "-r", "__ns:=/bench", "-r", "__node:=twin") == []
    # the same typo in a -p with a node part
    assert unapplied("-p", "twin_nod:log_dir:=/x") == [
        "-p twin_nod:log_dir:=/x is not applied: twin_nod does not match this node's name /twin_node "
        "(use -p log_dir:=... or -p twin_node:log_dir:=...)"]
    assert unapplied("-p", "other_node:anything:=1", "-p", "twin_node:log_dir:=/x") == []


def test_sections_of_other_nodes_are_not_warned(tmp_path):
    """Behaviour: a shared params file with other nodes' sections (and one for this node) gives no warning;
    one with no section for this node at all says so, naming its sections."""
    assert unapplied("--params-file", TWIN_YAML) == []
    f = tmp_path / "p.yaml"
    f.write_text("/**:\n  ros__parameters:\n    use_sim_time: true\n"
                 "other_node:\n  ros__parameters:\n    anything: 1\n    log_dir: /y\n")
    assert unapplied("--params-file", str(f)) == []
    f.write_text("other_node:\n  ros__parameters:\n    anything: 1\n")
    (w,) = unapplied("--params-file", str(f))
    assert w == (f"--params-file {f} gives /twin_node no parameters: its sections are 'other_node' "
                 "(sections that apply: twin_node, /twin_node, /**)")


@pytest.mark.parametrize("content,needle", [
    (None, "file not found"), ("/**:\n  ros__parameters: [1, 2\n", "valid YAML"),
    ("- a\n- b\n", "a mapping of node names"),
    ("/**:\n  ros__parameters:\n    stale_timeout_s: &t 0.5\n    stamp_restart_s: *t\n", "rcl refuses aliases"),
    ("/**:\n  ros__parameters: 3\n", "a mapping of parameter values"),
    ("a0: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}" if i > 1 else "*a"] * 10) + "]\n" for i in range(1, 9)),
     "alias"),
])
def test_bad_params_file_is_one_line(tmp_path, content, needle):
    f = tmp_path / "p.yaml"
    if content is not None:
        f.write_text(content)
    with pytest.raises(InputError) as ei:
        effective("--params-file", str(f))
    assert needle in str(ei.value) and len(str(ei.value)) < MAX_ERROR_CHARS


def test_run_time_changes_refused_with_reason():
    class P:
        def __init__(self, name, value):
            self.name, self.value = name, value
    cur = {"use_sim_time": False, "tick_rate_hz": 100.0, "bearing_model": "mobility"}
    assert refuse_change(cur, [P("tick_rate_hz", 100.0)]) == (True, "")
    ok, why = refuse_change(cur, [P("use_sim_time", True)])
    assert not ok and "clock source" in why and "restart the node" in why
    for name in ("bearing_model", "shaft_speed_topic", "log_dir", "sample_period_s", "startup_rtf_threshold"):
        assert "cannot change while the node runs" in fixed_reason(name)


# ------------------------------------------------------------------ real processes
def node_main(monkeypatch, capsys, *ros_args):
    """The node's ``main`` in this process for a command line it must refuse before ``rclpy.init`` (reaching
    ``rclpy.init`` fails the test): (exit code, stdout + stderr)."""
    rclpy = pytest.importorskip("rclpy")
    from gerotor_twin.ros import node

    def no_init(*_a, **_k):        # pytest.fail: a BaseException, which main's `except Exception` does not catch
        pytest.fail("the parameters passed validation: rclpy.init reached")
    monkeypatch.setattr(rclpy, "init", no_init)
    code = node.main(["twin_node", "--ros-args", *ros_args])
    cap = capsys.readouterr()
    return code, cap.out + cap.err


def run_node(*ros_args, timeout=60):
    env_args = [sys.executable, "-m", "gerotor_twin.ros.node", "--ros-args", *ros_args]
    import os
    from gerotor_twin.ros.domain import claim_domain
    env = dict(os.environ, ROS_DOMAIN_ID=str(claim_domain()))
    p = subprocess.Popen(env_args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                         start_new_session=True)
    try:
        out, err = p.communicate(timeout=timeout)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait(10)
    return p.returncode, out + err


@pytest.mark.parametrize("args,needle", [
    (("--params-file", TWIN_YAML, "-p", "tick_rat_hz:=200.0"), "did you mean tick_rate_hz"),
    (("--params-file", TWIN_YAML, "-p", "tick_rate_hz:=abc"), "tick_rate_hz = 'abc'"),
    (("--params-file", "/nonexistent/twin.yaml"), "file not found"),
    (("--params-file", str(ROOT / "config" / "pump.yaml")), "ros__parameters"),
])
def test_node_refuses_bad_parameters_one_line(args, needle, monkeypatch, capsys):
    """Behaviour: exit 2, one line naming the problem, no traceback (the node's ``main``, which refuses these
    before ``rclpy.init``; the real process: ``test_node_refuses_bad_parameters_from_the_shell``)."""
    code, out = node_main(monkeypatch, capsys, *args)
    lines = [ln for ln in out.splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and needle in lines[0] and "Traceback" not in out, out


@pytest.mark.slow
def test_node_refuses_bad_parameters_from_the_shell(tmp_path):
    """Behaviour (real process): a bad ``-p`` value and a typo in a params file: exit 2, one line naming the
    problem, no traceback."""
    code, out = run_node("--params-file", TWIN_YAML, "-p", "tick_rate_hz:=abc")
    lines = [ln for ln in out.splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and "tick_rate_hz = 'abc'" in lines[0] and "Traceback" not in out, out
    f = tmp_path / "twin.yaml"
    f.write_text("/**:\n  ros__parameters:\n    stale_timout_s: 0.5\n")
    code, out = run_node("--params-file", str(f))
    lines = [ln for ln in out.splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and "did you mean stale_timeout_s" in lines[0] and str(f) in lines[0], out


@pytest.mark.slow
def test_node_pump_config_errors_name_pump_config(tmp_path):
    """Behaviour (real process): a missing or empty pump file given as pump_config is one line naming
    pump_config (not --config), the path, and for an empty file that it is empty; exit 2."""
    empty = tmp_path / "empty.yaml"
    empty.write_text("")
    for path, needle in ((tmp_path / "none.yaml", "file not found"), (empty, "the file is empty")):
        code, out = run_node("--params-file", TWIN_YAML, "-p", f"pump_config:={path}", "-p", "log_dir:=''")
        lines = [ln for ln in out.splitlines() if ln.strip()]
        assert code == 2 and len(lines) == 1, out
        assert lines[0].startswith(f"error: pump_config = '{path}' is invalid") and needle in lines[0], out
        assert "--config" not in out and "NoneType" not in out


@pytest.mark.slow
def test_node_warns_about_a_section_under_another_node_name(tmp_path):
    """Behaviour (real process): ``twin_nod: {ros__parameters: {log_dir: ...}}`` -> the node runs on its
    defaults but says so at start (WARN on the console naming the section, the expected node name and the
    ignored key) and its /diagnostics node status is WARN with that text; a pump_config note (an older
    file's numerics.tolerance) is said the same way, once."""
    import os
    import time
    from gerotor_twin.ros.domain import claim_domain
    from ros_peer import Peer, kill_node, latest_diag, stop_node
    import yaml
    f = tmp_path / "twin.yaml"
    f.write_text(f"twin_nod:\n  ros__parameters:\n    log_dir: {tmp_path / 'logs'}\n")
    pump = yaml.safe_load((ROOT / "config" / "pump.yaml").read_text())
    pump["numerics"]["tolerance"] = 5.0e-5                   # an older pump file's value
    old = tmp_path / "old_pump.yaml"
    old.write_text(yaml.safe_dump(pump))
    d = claim_domain()
    env = dict(os.environ, ROS_DOMAIN_ID=str(d), PYTHONUNBUFFERED="1")
    with open(tmp_path / "node.log", "w") as out:
        proc = subprocess.Popen([sys.executable, "-m", "gerotor_twin.ros.node", "--ros-args", "--params-file",
                                 str(f), "-p", "startup_rtf_threshold:=0.0", "-p", f"pump_config:={old}"],
                                stdout=out, stderr=subprocess.STDOUT, env=env, cwd=str(tmp_path),
                                start_new_session=True)
    peer = Peer(d)
    try:
        peer.wait_for(lambda: latest_diag(peer, "gerotor_twin: node").get("_level") is not None, 60,
                      "/diagnostics", proc)
        diag = latest_diag(peer, "gerotor_twin: node")
        assert diag["_level"] == 1 and "section 'twin_nod' is not applied" in diag["_message"], diag
        assert f"pump_config {old}: numerics.tolerance = 5e-05 is far outside" in diag["start_warnings"], diag
        assert stop_node(proc) == 0
    finally:
        kill_node(proc)
        peer.close()
    text = (tmp_path / "node.log").read_text()
    warn = [ln for ln in text.splitlines() if "twin_nod'" in ln]
    assert len(warn) == 1 and "WARN" in warn[0] and "/twin_node" in warn[0] and "log_dir" in warn[0], text
    assert "log off" in text and not (tmp_path / "logs").exists()
    notes = [ln for ln in text.splitlines() if "numerics.tolerance = 5e-05" in ln]
    assert len(notes) == 1 and "WARN" in notes[0] and "ln(rho)" in notes[0], text


@pytest.mark.slow
def test_node_refuses_live_changes_with_reason(tmp_path):
    """Behaviour (real process): use_sim_time and bearing_model cannot be set at run time; the reason comes back."""
    import rclpy
    from rcl_interfaces.srv import GetParameters, SetParameters
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter
    from gerotor_twin.ros.domain import claim_domain
    from ros_peer import kill_node, start_node, stop_node
    d = claim_domain()
    proc = start_node(d, tmp_path, "tick_rate_hz:=200")           # an integer for a double: accepted
    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=d)
    node = rclpy.create_node("param_peer", context=ctx)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)

    def call(srv, request):
        cli = node.create_client(srv, f"/twin_node/{'get' if srv is GetParameters else 'set'}_parameters")
        assert cli.wait_for_service(timeout_sec=60.0), (tmp_path / "node.log").read_text()
        for _ in range(3):      # a response sent before the node has matched this client's response reader is dropped
            fut = cli.call_async(request)       # ("failed to send response (timeout)": a service is two topics,
            ex.spin_until_future_complete(fut, timeout_sec=20)     # ros2/rclc#390): the same request again
            if fut.done():
                return fut.result()
            cli.remove_pending_request(fut)
        raise AssertionError("no response in three tries:\n" + (tmp_path / "node.log").read_text())

    try:
        got = call(GetParameters, GetParameters.Request(names=["tick_rate_hz", "use_sim_time"]))
        assert got.values[0].double_value == 200.0 and got.values[1].bool_value is False
        req = SetParameters.Request(parameters=[
            Parameter("use_sim_time", value=True).to_parameter_msg(),
            Parameter("bearing_model", value="fdm").to_parameter_msg(),
            Parameter("tick_rate_hz", value=200.0).to_parameter_msg()])
        res = call(SetParameters, req).results
        assert not res[0].successful and "use_sim_time cannot change" in res[0].reason, res[0].reason
        assert not res[1].successful and "bearing_model cannot change" in res[1].reason, res[1].reason
        assert res[2].successful                     # same value: a no-op is fine
        got = call(GetParameters, GetParameters.Request(names=["use_sim_time", "bearing_model"]))
        assert got.values[0].bool_value is False and got.values[1].string_value == "mobility"
        assert stop_node(proc, signal.SIGINT) == 0
    finally:
        kill_node(proc)
        ex.shutdown(timeout_sec=1.0)
        node.destroy_node()
        rclpy.try_shutdown(context=ctx)


@pytest.mark.parametrize("content,needle", [
    ("/**:\n  ros__parameters:\n    stale_timout_s: 0.5\n", "did you mean stale_timeout_s"),
    ("/**:\n  ros__parameters:\n    tick_rate_hz: [100\n", "valid YAML"),
    ("/**:\n  ros__parameters:\n    bearing_model: fdm\n    log_queue: 1.5\n", "log_queue = 1.5"),
])
def test_node_refuses_bad_params_file_one_line(tmp_path, content, needle, monkeypatch, capsys):
    """Behaviour: a typo or a malformed params file: exit 2, one line, no traceback (the node's ``main``; the
    real process: ``test_node_refuses_bad_parameters_from_the_shell``)."""
    f = tmp_path / "twin.yaml"
    f.write_text(content)
    code, out = node_main(monkeypatch, capsys, "--params-file", str(f))
    lines = [ln for ln in out.splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and needle in lines[0] and str(f) in lines[0], out


@pytest.mark.slow
def test_command_line_rcl_refuses_is_one_error_line():
    """Behaviour (real process): what only rcl checks (a malformed remap rule) ends in one `error:` line, exit 2
    (rcl logs its own [ERROR] line before; no traceback)."""
    code, out = run_node("-r", "foo")
    lines = [ln for ln in out.splitlines() if ln.strip()]
    assert code == 2 and lines[-1].startswith("error: ") and "remap" in lines[-1] and "Traceback" not in out, out
    assert len(lines) <= 2
