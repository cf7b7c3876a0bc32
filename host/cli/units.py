"""Command-line options shared by every command that works on a generated unit (codegen, verify,
cycles): `--unit` names a registered unit (codegen.units), the input flags bind it, and the host
adds its flight configuration and realistic inputs (host.sim.scenarios.configure_unit)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from codegen import artifact as art
from codegen import units
from codegen.names import name_problem, show
from codegen.unit import Unit
from codegen.units.dp import tables as dp_tables
from host.cli.args import parse_number
from host.errors import HostError
from host.control.nn_controller import load_artifact
from host.sim.scenarios import configure_unit


# the paper-000 example's parameters, found from any working directory
PAPER000_PARAMS = Path(__file__).resolve().parents[2] / "docs" / "tanh_paper000.toml"
PAPER002_PARAMS = Path(__file__).resolve().parents[2] / "docs" / "rbf_paper002.toml"


def add_unit_arguments(parser: argparse.ArgumentParser, default: str = "network") -> None:
    known = units.kinds()
    parser.add_argument("--unit", default=default, choices=sorted(known),
                        help="generated unit: " + "; ".join(f"{k}: {v.summary}" for k, v in sorted(known.items()))
                        + f" (default {default})")
    parser.add_argument("--artifact", metavar="FILE", help="model artifact (units network, controller)")
    parser.add_argument("--params", metavar="FILE", help="the unit's parameter file, .toml/.json (units tanh, rbf)")
    parser.add_argument("--tables", metavar="FILE", help="discrete-point tables (unit dp; `staregen dp build`)")
    parser.add_argument("--period", default=None, metavar="S", help="control period baked into the unit, s "
                        "(units tanh, rbf; default 0.1)")
    parser.add_argument("--name", default=None, help="entry name: files <name>.h/.c, functions <name>_* "
                        "(default: the unit's name)")


def deprecated(old: str, new: str) -> None:
    # stdout: stderr carries exactly one line, and only for an error
    print(f"staregen: '{old}' is deprecated and will be removed; use '{new}'")


def unit_from_args(args: argparse.Namespace) -> Unit:
    """The unit of --unit bound to --artifact / --params / --period / --name; user errors are one line."""
    kind = units.get(args.unit)
    tables = getattr(args, "tables", None)      # `staregen tanh` (deprecated) has no --tables
    given = {"artifact": args.artifact, "params": args.params, "tables": tables}
    for flag, value in given.items():
        if value is not None and flag not in kind.needs:
            raise HostError(f"--{flag} does not apply to unit {args.unit}")
    if args.name is not None and name_problem(args.name):    # the package-name rule: derived entries stay valid
        raise HostError(f"--name: {name_problem(args.name)} (got {show(args.name)})")
    inputs = {"name": args.name}
    if args.period is not None:
        if "params" not in kind.needs or not kind.takes_period:
            raise HostError(f"--period does not apply to unit {args.unit}")
        inputs["period"] = parse_number(args.period, "--period", positive=True)
    if args.params is not None:
        inputs["params"] = kind.load_params(args.params)
    if tables is not None:
        inputs["tables"] = dp_tables.load(tables)
    if args.artifact is not None:
        inputs["artifact"] = art.load(args.artifact)
    elif args.unit == "controller":
        print("unit controller: no --artifact, using the stand-in network fitted to the PID law")
        inputs["artifact"] = load_artifact(None)
    return configure_unit(args.unit, **inputs)


def add_report_unit_arguments(parser: argparse.ArgumentParser) -> None:
    """--unit U|all with the default inputs of a report over units (coverage, MISRA)."""
    parser.add_argument("--unit", default="all", choices=[*sorted(units.kinds()), "all"], help="unit (default all)")
    parser.add_argument("--artifact", metavar="FILE", help="network artifact (default: the stand-in network)")
    parser.add_argument("--params", metavar="FILE", default=str(PAPER000_PARAMS),
                        help="tanh parameters (default the paper-000 example, docs/tanh_paper000.toml)")
    parser.add_argument("--rbf-params", metavar="FILE", default=str(PAPER002_PARAMS),
                        help="rbf-law parameters (default paper 002's, docs/rbf_paper002.toml)")


def report_units(args: argparse.Namespace) -> list[Unit]:
    """The units of --unit (all registered ones for `all`) bound to --artifact / --params /
    --rbf-params, the others to their examples."""
    network = art.load(args.artifact) if args.artifact else load_artifact(None)
    inputs = {"network": {"artifact": network}, "controller": {"artifact": network},
              "tanh": {"params": units.get("tanh").load_params(args.params)},
              "rbf": {"params": units.get("rbf").load_params(args.rbf_params)}}
    kinds = sorted(units.kinds()) if args.unit == "all" else [args.unit]
    return [configure_unit(kind, **inputs.get(kind, units.get(kind).example())) for kind in kinds]
