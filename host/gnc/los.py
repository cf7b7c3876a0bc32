"""Line-of-sight measurements and desired state of paper 002 (docs/rbf-backstepping.md sections 1-3).

From the truth (host.plant.proximity): the measured LOS state (rho, q_eps, q_beta and their rates, exact
kinematics of the relative position and velocity), the chaser's 3-1-2 Euler angles and body rate, and the
desired values: rho_d = 100 m, the desired LOS l_d = -C_it n_b (the chaser looks at the target's feature
along -n_b) -> (q_eps_d, q_beta_d) with analytic first and second derivatives (the target's spin is known
to the chaser, L82), and the desired attitude C_bi,d = C_li(q_eps_d, q_beta_d) -> (phi_f, theta_f, psi_f)
with their derivatives. Angles handed to the law are wrapped to [-pi, pi] (the law wraps differences);
a time history of q_beta_d is unwrapped with numpy.unwrap by whoever plots it.

`LosMeasurement` has the field names of codegen.units.rbf.records.INPUT_DTYPE; `to_record` packs one
float32 record for the flight unit, the float64 values stay with the host law.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from codegen.units.rbf.records import INPUT_DTYPE
from host.core.rotations import (
    euler312_from_dcm,
    euler312_rate_matrix,
    euler312_rate_matrix_dot,
    euler312_rate_matrix_inverse,
    los_frame,
)
from host.plant.proximity import ProximityPlant, chaser_dcm, chaser_rate, relative_state

RHO_DESIRED = 100.0       # m (paper L200)


@dataclass(frozen=True)
class LosMeasurement:
    """One control instant's law input, float64, fields as in INPUT_DTYPE (each a 3-vector)."""

    los: np.ndarray           # rho, q_eps, q_beta
    los_rate: np.ndarray
    euler: np.ndarray         # phi, theta, psi (3-1-2)
    omega: np.ndarray         # body rate, body axes
    los_d: np.ndarray         # rho_d, q_eps_d, q_beta_d (q_beta_d wrapped)
    los_d_rate: np.ndarray
    los_d_acc: np.ndarray
    euler_d: np.ndarray       # phi_f, theta_f, psi_f
    euler_d_rate: np.ndarray
    euler_d_acc: np.ndarray


def to_record(m: LosMeasurement) -> np.ndarray:
    """One INPUT_DTYPE record (shape (1,)), float32 values of m."""
    rec = np.zeros(1, dtype=INPUT_DTYPE)
    for name in INPUT_DTYPE.names:
        rec[name][0] = getattr(m, name)
    return rec


def from_record(rec: np.ndarray) -> LosMeasurement:
    """The float64 measurement of one INPUT_DTYPE record (the float32 values, widened)."""
    rec = np.asarray(rec).reshape(-1)[0]
    return LosMeasurement(**{f.name: np.array(rec[f.name], dtype=float) for f in fields(LosMeasurement)})


def wrap(angle):
    """Angle in [-pi, pi)."""
    return (np.asarray(angle, dtype=float) + math.pi) % (2.0 * math.pi) - math.pi


# ----------------------------------------------------------------------------- LOS kinematics


def los_kinematics(r, v, a=None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(rho, q_eps, q_beta), their rates and (with the acceleration a) second derivatives, for a vector r(t)
    with derivatives v, a (inertial axes); q_eps = asin(y/rho), q_beta = atan2(-z, x). Exact kinematics,
    independent of eq. (2)."""
    x, y, z = (float(c) for c in r)
    vx, vy, vz = (float(c) for c in v)
    rho2 = x * x + y * y + z * z
    rho = math.sqrt(rho2)
    horiz2 = x * x + z * z                     # rho^2 cos^2(q_eps)
    horiz = math.sqrt(horiz2)
    rho_dot = (x * vx + y * vy + z * vz) / rho
    # q_eps = atan2(y, horiz): rate (y' horiz - y horiz') / rho^2
    horiz_dot = (x * vx + z * vz) / horiz
    n_eps = vy * horiz - y * horiz_dot
    eps_dot = n_eps / rho2
    # q_beta = atan2(-z, x): rate (x (-z') - (-z) x') / horiz^2
    n_beta = z * vx - x * vz
    beta_dot = n_beta / horiz2
    angles = np.array([rho, math.atan2(y, horiz), math.atan2(-z, x)])
    rates = np.array([rho_dot, eps_dot, beta_dot])
    if a is None:
        return angles, rates, None
    ax, ay, az = (float(c) for c in a)
    rho_ddot = (vx * vx + vy * vy + vz * vz + x * ax + y * ay + z * az - rho_dot * rho_dot) / rho
    horiz_ddot = (vx * vx + vz * vz + x * ax + z * az - horiz_dot * horiz_dot) / horiz
    eps_ddot = ((ay * horiz - y * horiz_ddot) * rho2 - n_eps * 2.0 * rho * rho_dot) / (rho2 * rho2)
    beta_ddot = ((z * ax - x * az) * horiz2 - n_beta * 2.0 * (x * vx + z * vz)) / (horiz2 * horiz2)
    return angles, rates, np.array([rho_ddot, eps_ddot, beta_ddot])


def los_acceleration_eq2(los, los_rate, accel_los) -> np.ndarray:
    """Eq. (2) of docs section 1 solved for (rho'', q_eps'', q_beta''), with accel_los = C_li (f + Delta_g - u_c),
    the relative acceleration (target minus chaser) in LOS axes."""
    rho, eps, _ = los
    rho_d, eps_d, beta_d = los_rate
    ax, ay, az = accel_los
    ce, se = math.cos(eps), math.sin(eps)
    return np.array([
        ax + rho * eps_d ** 2 + rho * beta_d ** 2 * ce * ce,
        (ay - 2.0 * rho_d * eps_d - rho * beta_d ** 2 * se * ce) / rho,
        -(az + 2.0 * rho_d * beta_d * ce - 2.0 * rho * eps_d * beta_d * se) / (rho * ce),
    ])


def los_frame_rate(los, los_rate) -> np.ndarray:
    """omega_l, the LOS frame's angular velocity in LOS axes: [q_beta' s(q_eps), q_beta' c(q_eps), q_eps']."""
    eps, beta_d, eps_d = los[1], los_rate[2], los_rate[1]
    return np.array([beta_d * math.sin(eps), beta_d * math.cos(eps), eps_d])


def los_frame_acceleration(los, los_rate, los_acc) -> np.ndarray:
    """d/dt omega_l (LOS axes)."""
    eps, eps_d, beta_d = los[1], los_rate[1], los_rate[2]
    eps_dd, beta_dd = los_acc[1], los_acc[2]
    se, ce = math.sin(eps), math.cos(eps)
    return np.array([beta_dd * se + beta_d * ce * eps_d, beta_dd * ce - beta_d * se * eps_d, eps_dd])


# ----------------------------------------------------------------------------- desired state (docs section 3)


@dataclass(frozen=True)
class DesiredState:
    los_d: np.ndarray
    los_d_rate: np.ndarray
    los_d_acc: np.ndarray
    euler_d: np.ndarray
    euler_d_rate: np.ndarray
    euler_d_acc: np.ndarray


def desired_los_direction(plant: ProximityPlant, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """l_d = -C_it n_b and its first two derivatives (constant spin: l' = w x l, l'' = w x (w x l))."""
    w = plant.tumble.rate_vector()
    l_d = -plant.tumble.feature(t)
    l_dot = np.cross(w, l_d)
    return l_d, l_dot, np.cross(w, l_dot)


def desired_attitude(los_d, los_d_rate, los_d_acc) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(phi_f, theta_f, psi_f) of C_bi,d = C_li(q_eps_d, q_beta_d) and their first two derivatives:
    Theta_f' = R^-1 omega_l, Theta_f'' = R^-1 (omega_l' - R' Theta_f') (the desired body rate is the LOS
    frame's rate, in body = LOS axes)."""
    euler_d = euler312_from_dcm(los_frame(los_d[1], los_d[2]))
    phi, theta = euler_d[0], euler_d[1]
    w_l = los_frame_rate(los_d, los_d_rate)
    euler_rate = euler312_rate_matrix_inverse(phi, theta) @ w_l
    R_dot = euler312_rate_matrix_dot(phi, theta, euler_rate[0], euler_rate[1])
    euler_acc = euler312_rate_matrix_inverse(phi, theta) @ (los_frame_acceleration(los_d, los_d_rate, los_d_acc)
                                                            - R_dot @ euler_rate)
    return euler_d, euler_rate, euler_acc


def desired_state(plant: ProximityPlant, t: float, rho_d: float = RHO_DESIRED) -> DesiredState:
    l_d, l_dot, l_ddot = desired_los_direction(plant, t)
    angles, rates, accs = los_kinematics(l_d, l_dot, l_ddot)
    los_d = np.array([rho_d, angles[1], angles[2]])
    los_d_rate = np.array([0.0, rates[1], rates[2]])
    los_d_acc = np.array([0.0, accs[1], accs[2]])
    return DesiredState(los_d, los_d_rate, los_d_acc, *desired_attitude(los_d, los_d_rate, los_d_acc))


# ----------------------------------------------------------------------------- measurement


def chaser_attitude(y) -> tuple[np.ndarray, np.ndarray]:
    """(phi, theta, psi) of the chaser's C_bi and its body rate."""
    return euler312_from_dcm(chaser_dcm(y)), chaser_rate(y)


def measure(plant: ProximityPlant, t: float, y, rho_d: float = RHO_DESIRED) -> LosMeasurement:
    """The law's input from the truth state y at time t (perfect measurements)."""
    r, v = relative_state(y)
    los, los_rate, _ = los_kinematics(r, v)
    euler, omega = chaser_attitude(y)
    d = desired_state(plant, t, rho_d)
    return LosMeasurement(los, los_rate, euler, omega, d.los_d, d.los_d_rate, d.los_d_acc,
                          d.euler_d, d.euler_d_rate, d.euler_d_acc)


def desired_body_rate(euler, euler_d_rate) -> np.ndarray:
    """omega_d = R(phi, theta) Theta_f' with the CURRENT R (docs section 4)."""
    return euler312_rate_matrix(euler[0], euler[1]) @ euler_d_rate
