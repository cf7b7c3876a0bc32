"""The discrete-point unit's gate classes: the network unit's four (inside / on the edges of / outside
the samples' range, special values) plus three of its own:
  samples   inputs exactly on anchor samples, and one ulp beside them;
  window    one input placed so that a box edge (q_k ± h_lk, in float32) lands exactly on a sample's
            value, at the level the row uses and at level 0: the closed-interval comparisons decide;
  empty     inputs whose every box is empty (one input beyond the range by more than the widest
            box's half-width): the every-sample level.
"""
from __future__ import annotations

import numpy as np

from codegen.artifact import Envelope, TABLE2_DESCRIPTIONS, TABLE2_NAMES, TABLE2_UNITS
from codegen.units.dp.tables import DpTables
from codegen.units.network import vectors as nv

CLASSES = (*nv.KINDS, "samples", "window", "empty")
F32 = np.float32


def sample_envelope(t: DpTables) -> Envelope:
    return Envelope(TABLE2_NAMES, TABLE2_UNITS, TABLE2_DESCRIPTIONS, t.X.min(axis=0), t.X.max(axis=0),
                    "range of the anchor samples")


def _sample_rows(t: DpTables, rng: np.random.Generator, n: int) -> np.ndarray:
    x = t.X[rng.integers(0, t.n, n)].copy()
    nudge = rng.random(n) < 0.5
    pos = rng.integers(0, 12, n)
    up = rng.random(n) < 0.5
    rows = np.flatnonzero(nudge)
    x[rows, pos[rows]] = np.nextafter(x[rows, pos[rows]], np.where(up[rows], F32(np.inf), F32(-np.inf)))
    return x


def _window_rows(t: DpTables, rng: np.random.Generator, n: int) -> np.ndarray:
    """Rows near a sample with one coordinate set so that q_k + h or q_k − h equals x_jk exactly
    (a few draws until float32 rounding allows an exact edge)."""
    x = _sample_rows(t, rng, n)
    for i in range(n):
        for _ in range(16):
            j, k = rng.integers(0, t.n), rng.integers(0, 12)
            lv = 0 if rng.random() < 0.3 else rng.integers(0, t.n_levels)
            q = _edge_input(t.half_widths[lv, k], t.X[j, k], rng.random() < 0.5)
            if q is not None:
                x[i, k] = q
                break
    return x


def _edge_input(h: np.float32, target: np.float32, upper: bool):
    """A float32 q with fl(q + h) == target (upper edge) or fl(q − h) == target, or None."""
    q = F32(target - h) if upper else F32(target + h)
    for _ in range(64):
        edge = F32(q + h) if upper else F32(q - h)
        if edge == target:
            return q
        q = np.nextafter(q, F32(np.inf) if edge < target else F32(-np.inf))
    return None


def _empty_rows(t: DpTables, rng: np.random.Generator, n: int) -> np.ndarray:
    x = _sample_rows(t, rng, n)
    k = rng.integers(0, 12, n)
    widest = t.half_widths[-1].astype(np.float64)
    lo, hi = t.X.min(axis=0).astype(np.float64), t.X.max(axis=0).astype(np.float64)
    gap = widest[k] * rng.uniform(1.01, 3.0, n)
    above = rng.random(n) < 0.5
    x[np.arange(n), k] = np.where(above, hi[k] + gap, lo[k] - gap).astype(np.float32)
    return x


def gate_inputs(t: DpTables, n: int, seed: int) -> dict[str, np.ndarray]:
    """n rows split over the classes (float32 (rows, 12) each), deterministic in seed."""
    rng = np.random.default_rng(seed)
    own = max(1, n // 10)
    vs = nv.gate_vectors(sample_envelope(t), max(len(nv.KINDS), n - 3 * own), seed)
    out = {name: np.ascontiguousarray(vs.x[vs.kind == k]) for k, name in enumerate(nv.KINDS)}
    out["samples"] = _sample_rows(t, rng, own)
    out["window"] = _window_rows(t, rng, own)
    out["empty"] = _empty_rows(t, rng, own)
    return out
