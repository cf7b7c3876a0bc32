"""`staregen evaluate`: the comparisons of paper 001 §7 for the controllers this project makes.

Engines. `batched` (the default): every controller with a batched form (host.control.controllers.
BATCH_CONTROLLERS: the PIDs, the network in float64 and as generated C (SIL, through its record
runner), PD+FF, the discrete-point law and its C) flies in one batched run per experiment, the
controllers side by side as the variants of one bank (host.control.batch.ControllerBank) on common
noise; each batched law equals its scalar run to 1e-9 (tests/host/sim/test_batched_laws.py). The
PIL run (central target only: the ARM emulator steps one record at a time) flies on the scalar
simulator. `scalar`: every controller on the scalar simulator, one process per core (the reference,
kept for the side-by-side benchmark).

* Staring (Tables 8-9, Fig. 10): J_A, J_ω, J (eq. 6-8, 25-27) of every controller over the
  targets, per target for the scatter, and on the central target alone (Table 8).
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
from tqdm import tqdm

from host.control.batch import ControllerBank
from host.control.controllers import build_batch_controller, build_controller, has_batch
from host.control.pid import TABLE1_GAINS, PidGains
from host.core.constants import DEG
from host.errors import HostError
from host.plant.error_model import TABLE6_ERRORS, ErrorModel
from host.sim.batched import simulate_batch
from host.sim.metrics import K1, K2, staring_metrics
from host.sim.simulator import SimConfig, simulate

STEP_DEG = 0.005
STEP_AT = 30.0
SETTLE_BAND = 0.05
TORQUE_AMPLITUDE = 0.03
ENGINES = ("batched", "scalar")
# `--quick`: the small preset (CI, a first look); its numbers are not comparable with the paper's
QUICK = {"targets": 3, "duration": 20.0, "response_targets": 1, "freqs": (0.1, 1.0), "freq_duration": 30.0}


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
class StepOffsetRows:
    """StepOffset on the rows whose target index is `first_stepped` or later (the stepped copies)."""
    targets: int
    first_stepped: int
    per_target_rows: int
    t0: float = STEP_AT
    deg: float = STEP_DEG

    def __call__(self, t: float) -> np.ndarray:
        out = np.zeros((self.targets * self.per_target_rows, 3))
        if t >= self.t0:
            out[self.first_stepped * self.per_target_rows:] = self.deg * DEG
        return out


@dataclass(frozen=True)
class SineTorqueRows:
    """SineTorque per target copy: copy 0 undisturbed, copy 1 + a·F + k on axis a at freqs[k]."""
    freqs: tuple[float, ...]
    per_target_rows: int
    amplitude: float = TORQUE_AMPLITUDE

    def __call__(self, t: float) -> np.ndarray:
        F = len(self.freqs)
        per_copy = np.zeros((1 + 3 * F, 3))
        for a in range(3):
            per_copy[1 + a * F:1 + (a + 1) * F, a] = self.amplitude * np.sin(2.0 * np.pi * np.asarray(self.freqs) * t)
        return np.repeat(per_copy, self.per_target_rows, axis=0)


@dataclass(frozen=True)
class ControllerSpec:
    """One evaluated controller: its registry name and factory options, or PID gains."""
    label: str
    name: str
    options: tuple = ()
    gains: PidGains | None = None

    def _options(self) -> dict:
        opts = dict(self.options)
        if self.gains is not None:
            opts["gains"] = self.gains
        return opts

    def factory(self, torque_limit: float, control_period: float) -> Callable:
        return functools.partial(build_controller, self.name, torque_limit=torque_limit,
                                 control_period=control_period, **self._options())

    def batch(self, torque_limit: float, control_period: float):
        return build_batch_controller(self.name, torque_limit=torque_limit, control_period=control_period,
                                      **self._options())


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
    errors: ErrorModel = TABLE6_ERRORS
    engine: str = "batched"
    preset: str = "paper"       # "paper" (100 targets × 100 s by default) or "quick"

    def config(self, duration: float, **extra) -> SimConfig:
        return SimConfig(duration=duration, seed=self.seed, errors=self.errors, **extra)

    def batched(self, spec: "ControllerSpec") -> bool:
        return self.engine == "batched" and has_batch(spec.name)

    def __post_init__(self):
        if self.engine not in ENGINES:
            raise HostError(f"unknown engine {self.engine!r} (choose from {', '.join(ENGINES)})")
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


# ----------------------------------------------------------------------------- the batched runs

def _bar_callback(total: int, progress: bool, desc: str):
    """(callback(k), close()) of a tqdm bar over the control steps of one batched run."""
    bar = tqdm(total=total, desc=desc, unit="step", disable=not progress, mininterval=0.5)
    return (lambda k: bar.update()), bar.close


def fly_bank(plan: EvalPlan, specs: list[ControllerSpec], targets: list[tuple[float, float]], streams: list[int],
              cfg: SimConfig, progress: bool, desc: str, record: bool = False):
    """Every spec side by side in one batched run; the result's variant g is specs[g]."""
    bank = ControllerBank([s.batch(cfg.spacecraft.torque_limit, cfg.control_period) for s in specs])
    update, close = _bar_callback(cfg.control_steps, progress, desc)
    try:
        return simulate_batch(bank, targets, (plan.seed,), cfg, streams=streams, record=record, progress=update)
    finally:
        close()


def _split(plan: EvalPlan, specs: list[ControllerSpec]) -> tuple[list, list]:
    """(specs flown batched, specs flown on the scalar simulator)."""
    return [s for s in specs if plan.batched(s)], [s for s in specs if not plan.batched(s)]


# ----------------------------------------------------------------------------- staring (Tables 8-9)

def scalar_staring(plan: EvalPlan, specs: list[ControllerSpec], workers=None, progress=True,
                   known: dict | None = None) -> dict:
    """Rows of the staring table on the scalar simulator (the PIL run on the central target only);
    `known` rows (label -> row) are taken as they are, not flown again."""
    cfg = plan.config(plan.duration)
    rows = dict(known or {})
    for spec in specs:
        if spec.label in rows:
            continue
        targets = [plan.central] if spec.name == "nn-arm" else list(plan.targets)
        make = spec.factory(cfg.spacecraft.torque_limit, cfg.control_period)
        out = _run(_job_metrics, [(make, lon, lat, cfg, s) for _, lon, lat, s in targets], workers, progress,
                   f"staring {spec.label}")
        rows[spec.label] = _row(np.array([o["J_A"] for o in out]), np.array([o["J_w"] for o in out]), plan)
    return {s.label: rows[s.label] for s in specs}


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


def _step_entry(pairs: list[np.ndarray], t: np.ndarray) -> dict:
    """Mean step metrics over the targets and the first target's response, from (base, stepped)
    histories of true A_bd (deg) at the control instants."""
    per_target = [step_metrics(stepped - base, t) for base, stepped in pairs]
    mean = {k: np.mean([p[k] for p in per_target], axis=0).tolist() for k in per_target[0]}
    first = pairs[0][1] - pairs[0][0]
    return {"mean": mean, "targets": len(per_target), "first_target_response_deg": first[t >= STEP_AT - 5.0].tolist(),
            "t": t[t >= STEP_AT - 5.0].tolist()}


def step_response(plan: EvalPlan, specs: list[ControllerSpec], workers=None, progress=True) -> dict:
    base = plan.config(plan.step_duration)
    t = np.arange(base.control_steps + 1) * base.control_period
    specs = [s for s in specs if s.name != "nn-arm"]
    batched, scalar = _split(plan, specs)
    out = {}
    if batched:   # the targets twice: copies 0..n-1 plain, n..2n-1 with the offset
        n = len(plan.response_targets)
        targets = [(lon, lat) for _, lon, lat, _ in plan.response_targets] * 2
        streams = [s for *_, s in plan.response_targets] * 2
        cfg = replace(base, attitude_offset=StepOffsetRows(2 * n, n, len(batched)))
        res = fly_bank(plan, batched, targets, streams, cfg, progress, f"step ({n} targets)", record=True)
        for g, spec in enumerate(batched):
            out[spec.label] = _step_entry([(res.A_bd_deg[i, g, 0], res.A_bd_deg[n + i, g, 0]) for i in range(n)], t)
    stepped = replace(base, attitude_offset=StepOffset())
    for spec in scalar:
        make = spec.factory(base.spacecraft.torque_limit, base.control_period)
        jobs = [(make, lon, lat, c, s) for _, lon, lat, s in plan.response_targets for c in (base, stepped)]
        hist = _run(_job_history, jobs, workers, progress, f"step {spec.label}")
        out[spec.label] = _step_entry([(hist[2 * i], hist[2 * i + 1]) for i in range(len(plan.response_targets))], t)
    return {s.label: out[s.label] for s in specs}


# ----------------------------------------------------------------------------- frequency response (Figs. 13-14)

def sine_amplitude(d: np.ndarray, t: np.ndarray, hz: float) -> float:
    """Amplitude of the `hz` component of d(t): least squares on [sin, cos, 1]."""
    w = 2.0 * np.pi * hz
    A = np.stack([np.sin(w * t), np.cos(w * t), np.ones_like(t)], -1)
    coef, *_ = np.linalg.lstsq(A, d, rcond=None)
    return float(np.hypot(coef[0], coef[1]))


def _amplitudes(hist: list[np.ndarray], t: np.ndarray, keep: np.ndarray, freqs: tuple[float, ...]) -> list:
    """(3, F) attitude amplitudes from histories [undisturbed, axis a at freqs[k] (index 1 + a·F + k)]."""
    mags = np.zeros((3, len(freqs)))
    for a in range(3):
        for k, f in enumerate(freqs):
            d = hist[1 + a * len(freqs) + k][:, a] - hist[0][:, a]
            mags[a, k] = sine_amplitude(d[keep], t[keep], f)
    return mags.tolist()


def frequency_response(plan: EvalPlan, specs: list[ControllerSpec], workers=None, progress=True) -> dict:
    base = plan.config(plan.freq_duration)
    t = np.arange(base.control_steps + 1) * base.control_period
    keep = t >= plan.freq_settle
    _, lon, lat, stream = plan.central
    specs = [s for s in specs if s.name != "nn-arm"]
    batched, scalar = _split(plan, specs)
    copies = 1 + 3 * len(plan.freqs)
    out = {}
    if batched:   # the central target once undisturbed and once per (axis, frequency)
        cfg = replace(base, extra_torque=SineTorqueRows(tuple(plan.freqs), len(batched)))
        res = fly_bank(plan, batched, [(lon, lat)] * copies, [stream] * copies, cfg, progress,
                        f"frequency ({copies} runs)", record=True)
        for g, spec in enumerate(batched):
            hist = [res.A_bd_deg[c, g, 0] for c in range(copies)]
            out[spec.label] = {"freqs_hz": list(plan.freqs), "amplitude_deg": _amplitudes(hist, t, keep, plan.freqs)}
    for spec in scalar:
        make = spec.factory(base.spacecraft.torque_limit, base.control_period)
        cfgs = [base] + [replace(base, extra_torque=SineTorque(a, f)) for a in range(3) for f in plan.freqs]
        hist = _run(_job_history, [(make, lon, lat, c, stream) for c in cfgs], workers, progress, f"frequency {spec.label}")
        out[spec.label] = {"freqs_hz": list(plan.freqs), "amplitude_deg": _amplitudes(hist, t, keep, plan.freqs)}
    return {s.label: out[s.label] for s in specs}


def staring_tables(plan: EvalPlan, specs: list[ControllerSpec], workers=None, progress=True) -> dict:
    """Tables 8 and 9: {"staring_central": rows, "staring": rows}. Batched, the central target flies in
    the same run as the targets; the PIL run flies the central target only, so its row of the central
    table is its row of the targets' table too."""
    batched, scalar = _split(plan, specs)
    central_plan = replace(plan, targets=(plan.central,))
    rows_c, rows_t = {}, {}
    if batched:
        both = replace(plan, targets=(plan.central,) + tuple(plan.targets))
        res = fly_bank(both, batched, [(lon, lat) for _, lon, lat, _ in both.targets], [s for *_, s in both.targets],
                       plan.config(plan.duration), progress, f"staring (central + {len(plan.targets)} targets)")
        for g, spec in enumerate(batched):
            rows_c[spec.label] = _row(res.J_A[:1, g, 0], res.J_w[:1, g, 0], plan)
            rows_t[spec.label] = _row(res.J_A[1:, g, 0], res.J_w[1:, g, 0], plan)
    if scalar:
        rows_c.update(scalar_staring(central_plan, scalar, workers, progress))
        rows_t.update(scalar_staring(plan, scalar, workers, progress,
                                     known={s.label: rows_c[s.label] for s in scalar if s.name == "nn-arm"}))
    return {"staring": {s.label: rows_t[s.label] for s in specs},
            "staring_central": {s.label: rows_c[s.label] for s in specs}}


EXPERIMENTS = {"staring": staring_tables, "step": step_response, "frequency": frequency_response}


def _experiment(name: str, plan: EvalPlan, specs: list[ControllerSpec], workers, progress) -> tuple[dict, float]:
    t0 = time.perf_counter()
    return EXPERIMENTS[name](plan, specs, workers, progress), round(time.perf_counter() - t0, 2)


def _run_experiments(plan: EvalPlan, specs: list[ControllerSpec], workers, progress) -> dict[str, tuple]:
    """The three experiments; batched, each in its own process (up to `workers`, default every core):
    a batched run uses one core, and the experiments are independent."""
    n = max(1, min(workers or os.cpu_count() or 1, len(EXPERIMENTS)))
    if plan.engine != "batched" or n == 1:
        return {name: _experiment(name, plan, specs, workers, progress) for name in EXPERIMENTS}
    with ProcessPoolExecutor(max_workers=n, mp_context=get_context("spawn")) as pool:
        futures = {name: pool.submit(_experiment, name, plan, specs, 1, progress) for name in EXPERIMENTS}
        return {name: fut.result() for name, fut in futures.items()}


def evaluate(plan: EvalPlan, specs: list[ControllerSpec], workers=None, progress=True) -> dict:
    labels = [s.label for s in specs]
    if len(set(labels)) != len(labels):
        raise HostError(f"controllers listed twice: {labels}")
    done = _run_experiments(plan, specs, workers, progress)
    result = {**done["staring"][0], "step": done["step"][0], "frequency": done["frequency"][0]}
    result["timing"] = {f"{name}_s": seconds for name, (_, seconds) in done.items()}
    result["plan"] = {"targets": len(plan.targets), "response_targets": len(plan.response_targets),
                      "duration": plan.duration, "seed": plan.seed, "step_duration": plan.step_duration,
                      "freqs_hz": list(plan.freqs), "freq_duration": plan.freq_duration,
                      "freq_settle": plan.freq_settle, "k1": plan.k1, "k2": plan.k2, "engine": plan.engine,
                      "preset": plan.preset, "error_reading": plan.errors.reading}
    return result


def table1_spec() -> ControllerSpec:
    return ControllerSpec("PID (Table 1)", "pid", gains=TABLE1_GAINS)


def tuned_spec(kp, ki, kd) -> ControllerSpec:
    return ControllerSpec("PID (tuned)", "pid", gains=PidGains(np.asarray(kp, float), np.asarray(ki, float),
                                                                  np.asarray(kd, float)))

