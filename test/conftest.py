"""Shared fixtures: the default pump, its tables built once per session."""
import os
from pathlib import Path

import pytest

os.environ.setdefault("AMENT_PREFIX_PATH", str(Path(__file__).resolve().parent.parent / ".venv"))


@pytest.fixture(scope="session")
def cfg():
    from gerotor_twin.config import load_config
    return load_config()


@pytest.fixture(scope="session")
def fixed_model(cfg):
    from gerotor_twin.model.pump import PumpModel
    return PumpModel(cfg, "fixed")


@pytest.fixture
def small_filesystem(tmp_path):
    """``mount(size)``: a tmpfs of ``size`` (e.g. ``"96k"``) mounted under ``tmp_path`` for a full-disk test,
    unmounted afterwards; the test is skipped where tmpfs cannot be mounted (not root)."""
    import subprocess
    mounts = []

    def mount(size: str) -> Path:
        mnt = tmp_path / f"disk{len(mounts)}"
        mnt.mkdir()
        r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(mnt)], capture_output=True,
                           text=True)
        if r.returncode != 0:
            pytest.skip(f"cannot mount a tmpfs here: {r.stderr.strip() or r.returncode}")
        mounts.append(mnt)
        return mnt

    yield mount
    for mnt in mounts:
        subprocess.run(["umount", "-l", str(mnt)], check=False)
