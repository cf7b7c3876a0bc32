"""Gate input classes of the generated tanh-law step (independent (state, input) rows):
  random      random rotations R_c, R_t, rates over several decades, random ϖ
  small       errors of 1e-7 .. 3e-2 rad (x1 inside and around η: f's quadratic patch)
  delta       ϖ = x2 − δ with ‖δ‖ across n1 and √delta_reg (u_a's inner branch, ρ's switch),
              some δ components exactly 0 (sig(0)^γ: sg_powf_const's +0 edge)
  singular    errors within 1.5° of 180° and exactly 180°, and across q0 = q0_min
  off_so3     matrices off SO(3) (noise 1e-6 .. 1, arbitrary matrices, and R_e = I + a large skew
              part exactly: the 180° fallback with a zero diagonal excess, e = 0)
  extreme     rates and ϖ over 1e3 .. FLT_MAX (overflow paths, the ϖ clamp)
  special     ±0, subnormals, ±Inf, NaN, ±FLT_MAX in random input/state positions
Closed-loop sequences need a plant and come from the host (`ClosedLoop`, host.sim.scenarios);
without one, `open_sequences` strings gate rows together (the state still carried by the C).
"""
from __future__ import annotations

from typing import Protocol

import numpy as np
from scipy.spatial.transform import Rotation

from codegen.unit import Batch, class_sizes
from codegen.units.tanh import golden as gt
from codegen.units.tanh.emit import INPUT_DTYPE, STATE_DTYPE, Constants32

F32 = np.float32
CLASSES = ("random", "small", "delta", "singular", "off_so3", "extreme", "special")
SPECIAL = np.array([0.0, -0.0, 1e-45, -1e-45, 1.1754942e-38, -1.1754942e-38, 1.1754944e-38,
                    np.inf, -np.inf, np.nan, -np.nan, 3.4028235e38, -3.4028235e38], dtype=F32)


def random_rotations(n: int, rng) -> np.ndarray:
    return Rotation.random(n, random_state=rng).as_matrix()


def axis_angle_rotations(angles: np.ndarray, rng) -> np.ndarray:
    axis = rng.normal(size=(angles.size, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    return Rotation.from_rotvec(axis * angles[:, None]).as_matrix()


def _log_uniform(rng, lo: float, hi: float, shape) -> np.ndarray:
    return np.exp(rng.uniform(np.log(lo), np.log(hi), shape)) * rng.choice([-1.0, 1.0], shape)


def input_rows(R_c, w_c, R_t, w_t, wdot_t) -> np.ndarray:
    n = R_c.shape[0]
    with np.errstate(over="ignore"):
        return np.ascontiguousarray(np.concatenate(
            [R_c.reshape(n, 9), w_c, R_t.reshape(n, 9), w_t, wdot_t], axis=1).astype(F32))


def _motion(rng, n: int, scale: float = 1.0):
    return (_log_uniform(rng, 1e-6, 2.0 * scale, (n, 3)), _log_uniform(rng, 1e-6, 0.2 * scale, (n, 3)),
            _log_uniform(rng, 1e-7, 0.02 * scale, (n, 3)))


def _class_random(k, rng, n):
    w_c, w_t, wdot_t = _motion(rng, n)
    return _log_uniform(rng, 1e-4, 20.0, (n, 3)).astype(F32), input_rows(random_rotations(n, rng), w_c, random_rotations(n, rng), w_t, wdot_t)


def _class_small(k, rng, n):
    R_t = random_rotations(n, rng)
    R_c = R_t @ axis_angle_rotations(np.exp(rng.uniform(np.log(1e-7), np.log(3e-2), n)), rng)
    w_c, w_t, wdot_t = _motion(rng, n, 0.01)
    return _log_uniform(rng, 1e-6, 1.0, (n, 3)).astype(F32), input_rows(R_c, w_c, R_t, w_t, wdot_t)


def _class_delta(k, rng, n):
    """ϖ = x2 − δ: x2 from the golden step itself, ‖δ‖ log-uniform over [1e-6, 0.3]."""
    state, x = _class_random(k, rng, n)
    half = n // 2
    state[:half], x[:half] = _class_small(k, rng, half)
    out, _ = gt.step(k, np.zeros(n, STATE_DTYPE), x.view(INPUT_DTYPE).reshape(n))
    d = rng.normal(size=(n, 3))
    d *= (np.exp(rng.uniform(np.log(1e-6), np.log(0.3), n)) / np.linalg.norm(d, axis=1))[:, None]
    d[rng.random((n, 3)) < 0.1] = 0.0   # ϖ_i = x2_i exactly: δ_i = +0
    return (out["x2"].astype(np.float64) - d).astype(F32), x


def _class_singular(k, rng, n):
    R_t = random_rotations(n, rng)
    angle = np.pi - np.exp(rng.uniform(np.log(1e-7), np.log(np.radians(1.5)), n))
    q0_edge = 2.0 * np.arccos(float(k.q0min_sq) ** 0.5) + rng.uniform(-1e-5, 1e-5, n)
    angle = np.where(rng.random(n) < 0.3, q0_edge, angle)
    angle[: n // 10] = np.pi  # exactly 180°: R_e symmetric, q0 = 0
    R_c = R_t @ axis_angle_rotations(angle, rng)
    w_c, w_t, wdot_t = _motion(rng, n)
    return _log_uniform(rng, 1e-4, 20.0, (n, 3)).astype(F32), input_rows(R_c, w_c, R_t, w_t, wdot_t)


def _class_off_so3(k, rng, n):
    state, x = _class_random(k, rng, n)
    noise = _log_uniform(rng, 1e-6, 1.0, (n, 1)) * rng.normal(size=(n, 18))
    x[:, 0:9] += noise[:, :9].astype(F32)
    x[:, 12:21] += noise[:, 9:].astype(F32)
    x[: n // 4, 0:9] = rng.normal(size=(n // 4, 9)).astype(F32)
    # R_t = I, R_c = I + [a]x with |a| >= 4: R_e = R_c exactly, trace 3, |x1| >= 1, so the fallback
    # runs with diagonal excess (1 + 2 max R_e,ii) - trace = 0 and returns e = 0
    m = n // 8
    a = _log_uniform(rng, 4.0, 100.0, (m, 3))
    skew = np.zeros((m, 3, 3))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -a[:, 2], a[:, 1], -a[:, 0]
    skew -= skew.transpose(0, 2, 1)
    x[n - m:, 0:9] = (np.eye(3) + skew).reshape(m, 9).astype(F32)
    x[n - m:, 12:21] = np.eye(3).reshape(1, 9).astype(F32)
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


def gate_classes(k: Constants32, n: int, seed: int = 0) -> dict[str, Batch]:
    """n independent (state, input) rows in the seven classes (deterministic in seed)."""
    sizes = class_sizes(n, CLASSES, "tanh")
    rng = np.random.default_rng(seed)
    out = {}
    for name, m in zip(CLASSES, sizes):
        state, x = _MAKERS[name](k, rng, m)
        out[name] = Batch(np.ascontiguousarray(state).view(STATE_DTYPE).reshape(m),
                          np.ascontiguousarray(x).view(INPUT_DTYPE).reshape(m))
    return out


class ClosedLoop(Protocol):
    """Host-side source of closed-loop inputs: the golden step flying a plant."""

    def sequences(self, unit, n_seq: int, steps: int, seed: int) -> np.ndarray:
        """(n_seq, steps) INPUT_DTYPE records recorded while the unit's golden step flies a plant."""

    def cycle_classes(self, unit) -> dict[str, Batch]:
        """Extra cycle-report classes (e.g. the records of the paper-000 example run)."""


def open_sequences(k: Constants32, n_seq: int, steps: int, seed: int) -> np.ndarray:
    """(n_seq, steps) inputs without a plant: rows of the random and small classes in turn."""
    classes = gate_classes(k, max(2 * n_seq * steps, len(CLASSES)) * 4, seed)
    rows = np.concatenate([classes["random"].input, classes["small"].input])
    return np.ascontiguousarray(rows[:n_seq * steps].reshape(n_seq, steps))
