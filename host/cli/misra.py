"""`staregen misra [--unit U | --unit all] [--md FILE]`: cppcheck's MISRA C:2012 addon over each
unit's generated C, findings per rule, matched against the deviations documented in docs/misra.md.
Exit 1 while any finding is undocumented."""
from __future__ import annotations

import argparse
from pathlib import Path

from codegen import atomic
from host.cli.units import add_report_unit_arguments, report_units
from tools.misra import check, load_deviations, summary, undocumented

DEVIATIONS = Path(__file__).resolve().parents[2] / "docs" / "misra.md"


def register(subparsers) -> None:
    parser = subparsers.add_parser("misra", help="MISRA C:2012 findings of the generated C (cppcheck addon)",
                                   description=__doc__.splitlines()[0])
    add_report_unit_arguments(parser)
    parser.add_argument("--md", metavar="FILE", help="write the summary as Markdown")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    deviations = load_deviations(DEVIATIONS)
    lines, open_total = ["# MISRA C:2012 findings of the generated C (`staregen misra`)", ""], 0
    for unit in report_units(args):
        findings = check(unit)
        open_total += len(undocumented(findings, deviations))
        lines += summary(unit.kind, findings, deviations)
    print("\n".join(lines))
    if args.md:
        atomic.write_text(args.md, "\n".join(lines) + "\n")
    return 0 if open_total == 0 else 1
