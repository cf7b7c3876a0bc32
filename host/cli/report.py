"""`staregen report --evaluate DIR [--tune DIR] --out DIR`: report.md, the figures and one
self-contained report.html of an evaluation (and a PID tuning), each table beside the paper's."""
from __future__ import annotations

import argparse
from pathlib import Path

from host.errors import HostError
from host.tune.report import write_report


def register(subparsers) -> None:
    p = subparsers.add_parser("report", help="report.md + report.html of a tuning and an evaluation",
                              description=__doc__.splitlines()[0])
    p.add_argument("--evaluate", required=True, metavar="DIR", help="folder written by `staregen evaluate`")
    p.add_argument("--tune", default=None, metavar="DIR", help="folder written by `staregen tune pid`")
    p.add_argument("--calibration", default=None, metavar="DIR",
                   help="folder written by `staregen calibrate` (adds the section 'Fidelity to paper 001')")
    # dest "commands": "command" is the subcommand's name, which the one-line error prints
    p.add_argument("--command", dest="commands", action="append", default=[],
                   help="a command of the run, to list (repeatable)")
    p.add_argument("--out", required=True, help="report folder (created)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise HostError(f"output folder {out} exists and is not a directory")
    evaluate_dir = Path(args.evaluate)
    if not evaluate_dir.is_dir():
        raise HostError(f"--evaluate {evaluate_dir}: not a folder")
    tune_dir = Path(args.tune) if args.tune else None
    if tune_dir is not None and not tune_dir.is_dir():
        raise HostError(f"--tune {tune_dir}: not a folder")
    cal_dir = Path(args.calibration) if args.calibration else None
    if cal_dir is not None and not cal_dir.is_dir():
        raise HostError(f"--calibration {cal_dir}: not a folder")
    paths = write_report(out, evaluate_dir, tune_dir, args.commands, cal_dir)
    print(f"wrote {paths['md']} and {paths['html']}")
    return 0
