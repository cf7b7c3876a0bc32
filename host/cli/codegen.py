"""`staregen codegen --unit network|controller|tanh|... [--artifact F | --params F] --out DIR [--name N]`:
write the flight C of a generated unit (its .h/.c files and the sg_math library they call)."""
from __future__ import annotations

import argparse

from codegen.cgen import write_sources
from host.cli.units import add_unit_arguments, unit_from_args


def register(subparsers) -> None:
    parser = subparsers.add_parser("codegen", help="generate the flight C of a unit (default: the network path)")
    add_unit_arguments(parser)
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder (created if needed)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    for path in write_sources(unit_from_args(args).sources(), args.out):
        print(path)
    return 0
