"""`staregen dp`: the discrete-point controller of seed paper 003 (docs/discrete-point.md).

accuracy: the host law (float64) on the network's 75/25 split of a `staregen samples` dataset over a
grid of r × S_limit, beside the 12-40-3 network and the fitted baselines; a markdown table on
stdout and, with --out, in a file.
build: the tables artifact the flight C is generated from (`staregen codegen --unit dp --tables F`):
the training split's samples (the network's 75 %, or the first --n-max of them) and the settings.
"""
from __future__ import annotations

from pathlib import Path

from tqdm import tqdm

from codegen import atomic
from codegen.units.dp import tables as dp_tables
from host.cli.args import parse_int, parse_list, parse_number
from codegen.units.dp.params import DpParams
from host.control.nn_controller import load_artifact
from host.errors import HostError
from host.learn import training
from host.learn.discrete_point_sweep import markdown, sweep


def register(subparsers) -> None:
    p = subparsers.add_parser("dp", help="the discrete-point controller (paper 003): host accuracy, flight tables",
                              description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="dp_command", required=True, metavar="ACTION")
    a = sub.add_parser("accuracy", help="r x S_limit accuracy table on the network's test split")
    a.add_argument("--data", required=True, help="dataset folder written by `staregen samples`")
    a.add_argument("--network", default=None, help="artifact trained on --data (its row joins the table)")
    a.add_argument("--r", default="0.03,0.05,0.07,0.1,0.5", help="box sides, fractions of each range, in (0, 1)")
    a.add_argument("--s-limit", default="64,128,256,512", help="point caps, integers >= 13")
    d = DpParams()
    a.add_argument("--n-min", default=str(d.n_min), help=f"points needed before widening (default {d.n_min})")
    a.add_argument("--widen", default=str(d.widen), help=f"box growth per level (default {d.widen:g})")
    a.add_argument("--seed", default="0", help="split seed, as `staregen train --seed` (default 0)")
    a.add_argument("--out", default=None, help="markdown file to write (atomically)")
    a.add_argument("--no-progress", action="store_true", help="no progress bar")
    a.set_defaults(func=accuracy_main)

    b = sub.add_parser("build", help="the tables artifact of the flight C from a dataset's training split")
    b.add_argument("--data", required=True, help="dataset folder written by `staregen samples`")
    b.add_argument("--out", required=True, help="tables file to write (atomically; its folder must exist)")
    b.add_argument("--r", default=str(d.r), help=f"level-0 box side, fraction of each range (default {d.r:g})")
    b.add_argument("--s-limit", default=str(d.s_limit), help=f"points in the fit at most (default {d.s_limit})")
    b.add_argument("--n-min", default=str(d.n_min), help=f"points needed before widening (default {d.n_min})")
    b.add_argument("--widen", default=str(d.widen), help=f"box growth per level (default {d.widen:g})")
    b.add_argument("--iterations", default=str(d.iterations), help=f"IRLS reweightings (default {d.iterations})")
    b.add_argument("--n-max", default=None, help="keep only the first N training samples (default: all)")
    b.add_argument("--seed", default="0", help="split seed, as `staregen train --seed` (default 0)")
    b.set_defaults(func=build_main)


def accuracy_main(args) -> int:
    rs = parse_list(args.r, "--r", lambda p: parse_number(p, "--r", positive=True))
    s_limits = parse_list(args.s_limit, "--s-limit", lambda p: parse_int(p, "--s-limit", 1))
    base = DpParams(n_min=parse_int(args.n_min, "--n-min", 1), widen=parse_number(args.widen, "--widen"),
                    s_limit=max(s_limits))
    for r in rs:
        DpParams(r=r, widen=base.widen).validate()
    for s in s_limits:
        DpParams(s_limit=s, n_min=min(base.n_min, s)).validate()
    base.validate()
    X, Y, report = training.load_training_data(args.data)
    network = None if args.network is None else load_artifact(args.network)
    seed = parse_int(args.seed, "--seed", 0)
    with tqdm(total=len(rs) * len(s_limits), desc="discrete point", disable=args.no_progress, delay=0.5) as bar:
        rows = sweep(X, Y, rs, s_limits, base, network, seed, bound=training.torque_bound_of(report),
                     progress=bar.update)
    text = f"{len(X)} samples from {args.data}, split seed {seed} (75 / 25)\n\n" + markdown(rows) + "\n"
    print(text, end="")
    if args.out is not None:
        out = Path(args.out)
        if not out.parent.is_dir():
            raise HostError(f"--out: folder {out.parent} does not exist")
        atomic.write_text(out, text)
    return 0


def build_main(args) -> int:
    params = DpParams(r=parse_number(args.r, "--r", positive=True), s_limit=parse_int(args.s_limit, "--s-limit", 1),
                      n_min=parse_int(args.n_min, "--n-min", 1), widen=parse_number(args.widen, "--widen"),
                      iterations=parse_int(args.iterations, "--iterations", 0)).validate()
    seed = parse_int(args.seed, "--seed", 0)
    n_max = None if args.n_max is None else parse_int(args.n_max, "--n-max", 1)   # every flag before the data
    out = Path(args.out)
    if not out.parent.is_dir():
        raise HostError(f"--out: folder {out.parent} does not exist")
    X, Y, _ = training.load_training_data(args.data)
    split = training.make_split(X, Y, seed)
    Xt, Yt = split.X_train, split.Y_train
    if n_max is not None:
        Xt, Yt = Xt[:n_max], Yt[:n_max]
    problem = dp_tables.flash_problem(len(Xt))
    if problem:
        raise HostError(f"{args.data}: {problem} (use --n-max)")
    t = dp_tables.from_arrays(Xt, Yt, params, {"creator": "staregen dp build", "seed": seed,
                                               "dataset_sha256": training.dataset_sha256(X, Y)})
    t.save(out)
    print(f"tables {out}: {t.n} samples ({t.flash_bytes:,} bytes of flash), {t.n_levels} box levels, "
          f"S_limit {params.s_limit}, sha256 {t.sha256[:16]}")
    return 0
