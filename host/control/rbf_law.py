"""Paper 002's RBF adaptive finite-time backstepping law, float64 host model (theorem 1: eq. 15-18;
theorem 2: eq. 25-26), exactly the discrete step of docs/rbf-backstepping.md section 11, steps 1-8.

The flight unit (codegen/units/rbf, float32) computes the same quantities; this module is its float64
reference for the closed loop. Channel order (rho, q_eps, q_beta, phi, theta, psi). One control period:
`step(params, state, m, period) -> (LawOutput, state after)`; `RbfLaw` carries the state and is the
pluggable controller of host.sim.rbf_tracking (it also accepts the unit's INPUT_DTYPE record).

The pieces are separate functions so that tests can check each against an independent computation:
`tracking_terms` (steps 2-4: errors, virtual control nu, its derivative, z), `basis` (step 5),
`nominal_model` (F, G of section 4), `control_vector` / `commands` (steps 6-7), `adapt` (step 8).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from codegen.units.rbf.params import (  # noqa: F401 (re-exported for host callers)
    ANGLE_MAX,
    RbfParams,
    RbfParamsError,
    load_params,
    paper_params,
    params_from_mapping,
)
from codegen.units.rbf.records import (  # noqa: F401 (re-exported)
    OUTPUT_DTYPE,
    STATUS_FORCE_LIMITED,
    STATUS_INVALID_INPUT,
    STATUS_OK,
    STATUS_TORQUE_LIMITED,
    STATUS_WEIGHT_BOUND,
)
from host.core.rotations import (
    dcm_from_euler312,
    euler312_rate_matrix,
    euler312_rate_matrix_dot,
    euler312_rate_matrix_inverse,
    los_frame,
)
from host.errors import HostError
from host.gnc.los import LosMeasurement, from_record

PERIOD = 0.1        # s, control period (docs section 8)
RESULT_MAX = 1e30   # the flight unit's result guard on sum |v'| + sum |z| (docs section 13)
ZERO3 = np.zeros(3)


class LawOutput(NamedTuple):
    force: np.ndarray      # N, body axes, commanded (clipped to +-force_max)
    torque: np.ndarray     # N*m, body axes, commanded (clipped to +-torque_max)
    w_hat: np.ndarray      # first network's estimate theta^T phi (units of x2')
    status: int


@dataclass(frozen=True)
class RbfState:
    theta: np.ndarray          # (N, 6) weights of the network for w
    theta_delta: np.ndarray    # (N, 6) weights of the network for G Delta_u (theorem 2; zero under theorem 1)
    command: np.ndarray        # (6,) last output (force/force_max, torque/torque_max): the second network's input


def initial_state(p: RbfParams) -> RbfState:
    return RbfState(np.zeros((p.nodes, 6)), np.zeros((p.nodes, 6)), np.zeros(6))


def sig(x, a):
    """sig(x)^a = |x|^a sign(x), element-wise."""
    x = np.asarray(x, dtype=float)
    return np.abs(x) ** a * np.sign(x)


def wrap_difference(d):
    """One +-2 pi correction when a difference of two angles in [-3.5, 3.5] leaves [-pi, pi] (step 3)."""
    d = np.asarray(d, dtype=float)
    return np.where(d > math.pi, d - 2.0 * math.pi, np.where(d < -math.pi, d + 2.0 * math.pi, d))


# ----------------------------------------------------------------------------- step 1: valid box


def _limit(x: float) -> float:
    """A limit as the flight unit holds it (float32), so both refuse the same inputs at the box edge."""
    return float(np.float32(x))


def valid_input(p: RbfParams, m: LosMeasurement) -> bool:
    values = np.concatenate([np.ravel(getattr(m, name)) for name in LosMeasurement.__dataclass_fields__])
    if not np.all(np.isfinite(values)):
        return False
    (rho, eps, beta), (rho_d, eps_d, beta_d) = m.los, m.los_d
    (phi, theta, psi), (phi_f, theta_f, psi_f) = m.euler, m.euler_d
    rates = [m.los_rate[1], m.los_rate[2], *m.omega, m.los_d_rate[1], m.los_d_rate[2], *m.euler_d_rate]
    rho_min, rho_max = _limit(p.rho_min), _limit(p.rho_max)
    return bool(
        rho_min <= rho <= rho_max and rho_min <= rho_d <= rho_max
        and max(abs(eps), abs(eps_d), abs(phi), abs(phi_f)) <= _limit(p.tilt_max)
        and max(abs(beta), abs(theta), abs(psi), abs(beta_d), abs(theta_f), abs(psi_f)) <= _limit(ANGLE_MAX)
        and max(abs(m.los_rate[0]), abs(m.los_d_rate[0])) <= _limit(p.speed_max)
        and max(abs(r) for r in rates) <= _limit(p.rate_max)
        and max(np.max(np.abs(m.los_d_acc)), np.max(np.abs(m.euler_d_acc))) <= _limit(p.accel_max))


# ----------------------------------------------------------------------------- steps 2-4: errors, nu, z


@dataclass(frozen=True)
class TrackingTerms:
    e1: np.ndarray         # x1 (6)
    e2: np.ndarray         # x2 (6)
    e1_dot: np.ndarray     # A(x1) x2
    s: np.ndarray          # sig(e1)^alpha
    eta: np.ndarray        # guarded derivative gain of sig(e1)^alpha
    nu: np.ndarray         # virtual control
    nu_dot: np.ndarray
    z: np.ndarray          # e2 - nu
    R: np.ndarray          # R(phi, theta) of the measured attitude
    R_inv: np.ndarray
    R_dot: np.ndarray      # along the measured Euler rates
    euler_rate: np.ndarray


def tracking_terms(p: RbfParams, m: LosMeasurement) -> TrackingTerms:
    phi, theta = m.euler[0], m.euler[1]
    R = euler312_rate_matrix(phi, theta)
    R_inv = euler312_rate_matrix_inverse(phi, theta)
    euler_rate = R_inv @ m.omega                                     # step 2: Theta' = R^-1 omega
    R_dot = euler312_rate_matrix_dot(phi, theta, euler_rate[0], euler_rate[1])
    e1 = np.concatenate([[m.los[0] - m.los_d[0]], wrap_difference(m.los[1:] - m.los_d[1:]),
                         wrap_difference(m.euler - m.euler_d)])
    omega_d = R @ m.euler_d_rate                                     # current R: x1' = A x2 exactly
    e2 = np.concatenate([m.los_rate - m.los_d_rate, m.omega - omega_d])
    e1_dot = np.concatenate([e2[:3], R_inv @ e2[3:]])
    k1, a, delta = np.asarray(p.k1), p.alpha, p.delta
    s = sig(e1, a)
    abs_e1 = np.abs(e1)
    eta = np.where(abs_e1 > delta, a * np.maximum(abs_e1, delta) ** (a - 1.0), a * delta ** (a - 1.0))
    k1s, k1_eta_e1dot = k1 * s, k1 * eta * e1_dot
    nu = np.concatenate([-k1s[:3], -R @ k1s[3:]])
    nu_dot = np.concatenate([-k1_eta_e1dot[:3], -R_dot @ k1s[3:] - R @ k1_eta_e1dot[3:]])
    return TrackingTerms(e1, e2, e1_dot, s, eta, nu, nu_dot, e2 - nu, R, R_inv, R_dot, euler_rate)


# ----------------------------------------------------------------------------- step 5: RBF basis


def basis(p: RbfParams, e1: np.ndarray, e2: np.ndarray) -> np.ndarray:
    """phi_j = exp(-|e/s - c_j 1|^2 / (2 sigma^2)), diagonal centres (docs section 5)."""
    e = np.concatenate([e1, e2]) / np.asarray(p.input_scale)
    d2 = np.sum((e[None, :] - p.centres()[:, None]) ** 2, axis=1)
    return np.exp(-d2 / (2.0 * p.sigma ** 2))


def command_basis(p: RbfParams, phi: np.ndarray, command: np.ndarray) -> np.ndarray:
    """phi_Delta_j = phi_j exp(-|u_prev - c_j 1|^2 / (2 sigma^2)): the same diagonal layout on the
    18 inputs [e; u_prev] (docs section 7: G Delta_u depends on the command, which the first network
    does not see)."""
    d2 = np.sum((command[None, :] - p.centres()[:, None]) ** 2, axis=1)
    return phi * np.exp(-d2 / (2.0 * p.sigma ** 2))


# ----------------------------------------------------------------------------- step 6: F, G, the law


def nominal_model(p: RbfParams, m: LosMeasurement, t: TrackingTerms) -> tuple[np.ndarray, np.ndarray]:
    """(F, diagonal of G) of x2' = F + G u + w (docs section 4) with the nominal inertia J_n;
    u = [u_c (m/s^2, LOS axes); T_c (N*m, body)]."""
    rho, eps, _ = m.los
    rho_dot, eps_dot, beta_dot = m.los_rate
    ce, se = math.cos(eps), math.sin(eps)
    J = np.asarray(p.inertia)
    w = m.omega
    F = np.array([
        rho * eps_dot ** 2 + rho * beta_dot ** 2 * ce * ce - m.los_d_acc[0],
        (-2.0 * rho_dot * eps_dot - rho * beta_dot ** 2 * se * ce) / rho - m.los_d_acc[1],
        (-2.0 * rho_dot * beta_dot * ce + 2.0 * rho * eps_dot * beta_dot * se) / (rho * ce) - m.los_d_acc[2],
        *(-np.cross(w, J * w) / J - t.R_dot @ m.euler_d_rate - t.R @ m.euler_d_acc),
    ])
    G = np.array([-1.0, -1.0 / rho, 1.0 / (rho * ce), *(1.0 / J)])
    return F, G


def control_vector(p: RbfParams, F: np.ndarray, t: TrackingTerms, w_hat_total: np.ndarray) -> np.ndarray:
    """v = -F - A^T e1 + nu' - K2 sig(z)^alpha - K3 sgn(z) - w_hat (- w_hat_Delta), so that G u = v."""
    At_e1 = np.concatenate([t.e1[:3], t.R_inv.T @ t.e1[3:]])
    return (-F - At_e1 + t.nu_dot - np.asarray(p.k2) * sig(t.z, p.alpha) - p.k3 * np.sign(t.z)
            - w_hat_total)


def body_acceleration(m: LosMeasurement, u_c: np.ndarray) -> np.ndarray:
    """a_b = C_bi C_li^T u_c (exact LOS -> body rotation from the measured attitude and LOS angles)."""
    return dcm_from_euler312(m.euler) @ (los_frame(m.los[1], m.los[2]).T @ u_c)


def commands(p: RbfParams, m: LosMeasurement, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u_c in LOS axes (m/s^2), unclipped force (N, body), unclipped torque (N*m, body)) from G u = v."""
    rho, eps = m.los[0], m.los[1]
    u_c = np.array([-v[0], -rho * v[1], rho * math.cos(eps) * v[2]])
    force = p.mass * body_acceleration(m, u_c)
    torque = np.asarray(p.inertia) * v[3:]
    return u_c, force, torque


# ----------------------------------------------------------------------------- step 8: adaptation


def weight_bounds(p: RbfParams) -> np.ndarray:
    return np.asarray(p.theta_max, dtype=float)


def adapt(p: RbfParams, weights: np.ndarray, phi: np.ndarray, z: np.ndarray, gain: float,
          period: float) -> tuple[np.ndarray, bool]:
    """theta <- clip((1 - T gain lambda) theta + T gain phi z^T, +-theta_max); (new weights, bound hit)."""
    raw = (1.0 - period * gain * p.lam) * weights + period * gain * np.outer(phi, z)
    bound = weight_bounds(p)
    clipped = np.clip(raw, -bound, bound)
    return clipped, bool(np.any(clipped != raw))


# ----------------------------------------------------------------------------- the whole step


def invalid_output() -> LawOutput:
    return LawOutput(ZERO3.copy(), ZERO3.copy(), np.zeros(6), STATUS_INVALID_INPUT)


def step(p: RbfParams, state: RbfState, m: LosMeasurement, period: float = PERIOD) -> tuple[LawOutput, RbfState]:
    """One control period (section 11, steps 1-8)."""
    if not valid_input(p, m):
        return invalid_output(), RbfState(state.theta, state.theta_delta, np.zeros(6))   # the command was 0
    t = tracking_terms(p, m)
    phi = basis(p, t.e1, t.e2)
    phi_delta = command_basis(p, phi, state.command)
    w_hat = state.theta.T @ phi
    w_hat_delta = state.theta_delta.T @ phi_delta if p.theorem == 2 else np.zeros(6)
    F, _ = nominal_model(p, m, t)
    v = control_vector(p, F, t, w_hat + w_hat_delta)
    if np.sum(np.abs(v + w_hat + w_hat_delta)) + np.sum(np.abs(t.z)) > RESULT_MAX:
        # the unit's result guard (docs section 13): a law this far out (absurd gains) is refused
        return invalid_output(), RbfState(state.theta, state.theta_delta, np.zeros(6))
    _, force, torque = commands(p, m, v)
    status = STATUS_OK
    if np.any(np.abs(force) > p.force_max):
        status |= STATUS_FORCE_LIMITED
    if np.any(np.abs(torque) > p.torque_max):
        status |= STATUS_TORQUE_LIMITED
    force = np.clip(force, -p.force_max, p.force_max)
    torque = np.clip(torque, -p.torque_max, p.torque_max)
    theta, hit = adapt(p, state.theta, phi, t.z, p.gamma, period)
    theta_delta = state.theta_delta
    if p.theorem == 2:
        theta_delta, hit_delta = adapt(p, state.theta_delta, phi_delta, t.z, p.gamma_delta, period)
        hit = hit or hit_delta
    if hit:
        status |= STATUS_WEIGHT_BOUND
    if not (np.all(np.isfinite(force)) and np.all(np.isfinite(torque)) and np.all(np.isfinite(theta))
            and np.all(np.isfinite(theta_delta))):
        return invalid_output(), RbfState(state.theta, state.theta_delta, np.zeros(6))
    command = np.concatenate([force / p.force_max, torque / p.torque_max])
    return LawOutput(force, torque, w_hat, status), RbfState(theta, theta_delta, command)


class RbfLaw:
    """The float64 law with its state: call it with a LosMeasurement (or step_record with an INPUT_DTYPE
    record) once per control period."""

    def __init__(self, params: RbfParams, period: float = PERIOD):
        if not (period > 0 and math.isfinite(period)):
            raise HostError(f"control period must be a positive number of seconds, got {period!r}")
        if period * max(params.gamma, params.gamma_delta) * params.lam >= 1.0:
            raise HostError(f"control period {period!r} s: the leakage factor 1 - T*gamma*lambda must stay > 0")
        self.params, self.period = params, float(period)
        self.state = initial_state(params)

    def __call__(self, m: LosMeasurement) -> LawOutput:
        out, self.state = step(self.params, self.state, m, self.period)
        return out

    def step_record(self, record: np.ndarray) -> np.ndarray:
        """One OUTPUT_DTYPE record (shape (1,)) for one INPUT_DTYPE record."""
        out = self(from_record(record))
        rec = np.zeros(1, dtype=OUTPUT_DTYPE)
        rec["force"][0], rec["torque"][0], rec["w_hat"][0], rec["status"][0] = out
        return rec
