"""`staregen fuzz --unit U [--artifact F | --params F] [--n N] [--seed S]`: random-bit records through
the unit's C built with AddressSanitizer + UndefinedBehaviorSanitizer (x86-64), compared word for
word with the golden model; the golden outputs held to the unit's invariants. Exit 1 on any
mismatch, report or invariant problem."""
from __future__ import annotations

import argparse

from tqdm import tqdm

from host.cli.args import parse_int
from host.cli.units import add_unit_arguments, unit_from_args
from tools.fuzz import fuzz

MAX_RECORDS = 100_000_000


def register(subparsers) -> None:
    parser = subparsers.add_parser("fuzz", help="random-bit records: sanitizer C vs golden model",
                                   description=__doc__.splitlines()[0])
    add_unit_arguments(parser)
    parser.add_argument("--n", default="1000000", help="records (default 1,000,000)")
    parser.add_argument("--seed", default="0", help="seed (default 0)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    n = parse_int(args.n, "--n", minimum=1, maximum=MAX_RECORDS)
    seed = parse_int(args.seed, "--seed", maximum=2**63 - 1)
    unit = unit_from_args(args)
    with tqdm(total=n, unit="rec", disable=n < 200_000, leave=False) as bar:
        result = fuzz(unit, n, seed, progress=bar.update)
    for p in result.invariant_problems[:5]:
        print("  " + p)
    return 0 if result.ok else 1
