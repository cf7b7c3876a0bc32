"""`staregen config init|check|seal`: the controller configuration artifact (controller.toml).

  init --out FILE   write the defaults (paper 001 Table 1 gains, Table 6 torque limit, 0.1 s,
                    WGS-84) with comments and their seal
  check FILE        validate every key and the seal; print the values' sha256
  seal FILE         after a hand edit: validate the values, then rewrite the seal line
Schema: docs/controller-config.md.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from codegen.package import config as pc
from host.control.nn_controller import CONFIG_SOURCES, DEFAULT_PACKAGE_NAME, default_package_config
from host.errors import HostError


def register(subparsers) -> None:
    p = subparsers.add_parser("config", help="the controller configuration artifact (controller.toml)",
                              description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="config_command", required=True, metavar="ACTION")
    init = sub.add_parser("init", help="write the default configuration with comments")
    init.add_argument("--out", required=True, metavar="FILE", help="file to write (e.g. controller.toml)")
    init.add_argument("--name", default=DEFAULT_PACKAGE_NAME, help=f"entry-name prefix (default {DEFAULT_PACKAGE_NAME})")
    init.add_argument("--force", action="store_true", help="replace an existing file")
    init.set_defaults(func=run_init)
    check = sub.add_parser("check", help="validate a configuration file and its seal")
    check.add_argument("file", metavar="FILE")
    check.set_defaults(func=run_check)
    seal = sub.add_parser("seal", help="re-seal a hand-edited configuration after validating it")
    seal.add_argument("file", metavar="FILE")
    seal.set_defaults(func=run_seal)


def run_init(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if out.exists() and not args.force:
        raise HostError(f"{out} exists; use --force to replace it")
    try:
        cfg = default_package_config(args.name)
    except pc.ConfigError as exc:
        raise HostError(f"--name: {exc}") from None
    pc.write(cfg, out, CONFIG_SOURCES)
    print(f"{out}: defaults written (sha256 {cfg.sha256})")
    return 0


def run_check(args: argparse.Namespace) -> int:
    cfg = pc.load(args.file)
    c = cfg.controller
    print(f"{args.file}: valid, sealed (sha256 {cfg.sha256}); package {cfg.name}, units {', '.join(cfg.units)}; "
          f"Kp {list(c.kp)}, Ki {list(c.ki)}, Kd {list(c.kd)}, torque limit {c.torque_limit:g} N*m, "
          f"period {c.control_period:g} s, dwell {c.dwell_steps}")
    return 0


def run_seal(args: argparse.Namespace) -> int:
    digest, changed = pc.seal(args.file)
    print(f"{args.file}: {'sealed' if changed else 'seal already current'} (sha256 {digest})")
    return 0
