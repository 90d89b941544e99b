"""Where the package's files beside the code are: config, launch, layouts, bags.

``setup.py`` installs them under ``share/gerotor_twin/`` of the install prefix
(``config/pump.yaml``, ``config/twin.yaml``, ``config/pumps/``,
``config/profiles/``, ``config/bench_pumps/``, ``config/maps/``, ``launch/``, ``layouts/``, ``bags/``); a source checkout
has them at the same relative paths beside ``gerotor_twin/``.
:func:`share_dir` finds the one directory that holds them, looking in order at

1. the source tree (``package.xml`` beside the package directory): a checkout
   run in place or an editable install, so that an edit of a config file is
   seen at once (an editable install also copies the files to its prefix's
   ``share/``, where they go stale);
2. the ament index (``ament_index_python``, ``AMENT_PREFIX_PATH``): a colcon
   install space or any other sourced prefix;
3. ``share/gerotor_twin`` of the prefix the package is installed in (a wheel
   in a venv, ``pip install --prefix`` / ``--user``, an unsourced colcon
   install space), of a ``pip install --target`` directory, and of
   ``sys.prefix``.

Each candidate counts only if it holds ``package.xml`` (installed with the
other files), so a half-matching directory is never taken.
"""
from __future__ import annotations

import functools
import sys
from pathlib import Path

__all__ = ["PACKAGE", "share_dir", "resource_path", "share_candidates"]

PACKAGE = "gerotor_twin"
_MARKER = "package.xml"
_CODE = Path(__file__).resolve().parent          # the package directory (gerotor_twin/)


def _ament_share() -> Path | None:
    """The package's share directory in the ament index, or None (no ament_index_python, no
    ``AMENT_PREFIX_PATH``, or the package not registered in it)."""
    try:
        from ament_index_python.packages import get_package_share_directory
        return Path(get_package_share_directory(PACKAGE))
    except (ImportError, LookupError, OSError, ValueError):   # PackageNotFoundError is a KeyError
        return None


def _install_prefixes(code: Path = _CODE) -> list[Path]:
    """Prefixes the package may be installed in: that of its ``lib/pythonX.Y/site-packages``,
    the directory holding it (``pip install --target``) and ``sys.prefix``."""
    site = code.parent
    out = [site.parents[2]] if site.parent.name.startswith("python") and len(site.parents) > 2 else []
    return out + [site, Path(sys.prefix)]


def share_candidates(code: Path = _CODE) -> list[Path]:
    """The directories :func:`share_dir` looks at, in order (see the module docstring).

    Parameters
    ----------
    code : Path
        The package directory (default: this one).
    """
    ament = _ament_share()
    return ([code.parent] + ([ament] if ament else [])
            + [p / "share" / PACKAGE for p in _install_prefixes(code)])


@functools.lru_cache(maxsize=None)
def share_dir(code: Path = _CODE) -> Path:
    """The directory holding the package's files (``config/``, ``launch/``, ``layouts/``, ``bags/``).

    Parameters
    ----------
    code : Path
        The package directory (default: this one).

    Raises
    ------
    FileNotFoundError
        No candidate holds them (an install that left out its data files); the message lists
        where it looked.
    """
    candidates = share_candidates(code)
    for d in candidates:
        if (d / _MARKER).is_file():
            return d
    raise FileNotFoundError(f"{PACKAGE}: its data files (config/, bags/, ...) are not installed; looked in "
                            + ", ".join(str(d) for d in candidates))


def resource_path(*parts: str) -> Path:
    """A file or directory of the package's data, e.g. ``resource_path("config", "pumps")``.

    The path is under :func:`share_dir`; whether it exists is for the caller to check (a
    missing file gives the caller's own error naming the path).
    """
    return share_dir().joinpath(*parts)
