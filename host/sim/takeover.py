"""Paper 004's closed loop (docs/gp-takeover.md sections 1, 3, 5): the combined body after capture,
stabilised by a takeover law, and the data collection that feeds the GP.

One control period: truth (host.plant.takeover) -> measured q, ω, h_w (perfect, or with an error model
such as Table 6's: star sensor, gyro, wheel bias and noise) -> controller -> wheels (torque and
momentum limits, then the wheel errors) -> truth, RK4 at 0.01 s with the wheel command held over
0.1 s. A controller is any callable
`(t, q, ω, h_w) -> LawOutput`; `law_controller` adapts the time-free laws of
host.control.takeover_laws.

History (one row per control instant, the last row has no command): t, q, ω, h_w, attitude error
angle, commanded and applied torque, counter-torque, GP mean / variance and gains, the truth's ω̇ and
unknown term d (section 2).
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

from host.control.takeover_laws import (
    Gains,
    LawOutput,
    attitude_error,
    pd_torque,
)
from host.core.constants import DEG
from host.errors import HostError
from host.plant.error_model import ErrorModel, draw_noise
from host.plant.takeover import (
    DT,
    PERIOD,
    TakeoverPlant,
    axis_angle_quat,
    capture_state,
    error_quat,
    measured_unknown_term,
    quat_compose,
)
from host.sim.rbf_tracking import time_to_stay_within

Controller = Callable[[float, np.ndarray, np.ndarray, np.ndarray], LawOutput]

STEADY_WINDOW = 60.0          # s, steady-state error window at the end of a run

# section 3: data collection
RUN_DURATION = 300.0          # s
RATE_SPREAD = 0.6 * DEG       # rad/s, initial rates uniform +-
SETPOINT_PERIOD = 60.0        # s
SETPOINT_RADIUS = 25.0 * DEG  # rad, setpoints uniform in this ball of rotation vectors
SINE_AMPLITUDE = 0.06         # N·m per component
SINE_FREQUENCIES = 0.004 * 2.0 ** np.arange(5)   # Hz
SAMPLE_RATE = 1.0             # Hz


def law_controller(law) -> Controller:
    return lambda t, q, omega, h_w: law(q, omega, h_w)


def error_angle(q) -> float:
    """Rotation angle (rad) between the body and the reference frame."""
    q = np.asarray(q, dtype=float)
    return 2.0 * math.atan2(math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2), abs(q[3]))


# ----------------------------------------------------------------------------- closed loop


def simulate(controller: Controller, duration: float, plant: TakeoverPlant | None = None, x0=None,
             period: float = PERIOD, dt: float = DT, errors: ErrorModel | None = None,
             seed: int = 0) -> dict[str, np.ndarray]:
    """Closed loop for `duration` s from x0 (default: the capture state of section 1). With `errors`
    (e.g. TABLE6_ERRORS) the controller sees measured q, ω and the wheels add their bias and noise;
    `seed` picks the noise. Without, sensors and wheels are perfect."""
    if not (isinstance(duration, (int, float)) and math.isfinite(duration) and duration > 0):
        raise HostError(f"duration must be a positive number of seconds, got {duration!r}")
    if not (0 < dt <= period and math.isfinite(period)):
        raise HostError(f"need 0 < dt <= period, got dt={dt!r}, period={period!r}")
    plant = plant or TakeoverPlant()
    x = capture_state(plant) if x0 is None else np.array(x0, dtype=float)
    n = max(1, math.ceil(duration / period - 1e-9))
    substeps = max(1, math.ceil(period / dt - 1e-9))
    noise = draw_noise(errors, seed, 0, n + 1, period, substeps) if errors is not None else None
    h = _History(n + 1)
    for k in range(n + 1):
        t = k * period
        q_m, w_m = measured_attitude(x, errors, noise, k)
        h.state(k, t, x, q_m, w_m, plant)
        if k == n:
            break
        out = controller(t, q_m, w_m, x[7:10].copy())
        u = plant.applied_torque(out.torque, x[7:10])
        u_steps = wheel_torques(u, errors, noise, k, substeps)
        h.command(k, out, u, u_steps, plant, x)
        for u_j in u_steps:
            x = plant.rk4_step(x, u_j, period / substeps)
    hist = h.arrays()
    hist["period"] = np.float64(period)
    return hist


def small_rotation_quat(e) -> np.ndarray:
    """The quaternion of a small body-axis rotation vector e (rad), normalised."""
    q = np.concatenate([0.5 * np.asarray(e, float), [1.0]])
    return q / np.sqrt(q @ q)


def measured_attitude(x, errors: ErrorModel | None, noise, k: int):
    """Star sensor and gyro at control instant k: (bias + noise) as a small body-axis rotation on q (our
    reading of Table 6's per-angle error for a quaternion output) and as an additive error on ω."""
    q, w = x[0:4].copy(), x[4:7].copy()
    if errors is None:
        return q, w
    q_m = quat_compose(small_rotation_quat(errors.star.bias_array + noise.star[k]), q)
    return q_m, (w + errors.gyro.bias_array) + noise.gyro[k]


def wheel_torques(u, errors: ErrorModel | None, noise, k: int, substeps: int) -> list[np.ndarray]:
    """The torque the wheels put on the body at each plant step of period k: (u + bias) + noise."""
    if errors is None:
        return [u] * substeps
    rows = noise.wheels[k * substeps:(k + 1) * substeps]
    return [(u + errors.wheels.bias_array) + r for r in rows]


class _History:
    def __init__(self, n: int):
        nan3 = lambda: np.full((n, 3), np.nan)   # noqa: E731
        self.t, self.angle = np.empty(n), np.empty(n)
        self.q, self.q_meas = np.empty((n, 4)), np.empty((n, 4))
        self.omega_meas = np.empty((n, 3))
        self.torque_known = nan3()                # the command after the limits: what the servicer knows it asked
        self.omega, self.h_w, self.counter_torque = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
        self.torque, self.torque_applied = nan3(), nan3()
        self.mu, self.var = nan3(), nan3()
        self.gains = np.full((n, 2), np.nan)
        self.omega_dot, self.d_true = nan3(), nan3()

    def state(self, k, t, x, q_m, w_m, plant):
        self.t[k], self.q[k], self.omega[k], self.h_w[k] = t, x[0:4], x[4:7], x[7:10]
        self.q_meas[k], self.omega_meas[k] = q_m, w_m
        self.angle[k] = error_angle(x[0:4])
        self.counter_torque[k] = plant.counter_torque(x)

    def command(self, k, out, u, u_steps, plant, x):
        self.torque[k], self.torque_known[k] = out.torque, u
        self.torque_applied[k] = np.mean(u_steps, axis=0)          # exact mean over the period (ZOH per step)
        self.mu[k], self.var[k], self.gains[k] = out.mu, out.var, out.gains
        wdot = plant.derivative(x, u_steps[0])[4:7]         # truth ω̇ at the start of the period
        self.omega_dot[k], self.d_true[k] = wdot, plant.unknown_term(x, wdot)

    def arrays(self) -> dict[str, np.ndarray]:
        return dict(vars(self))


# ----------------------------------------------------------------------------- metrics


def momentum_limit_time(t, h_w, limit: float, window: float = STEADY_WINDOW) -> list:
    """Per axis: when |h_w| reaches `limit` if it keeps its slope of the last `window` s (None if it
    is not growing)."""
    sel = t >= t[-1] - window
    out = []
    for i in range(3):
        slope = np.polyfit(t[sel], h_w[sel, i], 1)[0]
        h = h_w[-1, i]
        growing = slope * h > 0 or (h == 0 and slope != 0)
        out.append(float(t[-1] + (limit - abs(h)) / abs(slope)) if growing else None)
    return out


def metrics_of(hist: dict[str, np.ndarray], plant: TakeoverPlant | None = None,
               steady_window: float = STEADY_WINDOW) -> dict:
    plant = plant or TakeoverPlant()
    t, angle = hist["t"], hist["angle"] / DEG
    ctrl = slice(0, len(t) - 1)
    steady = t >= t[-1] - steady_window
    return {
        "t_settle_1deg": time_to_stay_within(t, angle, 1.0),
        "t_settle_0p1deg": time_to_stay_within(t, angle, 0.1),
        "steady_error_deg_mean": float(np.mean(angle[steady])),
        "steady_error_deg_max": float(np.max(angle[steady])),
        "max_abs_h_w": np.max(np.abs(hist["h_w"]), axis=0).tolist(),
        "h_w_end": hist["h_w"][-1].tolist(),
        "t_momentum_limit": momentum_limit_time(t, hist["h_w"], plant.momentum_limit),
        "torque_rms": np.sqrt(np.mean(hist["torque_applied"][ctrl] ** 2, axis=0)).tolist(),
        "counter_torque_end": hist["counter_torque"][-1].tolist(),
        "finite": bool(np.all(np.isfinite(hist["q"])) and np.all(np.isfinite(hist["torque"][ctrl]))),
        "duration": float(t[-1]),
    }


# ----------------------------------------------------------------------------- section 3: data


def random_setpoint(rng: np.random.Generator, radius: float = SETPOINT_RADIUS) -> np.ndarray:
    """A quaternion whose rotation vector is uniform in the ball of `radius` (rad)."""
    v = rng.normal(size=3)
    angle = radius * rng.uniform() ** (1.0 / 3.0)
    return axis_angle_quat(v, angle)


class Excitation:
    """Section 3's excitation: the baseline PD towards setpoints redrawn every 60 s, plus a multisine per
    axis, clipped to the torque limit."""

    def __init__(self, seed: int, duration: float = RUN_DURATION, gains: Gains | None = None,
                 prior_inertia=None, torque_max: float = 1.0):
        rng = np.random.default_rng(seed)
        self.initial_rate = rng.uniform(-RATE_SPREAD, RATE_SPREAD, size=3)
        n_set = max(1, math.ceil(duration / SETPOINT_PERIOD))
        self.setpoints = [random_setpoint(rng) for _ in range(n_set)]
        self.phases = rng.uniform(0.0, 2.0 * math.pi, size=(3, SINE_FREQUENCIES.size))
        self.gains = gains or Gains()
        self.prior_inertia = TakeoverPlant().prior_inertia if prior_inertia is None else prior_inertia
        self.torque_max = torque_max

    def multisine(self, t: float) -> np.ndarray:
        return SINE_AMPLITUDE * np.sum(np.sin(2.0 * math.pi * SINE_FREQUENCIES * t + self.phases), axis=1)

    def __call__(self, t, q, omega, h_w) -> LawOutput:
        q_s = self.setpoints[min(int(t // SETPOINT_PERIOD), len(self.setpoints) - 1)]
        q_v = error_quat(q, q_s)[:3]
        g = self.gains
        u = pd_torque(q_v, omega, h_w, g.k1, g.k2, self.prior_inertia) + self.multisine(t)
        u = np.clip(u, -self.torque_max, self.torque_max)
        return LawOutput(u, np.zeros(3), np.zeros(3), np.array([g.k1, g.k2]))


def _trapezoid_mean(a: np.ndarray) -> np.ndarray:
    """Mean over a window of equally spaced samples (trapezoid rule), along axis 0."""
    return (0.5 * (a[0] + a[-1]) + np.sum(a[1:-1], axis=0)) / (len(a) - 1)


def samples_of(hist: dict[str, np.ndarray], prior_inertia, sample_rate: float = SAMPLE_RATE) -> dict:
    """1 Hz samples of one run (section 3): ω̇ by the central difference of ω over ±half a sample
    interval, ω and h_w the window means, u the mean applied torque over the window (exact: ZOH),
    q_v at the sample (q4 ≥ 0); d = J_s ω̇ + ω×(J_s ω + h_w) − u."""
    T = float(hist["period"])
    half = int(round(0.5 / (sample_rate * T)))            # control periods in half a window
    step = 2 * half
    n_ctrl = len(hist["t"]) - 1
    ks = np.arange(step, n_ctrl - half + 1, step)         # t = 1 .. 299 s for 300 s at 1 Hz
    rows = {key: [] for key in ("t", "x", "d", "u", "h_w", "omega_dot_true", "d_true")}
    for k in ks:
        omega_dot = (hist["omega_meas"][k + half] - hist["omega_meas"][k - half]) / (2 * half * T)
        omega = _trapezoid_mean(hist["omega_meas"][k - half:k + half + 1])
        h_w = _trapezoid_mean(hist["h_w"][k - half:k + half + 1])
        u = np.mean(hist["torque_known"][k - half:k + half], axis=0)
        rows["t"].append(hist["t"][k])
        rows["x"].append(np.concatenate([attitude_error(hist["q_meas"][k]), omega, omega_dot]))
        rows["d"].append(measured_unknown_term(prior_inertia, omega, omega_dot, h_w, u))
        rows["u"].append(u)
        rows["h_w"].append(h_w)
        rows["omega_dot_true"].append(hist["omega_dot"][k])
        rows["d_true"].append(hist["d_true"][k])
    return {key: np.array(v) for key, v in rows.items()}


def collect(seeds, duration: float = RUN_DURATION, plant: TakeoverPlant | None = None,
            errors: ErrorModel | None = None) -> dict[str, np.ndarray]:
    """Section 3's data: one excited run per seed from the capture attitude; the samples of all runs
    stacked (x N×9, d N×3, u, h_w, t, seed, and the truth's ω̇ and d at the sample instants). With
    `errors` the samples come from the measured q and ω and the wheels' errors act on the truth (the
    run's seed also picks the noise)."""
    seeds = list(seeds)
    if not seeds or not all(isinstance(s, (int, np.integer)) and s >= 0 for s in seeds):
        raise HostError(f"seeds must be a non-empty list of non-negative integers, got {seeds!r}")
    plant = plant or TakeoverPlant()
    parts = []
    for seed in seeds:
        exc = Excitation(int(seed), duration, prior_inertia=plant.prior_inertia)
        x0 = capture_state(plant, omega0=exc.initial_rate)
        part = samples_of(simulate(exc, duration, plant, x0, errors=errors, seed=int(seed)), plant.prior_inertia)
        part["seed"] = np.full(len(part["t"]), int(seed))
        parts.append(part)
    return {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}


__all__ = ["Controller", "law_controller", "simulate", "metrics_of", "momentum_limit_time", "collect",
           "samples_of", "Excitation", "error_angle", "measured_attitude", "wheel_torques"]
