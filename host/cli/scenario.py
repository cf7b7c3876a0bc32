"""`staregen scenario list|init|check|seal`: the scenario file (scenario.toml), one reading of
paper 001 Table 6's sensor and actuator errors.

  list                          the known readings with their descriptions
  init [--reading NAME] --out FILE
                                write a reading (default table6) with comments and its seal
  check FILE                    validate every key and the seal; print the reading, the sha256
                                and the resolved errors in SI
  seal FILE                     after a hand edit: validate the values, then rewrite the seal line
Schema: docs/scenario.md.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from host.errors import HostError
from host.plant.error_model import ErrorSource
from host.sim import scenario_file as sf


def register(subparsers) -> None:
    p = subparsers.add_parser("scenario", help="the scenario file (scenario.toml): a reading of Table 6's errors",
                              description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="scenario_command", required=True, metavar="ACTION")
    listing = sub.add_parser("list", help="the known readings")
    listing.set_defaults(func=run_list)
    init = sub.add_parser("init", help="write a reading with comments and its seal")
    init.add_argument("--reading", default=sf.DEFAULT_READING, metavar="NAME",
                      help=f"reading to write (default {sf.DEFAULT_READING}; see `scenario list`)")
    init.add_argument("--out", required=True, metavar="FILE", help="file to write (e.g. scenario.toml)")
    init.add_argument("--force", action="store_true", help="replace an existing file")
    init.set_defaults(func=run_init)
    check = sub.add_parser("check", help="validate a scenario file and its seal")
    check.add_argument("file", metavar="FILE")
    check.set_defaults(func=run_check)
    seal = sub.add_parser("seal", help="re-seal a hand-edited scenario after validating it")
    seal.add_argument("file", metavar="FILE")
    seal.set_defaults(func=run_seal)


def run_list(args: argparse.Namespace) -> int:
    for name, (description, _) in sf.READINGS.items():
        print(f"{name}: {description}")
    return 0


def run_init(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if out.exists() and not args.force:
        raise HostError(f"{out} exists; use --force to replace it")
    scenario = sf.from_reading(args.reading)
    sf.write(scenario, out)
    print(f"{out}: reading {scenario.reading} written (sha256 {scenario.sha256})")
    return 0


def _source_line(name: str, source: ErrorSource, unit: str) -> str:
    bias = ", ".join(f"{x:.6g}" for x in source.bias)
    sigma = ", ".join(f"{x:.6g}" for x in source.sigma)
    return f"  {name}: bias [{bias}] {unit}, sigma (1σ per axis) [{sigma}] {unit}, new draw every {source.period:g} s"


def run_check(args: argparse.Namespace) -> int:
    scenario = sf.load(args.file)
    e = scenario.errors
    print(f"{args.file}: valid, sealed (sha256 {scenario.sha256}); reading {scenario.reading}")
    for keys, source in zip(sf.SOURCES, (e.star, e.gyro, e.wheels)):
        print(_source_line(keys.table, source, keys.si_name))
    return 0


def run_seal(args: argparse.Namespace) -> int:
    digest, changed = sf.seal(args.file)
    print(f"{args.file}: {'sealed' if changed else 'seal already current'} (sha256 {digest})")
    return 0
