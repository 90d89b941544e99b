"""Acceptance criterion of the report: tolerance bands and a pass/fail verdict per plateau.

A plateau **passes** when every enabled check holds for the plateau means
(predicted − measured):

* ``|mean flow error| ≤ flow_abs_lpm + flow_rel · |measured mean flow|``  [L/min]
* ``|Δη_v| ≤ eta_pts``  [%-points of volumetric efficiency]

and at least ``min_fraction`` of the plateau's grid bins carry a prediction.
A plateau with too few predicted bins gets ``no data`` (neither pass nor fail).
A tolerance set to ``off`` disables its check (for the flow: ``off`` on one
part makes it 0, both ``off`` disable the flow check).  Defaults (a model tolerance, not
the flow meter's accuracy): 0.2 L/min + 1 % of the reading, 1.0 %-point,
80 % of the bins.  They are set with ``--tol-flow-lpm``, ``--tol-flow-rel``,
``--tol-eta-pts``, ``--min-predicted-fraction`` or a YAML file
(``--acceptance F.yaml``, keys of the same names without ``--`` and with ``_``,
optionally under a top-level ``acceptance:``); command-line options win.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from pathlib import Path

from gerotor_twin.errors import InputError

__all__ = ["AcceptanceCriterion", "verdict", "tally", "tally_text", "criterion_from_args", "add_arguments", "PASS",
           "FAIL", "NO_DATA"]

LPM = 6e4
PASS, FAIL, NO_DATA = "pass", "fail", "no data"


@dataclass(frozen=True)
class AcceptanceCriterion:
    """Tolerances of the per-plateau verdict (``None``: check disabled)."""
    flow_abs_lpm: float | None = 0.2     #: absolute part of the flow tolerance [L/min]
    flow_rel: float | None = 0.01        #: relative part, fraction of the measured mean flow [-]
    eta_pts: float | None = 1.0          #: volumetric-efficiency tolerance [%-points]
    min_fraction: float = 0.8            #: least fraction of plateau bins with a prediction [-]

    def __post_init__(self):
        for name in ("flow_abs_lpm", "flow_rel", "eta_pts"):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise InputError(f"acceptance.{name}", v, "a finite number >= 0, or 'off'")
        if not (isinstance(self.min_fraction, (int, float)) and 0 <= self.min_fraction <= 1):
            raise InputError("acceptance.min_fraction", self.min_fraction, "[0, 1]")
        if self.flow_abs_lpm is None and self.flow_rel is not None:
            object.__setattr__(self, "flow_abs_lpm", 0.0)
        if self.flow_rel is None and self.flow_abs_lpm is not None:
            object.__setattr__(self, "flow_rel", 0.0)

    @property
    def checks_flow(self) -> bool:
        return self.flow_abs_lpm is not None

    def flow_tolerance_m3s(self, q_measured_m3s: float) -> float | None:
        """Flow tolerance [m³/s] at a measured mean flow [m³/s] (``None`` if the check is off)."""
        if not self.checks_flow:
            return None
        return self.flow_abs_lpm / LPM + self.flow_rel * abs(q_measured_m3s)

    def eta_tolerance(self) -> float | None:
        """Volumetric-efficiency tolerance [-] (``None`` if the check is off)."""
        return None if self.eta_pts is None else self.eta_pts / 100.0

    def describe(self) -> str:
        parts = []
        if self.checks_flow:
            parts.append(f"|mean flow error| <= {self.flow_abs_lpm:g} L/min + {self.flow_rel * 100:g} % of the "
                         "measured mean flow")
        if self.eta_pts is not None:
            parts.append(f"|volumetric efficiency error| <= {self.eta_pts:g} %-points")
        if not parts:
            parts.append("no tolerance enabled (every plateau with data passes)")
        return (" and ".join(parts) + f"; at least {self.min_fraction * 100:g} % of the plateau's 0.1 s bins "
                "predicted, else 'no data'")

    def as_dict(self) -> dict:
        return asdict(self)


def verdict(row: dict, crit: AcceptanceCriterion) -> dict:
    """Verdict of one plateau row of :func:`analysis.compare`.

    Returns
    -------
    dict
        ``verdict`` (``pass`` / ``fail`` / ``no data``), ``reasons`` (list of str, why it failed or has
        no data), ``failed`` (the checks that failed: ``flow``, ``η``, ``data``), ``flow_tol_m3s`` and
        ``eta_tol`` (the tolerances applied, [m³/s] and [-], or None).
    """
    q_m, q_p = row["flow_measured_m3s"], row["flow_predicted_m3s"]
    e_m, e_p = row["eta_measured"], row["eta_predicted"]
    n_bins = max(1, row.get("bins", 0) or 0)
    n_pred = row["flow_error_m3s"]["n"]
    ftol = None if q_m is None else crit.flow_tolerance_m3s(q_m)
    etol = crit.eta_tolerance()
    out = {"verdict": NO_DATA, "reasons": [], "failed": [], "flow_tol_m3s": ftol, "eta_tol": etol}
    if q_p is None or n_pred < crit.min_fraction * n_bins:
        out["reasons"].append(f"only {n_pred} of {n_bins} bins predicted")
        out["failed"].append("data")
        return out
    if ftol is not None and abs(q_p - q_m) > ftol:
        out["reasons"].append(f"flow error {(q_p - q_m) * LPM:+.3f} L/min outside ±{ftol * LPM:.3f}")
        out["failed"].append("flow")
    if etol is not None and e_p is not None and e_m is not None and abs(e_p - e_m) > etol:
        out["reasons"].append(f"η error {(e_p - e_m) * 100:+.2f} pt outside ±{etol * 100:.2f}")
        out["failed"].append("η")
    out["verdict"] = FAIL if out["reasons"] else PASS
    return out


def tally(verdicts) -> dict[str, int]:
    """Number of plateaus per verdict (``pass``, ``fail``, ``no data``) in one twin's :func:`verdict` results."""
    return {k: sum(v["verdict"] == k for v in verdicts) for k in (PASS, FAIL, NO_DATA)}


def tally_text(verdicts) -> str:
    """The tally in words: ``"1 pass, 3 fail"``, with ``", k no data"`` only when there are such plateaus."""
    n = tally(verdicts)
    return f"{n[PASS]} pass, {n[FAIL]} fail" + (f", {n[NO_DATA]} no data" if n[NO_DATA] else "")


_KEYS = {"flow_abs_lpm": "--tol-flow-lpm", "flow_rel": "--tol-flow-rel", "eta_pts": "--tol-eta-pts",
         "min_fraction": "--min-predicted-fraction"}


def _value(field: str, v):
    """A tolerance from text or YAML: a number >= 0, or off/none (disabled)."""
    if v is None or (isinstance(v, str) and v.strip().lower() in ("off", "none", "")):
        if field == "min_fraction":
            raise InputError(field, v, "a number in [0, 1]")
        return None
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise InputError(field, v, "a number >= 0, or 'off'") from None
    if not math.isfinite(x) or x < 0:
        raise InputError(field, v, "a finite number >= 0, or 'off'")
    return x


def load_file(path: str | Path) -> dict:
    """Tolerances from a YAML file (top-level keys or under ``acceptance:``)."""
    from gerotor_twin.yaml_safe import load_yaml_file
    p = Path(path)
    raw = load_yaml_file(p, "--acceptance") or {}
    if isinstance(raw, dict) and isinstance(raw.get("acceptance"), dict):
        raw = raw["acceptance"]
    if not isinstance(raw, dict):
        raise InputError(f"{p}", type(raw).__name__, "a mapping of tolerances")
    bad = sorted(set(raw) - set(_KEYS))
    if bad:
        raise InputError(f"{p}: {bad[0]}", raw[bad[0]], f"one of the keys {sorted(_KEYS)}", "unknown key")
    return {k: _value(f"{p}: {k}", v) for k, v in raw.items()}


def criterion_from_args(args) -> AcceptanceCriterion:
    """The criterion from defaults, then ``--acceptance`` file, then the single options."""
    values = load_file(args.acceptance) if getattr(args, "acceptance", None) else {}
    for key, opt in _KEYS.items():
        v = getattr(args, key, None)
        if v is not None:
            values[key] = _value(opt, v)
    return replace(AcceptanceCriterion(), **values)


def add_arguments(p) -> None:
    """The acceptance options of ``gerotor-twin report`` (and of commands that write a report)."""
    g = p.add_argument_group("acceptance criterion (per-plateau verdict; 'off' disables a check)")
    g.add_argument("--acceptance", metavar="F.yaml", help="tolerances from a YAML file (keys: "
                   + ", ".join(_KEYS) + ")")
    g.add_argument("--tol-flow-lpm", dest="flow_abs_lpm", metavar="L_MIN",
                   help="absolute flow tolerance [L/min] (default 0.2)")
    g.add_argument("--tol-flow-rel", dest="flow_rel", metavar="FRACTION",
                   help="flow tolerance as a fraction of the measured mean flow [-] (default 0.01)")
    g.add_argument("--tol-eta-pts", dest="eta_pts", metavar="POINTS",
                   help="volumetric-efficiency tolerance [%%-points] (default 1.0)")
    g.add_argument("--min-predicted-fraction", dest="min_fraction", metavar="FRACTION",
                   help="least fraction of a plateau's bins with a prediction, else 'no data' (default 0.8)")
