"""`staregen tanh codegen|gate`: the old spellings of `codegen --unit tanh` and `verify --unit tanh`
(kept one more release, with a deprecation line)."""
from __future__ import annotations

import argparse

from host.cli import codegen, verify
from host.cli.units import deprecated


def register(subparsers) -> None:
    parser = subparsers.add_parser("tanh", help="deprecated: codegen / verify --unit tanh")
    sub = parser.add_subparsers(dest="tanh_command", required=True, metavar="ACTION")
    gen = sub.add_parser("codegen", help="deprecated: staregen codegen --unit tanh")
    gen.add_argument("--params", required=True, metavar="FILE", help="parameter file (.toml or .json)")
    gen.add_argument("--out", required=True, metavar="DIR", help="output folder (created if needed)")
    gen.add_argument("--period", default=None, metavar="S", help="control period, s (default 0.1)")
    gen.add_argument("--name", default=None, help="entry name (default tanh)")
    gen.set_defaults(func=run_codegen)
    gate = sub.add_parser("gate", help="deprecated: staregen verify --unit tanh")
    gate.add_argument("--params", required=True, metavar="FILE", help="parameter file (.toml or .json)")
    gate.add_argument("--period", default=None, metavar="S", help="control period, s (default 0.1)")
    verify.add_gate_arguments(gate)
    gate.set_defaults(func=run_old_gate, name=None)


def _as_unit(args: argparse.Namespace) -> argparse.Namespace:
    args.unit, args.artifact = "tanh", None
    return args


def run_codegen(args: argparse.Namespace) -> int:
    deprecated("tanh codegen", "codegen --unit tanh")
    return codegen.run(_as_unit(args))


def run_old_gate(args: argparse.Namespace) -> int:
    deprecated("tanh gate", "verify --unit tanh")
    return verify.run_unit_gate(_as_unit(args))
