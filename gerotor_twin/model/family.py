"""The pump family of ``config/pumps/`` and the operating grid each of its pumps is checked on.

``gerotor-twin bench accuracy --family`` and ``bench realtime --family`` run every pump of the
family with the default numerics (no per-pump settings) at the corners and the middle of its own
operating range; docs/pumps.md describes the pumps, docs/numerics.md the figures.

The grid of a pump (:func:`family_grid`) follows its ``range``: speeds {n_lo, (n_lo + n_hi)/2, n_hi}
and delivery pressures {p_lo, p_hi} [bar gauge], with n_hi = ``range.max_speed_rpm``, n_lo =
``range.min_speed_rpm`` (10 % of n_hi where the config has none), p_hi = ``range.max_delivery_bar``
and p_lo = ``range.min_delivery_bar`` (2 bar, or 10 % of p_hi if that is lower, where it has none).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..config import load_config
from ..errors import InputError
from ..resources import resource_path

__all__ = ["FamilyPump", "family_dir", "family_pumps", "family_grid", "speed_extremes", "pressure_extremes"]


@dataclass(frozen=True)
class FamilyPump:
    """One pump of the family: its name (the file's stem), file and loaded config."""
    name: str
    path: Path
    config: object


def family_dir() -> Path:
    """``config/pumps/`` of the package's data (:func:`gerotor_twin.resources.share_dir`)."""
    return resource_path("config", "pumps")


def family_pumps(directory: str | Path | None = None, names: str | None = None) -> list[FamilyPump]:
    """Every pump YAML of ``directory`` (default :func:`family_dir`), sorted by name.

    ``names``: comma-separated stems to keep (e.g. ``"lube7_new,engine10"``); an unknown name is an error.
    """
    d = Path(directory) if directory else family_dir()
    files = sorted(d.glob("*.yaml"))
    if not files:
        raise InputError("--family", str(d), "a directory with pump YAML files")
    pumps = {f.stem: f for f in files}
    keep = [n for n in (names or "").split(",") if n]
    for n in keep:
        if n not in pumps:
            raise InputError("--pumps", n, ", ".join(pumps))
    return [FamilyPump(stem, f, load_config(f)) for stem, f in pumps.items() if not keep or stem in keep]


def speed_extremes(cfg) -> tuple[float, float]:
    """(lowest, highest) operating speed of the pump [rpm] (see the module docstring)."""
    hi = float(cfg.range.max_speed_rpm)
    lo = getattr(cfg.range, "min_speed_rpm", None)
    return (float(lo) if lo else round(0.1 * hi), hi)


def pressure_extremes(cfg) -> tuple[float, float]:
    """(lowest, highest) delivery pressure of the pump [bar gauge] (see the module docstring)."""
    hi = float(cfg.range.max_delivery_bar)
    lo = getattr(cfg.range, "min_delivery_bar", None)
    return (float(lo) if lo else min(2.0, 0.1 * hi), hi)


def family_grid(cfg) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(speeds [rpm], delivery pressures [bar gauge]) of the accuracy grid of one pump."""
    n_lo, n_hi = speed_extremes(cfg)
    return (n_lo, round(0.5 * (n_lo + n_hi)), n_hi), pressure_extremes(cfg)
