r"""Which parameter set to fit: cross-validation among candidates, and a two-term empirical law as the baseline.

Each candidate set of parameters (the prior itself, fitting nothing, among them) is fitted on
all folds but one and predicts the points of the one left out (:func:`folds`: leave one speed
out, or leave one point out).  Its held-out error is the root mean square of the volumetric-
efficiency errors of every point when held out, ``e_i = η_model,i − η_meas,i`` [-].  The set
chosen is the one with the fewest fitted directions whose held-out RMSE is within the noise of
the best: one standard error, or the RMS standard deviation of a point's η_v the fit assumes
where that is larger (the one-standard-error rule; Hastie, Tibshirani & Friedman, *The Elements of
Statistical Learning*, 2nd ed., sec. 7.10), the standard error of an RMSE from that of the
mean squared error:

.. math::
    \mathrm{SE}(\mathrm{RMSE}) = \frac{\mathrm{sd}(e_i^2)}{2\,\mathrm{RMSE}\,\sqrt{m}}

The chosen set's held-out errors give the model-form error of its predictions and with it the 95 %
prediction interval of a predicted efficiency (:mod:`.prediction`: parameters ⊕ measurement ⊕ the
model-form error the folds showed; with neither parameter nor measurement variance it is
``± t₀.₉₇₅,m−1 · RMSE_cv``).

The baseline is the law a spreadsheet fits to a map,

.. math::
    1 - \eta_v = a + b \, \frac{\Delta p}{n}

(Δp = p_delivery − p_suction [Pa], n [rev/s]; ``a``: losses proportional to the flow,
``b``: laminar leakage), fitted by linear least squares on the same folds.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np

from . import fit as C
from . import prediction as P

__all__ = ["folds", "resolve_scheme", "candidate_sets", "Candidate", "cross_validate", "baseline", "choose", "prediction_band",
           "held_out_by_speed", "BY_SPEED_NOTE",
           "CV_SCHEMES"]

CV_SCHEMES = ("speed", "point")
#: speeds within this relative difference are one speed of a map or a recording [-]
SPEED_TOLERANCE = 0.02


def folds(records: list[PlateauRecord], scheme: str) -> list[np.ndarray]:
    """Index arrays of the points each fold holds out: ``"speed"`` (one fold per speed, speeds within
    :data:`SPEED_TOLERANCE` together) or ``"point"`` (one fold per point)."""
    if scheme == "point":
        return [np.array([i]) for i in range(len(records))]
    speeds: list[float] = []
    label = []
    for r in records:
        k = next((j for j, s in enumerate(speeds) if abs(r.omega - s) <= SPEED_TOLERANCE * s), None)
        if k is None:
            speeds.append(r.omega)
            k = len(speeds) - 1
        label.append(k)
    label = np.array(label)
    return [np.flatnonzero(label == k) for k in range(len(speeds))]


def resolve_scheme(scheme: str, records: list) -> str:
    """``"auto"`` → ``"speed"`` when the points have two speeds or more, else ``"point"`` (``"none"`` for a single
    point); others as given."""
    from ..errors import InputError
    if scheme not in CV_SCHEMES + ("none", "auto"):
        raise InputError("--cv", scheme, "auto | speed | point | none")
    if scheme == "auto":
        if len(records) < 2:
            return "none"           # nothing to hold out: the fit is reported unchecked
        return "speed" if len(folds(records, "speed")) >= 2 else "point"
    if scheme == "speed" and len(folds(records, "speed")) < 2:
        raise InputError("--cv", scheme, "point or none for points at one speed", "leave-one-speed-out needs two speeds")
    return scheme


def candidate_sets(params: tuple[str, ...], max_subsets: int = 3) -> list[tuple[str, ...]]:
    """The prior (empty set), then every subset of ``params`` when they are at most ``max_subsets``, else
    the prefixes of ``params`` (its order: the user's), smallest first."""
    if len(params) <= max_subsets:
        return [s for k in range(len(params) + 1) for s in itertools.combinations(params, k)]
    return [params[:k] for k in range(len(params) + 1)]


@dataclass(frozen=True)
class Candidate:
    """One candidate set: its held-out and fit errors (η_v, [-])."""
    names: tuple[str, ...]
    cv_errors: np.ndarray        #: each point's η error when its fold was held out [-]
    fit_errors: np.ndarray       #: each point's η error of the fit on all points [-]
    directions: int              #: identifiable directions of the fit on all points [-]
    cv_param_var: np.ndarray | None = None   #: each held-out point's gᵀ Σ_x g of its fold's fit [-²] (None: 0)
    cv_meas_var: np.ndarray | None = None    #: each point's measurement variance of η [-²] (None: 0)
    held: tuple[str, ...] = ()   #: parameters of the set the identifiability analysis kept at the prior
    rcond: float = math.nan      #: the analysis's singular-value ratio [-]

    def model_form(self, level: float = 0.95) -> P.ModelFormError:
        """The model-form error its held-out errors show (:func:`.prediction.model_form_error`)."""
        zero = np.zeros_like(self.cv_errors)
        return P.model_form_error(self.cv_errors, zero if self.cv_param_var is None else self.cv_param_var,
                                  zero if self.cv_meas_var is None else self.cv_meas_var, level)

    @property
    def cv_rmse(self) -> float:
        return _rmse(self.cv_errors)

    @property
    def cv_rmse_se(self) -> float:
        """Standard error of :attr:`cv_rmse` (module doc) [-]."""
        e2 = self.cv_errors ** 2
        r = self.cv_rmse
        return float(np.std(e2, ddof=1) / (2 * r * math.sqrt(e2.size))) if e2.size > 1 and r > 0 else 0.0

    def summary(self) -> dict:
        return {"params": list(self.names), "directions": self.directions,
                "fit_rmse": _rmse(self.fit_errors), "fit_max_abs": float(np.abs(self.fit_errors).max()),
                "cv_rmse": self.cv_rmse, "cv_rmse_se": self.cv_rmse_se,
                "cv_max_abs": float(np.abs(self.cv_errors).max()),
                "cv_mean_abs": float(np.mean(np.abs(self.cv_errors))), "cv_errors": self.cv_errors.tolist(),
                "model_form_sd_eta": self.model_form().sd, "held_at_prior": list(self.held), "rcond": self.rcond}


def _rmse(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(e)))) if len(e) else math.nan


def _eta_errors(records, flow_model, displacement_m3: float) -> np.ndarray:
    return np.array([r["eta_error"] for r in C.plateau_errors(records, flow_model, displacement_m3)])


def cross_validate(ev: C.Evaluator, names, records, fold_index, displacement_m3: float, opts: dict,
                   say=lambda s: None) -> tuple[Candidate, C.FitResult]:
    """Held-out η errors of fitting ``names`` (each fold fitted on the others), and the fit on all points.

    Every fold fits the directions the fit on all points fits (its groups and its parameters kept at the prior,
    :func:`.identifiability.analyse` of the Jacobian at the prior over all operating points): the model each
    fold is judged as is the model the calibration writes.  That analysis looks at the operating points, not at
    the measured flows, so deciding it before the folds are left out does not leak the held-out values into
    the fit (the unsupervised screening that may precede cross-validation: Hastie, Tibshirani & Friedman,
    *The Elements of Statistical Learning*, 2nd ed., sec. 7.10.2); a direction that the points of a fold
    determine poorly shows as a large held-out error instead of being dropped from that fold alone."""
    names = tuple(names)
    fr = C.fit(ev, names, records, **opts)
    cv = np.full(len(records), np.nan)
    pv = np.zeros(len(records))
    for held in fold_index:
        out = set(held.tolist())
        train = [r for i, r in enumerate(records) if i not in out]
        test = [records[i] for i in held]
        fk = C.fit(ev, names, train, **opts, structure=fr.analysis)
        q = ev.flows(names, [fk.x], test)[0]
        cv[held] = _eta_errors(test, q, displacement_m3)
        pv[held] = P.param_variance(P.eta_gradients(ev, names, fk.x, test, displacement_m3, q), fk.cov_x)
    a = fr.analysis
    cand = Candidate(names, cv, _eta_errors(records, fr.flow_model, displacement_m3), len(a["groups"]),
                     pv, P.measurement_variance(records, displacement_m3),
                     tuple(a.get("fixed", ())) + tuple(a.get("insensitive", ())), float(a.get("rcond", math.nan)))
    say(f"  {'+'.join(names) or 'prior'}: fit RMSE {100 * _rmse(cand.fit_errors):.2f} pt, held-out RMSE {100 * cand.cv_rmse:.2f} pt")
    return cand, fr


def choose(cands: list[Candidate], noise: float = 0.0) -> tuple[Candidate, str]:
    """The simplest candidate within the noise of the best held-out RMSE, and why (one line).

    Within the noise: held-out RMSE ≤ best + max(its standard error, ``noise``), ``noise`` [-] being the
    RMS standard deviation of a point's η_v the fit assumes (measurement ⊕ model-error floor): a smaller
    difference is not evidence.  Simplest: the fewest identifiable directions (tip and lateral fitted as one
    common factor count once), then the lower held-out RMSE.
    """
    best = min(cands, key=lambda c: c.cv_rmse)
    margin = max(best.cv_rmse_se, noise)
    ok = [c for c in cands if c.cv_rmse <= best.cv_rmse + margin]
    pick = min(ok, key=lambda c: (c.directions, c.cv_rmse))
    name = "+".join(pick.names) or "the prior (nothing fitted)"
    if pick is best:
        why = f"{name}: lowest held-out RMSE ({100 * best.cv_rmse:.2f} pt)"
    else:
        why = (f"{name}: the fewest fitted directions ({pick.directions}) within the noise of the best held-out "
               f"RMSE ({100 * pick.cv_rmse:.2f} ≤ {100 * best.cv_rmse:.2f} + {100 * margin:.2f} pt, "
               f"{'+'.join(best.names)})")
    return pick, why


def held_out_by_speed(sel: dict) -> list[tuple[float, float]]:
    """(speed [rpm], the chosen set's mean |η error| held out [-]) per fold of a leave-one-speed-out selection
    (the dict :func:`.command.calibrate_records` returns as ``selection``), by speed; empty for other schemes."""
    if sel.get("cv") != "speed" or "fold_rpm" not in sel:
        return []
    return sorted(zip(sel["fold_rpm"], sel["chosen_fold_mean_abs"]))


#: what the by-speed line adds: the end speeds are extrapolated
BY_SPEED_NOTE = "the lowest and highest speeds held out are predicted beyond the speeds fitted"


def prediction_band(cand: Candidate, level: float = 0.95, param_var: float = 0.0, meas_var: float = 0.0) -> float:
    """Half-width of the ``level`` prediction interval of η_v [-] at a point of parameter variance ``param_var``
    and measurement variance ``meas_var`` [-²] (:mod:`.prediction`; the model-form error from the held-out
    errors)."""
    return float(cand.model_form(level).half_width(param_var, meas_var))


def baseline(records, fold_index, displacement_m3: float, p_suction_default_pa: float) -> dict:
    """The empirical law of the module doc: fit on all points, and held out on the same folds as the twin."""
    recs = [r if math.isfinite(r.p_suction_pa) else replace(r, p_suction_pa=p_suction_default_pa) for r in records]
    x = np.array([(r.p_delivery_pa - r.p_suction_pa) / (r.omega / (2 * math.pi)) for r in recs])
    y = np.array([1 - r.flow_m3s / (displacement_m3 * r.omega / (2 * math.pi)) for r in recs])
    design = np.column_stack([np.ones_like(x), x])

    def fit(idx):
        return np.linalg.lstsq(design[idx], y[idx], rcond=None)[0]
    coef = fit(np.arange(len(recs)))
    cv = np.full(len(recs), np.nan)
    for held in fold_index:
        train = np.setdiff1d(np.arange(len(recs)), held)
        cv[held] = -(design[held] @ fit(train) - y[held])      # η error = −(error of 1 − η)
    fit_e = -(design @ coef - y)
    return {"law": "1 − η = a + b·Δp/n", "a": float(coef[0]), "b_per_pa_s": float(coef[1]),
            "fit_rmse": _rmse(fit_e), "fit_max_abs": float(np.abs(fit_e).max()),
            "cv_rmse": _rmse(cv), "cv_max_abs": float(np.abs(cv).max()), "cv_errors": cv.tolist()}

