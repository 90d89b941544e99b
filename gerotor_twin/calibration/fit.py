"""The least-squares fit of physical parameters to the mean delivery flow of steady operating points.

For every steady operating point (a plateau of a recording, :mod:`.plateaus`, or a row of a
map, :mod:`.pump_map`) the
twin is run to periodic steady state at the plateau's measured speed, suction and
delivery pressure (:func:`.fit_model.plateau_flow`), in parallel over plateaus on all
cores.  The weighted residuals ``r_i = (q_model,i − q_meas,i) / σ_i`` (σ_i: standard
error of the plateau's mean flow, ⊕ ``flow_floor`` × q, the model's own error:
:data:`MODEL_FLOW_SD_REL` by default) are minimised by
:func:`scipy.optimize.least_squares` over the identifiable combinations of the chosen
log-factors (:mod:`.identifiability`); the others stay at the prior.  Every k-th plateau
of each recording is held out first (fit on the rest, error on those), then the
parameters are refitted on all plateaus for the config that is written.
"""
from __future__ import annotations

import dataclasses
import json
import math
import multiprocessing
import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ..errors import InputError
from ..twin.health import HealthSettings
from . import identifiability as ident
from .fit_model import (PARAMETERS, PlateauTask, apply, at_meter, plateau_flow, prior_values, with_edge_losses,
                        without_edge_losses)
from .plateaus import PlateauRecord

__all__ = ["Evaluator", "FitResult", "fit", "split_holdout", "plateau_errors", "MODEL_FLOW_SD_REL"]

#: Model error of a plateau's mean flow, relative [-], added in quadrature to its standard error: the
#: health estimator's default for the same thing (``HealthSettings.model_sd_rel``).  Without it the
#: intervals hold the noise only: at the true clearances the twin's mean flows differ from the bench
#: emulator's by −0.6 to +0.01 % (five plateaus, factor 1.2, measured 2026-12-01) at standard
#: errors of 0.04–0.4 %, and the 95 % interval of the lateral factor missed the truth.
MODEL_FLOW_SD_REL = HealthSettings().model_sd_rel

FD_STEP = 0.02          #: finite-difference step of the log-factors [-] (2 % of the value)


class Evaluator:
    """Runs :func:`plateau_flow` for many (config, plateau) pairs, in worker processes."""

    def __init__(self, raw_prior: dict, bearing: str, jobs: int | None = None, progress=None,
                 flow_meter: str = "delivery"):
        self.raw_prior = raw_prior
        self.bearing = bearing
        self.flow_meter = flow_meter      #: where the flows compared were measured (``hydraulics.meter.FLOW_METERS``)
        self.table_tip = float(raw_prior["clearances"]["tooth_tip_m"])
        self.jobs = max(1, int(jobs or os.cpu_count() or 1))
        self.progress = progress
        self.simulated = 0
        #: the last revolution's change of the runs that stopped at their revolution limit unsettled [-]
        self.unsettled: list[float] = []
        self._pool = None
        self._runs: dict[str, dict] = {}

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def flows(self, names, xs: list[np.ndarray], records: list[PlateauRecord]) -> np.ndarray:
        """Model mean delivery flow [m³/s] as the flow meter reads it (``flow_meter``, :func:`.fit_model.at_meter`),
        shape (len(xs), len(records)).

        Each (config, plateau) runs once per evaluator: a run is kept and reused by every later call that
        needs it (the prior and the finite-difference steps of each fold and candidate set), and configs that
        differ only in their ``volumetric`` section (the effective displacement, the bypass: losses applied
        after the chamber model) share one run (:func:`.fit_model.with_edge_losses`).  ``simulated`` counts
        the runs.
        """
        wanted = []                          # (run key, config, plateau) per output element
        todo: dict[str, PlateauTask] = {}
        for x in xs:
            raw = apply(self.raw_prior, names, x)
            sim = without_edge_losses(raw)
            for r in records:
                task = PlateauTask(sim, self.table_tip, self.bearing, r.omega, r.p_suction_pa, r.p_delivery_pa,
                                   r.oil_temperature_c)
                key = json.dumps(dataclasses.asdict(task), sort_keys=True)
                wanted.append((key, raw, r))
                if key not in self._runs:
                    todo[key] = task
        self._run(todo)
        flows = [at_meter(self._runs[key], with_edge_losses(self._runs[key], raw, r.omega), self.flow_meter)
                 for key, raw, r in wanted]
        return np.array(flows).reshape(len(xs), len(records))

    def _run(self, todo: dict) -> None:
        """Run the tasks ``todo`` (key → :class:`.fit_model.PlateauTask`) into the kept runs."""
        if not todo:
            return
        tasks = list(todo.values())
        if self.jobs == 1 or len(tasks) < 2:
            out = [plateau_flow(t) for t in tasks]
        else:
            first = []
            if self._pool is None:   # compile/load the kernel here first: forked workers inherit it
                first = [plateau_flow(tasks[0])]
                self._pool = ProcessPoolExecutor(self.jobs, mp_context=multiprocessing.get_context("fork"))
            rest = tasks[len(first):]
            out = first + list(self._pool.map(plateau_flow, rest, chunksize=max(1, len(rest) // (4 * self.jobs))))
        self._runs.update(zip(todo, out))
        self.simulated += len(tasks)
        self.unsettled += [o["periodicity_error"] for o in out if not o["settled"]]
        if self.progress:
            self.progress(f"  {self.simulated} plateau simulations")


@dataclass(frozen=True)
class FitResult:
    """A least-squares fit over one set of plateaus (log-factors x = ln(value/prior))."""
    names: tuple[str, ...]
    x: np.ndarray                #: fitted log-factors [-]
    cov_x: np.ndarray            #: covariance of x (rank r) [-]
    analysis: dict               #: :func:`identifiability.analyse` at the prior
    residuals: np.ndarray        #: weighted residuals at the fit [-]
    flow_model: np.ndarray       #: model flow at the fit [m³/s]
    flow_prior: np.ndarray       #: model flow at the prior [m³/s]
    s2: float                    #: residual variance factor (≥ 1) [-]
    dof: int
    iterations: int


def sigmas(records: list[PlateauRecord], flow_floor: float) -> np.ndarray:
    """Standard deviation of each plateau's mean flow [m³/s] (≥ 1e-9)."""
    sem = np.array([r.flow_sem_m3s if math.isfinite(r.flow_sem_m3s) else 0.0 for r in records])
    q = np.array([r.flow_m3s for r in records])
    return np.maximum(np.hypot(sem, flow_floor * np.abs(q)), 1e-9)


def _jacobian(ev: Evaluator, names, x, records, f0, sig, which=None) -> np.ndarray:
    """Weighted Jacobian of the flows over the coordinates x by forward differences (FD_STEP); only the columns
    of the parameters ``which`` (booleans, default all) are computed, the others are 0."""
    which = np.ones(len(names), bool) if which is None else np.asarray(which, bool)
    idx = np.flatnonzero(which)
    out = np.zeros((len(records), len(names)))
    if idx.size:
        fp = ev.flows(names, [x + FD_STEP * np.eye(len(names))[i] for i in idx], records)
        out[:, idx] = ((fp - f0) / FD_STEP / sig).T
    return out


def fit(ev: Evaluator, names, records: list[PlateauRecord], *, rcond: float = 0.1,
        flow_floor: float = MODEL_FLOW_SD_REL,
        progress=None, structure: dict | None = None) -> FitResult:
    """Fit the identifiable combinations of ``names`` to ``records`` (see module doc).

    ``structure``: the :func:`identifiability.analyse` result of another fit of ``names`` (a cross-validation
    fold takes the fit on all points'), whose groups and fixed parameters this fit keeps instead of analysing
    ``records`` itself."""
    if len(records) < 1:
        raise InputError("plateaus", 0, "at least one steady plateau to fit")
    say = progress or (lambda s: None)
    q = np.array([r.flow_m3s for r in records])
    sig = sigmas(records, flow_floor)
    p = len(names)
    f_prior = ev.flows(names, [np.zeros(p)], records)[0]
    if p == 0:          # the prior itself: nothing to fit
        return FitResult((), np.zeros(0), np.zeros((0, 0)), ident.analyse(np.zeros((len(records), 0)), (), rcond),
                         (f_prior - q) / sig, f_prior, f_prior, math.nan, len(records), 0)
    if structure is not None:
        analysis = structure
    else:
        x_a = analysis_point(names, ev.raw_prior)
        f_a = f_prior if not x_a.any() else ev.flows(names, [x_a], records)[0]
        analysis = ident.analyse(_jacobian(ev, names, x_a, records, f_a, sig), names, rcond,
                                 linear=[PARAMETERS[n].step > 0 for n in names])
    basis = analysis["basis"]
    say(f"  identifiable directions: {len(analysis['kept'])} of {p}")
    cache = {}

    def model(b):
        key = tuple(np.round(b, 12))
        if key not in cache:
            cache[key] = ev.flows(names, [basis @ b], records)[0]
        return cache[key]

    def fun(b):
        r = (model(b) - q) / sig
        say(f"  iteration: x = {np.round(basis @ b, 4).tolist()}, rms weighted residual {np.sqrt(np.mean(r ** 2)):.3g}")
        return r

    def jac(b, cols=None):
        """∂r/∂b; with ``cols`` (booleans over b) only those columns, the parameters of the others not run."""
        which = None if cols is None else (basis[:, np.asarray(cols, bool)] > 0).any(axis=1)
        return _jacobian(ev, names, basis @ b, records, model(b), sig, which) @ basis

    r = basis.shape[1]
    if r == 0:
        b, nfev = np.zeros(0), 0
    else:
        lo, hi = _bounds(names, ev.raw_prior, basis)
        b, nfev = _solve(fun, jac, lo, hi)
    x = basis @ b
    res = (model(b) - q) / sig
    jb = jac(b) if r else np.zeros((len(records), 0))
    cov_b, s2, dof = ident.covariance(jb, res) if r else (np.zeros((0, 0)), math.nan, len(records))
    return FitResult(tuple(names), x, basis @ cov_b @ basis.T, analysis, res, model(b), f_prior, s2, dof, nfev)


def analysis_point(names, raw_prior: dict) -> np.ndarray:
    """Where the identifiability analysis takes the Jacobian: the prior (x = 0), but a gate (the parameter another
    of ``names`` acts through, :attr:`.fit_model.FitParameter.gate`) whose prior is zero one step in (x = 1), so
    that the parameter acting through it is seen (the filling margin has no effect without a filling loss)."""
    priors = dict(zip(names, prior_values(raw_prior, names)))
    gates = {PARAMETERS[n].gate for n in names} & set(names)
    return np.array([1.0 if n in gates and priors[n] == 0.0 and PARAMETERS[n].step > 0 else 0.0 for n in names])


def _least_squares(fun, jac, b0, lo, hi):
    return least_squares(fun, b0, jac=jac, bounds=(lo, hi), x_scale=0.05, xtol=1e-4, ftol=1e-6, max_nfev=30)


def _solve(fun, jac, lo, hi) -> tuple[np.ndarray, int]:
    """The fitted coordinates b within [lo, hi] and the residual evaluations it took.

    A coordinate whose prior is its lower bound (``lo`` = 0: a bypass area, a gap's opening, 0 for a rigid pump)
    is first held there while the others are fitted — the same steps as the set without it, so its runs are
    shared with that set's — and then released only where the data pull it into the feasible side by more
    than its own standard deviation.  With g_k = (J e_k)ᵀ r the gradient of ½‖r‖² along it (one forward
    difference) and H_k = ‖J e_k‖² its Gauss–Newton curvature, the step to the unconstrained optimum is
    δ = −g_k/H_k and its standard deviation 1/√H_k (r is weighted by each point's σ), so it is released when
    g_k < 0 (the Karush–Kuhn–Tucker condition of a lower bound fails: Nocedal & Wright, *Numerical
    Optimization*, 2nd ed., sec. 12.3) and g_k²/H_k > 1: the χ² the step would gain exceeds 1 (the score test
    at one standard deviation).  Fitted from inside instead, such a coordinate creeps to its bound over 11–19
    Jacobians (a trust region shrinking on the bound), which doubled a recording's calibration with the gaps'
    opening offered on a rigid pump."""
    pinned = lo >= 0
    free = ~pinned
    b = np.where(pinned, lo, 0.0)
    nfev = 0
    if free.any():
        def fun_free(bf):
            return fun(_put(b, free, bf))

        def jac_free(bf):
            return jac(_put(b, free, bf), free)[:, free]
        sol = _least_squares(fun_free, jac_free, b[free], lo[free], hi[free])
        b, nfev = _put(b, free, sol.x), sol.nfev
    if not pinned.any():
        return b, nfev
    jp = jac(b, pinned)[:, pinned]
    grad, curv = jp.T @ fun(b), np.sum(jp ** 2, axis=0)
    release = (grad < 0) & (grad ** 2 > curv)
    if not release.any():
        return b, nfev + 1
    # a start on a bound would get steps scaled by its distance to it: start inside
    b0 = np.where(pinned, lo + np.minimum(0.1, (hi - lo) / 2), b)
    sol = _least_squares(fun, jac, b0, lo, hi)
    return sol.x, nfev + 1 + sol.nfev


def _put(b: np.ndarray, mask: np.ndarray, values) -> np.ndarray:
    """``b`` with its ``mask`` entries replaced by ``values``."""
    out = np.array(b, float)
    out[mask] = values
    return out


def _bounds(names, raw_prior: dict, basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of the fitted coordinates b (x = basis @ b): each group within every member's physical bounds."""
    xb = np.array([PARAMETERS[n].x_bounds(v) for n, v in zip(names, prior_values(raw_prior, names))])
    lo = np.array([xb[basis[:, k] > 0, 0].max() for k in range(basis.shape[1])])
    hi = np.array([xb[basis[:, k] > 0, 1].min() for k in range(basis.shape[1])])
    return lo, hi


def split_holdout(records: list[PlateauRecord], every: int) -> tuple[list, list]:
    """Every ``every``-th plateau of each recording held out (0: none) → (train, held out)."""
    if every == 0:
        return list(records), []
    if every < 2:
        raise InputError("--holdout", every, "0 (none) or an integer ≥ 2 (every k-th plateau held out)")
    train, held = [], []
    for r in records:
        (held if r.index % every == 0 else train).append(r)
    if not train:
        raise InputError("--holdout", every, "a value leaving plateaus to fit")
    return train, held


def plateau_errors(records: list[PlateauRecord], flow_model: np.ndarray, displacement_m3: float) -> list[dict]:
    """Per plateau: measured and model flow [m³/s], η_v [-] and their errors (model − measured); ``eta_sem``:
    the standard error of the measured η_v (of the plateau's mean flow) [-]."""
    rows = []
    for r, fm in zip(records, flow_model):
        qth = displacement_m3 * r.omega / (2 * math.pi)
        rows.append({"plateau": r.label(), "rpm": r.rpm, "p_delivery_pa": r.p_delivery_pa,
                     "oil_temperature_c": r.oil_temperature_c, "flow_measured_m3s": r.flow_m3s,
                     "flow_model_m3s": float(fm), "flow_error_m3s": float(fm - r.flow_m3s),
                     "eta_measured": r.flow_m3s / qth, "eta_model": float(fm) / qth,
                     "eta_error": float(fm - r.flow_m3s) / qth, "eta_sem": r.flow_sem_m3s / qth})
    return rows


def summary_stats(rows: list[dict], key: str = "eta_error") -> dict:
    """Bias, RMSE, max |·| of one error column of :func:`plateau_errors` rows."""
    e = np.array([r[key] for r in rows], float)
    if e.size == 0:
        return {"bias": None, "rmse": None, "max_abs": None, "n": 0}
    return {"bias": float(e.mean()), "rmse": float(np.sqrt(np.mean(e ** 2))), "max_abs": float(np.abs(e).max()),
            "n": int(e.size)}


def parameter_table(fr: FitResult, raw_prior: dict, z: float = 1.96) -> list[dict]:
    """Fitted value, 95 % interval (``z`` σ of the fitted coordinate: log-normal for a log-factor) and whether
    the data determine it alone; ``log_factor``: the fitted coordinate x (:mod:`.fit_model`)."""
    prior = prior_values(raw_prior, fr.names)
    sd = np.sqrt(np.clip(np.diag(fr.cov_x), 0, None))
    alone = _separately_determined(fr)
    rows = []
    for i, n in enumerate(fr.names):
        p = PARAMETERS[n]
        rows.append({"name": n, "field": f"{p.section}.{p.key}", "unit": p.unit,
                     "prior": float(prior[i]), "value": float(p.value(prior[i], fr.x[i])),
                     "log_factor": float(fr.x[i]), "log_factor_sd": float(sd[i]), "linear": p.step > 0,
                     "ci95": [float(p.value(prior[i], fr.x[i] - z * sd[i])),
                              float(p.value(prior[i], fr.x[i] + z * sd[i]))],
                     "identifiable": bool(alone[i])})
    return rows


def _separately_determined(fr: FitResult) -> np.ndarray:
    """A parameter is determined on its own when its axis lies in the kept subspace."""
    basis = fr.analysis["basis"]
    out = np.zeros(len(fr.names), bool)
    for i in range(len(fr.names)):
        e = np.zeros(len(fr.names))
        e[i] = 1.0
        out[i] = basis.shape[1] > 0 and np.linalg.norm(basis @ (basis.T @ e) - e) < 1e-6 if basis.size else False
    return out


def combinations(fr: FitResult, z: float = 1.96) -> list[dict]:
    """Each identifiable combination c·x with its standard deviation and 95 % interval; ``factor``: exp(c·x),
    the common factor of a group of log-factors (``linear``: the group holds a linearly fitted parameter, whose
    value is in :func:`parameter_table`)."""
    out = []
    combos = fr.analysis["combinations"]
    for k in range(combos.shape[1]):
        c = combos[:, k]
        v, sd = float(c @ fr.x), float(math.sqrt(max(c @ fr.cov_x @ c, 0.0)))
        linear = any(PARAMETERS[n].step > 0 for n, ci in zip(fr.names, c) if abs(ci) > 0)
        out.append({"coefficients": dict(zip(fr.names, c.tolist())), "linear": linear,
                    "label": ident.combination_label(c, fr.names), "value": v, "sd": sd,
                    "ci95": [v - z * sd, v + z * sd], "factor": math.exp(v),
                    "factor_ci95": [math.exp(v - z * sd), math.exp(v + z * sd)]})
    return out


def run_timed(fn, *args, **kw):
    """``fn(*args, **kw)`` and its wall time [s]."""
    t0 = time.perf_counter()
    out = fn(*args, **kw)
    return out, time.perf_counter() - t0
