"""`staregen verify --artifact FILE --target x86 [--vectors N] [--seed S]`: the bit-exact gate.

Golden model vs the generated C on N seeded vectors (inside the envelope, on and one ulp
around its bounds, outside it, special values). Prints mismatches (count, first few with bit
patterns) and exits 1 on any; also prints the golden model's max error against a float64
reference of the same network over the in-envelope vectors, and the run times.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from codegen import artifact as art
from codegen.units.network import reference
from codegen import bitcompare
from codegen.units.network import golden, vectors
from host.cli.c_eval import EVALUATORS, evaluator
from host.errors import HostError

DEFAULT_VECTORS = 100_000
REFERENCE = "golden"


def gate_targets(choice: str) -> list[str]:
    """`all` means every registered target except the golden model itself."""
    return [t for t in EVALUATORS if t != REFERENCE] if choice == "all" else [choice]


def register(subparsers) -> None:
    parser = subparsers.add_parser("verify", help="bit-exact gate: golden model vs the generated C")
    parser.add_argument("--artifact", required=True, metavar="FILE")
    parser.add_argument("--target", required=True, choices=[*sorted(t for t in EVALUATORS if t != REFERENCE), "all"])
    parser.add_argument("--vectors", type=int, default=DEFAULT_VECTORS, metavar="N",
                        help=f"number of vectors (default {DEFAULT_VECTORS})")
    parser.add_argument("--seed", type=int, default=0, help="vector seed (default 0)")
    parser.add_argument("--controller", action="store_true",
                        help="gate the whole controller step (Fig. 2) instead of the network path: "
                             "N independent steps plus --sequences runs of 1,000 steps")
    parser.add_argument("--sequences", type=int, default=20, metavar="S",
                        help="--controller: sequences of 1,000 consecutive steps (default 20)")
    parser.set_defaults(func=run)


def reference_error(a: art.Artifact, vs: vectors.VectorSet, y_golden: np.ndarray) -> list[str]:
    """Golden vs float64 reference on in-envelope rows: absolute and relative to the output range."""
    inside = vectors.inside_mask(a.envelope, vs.x)
    if not inside.any():
        return ["golden vs float64 reference: no in-envelope vectors"]
    ref = reference.reference_eval64(a, vs.x[inside])
    err = np.abs(y_golden[inside].astype(np.float64) - ref).max(axis=0)
    span = a.output_map.xmax - a.output_map.xmin
    rel = err / np.where(span > 0, span, 1.0)
    per_out = ", ".join(f"{n} {e:.3g} {u}" for n, e, u in zip(a.outputs.names, err, a.outputs.units))
    return [f"golden vs float64 reference ({int(inside.sum())} in-envelope vectors): max |error| {per_out}",
            f"  max |error| / output range: {rel.max():.3g}"]


def compare_target(target: str, a: art.Artifact, x: np.ndarray, y_golden: np.ndarray) -> bool:
    t0 = time.perf_counter()
    evaluate = evaluator(target, a)
    t1 = time.perf_counter()
    y = evaluate(x)
    t2 = time.perf_counter()
    result = bitcompare.compare(y_golden, y)
    print(f"{target}: prepare {t1 - t0:.2f} s, evaluate {t2 - t1:.2f} s")
    for line in result.report("golden", target):
        print(f"{target} vs golden: {line}" if not line.startswith("  ") else line)
    return result.ok


def run_gate(a: art.Artifact, n_vectors: int, seed: int, targets: list[str]) -> bool:
    """Golden vs each target on the gate's vector set; prints the report, returns pass/fail."""
    start = time.perf_counter()
    vs = vectors.gate_vectors(a.envelope, n_vectors, seed)
    counts = ", ".join(f"{k} {v}" for k, v in vs.counts().items())
    print(f"vectors: {vs.x.shape[0]} ({counts}), seed {seed}")
    t0 = time.perf_counter()
    y_golden = golden.network_eval(a, vs.x)
    print(f"golden: evaluate {time.perf_counter() - t0:.2f} s")
    ok = all([compare_target(t, a, vs.x, y_golden) for t in targets])
    for line in reference_error(a, vs, y_golden):
        print(line)
    print(f"total {time.perf_counter() - start:.2f} s: {'PASS' if ok else 'FAIL'}")
    return ok


def run(args: argparse.Namespace) -> int:
    if args.vectors < 1:
        raise HostError(f"--vectors: need at least 1, got {args.vectors}")
    a = art.load(args.artifact)
    print(f"artifact {args.artifact}: {a.shape_text}, sha256 {a.sha256}")
    if args.controller:
        return run_controller_gate(a, args)
    return 0 if run_gate(a, args.vectors, args.seed, gate_targets(args.target)) else 1


def run_controller_gate(a: art.Artifact, args: argparse.Namespace) -> int:
    from host import controller_gate
    from host.nn_controller import flight_config

    if args.sequences < 0:
        raise HostError(f"--sequences: must not be negative, got {args.sequences}")
    start = time.perf_counter()
    ok = controller_gate.run_gate(a, flight_config(), args.vectors, args.sequences, 1000, args.seed,
                                  targets=gate_targets(args.target))
    print(f"total {time.perf_counter() - start:.2f} s: {'PASS' if ok else 'FAIL'}")
    return 0 if ok else 1
