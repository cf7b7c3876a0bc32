"""`staregen misra [--unit U | --unit all] [--md FILE]`: cppcheck's MISRA C:2012 addon over each
unit's generated C, findings per rule, matched against the deviations documented in docs/misra.md.
Exit 1 while any finding is undocumented."""
from __future__ import annotations

import argparse
from pathlib import Path

from codegen import atomic, units
from codegen import artifact as art
from codegen.units.tanh.params import load_params
from host.control.nn_controller import load_artifact
from host.sim.scenarios import configure_unit
from tools.misra import check, load_deviations, summary, undocumented

DEVIATIONS = Path(__file__).resolve().parents[2] / "docs" / "misra.md"


def register(subparsers) -> None:
    parser = subparsers.add_parser("misra", help="MISRA C:2012 findings of the generated C (cppcheck addon)",
                                   description=__doc__.splitlines()[0])
    parser.add_argument("--unit", default="all", choices=[*sorted(units.kinds()), "all"], help="unit (default all)")
    parser.add_argument("--artifact", metavar="FILE", help="network artifact (default: the stand-in network)")
    parser.add_argument("--params", metavar="FILE", default="docs/tanh_paper000.toml", help="tanh parameters")
    parser.add_argument("--md", metavar="FILE", help="write the summary as Markdown")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    network = art.load(args.artifact) if args.artifact else load_artifact(None)
    inputs = {"network": {"artifact": network}, "controller": {"artifact": network},
              "tanh": {"params": load_params(args.params)}}
    deviations = load_deviations(DEVIATIONS)
    kinds = sorted(units.kinds()) if args.unit == "all" else [args.unit]
    lines, open_total = ["# MISRA C:2012 findings of the generated C (`staregen misra`)", ""], 0
    for kind in kinds:
        findings = check(configure_unit(kind, **inputs.get(kind, units.get(kind).example())))
        open_total += len(undocumented(findings, deviations))
        lines += summary(kind, findings, deviations)
    print("\n".join(lines))
    if args.md:
        atomic.write_text(args.md, "\n".join(lines) + "\n")
    return 0 if open_total == 0 else 1
