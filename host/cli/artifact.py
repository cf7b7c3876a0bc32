"""`staregen artifact check FILE` and `staregen artifact random --shape 12-40-3 --seed S --out FILE`."""
from __future__ import annotations

import argparse

from codegen import artifact as art
from host.cli.args import parse_int, shown
from host.errors import HostError


def register(subparsers) -> None:
    parser = subparsers.add_parser("artifact", help="check or create a model artifact (JSON)")
    actions = parser.add_subparsers(dest="action", required=True, metavar="ACTION")

    check = actions.add_parser("check", help="validate an artifact file and print its summary")
    check.add_argument("file", metavar="FILE")
    check.set_defaults(func=run_check)

    random = actions.add_parser("random", help="write a randomly initialised (untrained) artifact")
    random.add_argument("--shape", default="12-40-3", help="N_IN-N_HIDDEN-N_OUT (default 12-40-3)")
    random.add_argument("--seed", default="0", help="random seed (default 0)")
    random.add_argument("--out", required=True, metavar="FILE", help="artifact to write")
    random.set_defaults(func=run_random)


def run_check(args: argparse.Namespace) -> int:
    a = art.load(args.file)
    print(f"OK {args.file}: {art.summary(a)}")
    return 0


# What 1 MB of the STM32F417's flash holds as float32 weights: a bigger network cannot fly, and refusing
# it here keeps `--shape 10000-10000-10000` from allocating gigabytes before anything is checked.
MAX_WEIGHTS = 1 << 18


def parse_shape(text: str) -> tuple[int, int, int]:
    """--shape N_IN-N_HIDDEN-N_OUT: three integers in ASCII digits, each layer at most the artifact's
    MAX_LAYER_SIZE, the weights and biases together at most MAX_WEIGHTS."""
    parts = text.split("-")
    if len(parts) != 3:
        raise HostError(f"--shape: expected N_IN-N_HIDDEN-N_OUT (e.g. 12-40-3), got {shown(text)}")
    n_in, n_hidden, n_out = (parse_int(p, "--shape: a layer size", minimum=1, maximum=art.MAX_LAYER_SIZE)
                             for p in parts)
    weights = n_hidden * (n_in + 1) + n_out * (n_hidden + 1)
    if weights > MAX_WEIGHTS:
        raise HostError(f"--shape {n_in}-{n_hidden}-{n_out}: {weights:,} weights and biases, more than the "
                        f"{MAX_WEIGHTS:,} that fit in 1 MB of flash as float32")
    return n_in, n_hidden, n_out


def run_random(args: argparse.Namespace) -> int:
    seed = parse_int(args.seed, "--seed", maximum=2**32 - 1)
    a = art.random_artifact(parse_shape(args.shape), seed)
    path = a.save(args.out)
    print(f"wrote {path}: {a.shape_text}, seed {seed}, sha256 {a.sha256}")
    return 0
