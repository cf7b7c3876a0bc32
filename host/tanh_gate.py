"""Bit-exact three-way gate of the generated tanh-law step: golden == x86 C == ARM C.

Independent rows (state + input, seeded, `gate_vectors`) in seven classes:
  random      random rotations R_c, R_t, rates over several decades, random ϖ
  small       errors of 1e-7 .. 3e-2 rad (x1 inside and around η: f's quadratic patch)
  delta       ϖ = x2 − δ with ‖δ‖ across n1 and √delta_reg (u_a's inner branch, ρ's switch)
  singular    errors within 1.5° of 180° and exactly 180°, and across q0 = q0_min
  off_so3     matrices off SO(3) (noise 1e-6 .. 1, arbitrary matrices)
  extreme     rates and ϖ over 1e3 .. FLT_MAX (overflow paths, the ϖ clamp)
  special     ±0, subnormals, ±Inf, NaN, ±FLT_MAX in random input/state positions
and closed-loop time series (`closed_sequences`): the golden step flies the paper-000 plant for
T steps from random starts (some near 180°), the float32 inputs are recorded and replayed
through each C build from tanh_init with the state carried inside the C. Everything is
compared as uint32 bit patterns (NaN as a class) at every row / step.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.spatial.transform import Rotation

from codegen import bitcompare
from codegen import golden_tanh as gt
from codegen.tanh_emit import DEFAULT_PERIOD, constants32
from codegen.tanh_params import TanhParams

F32 = np.float32
CLASSES = ("random", "small", "delta", "singular", "off_so3", "extreme", "special")
SPECIAL = np.array([0.0, -0.0, 1e-45, -1e-45, 1.1754942e-38, -1.1754942e-38, 1.1754944e-38,
                    np.inf, -np.inf, np.nan, -np.nan, 3.4028235e38, -3.4028235e38], dtype=F32)


def _rot(n: int, rng) -> np.ndarray:
    return Rotation.random(n, random_state=rng).as_matrix()


def _rotvec(angles: np.ndarray, rng) -> np.ndarray:
    axis = rng.normal(size=(angles.size, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    return Rotation.from_rotvec(axis * angles[:, None]).as_matrix()


def _log_uniform(rng, lo: float, hi: float, shape) -> np.ndarray:
    return np.exp(rng.uniform(np.log(lo), np.log(hi), shape)) * rng.choice([-1.0, 1.0], shape)


def _inputs(R_c, w_c, R_t, w_t, wdot_t) -> np.ndarray:
    n = R_c.shape[0]
    with np.errstate(over="ignore"):
        return np.ascontiguousarray(np.concatenate(
            [R_c.reshape(n, 9), w_c, R_t.reshape(n, 9), w_t, wdot_t], axis=1).astype(F32))


def _motion(rng, n: int, scale: float = 1.0):
    return (_log_uniform(rng, 1e-6, 2.0 * scale, (n, 3)), _log_uniform(rng, 1e-6, 0.2 * scale, (n, 3)),
            _log_uniform(rng, 1e-7, 0.02 * scale, (n, 3)))


def _class_random(k, rng, n):
    w_c, w_t, wdot_t = _motion(rng, n)
    return _log_uniform(rng, 1e-4, 20.0, (n, 3)).astype(F32), _inputs(_rot(n, rng), w_c, _rot(n, rng), w_t, wdot_t)


def _class_small(k, rng, n):
    R_t = _rot(n, rng)
    R_c = R_t @ _rotvec(np.exp(rng.uniform(np.log(1e-7), np.log(3e-2), n)), rng)
    w_c, w_t, wdot_t = _motion(rng, n, 0.01)
    return _log_uniform(rng, 1e-6, 1.0, (n, 3)).astype(F32), _inputs(R_c, w_c, R_t, w_t, wdot_t)


def _class_delta(k, rng, n):
    """ϖ = x2 − δ: x2 from the golden step itself, ‖δ‖ log-uniform over [1e-6, 0.3]."""
    state, x = _class_random(k, rng, n)
    half = n // 2
    state[:half], x[:half] = _class_small(k, rng, half)
    _, out = gt.step(k, np.zeros((n, 3), F32), x)
    d = rng.normal(size=(n, 3))
    d *= (np.exp(rng.uniform(np.log(1e-6), np.log(0.3), n)) / np.linalg.norm(d, axis=1))[:, None]
    return (out[:, 6:9].astype(np.float64) - d).astype(F32), x


def _class_singular(k, rng, n):
    R_t = _rot(n, rng)
    angle = np.pi - np.exp(rng.uniform(np.log(1e-7), np.log(np.radians(1.5)), n))
    q0_edge = 2.0 * np.arccos(float(k.q0min_sq) ** 0.5) + rng.uniform(-1e-5, 1e-5, n)
    angle = np.where(rng.random(n) < 0.3, q0_edge, angle)
    angle[: n // 10] = np.pi  # exactly 180°: R_e symmetric, q0 = 0
    R_c = R_t @ _rotvec(angle, rng)
    w_c, w_t, wdot_t = _motion(rng, n)
    return _log_uniform(rng, 1e-4, 20.0, (n, 3)).astype(F32), _inputs(R_c, w_c, R_t, w_t, wdot_t)


def _class_off_so3(k, rng, n):
    state, x = _class_random(k, rng, n)
    noise = _log_uniform(rng, 1e-6, 1.0, (n, 1)) * rng.normal(size=(n, 18))
    x[:, 0:9] += noise[:, :9].astype(F32)
    x[:, 12:21] += noise[:, 9:].astype(F32)
    x[: n // 4, 0:9] = rng.normal(size=(n // 4, 9)).astype(F32)
    return state, x


def _class_extreme(k, rng, n):
    state, x = _class_random(k, rng, n)
    with np.errstate(over="ignore"):
        big = _log_uniform(rng, 1e3, 3e38, (n, 9)).astype(F32)
        state = np.where(rng.random((n, 3)) < 0.5, big[:, :3], state).astype(F32)
        x[:, 9:12] = np.where(rng.random((n, 3)) < 0.5, big[:, 3:6], x[:, 9:12])
        x[:, 24:27] = np.where(rng.random((n, 3)) < 0.3, big[:, 6:9], x[:, 24:27])
    return state, x


def _class_special(k, rng, n):
    state, x = _class_random(k, rng, n)
    rec = np.concatenate([state, x], axis=1)
    cols = rng.integers(0, rec.shape[1], n)
    rec[np.arange(n), cols] = SPECIAL[np.arange(n) % SPECIAL.size]
    extra = rng.random(rec.shape) < 0.02
    rec[extra] = SPECIAL[rng.integers(0, SPECIAL.size, int(extra.sum()))]
    return np.ascontiguousarray(rec[:, :3]), np.ascontiguousarray(rec[:, 3:])


_MAKERS = {"random": _class_random, "small": _class_small, "delta": _class_delta,
           "singular": _class_singular, "off_so3": _class_off_so3, "extreme": _class_extreme,
           "special": _class_special}


def gate_vectors(params: TanhParams, n: int, seed: int = 0, period: float = DEFAULT_PERIOD
                 ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """{class: (state (m, 3), inputs (m, 27))} float32, n rows in all (deterministic in seed)."""
    if n < len(CLASSES):
        raise ValueError(f"need at least {len(CLASSES)} vectors, got {n}")
    k = constants32(params, period)
    rng = np.random.default_rng(seed)
    sizes = [n // len(CLASSES)] * len(CLASSES)
    sizes[0] += n - sum(sizes)
    return {name: _MAKERS[name](k, rng, m) for name, m in zip(CLASSES, sizes)}


# ----------------------------------------------------------------------------- closed sequences


def _plant_step(J, J_inv, R, w, u, t, h, amp):
    """One RK4 step (batch) of J ω̇ = −ω×Jω + u + d(t), Ṙ = R[ω]×, u held."""
    def rates(t, R, w):
        d = amp * np.stack([np.sin(0.1 * t), np.cos(0.2 * t), np.sin(0.2 * t)])
        wdot = (-np.cross(w, w @ J.T) + u + d) @ J_inv.T
        W = np.zeros(w.shape[:1] + (3, 3))
        W[:, 0, 1], W[:, 0, 2], W[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
        W[:, 1, 0], W[:, 2, 0], W[:, 2, 1] = w[:, 2], -w[:, 1], w[:, 0]
        return R @ W, wdot
    k1 = rates(t, R, w)
    k2 = rates(t + h / 2, R + h / 2 * k1[0], w + h / 2 * k1[1])
    k3 = rates(t + h / 2, R + h / 2 * k2[0], w + h / 2 * k2[1])
    k4 = rates(t + h, R + h * k3[0], w + h * k3[1])
    return (R + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]),
            w + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]))


def closed_sequences(params: TanhParams, n_seq: int, steps: int, seed: int = 0,
                     period: float = DEFAULT_PERIOD, substeps: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """(inputs (S, T, 27), golden outputs (S, T, 13)): the golden step in closed loop with the
    rigid body of J (paper 000's disturbance), from random attitudes (a quarter, at least one,
    within 1° of 180°), random rates and a slowly turning target."""
    k = constants32(params, period)
    rng = np.random.default_rng(seed)
    J = np.array(params.inertia)
    J_inv = np.linalg.inv(J)
    R_t0 = _rot(n_seq, rng)
    angle = rng.uniform(0.0, np.pi, n_seq)
    near = max(1, n_seq // 4)
    angle[:near] = np.pi - rng.uniform(0.0, np.radians(1.0), near)  # q0 < q0_min: starts in the fallback
    R = R_t0 @ _rotvec(angle, rng)
    w = rng.normal(scale=0.1, size=(n_seq, 3))
    w_t = rng.normal(scale=0.002, size=(n_seq, 3)) * (rng.random((n_seq, 1)) < 0.5)
    state = np.zeros((n_seq, 3), F32)
    inputs = np.empty((n_seq, steps, gt.N_IN), F32)
    outputs = np.empty((n_seq, steps, gt.N_OUT), F32)
    zero = np.zeros((n_seq, 3))
    for s in range(steps):
        t = s * period
        R_t = R_t0 @ Rotation.from_rotvec(w_t * t).as_matrix()
        x = _inputs(R, w, R_t, w_t, zero)
        state, out = gt.step(k, state, x)
        inputs[:, s], outputs[:, s] = x, out
        u = out[:, 0:3].astype(np.float64)
        for j in range(substeps):
            R, w = _plant_step(J, J_inv, R, w, u, t + j * period / substeps, period / substeps, 0.002)
    return inputs, outputs


# ----------------------------------------------------------------------------- the gate


def _report(name: str, target: str, expected: np.ndarray, actual: np.ndarray) -> bool:
    result = bitcompare.compare(expected, actual)
    lines = result.report("golden", target)
    print(f"  {name}: {target} vs golden: {lines[0]}")
    for line in lines[1:]:
        print("  " + line)
    return result.ok


def evaluators(params: TanhParams, targets, period: float):
    from host.tanh_sil import ArmTanh, X86Tanh

    makers = {"x86": X86Tanh, "arm": ArmTanh}
    return {t: makers[t](params, period) for t in targets}


def run_gate(params: TanhParams, n: int, seed: int = 0, targets=("x86", "arm"),
             period: float = DEFAULT_PERIOD, n_seq: int = 8, steps: int = 1000) -> bool:
    """Prints the per-class / per-target report and timings; True when every bit matches."""
    start = time.perf_counter()
    k = constants32(params, period)
    vectors = gate_vectors(params, n, seed, period)
    t0 = time.perf_counter()
    golden = {c: gt.step(k, s, x)[1] for c, (s, x) in vectors.items()}
    t1 = time.perf_counter()
    inputs, seq_golden = closed_sequences(params, n_seq, steps, seed, period) if n_seq else (None, None)
    t2 = time.perf_counter()
    counts = ", ".join(f"{c} {x.shape[0]}" for c, (_, x) in vectors.items())
    print(f"vectors: {n} ({counts}), seed {seed}; golden {t1 - t0:.2f} s; "
          f"{n_seq} closed sequences x {steps} steps (golden + plant) {t2 - t1:.2f} s")
    status = np.concatenate([g[:, 12].view(np.uint32) for g in golden.values()])
    print("golden status: " + ", ".join(f"{name} {int((status == v).sum())}"
                                         for v, name in enumerate(("ok", "singular", "invalid"))))
    ok = True
    for target, ev in evaluators(params, targets, period).items():
        t0 = time.perf_counter()
        for c, (s, x) in vectors.items():
            ok &= _report(c, target, golden[c], ev.step(s, x))
        for i in range(n_seq):
            ok &= _report(f"sequence {i}", target, seq_golden[i], ev.sequence(inputs[i]))
        print(f"{target}: {time.perf_counter() - t0:.2f} s")
    print(f"total {time.perf_counter() - start:.2f} s: {'PASS' if ok else 'FAIL'}")
    return bool(ok)
