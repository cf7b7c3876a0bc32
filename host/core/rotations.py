"""The one owner of attitude conventions (SPEC section 2). Everything else imports from here.

Conventions
-----------
* DCMs are passive: ``L_xy`` maps components from frame S_y to frame S_x, ``v_x = L_xy @ v_y``.
* Elementary frame rotations ``frame_rot_x/y/z(a)`` are the passive matrices of a rotation of
  the frame by angle ``a`` about that axis (e.g. ``frame_rot_z(a) = [[c, s, 0], [-s, c, 0], [0, 0, 1]]``).
* Euler angles of paper 001: order 3-1-2, ``A = [phi, theta, psi]``: first psi about z, then phi
  about x, then theta about y, so ``L = Ry(theta) @ Rx(phi) @ Rz(psi)``.
* Quaternion ``q = [q1, q2, q3, q4]``, scalar last, the rotation from a reference frame to the
  body; ``dcm_from_quat`` is Wie's C(q) (reference -> body) and ``quat_rate`` is paper 001 eq. (3).
* Paper 000 (finite-time tanh controller) uses active rotation matrices R that map body to
  reference, built yaw-pitch-roll: ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)`` (its eq. 31 with the
  row-2 typo fixed). ``dcm_from_euler321`` returns that matrix; it is used only by that controller.

All angles in radians. Functions accept a single item or a batch (leading dimensions).
"""
from __future__ import annotations

import numpy as np

# ----------------------------------------------------------------------------- helpers


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix [v×] so that skew(a) @ b == cross(a, b)."""
    v = np.asarray(v, dtype=float)
    z = np.zeros(v.shape[:-1])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack(
        [np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)], -2
    )


def vee(m: np.ndarray) -> np.ndarray:
    """Inverse of skew for a skew-symmetric matrix."""
    m = np.asarray(m, dtype=float)
    return np.stack([m[..., 2, 1], m[..., 0, 2], m[..., 1, 0]], -1)


def _stack33(rows) -> np.ndarray:
    return np.stack([np.stack(r, -1) for r in rows], -2)


# ----------------------------------------------------------------------------- elementary rotations


def frame_rot_x(a) -> np.ndarray:
    """Passive rotation of the frame about x by a: components in the rotated frame."""
    a = np.asarray(a, dtype=float)
    c, s, o, z = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
    return _stack33([(o, z, z), (z, c, s), (z, -s, c)])


def frame_rot_y(a) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    c, s, o, z = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
    return _stack33([(c, z, -s), (z, o, z), (s, z, c)])


def frame_rot_z(a) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    c, s, o, z = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
    return _stack33([(c, s, z), (-s, c, z), (z, z, o)])


# ----------------------------------------------------------------------------- Euler 3-1-2 (paper 001)


def dcm_from_euler312(A) -> np.ndarray:
    """L = Ry(theta) Rx(phi) Rz(psi) for A = [phi, theta, psi] (rotation psi -> phi -> theta)."""
    A = np.asarray(A, dtype=float)
    phi, theta, psi = A[..., 0], A[..., 1], A[..., 2]
    return frame_rot_y(theta) @ frame_rot_x(phi) @ frame_rot_z(psi)


def euler312_from_dcm(L) -> np.ndarray:
    """Inverse of dcm_from_euler312; phi in [-pi/2, pi/2], singular at |phi| = pi/2.

    From the product: L[1,2] = sin(phi), L[1,0] = -cos(phi) sin(psi), L[1,1] = cos(phi) cos(psi),
    L[0,2] = -sin(theta) cos(phi), L[2,2] = cos(theta) cos(phi).
    """
    L = np.asarray(L, dtype=float)
    phi = np.arcsin(np.clip(L[..., 1, 2], -1.0, 1.0))
    psi = np.arctan2(-L[..., 1, 0], L[..., 1, 1])
    theta = np.arctan2(-L[..., 0, 2], L[..., 2, 2])
    return np.stack([phi, theta, psi], -1)


# ----------------------------------------------------------------------------- quaternions (scalar last)


def dcm_from_quat(q) -> np.ndarray:
    """Wie's C(q): reference -> body passive DCM for q = [q1, q2, q3, q4] (scalar last)."""
    q = np.asarray(q, dtype=float)
    q1, q2, q3, q4 = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return _stack33(
        [
            (1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 + q3 * q4), 2 * (q1 * q3 - q2 * q4)),
            (2 * (q2 * q1 - q3 * q4), 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 + q1 * q4)),
            (2 * (q3 * q1 + q2 * q4), 2 * (q3 * q2 - q1 * q4), 1 - 2 * (q1 * q1 + q2 * q2)),
        ]
    )


def quat_from_dcm(L) -> np.ndarray:
    """Inverse of dcm_from_quat (Shepperd's method: pivot on the largest of 4 candidates).

    Returns the quaternion with q4 >= 0 (the two signs are the same rotation).
    """
    L = np.asarray(L, dtype=float)
    batch = L.shape[:-2]
    Lf = L.reshape(-1, 3, 3)
    tr = np.trace(Lf, axis1=1, axis2=2)
    diag = np.stack([Lf[:, 0, 0], Lf[:, 1, 1], Lf[:, 2, 2], tr], -1)
    k = np.argmax(diag, axis=1)
    q = np.empty((Lf.shape[0], 4))
    for i in range(Lf.shape[0]):
        m = Lf[i]
        if k[i] == 3:
            q4 = 0.5 * np.sqrt(1 + tr[i])
            q[i] = [(m[1, 2] - m[2, 1]) / (4 * q4), (m[2, 0] - m[0, 2]) / (4 * q4),
                    (m[0, 1] - m[1, 0]) / (4 * q4), q4]
        elif k[i] == 0:
            q1 = 0.5 * np.sqrt(1 + 2 * m[0, 0] - tr[i])
            q[i] = [q1, (m[0, 1] + m[1, 0]) / (4 * q1), (m[0, 2] + m[2, 0]) / (4 * q1),
                    (m[1, 2] - m[2, 1]) / (4 * q1)]
        elif k[i] == 1:
            q2 = 0.5 * np.sqrt(1 + 2 * m[1, 1] - tr[i])
            q[i] = [(m[0, 1] + m[1, 0]) / (4 * q2), q2, (m[1, 2] + m[2, 1]) / (4 * q2),
                    (m[2, 0] - m[0, 2]) / (4 * q2)]
        else:
            q3 = 0.5 * np.sqrt(1 + 2 * m[2, 2] - tr[i])
            q[i] = [(m[0, 2] + m[2, 0]) / (4 * q3), (m[1, 2] + m[2, 1]) / (4 * q3), q3,
                    (m[0, 1] - m[1, 0]) / (4 * q3)]
    q *= np.where(q[:, 3:4] < 0, -1.0, 1.0)
    return q.reshape(batch + (4,))


def omega_matrix(w) -> np.ndarray:
    """Omega(w) of paper 001 eq. (16): q_dot = 0.5 * Omega(w) @ q (scalar-last quaternion)."""
    w = np.asarray(w, dtype=float)
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    o = np.zeros_like(x)
    return np.stack(
        [
            np.stack([o, z, -y, x], -1),
            np.stack([-z, o, x, y], -1),
            np.stack([y, -x, o, z], -1),
            np.stack([-x, -y, -z, o], -1),
        ],
        -2,
    )


def quat_rate(q, w) -> np.ndarray:
    """Paper 001 eq. (3): the quaternion rate for body rate w (in body axes)."""
    return 0.5 * (omega_matrix(w) @ np.asarray(q, dtype=float)[..., None])[..., 0]


def quat_step_exact(q, w, dt: float) -> np.ndarray:
    """Exact propagation of eq. (3) over dt for a body rate w held constant (matrix exponential).

    exp(0.5*Omega*dt) = cos(|w|dt/2) I + sin(|w|dt/2)/|w| * Omega, since Omega^2 = -|w|^2 I.
    """
    w = np.asarray(w, dtype=float)
    n = np.linalg.norm(w, axis=-1)
    half = 0.5 * n * dt
    # sin(half)/n -> dt/2 as n -> 0 (Taylor to avoid 0/0)
    s_over_n = np.where(n > 1e-12, np.sin(half) / np.where(n > 1e-12, n, 1.0), 0.5 * dt)
    M = np.cos(half)[..., None, None] * np.eye(4) + s_over_n[..., None, None] * omega_matrix(w)
    return (M @ np.asarray(q, dtype=float)[..., None])[..., 0]


def quat_normalise(q) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


# ----------------------------------------------------------------------------- Paper 000 (yaw-pitch-roll, active)


def active_rot_x(a) -> np.ndarray:
    return np.swapaxes(frame_rot_x(a), -1, -2)


def active_rot_y(a) -> np.ndarray:
    return np.swapaxes(frame_rot_y(a), -1, -2)


def active_rot_z(a) -> np.ndarray:
    return np.swapaxes(frame_rot_z(a), -1, -2)


def dcm_from_euler321(roll, pitch, yaw) -> np.ndarray:
    """Paper 000's attitude matrix R (body -> reference): Rz(yaw) Ry(pitch) Rx(roll), active.

    Equals paper 000 eq. 31 with its row-2 typo fixed; with eq. 30's angles it gives eq. 32.
    """
    return active_rot_z(yaw) @ active_rot_y(pitch) @ active_rot_x(roll)


def project_to_so3(M) -> np.ndarray:
    """Nearest rotation matrix (Frobenius norm) via SVD; used for matrices printed to few digits."""
    U, _, Vt = np.linalg.svd(np.asarray(M, dtype=float))
    D = np.eye(3)
    D[2, 2] = np.sign(np.linalg.det(U @ Vt))
    return U @ D @ Vt


# ----------------------------------------------------------------------------- Euler 3-1-2 kinematics (paper 002)
# Paper 002 uses the same order as paper 001 (C_bi = Ry(theta) Rx(phi) Rz(psi)); its eq. (4)-(6) relate the
# body rate to the Euler-angle rates through R(phi, theta) (docs/rbf-backstepping.md section 2).


def euler312_rate_matrix(phi, theta) -> np.ndarray:
    """R(phi, theta) with omega = R @ [phi_dot, theta_dot, psi_dot] (body rate, body axes); det R = cos(phi).

    Why this form: omega = theta_dot*y + Ry(theta)(phi_dot*x) + Ry(theta)Rx(phi)(psi_dot*z).
    """
    phi, theta = np.asarray(phi, dtype=float), np.asarray(theta, dtype=float)
    cp, sp, ct, st = np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta)
    o, z = np.ones_like(cp), np.zeros_like(cp)
    return _stack33([(ct, z, -st * cp), (z, o, sp), (st, z, ct * cp)])


def euler312_rate_matrix_inverse(phi, theta) -> np.ndarray:
    """R^-1 (Euler-angle rates from the body rate); singular at |phi| = pi/2."""
    phi, theta = np.asarray(phi, dtype=float), np.asarray(theta, dtype=float)
    cp, tp, ct, st = np.cos(phi), np.tan(phi), np.cos(theta), np.sin(theta)
    o, z = np.ones_like(cp), np.zeros_like(cp)
    return _stack33([(ct, z, st), (st * tp, o, -ct * tp), (-st / cp, z, ct / cp)])


def euler312_rate_matrix_dot(phi, theta, phi_dot, theta_dot) -> np.ndarray:
    """d/dt R(phi, theta) along a motion with Euler rates phi_dot, theta_dot (psi does not enter R)."""
    phi, theta = np.asarray(phi, dtype=float), np.asarray(theta, dtype=float)
    pd, td = np.asarray(phi_dot, dtype=float), np.asarray(theta_dot, dtype=float)
    cp, sp, ct, st = np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta)
    z = np.zeros(np.broadcast(cp, pd, td).shape)
    return _stack33([(-st * td, z, -ct * cp * td + st * sp * pd),
                     (z, z, cp * pd),
                     (ct * td, z, -st * cp * td - ct * sp * pd)])


# ----------------------------------------------------------------------------- line-of-sight frame (paper 002)


def los_frame(q_eps, q_beta) -> np.ndarray:
    """C_li = Rz(q_eps) Ry(q_beta): inertial -> LOS; x_l along the LOS, y_l in the plane of x_l and y_i.

    Row 0 (x_l in inertial axes) = [c(q_eps) c(q_beta), s(q_eps), -c(q_eps) s(q_beta)].
    """
    return frame_rot_z(q_eps) @ frame_rot_y(q_beta)


def los_angles(r) -> np.ndarray:
    """[rho, q_eps, q_beta] of a relative position r (inertial axes): rho = |r|, q_eps = asin(y/rho)
    (elevation, [-pi/2, pi/2]), q_beta = atan2(-z, x) (azimuth, [-pi, pi]); the inverse of
    r = rho * los_frame(q_eps, q_beta)[0]."""
    r = np.asarray(r, dtype=float)
    rho = np.linalg.norm(r, axis=-1)
    q_eps = np.arcsin(np.clip(r[..., 1] / rho, -1.0, 1.0))
    q_beta = np.arctan2(-r[..., 2], r[..., 0])
    return np.stack([rho, q_eps, q_beta], -1)
