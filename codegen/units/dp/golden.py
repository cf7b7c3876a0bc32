"""Golden model of the generated discrete-point step (templates/dp.c.j2): the same IEEE float32
operations in the same order, vectorised over records (SPEC 6).

How the order is kept while vectorising:
* selection (bisection, box test, reservoir) is exact integer / comparison work: numpy's
  `searchsorted` on the float32 column is the C's lower / upper bound, the box test the same
  comparisons, and the reservoir replays the C's xorshift32 stream from one precomputed table;
* every sum over the selected points is the C's sequential `acc = acc + t` from 0.0f:
  `np.add.accumulate` over a zero-prefixed axis (a strictly sequential float32 running sum),
  read at index m (the rows' point count), so padding beyond m never enters;
* the 13 x 13 LDL^T solve loops over the indices as the C does, on (rows,) vectors.
"""
from __future__ import annotations

import numpy as np

from codegen.units.dp.params import N_IN, N_OUT, N_PARAM
from codegen.units.dp.tables import MEAN_ABS_TO_SIGMA, DpTables

F32 = np.float32
XORSHIFT_SEED = 0x9E3779B9          # any non-zero 32-bit state; reset at every step (a pure function)
STATUS_WIDENED = 1                  # a box wider than level 0 was needed
STATUS_EVERY_SAMPLE = 2             # no box held n_min points: every sample was the neighbourhood
STATUS_SINGULAR = 4                 # a fit's system was not positive definite: weighted mean used
STATUS_INVALID = 8                  # non-finite input or result: zero torque, caller falls back

OUTPUT_DTYPE = np.dtype([("torque", "<f4", (N_OUT,)), ("found", "<u4"), ("used", "<u4"),
                         ("level", "<u4"), ("status", "<u4")])
INPUT_DTYPE = np.dtype([("x", "<f4", (N_IN,))])


def xorshift_stream(n: int, seed: int = XORSHIFT_SEED) -> np.ndarray:
    """The first n states after `seed` of xorshift32 (13, 17, 5), uint64 for the multiply-shift."""
    out = np.empty(n, dtype=np.uint64)
    s = seed
    for i in range(n):
        s ^= (s << 13) & 0xFFFFFFFF
        s ^= s >> 17
        s ^= (s << 5) & 0xFFFFFFFF
        out[i] = s
    return out


class Constants:
    """The tables as the C holds them, plus the replayed PRNG stream (built once per unit)."""

    def __init__(self, t: DpTables):
        p = t.params
        self.t, self.n, self.s, self.n_min, self.iterations = t, t.n, p.s_limit, p.n_min, p.iterations
        self.X, self.Y, self.order = t.X, t.Y, t.order.astype(np.int64)
        self.sorted_cols = [t.X[self.order[k], k] for k in range(N_IN)]     # X[X3[j][k]][k] as the C reads it
        self.half, self.inv_span = t.half_widths, t.inv_span
        self.c_scale = F32(p.tukey_c * MEAN_ABS_TO_SIGMA)
        self.ridge = F32(p.ridge)
        self.stream = xorshift_stream(max(t.n - p.s_limit, 0))


# ----------------------------------------------------------------------------- selection

def reservoir(c: Constants, hits: np.ndarray) -> np.ndarray:
    """Algorithm R as the C runs it over `hits` in order: hit f >= S draws u (the next xorshift32
    state) and j = (u·(f+1)) >> 32; j < S replaces slot j (the last replacement wins)."""
    s, f = c.s, len(hits)
    if f <= s:
        return hits.copy()
    idx = np.arange(s, f, dtype=np.uint64)
    j = (c.stream[:f - s] * (idx + np.uint64(1))) >> np.uint64(32)
    take = j < s
    last = np.full(s, -1, dtype=np.int64)
    np.maximum.at(last, j[take].astype(np.int64), idx[take].astype(np.int64))
    out = hits[:s].copy()
    replaced = last >= 0
    out[replaced] = hits[last[replaced]]
    return out


def select_rows(c: Constants, Q: np.ndarray):
    """Per row: selected IDs (padded with 0 to S), points found, points used, level."""
    R, L = Q.shape[0], c.half.shape[0]
    sel = np.zeros((R, c.s), dtype=np.int64)
    found = np.zeros(R, dtype=np.int64)
    level = np.full(R, L, dtype=np.int64)
    pending = np.ones(R, dtype=bool)
    for lv in range(L):
        rows = np.flatnonzero(pending)
        if rows.size == 0:
            break
        lo = Q[rows] - c.half[lv]                   # float32, as the C's lo[k] = q[k] - half[l][k]
        hi = Q[rows] + c.half[lv]
        a = np.stack([np.searchsorted(c.sorted_cols[k], lo[:, k], side="left") for k in range(N_IN)], axis=1)
        b = np.stack([np.searchsorted(c.sorted_cols[k], hi[:, k], side="right") for k in range(N_IN)], axis=1)
        counts = b - a
        kbest = np.argmin(counts, axis=1)           # first minimum: the C's strict `<`
        best = counts[np.arange(rows.size), kbest]
        for i in np.flatnonzero(best >= c.n_min):
            r, k = rows[i], kbest[i]
            cand = c.order[k, a[i, k]:b[i, k]]
            xc = c.X[cand]
            inside = np.all((xc >= lo[i]) & (xc <= hi[i]), axis=1)
            hits = cand[inside]
            if hits.size >= c.n_min:
                chosen = reservoir(c, hits)
                sel[r, :chosen.size] = chosen
                found[r], level[r], pending[r] = hits.size, lv, False
    every = reservoir(c, np.arange(c.n, dtype=np.int64))
    for r in np.flatnonzero(pending):
        sel[r, :every.size] = every
        found[r] = c.n
    used = np.minimum(found, c.s)
    return sel, found, used, level


# ----------------------------------------------------------------------------- the fit

def _running_sum_at(terms: np.ndarray, m: np.ndarray) -> np.ndarray:
    """The C's `acc = 0.0f; for p < m: acc = acc + terms[p]` for every row (axis 1 is p)."""
    shape = list(terms.shape)
    shape[1] = 1
    acc = np.add.accumulate(np.concatenate([np.zeros(shape, F32), terms], axis=1), axis=1, dtype=F32)
    index = m.reshape([-1] + [1] * (terms.ndim - 1))
    return np.take_along_axis(acc, index, axis=1)[:, 0]


PAIRS = [(a, b) for a in range(N_PARAM) for b in range(a + 1)]     # lower triangle, the C's loop order


def normal_equations(phi: np.ndarray, w: np.ndarray, y: np.ndarray, m: np.ndarray, ridge: F32):
    """A (rows, 13, 13) lower triangle and rhs (rows, 13): per point p, t_a = w_p·phi_pa;
    A[a][b] += t_a·phi_pb, rhs[a] += t_a·y_p; then the ridge on the slope diagonal."""
    R = phi.shape[0]
    t = w[:, :, None] * phi                                     # (R, S, 13)
    A = np.zeros((R, N_PARAM, N_PARAM), dtype=F32)
    ai = np.array([p[0] for p in PAIRS])
    bi = np.array([p[1] for p in PAIRS])
    terms = t[:, :, ai] * phi[:, :, bi]                         # (R, S, 91)
    A[:, ai, bi] = _running_sum_at(terms, m)
    rhs = _running_sum_at(t * y[:, :, None], m)
    lam = ridge * A[:, 0, 0]
    for a in range(1, N_PARAM):
        A[:, a, a] = A[:, a, a] + lam
    return A, rhs


def ldlt_solve(A: np.ndarray, rhs: np.ndarray):
    """LDL^T of the lower triangle and the solve, the C's loops; rows whose pivot is not > 0 (or
    not finite) get the weighted mean rhs0 / A00 as intercept and zero slopes (singular)."""
    R = A.shape[0]
    L = np.zeros((R, N_PARAM, N_PARAM), dtype=F32)
    LD = np.zeros((R, N_PARAM, N_PARAM), dtype=F32)
    D = np.zeros((R, N_PARAM), dtype=F32)
    singular = np.zeros(R, dtype=bool)
    with np.errstate(all="ignore"):
        for i in range(N_PARAM):
            for j in range(i):
                s = A[:, i, j].copy()
                for k in range(j):
                    s = s - LD[:, i, k] * L[:, j, k]
                LD[:, i, j] = s
                L[:, i, j] = s / D[:, j]
            d = A[:, i, i].copy()
            for k in range(i):
                d = d - LD[:, i, k] * L[:, i, k]
            singular |= ~(d > 0) | ~np.isfinite(d)
            D[:, i] = d
        u = np.zeros((R, N_PARAM), dtype=F32)
        for i in range(N_PARAM):
            s = rhs[:, i].copy()
            for k in range(i):
                s = s - L[:, i, k] * u[:, k]
            u[:, i] = s
        v = u / D
        beta = np.zeros((R, N_PARAM), dtype=F32)
        for i in range(N_PARAM - 1, -1, -1):
            s = v[:, i].copy()
            for k in range(i + 1, N_PARAM):
                s = s - L[:, k, i] * beta[:, k]
            beta[:, i] = s
        mean = rhs[:, 0] / A[:, 0, 0]
    beta[singular] = 0
    beta[singular, 0] = mean[singular]
    return beta, singular


def residuals(beta: np.ndarray, Z: np.ndarray, y: np.ndarray) -> np.ndarray:
    """e_p = y_p − (β0 + β1·z_p1 + ... + β12·z_p12), summed left to right as the C does."""
    pred = np.repeat(beta[:, :1], Z.shape[1], axis=1)
    for k in range(N_IN):
        pred = pred + beta[:, k + 1:k + 2] * Z[:, :, k]
    return y - pred


def fit_output(c: Constants, Z, phi, y, m, A0, rhs_unused=None):
    """One output: the unweighted fit (A0 shared), then `iterations` Tukey reweightings."""
    R = Z.shape[0]
    ones = np.ones(Z.shape[:2], dtype=F32)
    _, rhs = normal_equations(phi, ones, y, m, c.ridge)
    beta, singular = ldlt_solve(A0, rhs)
    active = ~singular
    mf = m.astype(F32)
    with np.errstate(all="ignore"):
        for _ in range(c.iterations):
            if not active.any():
                break
            e = residuals(beta, Z, y)
            sa = _running_sum_at(np.abs(e), m)
            cs = c.c_scale * (sa / mf)
            active &= cs > 0                         # an exact fit (or NaN): stop reweighting
            rows = np.flatnonzero(active)
            if rows.size == 0:
                break
            u = e[rows] * (F32(1.0) / cs[rows])[:, None]
            tt = F32(1.0) - u * u
            w = np.where(np.abs(u) < F32(1.0), tt * tt, F32(0.0)).astype(F32)
            A, rhs_w = normal_equations(phi[rows], w, y[rows], m[rows], c.ridge)
            b_new, sing = ldlt_solve(A, rhs_w)
            beta[rows] = b_new
            singular[rows] |= sing
            active[rows[sing]] = False
    return beta[:, 0], singular


def step(c: Constants, inp: np.ndarray, chunk: int | None = None) -> np.ndarray:
    """Output records for input records (INPUT_DTYPE), in chunks to bound memory."""
    if inp.dtype != INPUT_DTYPE:
        raise ValueError(f"dp golden: expected input dtype {INPUT_DTYPE}, got {inp.dtype}")
    R = inp.shape[0]
    out = np.zeros(R, dtype=OUTPUT_DTYPE)
    chunk = chunk or max(1, (1 << 22) // (c.s * 91))
    for s0 in range(0, R, chunk):
        out[s0:s0 + chunk] = _step_chunk(c, np.ascontiguousarray(inp["x"][s0:s0 + chunk]))
    return out


def _step_chunk(c: Constants, Q: np.ndarray) -> np.ndarray:
    with np.errstate(all="ignore"):      # huge finite inputs overflow on purpose: the C's INVALID path
        return _step_rows(c, Q)


def _step_rows(c: Constants, Q: np.ndarray) -> np.ndarray:
    R = Q.shape[0]
    out = np.zeros(R, dtype=OUTPUT_DTYPE)
    valid = np.all(np.isfinite(Q), axis=1)
    out["status"][~valid] = STATUS_INVALID
    rows = np.flatnonzero(valid)
    if rows.size == 0:
        return out
    q = Q[rows]
    sel, found, used, level = select_rows(c, q)
    with np.errstate(all="ignore"):
        Z = (c.X[sel] - q[:, None, :]) * c.inv_span             # (R, S, 12): (x − q)·(1/range)
    phi = np.concatenate([np.ones(Z.shape[:2] + (1,), F32), Z], axis=2)
    ones = np.ones(Z.shape[:2], dtype=F32)
    A0, _ = normal_equations(phi, ones, c.Y[sel, 0], used, c.ridge)
    torque = np.zeros((rows.size, N_OUT), dtype=F32)
    singular = np.zeros(rows.size, dtype=bool)
    for o in range(N_OUT):
        torque[:, o], sing = fit_output(c, Z, phi, c.Y[sel, o], used, A0)
        singular |= sing
    status = np.where(level > 0, STATUS_WIDENED, 0) | np.where(level == c.half.shape[0], STATUS_EVERY_SAMPLE, 0) \
        | np.where(singular, STATUS_SINGULAR, 0)
    # the C tests (t0 + t1) + t2: finite iff every term is (and their sum does not overflow)
    bad = ~np.isfinite((torque[:, 0] + torque[:, 1]) + torque[:, 2])
    torque[bad] = 0
    status = status | np.where(bad, STATUS_INVALID, 0)
    sub = out[rows]
    sub["torque"], sub["found"], sub["used"], sub["level"], sub["status"] = torque, found, used, level, status
    out[rows] = sub
    return out
