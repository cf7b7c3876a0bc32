"""The batched closed-loop staring simulator: many scenarios of one controller advanced at once.

A scenario is (target, controller variant, seed). One run holds T targets × G variants × N seeds,
laid out target-major as numpy arrays (T, G·N, …) and handed to the controller as rows
(host.control.batch), and advances them together through the same loop as the scalar simulator
(host.sim.simulator, the reference): the sensors sample the true state every control period, the
controller (any BatchController: the PID, the network, the baselines, the discrete-point law, the
generated C through its record runner) commands a torque, the wheels apply it (saturation, the
scenario's errors, momentum limit) held over the period, and RK4 at the plant step integrates eq. 4
with the environmental torques re-evaluated at every plant step.

What is shared and what is not:
* the orbit and its environment are one track for every scenario (they do not depend on attitude);
* the desired state of each target (from the true orbit: the GPS is ideal, so the controller's own
  guidance equals it) is computed once per target, at every plant sample;
* common random numbers: the noise of a scenario depends only on its target's stream and its seed,
  drawn by the scalar simulator's own function (host.sim.simulator.run_noise), never on its
  variant, so variants are compared on identical noise and every scenario reproduces its scalar run.

The staring metrics (eq. 6-8) are accumulated on the fly: at each plant sample the true errors are
formed and added, with the sample's window multiplicity (a sample on the boundary of two imaging
windows counts twice, as in host.sim.metrics), per axis, so that per-axis objectives are available
for tuning. With `record=True` the true A_bd at the control instants is kept too (the step and
frequency responses); otherwise memory is O(scenarios), not O(scenarios × samples).

Test inputs (step and frequency responses) are functions of time giving either one (3,) vector for
all scenarios or a (S, 3) array, one row per scenario in the flattened order (target, variant, seed).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from host.control.batch import BatchController, BatchLayout, BatchMeasurement
from host.control.pid import GainSets, PidBatch
from host.core.constants import DEG
from host.errors import HostError
from host.gnc.guidance import desired_state
from host.plant.error_model import plant_times
from host.sim import batch_plant as bp
from host.sim.metrics import DEFAULT_PLAN, K1, K2, ImagingPlan, window_samples
from host.sim.simulator import SimConfig, environment_track, initial_state, run_noise

__all__ = ["BatchResult", "GainSets", "simulate_batch", "simulate_pid_batch"]


@dataclass
class BatchResult:
    """Per-scenario staring metrics, arrays (T, G, N) or (T, G, N, 3) per axis; deg and deg/s."""
    J_A_axis: np.ndarray
    J_w_axis: np.ndarray
    m: int
    p: int
    saturated_steps: np.ndarray      # (T, G, N) control steps with any axis saturated
    A_bd_deg: np.ndarray | None = None   # (T, G, N, n_ctrl + 1, 3) true A_bd at the control instants (record=True)

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


# ----------------------------------------------------------------------------- layout helpers

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


def _rows(v: np.ndarray) -> np.ndarray:
    """(3, T, B) -> (T·B, 3)."""
    return np.moveaxis(v, 0, -1).reshape(-1, 3)


def _columns(rows: np.ndarray, T: int, B: int) -> np.ndarray:
    """(T·B, 3) -> (3, T, B)."""
    return np.moveaxis(np.asarray(rows, float).reshape(T, B, 3), -1, 0)


@dataclass
class _Targets:
    """Per target: the desired state at every plant sample (from the true orbit) and the initial state."""
    L_di: np.ndarray       # (n + 1, T, 3, 3)
    w_d: np.ndarray        # (n + 1, 3, T, 1)
    wdot_d: np.ndarray     # (n + 1, 3, T, 1)
    x0: np.ndarray         # (10, T, 1)

    @classmethod
    def build(cls, env, targets: Sequence[tuple[float, float]], n: int) -> "_Targets":
        T = len(targets)
        out = cls(np.empty((n + 1, T, 3, 3)), np.empty((n + 1, 3, T, 1)), np.empty((n + 1, 3, T, 1)),
                  np.empty((10, T, 1)))
        for i, (lon, lat) in enumerate(targets):
            d = desired_state(env.jd_days, env.sec_of_day, env.R, env.V, lon, lat)
            out.L_di[:, i], out.w_d[:, :, i, 0], out.wdot_d[:, :, i, 0] = d.L_di, d.omega_d, d.omegadot_d
            out.x0[:, i, 0] = initial_state(env, lon, lat)
        return out


class _Noise:
    """The scalar simulator's noise of every (target stream, seed), served per step as (3, T, B)."""

    def __init__(self, cfg: SimConfig, streams: Sequence[int], seeds: Sequence[int], variants: int):
        tracks = [[run_noise(cfg, seed, stream) for seed in seeds] for stream in streams]
        self.variants = variants

        def stack(field):   # (T, N, samples, 3)
            return np.array([[getattr(tr, field) for tr in per_target] for per_target in tracks])
        self.star, self.gyro, self.wheels = stack("star"), stack("gyro"), stack("wheels")

    def _at(self, noise: np.ndarray, i: int) -> np.ndarray:
        T, N = noise.shape[:2]
        per = np.broadcast_to(noise[:, None, :, i], (T, self.variants, N, 3)).reshape(T, self.variants * N, 3)
        return np.moveaxis(per, -1, 0)

    def star_at(self, k: int):
        return self._at(self.star, k)

    def gyro_at(self, k: int):
        return self._at(self.gyro, k)

    def wheels_at(self, j: int):
        return self._at(self.wheels, j)


# ----------------------------------------------------------------------------- the loop

class _Loop:
    """One batched run: state, sensors, the controller's rows, wheels, plant and the metrics."""

    def __init__(self, controller: BatchController, targets, seeds, cfg: SimConfig, plan: ImagingPlan,
                 streams, record: bool):
        self.cfg, self.controller = cfg, controller
        self.layout = BatchLayout(len(targets), int(controller.variants), len(seeds))
        T, B = self.layout.targets, self.layout.variants * self.layout.seeds
        self.T, self.B = T, B
        self.sub, self.n_ctrl = cfg.substeps, cfg.control_steps
        self.n = self.n_ctrl * self.sub
        self.env = environment_track(self.n + 1, cfg.plant_step)
        self.weights, self.m, self.p = _sample_weights(cfg, plan, self.n)
        self.plant = bp.Plant(cfg, self.env)
        self.tg = _Targets.build(self.env, targets, self.n)
        self.noise = _Noise(cfg, streams, seeds, self.layout.variants)
        self.lon = np.repeat(np.array([t[0] for t in targets], float), B)
        self.lat = np.repeat(np.array([t[1] for t in targets], float), B)
        errors = cfg.errors
        self.star_bias, self.gyro_bias, self.wheel_bias = (
            s.bias_array[:, None, None] for s in (errors.star, errors.gyro, errors.wheels))
        # the wheel error's draw index at each plant step (error_model.ErrorSource.draws' rule)
        self.wheel_draw = errors.wheels.draw_index(plant_times(self.n_ctrl, cfg.control_period, self.sub))
        self.x = np.ascontiguousarray(np.broadcast_to(self.tg.x0, (10, T, B)))
        self.sum_A, self.sum_w = np.zeros((3, T, B)), np.zeros((3, T, B))
        self.saturated_steps = np.zeros(T * B, dtype=np.int64)
        self.A_bd = np.empty((self.n_ctrl + 1, 3, T, B)) if record else None
        self.no_torque = np.zeros((3, T, B))

    def accumulate(self, j: int, L_bi) -> None:
        w = self.weights[j]
        if w:
            self.sum_A += w * np.abs(bp.euler312_of_product(L_bi, self.tg.L_di[j]))
            self.sum_w += w * np.abs(self.x[4:7] - self.tg.w_d[j])

    def measurement(self, k: int, L_bi) -> BatchMeasurement:
        """Star sensor on A_bo, gyro on ω_b, ideal GPS; then the float64 preprocessing
        (host.gnc.preprocess: L_bd = (L_bo(A_bo)·L_oi)·L_di^T, ω_e = ω_b − ω_d)."""
        cfg, env, T, B = self.cfg, self.env, self.T, self.B
        j0 = k * self.sub
        L_oi = env.L_oi[j0]
        A_bo = bp.euler312_of_product(L_bi, np.broadcast_to(L_oi, (T, 3, 3)))
        if cfg.sensor_errors:
            A_bo = (A_bo + self.star_bias) + self.noise.star_at(k)
        if cfg.attitude_offset is not None:   # a body-axes rotation of the measured attitude
            R = bp.dcm_from_euler312(np.broadcast_to(_broadcast_input(cfg.attitude_offset(env.t[j0]), T, B),
                                                     (3, T, B)))
            A_bo = bp.euler312(bp.matmul(R, bp.dcm_from_euler312(A_bo)))
        w_meas = self.x[4:7]
        if cfg.sensor_errors:
            w_meas = (w_meas + self.gyro_bias) + self.noise.gyro_at(k)
        D = bp.dcm_from_euler312(A_bo)
        C = np.stack([np.stack([(D[i, 0] * L_oi[0, c] + D[i, 1] * L_oi[1, c]) + D[i, 2] * L_oi[2, c]
                                for c in range(3)]) for i in range(3)])
        w_d = np.broadcast_to(self.tg.w_d[j0], (3, T, B))
        return BatchMeasurement(
            t=float(env.t[j0]), jd_days=int(env.jd_days[j0]), sec_of_day=float(env.sec_of_day[j0]),
            R_s=env.R[j0], V_s=env.V[j0], lon=self.lon, lat=self.lat, A_bo=_rows(A_bo), omega_b=_rows(w_meas),
            A_bd=_rows(bp.euler312_of_product(C, self.tg.L_di[j0])), omega_e=_rows(w_meas - w_d),
            omega_d=_rows(w_d), omegadot_d=_rows(np.broadcast_to(self.tg.wdot_d[j0], (3, T, B))))

    def advance(self, k: int, L_bi, cmd) -> None:
        """The command held over one control period: the wheels (saturation, errors), the momentum
        limit and the external torques at every plant step."""
        cfg, sc = self.cfg, self.cfg.spacecraft
        M_sat = np.clip(np.where(np.isfinite(cmd), cmd, 0.0), -sc.torque_limit, sc.torque_limit)
        j0 = k * self.sub
        for j in range(j0, j0 + self.sub):
            if j != j0:
                L_bi = bp.dcm_from_quat(self.x[0:4])
            self.accumulate(j, L_bi)
            if j == j0 or self.wheel_draw[j] != self.wheel_draw[j - 1]:   # a held draw: the same torque
                M_c = (M_sat + self.wheel_bias) + self.noise.wheels_at(j) if cfg.wheel_errors else M_sat
            M_ext = self.plant.external_torque(j, L_bi) if cfg.external_torques else self.no_torque
            if cfg.extra_torque is not None:
                M_ext = M_ext + _broadcast_input(cfg.extra_torque(self.env.t[j]), self.T, self.B)
            M_j = bp.momentum_limited(M_c, self.x[7:10], sc.momentum_limit)
            self.x = self.plant.rk4(self.x, M_j, M_ext, cfg.plant_step)

    def record(self, k: int, L_bi) -> None:
        if self.A_bd is not None:
            self.A_bd[k] = bp.euler312_of_product(L_bi, self.tg.L_di[k * self.sub])

    def run(self, progress: Callable[[int], None] | None) -> BatchResult:
        self.controller.reset(self.layout)
        for k in range(self.n_ctrl):
            L_bi = bp.dcm_from_quat(self.x[0:4])
            self.record(k, L_bi)
            out = self.controller.step(self.measurement(k, L_bi))
            self.saturated_steps += np.asarray(out.saturated, bool)
            self.advance(k, L_bi, _columns(out.torque, self.T, self.B))
            if progress is not None:
                progress(k)
        L_bi = bp.dcm_from_quat(self.x[0:4])
        self.accumulate(self.n, L_bi)
        self.record(self.n_ctrl, L_bi)
        return self.result()

    def result(self) -> BatchResult:
        lay = self.layout
        shape = (lay.targets, lay.variants, lay.seeds)
        count = self.m * (self.p + 1)

        def per_axis(s):
            return np.moveaxis(s / count / DEG, 0, -1).reshape(*shape, 3)
        A_bd = None
        if self.A_bd is not None:   # (n_ctrl + 1, 3, T, B) -> (T, G, N, n_ctrl + 1, 3), deg
            A_bd = np.moveaxis(self.A_bd, (0, 1), (-2, -1)).reshape(*shape, self.n_ctrl + 1, 3) / DEG
        return BatchResult(J_A_axis=per_axis(self.sum_A), J_w_axis=per_axis(self.sum_w), m=self.m, p=self.p,
                           saturated_steps=self.saturated_steps.reshape(shape), A_bd_deg=A_bd)


def simulate_batch(controller: BatchController, targets: Sequence[tuple[float, float]], seeds: Sequence[int] = (0,),
                   config: SimConfig = SimConfig(), plan: ImagingPlan = DEFAULT_PLAN,
                   streams: Sequence[int] | None = None, record: bool = False,
                   progress: Callable[[int], None] | None = None) -> BatchResult:
    """Fly every variant of `controller` at every target under every seed.

    targets: (lon, lat) rad; target i uses noise stream `streams[i]` (default i, as
    host.sim.simulator.simulate_targets does). config.extra_torque / attitude_offset may return
    (3,) or (T·G·N, 3). `progress(k)` is called after each control step.
    """
    if len(targets) == 0 or len(seeds) == 0:
        raise HostError(f"batched simulation needs at least one target and seed (got {len(targets)}, {len(seeds)})")
    streams = list(range(len(targets))) if streams is None else list(streams)
    if len(streams) != len(targets):
        raise HostError(f"{len(streams)} noise streams for {len(targets)} targets")
    return _Loop(controller, targets, list(seeds), config, plan, streams, record).run(progress)


def simulate_pid_batch(targets: Sequence[tuple[float, float]], gains: GainSets, seeds: Sequence[int] = (0,),
                       config: SimConfig = SimConfig(), plan: ImagingPlan = DEFAULT_PLAN,
                       streams: Sequence[int] | None = None, torque_limit: float | None = None,
                       progress: Callable[[int], None] | None = None) -> BatchResult:
    """The PID (host.control.pid) with every gain set at every target under every seed."""
    if len(gains) == 0:
        raise HostError("batched simulation needs at least one gain set")
    limit = config.spacecraft.torque_limit if torque_limit is None else float(torque_limit)
    return simulate_batch(PidBatch(gains, limit, config.control_period), targets, seeds, config, plan, streams,
                          progress=progress)
