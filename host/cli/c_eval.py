"""`staregen c-eval --artifact FILE --target golden|x86 --inputs IN.npy --out OUT.npy`.

Evaluates the generated network path (raw inputs -> raw outputs, float32 (N, n_in) -> (N, n_out))
on one target. EVALUATORS is the one place that knows how to run a target: a new target (the
ARM emulator) registers a factory `artifact -> (x -> y)` here and both c-eval and verify use it.
"""
from __future__ import annotations

import argparse
from pathlib import Path
from typing import Callable

import numpy as np

from codegen import artifact as art
from codegen.units.network import golden
from host.errors import HostError
from codegen import atomic

Evaluate = Callable[[np.ndarray], np.ndarray]


def golden_evaluator(a: art.Artifact) -> Evaluate:
    return lambda x: golden.network_eval(a, x)


def x86_evaluator(a: art.Artifact) -> Evaluate:
    from firmware import x86

    return x86.network_library(a).eval


def arm_evaluator(a: art.Artifact) -> Evaluate:
    from firmware import arm

    return arm.network_arm(a).eval


# target name -> factory(artifact) -> evaluate(x (N, n_in) float32) -> y (N, n_out) float32
EVALUATORS: dict[str, Callable[[art.Artifact], Evaluate]] = {
    "golden": golden_evaluator,
    "x86": x86_evaluator,
    "arm": arm_evaluator,
}


def evaluator(target: str, a: art.Artifact) -> Evaluate:
    """Prepare `target` for the artifact (build, load) and return its batch evaluator."""
    if target not in EVALUATORS:
        raise HostError(f"--target: unknown target {target!r} (choose from {', '.join(EVALUATORS)})")
    return EVALUATORS[target](a)


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
    return np.ascontiguousarray(x)


def register(subparsers) -> None:
    parser = subparsers.add_parser("c-eval", help="evaluate the generated network path on a target")
    parser.add_argument("--artifact", required=True, metavar="FILE")
    parser.add_argument("--target", required=True, choices=sorted(EVALUATORS))
    parser.add_argument("--inputs", required=True, metavar="IN.npy", help="float32 (N, n_in), raw units")
    parser.add_argument("--out", required=True, metavar="OUT.npy", help="float32 (N, n_out), raw units")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    a = art.load(args.artifact)
    x = load_inputs(args.inputs, a.n_in)
    y = evaluator(args.target, a)(x)
    with atomic.writing(args.out, suffix=".npy") as tmp:
        np.save(tmp, y)
    print(f"{args.target}: {x.shape[0]} vectors -> {args.out} ({y.dtype} {y.shape})")
    return 0
