"""`staregen gp table1 [--data takeover|synthetic] [--sizes 500,1000,1500,2000] [--m 20] --out DIR`:
paper 004's Table 1 — training time and test MSE of the exact GP and the sparse GP against the
training-set size, with the growth ratios beside the paper's (exact 6.31 s -> 303.78 s, 48x;
sparse 1.56 s -> 3.64 s, 2.3x). docs/gp-takeover.md sections 3, 4, 8.

The takeover data are section 3's PD-excited runs of the takeover scenario (training pool: seeds
0-9, test: seeds 100-103); `synthetic` is the smooth 9-D map the unit tests use."""
from __future__ import annotations

import argparse
import platform
import time
from pathlib import Path

import gpytorch
import torch

from codegen import atomic
from host.cli.args import parse_int, parse_list
from host.errors import HostError
from host.learn import gp
from host.learn.gp_table1 import PAPER_TABLE1, table1
from host.outputs import check_output_folder, json_marker_owner
from host.sim.takeover import collect

TRAIN_SEEDS, TEST_SEEDS = range(10), range(100, 104)
OWNED = json_marker_owner("table1.json")


def register(subparsers) -> None:
    p = subparsers.add_parser("gp", help="paper 004's sparse Gaussian process: Table 1",
                              description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="gp_command", required=True, metavar="SUBCOMMAND")
    t = sub.add_parser("table1", help="exact vs sparse GP: training time and MSE against the data-set size")
    t.add_argument("--data", choices=("takeover", "synthetic"), default="takeover",
                   help="section 3's takeover runs (default) or the synthetic test map")
    t.add_argument("--sizes", default="500,1000,1500,2000", help="training-set sizes (default 500,1000,1500,2000)")
    t.add_argument("--m", default=str(gp.DEFAULT_M), help=f"inducing points (default {gp.DEFAULT_M})")
    t.add_argument("--exact-iterations", default=str(gp.EXACT_ITERATIONS),
                   help=f"Adam iterations of the exact GP (default {gp.EXACT_ITERATIONS}, section 4)")
    t.add_argument("--sparse-iterations", default=str(gp.SPARSE_ITERATIONS),
                   help=f"Adam iterations of the sparse GP (default {gp.SPARSE_ITERATIONS})")
    t.add_argument("--repeats", default="1", help="timed repeats per size, the median is reported (default 1)")
    t.add_argument("--out", required=True, metavar="DIR", help="output folder (table1.json)")
    t.set_defaults(func=table1_main)


def _data(kind: str, n_max: int):
    if kind == "synthetic":
        return (*gp.synthetic(n_max, seed=0), *gp.synthetic(1000, seed=100))
    pool, test = collect(TRAIN_SEEDS), collect(TEST_SEEDS)
    if len(pool["x"]) < n_max:
        raise HostError(f"--sizes: the takeover pool holds {len(pool['x'])} samples, fewer than {n_max}")
    return pool["x"], pool["d"], test["x"], test["d"]


def table1_main(args: argparse.Namespace) -> int:
    sizes = parse_list(args.sizes, "--sizes", lambda s: parse_int(s, "--sizes", minimum=20, maximum=10_000))
    if list(sizes) != sorted(set(sizes)):
        raise HostError("--sizes must be increasing, without repeats")
    m = parse_int(args.m, "--m", minimum=2, maximum=200)
    if m > sizes[0]:
        raise HostError(f"--m {m} is more than the smallest training set ({sizes[0]})")
    exact_it = parse_int(args.exact_iterations, "--exact-iterations", minimum=1, maximum=100_000)
    sparse_it = parse_int(args.sparse_iterations, "--sparse-iterations", minimum=1, maximum=100_000)
    repeats = parse_int(args.repeats, "--repeats", minimum=1, maximum=20)
    out = Path(args.out)
    check_output_folder(out, OWNED)
    start = time.perf_counter()
    x_pool, d_pool, x_test, d_test = _data(args.data, max(sizes))
    collect_s = time.perf_counter() - start
    rows = table1(x_pool, d_pool, x_test, d_test, sizes, m, exact_iterations=exact_it, sparse_iterations=sparse_it,
                  repeats=repeats, log=lambda line: print(line, flush=True))
    doc = {"data": args.data, "pool": len(x_pool), "test": len(x_test), "m": m, "exact_iterations": exact_it,
           "sparse_iterations": sparse_it, "repeats": repeats, "data_seconds": round(collect_s, 2), "rows": rows,
           "paper": PAPER_TABLE1,
           "machine": {"cpu": platform.processor() or platform.machine(), "torch": torch.__version__,
                       "gpytorch": gpytorch.__version__, "threads": 1}}
    try:
        with atomic.directory(out) as tmp:
            atomic.write_json(tmp / "table1.json", doc)
    except OSError as exc:
        raise HostError(f"cannot write output folder {out}: {exc.strerror or exc}") from None
    print(f"{'N':>6} {'exact s':>9} {'growth':>7} {'exact MSE':>10} {'sparse s':>9} {'growth':>7} {'sparse MSE':>10}")
    for r in rows:
        print(f"{r['n']:>6} {r['exact_time_s']:>9.2f} {r['exact_growth']:>7.2f} {r['exact_mse']:>10.3g} "
              f"{r['sparse_time_s']:>9.2f} {r['sparse_growth']:>7.2f} {r['sparse_mse']:>10.3g}")
    print(f"paper: exact 6.31 -> 303.78 s (48x), sparse 1.56 -> 3.64 s (2.3x) from 500 to 2,000 points")
    print(f"wrote {out}/table1.json")
    return 0
