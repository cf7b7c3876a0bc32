"""Cycle reports of an entry point run through the firmware harness, and the micro-benchmarks.

profile_entry() runs classes of input records through the harness under the profiler and
returns, per mode, min/median/max cycles of the entry function per call, the same per function
(inclusive and exclusive, summed over the calls inside one evaluation), the painted stack depth
and the per-class spread. See docs/cycle-model.md for the model itself.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tools.errors import ToolError
from tools.m4.elf import Image
from tools.m4.harness import MAX_INSNS_PER_RECORD, Harness
from tools.m4.profile import MODES, Profiler, lenient_modes

CLOCK_HZ = 168_000_000
PAPER_BUDGET_CYCLES = 554_400  # the paper's 3.3 ms at 168 MHz


def stats(values) -> dict[str, int]:
    v = np.asarray(values, dtype=np.int64)
    if v.size == 0:
        return {"min": 0, "median": 0, "max": 0}
    return {"min": int(v.min()), "median": int(np.median(v)), "max": int(v.max())}


@dataclass
class EntryProfile:
    entry: str
    modes: tuple
    cycles: dict                     # mode -> stats of the entry function per call (strict table)
    cycles_lenient: dict             # the same under the lenient table
    by_class: dict                   # class -> mode -> stats
    functions: dict                  # function -> {"calls", "inclusive", "exclusive", "per_call"}
    stack_painted: int               # bytes below SP at the entry call, measured
    evaluations: int


def profile_entry(elf: str | Path | Image, entry: str, classes: dict[str, np.ndarray],
                  modes=MODES, max_insns_per_record: int = MAX_INSNS_PER_RECORD) -> EntryProfile:
    """classes: {name: (N, in_bytes) uint8 records}. The entry function must be called once per
    record by the harness adapter (directly or through a tail call)."""
    image = elf if isinstance(elf, Image) else Image(elf)
    modes = tuple(m for m in MODES if m in modes)
    prof = Profiler(image, entry, memory_modes=modes != ("ideal",))
    harness = Harness(image, machine=prof.machine, max_insns_per_record=max_insns_per_record)
    per_class, start = {}, 0
    prof.machine.paint_stack()
    for name, records in classes.items():
        harness.reset(runner=prof.run)
        harness.run(records, runner=prof.run)
        if len(prof.evaluations) - start != records.shape[0]:
            raise ToolError(f"{entry}: {len(prof.evaluations) - start} calls for "
                            f"{records.shape[0]} records of class {name} (adapter does not call it once per record)")
        per_class[name] = (start, len(prof.evaluations))
        start = len(prof.evaluations)
    evs = prof.evaluations
    if not evs:
        raise ToolError(f"{entry} was never called")
    painted = min(ev.sp for ev in evs) - prof.machine.lowest_stack_write()
    return EntryProfile(
        entry=entry, modes=modes,
        cycles={m: stats([ev.total[i] for ev in evs]) for i, m in enumerate(MODES) if m in modes},
        cycles_lenient={m: stats([lenient_modes(ev.total)[i] for ev in evs]) for i, m in enumerate(MODES)
                        if m in modes},
        by_class={c: {m: stats([ev.total[i] for ev in evs[a:b]]) for i, m in enumerate(MODES) if m in modes}
                  for c, (a, b) in per_class.items()},
        functions=_function_stats(image, evs, modes),
        stack_painted=max(painted, 0), evaluations=len(evs))


def _function_stats(image: Image, evs, modes) -> dict:
    fids = sorted({fid for ev in evs for fid in ev.calls})
    out = {}
    for fid in fids:
        name = image.functions[fid].name if fid >= 0 else "(no symbol)"
        row = {"calls": stats([ev.calls.get(fid, 0) for ev in evs])}
        for key in ("inclusive", "exclusive"):
            src = "incl" if key == "inclusive" else "excl"
            row[key] = {m: stats([getattr(ev, src).get(fid, [0, 0, 0, 0])[i] for ev in evs])
                        for i, m in enumerate(MODES) if m in modes}
        row["per_call_ideal"] = stats([c for ev in evs for c in ev.per_call.get(fid, [])])
        out[name] = row
    return out


# --------------------------------------------------------------------------- micro-benchmarks

_EXPECT = re.compile(r"^@ bench: (\w+)\n@ lenient: (\d+)\n@ strict: (\d+)$", re.M)
SCRATCH = 0x20000000
SCRATCH_WORDS = 64


def bench_expectations(bench_dir: Path) -> dict[str, dict[str, int]]:
    """{function: {"lenient": cycles, "strict": cycles}} (ideal) from the comments of
    firmware/bench/*.S, where each is derived by hand from the TRM."""
    out = {}
    for path in sorted(bench_dir.glob("*.S")):
        for m in _EXPECT.finditer(path.read_text()):
            out[m.group(1)] = {"lenient": int(m.group(2)), "strict": int(m.group(3))}
    return out


def run_bench(image: Image, name: str, repeat: int = 1) -> list[dict[str, tuple[int, int, int]]]:
    """Cycles of one benchmark per table, {"strict": (ideal, art, pessimistic), "lenient": ...},
    run `repeat` times on one machine (flash caches stay warm between runs), with r0 = a scratch
    buffer of self-pointers."""
    prof = Profiler(image, name)
    out = []
    for _ in range(repeat):
        prof.machine.write(SCRATCH, SCRATCH.to_bytes(4, "little") * SCRATCH_WORDS)
        strict = prof.run(name, (SCRATCH,))
        out.append({"strict": strict, "lenient": prof.lenient})
    return out
