"""`staregen artifact check FILE`, `staregen artifact random --shape 12-40-3 --seed S --out FILE` and
`staregen artifact standin --out FILE`."""
from __future__ import annotations

import argparse
from pathlib import Path

from codegen import artifact as art
from codegen.errors import CodegenError
from host.errors import HostError
from host.cli.args import parse_int
from host.control.standin import fit_pid_standin


def register(subparsers) -> None:
    parser = subparsers.add_parser("artifact", help="check or create a model artifact (JSON)")
    actions = parser.add_subparsers(dest="action", required=True, metavar="ACTION")

    check = actions.add_parser("check", help="validate an artifact file and print its summary")
    check.add_argument("file", metavar="FILE")
    check.set_defaults(func=run_check)

    random = actions.add_parser("random", help="write a randomly initialised (untrained) artifact")
    random.add_argument("--shape", default="12-40-3", help="N_IN-N_HIDDEN-N_OUT (default 12-40-3)")
    random.add_argument("--seed", default="0", help="random seed (default 0)")
    random.add_argument("--out", required=True, metavar="FILE", help="artifact to write")
    random.set_defaults(func=run_random)

    standin = actions.add_parser("standin", help="write the stand-in network: 12-40-3 fitted to the Table 1 PID law "
                                 "(what `simulate --controller nn-c` flies without --artifact; seconds, not a training)")
    standin.add_argument("--out", required=True, metavar="FILE", help="artifact to write")
    standin.set_defaults(func=run_standin)


def run_check(args: argparse.Namespace) -> int:
    a = art.load(args.file)
    print(f"OK {args.file}: {art.summary(a)}")
    return 0


def writable_artifact_path(out: str) -> Path:
    """--out of a command that writes an artifact: a new file, or an artifact file (ours) it replaces; a
    folder or any other existing file is refused in one line, before any work."""
    path = Path(out)
    if path.is_dir():
        raise HostError(f"--out {out}: is a directory (give a file name)")
    if path.exists():
        try:
            art.load(path)
        except CodegenError:
            raise HostError(f"--out {out}: exists and is not a staregen artifact; not overwritten") from None
    return path


def run_random(args: argparse.Namespace) -> int:
    seed = parse_int(args.seed, "--seed", maximum=2**32 - 1)
    out = writable_artifact_path(args.out)
    a = art.random_artifact(art.parse_shape(args.shape), seed)   # refused before allocating
    path = a.save(out)
    print(f"wrote {path}: {a.shape_text}, seed {seed}, sha256 {a.sha256}")
    return 0


def run_standin(args: argparse.Namespace) -> int:
    out = writable_artifact_path(args.out)
    a = fit_pid_standin()
    path = a.save(out)
    print(f"wrote {path}: {a.shape_text} stand-in fitted to the Table 1 PID law, sha256 {a.sha256}")
    return 0
