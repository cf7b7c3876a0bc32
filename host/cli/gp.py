"""`staregen gp table1|train`: paper 004's sparse GP (docs/gp-takeover.md).

`staregen gp table1 [--data takeover|synthetic] [--sizes 500,1000,1500,2000] [--m 20] --out DIR`:
paper 004's Table 1 — training time and test MSE of the exact GP and the sparse GP against the
training-set size, with the growth ratios beside the paper's (exact 6.31 s -> 303.78 s, 48x;
sparse 1.56 s -> 3.64 s, 2.3x). docs/gp-takeover.md sections 3, 4, 8.

The takeover data are section 3's PD-excited runs of the takeover scenario (training pool: seeds
0-9, test: seeds 100-103); `synthetic` is the smooth 9-D map the unit tests use.

`staregen gp train [--m 20] [--iterations 1000] [--seed 0] --out DIR`: the sparse GP trained on the
whole pool, its sealed artifact (gp.json), the law's file (gp_law.toml, read back before the folder
is written), train.json and the paper's Figs. 2-3 on held-out run 100 (host.learn.gp_train)."""
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
from codegen.units.gp.params import GpParamsError
from host.learn import gp, gp_train
from host.learn.gp_table1 import PAPER_TABLE1, table1
from host.outputs import check_output_folder, json_marker_owner
from host.sim.takeover import RUN_DURATION, collect

TRAIN_SEEDS, TEST_SEEDS = range(10), range(100, 104)
RUN_SECONDS = RUN_DURATION       # s per excited run (section 3)
OWNED = json_marker_owner("table1.json")
TRAIN_OWNED = json_marker_owner(gp_train.SUMMARY_NAME)
M_MIN, M_MAX = 2, 200


def register(subparsers) -> None:
    p = subparsers.add_parser("gp", help="paper 004's sparse Gaussian process: Table 1, the trained model",
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
    r = sub.add_parser("train", help="train the sparse GP on the takeover pool: artifact, law file, Figs. 2-3")
    r.add_argument("--m", default=str(gp.DEFAULT_M), help=f"inducing points, {M_MIN}-{M_MAX} (default {gp.DEFAULT_M})")
    r.add_argument("--iterations", default=str(gp.SPARSE_ITERATIONS),
                   help=f"Adam iterations (default {gp.SPARSE_ITERATIONS}, section 4)")
    r.add_argument("--seed", default="0", help="torch seed of the training (default 0)")
    r.add_argument("--out", required=True, metavar="DIR",
                   help="output folder (gp.json, gp_law.toml, train.json, fig2_gp_response.png, fig3_gp_error.png)")
    r.set_defaults(func=train_main)


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


def _train_data(log) -> tuple[gp_train.Dataset, gp_train.Dataset]:
    log(f"collecting section 3's data: pool seeds {TRAIN_SEEDS[0]}-{TRAIN_SEEDS[-1]}, "
        f"test seeds {TEST_SEEDS[0]}-{TEST_SEEDS[-1]}, {RUN_SECONDS:g} s per run")
    pool = gp_train.collect_runs(TRAIN_SEEDS, RUN_SECONDS, "pool", log)
    test = gp_train.collect_runs(TEST_SEEDS, RUN_SECONDS, "test", log)
    return pool, test


def train_main(args: argparse.Namespace) -> int:
    m = parse_int(args.m, "--m", minimum=M_MIN, maximum=M_MAX)
    iterations = parse_int(args.iterations, "--iterations", minimum=1, maximum=100_000)
    seed = parse_int(args.seed, "--seed", minimum=0, maximum=2**31 - 1)
    out = Path(args.out)
    check_output_folder(out, TRAIN_OWNED)
    log = lambda line: print(line, flush=True)   # noqa: E731
    pool, test = _train_data(log)
    if m > len(pool.x):
        raise HostError(f"--m {m} is more than the training pool ({len(pool.x)} samples)")
    trained = gp_train.train(pool, test, m, iterations, seed, log)
    try:
        with atomic.directory(out) as tmp:
            params = gp_train.write_outputs(tmp, trained)
    except GpParamsError as exc:
        raise HostError(f"the law file does not load, nothing written: {exc}") from None
    except OSError as exc:
        raise HostError(f"cannot write output folder {out}: {exc.strerror or exc}") from None
    s = trained.summary
    print(f"test MSE per axis {', '.join(f'{v:.3e}' for v in s['test']['mse_per_axis'])} (N·m)^2, "
          f"R^2 {', '.join(f'{v:.3f}' for v in s['test']['r2_per_axis'])}; train time {s['train_time_s']:.1f} s")
    print(f"law file: M = {params.n_inducing}, artifact sha256 {params.gp.sha256[:16]}...")
    print(f"wrote {out}/{gp_train.ARTIFACT_NAME}, {gp_train.LAW_NAME}, {gp_train.SUMMARY_NAME} and the figures")
    return 0
