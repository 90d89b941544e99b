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
