"""The one YAML loader (gerotor_twin.yaml_safe) and bounded error messages (gerotor_twin.errors).

Tier: behaviour (bad input gives one short line; nothing expands beyond a sane size).
"""
import subprocess
import sys
from pathlib import Path

import pytest

from gerotor_twin.errors import MAX_ERROR_CHARS, InputError, clip, one_line, short_repr
from gerotor_twin.yaml_safe import MAX_YAML_NODES, load_yaml, load_yaml_file

ROOT = Path(__file__).resolve().parent.parent


def laughs(levels: int = 12, width: int = 10) -> str:
    """The classic alias bomb: width**levels leaves from a few hundred bytes."""
    lines = ['a0: &a0 ["lol"]']
    for i in range(1, levels):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * width) + "]")
    return "\n".join(lines) + "\n"


def test_alias_bomb_refused_quickly_with_one_line():
    """Behaviour: 10**12 expanded nodes from < 1 kB: refused before any object is built."""
    text = laughs()
    assert len(text) < 1000
    with pytest.raises(InputError) as ei:
        load_yaml(text, "--config")
    msg = str(ei.value)
    assert "alias" in msg and str(MAX_YAML_NODES) in msg and "\n" not in msg and len(msg) < MAX_ERROR_CHARS


def test_small_aliases_still_allowed():
    """Behaviour: ordinary anchors (a few shared maps) load as before."""
    assert load_yaml("base: &b {x: 1}\nother: *b\n") == {"base": {"x": 1}, "other": {"x": 1}}


def test_recursive_alias_refused():
    with pytest.raises(InputError, match="recursive"):
        load_yaml("a: &a [*a]\n")


def test_exponent_floats_are_numbers():
    """Behaviour: YAML 1.2 / rcl read 1e-3 as a float (PyYAML's 1.1 rules would give a string)."""
    assert load_yaml("x: 1e-3\ny: -2E+2\nz: '1e3'\n") == {"x": 1e-3, "y": -200.0, "z": "1e3"}


@pytest.mark.parametrize("text,needle", [("a: [1, 2\n", "valid YAML"), ("[" * 5000, "valid YAML|nested"),
                                         ("x" * 2_000_000, "at most")])
def test_malformed_or_huge_text_is_one_line(text, needle):
    with pytest.raises(InputError) as ei:
        load_yaml(text, "--params-file")
    msg = str(ei.value)
    assert "\n" not in msg and len(msg) < MAX_ERROR_CHARS
    import re
    assert re.search(needle, msg)


def test_files_missing_directory_binary(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        load_yaml_file(tmp_path / "nope.yaml", "--config")
    with pytest.raises(InputError, match="directory"):
        load_yaml_file(tmp_path, "--config")
    (tmp_path / "b.yaml").write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(InputError, match="UTF-8"):
        load_yaml_file(tmp_path / "b.yaml", "--config")


def test_error_parts_bounded_whatever_the_value():
    """Behaviour: an InputError of a 100 MB string or a deeply shared structure stays short."""
    x = [1]
    for _ in range(40):
        x = [x] * 10                       # 10**40 leaves if printed in full
    for value in ("v" * 100_000_000, x, {"k" * 10_000: 1}):
        e = InputError("f" * 10_000, value, "a" * 10_000, "r" * 10_000)
        assert len(str(e)) < MAX_ERROR_CHARS
    assert len(short_repr(x)) <= 120 and clip("a\nb") == "a b"
    assert len(one_line(ValueError("z" * 10**6))) <= MAX_ERROR_CHARS


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "gerotor_twin", *args], capture_output=True, text=True,
                          cwd=ROOT, timeout=300)


COMMANDS = [("geometry",), ("simulate", "--rpm", "1000", "--bar", "5"), ("demo", "--out", "{tmp}/d"),
            ("bench", "realtime"), ("synth-bench", "-o", "{tmp}/s.mcap"),
            ("run-bag", "bags/bench_map.mcap", "-o", "{tmp}/r.mcap"), ("paper", "efficiency")]
BAD_CONFIGS = ["dir", "bomb", "unreadable"]


def _bad_config(tmp_path, bad):
    """--config as a directory, an alias bomb or an unreadable file (a Unix socket: ENXIO even for root)."""
    if bad == "dir":
        return tmp_path
    cfg = tmp_path / "pump.yaml"
    if bad == "bomb":
        cfg.write_text(laughs())
    else:
        import socket
        sock = socket.socket(socket.AF_UNIX)
        sock.bind(str(cfg))
        sock.close()
    return cfg


def _assert_one_config_line(stderr):
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: --config") and "Traceback" not in stderr, stderr
    assert len(lines[0]) < MAX_ERROR_CHARS


@pytest.mark.parametrize("args", COMMANDS)
@pytest.mark.parametrize("bad", BAD_CONFIGS)
def test_every_command_config_problem_is_one_line(tmp_path, args, bad, capsys, monkeypatch):
    """Behaviour: --config as a directory, an alias bomb or an unreadable file: one line, exit 2 (the
    command's ``main``, every command × every problem; the process around it: the next test)."""
    from gerotor_twin.cli import main
    monkeypatch.chdir(ROOT)
    cfg = _bad_config(tmp_path, bad)
    argv = [a.replace("{tmp}", str(tmp_path)) for a in args]
    assert main([*argv, "--config", str(cfg)]) == 2
    _assert_one_config_line(capsys.readouterr().err)


@pytest.mark.parametrize("i", range(len(COMMANDS)))
def test_every_command_config_problem_is_one_line_from_the_shell(tmp_path, i):
    """Behaviour: the same in a fresh ``python -m gerotor_twin`` process (exit status 2, stderr one line and
    nothing else, e.g. no warning at import): each command once, the three problems in turn."""
    cfg = _bad_config(tmp_path, BAD_CONFIGS[i % len(BAD_CONFIGS)])
    argv = [a.replace("{tmp}", str(tmp_path)) for a in COMMANDS[i]]
    p = run_cli(*argv, "--config", str(cfg))
    assert p.returncode == 2, p.stderr
    _assert_one_config_line(p.stderr)


def test_one_loader_everywhere():
    """Every YAML the package reads goes through gerotor_twin.yaml_safe (no other yaml.load/safe_load/compose)."""
    import re
    bad = []
    for f in (ROOT / "gerotor_twin").rglob("*.py"):
        if f.name == "yaml_safe.py":
            continue
        for n, line in enumerate(f.read_text().splitlines(), 1):
            if re.search(r"\byaml\.(safe_load|load|full_load|unsafe_load|load_all|safe_load_all|compose)\b", line) or \
                    re.search(r"\b(SafeLoader|FullLoader|CSafeLoader|CLoader)\b", line):
                bad.append(f"{f.relative_to(ROOT)}:{n}")
    assert not bad, bad


def test_pump_config_in_mcap_metadata_goes_through_the_loader(tmp_path):
    """A report over a twin log whose stored pump config is an alias bomb falls back, it does not blow up."""
    from gerotor_twin.report.data import TwinData, pump_config
    twin = TwinData.__new__(TwinData)
    twin.pump_config_yaml = laughs()
    twin.path = "x.mcap"
    cfg = pump_config(twin)                    # falls back to the default pump (noted by the caller)
    assert cfg.gears.chambers == 7


def test_own_warnings_print_as_one_line_others_as_python_does(capsys):
    """Behaviour: under ``one_line_warnings`` (the CLI's entry) a warning of the package's own class prints
    ``warning: <message>`` on one line, without Python's file, class and source line; another package's
    warning goes to the handler that was there before, which is back afterwards."""
    import warnings

    from gerotor_twin.errors import one_line_warnings
    from gerotor_twin.io.reader import TruncatedMcapWarning
    passed_on = []
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = before = lambda message, category, *rest: passed_on.append(category)
        with one_line_warnings():
            warnings.warn("bag.mcap: truncated\nrecovered 5 messages", TruncatedMcapWarning)
            warnings.warn("not ours", DeprecationWarning)
        assert warnings.showwarning is before
    assert capsys.readouterr().err == "warning: bag.mcap: truncated recovered 5 messages\n"
    assert passed_on == [DeprecationWarning]
