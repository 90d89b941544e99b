"""Scalar Kalman filter on an effective leakage factor (random-walk parameter, linear measurement).

Model (SI)::

    k_{n} = k_{n-1} + w,   w ~ N(0, q · Δt)                 (slow drift: wear)
    y_n   = H_n · k_n + v, v ~ N(0, R_n)

with ``y`` the measured flow loss (theoretical − measured delivery flow [m³/s]) over a
settled interval and ``H`` the flow loss the model predicts there with the configured
(calibrated) leakage, so ``k = 1`` is "as calibrated".  The measurement is linear in
``k``, so the Kalman filter is exact (an EKF would linearise nothing); compared with
recursive least squares with a forgetting factor it has an explicit noise model, so the
reported standard deviation √P means something, and its covariance cannot wind up
during long stretches without information (RLS forgetting divides P by λ every step,
informative or not; here P grows only by q·Δt).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["LeakageEstimate", "predict", "update"]


@dataclass(frozen=True)
class LeakageEstimate:
    """The filter state: factor, variance, last innovation."""
    k: float = 1.0               #: leakage factor relative to the configured model [-]
    var: float = 0.25            #: its variance [-]
    t_s: float | None = None     #: time of the last update [s]
    innovation: float = 0.0      #: last normalised innovation (y − H k)/√(H²P + R) [-]
    updates: int = 0

    @property
    def sd(self) -> float:
        return math.sqrt(max(self.var, 0.0))


def predict(est: LeakageEstimate, t_s: float, drift_per_sqrt_s: float) -> LeakageEstimate:
    """Random-walk prediction to time ``t_s`` [s]: variance + drift² · Δt."""
    dt = 0.0 if est.t_s is None else max(0.0, t_s - est.t_s)
    return LeakageEstimate(est.k, est.var + drift_per_sqrt_s ** 2 * dt, t_s, est.innovation, est.updates)


def update(est: LeakageEstimate, y: float, h: float, r: float) -> LeakageEstimate:
    """Kalman update with measurement ``y`` [m³/s], regressor ``h`` [m³/s] and noise variance ``r`` [m⁶/s²]."""
    s = h * h * est.var + r
    if not (math.isfinite(s) and s > 0 and math.isfinite(y) and math.isfinite(h)):
        return est
    nu = y - h * est.k
    gain = est.var * h / s
    return LeakageEstimate(est.k + gain * nu, (1.0 - gain * h) * est.var, est.t_s, nu / math.sqrt(s),
                           est.updates + 1)
