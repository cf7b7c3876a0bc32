"""DpModel.query_rows (the batched float64 discrete-point law) against a loop of DpModel.query on
every branch of the scalar law: several box levels, the reservoir over S_limit, every sample (far
outside the data), an exact fit (zero scale), a singular system (the weighted mean), an undefined
weighted mean (invalid), non-finite rows; the row selection against `select` ID for ID."""
from __future__ import annotations

import numpy as np
import pytest

import host.control.discrete_point as dp
from host.control.discrete_point import (DpModel, DpParams, RowsIndex, _reservoir_slots, _solve_or_mean,
                                         _solve_or_mean_stack, reservoir, select, select_rows)
from host.errors import HostError

SCALES = np.linspace(0.5, 3.0, 12)


def _model(config: DpParams, n=700, seed=0, zero_output=False) -> DpModel:
    """Uniform inputs, a smooth nonlinear torque with noise (the fit is not exact); with
    zero_output the third torque is 0 everywhere (every fit exact: zero scale)."""
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1.0, 1.0, (n, 12)) * SCALES
    A = rng.normal(size=(12, 3))
    Y = np.tanh(X @ A / 4.0) + 0.3 * np.sin(X[:, :3]) + rng.normal(0, 0.01, (n, 3))
    if zero_output:
        Y[:, 2] = 0.0
    return DpModel.fit(X, Y, config)


def _queries(model: DpModel, n=240, seed=1) -> np.ndarray:
    """Random rows inside the data, on and beside samples, on box edges and far outside."""
    rng = np.random.default_rng(seed)
    t, c = model.tables, model.config
    k = n // 6
    inside = rng.uniform(-1.0, 1.0, (2 * k, 12)) * SCALES
    on = t.X[rng.integers(0, t.n, k)]
    beside = np.nextafter(t.X[rng.integers(0, t.n, k)], np.inf)
    # a box edge on a sample: q_k = x_k − h_k at a random level
    edge = t.X[rng.integers(0, t.n, k)] + rng.normal(0, 0.05, (k, 12))
    H = np.array([0.5 * side * t.span for side in c.sides()])
    for i, row in enumerate(edge):
        d, j = rng.integers(0, 12), rng.integers(0, t.n)
        row[d] = t.X[j, d] - H[rng.integers(0, len(H)), d]
    far = rng.uniform(-1.0, 1.0, (n - 5 * k, 12)) * SCALES
    far[np.arange(len(far)), rng.integers(0, 12, len(far))] += 3.0 * t.span.max()   # every box empty
    return np.vstack([inside, on, beside, edge, far])


def _window_queries(model: DpModel, n=60, seed=11) -> np.ndarray:
    """Queries with a sample one ulp beyond its box edge in one input at the level `select` uses:
    there |x − q| <= h and q − h <= x <= q + h often disagree by rounding (the closed window)."""
    rng = np.random.default_rng(seed)
    t, c = model.tables, model.config
    H = np.array([0.5 * side * t.span for side in c.sides()])
    out = []
    while len(out) < n:
        j, d, lv = rng.integers(0, t.n), rng.integers(0, 12), rng.integers(0, len(H))
        q = t.X[j].copy()
        q[d] = np.nextafter(t.X[j, d] - H[lv, d], rng.choice([-np.inf, np.inf]))
        if select(t, c, q).level == lv:
            out.append(q)
    return np.array(out)


def _loop(model: DpModel, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    with np.errstate(all="ignore"):
        torque = np.array([model.query(q).torque for q in Q])
    invalid = ~np.all(np.isfinite(torque), axis=1)
    return torque, invalid


def _assert_rows_equal(model: DpModel, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    torque, invalid = model.query_rows(Q)
    ref, ref_invalid = _loop(model, Q)
    assert torque.shape == (len(Q), 3) and invalid.shape == (len(Q),) and invalid.dtype == bool
    assert np.array_equal(invalid, ref_invalid)
    assert np.all(torque[invalid] == 0.0)
    ok = ~invalid
    assert np.all(np.abs(torque[ok] - ref[ok]) <= 1e-12 * np.abs(ref[ok]) + 1e-15)
    return torque, invalid


def _assert_select_equal(model: DpModel, Q: np.ndarray, index: RowsIndex | None = None):
    t, c = model.tables, model.config
    nb = select_rows(t, c, Q, index)
    for r, q in enumerate(Q):
        one = select(t, c, q)
        assert (nb.level[r], nb.found[r], nb.used[r]) == (one.level, one.found, len(one.ids))
        assert np.array_equal(nb.ids[r, :nb.used[r]], one.ids) and np.all(nb.ids[r, nb.used[r]:] == -1)
    return nb


CONFIG = DpParams(r=0.05, s_limit=32, n_min=20, iterations=2)


@pytest.fixture(scope="module")
def base() -> tuple[DpModel, np.ndarray]:
    """The model with several levels and the reservoir, and its 300 queries of every class."""
    model = _model(CONFIG)
    return model, np.vstack([_queries(model), _window_queries(model)])


def test_selection_equals_select_on_every_level_and_the_reservoir(base):
    model, Q = base
    nb = _assert_select_equal(model, Q)
    L = len(CONFIG.sides())
    levels = set(nb.level.tolist())
    # the rows need several levels, some more points than S_limit, some every sample
    assert len(levels - {L}) >= 3 and L in levels
    assert np.any((nb.found > CONFIG.s_limit) & (nb.level < L)) and np.any(nb.found < CONFIG.s_limit)


def test_a_coarse_superset_gives_the_same_selection(monkeypatch):
    """Coarse prefix bitsets (as for the largest tables) make rows fail the first level tested
    exactly and go on to the next: the same selection."""
    model = _model(CONFIG)
    retried = []
    original = dp._next_level

    def spy(worth, rows, after):
        if np.any(after >= 0):
            retried.append(int(np.sum(after >= 0)))
        return original(worth, rows, after)
    monkeypatch.setattr(dp, "_next_level", spy)
    _assert_select_equal(model, _queries(model, 120, seed=2), RowsIndex.build(model.tables, block=37))
    assert sum(retried) > 0


def test_rows_equal_the_per_row_law(base):
    model, Q = base
    torque, invalid = _assert_rows_equal(model, Q)
    assert not invalid.any() and np.all(np.isfinite(torque))


def test_rows_equal_the_law_with_the_default_settings_and_one_row():
    model = _model(DpParams(), n=1500, seed=3)
    rng = np.random.default_rng(4)
    Q = model.tables.X[rng.integers(0, 1500, 200)] + rng.normal(0, 0.02, (200, 12)) * model.tables.span
    _assert_rows_equal(model, Q)
    _assert_rows_equal(model, Q[:1])
    torque, invalid = model.query_rows(np.zeros((0, 12)))
    assert torque.shape == (0, 3) and invalid.shape == (0,)


def test_an_exact_fit_stops_reweighting_as_the_scalar_does():
    """The third torque is 0 everywhere: b = 0, beta = 0, every residual 0, scale 0: the loop ends."""
    model = _model(CONFIG, zero_output=True)
    torque, _ = _assert_rows_equal(model, _queries(model, 200, seed=5))
    assert np.all(torque[:, 2] == 0.0) and np.all(torque[:, :2] != 0.0)


def test_a_singular_system_gives_the_weighted_mean_as_the_scalar_does():
    """ridge 0 and a cluster whose input 3 equals the query's exactly: the column of z_3 is 0, the
    Cholesky test fails, the fit is the weighted mean (rows elsewhere fit normally)."""
    rng = np.random.default_rng(6)
    cluster = rng.uniform(-0.01, 0.01, (200, 12))
    cluster[:, 3] = 0.0
    spread = rng.uniform(-1.0, 1.0, (400, 12))
    spread[:, 3] = rng.choice([-10.0, 10.0], 400)
    X = np.vstack([cluster, spread])
    Y = np.column_stack([np.linspace(1.0, 2.0, 600), np.sin(X[:, 0]), X[:, 1] ** 2])
    model = DpModel.fit(X, Y, DpParams(r=0.05, s_limit=32, n_min=20, ridge=0.0, iterations=1))
    Qc = rng.uniform(-0.005, 0.005, (100, 12))
    Qc[:, 3] = 0.0
    Q = np.vstack([Qc, rng.uniform(-1.0, 1.0, (100, 12))])
    torque, invalid = _assert_rows_equal(model, Q)
    nb = select_rows(model.tables, model.config, Qc)
    assert np.all(model.tables.X[nb.ids[:, :nb.used[0]], 3] == 0.0) and np.all(nb.used == 32)
    assert not invalid.any()
    # the weighted mean over the 32 selected samples of the first torque column
    assert np.allclose(torque[:100, 0], [model.tables.Y[nb.ids[r, :32], 0].mean() for r in range(100)],
                       rtol=1e-12, atol=0)


def test_an_undefined_weighted_mean_is_invalid_as_in_the_scalar():
    """tukey_c tiny: every point's |u| >= 1, every weight 0, A = 0: the weighted mean is 0/0."""
    model = _model(DpParams(r=0.05, s_limit=32, n_min=20, tukey_c=0.01))
    torque, invalid = _assert_rows_equal(model, _queries(model, 120, seed=7))
    assert invalid.any() and np.all(torque[invalid] == 0.0)


def test_non_finite_rows_are_invalid_and_leave_the_others_alone():
    model = _model(CONFIG)
    Q = _queries(model, 60, seed=8)
    clean, _ = model.query_rows(Q)
    dirty = Q.copy()
    dirty[[3, 17, 40], [0, 5, 11]] = [np.nan, np.inf, -np.inf]
    torque, invalid = model.query_rows(dirty)
    assert np.array_equal(np.flatnonzero(invalid), [3, 17, 40]) and np.all(torque[invalid] == 0.0)
    others = np.setdiff1d(np.arange(60), [3, 17, 40])
    assert np.array_equal(torque[others], clean[others])
    with pytest.raises(HostError, match="finite"):
        model.query(dirty[3])
    assert model.query_rows(np.full((2, 12), np.nan))[1].all()


@pytest.mark.parametrize("s_limit", [13, 32, 64])
def test_cached_reservoir_slots_are_the_reservoir(s_limit):
    for n in [s_limit + 1, s_limit + 2, 2 * s_limit + 3, 100, 257, 1000, 1500]:
        if n > s_limit:
            ids = np.arange(5000, 5000 + n)
            assert np.array_equal(ids[_reservoir_slots(n, s_limit)], reservoir(ids, s_limit))


def test_the_stacked_solve_is_the_scalar_solve_per_matrix():
    rng = np.random.default_rng(9)
    stack, rhs = [], []
    for i in range(40):
        M = rng.normal(size=(13, 13))
        A = M @ M.T + 13 * np.eye(13)                       # positive definite
        if i % 7 == 3:
            A[4, :] = A[:, 4] = 0.0                         # a zero pivot
        if i % 11 == 5:
            A[0, 0] = -1.0                                  # not positive definite
        if i == 20:
            A[2, 2] = np.nan
        stack.append(A)
        rhs.append(rng.normal(size=13))
    A, b = np.array(stack), np.array(rhs)
    with np.errstate(all="ignore"):
        beta, singular = _solve_or_mean_stack(A, b)
        for i in range(40):
            one, sing = _solve_or_mean(A[i], b[i])
            assert sing == singular[i]
            np.testing.assert_array_equal(beta[i], one)
    assert 3 <= singular.sum() < 40
