"""Paper 004 Table 1 harness (docs/gp-takeover.md §8): training time and test MSE of the exact GP
and the sparse GP on nested training sets (the first N of the pool), growth ratios against the
smallest N. Times follow §4 (construction + optimisation loop, one torch thread); MSE per §3.

    python -m host.learn.gp_table1 --synthetic [--sizes 500,1000,1500,2000] [--m 20]
                                   [--exact-iterations 200] [--sparse-iterations 1000]
"""
from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys

import numpy as np

from host.learn import gp


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


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--synthetic", action="store_true", required=True,
                   help="synthetic data (gp.synthetic); the takeover data come with host/sim/takeover.py")
    p.add_argument("--sizes", default="500,1000,1500,2000")
    p.add_argument("--m", type=int, default=gp.DEFAULT_M)
    p.add_argument("--repeats", type=int, default=1)
    p.add_argument("--exact-iterations", type=int, default=gp.EXACT_ITERATIONS,
                   help="fewer than §4's 200 for a quick per-iteration growth measurement")
    p.add_argument("--sparse-iterations", type=int, default=gp.SPARSE_ITERATIONS)
    args = p.parse_args(argv)
    sizes = tuple(int(s) for s in args.sizes.split(","))
    x_pool, d_pool = gp.synthetic(max(sizes), seed=0)
    x_test, d_test = gp.synthetic(1000, seed=100)
    import gpytorch
    import torch
    print(json.dumps({"cpu": platform.processor() or platform.machine(), "torch": torch.__version__,
                      "gpytorch": gpytorch.__version__, "threads": 1}), flush=True)
    rows = table1(x_pool, d_pool, x_test, d_test, sizes, args.m, exact_iterations=args.exact_iterations,
                  sparse_iterations=args.sparse_iterations, repeats=args.repeats,
                  log=lambda s: print(s, flush=True))
    for row in rows:
        print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
