"""The `staregen` command: one subcommand module per stage, registered below.

Each module in COMMANDS exposes `register(subparsers)`, which adds its parser and sets
`func=handler(args) -> int`. User errors (bad input, bad files, missing toolchain) raise one
of the layer error classes and are printed as one line with a non-zero exit, no traceback.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from codegen.errors import CodegenError
from firmware.errors import FirmwareError
from host.errors import HostError
from tools.errors import ToolError

USER_ERRORS = (HostError, CodegenError, FirmwareError, ToolError)

# Subcommand modules, in the order `staregen --help` lists them.
COMMANDS = [
    "host.cli.simulate",
    "host.cli.pipeline",
    "host.cli.samples",
    "host.cli.train",
    "host.cli.artifact",
    "host.cli.codegen",
    "host.cli.config",
    "host.cli.scenario",
    "host.cli.generate",
    "host.cli.package",
    "host.cli.c_eval",
    "host.cli.verify",
    "host.cli.fuzz",
    "host.cli.coverage",
    "host.cli.misra",
    "host.cli.cycles",
    "host.cli.impulse",
    "host.cli.tune",
    "host.cli.evaluate",
    "host.cli.calibrate",
    "host.cli.report",
    "host.cli.tanh",
    "host.cli.dp",
    "host.cli.gp",
    "host.cli.basilisk",
]


class OneLineParser(argparse.ArgumentParser):
    """argparse whose usage errors are one line (not the usage block), exit status 2; every
    subparser inherits it (add_subparsers uses the parent's class)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message.splitlines()[0] if message else 'bad arguments'}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="staregen",
        description="Staring-imaging attitude controllers: design on the ground, generate bit-exact flight C.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:   # --help (0) or a usage error, already printed (2)
        return exc.code if isinstance(exc.code, int) else 2
    try:
        return int(args.func(args) or 0)
    except USER_ERRORS as exc:
        print(f"staregen {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # e.g. `staregen ... | head`: the reader went away; not an error of ours
        sys.stderr.close()
        return 0
    except OSError as exc:   # a file system refusal (a folder in the way, /proc, ...): one line
        where = f": {exc.filename}" if getattr(exc, "filename", None) else ""
        print(f"staregen {args.command}: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"staregen {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
