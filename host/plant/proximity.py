"""Truth of paper 002's proximity scenario in inertial space (ECI): a tumbling, manoeuvring target on a
circular LEO orbit and a chaser (rigid body with body-fixed thrusters and torquers) near it.

Choices: docs/rbf-backstepping.md section 8. Both bodies are two-body (point-mass gravity, MU_EARTH), so the
gravity difference Delta_g is real truth that the law neglects. The target's tumble is a torque-free spin
about a principal axis, which is exactly a constant rotation about an inertially fixed axis: its attitude is
analytic in t (`TargetTumble`), not integrated. The chaser's truth mass and inertia differ from the law's
nominal ones (params: 100 kg, 1.1 J).

State y (19 floats): target r, v (0:6); chaser r, v (6:12); chaser quaternion q = [q1, q2, q3, q4]
(scalar last, inertial -> body, host.core.rotations.dcm_from_quat) (12:16); chaser body rate (16:19).
Propagation: RK4 steps of <= dt with the applied force and torque held (zero-order hold of the command).
Written on plain floats: a paper-length run takes 4e5 rate evaluations, where 3-vector numpy calls
would cost more than the arithmetic.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from host.core.constants import DEG, MU_EARTH
from host.core.rotations import dcm_from_quat

Vec = tuple[float, float, float]

TARGET_RADIUS = 6_878_000.0          # m, circular orbit (500 km altitude)
TARGET_INCLINATION = 45.0 * DEG      # orbit plane; nothing in the law depends on it
SPIN_RATE = 0.5 * DEG                # rad/s, target tumble
SPIN_TILT = 20.0 * DEG               # spin axis 20 deg from y_i (in the x_i-y_i plane)
FEATURE_PHASE = 40.0 * DEG           # where the feature axis x_t starts on its great circle
MANOEUVRE_STEP_TIME = 400.0          # s
MANOEUVRE_STEP = 0.005               # m/s^2 on x_i


def target_manoeuvre(t: float) -> Vec:
    """f(t) of docs section 8 (inertial, m/s^2): smooth sinusoids plus a 0.005 m/s^2 x step at 400 s."""
    step = MANOEUVRE_STEP if t >= MANOEUVRE_STEP_TIME else 0.0
    return (0.010 * math.sin(0.05 * t) + step, 0.008 * math.cos(0.03 * t), 0.006 * math.sin(0.02 * t + 1.0))


def dead_zone_saturation(u, dead_zone: float, limit: float) -> np.ndarray:
    """D(u) of docs section 7 per component: 0 inside the gap |u| < dead_zone, u in the band, +-limit beyond."""
    u = np.asarray(u, dtype=float)
    return np.where(np.abs(u) < dead_zone, 0.0, np.clip(u, -limit, limit))


@dataclass(frozen=True)
class Actuators:
    """Per body axis: thrust (N) and torque (N*m) dead zone and saturation (docs section 8)."""

    thrust_dead_zone: float = 1.0        # 0.01 m/s^2 x 100 kg
    thrust_max: float = 200.0            # = params force_max
    torque_dead_zone: float = 0.005
    torque_max: float = 0.5              # = params torque_max

    def apply(self, force, torque) -> tuple[np.ndarray, np.ndarray]:
        return (dead_zone_saturation(force, self.thrust_dead_zone, self.thrust_max),
                dead_zone_saturation(torque, self.torque_dead_zone, self.torque_max))


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


@dataclass(frozen=True)
class TargetTumble:
    """Torque-free spin at `rate` about the principal axis `axis` (inertial, fixed); the target's body y axis
    is the spin axis and the feature unit vector n_b is the body x axis."""

    rate: float = SPIN_RATE
    axis: tuple = (math.sin(SPIN_TILT), math.cos(SPIN_TILT), 0.0)
    feature_phase: float = FEATURE_PHASE
    n_b: tuple = (1.0, 0.0, 0.0)

    def initial_dcm(self) -> np.ndarray:
        """C_it(0), target body -> inertial (columns: body axes in inertial axes)."""
        a = _unit(self.axis)
        ref = _unit(np.cross(a, [0.0, 0.0, 1.0]))            # in the x_i-y_i plane, perpendicular to a
        x_t = math.cos(self.feature_phase) * ref + math.sin(self.feature_phase) * np.cross(ref, a)
        return np.stack([x_t, a, np.cross(x_t, a)], axis=1)

    def rate_vector(self) -> np.ndarray:
        """omega_t in inertial axes (constant)."""
        return self.rate * _unit(self.axis)

    def dcm(self, t: float) -> np.ndarray:
        """C_it(t) = Rot(axis, rate*t) C_it(0) (Rodrigues, active rotation about the fixed axis)."""
        a = _unit(self.axis)
        angle = self.rate * t
        K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        rot = np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)
        return rot @ self.initial_dcm()

    def feature(self, t: float) -> np.ndarray:
        """C_it(t) n_b: the feature direction in inertial axes."""
        return self.dcm(t) @ np.asarray(self.n_b, dtype=float)


def circular_orbit_state(radius: float = TARGET_RADIUS, inclination: float = TARGET_INCLINATION) -> np.ndarray:
    """[r, v] of a circular orbit at the ascending node (t = 0)."""
    v = math.sqrt(MU_EARTH / radius)
    return np.array([radius, 0.0, 0.0, 0.0, v * math.cos(inclination), v * math.sin(inclination)])


def _gravity(x: float, y: float, z: float) -> Vec:
    r2 = x * x + y * y + z * z
    k = -MU_EARTH / (r2 * math.sqrt(r2))
    return (k * x, k * y, k * z)


@dataclass(frozen=True)
class ProximityPlant:
    """Truth dynamics of target and chaser; `rates`, `rk4_step`, `hold` (one control period)."""

    mass: float = 95.0                                   # kg, truth (the law's nominal: params.mass)
    inertia: tuple = (10.0, 12.0, 14.0)                  # kg*m^2, truth, diagonal
    actuators: Actuators = field(default_factory=Actuators)
    manoeuvre: Callable[[float], Vec] = target_manoeuvre
    tumble: TargetTumble = field(default_factory=TargetTumble)

    def rates(self, t: float, y, force_b: Vec, torque: Vec) -> list[float]:
        """dy/dt for the APPLIED body-axis force (N) and torque (N*m)."""
        tx, ty, tz, tvx, tvy, tvz, cx, cy, cz, cvx, cvy, cvz, q1, q2, q3, q4, w1, w2, w3 = y
        gt = _gravity(tx, ty, tz)
        f = self.manoeuvre(t)
        gc = _gravity(cx, cy, cz)
        # thrust in inertial axes: C_ib F = C_bi^T F with Wie's C_bi(q)
        F1, F2, F3 = force_b[0] / self.mass, force_b[1] / self.mass, force_b[2] / self.mass
        c11, c12, c13 = 1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 + q3 * q4), 2 * (q1 * q3 - q2 * q4)
        c21, c22, c23 = 2 * (q2 * q1 - q3 * q4), 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 + q1 * q4)
        c31, c32, c33 = 2 * (q3 * q1 + q2 * q4), 2 * (q3 * q2 - q1 * q4), 1 - 2 * (q1 * q1 + q2 * q2)
        ax = c11 * F1 + c21 * F2 + c31 * F3
        ay = c12 * F1 + c22 * F2 + c32 * F3
        az = c13 * F1 + c23 * F2 + c33 * F3
        # quaternion rate 0.5 Omega(w) q (paper 001 eq. 3) and Euler's equation (diagonal J)
        J1, J2, J3 = self.inertia
        return [tvx, tvy, tvz, gt[0] + f[0], gt[1] + f[1], gt[2] + f[2],
                cvx, cvy, cvz, gc[0] + ax, gc[1] + ay, gc[2] + az,
                0.5 * (w3 * q2 - w2 * q3 + w1 * q4), 0.5 * (-w3 * q1 + w1 * q3 + w2 * q4),
                0.5 * (w2 * q1 - w1 * q2 + w3 * q4), 0.5 * (-w1 * q1 - w2 * q2 - w3 * q3),
                (torque[0] - (J3 - J2) * w2 * w3) / J1,
                (torque[1] - (J1 - J3) * w3 * w1) / J2,
                (torque[2] - (J2 - J1) * w1 * w2) / J3]

    def rk4_step(self, t: float, y, h: float, force_b: Vec, torque: Vec) -> list[float]:
        """One RK4 step with force and torque held; the quaternion is renormalised after the step."""
        k1 = self.rates(t, y, force_b, torque)
        k2 = self.rates(t + 0.5 * h, [a + 0.5 * h * b for a, b in zip(y, k1)], force_b, torque)
        k3 = self.rates(t + 0.5 * h, [a + 0.5 * h * b for a, b in zip(y, k2)], force_b, torque)
        k4 = self.rates(t + h, [a + h * b for a, b in zip(y, k3)], force_b, torque)
        out = [a + h / 6.0 * (b + 2.0 * (p + q) + r) for a, b, p, q, r in zip(y, k1, k2, k3, k4)]
        n = math.sqrt(out[12] ** 2 + out[13] ** 2 + out[14] ** 2 + out[15] ** 2)
        out[12:16] = [x / n for x in out[12:16]]
        return out

    def hold(self, t: float, y, period: float, dt: float, force_b: Vec, torque: Vec) -> list[float]:
        """Propagate over one control period with the APPLIED force and torque held (n equal RK4 steps <= dt)."""
        n = max(1, math.ceil(period / dt - 1e-9))
        h = period / n
        y = list(y)
        for k in range(n):
            y = self.rk4_step(t + k * h, y, h, force_b, torque)
        return y


# ----------------------------------------------------------------------------- state views


def relative_state(y) -> tuple[np.ndarray, np.ndarray]:
    """Target minus chaser position and velocity (inertial axes): the paper's rho vector."""
    y = np.asarray(y, dtype=float)
    return y[0:3] - y[6:9], y[3:6] - y[9:12]


def chaser_dcm(y) -> np.ndarray:
    """C_bi of the chaser."""
    return dcm_from_quat(np.asarray(y[12:16], dtype=float))


def chaser_rate(y) -> np.ndarray:
    return np.asarray(y[16:19], dtype=float)
