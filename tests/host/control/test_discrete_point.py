"""The float64 discrete-point law (host/control/discrete_point.py) against analytic truth: exact
on affine data, robust to outliers where least squares is not, the selection equal to a brute-force
box scan, the tables' invariant, the reservoir deterministic; bad settings refused in one line."""
from __future__ import annotations

import numpy as np
import pytest

from host.control.discrete_point import (DpParams, DpModel, DpTables, irls_intercept, reservoir, select,
                                         xorshift32)
from codegen.units.dp.params import DpParamsError
from host.errors import HostError


def _samples(n=600, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1.0, 1.0, (n, 12)) * np.linspace(0.5, 3.0, 12)
    A = rng.normal(size=(12, 3))
    b = rng.normal(size=3)
    return X, X @ A + b, A, b


def test_tables_hold_the_papers_invariant():
    X, Y, _, _ = _samples()
    t = DpTables.build(X, Y)
    for k in range(12):
        assert np.array_equal(X[t.X3[:, k], k], t.X2[:, k]) and np.all(np.diff(t.X2[:, k]) >= 0)
    assert np.allclose(t.span, X.max(0) - X.min(0), rtol=0, atol=0)


def test_affine_data_is_reproduced_exactly_at_any_query():
    X, Y, A, b = _samples()
    exact = DpModel.fit(X, Y, DpParams(r=0.05, s_limit=64, ridge=0.0))
    ridged = DpModel.fit(X, Y, DpParams(r=0.05, s_limit=64))
    rng = np.random.default_rng(1)
    for q in rng.uniform(-0.4, 0.4, (20, 12)):
        assert np.allclose(exact.query(q).torque, q @ A + b, rtol=0, atol=1e-9)
        # the default ridge (1e-6 of the weight sum) biases the slopes by ~1e-6 relative, no more
        assert np.allclose(ridged.query(q).torque, q @ A + b, rtol=0, atol=1e-4)


def test_irls_rejects_outliers_that_move_least_squares():
    rng = np.random.default_rng(2)
    Z = rng.uniform(-0.5, 0.5, (200, 12))
    y = 0.3 + Z @ rng.normal(size=12) + rng.normal(0, 1e-3, 200)
    y[:20] += 5.0                                   # 10 % gross errors
    ols = irls_intercept(Z, y, DpParams(iterations=0))
    robust = irls_intercept(Z, y, DpParams(iterations=5))
    assert abs(ols - 0.3) > 0.3 and abs(robust - 0.3) < 2e-3


def test_selection_equals_a_brute_force_box_scan():
    X, Y, _, _ = _samples(400)
    c = DpParams(r=0.1, s_limit=32, n_min=20)
    t = DpTables.build(X, Y)
    rng = np.random.default_rng(3)
    for q in rng.uniform(-1, 1, (30, 12)):
        nb = select(t, c, q)
        counts = [int(np.sum(np.all(np.abs(X - q) <= 0.5 * s * t.span, axis=1))) for s in c.sides()]
        first = next((i for i, n in enumerate(counts) if n >= c.n_min), len(counts))
        assert nb.level == first
        if first < len(counts):
            inside = np.all(np.abs(X[nb.ids] - q) <= 0.5 * c.sides()[first] * t.span, axis=1)
            assert nb.found == counts[first] and inside.all()
        assert len(nb.ids) == min(nb.found, c.s_limit) and len(set(nb.ids.tolist())) == len(nb.ids)


def test_reservoir_is_deterministic_and_draws_from_the_hits():
    hits = np.arange(1000, 3000)
    a, b = reservoir(hits, 64), reservoir(hits, 64)
    assert np.array_equal(a, b) and len(set(a.tolist())) == 64 and set(a.tolist()) <= set(hits.tolist())
    assert np.array_equal(reservoir(hits[:50], 64), hits[:50])
    # not just the first 64: Algorithm R replaces most of them
    assert np.sum(a < 1064) < 16
    assert xorshift32(1) == 270369 and xorshift32(0x9E3779B9) != 0x9E3779B9   # by hand: 1 ^ 1<<13 = 8193; ^ 8193>>17 = 8193; ^ 8193<<5 = 270369


@pytest.mark.parametrize("kwargs, message", [
    ({"r": 0.0}, "r must lie in (0, 1)"),
    ({"r": 1.0}, "r must lie in (0, 1)"),
    ({"s_limit": 12, "n_min": 12}, "S_limit must be an integer in [13, 4096]"),
    ({"n_min": 100, "s_limit": 64}, "n_min must be an integer in [13, S_limit = 64]"),
    ({"iterations": -1}, "iterations"),
    ({"widen": 1.0}, "widening factor"),
])
def test_bad_settings_are_refused_in_one_line(kwargs, message):
    with pytest.raises(DpParamsError) as e:
        DpParams(**kwargs).validate()
    assert message in str(e.value) and "\n" not in str(e.value)


def test_bad_samples_are_refused():
    X, Y, _, _ = _samples(30)
    with pytest.raises(HostError, match="at least n_min = 26"):
        DpModel.fit(X[:20], Y[:20])
    X[:, 4] = 1.0
    with pytest.raises(HostError, match="constant input dimension 4"):
        DpModel.fit(X, Y)


def test_a_singular_system_gives_the_weighted_mean_like_the_c():
    """ridge 0 and every point equal in one input: the C's LDLᵀ meets a zero pivot and returns the
    weighted mean; the float64 law does the same instead of raising."""
    Z = np.random.default_rng(5).uniform(-0.5, 0.5, (40, 12))
    Z[:, 3] = 0.0
    y = np.linspace(1.0, 2.0, 40)
    assert irls_intercept(Z, y, DpParams(ridge=0.0, iterations=2)) == pytest.approx(1.5, abs=1e-12)
