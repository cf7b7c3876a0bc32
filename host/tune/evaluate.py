"""`staregen evaluate`: the comparisons of paper 001 §7 for the controllers this project makes.

* Staring (Tables 8-9, Fig. 10): J_A, J_ω, J (eq. 6-8, 25-27) of every controller over the
  targets, per target for the scatter. The PIDs (Table 1 and tuned) fly on the batched simulator
  (equal to the scalar one to 1e-9, tests/host/sim/test_batched.py); the network (float64, SIL),
  the PD + feed-forward baseline and the PIL run (central target only: the ARM emulator is slow)
  fly on the scalar simulator, one process per core.
* Step response (§7.6.1, Tables 10-11, Figs. 11-12): per controller and target, two runs with the
  same noise, one with an extra 0.005° star-sensor error on the three axes from 30 s; their
  difference d(t) of the true A_bd is the response (the controller drives the true attitude to
  −0.005°). Overshoot = max(0, max(−d/0.005°) − 1) in %, settling time = from 30 s to the last
  instant |d + 0.005°| > 5 % · 0.005°, steady-state error = |mean d over the last 10 s + 0.005°|
  in degrees; each averaged over the targets.
* Frequency response (§7.7, Figs. 13-14): central target, a 0.03 N·m sinusoidal torque on one
  axis at a time over a frequency grid; the amplitude (deg) of that axis's A_bd at the forcing
  frequency, from a least-squares sine fit to the difference with the undisturbed run (same
  noise) after the first `settle` seconds.
* Impulse (§7.8, Fig. 15): host.sim.impulse, run as before.
"""
from __future__ import annotations

import functools
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, replace
from multiprocessing import get_context
from typing import Callable

import numpy as np

from host.control.controllers import build_controller
from host.control.pid import TABLE1_GAINS, PidGains
from host.core.constants import DEG
from host.errors import HostError
from host.sim.batched import GainSets, simulate_pid_batch
from host.sim.metrics import K1, K2, staring_metrics
from host.sim.simulator import SimConfig, simulate

STEP_DEG = 0.005
STEP_AT = 30.0
SETTLE_BAND = 0.05
TORQUE_AMPLITUDE = 0.03


@dataclass(frozen=True)
class StepOffset:
    """The §7.6.1 extra angle measurement error: `deg` on the three axes from `t0` on (picklable)."""
    t0: float = STEP_AT
    deg: float = STEP_DEG

    def __call__(self, t: float) -> np.ndarray:
        return np.full(3, self.deg * DEG) if t >= self.t0 else np.zeros(3)


@dataclass(frozen=True)
class SineTorque:
    """The §7.7 periodic external torque on one axis (picklable)."""
    axis: int
    hz: float
    amplitude: float = TORQUE_AMPLITUDE

    def __call__(self, t: float) -> np.ndarray:
        out = np.zeros(3)
        out[self.axis] = self.amplitude * np.sin(2.0 * np.pi * self.hz * t)
        return out


@dataclass(frozen=True)
class ControllerSpec:
    """One evaluated controller: its registry name and factory options, or PID gains (batched)."""
    label: str
    name: str
    options: tuple = ()
    gains: PidGains | None = None

    def factory(self, torque_limit: float, control_period: float) -> Callable:
        opts = dict(self.options)
        if self.gains is not None:
            opts["gains"] = self.gains
        return functools.partial(build_controller, self.name, torque_limit=torque_limit,
                                 control_period=control_period, **opts)


@dataclass(frozen=True)
class EvalPlan:
    targets: tuple[tuple[str, float, float, int], ...]        # name, lon, lat, noise stream
    response_targets: tuple[tuple[str, float, float, int], ...]
    central: tuple[str, float, float, int]
    duration: float = 100.0
    seed: int = 0
    step_duration: float = 60.0
    freqs: tuple[float, ...] = (0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 3.0, 4.5)
    freq_duration: float = 60.0
    freq_settle: float = 20.0
    k1: float = K1
    k2: float = K2

    def __post_init__(self):
        if not self.targets or not self.response_targets:
            raise HostError("evaluation needs at least one target for the tables and one for the responses")
        if not self.freqs or any(not (0.0 < f < 5.0) for f in self.freqs):
            raise HostError("frequencies must lie in (0, 5) Hz (below the 0.1 s period's Nyquist frequency)")
        if self.step_duration < STEP_AT + 15.0:
            raise HostError(f"the step response needs at least {STEP_AT + 15.0:g} s")
        if self.freq_duration < self.freq_settle + 10.0:
            raise HostError("the frequency response needs 10 s after its settling time")


# ----------------------------------------------------------------------------- jobs (one process each)

def _job_metrics(make, lon, lat, cfg: SimConfig, stream: int) -> dict:
    h = simulate(make(), lon, lat, cfg, stream)
    m = staring_metrics(h.t, h.A_bd, h.omega_e, t_end=cfg.control_steps * cfg.control_period)
    return {"J_A": m.J_A, "J_w": m.J_w, "J": m.J}


def _job_history(make, lon, lat, cfg: SimConfig, stream: int) -> np.ndarray:
    """True A_bd (deg) at the control instants."""
    h = simulate(make(), lon, lat, cfg, stream)
    sub = cfg.substeps
    return h.A_bd[::sub] / DEG


def _run(fn, jobs: list[tuple], workers: int | None, progress: bool, desc: str) -> list:
    from tqdm import tqdm

    workers = max(1, min(workers or os.cpu_count() or 1, len(jobs)))
    results: list = [None] * len(jobs)
    with tqdm(total=len(jobs), desc=desc, unit="run", disable=not progress, mininterval=0.5) as bar:
        if workers == 1:
            for i, job in enumerate(jobs):
                results[i] = fn(*job)
                bar.update()
        else:
            with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn")) as pool:
                futures = {pool.submit(fn, *job): i for i, job in enumerate(jobs)}
                for fut in as_completed(futures):
                    results[futures[fut]] = fut.result()
                    bar.update()
    return results


# ----------------------------------------------------------------------------- staring (Tables 8-9)

def staring(plan: EvalPlan, specs: list[ControllerSpec], workers=None, progress=True,
            known: dict | None = None) -> dict:
    """Rows of the staring table; `known` rows (label -> row) are taken as they are, not flown again."""
    cfg = SimConfig(duration=plan.duration, seed=plan.seed)
    rows = {}
    pids = [s for s in specs if s.gains is not None]
    if pids:
        gains = GainSets(np.array([s.gains.kp for s in pids]), np.array([s.gains.ki for s in pids]),
                         np.array([s.gains.kd for s in pids]))
        res = simulate_pid_batch([(lon, lat) for _, lon, lat, _ in plan.targets], gains, (plan.seed,), cfg,
                                 streams=[s for *_, s in plan.targets])
        for g, spec in enumerate(pids):
            rows[spec.label] = _row(res.J_A[:, g, 0], res.J_w[:, g, 0], plan)
    for spec in specs:
        if spec.gains is not None:
            continue
        if known and spec.label in known:
            rows[spec.label] = known[spec.label]
            continue
        targets = [plan.central] if spec.name == "nn-arm" else list(plan.targets)
        make = spec.factory(cfg.spacecraft.torque_limit, cfg.control_period)
        out = _run(_job_metrics, [(make, lon, lat, cfg, s) for _, lon, lat, s in targets], workers, progress,
                   f"staring {spec.label}")
        rows[spec.label] = _row(np.array([o["J_A"] for o in out]), np.array([o["J_w"] for o in out]), plan)
        rows[spec.label]["targets"] = len(targets)
    return rows


def _row(J_A: np.ndarray, J_w: np.ndarray, plan: EvalPlan) -> dict:
    J_A, J_w = np.asarray(J_A, float), np.asarray(J_w, float)
    return {"J_A": float(J_A.mean()), "J_w": float(J_w.mean()), "J": float(plan.k1 * J_A.mean() + plan.k2 * J_w.mean()),
            "targets": int(J_A.size), "per_target": {"J_A": J_A.tolist(), "J_w": J_w.tolist()}}


# ----------------------------------------------------------------------------- step response (Tables 10-11)

def step_metrics(d_deg: np.ndarray, t: np.ndarray, t0: float = STEP_AT, step: float = STEP_DEG) -> dict:
    """Overshoot (%), settling time (s) and steady-state error (deg) per axis of the response
    d (n, 3) (deg) to a −`step` change at t0 (see the module doc)."""
    after = t >= t0
    d, ta = d_deg[after], t[after]
    target = -step
    overshoot = np.maximum(0.0, (-d).max(axis=0) / step - 1.0) * 100.0
    outside = np.abs(d - target) > SETTLE_BAND * step
    settling = np.array([ta[np.flatnonzero(outside[:, a])[-1]] - t0 if outside[:, a].any() else 0.0
                         for a in range(3)])
    tail = ta >= ta[-1] - 10.0
    steady = np.abs(d[tail].mean(axis=0) - target)
    return {"overshoot_pct": overshoot.tolist(), "settling_s": settling.tolist(), "steady_state_deg": steady.tolist()}


def step_response(plan: EvalPlan, specs: list[ControllerSpec], workers=None, progress=True) -> dict:
    base = SimConfig(duration=plan.step_duration, seed=plan.seed)
    stepped = replace(base, attitude_offset=StepOffset())
    t = np.arange(base.control_steps + 1) * base.control_period
    out = {}
    for spec in specs:
        if spec.name == "nn-arm":
            continue
        make = spec.factory(base.spacecraft.torque_limit, base.control_period)
        jobs = [(make, lon, lat, c, s) for _, lon, lat, s in plan.response_targets for c in (base, stepped)]
        hist = _run(_job_history, jobs, workers, progress, f"step {spec.label}")
        per_target = [step_metrics(hist[2 * i + 1] - hist[2 * i], t) for i in range(len(plan.response_targets))]
        mean = {k: np.mean([p[k] for p in per_target], axis=0).tolist() for k in per_target[0]}
        central = hist[1] - hist[0]
        out[spec.label] = {"mean": mean, "targets": len(per_target),
                           "first_target_response_deg": central[t >= STEP_AT - 5.0].tolist(),
                           "t": t[t >= STEP_AT - 5.0].tolist()}
    return out


# ----------------------------------------------------------------------------- frequency response (Figs. 13-14)

def sine_amplitude(d: np.ndarray, t: np.ndarray, hz: float) -> float:
    """Amplitude of the `hz` component of d(t): least squares on [sin, cos, 1]."""
    w = 2.0 * np.pi * hz
    A = np.stack([np.sin(w * t), np.cos(w * t), np.ones_like(t)], -1)
    coef, *_ = np.linalg.lstsq(A, d, rcond=None)
    return float(np.hypot(coef[0], coef[1]))


def frequency_response(plan: EvalPlan, specs: list[ControllerSpec], workers=None, progress=True) -> dict:
    base = SimConfig(duration=plan.freq_duration, seed=plan.seed)
    t = np.arange(base.control_steps + 1) * base.control_period
    keep = t >= plan.freq_settle
    _, lon, lat, stream = plan.central
    out = {}
    for spec in specs:
        if spec.name == "nn-arm":
            continue
        make = spec.factory(base.spacecraft.torque_limit, base.control_period)
        cfgs = [base] + [replace(base, extra_torque=SineTorque(a, f)) for a in range(3) for f in plan.freqs]
        hist = _run(_job_history, [(make, lon, lat, c, stream) for c in cfgs], workers, progress, f"frequency {spec.label}")
        mags = np.zeros((3, len(plan.freqs)))
        for a in range(3):
            for k, f in enumerate(plan.freqs):
                d = hist[1 + a * len(plan.freqs) + k][:, a] - hist[0][:, a]
                mags[a, k] = sine_amplitude(d[keep], t[keep], f)
        out[spec.label] = {"freqs_hz": list(plan.freqs), "amplitude_deg": mags.tolist()}
    return out


def evaluate(plan: EvalPlan, specs: list[ControllerSpec], workers=None, progress=True) -> dict:
    labels = [s.label for s in specs]
    if len(set(labels)) != len(labels):
        raise HostError(f"controllers listed twice: {labels}")
    times = {}
    t0 = time.perf_counter()
    central = staring(replace(plan, targets=(plan.central,)), specs, workers, progress)
    # the PIL run flies the central target only: its row of the central table is its row here too
    result = {"staring": staring(plan, specs, workers, progress,
                                 known={s.label: central[s.label] for s in specs if s.name == "nn-arm"}),
              "staring_central": central}
    times["staring_s"] = round(time.perf_counter() - t0, 2)
    t0 = time.perf_counter()
    result["step"] = step_response(plan, specs, workers, progress)
    times["step_s"] = round(time.perf_counter() - t0, 2)
    t0 = time.perf_counter()
    result["frequency"] = frequency_response(plan, specs, workers, progress)
    times["frequency_s"] = round(time.perf_counter() - t0, 2)
    result["timing"] = times
    result["plan"] = {"targets": len(plan.targets), "response_targets": len(plan.response_targets),
                      "duration": plan.duration, "seed": plan.seed, "step_duration": plan.step_duration,
                      "freqs_hz": list(plan.freqs), "freq_duration": plan.freq_duration,
                      "freq_settle": plan.freq_settle, "k1": plan.k1, "k2": plan.k2}
    return result


def table1_spec() -> ControllerSpec:
    return ControllerSpec("PID (Table 1)", "pid", gains=TABLE1_GAINS)


def tuned_spec(kp, ki, kd) -> ControllerSpec:
    return ControllerSpec("PID (tuned)", "pid", gains=PidGains(np.asarray(kp, float), np.asarray(ki, float),
                                                                  np.asarray(kd, float)))

