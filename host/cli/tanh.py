"""`staregen tanh codegen|gate`: the generated C of paper 000's tanh saturation law.

  staregen tanh codegen --params FILE --out DIR [--period S] [--name tanh]
      write <name>.h, <name>.c, sg_math.h, sg_math.c (parameters baked in as float32 constants)
  staregen tanh gate --params FILE [--vectors N] [--sequences S --steps T] [--target x86|arm|all]
      bit-exact gate golden == x86 C == ARM C (host/tanh_gate.py); exit 1 on any mismatch

Parameter files: flat TOML/JSON keys, see docs/tanh-controller.md; errors are one line.
"""
from __future__ import annotations

import argparse
import math

from codegen.units.tanh import emit as tanh_emit
from codegen.units.tanh.params import load_params
from host.errors import HostError

DEFAULT_VECTORS = 100_000


def register(subparsers) -> None:
    parser = subparsers.add_parser("tanh", help="generated C of the paper-000 tanh law: codegen, bit-exact gate")
    sub = parser.add_subparsers(dest="tanh_command", required=True, metavar="ACTION")
    gen = sub.add_parser("codegen", help="write <name>.h/.c + sg_math from a parameter file")
    gen.add_argument("--params", required=True, metavar="FILE", help="parameter file (.toml or .json)")
    gen.add_argument("--out", required=True, metavar="DIR", help="output folder (created if needed)")
    _common(gen)
    gen.add_argument("--name", default=tanh_emit.DEFAULT_NAME, help="entry name (default tanh)")
    gen.set_defaults(func=run_codegen)
    gate = sub.add_parser("gate", help="bit-exact gate golden == x86 == ARM")
    gate.add_argument("--params", required=True, metavar="FILE", help="parameter file (.toml or .json)")
    _common(gate)
    gate.add_argument("--vectors", type=int, default=DEFAULT_VECTORS, metavar="N",
                      help=f"independent (state, input) rows (default {DEFAULT_VECTORS})")
    gate.add_argument("--sequences", type=int, default=8, metavar="S", help="closed-loop sequences (default 8)")
    gate.add_argument("--steps", type=int, default=1000, metavar="T", help="steps per sequence (default 1000)")
    gate.add_argument("--seed", type=int, default=0, help="vector seed (default 0)")
    gate.add_argument("--target", default="all", choices=("x86", "arm", "all"))
    gate.set_defaults(func=run_gate)


def _common(parser) -> None:
    parser.add_argument("--period", type=float, default=tanh_emit.DEFAULT_PERIOD, metavar="S",
                        help=f"control period baked into the Euler update, s (default {tanh_emit.DEFAULT_PERIOD})")


def _period(value: float) -> float:
    if not (math.isfinite(value) and value > 0):
        raise HostError(f"--period must be a positive number of seconds, got {value}")
    return value


def run_codegen(args: argparse.Namespace) -> int:
    params = load_params(args.params)
    for path in tanh_emit.emit_tanh(params, args.out, _period(args.period), args.name):
        print(path)
    return 0


def run_gate(args: argparse.Namespace) -> int:
    from host.tanh_gate import run_gate as gate

    if args.vectors < 7:
        raise HostError(f"--vectors: need at least 7 (one per class), got {args.vectors}")
    if args.sequences < 0 or args.steps < 1:
        raise HostError("--sequences must be >= 0 and --steps >= 1")
    params = load_params(args.params)
    targets = ("x86", "arm") if args.target == "all" else (args.target,)
    ok = gate(params, args.vectors, args.seed, targets, _period(args.period), args.sequences, args.steps)
    return 0 if ok else 1
