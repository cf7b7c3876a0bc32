"""Paper 004 Table 1 harness (docs/gp-takeover.md §8): training time and test MSE of the exact GP
and the sparse GP on nested training sets (the first N of the pool), growth ratios against the
smallest N. Times follow §4 (construction + optimisation loop, one torch thread); MSE per §3.

The command: `staregen gp table1` (host/cli/gp.py).
"""
from __future__ import annotations

import json
import statistics

import numpy as np

from host.learn import gp


# Paper 004 Table 1 (section 3.1): training seconds from 500 to 2,000 points (the MSEs are lost)
PAPER_TABLE1 = {"sizes": [500, 2000], "exact_s": [6.31, 303.78], "sparse_s": [1.56, 3.64],
                "exact_growth": 48.1, "sparse_growth": 2.33}


def warm_up(x, d, m: int) -> None:
    """One short untimed fit of each kind: the first fit of a process pays torch's and gpytorch's
    one-off set-up (about 2 s here), which would inflate the smallest N and every growth ratio."""
    gp.train_exact(x, d, iterations=2)
    gp.train_sparse(x, d, m=min(m, len(x)), iterations=2)


def table1(x_pool, d_pool, x_test, d_test, sizes=(500, 1000, 1500, 2000), m: int = gp.DEFAULT_M,
           exact_iterations: int = gp.EXACT_ITERATIONS, sparse_iterations: int = gp.SPARSE_ITERATIONS,
           repeats: int = 1, seed: int = 0, log=None) -> list[dict]:
    """One row per N: exact and sparse train time (median of `repeats`), MSE, growth vs the first N.
    The training sets are the first N of one permutation (seed) of the pool (nested sets, §3)."""
    x_pool, d_pool = gp.check_data(x_pool, d_pool)
    x_test, d_test = gp.check_data(x_test, d_test)
    if max(sizes) > len(x_pool):
        raise ValueError(f"the pool has {len(x_pool)} samples, fewer than N = {max(sizes)}")
    order = np.random.default_rng(seed).permutation(len(x_pool))
    warm_up(x_pool[order[:50]], d_pool[order[:50]], m)
    rows = []
    for n in sizes:
        idx = order[:n]
        row = {"n": int(n), "m": int(m)}
        for kind in ("exact", "sparse"):
            times, fit = [], None
            for _ in range(repeats):
                if kind == "exact":
                    fit = gp.train_exact(x_pool[idx], d_pool[idx], iterations=exact_iterations)
                else:
                    fit = gp.train_sparse(x_pool[idx], d_pool[idx], m=m, iterations=sparse_iterations)
                times.append(fit.train_time_s)
            mean, _ = fit.predict(x_test)
            row[f"{kind}_time_s"] = statistics.median(times)
            row[f"{kind}_mse"] = gp.mse(mean, d_test)["mse"]
            if kind == "sparse":
                row["kmeans_time_s"] = fit.kmeans_time_s
        if log:
            log(json.dumps(row))
        rows.append(row)
    for row in rows:
        for kind in ("exact", "sparse"):
            row[f"{kind}_growth"] = row[f"{kind}_time_s"] / rows[0][f"{kind}_time_s"]
        row["mse_ratio"] = row["sparse_mse"] / row["exact_mse"] if row["exact_mse"] > 0 else float("inf")
    return rows
