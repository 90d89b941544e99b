"""The numba cache: which sources invalidate it, where its files are, consistent argument types (behaviour).

numba checks a cached function against its own file only; ``gerotor_twin._jit`` hashes the
sources the compiled code can reach (the import closure of the modules that use ``_jit``) and
deletes the cache when they change.  These tests edit a temporary copy of the package, never the
worktree, and point numba's cache at a temporary directory.
"""
import copy
import shutil
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

from gerotor_twin import _jit

ROOT = Path(__file__).resolve().parent.parent
PKG = ROOT / "gerotor_twin"


@pytest.fixture
def package(tmp_path):
    """A copy of the package's sources (no caches) to edit."""
    dst = tmp_path / "src" / "gerotor_twin"
    shutil.copytree(PKG, dst, ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    return dst


def _touch(f: Path, text="\n# an edit\n"):
    f.write_text(f.read_text() + text)


def test_the_kernel_sources_are_the_modules_the_compiled_code_reaches():
    """The modules with compiled functions and what they import are in; the report, node and CLI are out."""
    rel = {f.relative_to(PKG).as_posix() for f in _jit.kernel_sources()}
    for f in ("_jit.py", "model/kernel.py", "model/flows.py", "model/contact.py", "model/params.py",
              "hydraulics/state_equation.py", "hydraulics/mixture.py", "bearing/mobility.py", "geometry/tables.py"):
        assert f in rel, f
    for f in ("report/html.py", "ros/node.py", "cli.py", "twin/core.py", "precompile.py", "offline/sweep.py"):
        assert f not in rel, f


def test_the_digest_ignores_a_module_the_kernel_does_not_use(package):
    d0 = _jit.source_digest(package)
    _touch(package / "report" / "html.py")
    _touch(package / "ros" / "node.py")
    (package / "report" / "new_panel.py").write_text("from ..model import kernel\n")   # imports the kernel: still out
    assert _jit.source_digest(package) == d0


@pytest.mark.parametrize("edited", ["model/flows.py", "model/kernel.py", "hydraulics/orifice.py", "_jit.py",
                                    "model/params.py"])
def test_the_digest_follows_a_kernel_source(package, edited):
    d0 = _jit.source_digest(package)
    _touch(package / edited)
    assert _jit.source_digest(package) != d0


def test_a_module_a_kernel_source_starts_to_import_becomes_a_kernel_source(package):
    """The closure is read from the imports: a new helper of flows.py counts, and so does its edit."""
    helper = package / "model" / "helper.py"
    helper.write_text("X = 1.0\n")
    d0 = _jit.source_digest(package)
    assert helper not in _jit.kernel_sources(package)
    _touch(package / "model" / "flows.py", "\nfrom .helper import X  # noqa\n")
    assert helper in _jit.kernel_sources(package)
    d1 = _jit.source_digest(package)
    _touch(helper, "Y = 2.0\n")
    assert _jit.source_digest(package) not in (d0, d1)


@pytest.fixture
def cache(package, tmp_path, monkeypatch):
    """numba's cache at tmp_path/numba (as with NUMBA_CACHE_DIR) for the package copy; returns a
    function that writes a fake cache file into numba's cache directory of a source directory."""
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "numba"))
    monkeypatch.setattr(_jit, "_PACKAGE", package)

    def put(subdir: str, name: str) -> Path:
        d = _jit._numba_cache_dir(next((package / subdir).glob("*.py")))
        d.mkdir(parents=True, exist_ok=True)
        f = d / name
        f.write_text("x")
        return f
    return put


def test_a_kernel_edit_deletes_the_cache_in_numbas_layout_and_nothing_else(cache, package, tmp_path):
    """With NUMBA_CACHE_DIR numba keeps one directory per source directory (``model_<sha1>``); the
    package's files there go, another project's stay."""
    assert _jit.invalidate_stale_cache()                  # no stamp yet: reset once
    kernel = cache("model", "kernel.integrate-441.py311.nbi")
    data = cache("model", "kernel.integrate-441.py311.1.nbc")
    hyd = cache("hydraulics", "orifice.orifice_flow-60.py311.nbi")
    other = tmp_path / "numba" / "elsewhere_0123" / "f-1.py311.nbi"
    other.parent.mkdir(parents=True)
    other.write_text("x")
    assert not _jit.invalidate_stale_cache()              # nothing changed: kept
    assert kernel.exists() and data.exists() and hyd.exists()
    _touch(package / "model" / "flows.py")
    assert _jit.invalidate_stale_cache()
    assert not (kernel.exists() or data.exists() or hyd.exists())
    assert other.exists()
    assert not _jit.invalidate_stale_cache()              # once


@pytest.mark.parametrize("edited", ["report/html.py", "ros/node.py", "cli.py"])
def test_an_edit_outside_the_kernel_keeps_the_cache(cache, package, edited):
    _jit.invalidate_stale_cache()
    kernel = cache("model", "kernel.integrate-441.py311.nbi")
    _touch(package / edited)
    assert not _jit.invalidate_stale_cache()
    assert kernel.exists()


def test_a_stamp_of_an_older_scheme_resets_the_cache(cache, package):
    _jit.invalidate_stale_cache()
    kernel = cache("model", "kernel.integrate-441.py311.nbi")
    (_jit._numba_cache_dir(package / "_jit.py") / _jit._STAMP).write_text("an older hash")
    assert _jit.invalidate_stale_cache()
    assert not kernel.exists()


# ------------------------------------------------------------------ one specialisation for every pump
def _raw(cfg_path):
    import yaml
    with open(cfg_path) as f:
        return yaml.safe_load(f)


def test_every_pump_passes_the_kernel_the_same_types(cfg):
    """Integer-valued YAML entries (``1`` for ``1.0``), another chamber count, table size, fluid model or
    boundary give the kernel the numba types of the default pump: the cache built at install serves them
    (a different type would compile the stepper again)."""
    from gerotor_twin.config import default_config_path, parse_config
    from gerotor_twin.model.params import operating
    from gerotor_twin.model.pump import PumpModel

    def types(raw, bearing="mobility"):
        m = PumpModel(parse_config(raw), bearing)
        op = operating(m.kernel, 100, 101325, 2_000_000)          # ints, as a caller might pass them
        return numba.typeof(m.kernel), numba.typeof(op), numba.typeof(m._ws)

    raw0 = _raw(default_config_path())
    base = types(raw0)
    ints = copy.deepcopy(raw0)
    ints["numerics"].update(closing_tolerance=1, table_points=1024)
    ints["orifice"].update(cd_max=1, lambda_crit=1000)
    ints["fluid"]["atmospheric_pa"] = 101325
    ints["mixture"]["polytropic_index"] = 1
    other = copy.deepcopy(raw0)
    other["gears"].update(chambers=8, width_m=0.02)
    other["boundary"]["mode"] = "restriction"
    other["fluid_model"] = "paper"
    for raw in (ints, other):
        assert types(raw) == base
    assert types(raw0, "fixed") == base


def test_typed_casts_scalars_to_the_declared_types_and_keeps_values_and_arrays():
    from gerotor_twin.hydraulics.state_equation import StateEquation
    from gerotor_twin.model.params import KernelTables
    rows = np.zeros((4, 3))
    t = _jit.typed(KernelTables(rows=rows, period=2, shift=np.float64(0.5), scale=3, turn_inner=np.bool_(True)))
    assert t.rows is rows
    assert [type(v) for v in t[1:]] == [float, float, float, bool, bool]
    assert t[1:] == (2.0, 0.5, 3.0, True, True)
    eos = _jit.typed(StateEquation(1, 2, 3, 4, 5, 6, 7, 8, 9, rows, 10, kind=1.0))
    assert type(eos.kind) is int and type(eos.beta_liquid) is float and type(eos.inv_ds) is float
    assert eos.band_c is rows


@pytest.mark.slow
def test_precompile_leaves_nothing_to_compile():
    """Behaviour: after ``python -m gerotor_twin.precompile`` (what ``make setup`` runs; here the fixed model, the
    compiled stepper the mobility model shares) a new process that runs it again compiles nothing
    (``--expect-cached`` exits 0 and says so): every specialisation a first model start hits is cached on disk.
    On the test machine's own cache, which ``make setup`` has built: a cold cache would cost a full compile
    (40–80 s) for what the first run here does anyway when the cache is stale.  That a compilation is seen at
    all (the exit status 1 of a cold cache) is the compile listener's, tested below on a small kernel in a cold
    cache."""
    import os
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("NUMBA_DISABLE_JIT", None)
    run = [sys.executable, "-m", "gerotor_twin.precompile", "--models", "fixed"]
    first = subprocess.run(run, env=env, capture_output=True, text=True, timeout=900)
    assert first.returncode == 0, first.stdout + first.stderr[-2000:]
    second = subprocess.run(run + ["--expect-cached"], env=env, capture_output=True, text=True, timeout=900)
    assert second.returncode == 0 and "nothing compiled" in second.stdout, second.stdout + second.stderr[-2000:]


_ANNOUNCE = r"""
import sys
from gerotor_twin.hydraulics.oil import walther_kinematic_viscosity
from gerotor_twin.precompile import announce_compilation
with announce_compilation("compiling now") as a:
    walther_kinematic_viscosity(313.15, 9.0, 3.5)
print(a.announced)
"""


def test_first_use_compilation_is_announced_once_and_a_cached_start_is_silent(tmp_path):
    """Behaviour: the progress line of a gear model compiled on first use (``announce_compilation``): one line
    when numba compiles this package's functions (here a Walther kernel and the two it calls, in a temporary
    ``NUMBA_CACHE_DIR``), none when the next process loads them from the cache."""
    import os
    env = dict(os.environ, PYTHONPATH=str(ROOT), NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    env.pop("NUMBA_DISABLE_JIT", None)
    runs = [subprocess.run([sys.executable, "-c", _ANNOUNCE], env=env, capture_output=True, text=True, timeout=300)
            for _ in range(2)]
    assert all(r.returncode == 0 for r in runs), runs[0].stderr[-2000:] + runs[1].stderr[-2000:]
    assert runs[0].stdout.split() == ["True"] and runs[0].stderr.count("compiling now") == 1, runs[0].stderr
    assert runs[1].stdout.split() == ["False"] and "compiling now" not in runs[1].stderr, runs[1].stderr


_EXPECT_CACHED = r"""
import sys
import gerotor_twin.precompile as P
from gerotor_twin.hydraulics.oil import walther_kinematic_viscosity
P.warm_up = lambda models: walther_kinematic_viscosity(313.15, 9.0, 3.5)     # a small kernel for the model's
sys.exit(P.main(["--models", "fixed", "--expect-cached"]))
"""


def test_precompile_expect_cached_exits_1_when_it_had_to_compile(tmp_path):
    """Behaviour: ``precompile --expect-cached`` exits 1 and names the count when anything was compiled (a cold
    ``NUMBA_CACHE_DIR``), 0 with "nothing compiled" when the next process finds it cached; ``warm_up`` replaced
    by a small kernel so that the cold cache costs seconds."""
    import os
    env = dict(os.environ, PYTHONPATH=str(ROOT), NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    env.pop("NUMBA_DISABLE_JIT", None)
    runs = [subprocess.run([sys.executable, "-c", _EXPECT_CACHED], env=env, capture_output=True, text=True,
                           timeout=300) for _ in range(2)]
    assert runs[0].returncode == 1 and "compiled" in runs[0].stdout and "nothing" not in runs[0].stdout, runs[0]
    assert runs[1].returncode == 0 and "nothing compiled" in runs[1].stdout, runs[1]


# ------------------------------------------------------------------ one compile of each inlined helper
def _njit_calls(path, names):
    """(function, call) for every call of ``names`` inside a compiled function of the file at ``path``."""
    import ast
    tree = ast.parse(path.read_text())
    for fn in ast.walk(tree):
        if isinstance(fn, ast.FunctionDef) and any("njit" in ast.unparse(d) for d in fn.decorator_list):
            for node in ast.walk(fn):
                if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in names:
                    yield fn.name, node


def test_the_stepper_passes_its_flags_typed_so_each_helper_compiles_once():
    """``rhs(..., want_jac)`` and ``contact(..., reuse)`` are called from compiled code with ``bool(...)``: a
    literal ``True``/``False`` (or the flag left out) is a numba type of its own, so each value would compile
    the helper again (``rhs``: ≈ 6 s of the install's compile, docs/performance.md, "First compile")."""
    calls = [(f.name, fn, ast_call) for f in (PKG / "model" / "kernel.py", PKG / "model" / "coupled_reference.py")
             for fn, ast_call in _njit_calls(f, {"rhs", "contact"})]
    assert len(calls) >= 6                       # rhs twice and contact three times in the stepper, at least
    for file, fn, call in calls:
        flag = call.args[8] if len(call.args) > 8 else None
        ok = (flag is not None and type(flag).__name__ == "Call" and getattr(flag.func, "id", "") == "bool")
        assert ok, f"{file}:{call.lineno} ({fn}): {call.func.id}(...) needs its flag as bool(...)"
