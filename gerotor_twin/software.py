"""Which gerotor_twin made a file: package version and git revision (for logs and reports)."""
from __future__ import annotations

import functools
import subprocess
from pathlib import Path

from gerotor_twin import __version__

__all__ = ["software_identity", "SOFTWARE_METADATA"]

#: Name of the MCAP metadata record that carries :func:`software_identity`.
SOFTWARE_METADATA = "gerotor_twin.software"


def _git(root: Path, *args: str) -> str | None:
    try:
        r = subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return r.stdout.strip() if r.returncode == 0 else None


@functools.lru_cache(maxsize=1)
def software_identity() -> dict[str, str]:
    """``version``, ``git_revision`` (commit hash, ``+dirty`` when tracked files differ from it, or
    ``unknown`` when the package is not in a git checkout) and ``git_describe``."""
    root = Path(__file__).resolve().parent.parent
    rev = _git(root, "rev-parse", "HEAD") if (root / ".git").exists() else None
    if rev is None:
        return {"version": __version__, "git_revision": "unknown (not a git checkout)", "git_describe": ""}
    dirty = _git(root, "status", "--porcelain", "--untracked-files=no")
    return {"version": __version__, "git_revision": rev + ("+dirty" if dirty else ""),
            "git_describe": _git(root, "describe", "--always", "--dirty") or ""}
