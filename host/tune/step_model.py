"""What sets the step response (§7.6.1, Tables 10-11): a per-axis discrete PD model of a law.

The step response of `staregen evaluate` is the difference of two closed-loop runs with the same
noise, one with a 0.005° measurement offset from 30 s. For a law that is linear in (A_bd, ω_e) the
noise, the feed-forward and the disturbances cancel in that difference, and what is left per axis is
a rigid body under a PD law with a zero-order hold:

    I·θ̈ = u,   u_k = −(Kp·(θ_k + s)·(180/π)° + Kd·ω_k·(180/π)°/s)   held over [kT, (k+1)T),

whose exact discretisation is θ_{k+1} = θ_k + T·ω_k + T²/(2I)·u_k, ω_{k+1} = ω_k + T/I·u_k. The
network's policy is a PD + feed-forward law to within about 1 % of its torque (BENCHMARKS.md), so its
fitted PD + feed-forward coefficients (<artifact>.baselines.json) give its effective Kp, Kd; the
model's overshoot and 5 % settling time are then compared with the measured ones: where they
agree, the gains are what set the step response (the OCP's effort weight and horizon set the
gains), not the noise.

Units as the paper's PID: Kp in N·m/°, Kd in N·m/(°/s), inertia in kg·m² (the diagonal).
"""
from __future__ import annotations

import numpy as np

from host.core.constants import DEG
from host.errors import HostError
from host.tune.evaluate import STEP_AT, STEP_DEG, step_metrics


def pd_step_response(kp: float, kd: float, inertia: float, period: float = 0.1, duration: float = 60.0,
                     t0: float = STEP_AT, step_deg: float = STEP_DEG) -> tuple[np.ndarray, np.ndarray]:
    """(t, d_deg): the attitude (deg) at the control instants after a measurement offset of +step
    from t0 (the law drives the true attitude to −step)."""
    if not (kp > 0 and kd >= 0 and inertia > 0 and period > 0):
        raise HostError(f"PD model needs Kp > 0, Kd >= 0, I > 0, T > 0 (got {kp}, {kd}, {inertia}, {period})")
    n = int(round(duration / period))
    t = np.arange(n + 1) * period
    theta, omega = 0.0, 0.0
    d = np.zeros(n + 1)
    for k in range(n):
        offset = step_deg * DEG if t[k] >= t0 - 1e-9 else 0.0
        u = -(kp * (theta + offset) / DEG + kd * omega / DEG)
        theta, omega = theta + period * omega + period * period / (2.0 * inertia) * u, omega + period / inertia * u
        d[k + 1] = theta / DEG
    return t, d


def predicted_step(kp, kd, inertia, period: float = 0.1, duration: float = 60.0) -> dict:
    """step_metrics of the PD model per axis (kp, kd, inertia: three values each)."""
    per_axis = []
    for a in range(3):
        t, d = pd_step_response(float(kp[a]), float(kd[a]), float(inertia[a]), period, duration)
        per_axis.append(np.repeat(d[:, None], 3, axis=1))
    responses = np.stack([per_axis[a][:, a] for a in range(3)], axis=1)
    return step_metrics(responses, t)


def pdff_gains(coef) -> tuple[np.ndarray, np.ndarray]:
    """Effective (Kp, Kd) per axis of a fitted PD + feed-forward law (host.control.baselines.
    SaturatedLinear.coef, rows [A_bd (3), ω_e (3), M_ff (3), 1]): the minus of its diagonal terms."""
    c = np.asarray(coef, float)
    if c.shape != (10, 3):
        raise HostError(f"PD + feed-forward coefficients must be (10, 3), got {c.shape}")
    return -np.diag(c[0:3]), -np.diag(c[3:6])


def gains_for_settling(target_s: float, inertia: float, zeta: float = 1.0, period: float = 0.1) -> tuple[float, float]:
    """The (Kp, Kd) of damping ratio `zeta` whose PD model settles (5 %) in `target_s`, by bisection
    on the natural frequency: how stiff a law must be to settle as fast as the paper's network."""
    lo, hi = 0.01, 20.0                           # rad/s
    for _ in range(60):
        wn = np.sqrt(lo * hi)
        kp, kd = inertia * wn * wn * DEG, 2.0 * zeta * inertia * wn * DEG
        t, d = pd_step_response(kp, kd, inertia, period)
        settle = step_metrics(np.repeat(d[:, None], 3, 1), t)["settling_s"][0]
        lo, hi = (wn, hi) if settle > target_s else (lo, wn)
    return kp, kd
