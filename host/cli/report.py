"""`staregen report [--evaluate DIR [--tune DIR]] [--rbf DIR ...] [--gp DIR ...] [--basilisk DIR ...] --out DIR`:
report.md, the figures and one self-contained report.html of an evaluation (and a PID tuning, paper 002's and
paper 004's runs, the Basilisk cross-checks), each table beside the paper's."""
from __future__ import annotations

import argparse
from pathlib import Path

from host.errors import HostError
from host.tune.report import write_report


def register(subparsers) -> None:
    p = subparsers.add_parser("report", help="report.md + report.html of a tuning and an evaluation",
                              description=__doc__.splitlines()[0])
    p.add_argument("--evaluate", default=None, metavar="DIR", help="folder written by `staregen evaluate` "
                   "(paper 001's comparison; --evaluate, --rbf or --gp is required)")
    p.add_argument("--rbf", dest="rbf_dirs", action="append", default=[], metavar="DIR",
                   help="folder written by `staregen simulate --controller rbf|rbf-c|rbf-arm` (adds paper 002's "
                        "section; repeatable: e.g. theorem 1, theorem 2, SIL, PIL)")
    p.add_argument("--gp", dest="gp_dirs", action="append", default=[], metavar="DIR",
                   help="folder written by `staregen simulate --controller gp-baseline|gp` (adds paper 004's "
                        "section: baseline against the GP law, both starts; repeatable)")
    p.add_argument("--basilisk", dest="basilisk_dirs", action="append", default=[], metavar="DIR",
                   help="folder written by `staregen basilisk --compare` (adds the Basilisk cross-check: the table and "
                        "the overlay plot; repeatable)")
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
    if args.evaluate is None and not args.rbf_dirs and not args.gp_dirs and not args.basilisk_dirs:
        raise HostError("give --evaluate DIR, --rbf DIR, --gp DIR, --basilisk DIR or several")
    evaluate_dir = Path(args.evaluate) if args.evaluate is not None else None
    if evaluate_dir is not None and not evaluate_dir.is_dir():
        raise HostError(f"--evaluate {evaluate_dir}: not a folder")
    rbf_dirs = [Path(d) for d in args.rbf_dirs]
    for d in rbf_dirs:
        if not d.is_dir():
            raise HostError(f"--rbf {d}: not a folder")
    gp_dirs = [Path(d) for d in args.gp_dirs]
    for d in gp_dirs:
        if not d.is_dir():
            raise HostError(f"--gp {d}: not a folder")
    basilisk_dirs = [Path(d) for d in args.basilisk_dirs]
    for d in basilisk_dirs:
        if not d.is_dir():
            raise HostError(f"--basilisk {d}: not a folder")
    tune_dir = Path(args.tune) if args.tune else None
    if tune_dir is not None and not tune_dir.is_dir():
        raise HostError(f"--tune {tune_dir}: not a folder")
    cal_dir = Path(args.calibration) if args.calibration else None
    if cal_dir is not None and not cal_dir.is_dir():
        raise HostError(f"--calibration {cal_dir}: not a folder")
    if evaluate_dir is None and (tune_dir is not None or cal_dir is not None):
        raise HostError("--tune and --calibration need --evaluate")
    paths = write_report(out, evaluate_dir, tune_dir, args.commands, cal_dir, rbf_dirs, gp_dirs, basilisk_dirs)
    print(f"wrote {paths['md']} and {paths['html']}")
    return 0
