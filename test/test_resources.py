"""One lookup for the package's data files: the order of the places it looks in (behaviour).

Each case lays out a directory tree as an install would (source checkout, wheel in a
prefix, ``pip install --target``, colcon install space through the ament index) and checks
which ``share`` directory :func:`gerotor_twin.resources.share_dir` picks.  That a real wheel
installs the files and is found is test_install.py's.
"""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

from gerotor_twin import resources
from gerotor_twin.config import default_config_path
from gerotor_twin.model.family import family_dir

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(autouse=True)
def no_ament(monkeypatch):
    """No ament index unless a test provides one; a fresh cache around each test."""
    monkeypatch.setattr(resources, "_ament_share", lambda: None)
    resources.share_dir.cache_clear()
    yield
    resources.share_dir.cache_clear()


def _share(prefix: Path) -> Path:
    """``prefix/share/gerotor_twin`` holding the marker file, as an install leaves it."""
    d = prefix / "share" / "gerotor_twin"
    d.mkdir(parents=True)
    (d / "package.xml").write_text("<package/>")
    return d


def _code(site: Path) -> Path:
    """A package directory ``gerotor_twin/`` in ``site``."""
    code = site / "gerotor_twin"
    code.mkdir(parents=True)
    return code


def test_source_checkout_is_its_own_share():
    """Behaviour: run from this checkout, the data are the checkout's (an edit of a config is seen at once)."""
    resources.share_dir.cache_clear()
    assert resources.share_dir() == ROOT
    assert default_config_path() == ROOT / "config" / "pump.yaml"
    assert family_dir() == ROOT / "config" / "pumps"


def test_wheel_in_a_prefix(tmp_path):
    """Behaviour: a wheel in ``prefix/lib/pythonX.Y/site-packages`` finds ``prefix/share/gerotor_twin``."""
    code = _code(tmp_path / "lib" / "python3.12" / "site-packages")
    share = _share(tmp_path)
    assert resources.share_dir(code) == share


def test_pip_target_directory(tmp_path):
    """Behaviour: ``pip install --target T`` puts the data in ``T/share/gerotor_twin``; they are found."""
    code = _code(tmp_path / "target")
    share = _share(tmp_path / "target")
    assert resources.share_dir(code) == share


def test_ament_index_before_the_prefix(tmp_path, monkeypatch):
    """Behaviour: a package registered in the ament index (colcon install space) wins over the prefix guess."""
    code = _code(tmp_path / "venv" / "lib" / "python3.12" / "site-packages")
    _share(tmp_path / "venv")
    ament = _share(tmp_path / "install")
    monkeypatch.setattr(resources, "_ament_share", lambda: ament)
    assert resources.share_dir(code) == ament


def test_source_tree_before_the_ament_index(tmp_path, monkeypatch):
    """Behaviour: a source tree (``package.xml`` beside the package) wins over an installed copy, which an
    editable install would leave stale."""
    code = _code(tmp_path / "checkout")
    (tmp_path / "checkout" / "package.xml").write_text("<package/>")
    ament = _share(tmp_path / "install")
    monkeypatch.setattr(resources, "_ament_share", lambda: ament)
    assert resources.share_dir(code) == tmp_path / "checkout"


def test_a_directory_without_the_marker_is_not_taken(tmp_path):
    """Behaviour: a ``share/gerotor_twin`` without ``package.xml`` (a partial copy) is passed over."""
    site = tmp_path / "lib" / "python3.12" / "site-packages"
    code = _code(site)
    (tmp_path / "share" / "gerotor_twin" / "config").mkdir(parents=True)      # looked at first, incomplete
    share = _share(site)
    assert resources.share_dir(code) == share


def test_nothing_installed_names_where_it_looked(tmp_path):
    """Behaviour: no data anywhere is one error listing the places looked in."""
    code = _code(tmp_path / "lib" / "python3.12" / "site-packages")
    if (Path(sys.prefix) / "share" / "gerotor_twin" / "package.xml").is_file():
        pytest.skip("this environment has the package's data installed under sys.prefix")
    with pytest.raises(FileNotFoundError, match="not installed; looked in") as err:
        resources.share_dir(code)
    assert str(tmp_path / "share" / "gerotor_twin") in str(err.value)
