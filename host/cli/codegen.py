"""`staregen codegen --artifact FILE --out DIR [--name network]`: emit the flight C of the network path."""
from __future__ import annotations

import argparse

from codegen import artifact as art
from codegen.units.network import emit


def register(subparsers) -> None:
    parser = subparsers.add_parser("codegen", help="generate the flight C (network path + sg_math) from an artifact")
    parser.add_argument("--artifact", required=True, metavar="FILE")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder (created if needed)")
    parser.add_argument("--name", default=emit.DEFAULT_NAME,
                        help="entry name: files <name>.h/.c, functions <name>_* (default network)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    a = art.load(args.artifact)
    for path in emit.emit(a, args.out, args.name):
        print(path)
    return 0
