"""Rotations against analytic truth: round trips, kinematics, and paper 000 eq. 30 -> eq. 32."""
import numpy as np
import pytest

from host.core import rotations as rot

RNG = np.random.default_rng(12345)


def random_euler312(n):
    # away from the 3-1-2 singularity |phi| = 90 deg
    phi = RNG.uniform(-1.4, 1.4, n)
    theta = RNG.uniform(-np.pi + 1e-3, np.pi - 1e-3, n)
    psi = RNG.uniform(-np.pi + 1e-3, np.pi - 1e-3, n)
    return np.stack([phi, theta, psi], -1)


def random_quat(n):
    q = RNG.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def test_elementary_frame_rotation_is_passive():
    # A frame rotated by +90 deg about z sees the old x axis along its -y axis.
    v = rot.frame_rot_z(np.pi / 2) @ np.array([1.0, 0.0, 0.0])
    np.testing.assert_allclose(v, [0.0, -1.0, 0.0], atol=1e-15)


def test_euler312_order_is_psi_then_phi_then_theta():
    phi, theta, psi = 0.3, -0.2, 1.1
    expected = rot.frame_rot_y(theta) @ rot.frame_rot_x(phi) @ rot.frame_rot_z(psi)
    np.testing.assert_allclose(rot.dcm_from_euler312([phi, theta, psi]), expected, atol=0)
    # a pure psi rotation is about z only: z components unchanged
    L = rot.dcm_from_euler312([0.0, 0.0, 0.7])
    np.testing.assert_allclose(L[2], [0, 0, 1], atol=1e-15)


def test_euler312_round_trip():
    A = random_euler312(2000)
    L = rot.dcm_from_euler312(A)
    np.testing.assert_allclose(rot.euler312_from_dcm(L), A, atol=1e-12)
    np.testing.assert_allclose(L @ np.swapaxes(L, -1, -2), np.broadcast_to(np.eye(3), L.shape), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(L), 1.0, atol=1e-14)


def test_quat_round_trip():
    q = random_quat(2000)
    q *= np.where(q[:, 3:4] < 0, -1, 1)
    L = rot.dcm_from_quat(q)
    np.testing.assert_allclose(L @ np.swapaxes(L, -1, -2), np.broadcast_to(np.eye(3), L.shape), atol=1e-14)
    np.testing.assert_allclose(rot.quat_from_dcm(L), q, atol=1e-12)


def test_quat_matches_axis_angle():
    # q = [e sin(a/2), cos(a/2)] about z is the frame rotation Rz(a) (reference -> body).
    a = 0.8
    q = np.array([0, 0, np.sin(a / 2), np.cos(a / 2)])
    np.testing.assert_allclose(rot.dcm_from_quat(q), rot.frame_rot_z(a), atol=1e-15)


def test_quaternion_kinematics_match_dcm_kinematics():
    # d/dt C(q) = -[w x] C(q) when q_dot = 0.5 Omega(w) q (paper 001 eq. 3).
    q = random_quat(50)
    w = RNG.normal(size=(50, 3))
    h = 1e-6
    dC = (rot.dcm_from_quat(q + h * rot.quat_rate(q, w)) - rot.dcm_from_quat(q - h * rot.quat_rate(q, w))) / (2 * h)
    np.testing.assert_allclose(dC, -rot.skew(w) @ rot.dcm_from_quat(q), atol=1e-8)


def test_exact_quaternion_step_equals_fine_rk4():
    q = random_quat(1)[0]
    w = np.array([0.3, -0.2, 0.5])
    dt = 0.5
    ref = q.copy()
    n = 2000
    hh = dt / n
    for _ in range(n):
        k1 = rot.quat_rate(ref, w)
        k2 = rot.quat_rate(ref + 0.5 * hh * k1, w)
        k3 = rot.quat_rate(ref + 0.5 * hh * k2, w)
        k4 = rot.quat_rate(ref + hh * k3, w)
        ref = ref + hh / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    np.testing.assert_allclose(rot.quat_step_exact(q, w, dt), ref, atol=1e-13)


def test_skew_vee():
    a, b = RNG.normal(size=3), RNG.normal(size=3)
    np.testing.assert_allclose(rot.skew(a) @ b, np.cross(a, b), atol=1e-15)
    np.testing.assert_allclose(rot.vee(rot.skew(a)), a)


def test_paper000_eq30_gives_eq32():
    roll, pitch, yaw = np.deg2rad([-3.0894125, -34.4091333, 31.022785])
    R = rot.dcm_from_euler321(roll, pitch, yaw)
    eq32 = np.array([[0.7070141, -0.4885306, -0.5113404],
                     [0.4251997, 0.8714131, -0.2446312],
                     [0.5650985, -0.0444641, 0.8238244]])
    np.testing.assert_allclose(R, eq32, atol=1e-6)
    # eq. 31 row 3 as printed (correct there): [-s(pitch), s(roll)c(pitch), c(roll)c(pitch)]
    np.testing.assert_allclose(R[2], [-np.sin(pitch), np.sin(roll) * np.cos(pitch), np.cos(roll) * np.cos(pitch)], atol=1e-15)


def test_project_to_so3():
    Rc0 = np.array([[-0.5414, -0.7072, -0.4546], [-0.0009, -0.5403, 0.8415], [-0.8407, 0.4560, 0.2919]])
    R = rot.project_to_so3(Rc0)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
    assert np.max(np.abs(R - Rc0)) < 1e-3


# ----------------------------------------------------------------------------- paper 002: 3-1-2 kinematics, LOS frame


def _body_rate_from_dcm_motion(A, A_dot, h=1e-6):
    """omega (body axes) from C_dot = -[omega]x C by central differences of dcm_from_euler312."""
    C = rot.dcm_from_euler312(A)
    C_dot = (rot.dcm_from_euler312(A + h * A_dot) - rot.dcm_from_euler312(A - h * A_dot)) / (2 * h)
    return rot.vee(-C_dot @ np.swapaxes(C, -1, -2))


def test_euler312_rate_matrix_against_finite_differences():
    A = random_euler312(200)
    A_dot = RNG.normal(size=(200, 3))
    R = rot.euler312_rate_matrix(A[:, 0], A[:, 1])
    np.testing.assert_allclose((R @ A_dot[..., None])[..., 0], _body_rate_from_dcm_motion(A, A_dot), atol=2e-8)


def test_euler312_rate_matrix_inverse_and_determinant():
    A = random_euler312(200)
    R = rot.euler312_rate_matrix(A[:, 0], A[:, 1])
    R_inv = rot.euler312_rate_matrix_inverse(A[:, 0], A[:, 1])
    np.testing.assert_allclose(R_inv @ R, np.broadcast_to(np.eye(3), R.shape), atol=1e-9)
    np.testing.assert_allclose(np.linalg.det(R), np.cos(A[:, 0]), atol=1e-12)


def test_euler312_rate_matrix_dot_against_finite_differences():
    A = random_euler312(100)
    A_dot = RNG.normal(size=(100, 3))
    h = 1e-6
    numeric = (rot.euler312_rate_matrix(A[:, 0] + h * A_dot[:, 0], A[:, 1] + h * A_dot[:, 1])
               - rot.euler312_rate_matrix(A[:, 0] - h * A_dot[:, 0], A[:, 1] - h * A_dot[:, 1])) / (2 * h)
    analytic = rot.euler312_rate_matrix_dot(A[:, 0], A[:, 1], A_dot[:, 0], A_dot[:, 1])
    np.testing.assert_allclose(analytic, numeric, atol=1e-8)


def test_los_frame_x_axis_along_the_vector_and_y_in_the_xl_yi_plane():
    r = RNG.normal(size=(300, 3)) * [200.0, 50.0, 200.0]
    rho, q_eps, q_beta = rot.los_angles(r).T
    C = rot.los_frame(q_eps, q_beta)
    np.testing.assert_allclose(rho, np.linalg.norm(r, axis=1), rtol=1e-15)
    np.testing.assert_allclose(C[:, 0] * rho[:, None], r, atol=1e-10)          # x_l = r / rho
    y_i = np.array([0.0, 1.0, 0.0])
    # y_l is in span(x_l, y_i): the triple product vanishes; and it points to the +y_i side
    np.testing.assert_allclose(np.einsum("ij,ij->i", np.cross(C[:, 0], y_i), C[:, 1]), 0.0, atol=1e-14)
    assert np.all(C[:, 1] @ y_i > 0)
    np.testing.assert_allclose(C @ np.swapaxes(C, -1, -2), np.broadcast_to(np.eye(3), C.shape), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(C), 1.0, atol=1e-14)
