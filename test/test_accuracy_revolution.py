"""A reference revolution read at another run's angles (``accuracy.Revolution.at``).

Closed form: a reference whose chamber j holds p = 1000·j + 10·φ [Pa] (φ the angle within the revolution) is read
back exactly where it is linear in φ, its columns relabelled by the revolutions between the two runs (chambers
turn with the outer gear: k revolutions later chamber j sits where chamber j − k was), and periodically across
the end of the revolution.
"""
import math

import numpy as np
import pytest

from gerotor_twin.model.accuracy import Revolution

TWO_PI = 2 * math.pi
N, SAMPLES, REV0 = 7, 48, 5


def reference() -> Revolution:
    """Samples at φ = 2π(i+1)/SAMPLES, i = 0 … SAMPLES−1, of revolution REV0."""
    phi = TWO_PI * np.arange(1, SAMPLES + 1) / SAMPLES
    p = 1000.0 * np.arange(N)[None, :] + 10.0 * phi[:, None]
    return Revolution(TWO_PI * REV0 + phi, p, 2.0 * phi, 0.9, 1e-4, float(p.max()))


@pytest.mark.parametrize("k", [0, 1, 3, N + 2, -1, -N - 4])
def test_at_relabels_the_chambers_by_the_revolutions_between_the_runs(k):
    """Closed form: at angles k revolutions after the reference's, inside its samples (linear there), column j
    reads 1000·((j − k) mod N) + 10·φ and the flow 2φ."""
    ref = reference()
    phi = np.linspace(TWO_PI / SAMPLES, TWO_PI, 61)
    p, q = ref.at(TWO_PI * (REV0 + k) + phi)
    want = 1000.0 * ((np.arange(N)[None, :] - k) % N) + 10.0 * phi[:, None]
    np.testing.assert_allclose(p, want, rtol=0, atol=1e-9)
    np.testing.assert_allclose(q, 2.0 * phi, rtol=0, atol=1e-12)


def test_at_wraps_below_the_first_sample_to_the_revolutions_end():
    """Closed form: between the revolution's last sample (φ = 2π) and its first (2π/SAMPLES), the reference is
    interpolated across the end of the revolution, from p(2π) to p(2π/SAMPLES)."""
    ref = reference()
    h = TWO_PI / SAMPLES
    phi = np.array([1e-6 * h, 0.25 * h, 0.5 * h, 0.999 * h])
    p, q = ref.at(TWO_PI * (REV0 + 2) + phi)
    w = phi / h                                        # weight of the first sample
    want = 1000.0 * ((np.arange(N)[None, :] - 2) % N) + (10.0 * (1 - w) * TWO_PI + 10.0 * w * h)[:, None]
    np.testing.assert_allclose(p, want, rtol=0, atol=1e-9)
    np.testing.assert_allclose(q, 2.0 * ((1 - w) * TWO_PI + w * h), rtol=0, atol=1e-12)
