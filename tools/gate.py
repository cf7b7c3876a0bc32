"""The bit-exact gate, written once for every unit: golden == x86 C == ARM C.

For a unit it takes the unit's gate classes (independent steps from chosen states) and, for a
stateful unit, its sequences (consecutive steps from init with the state carried inside the C),
runs the golden model and every target, and compares every output field and the state after
each step as 32-bit patterns, exactly: NaN too (the units emit only the canonical NaN). It also
holds the golden outputs to
the unit's own invariants (e.g. the torque bound) and prints the unit's extra lines (e.g. the
network's float64 reference error).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from codegen import bitcompare
from codegen.unit import Unit
from tools.runners import runner

MAX_LINES = 10


def compare_fields(expected: np.ndarray, actual: np.ndarray, what: str = "") -> list[str]:
    """Every field of two record arrays of one dtype, bit for bit (NaN included); [] if equal."""
    if expected.dtype != actual.dtype or expected.shape != actual.shape:
        return [f"{what}records differ in dtype or shape: {expected.dtype} {expected.shape} vs "
                f"{actual.dtype} {actual.shape}"]
    problems = []
    rows = expected.shape[0] if expected.ndim else 1
    if rows == 0:
        return []
    for name in expected.dtype.names:
        e = np.ascontiguousarray(expected[name]).reshape(rows, -1)
        a = np.ascontiguousarray(actual[name]).reshape(rows, -1)
        if e.dtype == np.float32:
            c = bitcompare.compare(e, a)
            if not c.ok:
                problems.append(f"{what}{name}: " + "; ".join(c.report("golden", "C")))
        elif not np.array_equal(e, a):
            bad = np.argwhere(e != a)
            r, k = bad[0]
            problems.append(f"{what}{name}: {int((e != a).sum())} differences (first row {r} col {k}: "
                            f"golden {int(e[r, k])} != C {int(a[r, k])})")
    return problems


def count_mismatches(expected: np.ndarray, actual: np.ndarray) -> int:
    """Mismatching 32-bit words of two record arrays of one dtype (every bit, NaN included)."""
    e, a = words_of(expected), words_of(actual)
    if e.shape != a.shape:
        return max(e.size, a.size)
    return int((e != a).sum())


def words_of(records: np.ndarray) -> np.ndarray:
    """Record array of any shape -> (rows, words) uint32."""
    r = np.ascontiguousarray(records)
    return r.view(np.uint32).reshape(r.size, -1) if r.size else np.zeros((0, r.dtype.itemsize // 4), np.uint32)


@dataclass
class GateResult:
    ok: bool
    vectors: int
    sequences: int
    steps: int
    counts: dict[str, int]
    seconds: dict[str, float] = field(default_factory=dict)
    problems: dict[str, list[str]] = field(default_factory=dict)
    mismatches: dict[str, int] = field(default_factory=dict)    # target -> mismatching words


def run_gate(unit: Unit, n: int, n_seq: int = 0, steps: int = 1000, seed: int = 0,
             targets=("x86", "arm"), log=print) -> GateResult:
    """Golden vs each target on n independent steps (the unit's classes) and, for a stateful unit,
    n_seq sequences of `steps` steps. Logs the report; returns the result (ok when every bit matches
    and the unit's invariants hold)."""
    start = time.perf_counter()
    classes = {c: b for c, b in unit.gate_classes(n, seed).items() if b.input.shape[0] > 0}
    seqs = unit.gate_sequences(n_seq, steps, seed + 1) if unit.stateful and n_seq > 0 else None
    counts = {c: int(b.input.shape[0]) for c, b in classes.items()}
    made = time.perf_counter()
    seq_text = f", {seqs.shape[0]} sequences x {seqs.shape[1]} steps" if seqs is not None else ""
    log(f"unit {unit.identity()}")
    log(f"vectors: {sum(counts.values())} (" + ", ".join(f"{c} {k}" for c, k in counts.items())
        + f"), seed {seed}{seq_text}; made in {made - start:.2f} s")
    golden = {c: unit.golden(b.state, b.input) for c, b in classes.items()}
    g_seq = unit.golden_sequences(seqs) if seqs is not None else None
    result = GateResult(True, sum(counts.values()), 0 if seqs is None else seqs.shape[0],
                        0 if seqs is None else seqs.shape[1], counts)
    result.seconds["golden"] = round(time.perf_counter() - made, 2)
    outs = {c: o for c, (o, _) in golden.items()}
    summary = [s for s in (unit.describe_outputs(np.concatenate(list(outs.values()))),
                           unit.describe_outputs(g_seq) if g_seq is not None else None) if s]
    log(f"golden: {result.seconds['golden']:.2f} s" + ("; " + "; sequences: ".join(summary) if summary else ""))
    invariants = unit.check_outputs(np.concatenate(list(outs.values())))
    if g_seq is not None:
        invariants += unit.check_outputs(g_seq.reshape(-1))
    if unit.stateful:
        invariants += unit.check_state(np.concatenate([s for _, s in golden.values()]))
    _log_problems(result, "golden", invariants, log, "invariants hold")
    for target in targets:
        t0 = time.perf_counter()
        run = runner(unit, target)
        problems, bad = [], 0
        for c, b in classes.items():
            out, state = run.records(b)
            problems += compare_fields(golden[c][0], out, f"{c}: ")
            bad += count_mismatches(golden[c][0], out)
            if unit.stateful:
                problems += compare_fields(golden[c][1], state, f"{c}: state.")
                bad += count_mismatches(golden[c][1], state)
        for s in range(0 if seqs is None else seqs.shape[0]):
            run.reset()
            out = run.sequence(seqs[s])
            problems += compare_fields(g_seq[s], out, f"sequence {s}: ")
            bad += count_mismatches(g_seq[s], out)
        result.mismatches[target] = bad
        result.seconds[target] = round(time.perf_counter() - t0, 2)
        _log_problems(result, f"{target} vs golden ({result.seconds[target]:.2f} s)", problems, log, "identical")
    for line in unit.extra_report(classes, outs):
        log(line)
    result.seconds["total"] = round(time.perf_counter() - start, 2)
    log(f"total {result.seconds['total']:.2f} s: {'PASS' if result.ok else 'FAIL'}")
    return result


def _log_problems(result: GateResult, what: str, problems: list[str], log, good: str) -> None:
    log(f"{what}: " + (good if not problems else "MISMATCH"))
    for p in problems[:MAX_LINES]:
        log("  " + p)
    if problems:
        result.ok = False
        result.problems[what] = problems

