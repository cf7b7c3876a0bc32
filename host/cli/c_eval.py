"""`staregen c-eval --artifact FILE --target golden|x86|arm --inputs IN.npy --out OUT.npy`.

Evaluates the network unit (raw inputs -> raw outputs, float32 (N, n_in) -> (N, n_out)) on one
target through the one runner of each target (tools/runners.py).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from codegen import artifact as art
from codegen import atomic
from codegen.unit import Batch
from codegen.units.network.unit import NetworkUnit
from host.errors import HostError
from tools.runners import TARGETS, runner


def evaluate(a: art.Artifact, target: str, x: np.ndarray) -> np.ndarray:
    """The network path of `a` on `target`: float32 (N, n_in) -> float32 (N, n_out)."""
    unit = NetworkUnit(a)
    rec = np.zeros(x.shape[0], dtype=unit.input_dtype)
    rec["x"] = x
    out, _ = runner(unit, target).records(Batch(None, rec))
    return np.ascontiguousarray(out["y"])


def load_inputs(path: str, n_in: int) -> np.ndarray:
    """A float32 (N, n_in) array from .npy; anything else is refused, not converted."""
    p = Path(path)
    if not p.is_file():
        raise HostError(f"--inputs: {path}: no such file")
    try:
        x = np.load(p, allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise HostError(f"--inputs: {path}: not a .npy array ({exc})") from None
    if not isinstance(x, np.ndarray) or x.dtype != np.float32 or x.ndim != 2 or x.shape[1] != n_in:
        got = f"{x.dtype} {x.shape}" if isinstance(x, np.ndarray) else type(x).__name__
        raise HostError(f"--inputs: {path}: expected a float32 array of shape (N, {n_in}), got {got}")
    if x.shape[0] == 0:
        raise HostError(f"--inputs: {path}: no rows (shape {x.shape})")
    return np.ascontiguousarray(x)


def register(subparsers) -> None:
    parser = subparsers.add_parser("c-eval", help="evaluate the generated network path on a target")
    parser.add_argument("--artifact", required=True, metavar="FILE")
    parser.add_argument("--target", required=True, choices=TARGETS)
    parser.add_argument("--inputs", required=True, metavar="IN.npy", help="float32 (N, n_in), raw units")
    parser.add_argument("--out", required=True, metavar="OUT.npy", help="float32 (N, n_out), raw units")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    a = art.load(args.artifact)
    x = load_inputs(args.inputs, a.n_in)
    y = evaluate(a, args.target, x)
    with atomic.writing(args.out, suffix=".npy") as tmp:
        np.save(tmp, y)
    print(f"{args.target}: {x.shape[0]} vectors -> {args.out} ({y.dtype} {y.shape})")
    return 0
