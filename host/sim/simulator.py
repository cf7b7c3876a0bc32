"""Closed-loop staring simulation: orbit + environment, rigid body with wheels, sensors, controller.

Timing
* Control period T = 0.1 s: at t_k = k·T the sensors sample the true state, the controller returns
  a torque, the wheels apply it (saturation, Table 6 errors) held constant until t_{k+1} (ZOH, no
  computation delay).
* Plant: RK4 with step τ = 0.02 s (5 per period). Within a period the torque is constant and the
  body rate is ≤ 0.03 rad/s, so the RK4 local error ~(|ω|τ)^5 is negligible; τ < T is chosen so
  the disturbance torques and the wheel momentum limit are re-evaluated inside each period and
  the recorded attitude (hence J, eq. 6-7, "p simulation steps per window") resolves the
  intra-period motion. Halving τ to 0.01 s moves the central-target attitude at the control
  instants by ~1e-9° over 100 s (integration converged); J_ω changes by ~1 % only because the
  rate error inside a period (a ramp under constant torque) is sampled twice as densely.
* Orbit: the Table 5 orbit propagated with two-body RK4 at the same step τ, once per run and
  shared by all targets (it does not depend on the attitude); disturbances are evaluated at the
  start of each plant step and held over it (they vary on the orbital time scale).

Initial state (Table 6): attitude = desired attitude, rate = desired rate, wheel momentum zero.
Histories are sampled at every plant step, t_j = j·τ, j = 0 … n (n·τ = duration, both ends
included); the torque arrays hold the torque applied over [t_j, t_j + τ), and their final sample
(no interval follows) repeats the last interval's values. "True" errors use the true state and the
desired state computed from the true orbit; the controller's own view (from noisy sensors) is
recorded too.

Errors: the scenario's error model (SimConfig.errors, host.plant.error_model; default the `table6`
reading): the star sensor and the gyro read (true + bias) + noise at the control instants, the wheels
apply (saturated command + bias) + noise at every plant step, each noise drawn with its own period.
Deterministic: the noise of target stream s under seed N comes from SeedSequence([N, s]), split
into independent star-sensor, gyro and wheel generators and drawn once per run
(error_model.draw_noise, shared with the batched simulator), so results do not depend on the
number of worker processes.
"""
from __future__ import annotations

import functools
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from multiprocessing import get_context
from typing import Callable, Sequence

import numpy as np

from host.plant import orbit
from host.control.controllers import Controller, Measurement
from host.plant.disturbances import DEFAULT_DISTURBANCES, DisturbanceParams, total_disturbance_torque
from host.plant.environment import EnvironmentTrack
from host.errors import HostError
from host.gnc.guidance import desired_state
from host.core.rotations import dcm_from_euler312, dcm_from_quat, euler312_from_dcm, quat_from_dcm
from host.plant.error_model import TABLE6_ERRORS, ErrorModel, NoiseTrack, draw_noise
from host.plant.sensors import Gps, measure
from host.plant.spacecraft import (TABLE6, SpacecraftParams, momentum_limited_torque, pack_state, rk4_step,
                                   unpack_state, wheel_torque)
from host.core.timebase import add_seconds
from host.core.vec3 import dcm_from_quat3

SCENARIO_EPOCH = orbit.TABLE5_EPOCH   # (jd_days, sec_of_day) of 2017-05-31 04:40:00 UTC


@dataclass(frozen=True)
class SimConfig:
    duration: float = 100.0           # s
    control_period: float = 0.1       # s
    plant_step: float = 0.02          # s, must divide the control period
    seed: int = 0
    spacecraft: SpacecraftParams = TABLE6
    errors: ErrorModel = TABLE6_ERRORS    # Table 6 sensor and wheel errors, as the scenario reads them
    disturbances: DisturbanceParams = DEFAULT_DISTURBANCES
    sensor_errors: bool = True        # False: perfect star sensor and gyro
    wheel_errors: bool = True         # False: wheels apply the saturated command exactly
    external_torques: bool = True     # False: no environmental disturbances
    # test inputs (step / frequency / impulse responses): functions of t [s] -> (3,)
    extra_torque: Callable[[float], np.ndarray] | None = None      # N·m on the body
    # rad, 3-1-2 angles of a small rotation about the body axes applied to the star sensor's
    # measured attitude (L_bo -> R(offset)·L_bo): the controller's own A_bd moves by it (to first
    # order), whatever the off-nadir angle; the §7.6.1 "extra angle measurement error"
    attitude_offset: Callable[[float], np.ndarray] | None = None

    @property
    def substeps(self) -> int:
        n = round(self.control_period / self.plant_step)
        if n < 1 or abs(n * self.plant_step - self.control_period) > 1e-9 * self.control_period:
            raise HostError(f"plant step {self.plant_step} s must divide the control period {self.control_period} s")
        return n

    @property
    def control_steps(self) -> int:
        if not np.isfinite(self.duration) or self.duration <= 0:
            raise HostError(f"duration must be a positive number of seconds, got {self.duration}")
        return int(np.ceil(self.duration / self.control_period - 1e-9))


@dataclass
class History:
    """Recorded run, sampled at t_j = j·τ (arrays (n+1, …)); angles rad, rates rad/s, torques N·m."""
    t: np.ndarray
    A_bd: np.ndarray            # true 3-1-2 Euler angles of body w.r.t. desired frame
    omega_e: np.ndarray         # true ω_b − ω_d
    omega_b: np.ndarray         # true body rate
    omega_d: np.ndarray         # desired rate (S_d), from the true orbit
    omegadot_d: np.ndarray
    q_bi: np.ndarray            # true attitude quaternion (scalar last)
    h_w: np.ndarray             # wheel momentum, N·m·s
    torque_cmd: np.ndarray      # controller command (held over the period)
    torque_applied: np.ndarray  # wheel torque on the body after saturation, errors, momentum limit
    torque_ext: np.ndarray      # environmental + extra torque
    A_bd_ctrl: np.ndarray       # the controller's own A_bd (from measurements), NaN if not reported
    omega_e_ctrl: np.ndarray
    mode: np.ndarray            # str per sample
    lon: float
    lat: float
    seed: int
    stream: int

    def arrays(self) -> dict:
        """Everything as numpy arrays (for np.savez)."""
        return {k: np.asarray(v) for k, v in self.__dict__.items()}


# ----------------------------------------------------------------------------- environment

@functools.lru_cache(maxsize=4)
def environment_track(n_samples: int, plant_step: float) -> EnvironmentTrack:
    """Table 5 orbit and its environment at t = 0, τ, …, (n_samples−1)·τ (cached per process)."""
    states = orbit.propagate_rk4(orbit.table5_initial_state(), plant_step, n_samples - 1)
    t = np.arange(n_samples) * plant_step
    jd, sec = add_seconds(*SCENARIO_EPOCH, t)
    return EnvironmentTrack(t, jd, sec, states)


def initial_state(env: EnvironmentTrack, lon: float, lat: float) -> np.ndarray:
    """Table 6: body on the desired attitude with the desired rate, wheels at rest."""
    d = desired_state(env.jd_days[0], env.sec_of_day[0], env.R[0], env.V[0], lon, lat)
    return pack_state(quat_from_dcm(d.L_di), d.omega_d, np.zeros(3))


# ----------------------------------------------------------------------------- the loop

class _Recorder:
    def __init__(self, n: int):
        n += 1  # states at both ends of the run
        self.x = np.empty((n, 10))
        self.cmd = np.empty((n, 3))
        self.applied = np.empty((n, 3))
        self.ext = np.empty((n, 3))
        self.A_ctrl = np.full((n, 3), np.nan)
        self.w_ctrl = np.full((n, 3), np.nan)
        self.mode = np.empty(n, dtype=object)


def sense(L_bi, L_oi, omega_b, R, V, jd_days, sec_of_day, t, noise_star, noise_gyro, lon, lat,
          cfg: SimConfig) -> Measurement:
    """What the sensors give the controller of a true state (any simulator's): star sensor and gyro with
    the scenario's errors and this instant's noise, the §7.6.1 extra angle, the ideal GPS."""
    A_bo = measure(euler312_from_dcm(L_bi @ L_oi.T), cfg.errors.star, noise_star, cfg.sensor_errors)
    if cfg.attitude_offset is not None:
        A_bo = euler312_from_dcm(dcm_from_euler312(np.asarray(cfg.attitude_offset(t), float)) @ dcm_from_euler312(A_bo))
    R, V = Gps().measure(R, V)
    return Measurement(t=t, jd_days=int(jd_days), sec_of_day=float(sec_of_day), A_bo=A_bo,
                       omega_b=measure(omega_b, cfg.errors.gyro, noise_gyro, cfg.sensor_errors), R_s=R, V_s=V,
                       lon=lon, lat=lat)


def _measure(x, env, k_sample, t, noise_star, noise_gyro, lon, lat, cfg: SimConfig) -> Measurement:
    q, w, _ = unpack_state(x)
    return sense(dcm_from_quat3(q), env.L_oi[k_sample], w, env.R[k_sample], env.V[k_sample], env.jd_days[k_sample],
                 env.sec_of_day[k_sample], t, noise_star, noise_gyro, lon, lat, cfg)


def _advance_one_period(x, cmd, j0: int, sub: int, env: EnvironmentTrack, rec: _Recorder,
                        cfg: SimConfig, wheel_noise: np.ndarray) -> np.ndarray:
    """Integrate the plant over one control period (sub RK4 steps) with the command held; the wheel
    errors, the momentum limit and the external torques are re-evaluated at each plant step."""
    sc = cfg.spacecraft
    inertia, inertia_inv = sc.inertia, sc.inertia_inv
    for j in range(j0, j0 + sub):
        rec.x[j] = x
        L_bi = dcm_from_quat3(x[0:4])
        M_ext = (total_disturbance_torque(env, j, L_bi, inertia, cfg.disturbances)
                 if cfg.external_torques else np.zeros(3))
        if cfg.extra_torque is not None:
            M_ext = M_ext + np.asarray(cfg.extra_torque(env.t[j]), float)
        M_c = wheel_torque(cmd, sc.torque_limit, cfg.errors.wheels.bias_array, wheel_noise[j], cfg.wheel_errors)
        M_j = momentum_limited_torque(M_c, x[7:10], sc.momentum_limit)
        rec.applied[j], rec.ext[j] = M_j, M_ext
        x = rk4_step(x, M_j, M_ext, cfg.plant_step, inertia, inertia_inv)
    return x


def simulate(controller: Controller, lon: float, lat: float, config: SimConfig = SimConfig(),
             stream: int = 0) -> History:
    """Fly `controller` staring at (lon, lat) [rad] for config.duration seconds."""
    cfg = config
    sub, n_ctrl = cfg.substeps, cfg.control_steps
    n = n_ctrl * sub
    env = environment_track(n + 1, cfg.plant_step)
    noise = run_noise(cfg, cfg.seed, stream)

    controller.reset()
    x = initial_state(env, lon, lat)
    rec = _Recorder(n)
    for k in range(n_ctrl):
        j0 = k * sub
        out = controller.step(_measure(x, env, j0, env.t[j0], noise.star[k], noise.gyro[k], lon, lat, cfg))
        cmd = np.asarray(out.torque, float)
        rec.cmd[j0:j0 + sub] = cmd
        rec.mode[j0:j0 + sub] = out.mode
        rec.A_ctrl[j0:j0 + sub] = out.info.get("A_bd", np.nan)
        rec.w_ctrl[j0:j0 + sub] = out.info.get("omega_e", np.nan)
        x = _advance_one_period(x, cmd, j0, sub, env, rec, cfg, noise.wheels)
    rec.x[n] = x
    for a in (rec.cmd, rec.applied, rec.ext, rec.A_ctrl, rec.w_ctrl, rec.mode):
        a[n] = a[n - 1]
    return _history(rec, env, n + 1, lon, lat, cfg, stream)


def run_noise(cfg: SimConfig, seed: int, stream: int) -> NoiseTrack:
    """The random sensor and wheel errors of one run (the same draws in every simulator)."""
    return draw_noise(cfg.errors, seed, stream, cfg.control_steps, cfg.control_period, cfg.substeps,
                      sensors=cfg.sensor_errors, wheels=cfg.wheel_errors)


def true_errors(env: EnvironmentTrack, q_bi, omega_b, lon: float, lat: float):
    """(A_bd, ω_e, desired state) for the first len(q_bi) samples, batched, from the true orbit:
    A_bd = euler312(L_bi·L_di^T), ω_e = ω_b − ω_d."""
    n = len(q_bi)
    d = desired_state(env.jd_days[:n], env.sec_of_day[:n], env.R[:n], env.V[:n], lon, lat)
    L_bd = dcm_from_quat(q_bi) @ np.swapaxes(d.L_di, -1, -2)
    return euler312_from_dcm(L_bd), np.asarray(omega_b) - d.omega_d, d


def _history(rec: _Recorder, env: EnvironmentTrack, n: int, lon, lat, cfg: SimConfig, stream) -> History:
    """True errors for the whole run at once (batched guidance on the true orbit); n samples."""
    q, w, h = unpack_state(rec.x)
    A_bd, omega_e, d = true_errors(env, q, w, lon, lat)
    return History(t=env.t[:n].copy(), A_bd=A_bd, omega_e=omega_e,
                   omega_b=w.copy(), omega_d=d.omega_d, omegadot_d=d.omegadot_d, q_bi=q.copy(),
                   h_w=h.copy(), torque_cmd=rec.cmd, torque_applied=rec.applied, torque_ext=rec.ext,
                   A_bd_ctrl=rec.A_ctrl, omega_e_ctrl=rec.w_ctrl, mode=rec.mode.astype(str),
                   lon=float(lon), lat=float(lat), seed=cfg.seed, stream=stream)


# ----------------------------------------------------------------------------- many targets

Engine = Callable[[Controller, float, float, SimConfig, int], History]


def _simulate_one(make_controller: Callable[[], Controller], lon, lat, config, stream, engine: Engine) -> History:
    return engine(make_controller(), lon, lat, config, stream)


def simulate_targets(make_controller: Callable[[], Controller], targets: Sequence[tuple[float, float]],
                     config: SimConfig = SimConfig(), workers: int | None = None,
                     progress: bool = True, engine: Engine = simulate) -> list[History]:
    """One run per (lon, lat) target, target i on noise stream i, in a process pool.

    `make_controller` must be picklable (a module-level function or functools.partial), and so must
    `engine` (the simulator: `simulate`, or another with its signature, e.g. Basilisk's). Results
    come back in target order whatever order the workers finish in.
    """
    from tqdm import tqdm

    workers = max(1, min(workers or os.cpu_count() or 1, len(targets)))
    bar = tqdm(total=len(targets), desc="targets", unit="target", disable=not progress, mininterval=0.5)
    results: list[History | None] = [None] * len(targets)
    try:
        if workers == 1:
            for i, (lon, lat) in enumerate(targets):
                results[i] = _simulate_one(make_controller, lon, lat, config, i, engine)
                bar.update()
        else:
            with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn")) as pool:
                futures = {pool.submit(_simulate_one, make_controller, lon, lat, config, i, engine): i
                           for i, (lon, lat) in enumerate(targets)}
                for fut in as_completed(futures):
                    results[futures[fut]] = fut.result()
                    bar.update()
    finally:
        bar.close()
    return results  # type: ignore[return-value]
