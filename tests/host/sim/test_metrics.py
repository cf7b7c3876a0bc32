"""J_A, J_w, J (paper 001 eq. 6-8, 25-27) on synthetic sequences computed by hand."""
import numpy as np
import pytest

from host.core.constants import DEG
from host.errors import HostError
from host.sim.metrics import ImagingPlan, StaringMetrics, average_metrics, staring_metrics


def synthetic():
    t = np.arange(7) * 0.5                           # 0, 0.5, ..., 3 s
    A_deg = np.stack([t, -np.ones_like(t), np.zeros_like(t)], -1)
    A_deg[:2] = 1e3                                  # before t_first: must not count
    w_deg = np.tile([0.1, 0.0, 0.0], (7, 1))
    w_deg[:2] = -1e3
    return t, A_deg * DEG, w_deg * DEG


def test_hand_computed_value():
    # windows [1, 2] and [2, 3], 3 samples each (p = 2), the sample at t = 2 counted in both:
    # sum|A| = (1 + 1.5 + 2 + 3*1) + (2 + 2.5 + 3 + 3*1) = 18  ->  J_A = 18 / (3*2*3) = 1
    # sum|w| = 6 * 0.1 = 0.6  ->  J_w = 0.6 / 18 = 1/30;   J = 1 + 5/30
    t, A, w = synthetic()
    m = staring_metrics(t, A, w, ImagingPlan(T_img=1.0, t_first=1.0))
    assert (m.m, m.p) == (2, 2)
    assert m.J_A == pytest.approx(1.0, rel=1e-14)
    assert m.J_w == pytest.approx(1 / 30, rel=1e-14)
    assert m.J == pytest.approx(1 + 5 / 30, rel=1e-14)


def test_weights_and_units():
    t, A, w = synthetic()
    m = staring_metrics(t, A, w, ImagingPlan(1.0, 1.0), k1=2.0, k2=0.0)
    assert m.J == pytest.approx(2.0)
    # metrics are in degrees: a constant 1 arcsec error gives J_A = 1/3600
    n = 101
    tt = np.linspace(0, 10, n)
    m = staring_metrics(tt, np.full((n, 3), DEG / 3600), np.zeros((n, 3)), ImagingPlan(1.0, 0.0))
    assert m.J_A == pytest.approx(1 / 3600, rel=1e-12) and m.J_w == 0 and m.m == 10 and m.p == 10


def test_partial_last_window_is_not_an_image():
    t = np.arange(0, 3.51, 0.5)
    m = staring_metrics(t, np.zeros((len(t), 3)), np.zeros((len(t), 3)), ImagingPlan(1.0, 1.0))
    assert m.m == 2   # [1,2], [2,3]; [3, 4] would run past the end


def test_no_window_fits_is_a_user_error():
    t = np.arange(0, 5.01, 0.5)
    with pytest.raises(HostError):
        staring_metrics(t, np.zeros((len(t), 3)), np.zeros((len(t), 3)), ImagingPlan(1.0, 10.0))


def test_average_over_targets_eq25_27():
    runs = [StaringMetrics(1.0, 0.1, 1.5), StaringMetrics(3.0, 0.3, 4.5)]
    avg = average_metrics(runs)
    assert (avg.J_A, avg.J_w) == (2.0, pytest.approx(0.2))
    assert avg.J == pytest.approx(3.0)   # mean of J_i = k1*mean J_A + k2*mean J_w
