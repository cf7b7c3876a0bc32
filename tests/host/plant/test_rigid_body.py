"""The rigid body on SO(3) (paper 000's plant) against analytic truth and its conservation laws."""
import numpy as np

from host.plant.rigid_body import RigidBody, paper000_disturbance, rows, state

J = np.array([[27.7, 0.3, -0.2], [0.3, 23.5, 0.5], [-0.2, 0.5, 24.6]])


def fly(body, y, u, seconds, h=1e-3):
    for k in range(int(round(seconds / h))):
        y = body.rk4_step(k * h, y, h, u)
    return y


def test_torque_free_motion_conserves_momentum_energy_and_orthonormality():
    body = RigidBody(J)
    R0, w0 = np.eye(3), np.array([0.3, -0.2, 0.5])
    y = fly(body, state(R0, w0), (0.0, 0.0, 0.0), 10.0)
    R, w = np.array(rows(y)), np.array(y[9:12])
    H0, H = R0 @ J @ w0, R @ J @ w            # angular momentum in the reference frame
    np.testing.assert_allclose(H, H0, rtol=1e-9, atol=1e-12)
    assert abs(0.5 * w @ J @ w - 0.5 * w0 @ J @ w0) < 1e-10
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-10)


def test_constant_torque_about_a_principal_axis_spins_up_linearly():
    Jd = np.diag([2.0, 3.0, 4.0])
    body = RigidBody(Jd)
    y = fly(body, state(np.eye(3), (0.0, 0.0, 0.0)), (0.0, 0.0, 0.8), 2.0)
    w = np.array(y[9:12])
    np.testing.assert_allclose(w, [0.0, 0.0, 0.8 / 4.0 * 2.0], atol=1e-12)
    angle = 0.5 * 0.2 * 2.0 ** 2              # ½ (u/J) t²
    np.testing.assert_allclose(np.array(rows(y)), [[np.cos(angle), -np.sin(angle), 0.0],
                                                    [np.sin(angle), np.cos(angle), 0.0], [0.0, 0.0, 1.0]], atol=1e-9)


def test_paper000_disturbance_is_the_printed_one():
    d = paper000_disturbance(0.002)
    t = 7.3
    np.testing.assert_allclose(d(t), 0.002 * np.array([np.sin(0.1 * t), np.cos(0.2 * t), np.sin(0.2 * t)]), rtol=0,
                               atol=0)
    body = RigidBody(np.eye(3), d)
    rates = body.rates(t, state(np.eye(3), (0.0, 0.0, 0.0)), (0.0, 0.0, 0.0))
    np.testing.assert_allclose(rates[9:12], d(t), atol=1e-18)
