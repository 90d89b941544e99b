"""The package as a user installs it: a clean install log (behaviour).

A copy of the source tree (without venv, caches or build output) is built with pip as
``make setup`` builds it (build isolation: the newest setuptools the index offers).  The
install log must hold nothing of the project's making (setup metadata setuptools does not
know, the editable-install notice); the lines this machine's pip configuration prints about
its own ignored index locations are not the project's and are left out.

Every pip call installs into a fresh directory of the test, never into the running
environment (``--python`` of an empty venv).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow            # pip builds with build isolation: ≈ 10 s for the module

ROOT = Path(__file__).resolve().parent.parent
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


def _env(**extra: str) -> dict:
    """The environment without this checkout on the path and without an ament prefix, plus ``extra``."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "AMENT_PREFIX_PATH")}
    return {**env, **extra}
