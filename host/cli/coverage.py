"""`staregen coverage [--unit U ... | --unit all] [--vectors N] [--md FILE]`: gcov line and branch
coverage of each unit's generated C under its gate vectors, every untaken branch listed with its
source line (the material of docs/coverage.md)."""
from __future__ import annotations

import argparse

from codegen import atomic, units
from codegen.units.tanh.params import load_params
from host.cli.args import parse_int
from host.control.nn_controller import load_artifact
from host.sim.scenarios import configure_unit
from codegen import artifact as art
from tools.coverage import measure, report_lines


def register(subparsers) -> None:
    parser = subparsers.add_parser("coverage", help="branch coverage of the generated C under the gate vectors",
                                   description=__doc__.splitlines()[0])
    parser.add_argument("--unit", default="all", choices=[*sorted(units.kinds()), "all"], help="unit (default all)")
    parser.add_argument("--artifact", metavar="FILE", help="network artifact (default: the stand-in network)")
    parser.add_argument("--params", metavar="FILE", default="docs/tanh_paper000.toml",
                        help="tanh parameters (default docs/tanh_paper000.toml)")
    parser.add_argument("--vectors", default="20000", help="gate vectors per unit (default 20000)")
    parser.add_argument("--seed", default="0", help="vector seed (default 0)")
    parser.add_argument("--md", metavar="FILE", help="write the report as Markdown")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    n = parse_int(args.vectors, "--vectors", minimum=100, maximum=10_000_000)
    seed = parse_int(args.seed, "--seed", maximum=2**32 - 1)
    network = art.load(args.artifact) if args.artifact else load_artifact(None)
    inputs = {"network": {"artifact": network}, "controller": {"artifact": network},
              "tanh": {"params": load_params(args.params)}}
    kinds = sorted(units.kinds()) if args.unit == "all" else [args.unit]
    lines = ["# Structural coverage of the generated C (`staregen coverage`)", ""]
    for kind in kinds:
        unit = configure_unit(kind, **inputs.get(kind, units.get(kind).example()))
        rep = measure(unit, n, seed=seed)
        lines += report_lines(rep, unit.sources()) + [""]
    text = "\n".join(lines)
    print(text)
    if args.md:
        atomic.write_text(args.md, text + "\n")
    return 0
