"""Config validation and CLI behaviour (bad input gives one clear line, exit 2, no traceback)."""
import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from gerotor_twin.config import default_config_path, load_config, parse_config
from gerotor_twin.errors import InputError

ROOT = Path(__file__).resolve().parent.parent


def raw():
    return yaml.safe_load(default_config_path().read_text())


@pytest.mark.parametrize("mutate,field", [
    (lambda r: r["gears"].update(width_m=-1.0), "gears.width_m"),
    (lambda r: r["gears"].update(lobe_radius_m=17.5e-3), "gears.lobe_radius_m"),
    (lambda r: r["gears"].update(colour="red"), "gears.colour"),
    (lambda r: r.update(extra={}), "extra"),
    (lambda r: r["fluid"].update(viscosity_pa_s=float("nan")), "fluid.viscosity_pa_s"),
    (lambda r: r["clearances"].update(housing_radial_m=0.0), "clearances.housing_radial_m"),
    (lambda r: r["boundary"].update(mode="magic"), "boundary.mode"),
    (lambda r: r["ports"]["delivery"].update(end_deg=200.0), "ports.delivery.start_deg"),
    (lambda r: r["gears"].pop("width_m"), "gears.width_m"),
    # the oil, mixture and fluid-model sections (issue 13; test_config_oil.py has the rest)
    (lambda r: r["oil"].update(grade=46), "oil.grade"),                                  # both forms
    (lambda r: r["oil"].pop("viscosity_points"), "oil.grade"),                           # neither
    (lambda r: r["oil"].update(colour="amber"), "oil.colour"),
    (lambda r: r["oil"].update(viscosity_points=[[40, 46]]), "oil.viscosity_points"),
    (lambda r: r["oil"].update(viscosity_points=[[40, 46], [100, float("nan")]]),
     "oil.viscosity_points[1].viscosity"),
    (lambda r: r["oil"].update(viscosity_points=[[40, 46], [100, 60]]), "oil.viscosity_points[1].viscosity"),
    (lambda r: r["oil"].update(viscosity_points=[[40, 46], [900, 6]]), "oil.viscosity_points[1].temperature"),
    (lambda r: r["oil"].update(reference_temperature_c=500.0), "oil.reference_temperature_c"),
    (lambda r: r["oil"].update(bulk_modulus_pa=-1.0), "oil.bulk_modulus_pa"),
    (lambda r: r["oil"].update(density_15_kg_m3="heavy"), "oil.density_15_kg_m3"),
    (lambda r: r["fluid"].update(viscosity_pa_s=0.04), "fluid.viscosity_pa_s"),           # set by the oil
    (lambda r: r.update(fluid_model="ideal"), "fluid_model"),
    (lambda r: r["mixture"].update(air_fraction=0.9), "mixture.air_fraction"),
    (lambda r: r["mixture"].update(polytropic_index=2.0), "mixture.polytropic_index"),
    (lambda r: r["mixture"].update(bubbles=3), "mixture.bubbles"),
])
def test_bad_config_names_field(mutate, field):
    r = raw()
    mutate(r)
    with pytest.raises(InputError) as ei:
        parse_config(r)
    assert ei.value.field == field
    assert "allowed" in str(ei.value)


def test_default_config_loads():
    c = load_config()
    assert c.gears.chambers == 7 and c.boundary.mode == "imposed"


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "gerotor_twin", *args], capture_output=True, text=True,
                          cwd=ROOT, timeout=300)


def test_cli_geometry_json(tmp_path):
    p = run_cli("geometry", "--json", str(tmp_path / "g.json"), "--plot", str(tmp_path / "g.png"))
    assert p.returncode == 0, p.stderr
    d = json.loads((tmp_path / "g.json").read_text())
    for k in ("chambers", "eccentricity_m", "lobe_centre_radius_m", "lobe_radius_m", "width_m",
              "displacement_m3_per_rev", "min_chamber_volume_m3", "max_chamber_volume_m3"):
        assert k in d
    assert (tmp_path / "g.png").stat().st_size > 10000


def test_cli_simulate_json(tmp_path):
    p = run_cli("simulate", "--rpm", "2000", "--bar", "10", "--json", str(tmp_path / "s.json"),
                "--plot", str(tmp_path / "s.png"))
    assert p.returncode == 0, p.stderr
    d = json.loads((tmp_path / "s.json").read_text())
    for k in ("theoretical_flow_m3s", "mean_delivery_flow_m3s", "volumetric_efficiency", "delivery_flow_ripple",
              "min_chamber_pressure_pa", "max_chamber_pressure_pa"):
        assert k in d
    assert 0 < d["volumetric_efficiency"] < 1


def test_cli_simulate_says_when_it_did_not_settle(tmp_path, capsys):
    """Nothing silent: a run stopped by ``--revolutions`` before the settling test passed says so, on its summary
    line and in one warning naming the last change and what to raise, and its JSON says ``settled: false``; a
    settled run says neither."""
    from gerotor_twin.cli import main
    for revs, settled in (("2", False), ("30", True)):
        js = tmp_path / f"s{revs}.json"
        assert main(["simulate", "--rpm", "2000", "--bar", "10", "--revolutions", revs, "--json", str(js)]) == 0
        out, err = capsys.readouterr()
        warned = [ln for ln in err.splitlines() if "not settled" in ln]
        assert json.loads(js.read_text())["settled"] is settled
        if settled:
            assert not warned and "revolutions to periodic state" in out
        else:
            assert len(warned) == 1 and "changed the mean flow by" in warned[0] and "raise --revolutions" in warned[0]
            assert "2 revolutions and not settled" in out


@pytest.mark.parametrize("args,needle", [
    (("simulate", "--rpm", "5000", "--bar", "10"), "--rpm = 5000.0 is invalid; allowed: (0, 3300] rpm (the rated 3000 rpm + 10 %)"),
    (("simulate", "--rpm", "1000", "--bar", "40"), "--bar = 40.0 is invalid"),
    (("simulate", "--rpm", "nan", "--bar", "10"), "--rpm"),
    (("geometry", "--config", "/nonexistent.yaml"), "file not found"),
])
def test_cli_user_errors_are_one_line(args, needle, capsys):
    """Behaviour: exit 2, the field named, no traceback (the command's ``main``; the process: next test)."""
    from gerotor_twin.cli import main
    try:
        rc = main(list(args))
    except SystemExit as exc:                 # argparse's own refusals leave this way
        rc = exc.code
    err = capsys.readouterr().err
    assert rc == 2
    assert needle in err
    assert "Traceback" not in err


def test_cli_user_error_from_the_shell():
    """Behaviour: the same from ``python -m gerotor_twin``: exit status 2, the field named, no traceback."""
    p = run_cli("simulate", "--rpm", "5000", "--bar", "10")
    assert p.returncode == 2
    assert "--rpm = 5000.0 is invalid; allowed: (0, 3300] rpm (the rated 3000 rpm + 10 %)" in p.stderr
    assert "Traceback" not in p.stderr


def test_core_never_imports_rclpy():
    bad = []
    for f in (ROOT / "gerotor_twin").rglob("*.py"):
        if "ros" in f.relative_to(ROOT / "gerotor_twin").parts[:1]:
            continue
        for line in f.read_text().splitlines():
            s = line.strip()
            if s.startswith(("import rclpy", "from rclpy")):
                bad.append(str(f))
    assert not bad


def test_cli_bench_realtime_runs(tmp_path):
    p = run_cli("bench", "realtime", "--models", "fixed", "--seconds", "0.01", "--repeats", "1",
                "--json", str(tmp_path / "b.json"))
    assert p.returncode == 0, p.stderr
    rows = json.loads((tmp_path / "b.json").read_text())["realtime"]
    assert [r["rpm"] for r in rows] == [1000, 2000, 3000] and all(r["real_time_factor"] > 0 for r in rows)


def test_cli_bench_realtime_takes_rpm_and_bar(tmp_path, capsys):
    """Behaviour: --rpm selects the speeds of `bench realtime` (default 1000,2000,3000), --bar its pressure;
    a speed outside the pump's range is one line, exit 2."""
    from gerotor_twin.cli import main
    js = tmp_path / "b.json"
    assert main(["bench", "realtime", "--models", "fixed", "--rpm", "1500", "--bar", "10", "--seconds", "0.01",
                 "--repeats", "1", "--json", str(js)]) == 0
    assert "(10 bar," in capsys.readouterr().out
    assert [r["rpm"] for r in json.loads(js.read_text())["realtime"]] == [1500]
    assert main(["bench", "realtime", "--rpm", "4000"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --rpm = '4000'") and "\n" not in err


def test_cli_bench_realtime_in_calls(tmp_path, capsys):
    """Behaviour: --call-ms advances in calls of that much model time (as the node does per input sample), says
    so, and records it; a value outside (0, --seconds] is one line naming the option, exit 2.  The calls cover
    the same model time as one call: as many output steps (the model's step count)."""
    from gerotor_twin.cli import main
    from gerotor_twin.config import load_config
    from gerotor_twin.model.bench import advance_in_calls
    from gerotor_twin.model.pump import Inputs, PumpModel
    js = tmp_path / "b.json"
    assert main(["bench", "realtime", "--models", "fixed", "--rpm", "1500", "--seconds", "0.01", "--repeats", "1",
                 "--call-ms", "2", "--json", str(js)]) == 0
    assert "in calls of 2 ms" in capsys.readouterr().out
    assert json.loads(js.read_text())["realtime"][0]["call_s"] == pytest.approx(2e-3)
    assert main(["bench", "realtime", "--seconds", "0.01", "--call-ms", "20"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --call-ms = 20") and "\n" not in err
    cfg = load_config()
    m = PumpModel(cfg, "fixed")
    inp = Inputs(1500 * 3.141592653589793 / 30, 101325.0, 101325.0 + 10e5)
    s0 = m.initial_state(inp)
    one = advance_in_calls(m, s0, 0.012, inp)
    many = advance_in_calls(m, s0, 0.012, inp, call_s=0.003)
    assert many.t == pytest.approx(one.t) and many.counts["steps"] == one.counts["steps"]


def test_cli_output_into_a_closed_pipe_is_quiet(monkeypatch, capsys):
    """Behaviour: when the reader of stdout goes away (`gerotor-twin ... | head`) the command ends with
    128 + SIGPIPE and no traceback or 'error:' line."""
    from gerotor_twin import cli

    def gone(args):
        raise BrokenPipeError(32, "Broken pipe")
    parser = cli.build_parser()
    args = parser.parse_args(["geometry"])
    args.func = gone
    monkeypatch.setattr(cli, "build_parser", lambda argv=None: type("P", (), {"parse_args": lambda self, argv: args})())
    assert cli.main(["geometry"]) == 141         # (capsys's stdout has no file descriptor to redirect)
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("argv", [["run-bag", "bags/bench_transient.mcap", "-o", "{tmp}/x.mcap"],
                                  ["calibrate", "--bench", "bags/bench_map.mcap", "-o", "{tmp}/x.yaml"],
                                  ["batch", "bags", "-o", "{tmp}/fleet"]])
@pytest.mark.parametrize("bad", ["-1", "500", "nan"])
def test_oil_sensor_tau_refused_alike(tmp_path, capsys, argv, bad):
    """Bad input: every command with --oil-sensor-tau refuses it in one line naming the flag; nothing written."""
    from gerotor_twin.cli import main
    root = Path(__file__).resolve().parent.parent
    args = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    args = [str(root / a) if a.startswith("bags") else a for a in args] + ["--oil-sensor-tau", bad]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --oil-sensor-tau = ") and "\n" not in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("text,reason", [("", "the file is empty"), ("# only a comment\n", "the file is empty"),
                                         ("- gears\n", "the file holds a list")])
def test_empty_pump_file_names_the_path_and_the_option(tmp_path, text, reason):
    """Behaviour: an empty (or non-mapping) pump file is one line naming the option the path came from, the
    path and that it is empty, never ``config = 'NoneType'``; the node's errors say ``pump_config``."""
    f = tmp_path / "pump.yaml"
    f.write_text(text)
    with pytest.raises(InputError) as ei:
        load_config(f)
    msg = str(ei.value)
    assert msg.startswith(f"--config = '{f}' is invalid; allowed: a YAML mapping of the sections")
    assert reason in msg and "NoneType" not in msg
    with pytest.raises(InputError, match=rf"^pump_config = '{f}' is invalid.*\({reason}\)"):
        load_config(f, "pump_config")
    with pytest.raises(InputError, match=r"^pump_config = .*file not found"):
        load_config(tmp_path / "missing.yaml", "pump_config")


def _pump_file(tmp_path, **numerics):
    r = raw()
    r["numerics"].update(numerics)
    f = tmp_path / "old_pump.yaml"
    f.write_text(yaml.safe_dump(r))
    return f


def test_tolerance_of_an_older_pump_file_is_named_with_its_hint(tmp_path):
    """Behaviour: ``numerics.tolerance: 5.0e-5`` (an error on ln rho in older files) loads, with one note naming
    the key, the value, the default (read from Numerics), the sensible range and what changed; on the CLI a
    ``warning:`` line on stderr, exit 0."""
    from gerotor_twin.config import Numerics
    f = _pump_file(tmp_path, tolerance=5.0e-5)
    said = []
    cfg = load_config(f, warn=said.append)
    d = Numerics().tolerance
    assert cfg.numerics.tolerance == 5.0e-5 and len(said) == 1 and said == [f"--config {f}: {cfg.notes[0]}"]
    assert said[0].startswith(f"--config {f}: numerics.tolerance = 5e-05 is far outside its sensible range "
                              f"[{d / 100:g}, {d * 100:g}] (default {d:g}; 100x either way); "
                              "numerics.tolerance is a fraction of the pressure scale"), said
    assert "ln(rho)" in said[0] and "\n" not in said[0]
    p = run_cli("geometry", "--config", str(f), "--json", str(tmp_path / "g.json"))
    assert p.returncode == 0 and f"warning: --config {f}: numerics.tolerance = 5e-05" in p.stderr, p.stderr
    # the old meaning asked for explicitly: no note
    assert load_config(_pump_file(tmp_path, tolerance=5.0e-5, error_measure="log_density")).notes == ()


def test_every_numerics_number_far_from_its_default_is_named():
    """Behaviour: for every numeric key of ``numerics`` a value 100x (or more) away from its default, either
    way, is named (key, value, default, range); 10x away, the default itself and 0 ("off") are not."""
    import dataclasses
    from gerotor_twin.config import Numerics
    checked = 0
    for f in dataclasses.fields(Numerics):
        d = f.default
        if isinstance(d, bool) or not isinstance(d, (int, float)) or d == 0:
            continue
        for value, far in ((d * 100, True), (d / 100, True), (d * 10, False), (d / 10, False), (d, False), (0, False)):
            r = raw()
            r["numerics"][f.name] = int(value) if isinstance(d, int) else value
            try:
                cfg = parse_config(r)
            except InputError:
                continue                               # outside the hard limits: an error anyway
            notes = [n for n in cfg.notes if n.startswith(f"numerics.{f.name} = ")]
            assert len(notes) == far, (f.name, value, cfg.notes)
            checked += far
    assert checked >= 5


def test_removed_key_is_a_notice_not_an_error(monkeypatch):
    """Behaviour: a key listed as removed in config_notes.KEY_NOTES loads with a one-line notice that it is
    ignored (and why); unlisted, the same key is an unknown-key error."""
    from gerotor_twin import config_notes
    r = raw()
    r["numerics"]["substep_factor"] = 2.0
    with pytest.raises(InputError, match="numerics.substep_factor.*unknown key"):
        parse_config(r)
    monkeypatch.setitem(config_notes.KEY_NOTES, "numerics.substep_factor",
                        config_notes.KeyNote("removed", "the sub-steps follow numerics.tolerance alone"))
    cfg = parse_config(r)
    assert cfg.notes == ("numerics.substep_factor is no longer used and is ignored (= 2.0): the sub-steps "
                         "follow numerics.tolerance alone",)
    assert "substep_factor" in r["numerics"]                # the caller's mapping is left as it was


@pytest.mark.parametrize("key,value", [("rate_fraction", 0.3), ("top_tolerance", 1.0)])
def test_a_pump_file_with_a_removed_step_control_key_still_loads(key, value):
    """Behaviour: a pump file written when ``numerics.rate_fraction`` / ``top_tolerance`` existed loads with
    the defaults and one notice naming the key and what covers it now."""
    r = raw()
    r["numerics"][key] = value
    cfg = parse_config(r)
    assert cfg.numerics == parse_config(raw()).numerics
    assert len(cfg.notes) == 1 and cfg.notes[0].startswith(f"numerics.{key} is no longer used and is ignored")
    assert "closing_tolerance" in cfg.notes[0]


def test_shipped_pump_files_have_no_notes():
    """Behaviour: the packaged pump and the family load without a note (the range rule fits what is shipped)."""
    files = [default_config_path(), *sorted((ROOT / "config" / "pumps").glob("*.yaml")),
             *sorted((ROOT / "bags").glob("*.yaml"))]
    for f in files:
        assert load_config(f, warn=None).notes == (), f
