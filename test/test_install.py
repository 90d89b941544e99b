"""The package as a user installs it: a clean install log, and complete once installed (behaviour).

A copy of the source tree (without venv, caches or build output) is built with pip as
``make setup`` builds it (build isolation: the newest setuptools the index offers).  The
install log must hold nothing of the project's making (setup metadata setuptools does not
know, the editable-install notice); the lines this machine's pip configuration prints about
its own ignored index locations are not the project's and are left out.  The wheel, installed
into a venv and into a colcon-like prefix (``lib/pythonX.Y/site-packages`` + ``share/``, found
through ``AMENT_PREFIX_PATH``), must run a family command from outside the source tree: the
pumps of ``config/pumps/`` must be found in the installed ``share/gerotor_twin/``.

Every pip call installs into a fresh directory of the test, never into the running
environment (``--python`` of an empty venv; ``pip install --prefix`` run in the running
environment would uninstall its own copy of the package).
"""
from __future__ import annotations

import os
import shutil
import site
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow            # pip builds with build isolation: ≈ 10 s for the module

ROOT = Path(__file__).resolve().parent.parent
PUMPS = sorted(p.stem for p in (ROOT / "config" / "pumps").glob("*.yaml"))
_NOT_OURS = "is ignored: it is neither a file nor a directory"      # this machine's pip.conf, not the project
_JUNK = shutil.ignore_patterns(".venv", ".git", "__pycache__", "build", "out", "*.egg-info", ".pytest_cache")


def _pip(*args: str) -> str:
    """Run ``pip`` of the running interpreter quietly; return the lines it printed that are the project's."""
    r = subprocess.run([sys.executable, "-m", "pip", "--disable-pip-version-check", *args],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    return "\n".join(ln for ln in (r.stdout + r.stderr).splitlines() if ln.strip() and _NOT_OURS not in ln)


def _empty_venv(path: Path) -> Path:
    """A venv without pip at ``path``; its interpreter."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(path)], check=True, timeout=120)
    return path / "bin" / "python"


def _env(**extra: str) -> dict:
    """The environment without this checkout on the path and without an ament prefix, plus ``extra``."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "AMENT_PREFIX_PATH")}
    return {**env, **extra}


@pytest.fixture(scope="module")
def source(tmp_path_factory) -> Path:
    """A copy of the source tree as a fresh clone has it."""
    dst = tmp_path_factory.mktemp("clone") / "gerotor_twin_src"
    shutil.copytree(ROOT, dst, ignore=_JUNK, symlinks=True)
    return dst


@pytest.fixture(scope="module")
def wheel(source, tmp_path_factory) -> tuple[Path, str]:
    """The wheel built from :func:`source` and what pip printed of the project's while building it."""
    dist = tmp_path_factory.mktemp("dist")
    log = _pip("wheel", "--quiet", "--no-deps", "-w", str(dist), str(source))
    (whl,) = dist.glob("gerotor_twin-*.whl")
    return whl, log


def test_wheel_build_log_is_clean(wheel):
    """Behaviour: building the wheel prints nothing (no ``Unknown distribution option`` from setup metadata
    setuptools no longer knows, such as ``tests_require``)."""
    assert wheel[1] == ""


def test_editable_install_log_is_clean(source, tmp_path):
    """Behaviour: ``pip install --quiet --no-deps -e .`` (what ``make setup`` runs) prints nothing (no
    setuptools editable-install notice), and the venv then imports the package from the source tree."""
    python = _empty_venv(tmp_path / "venv")
    assert _pip("--python", str(python), "install", "--quiet", "--no-deps", "-e", str(source)) == ""
    r = subprocess.run([str(python), "-c", "import gerotor_twin; print(gerotor_twin.__file__)"],
                       capture_output=True, text=True, cwd=tmp_path, env=_env(), timeout=60)
    assert r.returncode == 0, r.stderr
    assert Path(r.stdout.strip()) == source / "gerotor_twin" / "__init__.py"


def _venv_install(whl: Path, tmp: Path) -> tuple[Path, dict, Path]:
    """The wheel in a venv whose other packages are the running environment's (through a ``.pth``);
    the interpreter, its environment and the prefix the data files belong in."""
    python = _empty_venv(tmp / "venv")
    _pip("--python", str(python), "install", "--quiet", "--no-deps", str(whl))
    purelib = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                             capture_output=True, text=True, check=True).stdout.strip()
    Path(purelib, "running_env.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    return python, _env(), tmp / "venv"


def _prefix_install(whl: Path, tmp: Path) -> tuple[Path, dict, Path]:
    """The wheel in a prefix laid out as a colcon install space, used as its ``setup.bash`` would (as
    :func:`_venv_install`)."""
    installer = _empty_venv(tmp / "installer")
    prefix = tmp / "install"
    _pip("--python", str(installer), "install", "--quiet", "--no-deps", "--prefix", str(prefix), str(whl))
    purelib = sysconfig.get_path("purelib", vars={"base": str(prefix), "platbase": str(prefix)})
    return Path(sys.executable), _env(PYTHONPATH=purelib, AMENT_PREFIX_PATH=str(prefix)), prefix


@pytest.mark.parametrize("install", [_venv_install, _prefix_install], ids=["venv", "colcon-prefix"])
def test_installed_wheel_finds_the_pump_family(wheel, tmp_path, install):
    """Behaviour: from an installed wheel, outside the source tree, ``bench accuracy --family`` finds the
    pumps of ``config/pumps/`` (an unknown ``--pumps`` name is refused with the list of the family's pumps,
    before any model runs) in the installed ``share/gerotor_twin/``."""
    python, env, prefix = install(wheel[0], tmp_path)
    work = tmp_path / "elsewhere"
    work.mkdir()
    r = subprocess.run([str(python), "-m", "gerotor_twin", "bench", "accuracy", "--family", "--pumps",
                        "no_such_pump"], capture_output=True, text=True, cwd=work, env=env, timeout=300)
    assert r.returncode == 2, r.stdout + r.stderr
    shown = r.stderr.split("allowed:", 1)[-1].split("...", 1)[0].strip()     # the one-line error is clipped
    assert "--pumps" in r.stderr and "05_compressor_lube" in shown and ", ".join(PUMPS).startswith(shown), r.stderr
    where = subprocess.run([str(python), "-c", "import gerotor_twin.resources as r; print(r.__file__); "
                            "print(r.resource_path('config', 'pumps'))"],
                           capture_output=True, text=True, cwd=work, env=env, timeout=120)
    assert where.returncode == 0, where.stderr
    module, pumps_dir = (Path(p) for p in where.stdout.split())
    assert tmp_path in module.parents and ROOT not in module.parents      # the installed copy ran
    assert pumps_dir == prefix / "share" / "gerotor_twin" / "config" / "pumps"


def test_wheel_holds_every_data_file(wheel):
    """Behaviour: the wheel installs under ``share/gerotor_twin/`` every file the commands read beside the code
    (the pumps, node parameters, bench profiles, launch file, layouts, bundled recordings), at its path in the
    source tree."""
    data = "gerotor_twin-0.1.0.data/data/share/gerotor_twin/"
    with zipfile.ZipFile(wheel[0]) as z:
        names = z.namelist()
    shared = {n[len(data):] for n in names if n.startswith(data)}
    wanted = {p.relative_to(ROOT).as_posix() for pattern in ("config/**/*.yaml", "launch/*.launch.py", "layouts/*",
                                                             "bags/*.mcap", "package.xml") for p in ROOT.glob(pattern)}
    assert wanted <= shared, sorted(wanted - shared)
    assert "gerotor_twin/report/report.js" in names
