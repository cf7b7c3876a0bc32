"""The batched simulator's plant and algebra: eq. 4 with wheels and the environmental torques on
component-major arrays.

Vectors are (3, T, B) arrays and matrices (3, 3, T, B): each component is one contiguous (T, B)
array, so every formula below is the scalar simulator's (host.core.rotations, host.core.vec3,
host.plant.spacecraft), written out on whole arrays. A constant matrix acts through one BLAS call.
"""
from __future__ import annotations

import numpy as np

from host.core.constants import MU_EARTH
from host.plant.environment import SOLAR_PRESSURE, EnvironmentTrack
from host.sim.simulator import SimConfig


# ----------------------------------------------------------------------------- algebra

def cross(a, b):
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def const_matvec(M, v):
    """(3, 3) constant matrix times (3, T, B) vectors."""
    return (M @ v.reshape(3, -1)).reshape(v.shape)


def rows_dot_const(L, c):
    """L (3, 3, T, B) times a constant (3,) vector: (3, T, B)."""
    return (L[:, 0] * c[0] + L[:, 1] * c[1]) + L[:, 2] * c[2]


def dcm_from_quat(q):
    q1, q2, q3, q4 = q[0], q[1], q[2], q[3]
    return np.stack([np.stack(r) for r in (
        (1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 + q3 * q4), 2 * (q1 * q3 - q2 * q4)),
        (2 * (q2 * q1 - q3 * q4), 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 + q1 * q4)),
        (2 * (q3 * q1 + q2 * q4), 2 * (q3 * q2 - q1 * q4), 1 - 2 * (q1 * q1 + q2 * q2)))])


def dcm_from_euler312(A):
    """Ry(theta) Rx(phi) Rz(psi), written out."""
    sf, cf = np.sin(A[0]), np.cos(A[0])
    st, ct = np.sin(A[1]), np.cos(A[1])
    sp, cp = np.sin(A[2]), np.cos(A[2])
    return np.stack([np.stack(r) for r in (
        (ct * cp - st * sf * sp, ct * sp + st * sf * cp, -st * cf),
        (-cf * sp, cf * cp, sf),
        (st * cp + ct * sf * sp, st * sp - ct * sf * cp, ct * cf))])


def euler312_from_entries(entry) -> np.ndarray:
    """host.core.rotations.euler312_from_dcm from an entry(i, k) function of the DCM."""
    phi = np.arcsin(np.clip(entry(1, 2), -1.0, 1.0))
    psi = np.arctan2(-entry(1, 0), entry(1, 1))
    theta = np.arctan2(-entry(0, 2), entry(2, 2))
    return np.stack([phi, theta, psi])


def euler312(L):
    return euler312_from_entries(lambda i, k: L[i, k])


def euler312_of_product(L, R_t):
    """euler312(L · R^T) for L (3, 3, T, B) and per-target R (T, 3, 3): only the five entries the
    angles need, each a row of L dotted with a row of R."""
    def entry(i, k):
        return (L[i, 0] * R_t[:, k, 0, None] + L[i, 1] * R_t[:, k, 1, None]) + L[i, 2] * R_t[:, k, 2, None]
    return euler312_from_entries(entry)


def matmul(A, B):
    """(3, 3, T, B) · (3, 3, T, B), entry by entry."""
    return np.stack([np.stack([(A[i, 0] * B[0, k] + A[i, 1] * B[1, k]) + A[i, 2] * B[2, k] for k in range(3)])
                     for i in range(3)])


def quat_rate(q, w):
    q1, q2, q3, q4 = q[0], q[1], q[2], q[3]
    wx, wy, wz = w[0], w[1], w[2]
    return 0.5 * np.stack([q4 * wx - (wy * q3 - wz * q2), q4 * wy - (wz * q1 - wx * q3),
                           q4 * wz - (wx * q2 - wy * q1), -(wx * q1 + wy * q2 + wz * q3)])


# ----------------------------------------------------------------------------- plant

class Plant:
    """Eq. 4 with wheels and the four environmental torques, on (10, T, B) states."""

    def __init__(self, cfg: SimConfig, env: EnvironmentTrack):
        sc = cfg.spacecraft
        self.inertia, self.inertia_inv = sc.inertia, sc.inertia_inv
        self.env, self.dist = env, cfg.disturbances

    def external_torque(self, j: int, L_bi) -> np.ndarray:
        """Sum of gravity gradient, drag, solar radiation and magnetic torques at sample j."""
        env, p = self.env, self.dist
        R = env.R[j]
        r = np.sqrt(R @ R)
        r_hat_b = rows_dot_const(L_bi, R / r)
        gg = (3.0 * MU_EARTH / r ** 3) * cross(r_hat_b, const_matvec(self.inertia, r_hat_b))
        gg = gg if p.gravity_gradient else 0.0 * gg
        v_b = rows_dot_const(L_bi, env.v_rel[j])
        speed = np.sqrt((v_b[0] * v_b[0] + v_b[1] * v_b[1]) + v_b[2] * v_b[2])
        drag = cross(p.drag_cp_offset, -0.5 * env.rho[j] * p.drag_coefficient * p.drag_area * speed * v_b)
        s_b = rows_dot_const(L_bi, env.sun_dir[j])
        srp = cross(p.srp_cp_offset, -env.sunlit[j] * SOLAR_PRESSURE * p.srp_area * (1.0 + p.srp_reflectivity) * s_b)
        mag = cross(p.residual_dipole, rows_dot_const(L_bi, env.B[j]))
        return ((gg + drag) + srp) + mag

    def derivative(self, x, M_c, M_ext):
        q, w, h = x[0:4], x[4:7], x[7:10]
        gyroscopic = cross(w, const_matvec(self.inertia, w) + h)
        wdot = const_matvec(self.inertia_inv, (M_c + M_ext) - gyroscopic)
        return np.concatenate([quat_rate(q, w), wdot, -M_c])

    def rk4(self, x, M_c, M_ext, dt: float):
        f = self.derivative
        k1 = f(x, M_c, M_ext)
        k2 = f(x + 0.5 * dt * k1, M_c, M_ext)
        k3 = f(x + 0.5 * dt * k2, M_c, M_ext)
        k4 = f(x + dt * k3, M_c, M_ext)
        x_new = x + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        q = x_new[0:4]
        x_new[0:4] = q / np.sqrt(((q[0] * q[0] + q[1] * q[1]) + q[2] * q[2]) + q[3] * q[3])
        return x_new


def momentum_limited(M_c, h, limit: float):
    spinning_up = (np.abs(h) >= limit) & (np.sign(-M_c) == np.sign(h))
    return np.where(spinning_up, 0.0, M_c)
