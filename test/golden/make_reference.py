"""Regenerate the golden reference revolutions of test_numerics_golden.py (tight numerics).

    .venv/bin/python test/golden/make_reference.py

Each file is one revolution at periodic steady state of the default pump (config/pump.yaml),
mobility model, computed with the reference numerics of gerotor_twin.model.accuracy
(ROS2 tolerance 1e-8 on ln(ρ/ρ₀), output step 16× finer than the default's). Regenerate only
when the physics or the pump config changes on purpose, and say so in the commit.
"""
import datetime
import subprocess
from pathlib import Path

from gerotor_twin.config import load_config
from gerotor_twin.model.accuracy import REFERENCE_REFINEMENT, REFERENCE_TOLERANCE, reference_revolution

POINTS = ((1000.0, 27.5), (2000.0, 27.5), (3000.0, 27.5))     # rpm, bar gauge
#: Below the rated pressure: where the defaults missed the budget before ∂f/∂t and the closing-port
#: measures (docs/numerics.md) and must now meet it.
LOW_POINTS = ((3000.0, 5.0), (3000.0, 15.0))
HERE = Path(__file__).resolve().parent


def path(rpm: float, bar: float) -> Path:
    return HERE / f"reference_{rpm:.0f}rpm_{bar:g}bar.npz"


def main() -> None:
    cfg = load_config()
    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                         cwd=HERE).stdout.strip()
    for rpm, bar in POINTS + LOW_POINTS:
        ref = reference_revolution(cfg, rpm, bar, "mobility")
        ref.save(path(rpm, bar), rpm=rpm, bar=bar, model="mobility", tolerance=REFERENCE_TOLERANCE,
                 refinement=REFERENCE_REFINEMENT, git=rev, date=datetime.date.today().isoformat())
        print(f"{path(rpm, bar).name}: eta {ref.volumetric_efficiency:.6f}, {ref.theta.size} samples")


if __name__ == "__main__":
    main()
