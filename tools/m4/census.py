"""Census of the timing events in one evaluation of an entry point (docs/cycle-model.md).

Every executed instruction is traced (a code hook: slow, for one record) and each event the two
timing tables treat differently is counted, so the gap between `lenient` and `strict` can be
read off a build: taken transfers and those landing on a 32-bit instruction at a halfword
address, literal loads, FP results read by the next instruction, addresses written by the
instruction just before, lone stores, VMOV core<->S, VDIV/VSQRT.
"""
from __future__ import annotations

from collections import Counter

import numpy as np
from unicorn import UC_HOOK_CODE

from tools.m4.decode import Decoder
from tools.m4.elf import Image
from tools.m4.harness import Harness
from tools.m4.machine import FLASH, Machine
from tools.m4.timing import FLOW_COND, FLOW_NONE, entry_extra
from tools.m4.wcet import Analysis

EVENTS = ("instructions", "taken transfers", "taken to a 32-bit halfword target", "literal loads",
          "FP result read by the next instruction", "address written by the instruction just before",
          "store followed by a memory access", "lone store", "VMOV core<->S", "VDIV/VSQRT")


def census(elf, sources, entry: str, record: np.ndarray) -> dict[str, int]:
    """Counts of EVENTS over the call of `entry` while the harness runs one record (the trace
    kept to the code of `entry` and what it calls, found by the static analysis)."""
    image = elf if isinstance(elf, Image) else Image(elf)
    trace: list[int] = []
    machine = Machine(image, install=lambda uc: uc.hook_add(UC_HOOK_CODE, lambda _u, a, _s, _d: trace.append(a)))
    harness = Harness(image, machine=machine)
    ranges = _reachable(Analysis(image, sources), entry)
    trace.clear()
    harness.run(np.ascontiguousarray(record.reshape(1, -1)))
    mine = [a for a in trace if any(lo <= a < hi for lo, hi in ranges)]
    return _count(Decoder(image, (FLASH[0], FLASH[0] + FLASH[1])), mine)


def _reachable(an: Analysis, entry: str) -> list[tuple[int, int]]:
    """Code ranges of `entry` and every function it calls."""
    seen, work, out = set(), [entry], []
    while work:
        fn = work.pop()
        if fn in seen:
            continue
        seen.add(fn)
        blocks = an.graph(fn)
        out += [(b.addr, b.end) for b in blocks.values()]
        work += [b.call for b in blocks.values() if b.call]
    return out


def _count(dec: Decoder, trace: list[int]) -> dict[str, int]:
    n = Counter({e: 0 for e in EVENTS})
    for i, a in enumerate(trace):
        c = dec.insn(a).cost
        n["instructions"] += 1
        text = dec.insn(a).text
        if c.mem and "pc" in c.addr_regs and text.startswith(("ldr", "vldr")):
            n["literal loads"] += 1
        if text.startswith(("vdiv", "vsqrt")):
            n["VDIV/VSQRT"] += 1
        if text.startswith("vmov") and c.cycles == 2 and c.strict == 1:
            n["VMOV core<->S"] += 1
        if i + 1 >= len(trace):
            continue
        nxt_addr = trace[i + 1]
        nxt = dec.insn(nxt_addr).cost
        taken = nxt_addr != a + dec.insn(a).size and c.flow != FLOW_NONE
        if taken or (c.flow not in (FLOW_NONE, FLOW_COND) and nxt_addr == a + dec.insn(a).size):
            n["taken transfers"] += 1
            n["taken to a 32-bit halfword target"] += entry_extra(nxt, nxt_addr)
            continue
        if c.fp_result & nxt.fp_reads:
            n["FP result read by the next instruction"] += 1
        if c.core_writes & nxt.addr_regs:
            n["address written by the instruction just before"] += 1
        if c.store:
            n["store followed by a memory access" if nxt.mem else "lone store"] += 1
    return dict(n)
