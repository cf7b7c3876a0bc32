"""The discrete-point controller of seed paper 003 in float64: the optimal-control samples kept as
anchor points, the points inside a box around the current input selected, the torque fitted to them
by iteratively reweighted least squares (IRLS). docs/discrete-point.md states every choice the paper
leaves open and why; the generated C (codegen/units/dp) runs the same algorithm in float32.

Offline (once, `DpTables.build`): per input dimension k the sorted sample values X2[:, k], the sample
IDs in that order X3[:, k] (a stable argsort) and the range R_k = max − min (paper 003 §3).

Per query q (12 inputs in Table 2 units, `DpModel.query`):
  1. levels l = 0, 1, ...: box half-widths h_k = (r·widen^l / 2)·R_k (side r·widen^l of the range,
     while below 2 ranges); the last level takes every sample;
  2. per level, bisection of each X2 column for [q_k − h_k, q_k + h_k] (closed), the dimension with
     the fewest candidates k* (lowest k on ties) scanned in X2 order, each candidate kept when all
     12 coordinates lie in the box; the first level with at least n_min points is used;
  3. more than s_limit points: reservoir sampling (Algorithm R) driven by xorshift32 from a fixed
     seed at every query, so the output is a function of the input alone;
  4. per output column: affine fit in centred, range-scaled coordinates z = (x − q)/R, weighted
     normal equations with a small ridge on the slopes, solved by LDLᵀ; IRLS with Tukey's bisquare
     (c = 4.685) on a scale of 1.2533·mean|residual| for a fixed number of iterations; the torque
     is the intercept (the fit's value at q).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from codegen.units.dp.golden import XORSHIFT_SEED
from codegen.units.dp.params import N_IN, N_OUT, N_PARAM, DpParams
from codegen.units.dp.tables import MEAN_ABS_TO_SIGMA
from host.errors import HostError



@dataclass(frozen=True)
class DpTables:
    """The offline tables of paper 003 §3 (float64 here; the unit stores them as float32)."""
    X: np.ndarray        # (N, 12) sample inputs, Table 2 units, in sample-ID order
    Y: np.ndarray        # (N, 3) optimal first commands, N·m
    X2: np.ndarray       # (N, 12) each column sorted ascending
    X3: np.ndarray       # (N, 12) sample IDs in that order: X[X3[j, k], k] == X2[j, k]
    lo: np.ndarray       # (12,) per-dimension minimum
    span: np.ndarray     # (12,) per-dimension range R_k > 0

    @classmethod
    def build(cls, X: np.ndarray, Y: np.ndarray, n_min: int = N_PARAM) -> "DpTables":
        X, Y = np.asarray(X, float), np.asarray(Y, float)
        if X.ndim != 2 or X.shape[1] != N_IN or Y.shape != (len(X), N_OUT):
            raise HostError(f"discrete-point samples must be (N, {N_IN}) inputs and (N, {N_OUT}) outputs, got "
                            f"{X.shape} and {Y.shape}")
        if len(X) < n_min:
            raise HostError(f"discrete-point controller needs at least n_min = {n_min} samples, got {len(X)}")
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(Y))):
            raise HostError("discrete-point samples must be finite")
        X3 = np.argsort(X, axis=0, kind="stable")
        X2 = np.take_along_axis(X, X3, axis=0)
        lo, span = X2[0].copy(), X2[-1] - X2[0]
        if np.any(span <= 0):
            raise HostError(f"discrete-point samples have a constant input dimension "
                            f"{int(np.argmin(span))} (its range must be > 0)")
        return cls(X, Y, X2, X3.astype(np.int64), lo, span)

    @property
    def n(self) -> int:
        return len(self.X)


def xorshift32(state: int) -> int:
    """Marsaglia's xorshift32 (13, 17, 5): the PRNG the C reproduces with uint32_t arithmetic."""
    state ^= (state << 13) & 0xFFFFFFFF
    state ^= state >> 17
    state ^= (state << 5) & 0xFFFFFFFF
    return state


def reservoir(ids: np.ndarray, s_limit: int) -> np.ndarray:
    """Algorithm R over `ids` in their order: slot j of the first s_limit; hit i >= s_limit draws
    u = xorshift32, j = (u·(i+1)) >> 32 (multiply-shift, no modulo bias beyond 2^-32) and replaces
    slot j when j < s_limit."""
    out = np.array(ids[:s_limit], copy=True)
    state = XORSHIFT_SEED
    for i in range(s_limit, len(ids)):
        state = xorshift32(state)
        j = (state * (i + 1)) >> 32
        if j < s_limit:
            out[j] = ids[i]
    return out


@dataclass(frozen=True)
class Neighbourhood:
    ids: np.ndarray      # selected sample IDs, in fit order
    found: int           # points in the used level's box (before the S_limit cap)
    level: int           # index into sides(); len(sides()) = every sample


def select(t: DpTables, c: DpParams, q: np.ndarray) -> Neighbourhood:
    """Steps 1-3: the first level whose box holds at least n_min points, capped at s_limit."""
    sides = c.sides()
    for level, side in enumerate(sides):
        h = 0.5 * side * t.span
        lo_idx = np.array([np.searchsorted(t.X2[:, k], q[k] - h[k], side="left") for k in range(N_IN)])
        hi_idx = np.array([np.searchsorted(t.X2[:, k], q[k] + h[k], side="right") for k in range(N_IN)])
        counts = hi_idx - lo_idx
        if counts.min() < c.n_min:       # the intersection cannot hold more than the smallest set
            continue
        k = int(np.argmin(counts))
        cand = t.X3[lo_idx[k]:hi_idx[k], k]
        inside = np.all(np.abs(t.X[cand] - q) <= h, axis=1)
        hits = cand[inside]
        if len(hits) >= c.n_min:
            return Neighbourhood(reservoir(hits, c.s_limit), len(hits), level)
    every = np.arange(t.n)
    return Neighbourhood(reservoir(every, c.s_limit), t.n, len(sides))


def _solve_or_mean(A: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, bool]:
    """The system's solution, or (as the C's LDLᵀ on a pivot that is not positive) the weighted
    mean b0 / A00 with zero slopes and singular = True."""
    try:
        np.linalg.cholesky(A)
        beta = np.linalg.solve(A, b)
        if np.all(np.isfinite(beta)):
            return beta, False
    except np.linalg.LinAlgError:
        pass
    beta = np.zeros(N_PARAM)
    with np.errstate(all="ignore"):
        beta[0] = b[0] / A[0, 0]
    return beta, True


def irls_intercept(Z: np.ndarray, y: np.ndarray, c: DpParams) -> float:
    """Step 4 for one output: the affine IRLS fit's value at the query (Z: (m, 12) scaled offsets);
    NaN when even the weighted mean is undefined (the caller's invalid case)."""
    Phi = np.hstack([np.ones((len(Z), 1)), Z])
    w = np.ones(len(Z))
    beta = np.zeros(N_PARAM)
    for it in range(c.iterations + 1):
        if it > 0:
            e = y - Phi @ beta
            scale = MEAN_ABS_TO_SIGMA * float(np.mean(np.abs(e)))
            if not scale > 0.0:
                break                    # an exact fit: nothing to reweight
            u = e / (c.tukey_c * scale)
            w = np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)
        A = Phi.T @ (w[:, None] * Phi)
        A[1:, 1:] += np.eye(N_IN) * (c.ridge * float(np.sum(w)))
        beta, singular = _solve_or_mean(A, Phi.T @ (w * y))
        if singular:
            break
    return float(beta[0])


@dataclass(frozen=True)
class DpResult:
    torque: np.ndarray   # (3,) N·m
    found: int
    used: int
    level: int


class DpModel:
    """Tables + configuration: the float64 discrete-point law."""

    def __init__(self, tables: DpTables, config: DpParams = DpParams()):
        self.tables, self.config = tables, config.validate()
        if tables.n < self.config.n_min:
            raise HostError(f"discrete-point controller needs at least n_min = {self.config.n_min} samples, "
                            f"got {tables.n}")

    @classmethod
    def fit(cls, X: np.ndarray, Y: np.ndarray, config: DpParams = DpParams()) -> "DpModel":
        config = config.validate()
        return cls(DpTables.build(X, Y, config.n_min), config)

    def query(self, q: np.ndarray) -> DpResult:
        q = np.asarray(q, float).reshape(N_IN)
        if not np.all(np.isfinite(q)):
            raise HostError("discrete-point query must be finite")
        t, c = self.tables, self.config
        nb = select(t, c, q)
        Z = (t.X[nb.ids] - q) / t.span
        torque = np.array([irls_intercept(Z, t.Y[nb.ids, i], c) for i in range(N_OUT)])
        return DpResult(torque, nb.found, len(nb.ids), nb.level)

    def predict(self, Q: np.ndarray) -> np.ndarray:
        """(M, 12) queries -> (M, 3) torques."""
        return np.array([self.query(q).torque for q in np.asarray(Q, float)])
