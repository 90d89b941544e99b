"""The sub-step controller's named parts (:mod:`gerotor_twin.model.step_control`): closed-form tests.

The error scale and the weights have their own tests (``test_error_scale.py``, ``test_kernel.py``); here the
norm and the step-size factor, against the standard controller of Hairer, Nørsett & Wanner (I, II.4,
eq. (4.13)) with the embedded solution of order q̂ = 1: fac = 0.9·‖e‖^(−1/2), clipped to [0.2, 4].
"""
import math

import numpy as np
import pytest

from gerotor_twin.model import step_control as SC


@pytest.mark.parametrize("en,want", [(1.0, 0.9), (0.81, 1.0), (0.09, 3.0), (0.01, 4.0), (1e-12, 4.0),
                                     (0.0, 4.0), (4.0, 0.45), (1e4, 0.2), (math.inf, 0.2), (math.nan, 0.2)])
def test_step_factor(en, want):
    """Closed form: 0.9/√en within [0.2, 4]; 4 when the norm is ~0, 0.2 when it is not finite."""
    assert SC.step_factor(en) == pytest.approx(want, rel=1e-15)


def test_step_factor_puts_the_next_error_at_the_safety_factor_squared():
    """Closed form: for an error ∝ h² (q̂ = 1) the next sub-step's norm is 0.81 whatever this one's was
    (inside the clipping range)."""
    for en in (0.1, 0.5, 1.0, 2.0, 10.0):
        assert en * SC.step_factor(en) ** 2 == pytest.approx(SC.SAFETY ** 2, rel=1e-12)


def test_error_norm_is_the_largest_weighted_error_and_never_accepts_nan():
    err = np.array([1e-3, -4e-3, 2e-3, 0.0])
    wt = np.array([100.0, 200.0, 500.0, 0.0])
    assert SC.error_norm(err, wt) == pytest.approx(1.0, rel=1e-15)      # max(0.1, 0.8, 1.0, 0)
    assert SC.error_norm(np.zeros(4), wt) == 0.0
    err[3] = math.nan
    assert math.isnan(SC.error_norm(err, wt))                            # rejected, then shrunk by 0.2
    err[3] = 0.0
    err[0] = math.inf
    assert SC.error_norm(err, wt) == math.inf
