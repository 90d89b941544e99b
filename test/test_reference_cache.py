"""The on-disk cache of reference revolutions (``bench accuracy``): what its key depends on, and that a
cached revolution is the computed one (behaviour tier)."""
import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gerotor_twin
from gerotor_twin.model import reference_cache as RC
from gerotor_twin.model.accuracy import Revolution, reference_numerics

PKG = Path(gerotor_twin.__file__).resolve().parent


def _rev(scale=1.0):
    th = np.linspace(0.1, 2 * np.pi, 8)
    return Revolution(th, scale * np.outer(np.ones(8), [1e5, 2e5, 3e5]), scale * np.full(8, 1e-4), 0.95, 1e-4,
                      3.5e5 * scale)


def test_code_digest_covers_the_code_a_reference_runs():
    """Behaviour: the digest hashes the kernel, the model driver, the steady-state run, the bearing and
    the configuration, so an edit of any of them invalidates every cached reference by itself."""
    from gerotor_twin import _jit
    from gerotor_twin.model import accuracy
    files = {f.relative_to(PKG).as_posix() for f in _jit.import_closure([Path(accuracy.__file__).resolve()])}
    for must in ("model/kernel.py", "model/pump.py", "model/steady.py", "model/accuracy.py", "config.py",
                 "bearing/mobility.py", "geometry/tables.py"):
        assert must in files, must
    assert "report/build.py" not in files and "ros/node.py" not in files


def test_key_depends_on_the_pump_the_point_the_model_and_the_code(cfg, monkeypatch):
    """Behaviour: each input of a reference changes the key; the numerics under test do not enter
    (the reference numerics replace them)."""
    ref = reference_numerics(cfg, 3000.0)
    k = RC.reference_key(ref, 3000.0, 27.5, "mobility")
    assert RC.reference_key(ref, 3000.0, 27.5, "mobility") == k
    assert RC.reference_key(ref, 2999.0, 27.5, "mobility") != k
    assert RC.reference_key(ref, 3000.0, 27.0, "mobility") != k
    assert RC.reference_key(ref, 3000.0, 27.5, "fixed") != k
    tip = dataclasses.replace(cfg, clearances=dataclasses.replace(cfg.clearances,
                                                                 tooth_tip_m=1.01 * cfg.clearances.tooth_tip_m))
    assert RC.reference_key(reference_numerics(tip, 3000.0), 3000.0, 27.5, "mobility") != k
    looser = dataclasses.replace(cfg, numerics=dataclasses.replace(cfg.numerics, tolerance=0.5 * cfg.numerics.tolerance))
    assert RC.reference_key(reference_numerics(looser, 3000.0), 3000.0, 27.5, "mobility") == k
    monkeypatch.setattr(RC, "code_digest", lambda: "another kernel")
    assert RC.reference_key(ref, 3000.0, 27.5, "mobility") != k


def test_cached_revolution_is_computed_once_and_read_back_whole(tmp_path):
    """Behaviour: the first call computes and stores, the second reads the same arrays back without
    computing; a torn file is recomputed and replaced; no directory: always computed."""
    calls = []

    def compute():
        calls.append(1)
        return _rev()

    a, hit_a = RC.cached_revolution(tmp_path, "k", compute, Revolution.load)
    b, hit_b = RC.cached_revolution(tmp_path, "k", compute, Revolution.load)
    assert (hit_a, hit_b, len(calls)) == (False, True, 1)
    for f in ("theta", "chamber_pressures", "delivery_flow"):
        assert np.array_equal(getattr(a, f), getattr(b, f))
    assert (b.volumetric_efficiency, b.peak_pressure) == (a.volumetric_efficiency, a.peak_pressure)
    (tmp_path / "k.npz").write_bytes(b"torn")
    _, hit_c = RC.cached_revolution(tmp_path, "k", compute, Revolution.load)
    assert not hit_c and len(calls) == 2 and list(tmp_path.iterdir()) == [tmp_path / "k.npz"]
    RC.cached_revolution(None, "k", compute, Revolution.load)
    assert len(calls) == 3


def test_default_directory_follows_the_environment(monkeypatch, tmp_path):
    """Behaviour: $GEROTOR_TWIN_CACHE, else $XDG_CACHE_HOME/gerotor_twin."""
    monkeypatch.setenv("GEROTOR_TWIN_CACHE", str(tmp_path / "a"))
    assert RC.default_directory() == tmp_path / "a" / "references"
    monkeypatch.delenv("GEROTOR_TWIN_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert RC.default_directory() == tmp_path / "x" / "gerotor_twin" / "references"


@pytest.mark.parametrize("text, word", [("nosuchkey=1", "nosuchkey"), ("tolerance=abc", "tolerance"),
                                        ("tolerance=-1", "tolerance")])
def test_bench_numerics_override_refuses_a_bad_field_naming_it(text, word, capsys):
    """Behaviour: ``bench --numerics`` with an unknown key, a value of the wrong type or out of range is
    one error line naming it (exit 2), before anything runs (the command's ``main``; the process: next test)."""
    from gerotor_twin.cli import main
    assert main(["bench", "accuracy", "--numerics", text]) == 2
    err = capsys.readouterr().err
    assert word in err and "Traceback" not in err and len(err.strip().splitlines()) == 1, err


def test_bench_numerics_override_refused_from_the_shell():
    """Behaviour: the same in a fresh ``python -m gerotor_twin.cli`` process: exit status 2, the field named."""
    r = subprocess.run([sys.executable, "-m", "gerotor_twin.cli", "bench", "accuracy", "--numerics", "nosuchkey=1"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert "nosuchkey" in r.stderr and "Traceback" not in r.stderr


def test_a_reference_does_not_depend_on_the_pressure_measures_settings(cfg):
    """Behaviour: the log-density measure of the references does not read ``closing_tolerance`` or
    ``log_density_tolerance`` (a run at those numerics is the same bit for bit with other values), so an A/B of
    either over the family keeps every cached reference: the reference configuration, hence its key, is the same."""
    import math
    from gerotor_twin.model.pump import Inputs, PumpModel
    from gerotor_twin.model.steady import reference_config

    def numerics(c, **kw):
        return dataclasses.replace(c, numerics=dataclasses.replace(c.numerics, **kw))

    other = numerics(cfg, closing_tolerance=0.5, log_density_tolerance=1e-2)
    assert RC.reference_key(reference_numerics(other, 3000.0), 3000.0, 27.5, "mobility") == \
        RC.reference_key(reference_numerics(cfg, 3000.0), 3000.0, 27.5, "mobility")
    inp = Inputs(3000 * math.pi / 30, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + 27.5e5)
    runs = []
    for c in (cfg, other):
        tight = numerics(reference_config(c), closing_tolerance=c.numerics.closing_tolerance,
                         log_density_tolerance=c.numerics.log_density_tolerance, tolerance=1e-6)
        m = PumpModel(tight, "mobility")
        s, out = m.advance(m.initial_state(inp), 120 * m.step_size(inp.omega), inp)
        runs.append((s.log_density, out.chamber_peak_pressures, s.counters))
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


def test_a_coupled_reference_is_keyed_by_what_it_reads(cfg):
    """Behaviour: the coupled reference reads of the numerics only the tables' resolution and the output step (its
    sample angles), so its key ignores the twin's step control (tolerance, error measure, closing tolerance, gear
    scheme, work bound) and changes with either of those two.  That the reference forgets the twin state it starts
    from is measured, not tested (minutes per revolution): docs/numerics.md."""
    from gerotor_twin.model.accuracy import coupled_key_config

    def numerics(c, **kw):
        return dataclasses.replace(c, numerics=dataclasses.replace(c.numerics, **kw))

    def key(c):
        return RC.reference_key(coupled_key_config(c), 3000.0, 27.5, "mobility-coupled")
    k = key(cfg)
    assert key(numerics(cfg, tolerance=0.1, error_measure="log_density", closing_tolerance=0.5,
                        log_density_tolerance=1e-2, gear_coupling="stages", max_substep_attempts=50)) == k
    assert key(numerics(cfg, max_step_deg=0.75)) != k
    assert key(numerics(cfg, max_step_s=1e-4)) != k
    assert key(numerics(cfg, table_points=1024)) != k
    assert key(dataclasses.replace(cfg, clearances=dataclasses.replace(cfg.clearances, tooth_tip_m=2e-5))) != k
