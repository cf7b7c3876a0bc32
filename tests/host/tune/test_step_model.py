"""The PD step model (host.tune.step_model) against analytic truth: a critically damped continuous
loop settles (5 %) at ω_n·t = 4.7439 (root of (1 + x)·e^(−x) = 0.05) and never overshoots; an
underdamped one overshoots by exp(−πζ/√(1−ζ²)); the fitted PD + feed-forward law's gains are the
minus of its diagonal; the inverse design settles where asked."""
from __future__ import annotations

import math

import numpy as np
import pytest

from host.core.constants import DEG
from host.errors import HostError
from host.tune.step_model import gains_for_settling, pd_step_response, pdff_gains, predicted_step

CRITICAL_X = 4.743864518    # (1 + x)·e^(−x) = 0.05


def _gains(wn: float, zeta: float, inertia: float) -> tuple[float, float]:
    return inertia * wn * wn * DEG, 2.0 * zeta * inertia * wn * DEG    # N·m/°, N·m/(°/s)


def test_a_critically_damped_loop_settles_at_the_analytic_time():
    I, wn, T = 500.0, 1.0, 0.001
    kp, kd = _gains(wn, 1.0, I)
    m = predicted_step([kp] * 3, [kd] * 3, [I] * 3, period=T, duration=45.0)
    assert all(abs(s - CRITICAL_X / wn) < 0.02 for s in m["settling_s"]), m
    assert m["overshoot_pct"] == [0.0, 0.0, 0.0]


def test_an_underdamped_loop_overshoots_as_the_second_order_formula():
    I, wn, zeta = 300.0, 1.5, 0.3
    kp, kd = _gains(wn, zeta, I)
    t, d = pd_step_response(kp, kd, I, period=0.0005, duration=90.0)
    expected = math.exp(-math.pi * zeta / math.sqrt(1 - zeta * zeta)) * 100.0
    overshoot = (max(-d) / 0.005 - 1.0) * 100.0
    assert abs(overshoot - expected) < 0.2, (overshoot, expected)
    assert abs(d[-1] + 0.005) < 1e-9


def test_pdff_gains_are_the_minus_of_the_diagonal():
    coef = np.zeros((10, 3))
    coef[0:3] = -np.diag([11.0, 12.0, 13.0]) + 0.5
    coef[3:6] = -np.diag([31.0, 32.0, 33.0]) - 0.25
    kp, kd = pdff_gains(coef)
    assert np.allclose(kp, [10.5, 11.5, 12.5]) and np.allclose(kd, [31.25, 32.25, 33.25])
    with pytest.raises(HostError, match=r"\(10, 3\)"):
        pdff_gains(np.zeros((9, 3)))


def test_the_inverse_design_settles_where_asked():
    I = 305.0
    kp, kd = gains_for_settling(3.0, I)
    settle = predicted_step([kp] * 3, [kd] * 3, [I] * 3)["settling_s"][0]
    assert 2.8 <= settle <= 3.0
    with pytest.raises(HostError, match="Kp > 0"):
        pd_step_response(0.0, 1.0, I)
