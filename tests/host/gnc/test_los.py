"""LOS measurement and desired state of paper 002: eq. (2) against central finite differences of the
two-body truth, the analytic LOS rates and the desired-state derivatives against finite differences,
the record packing."""
import math

import numpy as np
import pytest

from codegen.units.rbf.records import INPUT_DTYPE
from host.core.rotations import dcm_from_euler312, dcm_from_quat, los_frame
from host.gnc import los
from host.plant import proximity as px

PLANT = px.ProximityPlant()
FORCE = (30.0, -12.0, 18.0)       # N, body axes, held (applied directly: no dead zone here)


def _state_with_relative_motion():
    """Truth at t = 250 s: chaser 180 m from the target with a relative velocity, rotating body."""
    target = px.circular_orbit_state()
    q = np.array([0.2, -0.1, 0.4, 0.85])
    q /= np.linalg.norm(q)
    rel = np.array([120.0, 60.0, -120.0])                 # target - chaser
    return [*target, *(target[:3] - rel), *(target[3:] - [0.4, -0.7, 0.3]), *q, 0.01, -0.02, 0.015]


def _propagate(y, t0, span, steps=5):
    h = span / steps
    for k in range(steps):
        y = PLANT.rk4_step(t0 + k * h, y, h, FORCE, (0.0, 0.0, 0.0))
    return y


def _los_of(y):
    r, v = px.relative_state(y)
    return los.los_kinematics(r, v)


def test_los_rates_against_finite_differences_of_the_truth():
    y0, t0, H = _state_with_relative_motion(), 250.0, 0.005
    plus, minus = _propagate(y0, t0, H), _propagate(y0, t0, -H)
    numeric = (_los_of(plus)[0] - _los_of(minus)[0]) / (2 * H)
    np.testing.assert_allclose(_los_of(y0)[1], numeric, rtol=1e-6)


def test_eq2_against_central_differences_of_two_body_truth():
    """rho'', q_eps'', q_beta'' of the truth (central differences of the exact LOS rates along an RK4
    trajectory) equal eq. (2) with f + Delta_g - u_c (u_c the chaser's thrust acceleration, LOS axes)."""
    y0, t0, H = _state_with_relative_motion(), 250.0, 0.005
    plus, minus = _propagate(y0, t0, H), _propagate(y0, t0, -H)
    numeric = (_los_of(plus)[1] - _los_of(minus)[1]) / (2 * H)
    angles, rates, _ = _los_of(y0)
    y = np.asarray(y0)
    g = lambda r: -px.MU_EARTH * r / np.linalg.norm(r) ** 3           # noqa: E731
    delta_g = g(y[0:3]) - g(y[6:9])
    u_c = dcm_from_quat(y[12:16]).T @ np.asarray(FORCE) / PLANT.mass   # inertial
    accel_los = los_frame(angles[1], angles[2]) @ (np.asarray(PLANT.manoeuvre(t0)) + delta_g - u_c)
    formula = los.los_acceleration_eq2(angles, rates, accel_los)
    np.testing.assert_allclose(formula, numeric, rtol=1e-6)
    # the check has teeth: Delta_g alone is far above the tolerance, and flipping u_c's sign fails
    assert np.all(np.abs(los.los_acceleration_eq2(angles, rates, accel_los - los_frame(angles[1], angles[2]) @ delta_g)
                         - numeric) > 1e-6 * np.abs(numeric))
    wrong = los.los_acceleration_eq2(angles, rates, accel_los + 2 * los_frame(angles[1], angles[2]) @ u_c)
    assert np.all(np.abs(wrong - numeric) > 1e-3 * np.abs(numeric))


def test_los_kinematics_second_derivatives_equal_eq2():
    rng = np.random.default_rng(7)
    for _ in range(50):
        r, v, a = rng.normal(size=3) * 100, rng.normal(size=3), rng.normal(size=3) * 0.01
        angles, rates, accs = los.los_kinematics(r, v, a)
        np.testing.assert_allclose(los.los_acceleration_eq2(angles, rates, los_frame(angles[1], angles[2]) @ a),
                                   accs, rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("t", [0.0, 111.1, 359.95, 720.0])
def test_desired_state_derivatives_against_finite_differences(t):
    h = 1e-3
    d, dp, dm = los.desired_state(PLANT, t), los.desired_state(PLANT, t + h), los.desired_state(PLANT, t - h)
    def fd(name):
        diff = los.wrap(getattr(dp, name) - getattr(dm, name))          # q_beta_d may wrap between t -+ h
        return diff / (2 * h)
    np.testing.assert_allclose(d.los_d_rate, fd("los_d"), atol=1e-10)
    np.testing.assert_allclose(d.los_d_acc, fd("los_d_rate"), atol=1e-10)
    np.testing.assert_allclose(d.euler_d_rate, fd("euler_d"), atol=1e-10)
    np.testing.assert_allclose(d.euler_d_acc, fd("euler_d_rate"), atol=1e-10)
    assert np.any(np.abs(d.los_d_rate[1:]) > 1e-3)                   # the desired LOS really moves


def test_desired_los_looks_along_minus_the_feature_and_attitude_is_the_los_frame():
    t = 321.0
    d = los.desired_state(PLANT, t)
    C_ld = los_frame(d.los_d[1], d.los_d[2])
    np.testing.assert_allclose(C_ld[0], -PLANT.tumble.feature(t), atol=1e-14)
    np.testing.assert_allclose(dcm_from_euler312(d.euler_d), C_ld, atol=1e-14)
    assert d.los_d[0] == 100.0 and -math.pi <= d.los_d[2] <= math.pi
    assert abs(d.los_d[1]) <= 20.0 * math.pi / 180 + 1e-12           # the tumble keeps |q_eps_d| <= 20 deg


def test_record_round_trip_is_the_float32_measurement():
    m = los.measure(PLANT, 10.0, _state_with_relative_motion())
    rec = los.to_record(m)
    assert rec.dtype == INPUT_DTYPE and rec.shape == (1,)
    back = los.from_record(rec)
    for name in INPUT_DTYPE.names:
        np.testing.assert_array_equal(getattr(back, name), np.float32(getattr(m, name)).astype(float))
