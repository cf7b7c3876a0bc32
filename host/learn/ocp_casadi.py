"""CasADi-symbolic twins of the few attitude formulas the optimal-control problem needs.

Same conventions as host.core.rotations (scalar-last quaternions, Wie's C(q) reference -> body,
passive DCMs, Euler 3-1-2 A = [phi, theta, psi]) and the same state as host.plant.spacecraft
(x = [q_bi (4), omega_b (3, rad/s), h_w (3, N·m·s)]). tests/host/learn/test_ocp.py checks each function
against its numpy original. Every function takes casadi SX/MX/DM (column vectors) and builds
an expression; none of them evaluates anything.
"""
from __future__ import annotations

import casadi as ca


def skew(v):
    """[v×]: skew(a) @ b == cross(a, b)."""
    return ca.vertcat(
        ca.horzcat(0, -v[2], v[1]),
        ca.horzcat(v[2], 0, -v[0]),
        ca.horzcat(-v[1], v[0], 0),
    )


def omega_matrix(w):
    """Paper 001 eq. (16)."""
    x, y, z = w[0], w[1], w[2]
    return ca.vertcat(
        ca.horzcat(0, z, -y, x),
        ca.horzcat(-z, 0, x, y),
        ca.horzcat(y, -x, 0, z),
        ca.horzcat(-x, -y, -z, 0),
    )


def quat_rate(q, w):
    """Paper 001 eq. (3)."""
    return 0.5 * ca.mtimes(omega_matrix(w), q)


def dcm_from_quat(q):
    """Wie's C(q), reference -> body (host.core.rotations.dcm_from_quat)."""
    q1, q2, q3, q4 = q[0], q[1], q[2], q[3]
    return ca.vertcat(
        ca.horzcat(1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 + q3 * q4), 2 * (q1 * q3 - q2 * q4)),
        ca.horzcat(2 * (q2 * q1 - q3 * q4), 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 + q1 * q4)),
        ca.horzcat(2 * (q3 * q1 + q2 * q4), 2 * (q3 * q2 - q1 * q4), 1 - 2 * (q1 * q1 + q2 * q2)),
    )


def _frame_rot(axis: int, a):
    c, s = ca.cos(a), ca.sin(a)
    if axis == 0:
        return ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, c, s), ca.horzcat(0, -s, c))
    if axis == 1:
        return ca.vertcat(ca.horzcat(c, 0, -s), ca.horzcat(0, 1, 0), ca.horzcat(s, 0, c))
    return ca.vertcat(ca.horzcat(c, s, 0), ca.horzcat(-s, c, 0), ca.horzcat(0, 0, 1))


def dcm_from_euler312(A):
    """L = Ry(theta) Rx(phi) Rz(psi) for A = [phi, theta, psi] (radians)."""
    return ca.mtimes([_frame_rot(1, A[1]), _frame_rot(0, A[0]), _frame_rot(2, A[2])])


def euler312_from_dcm(L):
    """Inverse of dcm_from_euler312 (host.core.rotations.euler312_from_dcm), radians."""
    phi = ca.asin(L[1, 2])
    theta = ca.atan2(-L[0, 2], L[2, 2])
    psi = ca.atan2(-L[1, 0], L[1, 1])
    return ca.vertcat(phi, theta, psi)


def quat_from_small_rotation_dcm(L):
    """Quaternion of a DCM whose rotation is well below 180° (the trace branch of Shepperd).

    Only used for the initial attitude A_bd, a few hundredths of a degree, where 1 + tr(L) ≈ 4.
    """
    q4 = 0.5 * ca.sqrt(1 + L[0, 0] + L[1, 1] + L[2, 2])
    return ca.vertcat(
        (L[1, 2] - L[2, 1]) / (4 * q4),
        (L[2, 0] - L[0, 2]) / (4 * q4),
        (L[0, 1] - L[1, 0]) / (4 * q4),
        q4,
    )


def quat_product(a, b):
    """The quaternion c with C(c) = C(a)·C(b) (Wie's composition, scalar last)."""
    a1, a2, a3, a4 = a[0], a[1], a[2], a[3]
    M = ca.vertcat(
        ca.horzcat(a4, a3, -a2, a1),
        ca.horzcat(-a3, a4, a1, a2),
        ca.horzcat(a2, -a1, a4, a3),
        ca.horzcat(-a1, -a2, -a3, a4),
    )
    return ca.mtimes(M, b)


def quat_conjugate(q):
    """C(conj(q)) = C(q)^T for a unit quaternion."""
    return ca.vertcat(-q[0], -q[1], -q[2], q[3])


def error_dcm(q_b, q_d):
    """L_bd = C(q_b)·C(q_d)^T (desired frame -> body), through one quaternion product."""
    return dcm_from_quat(quat_product(q_b, quat_conjugate(q_d)))


def euler312_error(L_bd):
    """A_e: the 3-1-2 angles of L_bd, radians (eq. 6's error: desired frame -> body)."""
    return euler312_from_dcm(L_bd)


def relative_rate(L_bd, w_b, w_d):
    """ω_b − L_bd·ω_d: the body rate relative to the desired frame, body axes (rad/s)."""
    return w_b - ca.mtimes(L_bd, w_d)


def state_derivative(x, M, inertia, inertia_inv):
    """d/dt [q, ω, h_w] of host.plant.spacecraft.state_derivative with no external torque (eq. 3-4)."""
    q, w, h = x[0:4], x[4:7], x[7:10]
    gyroscopic = ca.cross(w, ca.mtimes(inertia, w) + h)
    wdot = ca.mtimes(inertia_inv, M - gyroscopic)
    return ca.vertcat(quat_rate(q, w), wdot, -M)


def rk4_states(f, x, dt: float):
    """One classic RK4 step of the autonomous x' = f(x) (torque held); returns x(t + dt)."""
    k1 = f(x)
    k2 = f(x + 0.5 * dt * k1)
    k3 = f(x + 0.5 * dt * k2)
    k4 = f(x + dt * k3)
    return x + (dt / 6.0) * (k1 + 2 * k2 + 2 * k3 + k4)


def desired_rate(w_d0, wdot_d, t):
    """Eq. (13): ω_d(t) = ω_d + t·ω̇_d (desired axes, rad/s)."""
    return w_d0 + t * wdot_d


def desired_quat_step(q, w_d0, wdot_d, t: float, dt: float):
    """One RK4 step of eq. (14) (with Ω(ω), eq. 16) for the linearly varying ω_d(t) of eq. (13).

    The body is propagated with the same RK4 step, so a body flying ω_b(t) = ω_d(t) from the
    same attitude stays on the desired sequence to O(dt^5) — eq. (15)'s forward Euler would
    drift by ≈ (dt/2)·ω̇_d·t.
    """
    def f(qq, tt):
        return quat_rate(qq, desired_rate(w_d0, wdot_d, tt))

    k1 = f(q, t)
    k2 = f(q + 0.5 * dt * k1, t + 0.5 * dt)
    k3 = f(q + 0.5 * dt * k2, t + 0.5 * dt)
    k4 = f(q + dt * k3, t + dt)
    return q + (dt / 6.0) * (k1 + 2 * k2 + 2 * k3 + k4)
