"""Gate vectors of the gp unit: independent input rows in named classes (the unit is stateless).

  inside     q_v and omega uniform in the GP's training envelope (the artifact's input range), |q|
             within 5 % of 1, either quaternion sign, wheel momentum up to 60 N*m*s
  inducing   exactly at the inducing points and 1e-6 away (the Nystrom residual's cancellation)
  edges      each coordinate at the envelope's minimum or maximum
  far        rotations of 60-180 deg and rates up to the box limit: far outside the data (prior variance)
  box        the valid box's limits exactly and one float32 step beyond (|q_i|, |q|^2, omega, h_w)
  special    NaN, +-Inf, -0, subnormals, +-FLT_MAX at random positions of inside rows
"""
from __future__ import annotations

import numpy as np

from codegen.unit import Batch, class_sizes
from codegen.units.gp import records as rec
from codegen.units.gp.params import GpLawParams

F32 = np.float32
CLASSES = ("inside", "inducing", "edges", "far", "box", "special")
N_FIELDS = 10          # q (4), omega (3), h_w (3)


def _quaternion(q_v: np.ndarray, rng: np.random.Generator, norm_spread: float) -> np.ndarray:
    """[q_v, q4] with q4 = sqrt(1 - |q_v|^2), the sign of the whole quaternion random, the norm scaled by
    1 +- norm_spread."""
    qv = np.asarray(q_v, dtype=np.float64)
    n2 = (qv * qv).sum(axis=1)
    big = n2 > 1.0
    qv[big] /= np.sqrt(n2[big])[:, None]
    q = np.concatenate([qv, np.sqrt(np.maximum(1.0 - (qv * qv).sum(axis=1), 0.0))[:, None]], axis=1)
    q *= rng.choice([-1.0, 1.0], size=(len(q), 1)) * rng.uniform(1 - norm_spread, 1 + norm_spread, (len(q), 1))
    return q


def _rows(q, omega, h_w) -> np.ndarray:
    x = np.concatenate([q, omega, h_w], axis=1)
    with np.errstate(over="ignore"):
        return np.ascontiguousarray(x.astype(F32)).view(rec.INPUT_DTYPE).reshape(len(x))


def _class_inside(p: GpLawParams, rng, n):
    lo, hi = p.gp.envelope_min, p.gp.envelope_max
    x = rng.uniform(lo[:6], hi[:6], (n, 6))
    return _rows(_quaternion(x[:, :3], rng, 0.05), x[:, 3:], rng.uniform(-60.0, 60.0, (n, 3)))


def _class_inducing(p: GpLawParams, rng, n):
    a = p.gp.arrays
    raw = a.Z[:, :6] * a.input_scale[:6]
    x = raw[rng.integers(0, len(raw), n)]
    x = x * (1.0 + rng.choice([0.0, 0.0, 1e-6, -1e-6], size=x.shape))
    return _rows(_quaternion(x[:, :3], rng, 0.0), x[:, 3:], rng.uniform(-60.0, 60.0, (n, 3)))


def _class_edges(p: GpLawParams, rng, n):
    lo, hi = p.gp.envelope_min[:6], p.gp.envelope_max[:6]
    x = np.where(rng.random((n, 6)) < 0.5, lo, hi)
    inner = rng.random((n, 6)) < 0.3      # some coordinates inside, the rest on the envelope
    x = np.where(inner, rng.uniform(lo, hi, (n, 6)), x)
    return _rows(_quaternion(x[:, :3], rng, 0.02), x[:, 3:], rng.uniform(-100.0, 100.0, (n, 3)))


def _class_far(p: GpLawParams, rng, n):
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = rng.uniform(np.radians(60.0), np.pi, n)
    q_v = axis * np.sin(angle / 2)[:, None]
    omega = rng.uniform(-rec.RATE_MAX, rec.RATE_MAX, (n, 3))
    return _rows(_quaternion(q_v, rng, 0.08), omega, rng.uniform(-rec.MOMENTUM_MAX, rec.MOMENTUM_MAX, (n, 3)))


def _class_box(p: GpLawParams, rng, n):
    rows = _class_inside(p, rng, n).view(F32).reshape(n, N_FIELDS).copy()
    limits = np.array([rec.Q_MAX] * 4 + [rec.RATE_MAX] * 3 + [rec.MOMENTUM_MAX] * 3, dtype=F32)
    col = rng.integers(4, N_FIELDS, n)              # omega and h_w at or just beyond their limits
    beyond = rng.random(n) < 0.5
    v = np.where(beyond, np.nextafter(limits[col], F32(np.inf)), limits[col]).astype(F32)
    rows[np.arange(n), col] = v * rng.choice([-1.0, 1.0], n).astype(F32)
    # a quarter: the quaternion's norm at the box's ends (|q|^2 = 0.81, 1.21 and one step across)
    qrows = rng.random(n) < 0.25
    target = rng.choice([rec.NORM2_MIN, rec.NORM2_MAX], n) * (1.0 + rng.choice([-1e-7, 0.0, 1e-7], n))
    q = rows[:, :4].astype(np.float64)
    q *= np.sqrt(target / (q * q).sum(axis=1))[:, None]
    rows[qrows, :4] = q[qrows].astype(F32)
    # a few: a component of q at +-1.1 exactly (inside the box, |q|^2 then decides) or one step beyond
    qbig = rng.random(n) < 0.1
    edge = np.where(rng.random(n) < 0.5, F32(rec.Q_MAX), np.nextafter(F32(rec.Q_MAX), F32(np.inf)))
    col_q = rng.integers(0, 4, n)
    rows[qbig, col_q[qbig]] = (edge * rng.choice([-1.0, 1.0], n).astype(F32))[qbig]
    return np.ascontiguousarray(rows).view(rec.INPUT_DTYPE).reshape(n)


def _class_special(p: GpLawParams, rng, n):
    rows = _class_inside(p, rng, n).view(F32).reshape(n, N_FIELDS).copy()
    specials = np.array([np.nan, np.inf, -np.inf, -0.0, 1e-40, -1e-40, np.finfo(F32).max, -np.finfo(F32).max,
                         0.0, np.finfo(F32).tiny], dtype=F32)
    # NaNs of both signs and with payloads (quiet and signalling patterns)
    specials = np.concatenate([specials, np.array([0xFFC00000, 0x7FC00001, 0x7F800001, 0xFFBFFFFF],
                                                  dtype=np.uint32).view(F32)])
    for _ in range(2):
        col = rng.integers(0, N_FIELDS, n)
        rows[np.arange(n), col] = specials[rng.integers(0, len(specials), n)]
    return np.ascontiguousarray(rows).view(rec.INPUT_DTYPE).reshape(n)


_MAKERS = {"inside": _class_inside, "inducing": _class_inducing, "edges": _class_edges, "far": _class_far,
           "box": _class_box, "special": _class_special}


def gate_classes(p: GpLawParams, n: int, seed: int = 0) -> dict[str, Batch]:
    """n independent input rows in the six classes (deterministic in seed)."""
    sizes = class_sizes(n, CLASSES, "gp")
    rng = np.random.default_rng(seed)
    return {name: Batch(None, _MAKERS[name](p, rng, m)) for name, m in zip(CLASSES, sizes)}
