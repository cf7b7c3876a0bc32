"""`staregen train` and `staregen sweep`: the network of paper 001 section 6, trained on OCP samples.

train: one 12-H-3 tansig net (default 12-40-3) on a dataset of `staregen samples`, exported as a
model artifact, with its test errors beside the linear and saturated-linear baselines.
sweep: the Table 3 grid (reduced by default, --full for all 3,876 nets) on Dask; writes
sweep.json, sweep.md and the best tansig net as model.json into --out.
"""
from __future__ import annotations


from host.learn import sweep as sweep_mod
from host.learn import training
from host.cli.args import parse_int, parse_number


def register(subparsers) -> None:
    _register_train(subparsers)
    _register_sweep(subparsers)


def _register_train(subparsers) -> None:
    p = subparsers.add_parser("train", help="train the 12-40-3 tansig net on OCP samples -> model artifact",
                              description="Train the 12-H-3 tansig network (paper 001 section 6) on a "
                                          "`staregen samples` dataset and export it as a model artifact.")
    p.add_argument("--data", required=True, help="dataset folder written by `staregen samples`")
    p.add_argument("--out", required=True, help="artifact file to write (atomically; its folder must exist)")
    p.add_argument("--recipe", default="default", choices=tuple(training.RECIPES),
                   help="default: full-batch Adam then L-BFGS; paper: SGD, dropout 0.1, weight decay 0.01")
    p.add_argument("--epochs", default=None,
                   help="epochs (paper: SGD passes; default: L-BFGS iterations after the Adam warm start)")
    p.add_argument("--hidden", default=str(training.DEFAULT_HIDDEN), help="hidden neurons (default 40)")
    p.add_argument("--seed", default="0", help="seed of the split and the initial weights (default 0)")
    p.set_defaults(func=train_main)


def _register_sweep(subparsers) -> None:
    p = subparsers.add_parser("sweep", help="Table 3 training sweep on Dask; exports the best tansig net",
                              description="Train the Table 3 grid (activation x hidden x epochs) on Dask, "
                                          "select by test MSE, export the best tansig net.")
    p.add_argument("--data", required=True, help="dataset folder written by `staregen samples`")
    p.add_argument("--out", required=True, help="folder for sweep.json, sweep.md and model.json (created)")
    p.add_argument("--full", action="store_true", help="the whole Table 3 grid, 4 x 51 x 19 = 3,876 nets")
    p.add_argument("--recipe", default="default", choices=tuple(training.RECIPES), help="training recipe")
    p.add_argument("--seed", default="0", help="seed of the split and the initial weights (default 0)")
    p.add_argument("--scheduler", default=None, help="existing Dask scheduler, tcp://host:port (default: local)")
    p.add_argument("--workers", default=None, help="local cluster worker processes (default: all cores)")
    p.add_argument("--connect-timeout", default="10", help="seconds to reach --scheduler (default 10)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=sweep_main)


def train_main(args) -> int:
    hidden = parse_int(args.hidden, "--hidden", 1)
    seed = parse_int(args.seed, "--seed", 0)
    epochs = None if args.epochs is None else parse_int(args.epochs, "--epochs", 1)
    out = training.check_writable(args.out)
    artifact, report = training.train_artifact(args.data, recipe=args.recipe, seed=seed, epochs=epochs,
                                               hidden=hidden)
    training.save_artifact(artifact, out)
    laws = training.save_baselines(report, out)
    print(report.summary())
    print(f"artifact {out} ({artifact.shape_text}, sha256 {artifact.sha256[:16]}…); baselines {laws}")
    return 0


def sweep_main(args) -> int:
    seed = parse_int(args.seed, "--seed", 0)
    workers = None if args.workers is None else parse_int(args.workers, "--workers", 1)
    timeout = parse_number(args.connect_timeout, "--connect-timeout", positive=True)
    data = training.load_training_data(args.data)  # a bad folder fails before the output folder is made
    out = sweep_mod.prepare_out_dir(args.out)
    result = sweep_mod.run_sweep(data, full=args.full, recipe=args.recipe, seed=seed,
                                 scheduler=args.scheduler, workers=workers, progress=not args.no_progress,
                                 connect_timeout=timeout)
    paths = sweep_mod.write_sweep(result, out)
    c = result.choice
    best, tansig = c["best_overall"], c["best_tansig"]
    print(f"sweep: {c['n_networks']} nets ({c['grid']}, {c['recipe']} recipe) in {result.wall_seconds:.1f} s "
          f"on {result.workers} workers; {c['n_diverged']} diverged")
    print(f"best overall: {best['activation']} {best['hidden']} hidden {best['epochs']} epochs, "
          f"test MSE {best['mse_mean_normalised']:.4g}; exported {c['exported']}: tansig {tansig['hidden']} "
          f"hidden {tansig['epochs']} epochs")
    print(result.report.markdown_table())
    print(f"wrote {paths['json']}, {paths['markdown']}, {paths['artifact']}")
    return 0
