"""The batched closed-loop staring simulator: many PID scenarios advanced at once.

A scenario is (target, gain set, seed). One run holds T targets × G gain sets × N seeds,
laid out target-major as numpy arrays (T, G·N, …), and advances them together through the same
loop as the scalar simulator (host.sim.simulator, the reference): the sensors sample the true state
every control period, the PID law of paper 001 (Table 1 form, host.control.pid) commands a torque,
the wheels apply it (saturation, Table 6 errors, momentum limit) held over the period, and RK4 at
the plant step integrates eq. 4 with the environmental torques re-evaluated at every plant step.

What is shared and what is not:
* the orbit and its environment are one track for every scenario (they do not depend on attitude);
* the desired state of each target (from the true orbit: the GPS is ideal, so the controller's own
  guidance equals it) is computed once per target, at every plant sample;
* common random numbers: the noise of a scenario depends only on its target and seed, exactly as in
  the scalar simulator (SeedSequence([seed, stream]) split into star-sensor, gyro and wheel
  generators, stream = the target's index), never on its gains, so gain sets are compared on
  identical noise and every scenario reproduces its scalar run.

The staring metrics (eq. 6-8) are accumulated on the fly: at each plant sample the true errors are
formed and added, with the sample's window multiplicity (a sample on the boundary of two imaging
windows counts twice, as in host.sim.metrics), per axis, so that per-axis objectives are available
for tuning. No history is kept: memory is O(scenarios), not O(scenarios × samples).

Test inputs (step and frequency responses) are functions of time giving either one (3,) vector for
all scenarios or a (S, 3) array, one row per scenario in the flattened order (target, gain, seed).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from host.core.constants import DEG
from host.errors import HostError
from host.gnc.guidance import desired_state
from host.plant.disturbances import DisturbanceParams
from host.plant.environment import SOLAR_PRESSURE, EnvironmentTrack
from host.core.constants import MU_EARTH
from host.sim.metrics import DEFAULT_PLAN, K1, K2, ImagingPlan, window_samples
from host.sim.simulator import SimConfig, environment_track, initial_state

TimeInput = Callable[[float], np.ndarray]


@dataclass(frozen=True)
class GainSets:
    """G PID gain sets (paper units: N·m/°, N·m/(°·s), N·m/(°/s)), each (G, 3) per axis."""
    kp: np.ndarray
    ki: np.ndarray
    kd: np.ndarray

    def __post_init__(self):
        shapes = {np.shape(self.kp), np.shape(self.ki), np.shape(self.kd)}
        if len(shapes) != 1 or len(next(iter(shapes))) != 2 or next(iter(shapes))[1] != 3:
            raise HostError(f"gain sets: kp, ki, kd must all be (G, 3) arrays, got {sorted(shapes)}")
        for name in ("kp", "ki", "kd"):
            if not np.all(np.isfinite(getattr(self, name))):
                raise HostError(f"gain sets: {name} has non-finite entries")

    def __len__(self) -> int:
        return int(np.shape(self.kp)[0])

    @classmethod
    def single(cls, kp, ki, kd) -> "GainSets":
        return cls(np.atleast_2d(np.asarray(kp, float)), np.atleast_2d(np.asarray(ki, float)),
                   np.atleast_2d(np.asarray(kd, float)))


@dataclass
class BatchResult:
    """Per-scenario staring metrics, arrays (T, G, N) or (T, G, N, 3) per axis; deg and deg/s."""
    J_A_axis: np.ndarray
    J_w_axis: np.ndarray
    m: int
    p: int
    saturated_steps: np.ndarray      # (T, G, N) control steps with any axis saturated

    @property
    def J_A(self) -> np.ndarray:
        return self.J_A_axis.mean(-1)

    @property
    def J_w(self) -> np.ndarray:
        return self.J_w_axis.mean(-1)

    def J(self, k1: float = K1, k2: float = K2) -> np.ndarray:
        return k1 * self.J_A + k2 * self.J_w

    def J_axis(self, k1: float = K1, k2: float = K2) -> np.ndarray:
        """Eq. 8 restricted to one axis: k1·mean|A_e,i| + k2·mean|ω_e,i| (its mean over axes is J)."""
        return k1 * self.J_A_axis + k2 * self.J_w_axis


# ----------------------------------------------------------------------------- component-major algebra
# Vectors are (3, T, B) arrays and matrices (3, 3, T, B): each component is one contiguous (T, B)
# array, so every formula below is the scalar simulator's, written out on whole arrays (the same
# formulas as host.core.rotations / host.core.vec3). A constant matrix acts through one BLAS call.

def _cross(a, b):
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _const_matvec(M, v):
    """(3, 3) constant matrix times (3, T, B) vectors."""
    return (M @ v.reshape(3, -1)).reshape(v.shape)


def _rows_dot_const(L, c):
    """L (3, 3, T, B) times a constant (3,) vector: (3, T, B)."""
    return (L[:, 0] * c[0] + L[:, 1] * c[1]) + L[:, 2] * c[2]


def _dcm_from_quat(q):
    q1, q2, q3, q4 = q[0], q[1], q[2], q[3]
    return np.stack([np.stack(r) for r in (
        (1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 + q3 * q4), 2 * (q1 * q3 - q2 * q4)),
        (2 * (q2 * q1 - q3 * q4), 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 + q1 * q4)),
        (2 * (q3 * q1 + q2 * q4), 2 * (q3 * q2 - q1 * q4), 1 - 2 * (q1 * q1 + q2 * q2)))])


def _dcm_from_euler312(A):
    """Ry(theta) Rx(phi) Rz(psi), written out."""
    sf, cf = np.sin(A[0]), np.cos(A[0])
    st, ct = np.sin(A[1]), np.cos(A[1])
    sp, cp = np.sin(A[2]), np.cos(A[2])
    return np.stack([np.stack(r) for r in (
        (ct * cp - st * sf * sp, ct * sp + st * sf * cp, -st * cf),
        (-cf * sp, cf * cp, sf),
        (st * cp + ct * sf * sp, st * sp - ct * sf * cp, ct * cf))])


def _euler312_from_entries(entry) -> np.ndarray:
    """host.core.rotations.euler312_from_dcm from an entry(i, k) function of the DCM."""
    phi = np.arcsin(np.clip(entry(1, 2), -1.0, 1.0))
    psi = np.arctan2(-entry(1, 0), entry(1, 1))
    theta = np.arctan2(-entry(0, 2), entry(2, 2))
    return np.stack([phi, theta, psi])


def _euler312(L):
    return _euler312_from_entries(lambda i, k: L[i, k])


def _euler312_of_product(L, R_t):
    """euler312(L · R^T) for L (3, 3, T, B) and per-target R (T, 3, 3): only the five entries the
    angles need, each a row of L dotted with a row of R."""
    def entry(i, k):
        return (L[i, 0] * R_t[:, k, 0, None] + L[i, 1] * R_t[:, k, 1, None]) + L[i, 2] * R_t[:, k, 2, None]
    return _euler312_from_entries(entry)


def _matmul(A, B):
    """(3, 3, T, B) · (3, 3, T, B), entry by entry."""
    return np.stack([np.stack([(A[i, 0] * B[0, k] + A[i, 1] * B[1, k]) + A[i, 2] * B[2, k] for k in range(3)])
                     for i in range(3)])


def _quat_rate(q, w):
    q1, q2, q3, q4 = q[0], q[1], q[2], q[3]
    wx, wy, wz = w[0], w[1], w[2]
    return 0.5 * np.stack([q4 * wx - (wy * q3 - wz * q2), q4 * wy - (wz * q1 - wx * q3),
                           q4 * wz - (wx * q2 - wy * q1), -(wx * q1 + wy * q2 + wz * q3)])


# ----------------------------------------------------------------------------- plant

class _Plant:
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
        r_hat_b = _rows_dot_const(L_bi, R / r)
        gg = (3.0 * MU_EARTH / r ** 3) * _cross(r_hat_b, _const_matvec(self.inertia, r_hat_b))
        v_b = _rows_dot_const(L_bi, env.v_rel[j])
        speed = np.sqrt((v_b[0] * v_b[0] + v_b[1] * v_b[1]) + v_b[2] * v_b[2])
        drag = _cross(p.drag_cp_offset, -0.5 * env.rho[j] * p.drag_coefficient * p.drag_area * speed * v_b)
        s_b = _rows_dot_const(L_bi, env.sun_dir[j])
        srp = _cross(p.srp_cp_offset, -env.sunlit[j] * SOLAR_PRESSURE * p.srp_area * (1.0 + p.srp_reflectivity) * s_b)
        mag = _cross(p.residual_dipole, _rows_dot_const(L_bi, env.B[j]))
        return ((gg + drag) + srp) + mag

    def derivative(self, x, M_c, M_ext):
        q, w, h = x[0:4], x[4:7], x[7:10]
        gyroscopic = _cross(w, _const_matvec(self.inertia, w) + h)
        wdot = _const_matvec(self.inertia_inv, (M_c + M_ext) - gyroscopic)
        return np.concatenate([_quat_rate(q, w), wdot, -M_c])

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


def _momentum_limited(M_c, h, limit: float):
    spinning_up = (np.abs(h) >= limit) & (np.sign(-M_c) == np.sign(h))
    return np.where(spinning_up, 0.0, M_c)


# ----------------------------------------------------------------------------- noise (common random numbers)

def _noise(cfg: SimConfig, streams: Sequence[int], seeds: Sequence[int], n_ctrl: int):
    """(T, N, n_ctrl, 3) star, gyro and wheel noise, drawn exactly as the scalar run draws it."""
    shape = (len(streams), len(seeds), n_ctrl, 3)
    star, gyro, wheel = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    for t, stream in enumerate(streams):
        for n, seed in enumerate(seeds):
            g_star, g_gyro, g_wheel = (np.random.default_rng(s)
                                       for s in np.random.SeedSequence([seed, stream]).spawn(3))
            if cfg.sensor_errors:
                star[t, n] = g_star.normal(0.0, cfg.sensors.star_sigma, (n_ctrl, 3))
                gyro[t, n] = g_gyro.normal(0.0, cfg.sensors.gyro_sigma, (n_ctrl, 3))
            if cfg.wheel_errors:
                wheel[t, n] = g_wheel.normal(0.0, cfg.spacecraft.wheel_noise_sigma, (n_ctrl, 3))
    return star, gyro, wheel


def _per_scenario(noise: np.ndarray, n_gains: int, k: int) -> np.ndarray:
    """(T, N, n_ctrl, 3) -> (3, T, G·N) at control step k, the same noise for every gain set."""
    T, N = noise.shape[:2]
    per = np.broadcast_to(noise[:, None, :, k], (T, n_gains, N, 3)).reshape(T, n_gains * N, 3)
    return np.moveaxis(per, -1, 0)


# ----------------------------------------------------------------------------- the run

def _sample_weights(cfg: SimConfig, plan: ImagingPlan, n: int) -> tuple[np.ndarray, int, int]:
    """How many imaging windows hold each plant sample (0, 1 or 2), the window count m and p."""
    t = np.arange(n + 1) * cfg.plant_step
    windows = plan.windows(cfg.control_steps * cfg.control_period)
    idx = window_samples(t, windows)
    counts = {len(i) for i in idx}
    if len(counts) != 1 or 0 in counts:
        raise HostError("imaging windows do not hold equal numbers of samples; use a plant step that divides T_img")
    weights = np.bincount(np.concatenate(idx), minlength=n + 1)
    return weights, len(idx), counts.pop() - 1


def _broadcast_input(value, T: int, B: int) -> np.ndarray:
    """A test input as (3, T, B): one (3,) vector for all scenarios, or (T·B, 3) rows."""
    v = np.asarray(value, float)
    if v.shape == (3,):
        return v[:, None, None]
    if v.shape == (T * B, 3):
        return np.moveaxis(v.reshape(T, B, 3), -1, 0)
    raise HostError(f"a test input must give (3,) or ({T * B}, 3) (one row per scenario), got {v.shape}")


def simulate_pid_batch(targets: Sequence[tuple[float, float]], gains: GainSets, seeds: Sequence[int] = (0,),
                       config: SimConfig = SimConfig(), plan: ImagingPlan = DEFAULT_PLAN,
                       streams: Sequence[int] | None = None, torque_limit: float | None = None,
                       progress: Callable[[int], None] | None = None) -> BatchResult:
    """Fly the PID with every gain set at every target under every seed.

    targets: (lon, lat) rad; target i uses noise stream `streams[i]` (default i, as
    host.sim.simulator.simulate_targets does). config.extra_torque / attitude_offset may return
    (3,) or (T·G·N, 3). `progress(k)` is called after each control step.
    """
    cfg = config
    T, G, N = len(targets), len(gains), len(seeds)
    if T == 0 or G == 0 or N == 0:
        raise HostError(f"batched simulation needs at least one target, gain set and seed (got {T}, {G}, {N})")
    streams = list(range(T)) if streams is None else list(streams)
    if len(streams) != T:
        raise HostError(f"{len(streams)} noise streams for {T} targets")
    sub, n_ctrl = cfg.substeps, cfg.control_steps
    n = n_ctrl * sub
    B = G * N
    env = environment_track(n + 1, cfg.plant_step)
    weights, m, p = _sample_weights(cfg, plan, n)
    plant = _Plant(cfg, env)
    sc, se = cfg.spacecraft, cfg.sensors
    limit = sc.torque_limit if torque_limit is None else float(torque_limit)

    # desired state of each target at every plant sample, from the true orbit
    L_di = np.empty((n + 1, T, 3, 3))
    w_d = np.empty((n + 1, 3, T, 1))
    x0 = np.empty((10, T, 1))
    for i, (lon, lat) in enumerate(targets):
        d = desired_state(env.jd_days, env.sec_of_day, env.R, env.V, lon, lat)
        L_di[:, i], w_d[:, :, i, 0] = d.L_di, d.omega_d
        x0[:, i, 0] = initial_state(env, lon, lat)
    x = np.ascontiguousarray(np.broadcast_to(x0, (10, T, B)))

    # gains per scenario, (3, 1, B) over the gain-major, seed-minor layout
    def per_gain(a):
        return np.repeat(np.asarray(a, float), N, axis=0).T[:, None, :]
    kp, ki, kd = per_gain(gains.kp), per_gain(gains.ki), per_gain(gains.kd)
    integral = np.zeros((3, T, B))
    star, gyro, wheel = _noise(cfg, streams, seeds, n_ctrl)
    star_bias, gyro_bias, wheel_bias = (np.asarray(v, float)[:, None, None]
                                        for v in (se.star_bias, se.gyro_bias, sc.wheel_bias))
    sum_A = np.zeros((3, T, B))
    sum_w = np.zeros((3, T, B))
    saturated_steps = np.zeros((T, B), dtype=np.int64)
    no_torque = np.zeros((3, T, B))

    def accumulate(j: int, L_bi, w) -> None:
        if weights[j]:
            sum_A[...] += weights[j] * np.abs(_euler312_of_product(L_bi, L_di[j]))
            sum_w[...] += weights[j] * np.abs(w - w_d[j])

    for k in range(n_ctrl):
        j0 = k * sub
        t0 = env.t[j0]
        L_bi = _dcm_from_quat(x[0:4])
        # sensors (Table 6): star sensor on A_bo, gyro on omega_b, ideal GPS
        A_bo = _euler312_of_product(L_bi, np.broadcast_to(env.L_oi[j0], (T, 3, 3)))
        if cfg.sensor_errors:
            A_bo = (A_bo + star_bias) + _per_scenario(star, G, k)
        if cfg.attitude_offset is not None:   # a body-axes rotation of the measured attitude
            R = _dcm_from_euler312(np.broadcast_to(_broadcast_input(cfg.attitude_offset(t0), T, B), (3, T, B)))
            A_bo = _euler312(_matmul(R, _dcm_from_euler312(A_bo)))
        w_meas = x[4:7]
        if cfg.sensor_errors:
            w_meas = (w_meas + gyro_bias) + _per_scenario(gyro, G, k)
        # preprocessing (host.gnc.preprocess): L_bd = (L_bo(A_bo) · L_oi) · L_di^T
        D = _dcm_from_euler312(A_bo)
        C = np.stack([np.stack([(D[i, 0] * env.L_oi[j0][0, c] + D[i, 1] * env.L_oi[j0][1, c])
                                + D[i, 2] * env.L_oi[j0][2, c] for c in range(3)]) for i in range(3)])
        A_deg = _euler312_of_product(C, L_di[j0]) / DEG
        w_deg = (w_meas - w_d[j0]) / DEG
        # the PID law (host.control.pid.PidLaw), anti-windup on saturated axes
        finite = np.all(np.isfinite(A_deg) & np.isfinite(w_deg), 0)
        integral_next = integral + A_deg * cfg.control_period
        raw = -((kp * A_deg + ki * integral_next) + kd * w_deg)
        saturated = np.abs(raw) > limit
        integral = np.where(finite & ~saturated, integral_next, integral)
        cmd = np.where(finite, np.clip(raw, -limit, limit), 0.0)
        saturated_steps += np.any(saturated, 0) & finite
        # wheels: saturation, then the Table 6 torque errors
        M_c = np.clip(np.where(np.isfinite(cmd), cmd, 0.0), -sc.torque_limit, sc.torque_limit)
        if cfg.wheel_errors:
            M_c = (M_c + wheel_bias) + _per_scenario(wheel, G, k)
        for j in range(j0, j0 + sub):
            if j != j0:
                L_bi = _dcm_from_quat(x[0:4])
            accumulate(j, L_bi, x[4:7])
            M_ext = plant.external_torque(j, L_bi) if cfg.external_torques else no_torque
            if cfg.extra_torque is not None:
                M_ext = M_ext + _broadcast_input(cfg.extra_torque(env.t[j]), T, B)
            M_j = _momentum_limited(M_c, x[7:10], sc.momentum_limit)
            x = plant.rk4(x, M_j, M_ext, cfg.plant_step)
        if progress is not None:
            progress(k)
    accumulate(n, _dcm_from_quat(x[0:4]), x[4:7])

    count = m * (p + 1)
    shape = (T, G, N)

    def per_axis(s):
        return np.moveaxis(s / count / DEG, 0, -1).reshape(*shape, 3)
    return BatchResult(J_A_axis=per_axis(sum_A), J_w_axis=per_axis(sum_w), m=m, p=p,
                       saturated_steps=saturated_steps.reshape(shape))
