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

`DpModel.query_rows(Q)` answers R queries at once with what R calls of `query` give (bit-identical
where tried; the contract is 1e-12 relative), for the batched closed loop: per level and row a
superset of the box from prefix bitsets of the sorted columns (an AND of 12 XORs) bounds the hit
count, and only levels whose bound reaches n_min are tested exactly, with `select`'s own tests, on
the superset's members; the reservoir's slot pattern depends on the hit count alone (the xorshift
stream restarts at every query) and is cached per count; the IRLS runs stacked over the rows with
the same point count (the scalar's BLAS/LAPACK calls on the scalar's shapes). A non-finite row is
invalid there (zero torque) instead of raising.
"""
from __future__ import annotations

import functools
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


# ----------------------------------------------------------------------------- many rows at once
# The batched law for the closed-loop simulator: `select_rows` and `irls_intercepts_rows` give per
# row exactly what `select` and `irls_intercept` give, without a Python call per row.

@functools.lru_cache(maxsize=32)
def _xorshift_states(count: int) -> np.ndarray:
    """The first `count` xorshift32 states after XORSHIFT_SEED (uint64 for the multiply-shift);
    callers ask for powers of two so a handful of streams serve every hit count."""
    out = np.empty(count, dtype=np.uint64)
    state = XORSHIFT_SEED
    for i in range(count):
        state = xorshift32(state)
        out[i] = state
    out.setflags(write=False)
    return out


@functools.lru_cache(maxsize=4096)
def _reservoir_slots(n: int, s_limit: int) -> np.ndarray:
    """Which hit position ends in each slot of `reservoir` over n > s_limit hits: the PRNG restarts
    at every query, so the pattern depends on (n, s_limit) only; reservoir(ids, s) == ids[slots]."""
    draws = n - s_limit
    states = _xorshift_states(1 << max(draws - 1, 0).bit_length())[:draws]
    i = np.arange(s_limit, n, dtype=np.uint64)
    j = (states * (i + np.uint64(1))) >> np.uint64(32)
    take = j < s_limit
    slots = np.arange(s_limit, dtype=np.int64)
    # later hits have larger positions, so the maximum per slot is the last replacement
    np.maximum.at(slots, j[take].astype(np.int64), i[take].astype(np.int64))
    slots.setflags(write=False)
    return slots


# prefix bitsets take at most about this many bytes; more samples coarsen them (a looser superset)
_PREFIX_BYTES = 32 << 20


@dataclass(frozen=True)
class RowsIndex:
    """Per-table arrays the row search reads (built once per model). prefix[k, j] is the bitset
    (np.packbits over sample IDs) of the samples among the first j·block of X2[:, k]: the samples
    whose k-th input lies in a rank interval are one XOR of two rows, a box's superset an AND."""
    rank: np.ndarray     # (N, 12) position of sample i in X2[:, k]: rank[X3[j, k], k] == j
    prefix: np.ndarray   # (12, ceil(N / block) + 1, ceil(N / 8)) uint8
    block: int           # ranks per prefix step (1: exact rank intervals)

    @classmethod
    def build(cls, t: DpTables, block: int | None = None) -> "RowsIndex":
        """block None: 1 unless the bitsets would pass _PREFIX_BYTES (any block gives the same
        selection; a coarser one only tests more candidates)."""
        N = t.n
        rank = np.empty_like(t.X3)
        rank[t.X3, np.arange(N_IN)] = np.arange(N)[:, None]
        if block is None:
            block = max(1, -(-N_IN * N * ((N + 7) // 8) // _PREFIX_BYTES))
        steps = np.arange(-(-N // block) + 1) * block
        prefix = np.stack([np.packbits(rank[None, :, k] < steps[:, None], axis=1) for k in range(N_IN)])
        return cls(rank, prefix, block)


@dataclass(frozen=True)
class RowsNeighbourhood:
    ids: np.ndarray      # (R, s_limit) selected sample IDs in fit order, row r valid up to used[r], -1 after
    used: np.ndarray     # (R,) points entering the fit: min(found, s_limit)
    found: np.ndarray    # (R,) points in the used level's box
    level: np.ndarray    # (R,) index into sides(); len(sides()) = every sample


def _level_half_widths(t: DpTables, c: DpParams) -> np.ndarray:
    """(levels, 12) h of every boxed level, the same expression as `select` (bit-equal)."""
    return np.array([0.5 * side * t.span for side in c.sides()]).reshape(-1, N_IN)


def select_rows(t: DpTables, c: DpParams, Q: np.ndarray, index: RowsIndex | None = None) -> RowsNeighbourhood:
    """`select` for every row of Q ((R, 12), finite): the same level, box count and IDs in the same
    order. Per level and row a superset of the box (the samples inside every input's interval
    widened by far more than rounding, from the prefix bitsets) bounds the hit count from above;
    only levels whose bound reaches n_min are tested exactly, on the superset's members, with
    `select`'s own tests (the interval of k* from the bisections, |x − q| <= h on every input)."""
    index = index or RowsIndex.build(t)
    Q = np.asarray(Q, float).reshape(-1, N_IN)
    R, N, s = len(Q), t.n, c.s_limit
    H = _level_half_widths(t, c)
    L = len(H)
    lo_v, hi_v = Q[None] - H[:, None], Q[None] + H[:, None]    # (L, R, 12), `select`'s q ± h
    delta = 1e-9 * (np.abs(Q)[None] + H[:, None])               # >> the rounding of x − q and q ± h
    lo_w, hi_w = lo_v - delta, hi_v + delta
    counts = np.empty((L, R, N_IN), dtype=np.int64)
    box = None                                                  # (L, R, bytes): the superset bitsets
    for k in range(N_IN):
        col = t.X2[:, k]
        a_exact = np.searchsorted(col, lo_v[..., k], side="left")
        b_exact = np.searchsorted(col, hi_v[..., k], side="right")
        counts[..., k] = b_exact - a_exact
        a = _widened_bound(col, lo_w[..., k], a_exact, "left") // index.block
        b = -(-_widened_bound(col, hi_w[..., k], b_exact, "right") // index.block)
        bits = index.prefix[k, b] ^ index.prefix[k, a]
        box = bits if box is None else np.bitwise_and(box, bits, out=box)
    kstar = np.argmin(counts, axis=-1)                          # (L, R), first minimum as `select`
    # `select` tests a level only when every interval holds n_min; the superset must hold them too
    worth = (counts.min(axis=-1) >= c.n_min) & (np.bitwise_count(box).sum(axis=-1) >= c.n_min)

    ids = np.full((R, s), -1, dtype=np.int64)
    found = np.full(R, N, dtype=np.int64)
    level = np.full(R, L, dtype=np.int64)
    cur = _next_level(worth, np.arange(R), np.full(R, -1))
    while True:
        rows = np.flatnonzero(cur >= 0)
        if rows.size == 0:
            break
        lv = cur[rows]
        bits = np.unpackbits(box[lv, rows], axis=1)
        rep, cand = np.nonzero(bits)                            # per row its superset, IDs ascending
        row_q, lv_rep, k_rep = rows[rep], lv[rep], kstar[lv[rep], rows[rep]]
        x_k = t.X[cand, k_rep]
        hit = ((lo_v[lv_rep, row_q, k_rep] <= x_k) & (x_k <= hi_v[lv_rep, row_q, k_rep])
               & np.all(np.abs(t.X[cand] - Q[row_q]) <= H[lv_rep], axis=1))
        n_hits = np.bincount(rep, weights=hit, minlength=rows.size).astype(np.int64)
        ok = n_hits >= c.n_min
        keep = hit & ok[rep]
        rep, cand, k_rep = rep[keep], cand[keep], k_rep[keep]
        # `select` keeps the hits in its k*'s scan order: X2 order of that column
        order = np.lexsort((index.rank[cand, k_rep], rep))
        done = rows[ok]
        if done.size:
            kept = np.where(ok, n_hits, 0)                      # the failed rows' hits were dropped
            starts = (np.cumsum(kept) - kept)[ok]
            ids[done] = _reservoir_rows(cand[order], starts, n_hits[ok], s)
            found[done], level[done] = n_hits[ok], lv[ok]
        cur[done] = -1
        fail = rows[~ok]
        cur[fail] = _next_level(worth, fail, cur[fail])
    every = np.flatnonzero(level == L)
    if every.size:
        ids[every] = _reservoir_rows(np.arange(N, dtype=np.int64), np.zeros(1, np.int64), np.array([N]), s)[0]
    return RowsNeighbourhood(ids, np.minimum(found, s), found, level)


def _widened_bound(col: np.ndarray, v: np.ndarray, exact: np.ndarray, side: str) -> np.ndarray:
    """np.searchsorted(col, v, side) given the bound `exact` of a value just inside v: the same
    unless a sample lies in between, which is rare (the widening is ~1e-9 relative), so only those
    entries are searched again."""
    if side == "left":
        near = col[np.maximum(exact - 1, 0)]
        redo = (exact > 0) & (near >= v)
    else:
        near = col[np.minimum(exact, len(col) - 1)]
        redo = (exact < len(col)) & (near <= v)
    if not redo.any():
        return exact
    out = exact.copy()
    out[redo] = np.searchsorted(col, v[redo], side=side)
    return out


def _next_level(worth: np.ndarray, rows: np.ndarray, after: np.ndarray) -> np.ndarray:
    """Per row the first level above `after` worth testing exactly; -1 when none (every sample)."""
    L = worth.shape[0]
    ok = worth[:, rows] & (np.arange(L)[:, None] > after[None, :])
    return np.where(ok.any(axis=0), np.argmax(ok, axis=0), -1)


def _reservoir_rows(flat: np.ndarray, starts: np.ndarray, found: np.ndarray, s_limit: int) -> np.ndarray:
    """`reservoir` for many rows: row r's hits are flat[starts[r]:starts[r] + found[r]];
    (rows, s_limit) IDs padded with -1."""
    D = found.size
    slot = np.broadcast_to(np.arange(s_limit), (D, s_limit)).copy()
    big = found > s_limit
    if big.any():
        uniq, inverse = np.unique(found[big], return_inverse=True)
        slot[big] = np.stack([_reservoir_slots(int(n), s_limit) for n in uniq])[inverse]
    valid = slot < found[:, None]
    out = np.where(valid, flat[starts[:, None] + np.where(valid, slot, 0)], -1)
    return out


def _positive_definite_stack(A: np.ndarray) -> np.ndarray:
    """Per matrix of the stack: does np.linalg.cholesky accept it (`_solve_or_mean`'s test)? A
    stack raises when any matrix fails, so a failing stack is halved until the culprits are alone."""
    try:
        np.linalg.cholesky(A)
        return np.ones(len(A), dtype=bool)
    except np.linalg.LinAlgError:
        if len(A) == 1:
            return np.zeros(1, dtype=bool)
        half = len(A) // 2
        return np.concatenate([_positive_definite_stack(A[:half]), _positive_definite_stack(A[half:])])


def _solve_stack(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """np.linalg.solve per matrix of the stack (K, 13, 13), (K, 13); NaN where it raises."""
    try:
        return np.linalg.solve(A, b[..., None])[..., 0]
    except np.linalg.LinAlgError:
        if len(A) == 1:
            return np.full(b.shape, np.nan)
        half = len(A) // 2
        return np.concatenate([_solve_stack(A[:half], b[:half]), _solve_stack(A[half:], b[half:])])


def _solve_or_mean_stack(A: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`_solve_or_mean` on a stack (K, 13, 13), (K, 13): the same LAPACK calls per matrix (a
    stacked call runs each matrix as the single call does); (beta (K, 13), singular (K,))."""
    beta = np.full(b.shape, np.nan)
    if len(A):
        pd = _positive_definite_stack(A)
        if pd.any():
            beta[pd] = _solve_stack(A[pd], b[pd])
    singular = ~np.all(np.isfinite(beta), axis=1)
    beta[singular] = 0.0
    beta[singular, 0] = b[singular, 0] / A[singular, 0, 0]
    return beta, singular


class _FitGroup:
    """The fits of the rows with the same point count m, arrays shaped as the scalar's (the BLAS
    calls of the stacked matmul then equal the scalar's bit for bit; zero padding would change
    gemm's summation and the mean's pairwise sum)."""

    def __init__(self, rows: np.ndarray, Phi: np.ndarray, Y: np.ndarray):
        G, m = Phi.shape[:2]
        self.rows, self.Phi, self.Y = rows, Phi, Y              # (G,), (G, m, 13), (G, 3, m)
        self.PhiT = Phi.transpose(0, 2, 1)[:, None]             # (G, 1, 13, m): the scalar's Phi.T view
        self.beta = np.zeros((G, N_OUT, N_PARAM))
        self.active = np.ones((G, N_OUT), dtype=bool)           # False once the scalar left its loop
        self.w = np.ones((G, N_OUT, m))
        self.unit = True                                        # w is still the first fit's ones

    def reweight(self, c: DpParams) -> None:
        """The scalar's `it > 0` step; a zero (or NaN) scale ends the loop keeping beta."""
        e = self.Y - (self.Phi[:, None] @ self.beta[..., None])[..., 0]
        scale = MEAN_ABS_TO_SIGMA * np.mean(np.abs(e), axis=-1)
        self.active &= scale > 0.0
        u = e / (c.tukey_c * scale[..., None])
        self.w = np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)
        self.unit = False

    def system(self, c: DpParams) -> tuple[np.ndarray, np.ndarray]:
        """The active fits' normal equations: (K, 13, 13), (K, 13)."""
        w = self.w
        # the unit weights of the first fit give one matrix for the three outputs
        ww = w[:, :1] if self.unit else w
        # w·Phi is a new array as in the scalar (the same array twice would make numpy call syrk)
        A = self.PhiT @ (ww[..., None] * self.Phi[:, None])     # (G, 3 or 1, 13, 13)
        diag = np.arange(1, N_PARAM)
        A[..., diag, diag] += (c.ridge * np.sum(ww, axis=-1))[..., None]
        A = np.broadcast_to(A, w.shape[:2] + A.shape[2:])
        rhs = (self.PhiT @ (w * self.Y)[..., None])[..., 0]     # (G, 3, 13)
        return A[self.active], rhs[self.active]

    def update(self, beta: np.ndarray, singular: np.ndarray) -> None:
        self.beta[self.active] = beta
        self.active[self.active] = ~singular                    # the weighted mean ends the loop


def irls_intercepts_rows(t: DpTables, c: DpParams, Q: np.ndarray, nb: RowsNeighbourhood) -> np.ndarray:
    """Step 4 for every row and output: (R, 3) as `irls_intercept` on each row's neighbourhood. The
    rows are grouped by point count (the scalar's shapes); each iteration's systems of all groups
    are solved as one stack."""
    Q = np.asarray(Q, float).reshape(-1, N_IN)
    groups = []
    for m in np.unique(nb.used):
        rows = np.flatnonzero(nb.used == m)
        ids = nb.ids[rows, :m]
        Z = (t.X[ids] - Q[rows, None, :]) / t.span
        Phi = np.concatenate([np.ones(Z.shape[:2] + (1,)), Z], axis=2)
        groups.append(_FitGroup(rows, Phi, t.Y[ids].transpose(0, 2, 1)))
    for it in range(c.iterations + 1):
        live = [g for g in groups if g.active.any()]
        if not live:
            break
        systems = []
        for g in live:
            if it > 0:
                g.reweight(c)
            systems.append(g.system(c))
        beta, singular = _solve_or_mean_stack(np.concatenate([A for A, _ in systems]),
                                              np.concatenate([b for _, b in systems]))
        start = 0
        for g, (A, _) in zip(live, systems):
            g.update(beta[start:start + len(A)], singular[start:start + len(A)])
            start += len(A)
    out = np.empty((len(Q), N_OUT))
    for g in groups:
        out[g.rows] = g.beta[..., 0]
    return out


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
        self._rows_index: RowsIndex | None = None       # query_rows' search arrays, built on first use

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

    def query_rows(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(R, 12) queries -> (torque (R, 3), invalid (R,)): row r is `query(Q[r]).torque` (to 1e-12
        relative; bit-identical where tried) with invalid[r] when that torque is not all finite.
        A non-finite row (which `query` refuses) is invalid too; invalid rows get zero torque and
        leave the other rows untouched. Floating-point warnings are silenced: invalid reports them."""
        Q = np.asarray(Q, float).reshape(-1, N_IN)
        torque = np.zeros((len(Q), N_OUT))
        finite = np.all(np.isfinite(Q), axis=1)
        if finite.any():
            t, c = self.tables, self.config
            if self._rows_index is None:
                self._rows_index = RowsIndex.build(t)
            with np.errstate(all="ignore"):
                nb = select_rows(t, c, Q[finite], self._rows_index)
                torque[finite] = irls_intercepts_rows(t, c, Q[finite], nb)
        invalid = ~finite | ~np.all(np.isfinite(torque), axis=1)
        torque[invalid] = 0.0
        return torque, invalid

    def predict(self, Q: np.ndarray) -> np.ndarray:
        """(M, 12) queries -> (M, 3) torques."""
        return np.array([self.query(q).torque for q in np.asarray(Q, float)])
