"""Truth of paper 004's attitude takeover (docs/gp-takeover.md section 1): the servicer (Table 6 body
with wheels) holding a captured target, one rigid combined body, and the target's PD counter-torque
(eq. 42) towards the pointing it had at capture.

Dynamics: host.plant.spacecraft.state_derivative with the combined inertia J_c and the counter-torque
as the external torque:  J_c ω̇ + ω×(J_c ω + h_w) = u + τ_t,  ḣ_w = −u.
The counter-torque depends on the state, so it is re-evaluated at every RK4 stage (it is a continuous
law of the target, not a held command); the wheel command is held over the control period (ZOH).

The unknown term of section 2 (what the GP learns), against the servicer's prior J_s:
    d := J_s ω̇ + ω×(J_s ω) + ω×h_w − u  =  −ΔJ ω̇ − ω×(ΔJ ω) + τ_t,   ΔJ = J_c − J_s.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from host.core.constants import DEG
from host.core.rotations import active_rot_z
from host.core.vec3 import cross3
from host.errors import HostError
from host.plant.spacecraft import (
    TABLE6,
    TABLE6_INERTIA,
    momentum_limited_torque,
    pack_state,
    saturate_torque,
    state_derivative,
)

# ----------------------------------------------------------------------------- section 1 numbers

SERVICER_MASS = TABLE6.mass                       # kg
TARGET_MASS = 300.0                               # kg
TARGET_INERTIA = np.diag([150.0, 120.0, 100.0])   # kg m^2, target axes
TARGET_ROTATION = active_rot_z(30.0 * DEG)        # R_st: target axes -> servicer axes
COM_OFFSET = np.array([2.5, 0.3, -0.2])           # m, servicer CoM -> target CoM

COUNTER_KP = 0.5         # N·m
COUNTER_KD = 5.0         # N·m·s/rad
COUNTER_LIMIT = 0.1      # N·m per axis

CAPTURE_AXIS = np.array([0.6, -0.48, 0.64])       # unit (0.36 + 0.2304 + 0.4096 = 1)
CAPTURE_ANGLE = 20.0 * DEG
CAPTURE_RATE = np.array([0.3, -0.5, 0.4]) * DEG   # rad/s

DT = 0.01        # s, RK4 step
PERIOD = 0.1     # s, control period (ZOH)


def combined_inertia(J_s, m_s, J_t, m_t, R_st, r) -> np.ndarray:
    """J_c about the combined CoM: J_s + R_st J_t R_stᵀ + μ_r (‖r‖² I − r rᵀ), μ_r = m_s m_t / (m_s + m_t).
    (The two parallel-axis shifts to the common CoM sum to the reduced-mass term.)"""
    if not (m_s > 0 and m_t > 0):
        raise HostError(f"masses must be positive, got m_s={m_s!r}, m_t={m_t!r}")
    r = np.asarray(r, dtype=float)
    mu = m_s * m_t / (m_s + m_t)
    return (np.asarray(J_s, float) + R_st @ np.asarray(J_t, float) @ R_st.T
            + mu * ((r @ r) * np.eye(3) - np.outer(r, r)))


def axis_angle_quat(axis, angle: float) -> np.ndarray:
    """Scalar-last quaternion of a rotation by `angle` about the unit `axis` (reference -> body)."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    return np.concatenate([math.sin(0.5 * angle) * a, [math.cos(0.5 * angle)]])


def quat_compose(p, q) -> np.ndarray:
    """Wie's product: the quaternion of C(p) C(q) (first q, then p), scalar last."""
    p1, p2, p3, p4 = p
    return np.array([
        p4 * q[0] + p3 * q[1] - p2 * q[2] + p1 * q[3],
        -p3 * q[0] + p4 * q[1] + p1 * q[2] + p2 * q[3],
        p2 * q[0] - p1 * q[1] + p4 * q[2] + p3 * q[3],
        -p1 * q[0] - p2 * q[1] - p3 * q[2] + p4 * q[3],
    ])


def quat_conjugate(q) -> np.ndarray:
    return np.array([-q[0], -q[1], -q[2], q[3]])


def error_quat(q, q_ref) -> np.ndarray:
    """q_e of C(q) C(q_ref)ᵀ with q_e4 ≥ 0 (the shorter way round)."""
    q_e = quat_compose(q, quat_conjugate(q_ref))
    return q_e if q_e[3] >= 0.0 else -q_e


def counter_torque(q, omega, q_t0, kp: float = COUNTER_KP, kd: float = COUNTER_KD,
                   limit: float = COUNTER_LIMIT) -> np.ndarray:
    """Eq. 42: the target's PD back towards its capture pointing, saturated per axis (combined body axes;
    scalar gains make the PD the same in the target's axes)."""
    q_e = error_quat(q, q_t0)
    return np.clip(-kp * q_e[:3] - kd * np.asarray(omega, float), -limit, limit)


@dataclass(frozen=True)
class TakeoverPlant:
    """Combined body with the servicer's wheels and the target's counter-torque."""

    inertia: np.ndarray = field(default_factory=lambda: combined_inertia(
        TABLE6_INERTIA, SERVICER_MASS, TARGET_INERTIA, TARGET_MASS, TARGET_ROTATION, COM_OFFSET))
    prior_inertia: np.ndarray = field(default_factory=lambda: TABLE6_INERTIA.copy())
    q_t0: np.ndarray = field(default_factory=lambda: axis_angle_quat(CAPTURE_AXIS, CAPTURE_ANGLE))
    kp: float = COUNTER_KP
    kd: float = COUNTER_KD
    counter_limit: float = COUNTER_LIMIT
    torque_limit: float = TABLE6.torque_limit
    momentum_limit: float = TABLE6.momentum_limit

    @functools.cached_property
    def inertia_inv(self) -> np.ndarray:
        return np.linalg.inv(self.inertia)

    @functools.cached_property
    def delta_inertia(self) -> np.ndarray:
        return self.inertia - self.prior_inertia

    def counter_torque(self, x) -> np.ndarray:
        return counter_torque(x[0:4], x[4:7], self.q_t0, self.kp, self.kd, self.counter_limit)

    def derivative(self, x, u) -> np.ndarray:
        """d/dt [q, ω, h_w] for the applied wheel torque u (N·m, on the body)."""
        return state_derivative(x, u, self.counter_torque(x), self.inertia, self.inertia_inv)

    def rk4_step(self, x, u, dt: float = DT) -> np.ndarray:
        f = self.derivative
        k1 = f(x, u)
        k2 = f(x + 0.5 * dt * k1, u)
        k3 = f(x + 0.5 * dt * k2, u)
        k4 = f(x + dt * k3, u)
        x_new = x + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        x_new[0:4] /= math.sqrt(x_new[0:4] @ x_new[0:4])
        return x_new

    def applied_torque(self, command, h_w) -> np.ndarray:
        """Wheel torque on the body: clipped to the torque limit, zero on an axis whose wheel is at its
        momentum limit and would spin up further (ḣ_w = −u)."""
        u = saturate_torque(np.asarray(command, dtype=float), self.torque_limit)
        return momentum_limited_torque(u, np.asarray(h_w, dtype=float), self.momentum_limit)

    def hold(self, x, u, period: float = PERIOD, dt: float = DT) -> np.ndarray:
        """Propagate one control period with the applied wheel torque u held (n equal RK4 steps ≤ dt);
        `applied_torque` is the caller's, once per period (the momentum limit acts at control instants)."""
        n = max(1, math.ceil(period / dt - 1e-9))
        h = period / n
        for _ in range(n):
            x = self.rk4_step(x, u, h)
        return x

    def unknown_term(self, x, omega_dot) -> np.ndarray:
        """Section 2's d from the truth: −ΔJ ω̇ − ω×(ΔJ ω) + τ_t."""
        w = x[4:7]
        dJ = self.delta_inertia
        return -dJ @ omega_dot - cross3(w, dJ @ w) + self.counter_torque(x)

    def unknown_term_at_rest_acceleration(self, q, omega) -> np.ndarray:
        """d₀ = τ_t − ω×(ΔJ ω): d at ω̇ = 0, what the GP law's mean should equal (the oracle)."""
        omega = np.asarray(omega, float)
        tau = counter_torque(q, omega, self.q_t0, self.kp, self.kd, self.counter_limit)
        return tau - cross3(omega, self.delta_inertia @ omega)


def measured_unknown_term(prior_inertia, omega, omega_dot, h_w, u) -> np.ndarray:
    """Section 2's d from measurable quantities: J_s ω̇ + ω×(J_s ω) + ω×h_w − u."""
    J = np.asarray(prior_inertia, float)
    return J @ omega_dot + cross3(omega, J @ omega + h_w) - u


def capture_state(plant: TakeoverPlant, omega0=CAPTURE_RATE, h_w0=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Post-capture state: attitude q_t0 (the target's pointing), residual tumble ω(0), wheels at rest."""
    return pack_state(plant.q_t0, omega0, h_w0)
