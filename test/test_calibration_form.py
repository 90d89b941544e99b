"""Calibration on pumps that differ from the twin in form (issue 28): never worse than the nominal twin, and
prediction intervals that hold the model-form error.

Tier: closed form (the model-form error from held-out errors, the interval's parts, the hold-out verdict).
"""
import math

import numpy as np
import pytest
from scipy.stats import t as student_t

from gerotor_twin.calibration import prediction as P
from gerotor_twin.calibration.command import holdout_verdict


def test_model_form_error_and_interval_closed_form():
    """Closed form: held-out errors ±1, ±2 pt with a parameter variance of (0.316 pt)² each and no measurement
    variance → σ_d² = mean(e²) − 1e-5 = 2.5e-4 − 1e-5; the half-width at a point of parameter variance 4e-6 and
    measurement variance 1e-6 is t(0.975, 3)·√(4e-6 + 1e-6 + σ_d²); errors smaller than the parameters'
    share give σ_d = 0 (not negative)."""
    e = np.array([0.01, -0.01, 0.02, -0.02])
    form = P.model_form_error(e, np.full(4, 1e-5), np.zeros(4))
    assert form.sd ** 2 == pytest.approx(2.5e-4 - 1e-5, rel=1e-12) and form.held_out == 4 and form.dof == 3
    assert form.half_width(4e-6, 1e-6) == pytest.approx(student_t.ppf(0.975, 3) * math.sqrt(5e-6 + form.sd ** 2))
    assert P.model_form_error(np.array([1e-4, -1e-4]), np.full(2, 1e-6), np.zeros(2)).sd == 0.0
    g = np.array([[1.0, 0.0], [0.5, 2.0]])
    cov_x = np.array([[4.0, 1.0], [1.0, 9.0]])
    assert P.param_variance(g, cov_x).tolist() == pytest.approx([4.0, 0.25 * 4 + 2 * 0.5 * 2 * 1 + 4 * 9])


def test_holdout_verdict_closed_form():
    """Closed form (``--cv none``): the fit is kept only when its held-out η RMSE is below the nominal twin's;
    the message is one line saying which and why, with both figures."""
    def ho(fit, nominal):
        rows = lambda e: [{"eta_error": v} for v in e]          # noqa: E731
        stats = lambda e: {"rmse": float(np.sqrt(np.mean(np.square(e)))), "max_abs": float(np.max(np.abs(e)))}  # noqa: E731
        return {"held_out": ["b#2", "b#4"], "plateaus": rows(fit), "plateaus_prior": rows(nominal),
                "eta_error": stats(fit), "eta_error_prior": stats(nominal)}
    worse = holdout_verdict(ho([0.008, -0.009], [0.004, 0.005]), ("tip", "lateral"))
    assert not worse["calibrated"] and worse["chosen"] == [] and "\n" not in worse["message"]
    assert worse["message"].startswith("calibration refused") and "nominal values are kept" in worse["message"]
    assert "fitted 0.85 / 0.85 pt, nominal 0.45 / 0.45 pt" in worse["message"]
    better = holdout_verdict(ho([0.001, -0.001], [0.004, 0.005]), ("tip", "lateral"))
    assert better["calibrated"] and better["message"].startswith("calibration accepted: tip+lateral")
    unchecked = holdout_verdict(None, ("tip",))
    assert unchecked["calibrated"] and not unchecked["checked"]
