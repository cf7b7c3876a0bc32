"""The bit-exact gate's input vectors: seeded, covering the envelope, its edges, outside, special values.

Classes (VectorSet.kind):
  inside   uniform inside the envelope [min, max] (float32 bounds, inclusive)
  bound    one input exactly on a bound, or one ulp inside/outside it; the others inside;
           plus corner rows with every input on a bound
  outside  some inputs outside the envelope, from one ulp-ish to 1e3 spans away; plus a 10x box
  special  one input (or all) set to ±0, ±subnormals, ±smallest normal, ±Inf, ±NaN, ±FLT_MAX
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from codegen.artifact import Envelope

KINDS = ("inside", "bound", "outside", "special")
INSIDE, BOUND, OUTSIDE, SPECIAL = range(len(KINDS))

F32 = np.finfo(np.float32)
SPECIAL_VALUES = np.array([
    0.0, -0.0,
    F32.smallest_subnormal, -F32.smallest_subnormal,
    F32.smallest_normal - F32.smallest_subnormal, -(F32.smallest_normal - F32.smallest_subnormal),
    F32.smallest_normal, -F32.smallest_normal,
    np.inf, -np.inf, np.nan, -np.nan,
    F32.max, -F32.max,
], dtype=np.float32)

# Shares of N per class; `inside` takes the remainder.
SHARE_BOUND = 0.15
SHARE_OUTSIDE = 0.15
SHARE_SPECIAL = 0.05


@dataclass(frozen=True)
class VectorSet:
    x: np.ndarray      # (N, n_in) float32
    kind: np.ndarray   # (N,) uint8, index into KINDS

    def counts(self) -> dict[str, int]:
        return {name: int((self.kind == k).sum()) for k, name in enumerate(KINDS)}


def inside_mask(env: Envelope, x: np.ndarray) -> np.ndarray:
    """Rows whose every input is finite and within [min, max]."""
    with np.errstate(invalid="ignore"):
        return np.all(np.isfinite(x) & (x >= env.min) & (x <= env.max), axis=1)


def _uniform_inside(env: Envelope, rng: np.random.Generator, n: int) -> np.ndarray:
    lo, hi = env.min.astype(np.float64), env.max.astype(np.float64)
    x = (lo + rng.random((n, lo.size)) * (hi - lo)).astype(np.float32)
    return np.clip(x, env.min, env.max)  # float32 rounding may step past a bound


def _edge_values(env: Envelope) -> np.ndarray:
    """(6, n_in): each bound, and one ulp inside and outside it."""
    up, down = np.float32(np.inf), np.float32(-np.inf)
    return np.stack([
        env.min, np.nextafter(env.min, up), np.nextafter(env.min, down),
        env.max, np.nextafter(env.max, down), np.nextafter(env.max, up),
    ])


def _bound_rows(env: Envelope, rng: np.random.Generator, n: int) -> np.ndarray:
    n_in = env.min.size
    x = _uniform_inside(env, rng, n)
    edges = _edge_values(env)
    n_corner = n // 10
    pos = rng.integers(0, n_in, n - n_corner)
    which = rng.integers(0, edges.shape[0], n - n_corner)
    x[np.arange(n - n_corner), pos] = edges[which, pos]
    # Corner rows: every input exactly on one of its bounds.
    corner = np.where(rng.random((n_corner, n_in)) < 0.5, env.min, env.max)
    x[n - n_corner:] = corner
    return x


def _outside_rows(env: Envelope, rng: np.random.Generator, n: int) -> np.ndarray:
    n_in = env.min.size
    lo, hi = env.min.astype(np.float64), env.max.astype(np.float64)
    span = hi - lo
    x = _uniform_inside(env, rng, n).astype(np.float64)
    n_box = n // 4
    # A tenfold box around the envelope (mostly outside in some input).
    centre = (lo + hi) / 2
    x[:n_box] = centre + (rng.random((n_box, n_in)) - 0.5) * 10 * span
    # The rest: 1..n_in inputs pushed past a bound by 1e-6 .. 1e3 spans.
    rest = n - n_box
    pushed = rng.random((rest, n_in)) < rng.uniform(0.05, 1.0, (rest, 1))
    pushed[np.arange(rest), rng.integers(0, n_in, rest)] = True
    distance = span * 10.0 ** rng.uniform(-6, 3, (rest, n_in))
    above = rng.random((rest, n_in)) < 0.5
    beyond = np.where(above, hi + distance, lo - distance)
    x[n_box:] = np.where(pushed, beyond, x[n_box:])
    with np.errstate(over="ignore"):
        x32 = x.astype(np.float32)
    return _force_outside(env, rng, x32)


def _force_outside(env: Envelope, rng: np.random.Generator, x: np.ndarray) -> np.ndarray:
    """Rows still inside (float32 rounding back onto a bound, or a box draw) get one input one ulp out."""
    rows = np.flatnonzero(inside_mask(env, x))
    pos = rng.integers(0, env.min.size, rows.size)
    above = rng.random(rows.size) < 0.5
    x[rows, pos] = np.where(above, np.nextafter(env.max[pos], np.float32(np.inf)),
                            np.nextafter(env.min[pos], np.float32(-np.inf)))
    return x


def _special_rows(env: Envelope, rng: np.random.Generator, n: int) -> np.ndarray:
    """Every special value in every input position, repeated with fresh inside values; some all-special rows."""
    n_in = env.min.size
    x = _uniform_inside(env, rng, n)
    values = SPECIAL_VALUES
    n_all = n // 10
    k = np.arange(n - n_all)
    pos = k % n_in
    which = (k // n_in) % values.size
    x[k, pos] = values[which]
    x[n - n_all:] = values[rng.integers(0, values.size, (n_all, n_in))]
    return x


def gate_vectors(env: Envelope, n: int, seed: int = 0) -> VectorSet:
    """n vectors (deterministic in seed) for the golden-vs-C gate, in class order."""
    if n < 1:
        raise ValueError(f"need at least one vector, got {n}")
    rng = np.random.default_rng(seed)
    counts = [0, int(n * SHARE_BOUND), int(n * SHARE_OUTSIDE), int(n * SHARE_SPECIAL)]
    counts[INSIDE] = n - sum(counts)
    makers = (_uniform_inside, _bound_rows, _outside_rows, _special_rows)
    blocks = [make(env, rng, c) for make, c in zip(makers, counts)]
    kind = np.repeat(np.arange(len(KINDS), dtype=np.uint8), counts)
    x = np.ascontiguousarray(np.concatenate(blocks).astype(np.float32, copy=False))
    return VectorSet(x=x, kind=kind)


def class_vectors(env: Envelope, per_class: int, seed: int) -> dict[str, np.ndarray]:
    """per_class rows of each gate class, float32 (per_class, n_in) each (the cycle report's classes)."""
    share = min(SHARE_BOUND, SHARE_OUTSIDE, SHARE_SPECIAL)
    vs = gate_vectors(env, int(np.ceil(per_class / share)) + 1, seed)
    out = {}
    for k, name in enumerate(KINDS):
        rows = vs.x[vs.kind == k][:per_class]
        if rows.shape[0] < per_class:
            raise ValueError(f"only {rows.shape[0]} vectors of class {name}")
        out[name] = np.ascontiguousarray(rows)
    return out
