"""Rigid body + reaction wheels (eq. 3-5) against conservation laws and independent formulas."""
import numpy as np

from host.core import rotations as rot
from host.plant.spacecraft import (TABLE6, TABLE6_INERTIA, inertial_angular_momentum, momentum_limited_torque,
                             pack_state, rk4_step, rotational_energy, saturate_torque, state_derivative)
from host.core.vec3 import cross3, dcm_from_quat3, quat_rate3

RNG = np.random.default_rng(7)
I = TABLE6_INERTIA
I_INV = np.linalg.inv(I)


def test_table6_inertia_follows_eq5_signs():
    expected = np.array([[797.34, -14.3, -25.1], [-14.3, 304.86, -10.5], [-25.1, -10.5, 792.48]])
    np.testing.assert_array_equal(I, expected)
    assert np.all(np.linalg.eigvalsh(I) > 0)


def test_fast_helpers_match_numpy_and_rotations():
    for _ in range(50):
        a, b = RNG.normal(size=3), RNG.normal(size=3)
        np.testing.assert_allclose(cross3(a, b), np.cross(a, b), rtol=0, atol=1e-15)
        q = RNG.normal(size=4)
        q /= np.linalg.norm(q)
        np.testing.assert_allclose(quat_rate3(q, a), rot.quat_rate(q, a), rtol=0, atol=1e-15)
        np.testing.assert_allclose(dcm_from_quat3(q), rot.dcm_from_quat(q), rtol=0, atol=1e-15)


def _tumble(x0, seconds, dt=0.02, M_c=lambda t: np.zeros(3)):
    x, out = x0.copy(), [x0.copy()]
    for k in range(int(round(seconds / dt))):
        x = rk4_step(x, M_c(k * dt), np.zeros(3), dt, I, I_INV)
        out.append(x)
    return np.array(out)


def _H_inertial(x):
    return inertial_angular_momentum(x, I, rot.dcm_from_quat(x[0:4]))


def test_torque_free_rigid_body_conserves_momentum_and_energy():
    q0 = rot.quat_normalise(RNG.normal(size=4))
    x0 = pack_state(q0, [0.05, -0.08, 0.03], np.zeros(3))  # tumbling about no principal axis
    xs = _tumble(x0, 100.0)
    H0, E0 = _H_inertial(xs[0]), rotational_energy(xs[0], I)
    H_err = max(np.linalg.norm(_H_inertial(x) - H0) for x in xs[::50]) / np.linalg.norm(H0)
    E_err = max(abs(rotational_energy(x, I) - E0) for x in xs[::50]) / E0
    assert H_err <= 1e-9 and E_err <= 1e-9, (H_err, E_err)
    # it really tumbles: the body rate changes direction by a lot
    w0, w1 = xs[0][4:7], xs[-1][4:7]
    assert np.degrees(np.arccos(w0 @ w1 / np.linalg.norm(w0) / np.linalg.norm(w1))) > 20


def test_spinning_wheels_gyrostat_conserves_momentum_and_energy():
    # M_c = 0: wheels keep their relative momentum; H = L_ib (I w + h) and 1/2 w'Iw are constant
    x0 = pack_state(rot.quat_normalise(RNG.normal(size=4)), [0.04, 0.06, -0.05], [3.0, -5.0, 2.0])
    xs = _tumble(x0, 100.0)
    H0, E0 = _H_inertial(xs[0]), rotational_energy(xs[0], I)
    H_err = max(np.linalg.norm(_H_inertial(x) - H0) for x in xs[::50]) / np.linalg.norm(H0)
    E_err = max(abs(rotational_energy(x, I) - E0) for x in xs[::50]) / E0
    assert H_err <= 1e-9 and E_err <= 1e-9, (H_err, E_err)
    np.testing.assert_allclose(xs[-1][7:10], [3.0, -5.0, 2.0], rtol=0, atol=0)


def test_wheel_torque_exchanges_momentum_without_changing_the_total():
    # internal torque moves momentum from the wheels to the body; the inertial total stays put
    x0 = pack_state(rot.quat_normalise(RNG.normal(size=4)), [0.01, -0.02, 0.015], [1.0, 0.5, -0.5])
    xs = _tumble(x0, 100.0, M_c=lambda t: 0.2 * np.array([np.sin(0.3 * t), np.cos(0.2 * t), -0.5]))
    H0 = _H_inertial(xs[0])
    H_err = max(np.linalg.norm(_H_inertial(x) - H0) for x in xs[::50]) / np.linalg.norm(H0)
    assert H_err <= 1e-9, H_err
    assert np.linalg.norm(xs[-1][7:10] - xs[0][7:10]) > 5.0   # wheels did take momentum


def test_constant_torque_spin_up_about_a_principal_axis_matches_closed_form():
    # diagonal inertia, torque and rate on z: w_z(t) = w0 + M t / Iz, angle = w0 t + M t^2/(2 Iz)
    Id = np.diag([10.0, 20.0, 30.0])
    x = pack_state([0, 0, 0, 1.0], [0, 0, 0.01], np.zeros(3))
    M = np.array([0, 0, 0.3])
    for _ in range(500):
        x = rk4_step(x, M, np.zeros(3), 0.02, Id, np.linalg.inv(Id))
    t = 10.0
    assert abs(x[6] - (0.01 + 0.3 * t / 30.0)) < 1e-12
    angle = 0.01 * t + 0.3 * t**2 / 60.0
    # quaternion of a rotation about z by angle (frame inertial -> body): [0, 0, sin(a/2), cos(a/2)]
    np.testing.assert_allclose(x[0:4], [0, 0, np.sin(angle / 2), np.cos(angle / 2)], atol=1e-10)
    np.testing.assert_allclose(x[7:10], -M * t, atol=1e-12)


def test_state_derivative_is_eq4():
    x = pack_state([0, 0, 0, 1.0], [0.1, 0.2, 0.3], [1.0, 2.0, 3.0])
    M_c, M_ext = np.array([0.1, -0.2, 0.05]), np.array([1e-4, 2e-4, -3e-4])
    d = state_derivative(x, M_c, M_ext, I, I_INV)
    w, h = x[4:7], x[7:10]
    # eq. 4 rearranged independently: I wdot = M_c + M_ext - w x (I w) - w x h
    lhs = I @ d[4:7]
    rhs = M_c + M_ext - np.cross(w, I @ w) - np.cross(w, h)
    np.testing.assert_allclose(lhs, rhs, atol=1e-12)
    np.testing.assert_array_equal(d[7:10], -M_c)


def test_saturation_and_momentum_limit():
    lim = TABLE6.torque_limit
    np.testing.assert_array_equal(saturate_torque(np.array([2.0, -3.0, 0.5]), lim), [lim, -lim, 0.5])
    np.testing.assert_array_equal(saturate_torque(np.array([np.nan, np.inf, -np.inf]), lim), [0, 0, 0])
    h = np.array([50.0, -50.0, 10.0])
    # hdot = -M_c: M_c = -1 would push h_x beyond +50 -> blocked; M_c = +1 brings it back -> allowed
    np.testing.assert_array_equal(momentum_limited_torque(np.array([-1.0, 1.0, -1.0]), h, 50.0), [0, 0, -1.0])
    np.testing.assert_array_equal(momentum_limited_torque(np.array([1.0, -1.0, 1.0]), h, 50.0), [1.0, -1.0, 1.0])
