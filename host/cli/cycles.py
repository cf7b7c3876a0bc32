"""`staregen cycles --unit network|controller|tanh|... [--artifact F | --params F] [--mode ideal|art|pessimistic|all]
[--per-class N] [--json FILE] [--md FILE]`: Cortex-M4 cycles, flash, RAM and stack of a unit's step.

Builds the unit's STM32F417 ELF, runs its input classes through the harness in the emulator under
the cycle model (tools/report.py), and reports per class and per function min / median / max
cycles, µs at 168 MHz, the share of the paper's 3.3 ms, flash, RAM, the worst-case stack (static
bound, cross-checked by stack painting) and the unit's budgets. `--entry` is the old spelling of
`--unit` (one more release).
"""
from __future__ import annotations

import argparse

from codegen import atomic
from host.cli.args import parse_int
from host.cli.units import add_unit_arguments, deprecated, unit_from_args
from tools.m4.profile import MODES
from tools.report import cycle_report, cycle_text

DEFAULT_PER_CLASS = 250


def register(subparsers) -> None:
    parser = subparsers.add_parser("cycles", help="cycle, memory and stack report of a unit's ARM build (emulated Cortex-M4)")
    add_unit_arguments(parser)
    parser.add_argument("--entry", default=None, help="deprecated: --unit")
    parser.add_argument("--mode", default="ideal", choices=[*MODES, "all"],
                        help="flash memory model (default ideal: 0 wait states); all = the three")
    parser.add_argument("--per-class", default=str(DEFAULT_PER_CLASS), metavar="N",
                        help=f"vectors per input class (default {DEFAULT_PER_CLASS})")
    parser.add_argument("--seed", default="0", help="vector seed (default 0)")
    parser.add_argument("--json", metavar="FILE", help="write the report as JSON")
    parser.add_argument("--md", metavar="FILE", help="write the report as Markdown")
    parser.set_defaults(func=run)


def publish(args: argparse.Namespace, name: str, entry: dict, lines: list[str]) -> int:
    """Print the report; write it as JSON ({"entries": {name: entry}}) and Markdown when asked."""
    print("\n".join(lines))
    if args.json:
        atomic.write_json(args.json, {"entries": {name: entry}})
        print(f"wrote {args.json}")
    if args.md:
        atomic.write_text(args.md, f"# Cycle report: {entry['identity']}\n\n" + "\n".join(lines) + "\n")
        print(f"wrote {args.md}")
    return 0


def run(args: argparse.Namespace) -> int:
    if args.entry is not None:
        deprecated(f"cycles --entry {args.entry}", f"cycles --unit {args.entry}")
        args.unit = args.entry
    per_class = parse_int(args.per_class, "--per-class", minimum=1, maximum=100_000)
    modes = MODES if args.mode == "all" else (args.mode,)
    unit = unit_from_args(args)
    rep = cycle_report(unit, modes, per_class, parse_int(args.seed, "--seed"))
    return publish(args, unit.kind, rep, cycle_text(rep))
