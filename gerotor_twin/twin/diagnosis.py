"""Fault classification from the signatures of the health monitor's settled windows (no ROS).

Each settled window of :class:`~gerotor_twin.twin.health.HealthMonitor` gives a :class:`WindowRecord`:
the operating point (speed, delivery and suction pressure, oil temperature), the measured and the
predicted mean delivery flow and the window's measurement noise.  The residual e = q_meas − q_pred
is compared with what each candidate fault would make of it.

Signatures (flow change per unit fault parameter, from the twin's own steady model at the window's
operating point, finite differences, cached per operating point by :class:`SteadySignatures`)
    ``tip_wear``         Q(tooth-tip clearance × (1 + h)) − Q
    ``lateral_wear``     Q(lateral clearance × (1 + h)) − Q          (gap leakage ∝ Δp/μ at any speed)
    ``air_ingress``      Q(free-air fraction + h_air) − Q             (more at low suction pressure, high speed)
    ``pressure_offset``  Q(p_delivery − δp) − Q                       (the transducer reads δp high: the loss
                                                                      does not follow the model's Δp dependence)
    ``flowmeter_drift``  q_pred                                       (a gain error, at any operating point)
A fault far beyond its step need not be linear in its size (8 % of free air fitted with the signature of 1 %
leaves χ² = 90 against the bound 31.6 on 12 windows at four operating points): with ``relinearise`` > 0 each perturbed kind's column is recomputed with the step set to
the size fitted (the secant from no fault to the fitted size, :meth:`SteadySignatures.relinearised`) and the
kind refitted, at most ``relinearise`` times (Gauss–Newton-like fixed-point iteration; stops when the rounded
size no longer changes).  The likelihood below is then that of the model linearised at the fitted size.
Each column is divided by its magnitude at the reference point (``reference_rpm``, ``reference_bar``) over
the theoretical flow there, so every kind's parameter θ is "flow change at the reference point / its
theoretical flow" [-] (a loss for wear and air ingress when θ > 0), with the same prior and the same drift.

Likelihood per kind
    θ starts from a prior N(0, ``prior_sd``²), grows at a constant rate r (faults develop: a ramp; with
    ``trend`` r ~ N(0, (``prior_sd`` / T)²), T the time spanned by the windows in view, so θ may cross its
    prior range within them; a step is r = 0) and drifts as a random walk (``drift_per_sqrt_s``
    [1/√s]): a Kalman filter on (θ, r) over the last ``horizon`` windows, e_i = θ_i·d_i + v_i,
    v_i ~ N(0, σ_i²).  The log-likelihood is the sum of the log predictive densities of the
    innovations (prediction-error decomposition); with zero drift it is the marginal likelihood
    log N(e; 0, diag σ² + prior_sd²·d dᵀ + (prior_sd/T)²·(d∘τ)(d∘τ)ᵀ), τ_i = t_i − t_0, of a Gaussian
    linear model, which penalises the fitted parameters (Occam factor) as BIC does asymptotically.  Without
    the trend a fault that grows by more than the random walk allows within the horizon (a ramp of
    several points in seconds) fits no kind and is ``unknown``.  A kind whose fitted θ has the sign the fault
    cannot have (a wear or air ingress that adds flow) beyond ``sign_sd`` standard deviations is
    excluded.  ``healthy``: e_i ~ N(0, σ_i²).  ``unknown``: e_i ~ N(0, (``unknown_scale``·σ_i)²).
    ``suction_restriction``: the flow residuals as ``healthy`` (the twin runs on the measured suction
    pressure, so the restriction's effect on the flow is in the prediction) times the likelihood ratio of
    the suction pressures falling with the flow against falling with the speed only
    (:func:`suction_log_ratio`; with ``trend`` the restriction's coefficient may grow in time as θ may);
    every other kind carries the suction pressures without that term.

Decision
    Probabilities: softmax of the log-likelihoods over the candidates (equal prior odds).  ``unknown``
    also when the best kind's innovations have χ² > n + ``chi2_z``·√(2n) (no kind explains the
    residuals), and when a flow kind wins on windows at fewer than two operating points (speed within
    ``point_speed_tol``, delivery pressure within ``point_pressure_pa``: :func:`operating_points`): there every kind fits the one residual and only the priors differ.
    The confidence of ``unknown`` is the probability of a fault (1 − that of ``healthy``).  A named flow kind
    comes with its closest candidate rival and their expected log-likelihood ratio (:func:`separation`); below
    2·``separable_z``² noise alone would reverse the call more often than Φ(−z) (10 %), and the naming is
    *tentative* (air ingress and a pressure offset at one speed; tip and lateral wear where the tip's Couette
    share is small).  ``speed_dropout`` is input accounting, not a flow signature: the fraction of shaft-speed
    samples missing over the horizon (:func:`missing_fraction`); above ``dropout_min`` it is named when
    the flow residuals are explained by ``healthy`` (confidence: that probability).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gerotor_twin.errors import InputError, check_int, check_ranges
from gerotor_twin.units import celsius_to_kelvin

__all__ = ["SpeedCounter", "suction_log_ratio", "WindowRecord", "DiagnosisSettings", "Diagnosis", "SteadySignatures", "FLOW_KINDS", "KINDS",
           "kind_log_likelihood", "fitted_residuals", "separation", "classify", "point_key", "operating_points", "missing_fraction", "KIND_CODES"]

#: fault kinds with a flow signature, in the order of the signature columns
FLOW_KINDS = ("tip_wear", "lateral_wear", "air_ingress", "pressure_offset", "flowmeter_drift")
#: every name the classifier can give; the index is the code published in ``twin/health`` (``fault``)
KINDS = ("healthy", *FLOW_KINDS, "suction_restriction", "speed_dropout", "unknown")
KIND_CODES = {k: i for i, k in enumerate(KINDS)}
#: sign θ can have (+1: the fault's own direction, a wear or air ingress that opens gaps / adds air; 0: either)
_SIGN = {"tip_wear": 1, "lateral_wear": 1, "air_ingress": 1, "pressure_offset": 0, "flowmeter_drift": 0}


@dataclass(frozen=True)
class WindowRecord:
    """One settled window of the health monitor (SI).

    Attributes
    ----------
    t_s : float
        End of the window [s].
    omega : float
        Mean shaft speed [rad/s].
    p_delivery, p_suction : float
        Mean delivery and suction pressure, absolute [Pa].
    oil_k : float or None
        Mean oil temperature [K] (None: the config's reference temperature).
    q_meas, q_pred, q_th : float
        Measured, predicted and theoretical mean delivery flow [m³/s].
    sd : float
        Standard deviation of q_meas − q_pred from measurement noise and model error [m³/s].
    speed_samples, speed_expected : int
        Shaft-speed samples received in the window and expected at the sensor's rate.
    """
    t_s: float
    omega: float
    p_delivery: float
    p_suction: float
    oil_k: float | None
    q_meas: float
    q_pred: float
    q_th: float
    sd: float
    speed_samples: int = 0
    speed_expected: int = 0

    @property
    def residual(self) -> float:
        """q_meas − q_pred [m³/s]."""
        return self.q_meas - self.q_pred


@dataclass(frozen=True)
class DiagnosisSettings:
    """Settings of the classifier (module doc); θ in fractions of the reference theoretical flow.

    ``horizon`` windows [-]; ``prior_sd`` [-] and ``drift_per_sqrt_s`` [1/√s] of θ; ``trend``: θ may also grow at
    a constant rate (prior standard deviation ``prior_sd`` / the windows' time span); ``unknown_scale`` [-] (noise
    factor of ``unknown``); ``chi2_z`` [-]; ``sign_sd`` [-]; ``dropout_min`` [-]; ``suction_sd_pa`` [Pa] (floor of
    the suction pressure's noise) and ``suction_prior_pa`` [Pa] (prior restriction drop at the largest flow);
    finite-difference steps ``rel_step`` [-] (clearance factor), ``air_step`` [-] (free-air fraction),
    ``pressure_step_pa`` [Pa]; ``relinearise`` [-]: at most this many re-linearisations of a kind's signature at
    its fitted size (0: the signatures at the steps only; module doc); ``point_speed_tol`` [-] (relative) and
    ``point_pressure_pa`` [Pa]: windows within both of each other are one operating point
    (:func:`operating_points`; the health monitor passes its steady-window tolerances); ``separable_z`` [-]: a named
    flow kind is firm when the windows separate it from every other candidate by an expected log-likelihood ratio
    of at least 2·z² (:func:`separation`; 1.2816: noise alone reverses the ratio's sign at most 10 % of the time),
    else tentative.
    """
    horizon: int = 30
    prior_sd: float = 0.2
    drift_per_sqrt_s: float = 0.002
    trend: bool = True
    unknown_scale: float = 4.0
    chi2_z: float = 4.0
    sign_sd: float = 3.0
    dropout_min: float = 0.05
    suction_sd_pa: float = 100.0
    suction_prior_pa: float = 5e4
    rel_step: float = 0.1
    air_step: float = 0.01
    pressure_step_pa: float = 1e5
    relinearise: int = 2
    point_speed_tol: float = 0.01
    point_pressure_pa: float = 5e4
    separable_z: float = 1.2816

    def __post_init__(self):
        check_ranges(self, "diagnosis_", (
            ("prior_sd", 1e-6, 10.0), ("drift_per_sqrt_s", 0.0, 1.0), ("unknown_scale", 1.01, 1e3), ("chi2_z", 0.0, 1e3),
            ("sign_sd", 0.0, 1e3), ("dropout_min", 0.0, 1.0), ("suction_sd_pa", 1e-3, 1e5), ("suction_prior_pa", 1.0, 1e6),
            ("rel_step", 1e-4, 1.0), ("air_step", 1e-5, 0.05), ("pressure_step_pa", 1.0, 1e6),
            ("point_speed_tol", 1e-4, 1.0), ("point_pressure_pa", 1.0, 1e7), ("separable_z", 0.0, 10.0)))
        check_int("diagnosis_horizon", self.horizon, 1, 10**5)
        check_int("diagnosis_relinearise", self.relinearise, 0, 10)
        if not isinstance(self.trend, bool):
            raise InputError("diagnosis_trend", self.trend, "true | false")


@dataclass(frozen=True)
class Diagnosis:
    """Result of :func:`classify`.

    Attributes
    ----------
    kind : str
        The named kind (:data:`KINDS`).
    confidence : float
        Its probability [-] (``unknown``: the probability of a fault; ``speed_dropout``: that of healthy flow).
    log_likelihood, probability, parameter : dict
        Per candidate: log-likelihood [-], probability [-], fitted θ [-] (suction restriction: b [Pa·s²/m⁶]).
    chi2 : float
        χ² of the best kind's normalised innovations [-].
    windows : int
        Windows used.
    dropout : float
        Fraction of the shaft-speed samples missing [-].
    rival : str
        When a flow kind is named: the candidate flow kind the windows separate least from it ('' otherwise).
    separation : float
        Their expected log-likelihood ratio (:func:`separation`) [-] (NaN: no rival).
    tentative : bool
        The separation is below 2·``separable_z``²: the windows cannot yet tell the named kind from ``rival``
        (the name is the more probable of the two, by the probability given).
    points : int
        Operating points among the windows (:func:`operating_points`) [-].
    """
    kind: str
    confidence: float
    log_likelihood: dict
    probability: dict
    parameter: dict
    chi2: float
    windows: int
    dropout: float = 0.0
    rival: str = ""
    separation: float = math.nan
    tentative: bool = False
    points: int = 0

    @property
    def code(self) -> int:
        """Index of :attr:`kind` in :data:`KINDS`."""
        return KIND_CODES[self.kind]


def point_key(rec: WindowRecord, rpm_step: float = 10.0, pressure_step_pa: float = 5e3,
              oil_step_k: float = 1.0) -> tuple:
    """The record's operating point rounded to ``rpm_step`` [rpm], ``pressure_step_pa`` [Pa] (delivery, suction)
    and ``oil_step_k`` [K]: (speed, delivery, suction, oil) in steps (oil None: the reference temperature)."""
    return (round(rec.omega * 30.0 / math.pi / rpm_step), round(rec.p_delivery / pressure_step_pa),
            round(rec.p_suction / pressure_step_pa), None if rec.oil_k is None else round(rec.oil_k / oil_step_k))


def operating_points(records, speed_tol: float, pressure_tol_pa: float) -> int:
    """Number of distinct operating points among ``records`` [-]: a record joins the first point found whose speed is
    within ``speed_tol`` (relative) [-] and delivery pressure within ``pressure_tol_pa`` [Pa] of the record that
    opened it, else it opens a new one (windows on one plateau are one point however the rounding of
    :func:`point_key` falls)."""
    points: list[WindowRecord] = []
    for r in records:
        if not any(abs(r.omega - q.omega) <= speed_tol * max(abs(q.omega), 1.0)
                   and abs(r.p_delivery - q.p_delivery) <= pressure_tol_pa for q in points):
            points.append(r)
    return len(points)


def kind_log_likelihood(e, d, sd, t_s, prior_sd: float, drift_per_sqrt_s: float,
                        rate_sd: float = 0.0) -> tuple[float, float, float, float]:
    """Log-likelihood of residuals ``e`` under e_i = θ_i·d_i + v_i, θ a trend plus a random walk (Kalman filter).

    θ_i = θ_0 + r·(t_i − t_0) + w_i: a fault that grows at a constant rate r (a ramp; r = 0 a step) and drifts
    (w a random walk), θ_0 ~ N(0, ``prior_sd``²), r ~ N(0, ``rate_sd``²).

    Parameters
    ----------
    e, d, sd, t_s : sequence of float
        Residuals [m³/s], signature per unit θ [m³/s], noise standard deviations [m³/s], times [s].
    prior_sd : float
        Prior standard deviation of θ [-].
    drift_per_sqrt_s : float
        Random-walk rate of θ [1/√s].
    rate_sd : float, optional
        Prior standard deviation of the growth rate r [1/s] (0: no trend, a scalar filter on θ).

    Returns
    -------
    tuple of float
        Log-likelihood [-], final θ [-] and its standard deviation [-], χ² of the normalised innovations [-].
    """
    x = np.zeros(2)                                        # θ [-], r [1/s]
    p = np.diag([prior_sd ** 2, rate_sd ** 2])
    ll = chi2 = 0.0
    t_prev = None
    for ei, di, si, ti in zip(e, d, sd, t_s):
        dt = 0.0 if t_prev is None else max(0.0, float(ti) - t_prev)
        t_prev = float(ti)
        f = np.array([[1.0, dt], [0.0, 1.0]])
        x, p = f @ x, f @ p @ f.T + np.diag([drift_per_sqrt_s ** 2 * dt, 0.0])
        h = np.array([float(di), 0.0])
        ph = p @ h
        s = float(h @ ph) + float(si) ** 2
        nu = float(ei) - float(h @ x)
        ll -= 0.5 * (nu * nu / s + math.log(2.0 * math.pi * s))
        chi2 += nu * nu / s
        gain = ph / s
        x, p = x + gain * nu, p - np.outer(gain, ph)
    return ll, float(x[0]), math.sqrt(max(float(p[0, 0]), 0.0)), chi2


def _white_log_likelihood(e, sd) -> float:
    e, sd = np.asarray(e, float), np.asarray(sd, float)
    return float(-0.5 * np.sum((e / sd) ** 2 + np.log(2.0 * math.pi * sd ** 2)))


class SpeedCounter:
    """Reception times of the accepted shaft-speed samples, for the count expected in a window.

    The sensor's period is the ``quantile`` of the intervals between the window's samples (the nominal one
    while fewer than 1 − ``quantile`` of them are missing); expected = window length / period.  When that
    period is below half the mean interval — samples received in bursts, or more than half of them missing —
    the reception times do not show the sensor's period and no count is expected.
    """

    def __init__(self, quantile: float = 0.25):
        self.quantile = quantile
        self._t: list[int] = []

    def add(self, receive_ns: int) -> None:
        self._t.append(int(receive_ns))

    def forget_after(self, now_ns: int) -> None:
        self._t = [t for t in self._t if t <= now_ns]

    def count(self, start_ns: int, end_ns: int) -> tuple[int, int]:
        """Samples received in [start_ns, end_ns) and the count expected at the sensor's period; forgets
        the samples before ``start_ns``."""
        self._t = [t for t in self._t if t >= start_ns]
        inside = [t for t in self._t if t < end_ns]
        if len(inside) < 3:
            return len(inside), 0
        gaps = np.diff(inside)
        period = float(np.quantile(gaps, self.quantile))
        if not period > 0.5 * float(np.mean(gaps)):
            return len(inside), 0
        return len(inside), int(round((end_ns - start_ns) / period))


def suction_log_ratio(records, sd_floor_pa: float, prior_pa: float, trend: bool = False) -> tuple[float, float]:
    """Log-likelihood ratio of a suction restriction against none, from the windows' suction pressures.

    Without restriction p_s = c − a·ω² (the suction line's drop ∝ speed²); a restriction adds − b·q²
    (its drop ∝ the intake flow², here the measured delivery flow, which at one speed falls with the
    delivery pressure), with ``trend`` b = b₀ + b₁·τ (a restriction that grows, as the flow kinds' θ may; τ
    the time since the first window).  Both fitted by least squares with a common noise σ profiled out, its
    variance floored at ``sd_floor_pa``² [Pa²]; the ratio carries the Occam factor ½·ln(1 + P_k / var k̂) of
    each restriction coefficient k, Gaussian priors with standard deviation P_b₀^½ = ``prior_pa`` [Pa] /
    (largest theoretical flow)² and P_b₁^½ = P_b₀^½ / T (T the windows' time span: b may cross its prior
    range within them, as the flow kinds' growth rate).

    Returns
    -------
    tuple of float
        Log-likelihood ratio [-] (−inf when the suction pressure never varies: no sensor) and the fitted
        b at the last window [Pa·s²/m⁶] (0 with fewer than 4 windows; the trend needs 5).
    """
    n = len(records)
    y = np.array([r.p_suction for r in records])
    if n < 4 or np.ptp(y) == 0.0:
        return -math.inf, 0.0
    t = np.array([r.t_s for r in records]) - records[0].t_s
    span = float(t[-1])
    trend = trend and span > 0.0 and n >= 5
    x0 = np.column_stack([np.ones(n), -np.array([r.omega for r in records]) ** 2])
    q2 = -np.array([r.q_meas for r in records]) ** 2
    x1 = np.column_stack([x0, q2, q2 * t] if trend else [x0, q2])
    rss = []
    for x in (x0, x1):
        coef = np.linalg.lstsq(x, y, rcond=None)[0]
        rss.append(float(np.sum((y - x @ coef) ** 2)) + n * sd_floor_pa ** 2)
    col = np.abs(x1).max(axis=0)
    col[col == 0] = 1.0                                                  # columns scaled: ω² ~ 1e5, q² ~ 1e-6
    cov = rss[1] / n * np.linalg.pinv((x1 / col).T @ (x1 / col)) / np.outer(col, col)
    prior_b = (prior_pa / max(r.q_th for r in records) ** 2) ** 2
    priors = (prior_b, prior_b / span ** 2) if trend else (prior_b,)
    occam = sum(0.5 * math.log1p(pk / max(float(cov[2 + i, 2 + i]), 1e-300)) for i, pk in enumerate(priors))
    b_last = float(coef[2] + (coef[3] * span if trend else 0.0))
    return 0.5 * n * math.log(rss[0] / rss[1]) - occam, b_last


def missing_fraction(records) -> float:
    """Fraction of the shaft-speed samples missing over ``records`` [-] (0 when none were expected)."""
    expected = sum(r.speed_expected for r in records)
    got = sum(r.speed_samples for r in records)
    return max(0.0, 1.0 - got / expected) if expected > 0 else 0.0


def fitted_residuals(e, d, sd, t_s, prior_sd: float, rate_sd: float = 0.0) -> np.ndarray:
    r"""The residuals a kind's model makes at its most probable size and growth [m³/s]:

    .. math:: \hat e_i = (\hat\theta_0 + \hat r\,\tau_i)\,d_i,\qquad \tau_i = t_i - t_0,

    (θ̂₀, r̂) the posterior mode of :func:`kind_log_likelihood`'s trend without the random walk (weighted least
    squares with the priors N(0, ``prior_sd``²), N(0, ``rate_sd``²); ``rate_sd`` 0: a step).  Arguments as
    :func:`kind_log_likelihood`'s."""
    d, w = np.asarray(d, float), 1.0 / np.asarray(sd, float)
    tau = np.asarray(t_s, float) - float(t_s[0])
    cols = np.column_stack([d, d * tau]) if rate_sd > 0 else d[:, None]
    prior = np.diag([prior_sd ** -2.0, rate_sd ** -2.0 if rate_sd > 0 else 0.0][:cols.shape[1]])
    a = cols * w[:, None]
    return cols @ np.linalg.solve(a.T @ a + prior, a.T @ (np.asarray(e, float) * w))


def separation(e, d_a, d_b, sd, t_s, prior_sd: float, drift_per_sqrt_s: float, rate_sd: float = 0.0) -> float:
    r"""How well the windows tell kind a from kind b: the expected log-likelihood ratio of a over b were a true
    as fitted [-].

    .. math:: \Delta = \ell_a(\hat e) - \ell_b(\hat e)

    with ê the residuals a fits (:func:`fitted_residuals`) and ℓ :func:`kind_log_likelihood` on them, noise-free.
    On residuals ê + v, v ~ N(0, diag σ²), the ratio of two Gaussian linear models is ≈ ½‖(I − P_b)(ê + v)‖²
    in the σ-weighted norm (P_b the projection on b's columns, a's columns reproducing ê): mean ≈ Δ, variance
    ≈ 2Δ, so the noise alone reverses its sign with a probability ≈ Φ(−√(Δ/2)).  Columns ``d_a``, ``d_b``
    [m³/s per unit θ]; the other arguments as :func:`kind_log_likelihood`'s.

    Notes
    -----
    Two kinds whose signatures are proportional over the windows (one operating point; or air ingress and a
    delivery-pressure offset at one speed, each the same flow change at every pressure there) give Δ ≈ 0 however
    large the fault: the data favour one of them by noise and by the models' small errors only.
    """
    fit = fitted_residuals(e, d_a, sd, t_s, prior_sd, rate_sd)
    ll = [kind_log_likelihood(fit, d, sd, t_s, prior_sd, drift_per_sqrt_s, rate_sd)[0] for d in (d_a, d_b)]
    return ll[0] - ll[1]


def _fit_kind(kind: str, recs, sigs, e, sd, t, s: DiagnosisSettings, rate_sd: float, relinearise=None):
    """:func:`kind_log_likelihood` of ``kind`` on the signature columns ``sigs``, re-linearised at the fitted
    size up to ``s.relinearise`` times by ``relinearise(recs, kind, θ, n)`` (the column at the size fitted with
    the column of n steps, and its size in steps; or None: keep this one); it stops when the size no longer
    changes.  Returns the fit and the column it was made with."""
    d, n = [g[kind] for g in sigs], 1.0
    fit = kind_log_likelihood(e, d, sd, t, s.prior_sd, s.drift_per_sqrt_s, rate_sd)
    for _ in range(s.relinearise if relinearise is not None else 0):
        new = relinearise(recs, kind, fit[1], n)
        if new is None or new[1] == n:
            break
        d, n = new
        fit = kind_log_likelihood(e, d, sd, t, s.prior_sd, s.drift_per_sqrt_s, rate_sd)
    return fit, d


def _closest_rival(kind: str, columns: dict, ll: dict, e, sd, t, s: DiagnosisSettings,
                   rate_sd: float) -> tuple[str, float]:
    """The candidate flow kind the windows separate least from ``kind`` and its :func:`separation` [-]."""
    seps = {k: separation(e, columns[kind], columns[k], sd, t, s.prior_sd, s.drift_per_sqrt_s, rate_sd)
            for k in FLOW_KINDS if k != kind and k in ll}
    return min(seps.items(), key=lambda kv: kv[1], default=("", math.nan))


def _decide(ll: dict, chi2: dict, recs, points: int, s: DiagnosisSettings) -> tuple[str, dict, str]:
    """The named kind (module doc, "Decision") on ``recs`` at ``points`` operating points, the candidates'
    probabilities and the most likely kind."""
    names = list(ll)
    v = np.array([ll[k] for k in names])
    p = np.exp(v - v.max())
    p /= p.sum()
    prob = dict(zip(names, p.tolist()))
    best = max((k for k in names if k != "unknown"), key=lambda k: ll[k])
    n = len(recs)
    kind = best if prob[best] >= prob["unknown"] else "unknown"
    if chi2[best] > n + s.chi2_z * math.sqrt(2.0 * n):
        kind = "unknown"
    if kind in FLOW_KINDS and points < 2:
        kind = "unknown"                     # one operating point: every kind fits it, only the priors differ
    return kind, prob, best


def classify(records, signatures, settings: DiagnosisSettings | None = None, relinearise=None) -> Diagnosis:
    """Name the fault that best explains the residuals of the last ``horizon`` windows.

    Parameters
    ----------
    records : sequence of WindowRecord
        Settled windows, oldest first.
    signatures : sequence of dict
        Per record, the signature of each of :data:`FLOW_KINDS` [m³/s per unit θ] (:class:`SteadySignatures`).
    settings : DiagnosisSettings, optional
    relinearise : callable, optional
        ``relinearise(records, kind, θ, n)``: the kind's signature per record [m³/s per unit θ] re-linearised at
        the size θ [-] fitted with the column of n finite-difference steps, with its own size in steps, or None
        where it keeps the one given (:meth:`SteadySignatures.relinearised`).
        Without it the signatures given are used as they are.

    Returns
    -------
    Diagnosis
        The named kind (:data:`KINDS`) and its confidence [-], every candidate's log-likelihood and
        probability, the fitted θ per kind [-], the best kind's χ² [-], the windows used and the fraction of
        speed samples missing [-].
    """
    s = settings or DiagnosisSettings()
    if len(records) != len(signatures):
        raise InputError("signatures", len(signatures), f"one per record ({len(records)})")
    recs, sigs = list(records)[-s.horizon:], list(signatures)[-s.horizon:]
    if not recs:
        return Diagnosis("unknown", 0.0, {}, {}, {}, math.nan, 0)
    e = [r.residual for r in recs]
    sd = [max(r.sd, 1e-15) for r in recs]
    t = [r.t_s for r in recs]
    ll = {"healthy": _white_log_likelihood(e, sd), "unknown": _white_log_likelihood(e, [s.unknown_scale * v for v in sd])}
    theta, chi2, columns = {}, {"healthy": float(sum((a / b) ** 2 for a, b in zip(e, sd)))}, {}
    span = t[-1] - t[0]
    rate_sd = s.prior_sd / span if s.trend and span > 0 else 0.0
    for kind in FLOW_KINDS:
        (ll_k, th, th_sd, chi2[kind]), columns[kind] = _fit_kind(kind, recs, sigs, e, sd, t, s, rate_sd, relinearise)
        theta[kind] = th
        if _SIGN[kind] and th * _SIGN[kind] < -s.sign_sd * th_sd:
            continue                                    # the fault cannot move the flow that way
        ll[kind] = ll_k
    ll["suction_restriction"], theta["suction_restriction"] = suction_log_ratio(recs, s.suction_sd_pa,
                                                                               s.suction_prior_pa, s.trend)
    ll["suction_restriction"] += ll["healthy"]       # the flow as predicted: the twin runs on the measured suction
    chi2["suction_restriction"] = chi2["healthy"]
    points = operating_points(recs, s.point_speed_tol, s.point_pressure_pa)
    kind, prob, best = _decide(ll, chi2, recs, points, s)
    rival, sep = _closest_rival(kind, columns, ll, e, sd, t, s, rate_sd) if kind in FLOW_KINDS else ("", math.nan)
    tentative = sep < 2.0 * s.separable_z ** 2            # the windows cannot yet tell it from ``rival``
    dropout = missing_fraction(recs)
    if kind == "healthy" and dropout > s.dropout_min:
        kind = "speed_dropout"
    conf = {"speed_dropout": prob["healthy"], "unknown": 1.0 - prob["healthy"]}.get(kind, prob.get(kind))
    return Diagnosis(kind, conf, ll, prob, theta, chi2[best], len(recs), dropout, rival, sep, tentative, points)


#: the kinds whose signature is a finite difference of the steady model: the setting that holds the step
_STEP = {"tip_wear": "rel_step", "lateral_wear": "rel_step", "air_ingress": "air_step",
         "pressure_offset": "pressure_step_pa"}


class SteadySignatures:
    """Signatures of :data:`FLOW_KINDS` at an operating point from the twin's steady model (cached).

    A private :class:`~gerotor_twin.model.pump.PumpModel` of the monitor's configured pump (same outer-gear
    model) runs :func:`~gerotor_twin.model.steady.run_steady` at the window's speed, pressures and oil
    temperature, as configured and with each perturbation; the cache key rounds the operating point to
    ``rpm_step`` [rpm], ``pressure_step_pa`` [Pa] and ``oil_step_k`` [K].  Columns are scaled by their
    value at the reference point (module doc), ``reference`` = (speed [rpm], delivery pressure [bar gauge], oil
    [°C] or None for the config's reference temperature; default the health monitor's default, which passes its
    own).
    :meth:`relinearised` gives a kind's column re-linearised at a fitted fault size (the finite difference taken
    with that size as its step).
    """

    def __init__(self, config, bearing: str = "mobility", settings: DiagnosisSettings | None = None,
                 reference: tuple = (1500.0, 20.0, 50.0), rpm_step: float = 10.0,
                 pressure_step_pa: float = 5e3, oil_step_k: float = 1.0):
        from gerotor_twin.model.pump import PumpModel
        self.config, self.settings = config, settings or DiagnosisSettings()
        self.model = PumpModel(config, bearing)
        self.steps = (rpm_step, pressure_step_pa, oil_step_k)
        self._cache: dict = {}
        self._sized: dict = {}
        self.p_atm = config.fluid.atmospheric_pa
        rpm, bar, *oil = reference         # oil [°C] or None: the config's reference temperature
        oil_k = None if not oil or oil[0] is None else celsius_to_kelvin(oil[0])
        self.reference_op = (rpm, self.p_atm + bar * 1e5, config.boundary.suction_pressure_pa, oil_k)
        ref = self._raw(self.reference_op)
        self._reference = ref["q0"], ref["q_th"]
        self.scale = {k: ref["q_th"] / abs(ref[k]) if ref[k] != 0 else 1.0 for k in FLOW_KINDS}
        self._sign = {k: -1.0 if ref[k] < 0 else 1.0 for k in FLOW_KINDS}

    def reference_loss(self, kind: str, theta: float) -> float:
        """Loss of volumetric efficiency at the reference point [-] of the fault ``kind`` fitted at θ [-].

        θ is the fault's flow change there over the theoretical flow, in the direction of its signature's
        step (module doc), so the loss is −θ times the sign of that step's flow change: θ itself for a wear or
        air ingress, −g·η_v for a meter gain g (θ = g·η_v)."""
        return -theta * self._sign[kind]

    def _q(self, op: tuple, kind: str | None = None, size: float = 0.0) -> tuple[float, float]:
        """Mean delivery and theoretical flow [m³/s] at ``op`` (rpm, delivery and suction pressure [Pa], oil [K]
        or None) as configured, or with the fault ``kind`` of ``size`` (its step's unit, :data:`_STEP`)."""
        from gerotor_twin.model.clearance_scale import scaled_config, take_config
        from gerotor_twin.model.steady import run_steady
        rpm, p_d, p_s, oil_k = op
        base = self.config
        cfg = {"tip_wear": lambda: scaled_config(base, tip=1.0 + size),
               "lateral_wear": lambda: scaled_config(base, lateral=1.0 + size),
               "air_ingress": lambda: scaled_config(base, air_fraction=base.air.air_fraction + size)}.get(kind)
        dp = size if kind == "pressure_offset" else 0.0
        if cfg is not None:
            take_config(self.model, cfg())
        try:
            res = run_steady(self.model, rpm, (p_d - self.p_atm - dp) / 1e5, p_suction=p_s, oil_temperature=oil_k)
        finally:
            if cfg is not None:
                take_config(self.model, base)
        return res.mean_delivery_flow_m3s, res.theoretical_flow_m3s

    def _step_change(self, op: tuple, q0: float, kind: str, h: float) -> float:
        """Flow change [m³/s] of one step h of ``kind`` at ``op``; where the step would leave the pump's range (a
        pressure offset at a delivery pressure below one step: an open-circuit lube pump near 0 bar), the step
        the other way, sign reversed — the column is a derivative, which either one-sided difference takes."""
        try:
            return self._q(op, kind, h)[0] - q0
        except InputError:
            return q0 - self._q(op, kind, -h)[0]

    def _raw(self, op: tuple) -> dict:
        """Unscaled flow changes [m³/s] per perturbation (of its step) at one operating point."""
        q0, qth = self._q(op)
        out = {k: self._step_change(op, q0, k, getattr(self.settings, step)) for k, step in _STEP.items()}
        out.update(flowmeter_drift=q0, q0=q0, q_th=qth)
        return out

    def _op(self, key: tuple) -> tuple:
        """The rounded operating point of a cache key: (rpm, delivery and suction pressure [Pa], oil [K] or None)."""
        rs, ps, ts = self.steps
        return key[0] * rs, key[1] * ps, key[2] * ps, None if key[3] is None else key[3] * ts

    def _point(self, rec: WindowRecord) -> tuple[tuple, dict]:
        """The record's cache key and the unscaled flow changes at its rounded operating point."""
        key = point_key(rec, *self.steps)
        raw = self._cache.get(key)
        if raw is None:
            raw = self._cache[key] = self._raw(self._op(key))
        return key, raw

    def __call__(self, rec: WindowRecord) -> dict:
        """Signature of each of :data:`FLOW_KINDS` at the record's operating point [m³/s per unit θ]."""
        raw = self._point(rec)[1]
        out = {k: raw[k] * self.scale[k] for k in FLOW_KINDS}
        out["flowmeter_drift"] = rec.q_pred * self.scale["flowmeter_drift"]
        return out

    def _change(self, key: tuple, q0: float, kind: str, n: float) -> float:
        """Flow change [m³/s] at the cache key's operating point (``"reference"``: the reference point) with the
        fault ``kind`` of ``n`` finite-difference steps (cached)."""
        change = self._sized.get((key, kind, n))
        if change is None:
            op = self.reference_op if key == "reference" else self._op(key)
            change = self._sized[(key, kind, n)] = self._q(op, kind, n * getattr(self.settings, _STEP[kind]))[0] - q0
        return change

    def relinearised(self, records, kind: str, theta: float, steps: float = 1.0) -> tuple[list[float], float] | None:
        """The signature of ``kind`` per record [m³/s per unit θ] re-linearised at the fitted size θ [-].

        θ is the flow change at the reference point over its theoretical flow; fitted with the column taken at
        ``steps`` (n, in finite-difference steps; 1: the linear signature), it corresponds to n' = θ / c(n)
        steps, c(n) the reference point's |flow change| / theoretical flow per step at n.  The column becomes
        the secant from no fault to n' steps, (Q(n') − Q) at each record's operating point scaled by
        theoretical flow / (Q(n') − Q) at the reference point times the sign of one step's flow change there, so
        that θ keeps its meaning (and its prior) on either side of no fault (a pressure offset read low: n' < 0).
        n' is rounded to a quarter octave (2^(j/4)) so that nearby fits share the cached steady runs.  None —
        keep the linear column — for the flow-meter gain (linear), within one step (|n'| ≤ 1: the finite
        difference interpolates there), in the direction the fault cannot have (:data:`_SIGN`), beyond a loss of
        the whole theoretical flow (|θ| > 1), and where the steady model refuses the size (outside the
        config's ranges).

        Returns
        -------
        tuple or None
            The column per record and n'.
        """
        if kind not in _STEP or not abs(theta) <= 1.0 or (_SIGN[kind] and theta * _SIGN[kind] < 0):
            return None
        q0_ref, qth_ref = self._reference
        try:
            per_step = (abs(self._change("reference", q0_ref, kind, steps)) / abs(steps) / qth_ref
                        if steps != 1.0 else 1.0 / self.scale[kind])
            n = theta / per_step
            if not abs(n) > 1.0:
                return None
            n = math.copysign(2.0 ** (round(4.0 * math.log2(abs(n))) / 4.0), n)
            ref = self._change("reference", q0_ref, kind, n)
            if not abs(ref) > 0.0:
                return None                     # the fault moves no flow at the reference point: θ has no scale
            scale = qth_ref * self._sign[kind] / ref    # θ in the unit step's direction, whichever way n goes
            out = []
            for rec in records:
                key, raw = self._point(rec)
                out.append(self._change(key, raw["q0"], kind, n) * scale)
        except InputError:
            return None
        return out, n
