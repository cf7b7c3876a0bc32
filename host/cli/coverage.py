"""`staregen coverage [--unit U | --unit all] [--vectors N] [--md FILE]`: gcov line and branch
coverage of each unit's generated C under its gate vectors, every untaken branch listed with its
source line (docs/coverage-report.md; the triage is docs/coverage.md)."""
from __future__ import annotations

import argparse

from codegen import atomic
from host.cli.args import parse_int
from host.cli.units import add_report_unit_arguments, report_units
from tools.coverage import measure, report_lines
from tools.coverage_library import library_lines, measure_library


def register(subparsers) -> None:
    parser = subparsers.add_parser("coverage", help="branch coverage of the generated C under the gate vectors",
                                   description=__doc__.splitlines()[0])
    add_report_unit_arguments(parser)
    parser.add_argument("--vectors", default="20000", help="gate vectors per unit (default 20000)")
    parser.add_argument("--seed", default="0", help="vector seed (default 0)")
    parser.add_argument("--md", metavar="FILE", help="write the report as Markdown (docs/coverage-report.md)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    n = parse_int(args.vectors, "--vectors", minimum=100, maximum=10_000_000)
    seed = parse_int(args.seed, "--seed", maximum=2**32 - 1)
    lines = ["# Structural coverage of the generated C (`staregen coverage`)", ""]
    for unit in report_units(args):
        lines += report_lines(measure(unit, n, seed=seed), unit.sources()) + [""]
    mismatches = 0
    if args.unit == "all":
        lib = measure_library(n, seed=seed)
        mismatches = sum(lib.mismatches.values())
        lines += library_lines(lib) + [""]
    text = "\n".join(lines)
    print(text)
    if args.md:
        atomic.write_text(args.md, text + "\n")
    return 0 if mismatches == 0 else 1
