"""Paper 000 section 4.2: the attitude-tracking example of the tanh law, continuous and sampled.

Scenario: J (eq. 27), R_c(0) (eq. 28, projected onto SO(3)), ω_c(0) = [0.1, 0.1, 0.1] rad/s,
static target R_t = dcm_from_euler321(eq. 30 in degrees) (= eq. 32 to 1e-6), ω_t = ω̇_t = 0,
disturbance d = 0.002·[sin 0.1t, cos 0.2t, sin 0.2t] N·m, parameters of section 4.2 plus
d_max = 0.0035 N·m (not printed in the paper; the true bound of d is 0.002·√2 = 0.00283).

Plant: host.plant.rigid_body (J ω̇ = −ω × Jω + u + d, Ṙ_c = R_c[ω]×, RK4 on plain floats).
* continuous reference (period None): the law is evaluated inside every RK4 stage and ϖ is
  integrated with the plant (a 15-state ODE);
* sampled (period T): the law runs at t = kT on the exact state, u is held (ZOH), ϖ advances by
  forward Euler (host.control.tanh_law.euler_update, with its overflow clamp), the plant is integrated
  with RK4 steps of ≤ dt.

`run(period, duration, dt, out_dir)` returns the metrics and the history; with out_dir it writes
metrics.json and figures like the paper's Figs. 5-8, each file atomically.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from host.core import rotations
from host.errors import HostError
from host.plant.rigid_body import RigidBody, paper000_disturbance, rows
from host.control.tanh_law import (
    LawConstants,
    Mat,
    TanhParams,
    Vec,
    attitude_error,
    compile_constants,
    error_matrix,
    euler_update,
    evaluate_law,
)
from codegen import atomic

# ----------------------------------------------------------------------------- paper 000, section 4.2

J_EQ27 = ((27.7, 0.3, -0.2), (0.3, 23.5, 0.5), (-0.2, 0.5, 24.6))          # kg·m²
RC0_EQ28 = ((-0.5414, -0.7072, -0.4546), (-0.0009, -0.5403, 0.8415), (-0.8407, 0.4560, 0.2919))
WC0_EQ29 = (0.1, 0.1, 0.1)                                                  # rad/s
EULER_EQ30_DEG = (-3.0894125, -34.4091333, 31.022785)                        # roll, pitch, yaw (deg)
RT_EQ32 = ((0.7070141, -0.4885306, -0.5113404), (0.4251997, 0.8714131, -0.2446312),
           (0.5650985, -0.0444641, 0.8238244))
DISTURBANCE_AMPLITUDE = 0.002                                               # N·m
D_MAX = 0.0035                                                              # N·m, our choice (see module doc)
SETTLE_THRESHOLD = 1e-2                                                     # ‖e‖ for t_settle
# Largest RK4 step for which the continuous reference is converged: t_settle 21.4325 / 21.4323 /
# 21.4321 s at 5e-4 / 2.5e-4 / 1.25e-4 s, but 17.665 s at 1e-3 s (the stiff δ/(δᵀδ) terms).
MAX_REFERENCE_STEP = 5e-4


def paper_parameters() -> TanhParams:
    """Section 4.2: k1=k2=k3=1.5, k4=7, k5=0.002, ε=50, β=0.3, γ=0.8, η=n1=λ=0.001, J of eq. 27."""
    return TanhParams(
        k1=1.5, k2=1.5, k3=1.5, k4=7.0, k5=0.002, eps1=50.0, eps2=50.0, eps3=50.0,
        beta1=0.3, beta2=0.3, gamma=0.8, eta=0.001, n1=0.001, lam=0.001, d_max=D_MAX,
        inertia=J_EQ27,
    )


def target_attitude() -> np.ndarray:
    """R_t from eq. 30 (degrees) through the paper's yaw-pitch-roll construction (eq. 31 fixed)."""
    roll, pitch, yaw = np.deg2rad(EULER_EQ30_DEG)
    return rotations.dcm_from_euler321(roll, pitch, yaw)


def initial_attitude() -> np.ndarray:
    """R_c(0): eq. 28 is printed to 4 digits (‖RRᵀ − I‖ ≈ 1e-4), so project it onto SO(3)."""
    return rotations.project_to_so3(np.array(RC0_EQ28))


@dataclass(frozen=True)
class Scenario:
    params: TanhParams
    plant_inertia: Mat
    R_c0: Mat
    w_c0: Vec
    R_t: Mat
    w_t: Vec = (0.0, 0.0, 0.0)
    wdot_t: Vec = (0.0, 0.0, 0.0)
    disturbance_amplitude: float = DISTURBANCE_AMPLITUDE


def paper_scenario(R_c0=None, w_c0=WC0_EQ29, params: TanhParams | None = None) -> Scenario:
    """The section 4.2 example; R_c0 / w_c0 / params may be overridden (e.g. a 179.5° start)."""
    R_c0 = initial_attitude() if R_c0 is None else np.asarray(R_c0, dtype=float)
    return Scenario(
        params=paper_parameters() if params is None else params,
        plant_inertia=J_EQ27,
        R_c0=_mat(R_c0),
        w_c0=tuple(float(x) for x in w_c0),
        R_t=_mat(target_attitude()),
    )


def _mat(m) -> Mat:
    return tuple(tuple(float(x) for x in row) for row in np.asarray(m, dtype=float))


# ----------------------------------------------------------------------------- plant


def plant(sc: Scenario) -> RigidBody:
    """The example's rigid body (host.plant.rigid_body) with paper 000's disturbance."""
    return RigidBody(sc.plant_inertia, paper000_disturbance(sc.disturbance_amplitude))


def initial_state(sc: Scenario) -> list[float]:
    return [x for row in sc.R_c0 for x in row] + list(sc.w_c0)


# ----------------------------------------------------------------------------- history


class History:
    """Preallocated arrays, one row per recorded instant."""

    def __init__(self, n: int):
        self.t = np.empty(n)
        self.e = np.empty((n, 3))
        self.w_e = np.empty((n, 3))
        self.x2 = np.empty((n, 3))
        self.u = np.empty((n, 3))
        self.varpi = np.empty((n, 3))
        self.status = np.empty(n, dtype=np.int8)
        self.n = 0

    def add(self, t: float, out, varpi: Vec, e: Vec | None = None, w_e: Vec | None = None) -> None:
        k = self.n
        self.t[k] = t
        self.e[k] = out.x1 if e is None else e
        self.w_e[k] = out.w_e if w_e is None else w_e
        self.x2[k] = out.x2
        self.u[k] = out.torque
        self.varpi[k] = varpi
        self.status[k] = out.status
        self.n = k + 1

    def as_dict(self) -> dict[str, np.ndarray]:
        n = self.n
        return {"t": self.t[:n], "e": self.e[:n], "w_e": self.w_e[:n], "x2": self.x2[:n],
                "u": self.u[:n], "varpi": self.varpi[:n], "status": self.status[:n]}


# ----------------------------------------------------------------------------- simulations


def simulate_continuous(sc: Scenario, duration: float, dt: float) -> dict[str, np.ndarray]:
    """RK4 on [R_c, ω_c, ϖ] with the law evaluated in every stage (the continuous-time reference)."""
    c = compile_constants(sc.params)
    body = plant(sc)
    n = step_count(duration, dt)
    h = duration / n
    hist = History(n + 1)
    y = initial_state(sc) + [0.0, 0.0, 0.0]

    def f(t, y):
        varpi = (y[12], y[13], y[14])
        out = evaluate_law(c, varpi, rows(y), (y[9], y[10], y[11]), sc.R_t, sc.w_t, sc.wdot_t)
        return out, body.rates(t, y, out.torque) + list(out.varpi_dot)

    for k in range(n):
        t = k * h
        out, k1 = f(t, y)
        hist.add(t, out, (y[12], y[13], y[14]))
        _, k2 = f(t + 0.5 * h, [a + 0.5 * h * b for a, b in zip(y, k1)])
        _, k3 = f(t + 0.5 * h, [a + 0.5 * h * b for a, b in zip(y, k2)])
        _, k4 = f(t + h, [a + h * b for a, b in zip(y, k3)])
        y = [a + h / 6.0 * (b + 2.0 * (p + q) + r) for a, b, p, q, r in zip(y, k1, k2, k3, k4)]
    out, _ = f(n * h, y)
    hist.add(n * h, out, (y[12], y[13], y[14]))
    return {**hist.as_dict(), "R_c_final": np.array(rows(y))}


def simulate_sampled(sc: Scenario, period: float, duration: float, dt: float) -> dict[str, np.ndarray]:
    """Flight-like run: law at t = kT, torque held, ϖ by forward Euler, plant RK4 with step ≤ dt.

    Recorded at every plant step: e and ω_e of the true state; u, x2, ϖ, status as held.
    The run covers a whole number of control periods (duration rounded up).
    """
    c = compile_constants(sc.params)
    body = plant(sc)
    n_ctrl = step_count(duration, period)
    n_sub = step_count(period, dt)
    h = period / n_sub
    hist = History(n_ctrl * n_sub + 1)
    y = initial_state(sc)
    varpi = (0.0, 0.0, 0.0)
    out = None
    for k in range(n_ctrl):
        t0 = k * period
        out = evaluate_law(c, varpi, rows(y), (y[9], y[10], y[11]), sc.R_t, sc.w_t, sc.wdot_t)
        for j in range(n_sub):
            t = t0 + j * h
            if j:
                hist.add(t, out, varpi, *true_errors(c, sc, y))
            else:
                hist.add(t, out, varpi)
            y = body.rk4_step(t, y, h, out.torque)
        varpi = euler_update(varpi, out.varpi_dot, period, sc.params.varpi_limit)
    final = evaluate_law(c, varpi, rows(y), (y[9], y[10], y[11]), sc.R_t, sc.w_t, sc.wdot_t)
    hist.add(n_ctrl * period, final, varpi)
    return {**hist.as_dict(), "R_c_final": np.array(rows(y))}


def true_errors(c: LawConstants, sc: Scenario, y) -> tuple[Vec, Vec]:
    """e and ω_e of the plant state between control instants (ω_t = 0 here, but keep the form)."""
    R_e = error_matrix(sc.R_t, rows(y))
    _, e, _ = attitude_error(R_e, c.params.q0_min)
    w_t = sc.w_t
    w_e = tuple(y[9 + i] - (R_e[0][i] * w_t[0] + R_e[1][i] * w_t[1] + R_e[2][i] * w_t[2])
                for i in range(3))
    return e, w_e


def step_count(span: float, step: float) -> int:
    """Number of equal steps of at most `step` covering `span` (tolerant to float noise)."""
    if not (step > 0 and math.isfinite(step)):
        raise HostError(f"step must be a positive number of seconds, got {step!r}")
    if not (span > 0 and math.isfinite(span)):
        raise HostError(f"duration must be a positive number of seconds, got {span!r}")
    return max(1, math.ceil(span / step - 1e-9))


# ----------------------------------------------------------------------------- metrics


def settling_time(t: np.ndarray, e_norm: np.ndarray, threshold: float = SETTLE_THRESHOLD) -> float | None:
    """First time after which ‖e‖ stays below threshold; None if it is not below at the end."""
    above = np.nonzero(e_norm >= threshold)[0]
    if above.size == 0:
        return float(t[0])
    last = int(above[-1])
    return None if last == len(t) - 1 else float(t[last + 1])


def metrics_of(history: dict[str, np.ndarray]) -> dict:
    e_norm = np.linalg.norm(history["e"], axis=1)
    R = history["R_c_final"]
    return {
        "t_settle": settling_time(history["t"], e_norm),
        "e_final": float(e_norm[-1]),
        "we_final": float(np.linalg.norm(history["w_e"][-1])),
        "u_max": float(np.max(np.abs(history["u"]))),
        # R_c is integrated as a matrix (no re-orthonormalisation): how far it drifted off SO(3)
        "so3_error_final": float(np.max(np.abs(R @ R.T - np.eye(3)))),
        "e_max": float(np.max(e_norm)),
        "singular_samples": int(np.count_nonzero(history["status"] == 1)),
        "invalid_samples": int(np.count_nonzero(history["status"] == 2)),
        "finite": bool(all(np.all(np.isfinite(history[k])) for k in ("e", "w_e", "x2", "u", "varpi"))),
    }


def run(period: float | None, duration: float, dt: float, out_dir: Path | None = None) -> dict:
    """The section 4.2 example: continuous reference (period None, RK4 step dt) or sampled at period.

    Returns {"metrics": {...}, "history": {...}} plus the metrics at top level (t_settle, e_final,
    we_final, u_max, ...). With out_dir, writes metrics.json and fig5..fig8 PNGs atomically.
    """
    sc = paper_scenario()
    if period is None and dt > MAX_REFERENCE_STEP * (1 + 1e-9):
        raise HostError(f"the continuous reference needs dt <= {MAX_REFERENCE_STEP} s (stiff δ/(δᵀδ) terms), got {dt}")
    start = time.perf_counter()
    if period is None:
        history = simulate_continuous(sc, duration, dt)
    else:
        history = simulate_sampled(sc, float(period), duration, dt)
    metrics = metrics_of(history)
    metrics.update({
        "mode": "continuous" if period is None else "sampled",
        "period": None if period is None else float(period),
        "dt": float(dt),
        "duration": float(duration),
        "settle_threshold": SETTLE_THRESHOLD,
        "runtime_s": round(time.perf_counter() - start, 3),
        "parameters": sc.params.to_mapping(),
    })
    if out_dir is not None:
        write_outputs(Path(out_dir), metrics, history)
    return {**metrics, "metrics": metrics, "history": history}


# ----------------------------------------------------------------------------- outputs

_FIGURES = (
    ("fig5_attitude_error.png", "e", "attitude error e = x1", "e_i (-)"),
    ("fig6_angular_velocity_error.png", "w_e", "angular-velocity error ω_e", "ω_e,i (rad/s)"),
    ("fig7_x2.png", "x2", "x2 = ω_e − ω_ev", "x2,i (rad/s)"),
    ("fig8_torque.png", "u", "control torque u", "u_i (N·m)"),
)


def write_outputs(out_dir: Path, metrics: dict, history: dict[str, np.ndarray]) -> None:
    atomic.write_json(out_dir / "metrics.json", metrics)
    for name, key, title, ylabel in _FIGURES:
        _plot(out_dir / name, history["t"], history[key], title, ylabel, metrics)


def _plot(path: Path, t: np.ndarray, values: np.ndarray, title: str, ylabel: str, metrics: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    stride = max(1, len(t) // 20000)  # plenty for a PNG, keeps savefig fast
    t, values = t[::stride], values[::stride]
    mode = metrics["mode"] if metrics["period"] is None else f"sampled T = {metrics['period']} s"
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for i in range(3):
        top.plot(t, values[:, i], label=f"{i + 1}")
        bottom.semilogy(t, np.maximum(np.abs(values[:, i]), 1e-12), label=f"|{i + 1}|")
    top.set_title(f"{title} ({mode})")
    top.set_ylabel(ylabel)
    top.legend(loc="upper right")
    top.grid(True, alpha=0.3)
    bottom.set_ylabel("magnitude (log)")
    bottom.set_xlabel("t (s)")
    bottom.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    with atomic.writing(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
