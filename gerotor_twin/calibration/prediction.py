r"""The uncertainty of a calibrated twin's prediction at a plateau, model-form error included.

A prediction of the calibrated twin at a steady operating point is its volumetric efficiency
η̂₀ = Q(x̂)/Q_th (Q_th = D n [m³/s]) at the fitted log-factors x̂; its error against a measured plateau is
e₀ = η̂₀ − η₀ [-].  Three independent parts make that error (linearised about x̂):

.. math::
    \operatorname{Var} e_0 = \underbrace{g_0^\top \Sigma_x\, g_0}_{\text{parameters}}
        + \underbrace{s_0^2}_{\text{measurement}} + \underbrace{\sigma_d^2}_{\text{model form}}

with g₀ = ∂η₀/∂x (finite differences, step :data:`.fit.FD_STEP`), Σ_x the covariance of the fitted
log-factors (:func:`.identifiability.covariance`), s₀ the standard error of the plateau's measured η
(of its mean flow) and σ_d² the variance of the twin's model-form error: what the twin gets wrong at any
parameter value (another port law, free air, a gap law of another form).  The parameter covariance alone
holds only the first term; at a wrong-form model it shrinks with more data while the error does not.

σ_d² is estimated out of sample from the leave-one-group-out cross-validation that chose the parameter set
(:func:`.selection.cross_validate`: fit on all groups of operating points but one — one speed, or one
point —, predict the one left out).  Each held-out error e_j has, by the same decomposition with the fold's
own fit, E[e_j²] = g_jᵀ Σ_x^(−k) g_j + s_j² + σ_d², so

.. math::
    \hat\sigma_d^2 = \max\Bigl(0,\ \frac1m \sum_{j=1}^{m}
        \bigl(e_j^2 - g_j^\top \Sigma_x^{(-k(j))} g_j - s_j^2\bigr)\Bigr)

over the m held-out points (e_j² holds a bias as well as a scatter: a systematic form error counts in
full).  The 95 % prediction interval of a new plateau's η is then

.. math::
    \hat\eta_0 \pm t_{0.975,\,m-1}\,\sqrt{g_0^\top \Sigma_x\, g_0 + s_0^2 + \hat\sigma_d^2}

and of its mean flow Q_th times that.  This is the classical prediction interval of a new observation
of a regression, ŷ₀ ± t·√(s² + f₀ᵀ Σ f₀) (Seber & Wild, *Nonlinear Regression*, Wiley 1989,
prediction of a new observation), with the residual variance s² replaced by the measurement variance
plus a model-discrepancy variance (the discrepancy term δ(x) of Kennedy & O'Hagan, "Bayesian calibration
of computer models", J. R. Stat. Soc. B 63(3), 425–464, 2001) estimated by cross-validation across
operating regions (Hastie, Tibshirani & Friedman, *The Elements of Statistical Learning*, 2nd ed.,
sec. 7.10), Student's t for the m held-out errors it rests on (m counts plateaus, not folds: the errors of
one fold share its fit, so fewer independent errors stand behind σ̂_d than m says, and with few folds the
t-quantile is optimistic).  It treats the form error as a scatter
of one size over the operating range: where the form error grows towards one corner of the range, the
interval is too wide elsewhere and too narrow there, and a range the folds never held out is not covered
by it.  The coverage over the shipped bench pumps is measured by
:mod:`gerotor_twin.offline.calibration_coverage`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import t as student_t

from . import fit as C

__all__ = ["eta_gradients", "param_variance", "measurement_variance", "ModelFormError", "model_form_error",
           "predict"]


def _qth(records, displacement_m3: float) -> np.ndarray:
    return np.array([displacement_m3 * r.omega / (2 * math.pi) for r in records])


def eta_gradients(ev: C.Evaluator, names, x: np.ndarray, records, displacement_m3: float,
                  flow_at_x: np.ndarray | None = None) -> np.ndarray:
    """∂η_i/∂x_k by forward differences of step :data:`.fit.FD_STEP` [-], shape (len(records), len(names))."""
    names = tuple(names)
    if not names or not records:
        return np.zeros((len(records), len(names)))
    f0 = ev.flows(names, [x], records)[0] if flow_at_x is None else np.asarray(flow_at_x)
    fp = ev.flows(names, [x + C.FD_STEP * e for e in np.eye(len(names))], records)
    return ((fp - f0) / C.FD_STEP).T / _qth(records, displacement_m3)[:, None]


def param_variance(g: np.ndarray, cov_x: np.ndarray) -> np.ndarray:
    """gᵢᵀ Σ_x gᵢ for each row gᵢ of ``g`` [-²]."""
    if g.size == 0:
        return np.zeros(g.shape[0])
    return np.einsum("ik,kl,il->i", g, cov_x, g)


def measurement_variance(records, displacement_m3: float) -> np.ndarray:
    """Variance of each record's measured η from its mean flow's standard error [-²] (0 where unknown: a map)."""
    sem = np.array([r.flow_sem_m3s if math.isfinite(r.flow_sem_m3s) else 0.0 for r in records])
    return (sem / _qth(records, displacement_m3)) ** 2


@dataclass(frozen=True)
class ModelFormError:
    """The model-form error of a parameter set, estimated from its held-out errors (module doc)."""
    sd: float                    #: σ̂_d [-] (η)
    held_out: int                #: m, held-out errors it rests on [-]
    level: float = 0.95          #: level of the prediction interval [-]

    @property
    def dof(self) -> int:
        return max(self.held_out - 1, 1)

    @property
    def t(self) -> float:
        """Student's t quantile of the interval [-]."""
        return float(student_t.ppf(0.5 + self.level / 2, self.dof))

    def half_width(self, param_var, meas_var=0.0) -> np.ndarray:
        """Half-width of the prediction interval of η [-] at points of parameter and measurement variance."""
        return self.t * np.sqrt(np.asarray(param_var) + np.asarray(meas_var) + self.sd ** 2)

    def as_dict(self) -> dict:
        return {"model_form_sd_eta": self.sd, "held_out": self.held_out, "dof": self.dof, "level": self.level,
                "t": self.t}


def model_form_error(cv_errors, cv_param_var, cv_meas_var, level: float = 0.95) -> ModelFormError:
    """σ̂_d from held-out errors e_j [-], their fold fits' parameter variances and their measurement
    variances [-²] (module doc).  A NaN parameter variance (a fold fitted on no more points than it has
    directions: no residual degrees of freedom, no covariance) counts as 0, so that fold's whole error is
    taken as model-form error (the interval errs on the wide side)."""
    e = np.asarray(cv_errors, float)
    # a fold fitted on no more points than directions has no covariance (NaN): its errors count as form error
    pv = np.nan_to_num(np.asarray(cv_param_var, float), nan=0.0)
    excess = e ** 2 - pv - np.nan_to_num(np.asarray(cv_meas_var, float), nan=0.0)
    return ModelFormError(float(math.sqrt(max(0.0, float(np.mean(excess))))) if e.size else 0.0, int(e.size), level)


def predict(ev: C.Evaluator, names, x: np.ndarray, cov_x: np.ndarray, records, displacement_m3: float,
            form: ModelFormError) -> list[dict]:
    """The twin at log-factors ``x`` on ``records``: per record the predicted η and mean flow, the 95 %
    interval's half-widths and their parts, and the error against the record's measurement.

    Returns
    -------
    list of dict
        ``eta_model``, ``eta_measured``, ``eta_error`` [-], ``flow_model_m3s``, ``flow_measured_m3s`` [m³/s],
        ``half_width_eta`` [-], ``half_width_flow_m3s`` [m³/s], ``sd_param_eta``, ``sd_meas_eta``,
        ``sd_form_eta`` [-], ``covered`` (|error| ≤ half-width).
    """
    names = tuple(names)
    q = ev.flows(names, [np.asarray(x, float)], records)[0]
    g = eta_gradients(ev, names, np.asarray(x, float), records, displacement_m3, q)
    pv = param_variance(g, np.asarray(cov_x, float))
    mv = measurement_variance(records, displacement_m3)
    hw = form.half_width(pv, mv)
    qth = _qth(records, displacement_m3)
    out = []
    for i, r in enumerate(records):
        err = (q[i] - r.flow_m3s) / qth[i]
        out.append({"plateau": r.label(), "rpm": r.rpm, "p_delivery_pa": r.p_delivery_pa,
                    "oil_temperature_c": r.oil_temperature_c,
                    "eta_model": float(q[i] / qth[i]), "eta_measured": float(r.flow_m3s / qth[i]), "eta_error": float(err),
                    "flow_model_m3s": float(q[i]), "flow_measured_m3s": float(r.flow_m3s),
                    "half_width_eta": float(hw[i]), "half_width_flow_m3s": float(hw[i] * qth[i]),
                    "sd_param_eta": float(math.sqrt(max(pv[i], 0.0))), "sd_meas_eta": float(math.sqrt(mv[i])),
                    "sd_form_eta": form.sd, "covered": bool(abs(err) <= hw[i])})
    return out
