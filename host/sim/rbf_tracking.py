"""Paper 002's closed loop: a chaser approaches a tumbling, manoeuvring target to 100 m and tracks the
feature's line of sight (docs/rbf-backstepping.md section 8), under the RBF backstepping law.

One control period: truth (host.plant.proximity) -> measurement and desired state (host.gnc.los) ->
controller -> actuators D(u) (dead zone + saturation per body axis) -> truth, RK4 at dt with the applied
force and torque held. The controller is any callable LosMeasurement -> LawOutput (force, torque, w_hat,
status); `RbfLaw` is the float64 one and `record_controller` wraps a record stepper (the generated C in
tools.inloop.InTheLoop.step) into the same shape.

History (one row per control instant): time, LOS and desired LOS, e1, commanded and applied force and
torque, w_hat and w_true (the unknown term the first network should learn: the truth's x2' minus
F + G D(u) of the law's nominal model, Fig. 4 of the paper), weight norms and maxima, status.
"""
from __future__ import annotations

import math
import time
from typing import Callable

import numpy as np

from host.control.rbf_law import (
    PERIOD,
    STATUS_WEIGHT_BOUND,
    LawOutput,
    RbfLaw,
    RbfParams,
    nominal_model,
    paper_params,
    tracking_terms,
)
from host.core.constants import DEG
from host.core.rotations import dcm_from_euler312, los_frame, quat_from_dcm
from host.errors import HostError
from host.gnc.los import (
    LosMeasurement,
    desired_state,
    from_record,
    los_kinematics,
    measure,
    to_record,
)
from host.plant.proximity import ProximityPlant, circular_orbit_state, relative_state

Controller = Callable[[LosMeasurement], LawOutput]

RHO0 = 260.0                  # m
LOS_OFFSET = 5.0 * DEG        # q_eps0 = q_eps_d(0) + 5 deg, q_beta0 = q_beta_d(0) - 5 deg
ATTITUDE_OFFSET = 8.0 * DEG   # per Euler angle
DT = 0.01                     # s, truth RK4 step
ACCURACY_FROM = 200.0         # s, start of the Table 2 window


def record_controller(step_record: Callable[[np.ndarray], np.ndarray]) -> Controller:
    """A controller from a record stepper (INPUT_DTYPE record -> OUTPUT_DTYPE record), e.g. the generated
    unit in tools.inloop.InTheLoop.step."""
    def controller(m: LosMeasurement) -> LawOutput:
        out = np.asarray(step_record(to_record(m))).reshape(-1)[0]
        return LawOutput(np.array(out["force"], dtype=float), np.array(out["torque"], dtype=float),
                         np.array(out["w_hat"], dtype=float), int(out["status"]))
    return controller


# ----------------------------------------------------------------------------- initial state


def initial_truth(plant: ProximityPlant, rho0: float = RHO0, los_offset: float = LOS_OFFSET,
                  attitude_offset: float = ATTITUDE_OFFSET) -> list[float]:
    """Docs section 8: rho0 = 260 m, LOS 5 deg off the desired one (+ on q_eps, - on q_beta), zero relative
    velocity (so zero LOS rates), Euler angles each 8 deg off the desired attitude, zero body rate."""
    target = circular_orbit_state()
    d = desired_state(plant, 0.0)
    x_l = los_frame(d.los_d[1] + los_offset, d.los_d[2] - los_offset)[0]
    chaser_r = target[:3] - rho0 * x_l
    q = quat_from_dcm(dcm_from_euler312(d.euler_d + attitude_offset))
    return [*target, *chaser_r, *target[3:], *q, 0.0, 0.0, 0.0]


# ----------------------------------------------------------------------------- the unknown term


def true_unknown_term(plant: ProximityPlant, p: RbfParams, t: float, y, m: LosMeasurement,
                      force_applied, torque_applied) -> np.ndarray:
    """w = x2'(truth) - F - G D(u), with F, G the law's nominal model and D(u) the applied force (as a LOS
    acceleration with the NOMINAL mass) and torque: what the first network should learn."""
    rates = plant.rates(t, y, tuple(force_applied), tuple(torque_applied))
    r, v = relative_state(y)
    a_rel = np.asarray(rates[3:6]) - np.asarray(rates[9:12])
    _, _, los_acc = los_kinematics(r, v, a_rel)
    terms = tracking_terms(p, m)
    omega_dot = np.asarray(rates[16:19])
    x2_dot = np.concatenate([los_acc - m.los_d_acc,
                             omega_dot - terms.R_dot @ m.euler_d_rate - terms.R @ m.euler_d_acc])
    F, G = nominal_model(p, m, terms)
    C_lb = los_frame(m.los[1], m.los[2]) @ dcm_from_euler312(m.euler).T
    u_applied = np.concatenate([C_lb @ np.asarray(force_applied) / p.mass, torque_applied])
    return x2_dot - F - G * u_applied


# ----------------------------------------------------------------------------- simulation


def simulate(params: RbfParams, duration: float, controller: Controller | None = None,
             plant: ProximityPlant | None = None, period: float = PERIOD, dt: float = DT) -> dict[str, np.ndarray]:
    """Closed loop for `duration` s; returns the history (arrays, one row per control instant, the last
    row is the state at the end with no command)."""
    if not (duration > 0 and math.isfinite(duration)):
        raise HostError(f"duration must be a positive number of seconds, got {duration!r}")
    if not (0 < dt <= period and math.isfinite(period)):
        raise HostError(f"need 0 < dt <= period, got dt={dt!r}, period={period!r}")
    plant = plant or ProximityPlant()
    law = controller if controller is not None else RbfLaw(params, period)
    n = max(1, math.ceil(duration / period - 1e-9))
    h = _History(n + 1, params.nodes)
    y = initial_truth(plant)
    for k in range(n + 1):
        t = k * period
        m = measure(plant, t, y)
        if k == n:
            h.add(k, t, m, params, None, None, None, np.full(6, np.nan), law)
            break
        out = law(m)
        force_applied, torque_applied = plant.actuators.apply(out.force, out.torque)
        w_true = true_unknown_term(plant, params, t, y, m, force_applied, torque_applied)
        h.add(k, t, m, params, out, force_applied, torque_applied, w_true, law)
        y = plant.hold(t, y, period, dt, tuple(force_applied), tuple(torque_applied))
    hist = h.arrays()
    hist["period"] = np.float64(period)
    hist["mass_truth"] = np.float64(plant.mass)
    return hist


class _History:
    def __init__(self, n: int, nodes: int):
        self.t = np.empty(n)
        self.los, self.los_d = np.empty((n, 3)), np.empty((n, 3))
        self.e1 = np.empty((n, 6))
        self.force, self.torque = np.full((n, 3), np.nan), np.full((n, 3), np.nan)
        self.force_applied, self.torque_applied = np.full((n, 3), np.nan), np.full((n, 3), np.nan)
        self.w_hat, self.w_true = np.full((n, 6), np.nan), np.full((n, 6), np.nan)
        self.theta_norm, self.theta_delta_norm = np.full(n, np.nan), np.full(n, np.nan)
        self.theta_abs_max = np.full((n, 6), np.nan)        # max_j |theta_jk| per channel
        self.theta_delta_abs_max = np.full((n, 6), np.nan)
        self.status = np.zeros(n, dtype=np.int64)

    def add(self, k, t, m, params, out, force_applied, torque_applied, w_true, law):
        self.t[k] = t
        self.los[k], self.los_d[k] = m.los, m.los_d
        self.e1[k] = tracking_terms(params, m).e1
        self.w_true[k] = w_true
        state = getattr(law, "state", None)       # the host law's weights (after this step's update)
        if state is not None:
            self.theta_norm[k] = np.linalg.norm(state.theta)
            self.theta_delta_norm[k] = np.linalg.norm(state.theta_delta)
            self.theta_abs_max[k] = np.max(np.abs(state.theta), axis=0)
            self.theta_delta_abs_max[k] = np.max(np.abs(state.theta_delta), axis=0)
        if out is None:
            return
        self.force[k], self.torque[k], self.w_hat[k], self.status[k] = out.force, out.torque, out.w_hat, out.status
        self.force_applied[k], self.torque_applied[k] = force_applied, torque_applied

    def arrays(self) -> dict[str, np.ndarray]:
        d = dict(vars(self))
        d["q_beta_d_unwrapped"] = np.unwrap(self.los_d[:, 2])
        return d


# ----------------------------------------------------------------------------- metrics


def time_to_stay_within(t: np.ndarray, err: np.ndarray, band: float) -> float | None:
    """First time after which |err| < band until the end; None if it is not inside at the end."""
    outside = np.nonzero(~(np.abs(err) < band))[0]
    if outside.size == 0:
        return float(t[0])
    last = int(outside[-1])
    return None if last == len(t) - 1 else float(t[last + 1])


def _last_time(t: np.ndarray, flags: np.ndarray) -> float | None:
    hits = np.nonzero(flags)[0]
    return float(t[hits[-1]]) if hits.size else None


def metrics_of(hist: dict[str, np.ndarray], accuracy_from: float = ACCURACY_FROM) -> dict:
    t, e1, T = hist["t"], hist["e1"], float(hist["period"])
    ctrl = slice(0, len(t) - 1)                        # rows with a command (the last row has none)
    window = t >= accuracy_from
    err = hist["w_hat"][ctrl] - hist["w_true"][ctrl]
    err_window = err[window[ctrl]]
    att_deg = e1[:, 3:] / DEG
    out = {
        "t_rho_5m": time_to_stay_within(t, e1[:, 0], 5.0),
        "t_rho_1m": time_to_stay_within(t, e1[:, 0], 1.0),
        "t_attitude_1deg": [time_to_stay_within(t, att_deg[:, i], 1.0) for i in range(3)],
        "t_attitude_0p1deg": [time_to_stay_within(t, att_deg[:, i], 0.1) for i in range(3)],
        # ZOH: the applied force is constant over each period, so the sums are the exact integrals
        "delta_v": float(np.sum(np.abs(hist["force_applied"][ctrl])) * T / float(hist["mass_truth"])),
        "torque_impulse": float(np.sum(np.abs(hist["torque_applied"][ctrl])) * T),
        "max_abs_theta": float(np.nanmax(hist["theta_abs_max"])),
        "max_abs_theta_delta": float(np.nanmax(hist["theta_delta_abs_max"])),
        "max_abs_theta_per_channel": np.nanmax(hist["theta_abs_max"], axis=0).tolist(),
        "weight_bound_active_steps": int(np.count_nonzero(hist["status"][ctrl] & STATUS_WEIGHT_BOUND)),
        "t_last_weight_bound": _last_time(t[ctrl], hist["status"][ctrl] & STATUS_WEIGHT_BOUND),
        "rms_w_error": np.sqrt(np.mean(err ** 2, axis=0)).tolist(),
        "rms_w_true": np.sqrt(np.mean(hist["w_true"][ctrl] ** 2, axis=0)).tolist(),
        "min_rho": float(np.min(hist["los"][:, 0])),
        "t_min_rho": float(t[int(np.argmin(hist["los"][:, 0]))]),
        "finite": bool(np.all(np.isfinite(e1)) and np.all(np.isfinite(hist["force"][ctrl]))),
        "duration": float(t[-1]),
    }
    if np.any(window):
        out.update({
            "accuracy_window": [accuracy_from, float(t[-1])],
            "rms_e1": np.sqrt(np.mean(e1[window] ** 2, axis=0)).tolist(),
            "max_abs_e1": np.max(np.abs(e1[window]), axis=0).tolist(),
            "rms_w_error_window": np.sqrt(np.mean(err_window ** 2, axis=0)).tolist() if len(err_window) else None,
            "rms_w_true_window": np.sqrt(np.mean(hist["w_true"][ctrl][window[ctrl]] ** 2, axis=0)).tolist(),
            # the period-2 limit cycle of the sampled sig(z)^alpha terms: half the step-to-step force change
            "force_chatter_rms": float(np.sqrt(np.mean((0.5 * np.diff(hist["force"][ctrl][window[ctrl]], axis=0)) ** 2))),
            "force_mean_norm": float(np.linalg.norm(np.mean(hist["force"][ctrl][window[ctrl]], axis=0))),
            "delta_v_window": float(np.sum(np.abs(hist["force_applied"][ctrl][window[ctrl]])) * T
                                    / float(hist["mass_truth"])),
        })
    return out


def run(theorem: int, duration: float = 1000.0, period: float = PERIOD, **overrides) -> dict:
    """The paper-length run of one theorem with paper_params(**overrides); metrics, wall time, history."""
    params = paper_params(theorem=theorem, **overrides)
    start = time.perf_counter()
    hist = simulate(params, duration, period=period)
    metrics = metrics_of(hist)
    metrics.update({"theorem": theorem, "period": period, "wall_time_s": round(time.perf_counter() - start, 2)})
    return {"metrics": metrics, "history": hist}


__all__ = ["Controller", "record_controller", "initial_truth", "true_unknown_term", "simulate",
           "metrics_of", "time_to_stay_within", "run", "from_record"]
