"""`staregen package check DIR [--run x86,arm,qemu] [--verify-key FILE]`: a flight package against its manifest.

Every file's sha256 is checked; an edited, missing or extra file (or an entry that is not a
regular file or folder) is named on one line and the exit status is 1. With --run, and only when
every file checks out (nothing of a failing package is configured, compiled or run), the package
is built with its own CMakeLists for each target and `<name>_selftest()` runs: x86-64 natively,
the STM32F417 image in the Cortex-M4 emulator (whose reference step must take the cycles the
manifest records) and in QEMU's netduinoplus2 (whose reference step must give the same output
words as the Cortex-M4 emulator's).

The manifest's seal catches accidents, not tampering (anyone can recompute it). With
--verify-key FILE the manifest's HMAC-SHA256 signature (`generate --sign-key FILE`) must verify
under that key: an unsigned manifest or a wrong key is one line and exit 1.
"""
from __future__ import annotations

import argparse

from codegen.package.manifest import load_key
from host.errors import HostError
from tools.package import RUN_TARGETS, check_package


def register(subparsers) -> None:
    p = subparsers.add_parser("package", help="check a flight package against its manifest",
                              description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="package_command", required=True, metavar="ACTION")
    check = sub.add_parser("check", help="verify every file's sha256; optionally re-run the self-test")
    check.add_argument("folder", metavar="DIR")
    check.add_argument("--run", default="", metavar="TARGETS",
                       help="comma-separated targets to build and run the self-test on: x86, arm (the "
                       "Cortex-M4 emulator), qemu (QEMU's netduinoplus2, compared word for word with arm)")
    check.add_argument("--verify-key", default=None, metavar="FILE",
                       help="key file of `generate --sign-key`: the manifest's HMAC-SHA256 signature must verify")
    check.set_defaults(func=run_check)


def parse_targets(text: str) -> tuple[str, ...]:
    targets = tuple(t.strip() for t in text.split(",") if t.strip())
    for t in targets:
        if t not in RUN_TARGETS:
            raise HostError(f"--run: unknown target {t!r} (choose from {', '.join(RUN_TARGETS)})")
    return tuple(dict.fromkeys(targets))


def run_check(args: argparse.Namespace) -> int:
    targets = parse_targets(args.run)
    key = load_key(args.verify_key) if args.verify_key is not None else None
    doc, problems, runs = check_package(args.folder, targets, key)
    for line in problems:
        print(f"{args.folder}: {line}")
    if problems:
        return 1
    generator = doc.get("generator") if isinstance(doc.get("generator"), dict) else {}
    print(f"{args.folder}: {len(doc['files'])} files match the manifest (package {doc['name']}, "
          f"staregen {str(generator.get('version', '?'))[:20]})" + ("; signature verified" if key else ""))
    for t, r in runs.items():
        cyc = r.get("reference_cycles")
        extra = f"; reference step {cyc['ideal']} ideal / {cyc['art']} art cycles" if cyc else ""
        if t == "qemu":
            extra = f"; reference step output {' '.join(r['reference_output'])} as in the Cortex-M4 emulator " \
                    f"({r['seconds']:.1f} s)"
        print(f"  {t}: self-test 0 mismatching words{extra}")
    return 0
