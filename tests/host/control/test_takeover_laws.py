"""Paper 004's host laws: the baseline against a hand-written PD, the GP law's mean subtraction, the gains
between their bounds and rising with the variance, the torque limit, bad input refused."""
import numpy as np
import pytest

from host.control import takeover_laws as tl
from host.errors import HostError
from host.plant.spacecraft import TABLE6_INERTIA


class FixedPredictor:
    """A stand-in GP: returns the same mean and variance everywhere, and remembers its input."""

    def __init__(self, mean, var):
        self.mean, self.var, self.seen = np.asarray(mean, float), np.asarray(var, float), None

    def predict(self, x):
        self.seen = np.array(x)
        return self.mean, self.var


Q = np.array([0.02, -0.03, 0.01, np.sqrt(1 - 0.02**2 - 0.03**2 - 0.01**2)])
W = np.array([0.001, -0.002, 0.0015])
HW = np.array([5.0, -3.0, 2.0])


def _by_hand(k1, k2, q, w, hw):
    J = TABLE6_INERTIA
    return -k1 * q[:3] - k2 * w + np.cross(w, J @ w + hw)


def test_baseline_is_the_quaternion_pd_with_the_prior_gyroscopic_term():
    out = tl.BaselineLaw()(Q, W, HW)
    np.testing.assert_allclose(out.torque, _by_hand(4.0, 72.0, Q, W, HW), atol=1e-14)
    np.testing.assert_array_equal(out.gains, [4.0, 72.0])
    # the other sign of the same attitude gives the same torque (q4 >= 0 chosen)
    np.testing.assert_allclose(tl.BaselineLaw()(-Q, W, HW).torque, out.torque, atol=1e-14)


def test_gp_law_with_zero_variance_is_the_baseline_minus_the_mean():
    mu = np.array([0.03, -0.01, 0.02])
    pred = FixedPredictor(mu, np.zeros(3))
    out = tl.GpLaw(pred, prior_variance=np.ones(3))(Q, W, HW)
    np.testing.assert_allclose(out.torque, _by_hand(4.0, 72.0, Q, W, HW) - mu, atol=1e-14)
    np.testing.assert_allclose(pred.seen, np.concatenate([Q[:3], W, np.zeros(3)]))   # ω̇ = 0
    np.testing.assert_array_equal(out.mu, mu)


@pytest.mark.parametrize("frac", [0.0, 0.25, 0.5, 1.0, 3.0])
def test_gains_are_affine_in_the_largest_variance_fraction_and_bounded(frac):
    prior = np.array([0.04, 0.01, 0.09])
    var = prior * np.array([0.1, frac, 0.05])               # axis y carries the largest fraction
    out = tl.GpLaw(FixedPredictor(np.zeros(3), var), prior)(Q, W, HW)
    s = min(max(frac, 0.1), 1.0)
    np.testing.assert_allclose(out.gains, [4.0 + 12.0 * s, 72.0 + 72.0 * s], rtol=1e-14)
    assert 4.0 <= out.gains[0] <= 16.0 and 72.0 <= out.gains[1] <= 144.0
    np.testing.assert_allclose(out.torque, _by_hand(*out.gains, Q, W, HW), atol=1e-14)


def test_gains_rise_monotonically_with_the_variance():
    prior = np.ones(3)
    gains = [tl.GpLaw(FixedPredictor(np.zeros(3), [v, 0, 0]), prior)(Q, W, HW).gains for v in
             np.linspace(0, 1.5, 16)]
    g = np.array(gains)
    assert np.all(np.diff(g, axis=0) >= 0) and g[0, 0] == 4.0 and g[-1, 0] == 16.0


def test_nan_variance_means_the_upper_gains_and_nan_mean_compensates_nothing():
    out = tl.GpLaw(FixedPredictor([np.nan, 0, 0], [np.nan, 0, 0]), np.ones(3))(Q, W, HW)
    np.testing.assert_array_equal(out.gains, [16.0, 144.0])
    np.testing.assert_allclose(out.torque, _by_hand(16.0, 144.0, Q, W, HW), atol=1e-14)


def test_torque_is_limited_per_axis():
    q = np.array([0.5, -0.5, 0.5, 0.5])
    out = tl.BaselineLaw()(q, np.array([0.05, 0.0, -0.05]), np.zeros(3))
    assert np.max(np.abs(out.torque)) == 1.0
    out = tl.GpLaw(FixedPredictor([5.0, -5.0, 0.0], np.zeros(3)), np.ones(3))(Q, W, HW)
    np.testing.assert_allclose(out.torque[:2], [-1.0, 1.0])


@pytest.mark.parametrize("prior", [np.zeros(3), np.ones(2), [1.0, np.inf, 1.0], [-1.0, 1.0, 1.0]])
def test_bad_prior_variance_is_refused(prior):
    with pytest.raises(HostError, match="prior_variance"):
        tl.GpLaw(FixedPredictor(np.zeros(3), np.zeros(3)), prior)


def test_bad_gains_and_predictor_are_refused():
    with pytest.raises(HostError):
        tl.Gains(k1=20.0)
    with pytest.raises(HostError, match="predict"):
        tl.GpLaw(object(), np.ones(3))
