"""`staregen verify --unit network|controller|tanh|... [--target x86|arm|all] [--vectors N] [--sequences S]`:
the bit-exact gate of a generated unit (tools/gate.py).

Golden model vs the generated C on N seeded vectors in the unit's classes (inside the envelope,
on and around its bounds, outside it, special values, ...) and, for a stateful unit, S sequences
of --steps consecutive steps from init. Every output field and the state are compared as bit
patterns, every bit (NaN outputs are canonical); exit 1 on any mismatch. The old spellings `verify --controller` and
`staregen tanh gate` still work for one release.
"""
from __future__ import annotations

import argparse

from host.cli.args import parse_int
from host.cli.units import add_unit_arguments, deprecated, unit_from_args
from tools.gate import run_gate

DEFAULT_VECTORS = 100_000
MAX_VECTORS = 10_000_000     # ~1 GB of golden temporaries for the largest unit
TARGETS = ("x86", "arm")


def gate_targets(choice: str) -> list[str]:
    """`all` means every C target."""
    return list(TARGETS) if choice == "all" else [choice]


def add_gate_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--target", default="all", choices=[*TARGETS, "all"], help="C target (default all)")
    parser.add_argument("--vectors", default=str(DEFAULT_VECTORS), metavar="N",
                        help=f"independent steps (default {DEFAULT_VECTORS})")
    parser.add_argument("--sequences", default=None, metavar="S",
                        help="stateful units: sequences from init (default 20 for the controller, 8 otherwise)")
    parser.add_argument("--steps", default="1000", metavar="T", help="steps per sequence (default 1000)")
    parser.add_argument("--seed", default="0", help="vector seed (default 0)")


def register(subparsers) -> None:
    parser = subparsers.add_parser("verify", help="bit-exact gate of a generated unit: golden model vs its C")
    add_unit_arguments(parser)
    add_gate_arguments(parser)
    parser.add_argument("--controller", action="store_true", help="deprecated: --unit controller")
    parser.set_defaults(func=run)


def run_unit_gate(args: argparse.Namespace) -> int:
    unit = unit_from_args(args)
    n = parse_int(args.vectors, "--vectors", minimum=1, maximum=MAX_VECTORS)
    default_seq = 20 if unit.kind == "controller" else 8
    n_seq = parse_int(args.sequences, "--sequences", maximum=10_000) if args.sequences is not None else default_seq
    steps = parse_int(args.steps, "--steps", minimum=6, maximum=1_000_000)
    result = run_gate(unit, n, n_seq, steps, parse_int(args.seed, "--seed"), gate_targets(args.target))
    return 0 if result.ok else 1


def run(args: argparse.Namespace) -> int:
    if args.controller:
        deprecated("verify --controller", "verify --unit controller")
        args.unit = "controller"
    return run_unit_gate(args)
