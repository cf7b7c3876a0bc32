"""The cycle profiler: block hooks with static costs, dynamic corrections, a call-stack tracker.

Per executed block: its precomputed zero-wait-state cost, plus P if the previous block ended in
a conditional branch that was taken (known from this block's address) and, strict, the taken
branch's target-alignment cycle; on a fall-through, the pair rules between the previous block's
last instruction and this block's first (pipelining, strict stalls); plus the flash stalls of
each memory model. IT-conditional instructions are charged 1 statically (their skipped cost); a
code hook on the IT instruction reads the flags and adds the rest for the members that execute
(no hook inside an IT block: it corrupts Unicorn's IT state). Literal-pool reads are known per
block; a memory hook watches only tables left in flash. Both timing tables and all three memory modes are costed in the same run: the
accumulators are strict ideal, strict art, strict pessimistic, lenient ideal (the memory stalls
are the same events under both tables, so lenient art = lenient ideal + art stalls).

Calls are BL/BLX into a block (frame pushed, return address = fall-through of the call);
tail calls are jumps to another function's first instruction (frame pushed with the caller's
return address); frames pop when execution reaches their return address.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from unicorn import UC_HOOK_BLOCK, UC_HOOK_CODE, UC_HOOK_MEM_READ
from unicorn import arm_const as R

from tools.m4.decode import LINE_SHIFT, Decoder, condition_holds
from tools.m4.elf import Image
from tools.m4.machine import FLASH, Machine
from tools.m4.memory import ArtModel, PessimisticModel
from tools.m4.timing import FLOW_CALL, FLOW_JUMP, pair

MODES = ("ideal", "art", "pessimistic")
_NOBLOCK_FALL = -1


@dataclass
class Evaluation:
    """Cycles of one call of the entry function: indices 0 ideal, 1 art, 2 pessimistic (strict
    table), 3 ideal under the lenient table."""

    total: tuple
    sp: int                                       # SP at the entry call
    calls: dict = field(default_factory=dict)     # fid -> number of calls
    incl: dict = field(default_factory=dict)      # fid -> [c0, c1, c2, c3] summed over calls
    excl: dict = field(default_factory=dict)      # fid -> [c0, c1, c2, c3]
    per_call: dict = field(default_factory=dict)  # fid -> list of ideal inclusive per call


class _Prev:
    """Stands in for 'the previous block' at the start of a run."""

    fall = _NOBLOCK_FALL
    flow = 0
    cond_pen = 0
    fid = -1
    addr = -1
    tail = (None, False)


def lenient_modes(total) -> tuple[int, int, int]:
    """(ideal, art, pessimistic) under the lenient table from an accumulator 4-tuple."""
    return total[3], total[3] + total[1] - total[0], total[3] + total[2] - total[0]


_ALIASES = {"sb": "r9", "sl": "r10", "fp": "r11", "ip": "r12"}


def _core_reg(uc, name: str) -> int:
    return uc.reg_read(R.UC_ARM_REG_R0 + int(_ALIASES.get(name, name)[1:]))


class Profiler:
    def __init__(self, image: Image, entry: str, memory_modes: bool = True):
        self.image = image
        self.entry_fid = image.functions.index(image.function(entry))
        self.dec = Decoder(image, (FLASH[0], FLASH[0] + FLASH[1]))
        self.memory_modes = memory_modes
        self.art, self.pess = ArtModel(), PessimisticModel()
        self.blocks: dict[int, object] = {}
        self._pairs: dict[tuple[int, int], tuple[int, int]] = {}  # fall-through pair costs
        self.starts = {f.start for f in image.functions}
        self.evaluations: list[Evaluation] = []
        self.insns = 0
        self._reset_run()
        self.machine = Machine(image, install=self._install)
        self.dec.read = self.machine.read

    # --- set-up --------------------------------------------------------------------------
    def _install(self, uc) -> None:
        uc.hook_add(UC_HOOK_BLOCK, self._on_block)
        for f in self.image.functions:
            if f.start < FLASH[0] or f.start >= FLASH[0] + FLASH[1] or f.size == 0:
                continue
            self.dec.scan_it(f.start, f.size)
        # The executed IT members are found at the IT instruction itself, from the flags: a code
        # hook on an instruction inside an IT block corrupts Unicorn's IT state (unicorn-engine
        # issue 2309: later instructions are skipped; measured here as outputs that differ from
        # an unhooked run).
        for it_addr, members in self.dec.it_blocks.items():
            if any(max(m[2]) > 0 or m[5] for m in members):
                uc.hook_add(UC_HOOK_CODE, self._on_it, members, it_addr, it_addr)
        if self.memory_modes:
            # Literal-pool reads are known per block (Block.lits); only tables left in flash need
            # a memory hook (a hook on reads inside an IT block would corrupt it, see _on_it).
            for o in self.image.flash_objects(FLASH):
                uc.hook_add(UC_HOOK_MEM_READ, self._on_flash_read, None, o.start, o.start + o.size - 1)
            # TBB/TBH read their table from the code: the index register gives the line.
            for f in self.image.functions:
                if FLASH[0] <= f.start < FLASH[0] + FLASH[1] and f.size:
                    for ins in self.dec.linear(f.start, f.size):
                        if ins.text.startswith(("tbb", "tbh")):
                            uc.hook_add(UC_HOOK_CODE, self._on_table_branch, ins, ins.addr, ins.addr)

    def _reset_run(self) -> None:
        self.c0 = self.c1 = self.c2 = self.c3 = 0
        self.prev = _Prev()
        self.stack: list[tuple] = []
        self._new_eval_accumulators()

    def _new_eval_accumulators(self) -> None:
        n = len(self.image.functions) + 1
        self.excl = [[0, 0, 0, 0] for _ in range(n)]
        self.incl = [[0, 0, 0, 0] for _ in range(n)]
        self.ncalls = [0] * n
        self.per_call: dict[int, list] = {}

    # --- hooks (hot path) ----------------------------------------------------------------
    def _on_block(self, uc, addr, size, _data):
        b = self.blocks.get(addr)
        if b is None or b.size != size:
            b = self.blocks[addr] = self.dec.block(addr, size)
        p = self.prev
        cost, cost_l = b.cost, b.cost_l
        # Taken: a new address, or an unconditional transfer to the next one (an IT-conditional
        # call or jump that lands on the next address was skipped).
        if addr != p.fall or (p.flow == FLOW_CALL or p.flow == FLOW_JUMP) and not p.tail[1]:
            if p.cond_pen:
                self._charge(p.fid, p.cond_pen, p.cond_pen)
            cost += b.entry_s
            self._track_flow(uc, p, b, addr)
        else:
            key = (p.addr, addr)
            d = self._pairs.get(key)
            if d is None:
                d = self._pairs[key] = pair(p.tail[0], b.head[0], p.tail[1], b.head[1])
            cost += d[0]
            cost_l += d[1]
        c1 = c2 = cost
        if self.memory_modes and b.lines:
            c1 += self.art.fetch(b.lines)
            c2 += self.pess.fetch(b.lines)
            for ln in b.lits:
                c1 += self.art.data(ln)
                c2 += self.pess.data(ln)
        self.c0 += cost
        self.c1 += c1
        self.c2 += c2
        self.c3 += cost_l
        e = self.excl[b.fid + 1]
        e[0] += cost
        e[1] += c1
        e[2] += c2
        e[3] += cost_l
        self.insns += b.n
        self.prev = b

    def _charge(self, fid, ds, dl):
        """Core cycles (not memory stalls): ds under the strict table, dl under the lenient."""
        self.c0 += ds
        self.c1 += ds
        self.c2 += ds
        self.c3 += dl
        e = self.excl[fid + 1]
        e[0] += ds
        e[1] += ds
        e[2] += ds
        e[3] += dl

    def _on_it(self, uc, addr, size, members):
        """An IT instruction: charge the executed members' extra cycles. A member after one that
        may change the flags is charged as executed (its condition is not known here)."""
        psr = uc.reg_read(R.UC_ARM_REG_XPSR)
        for _addr, cond, extra, flags_changed, _sets, lits in members:
            if flags_changed or condition_holds(cond, psr):
                self._charge(self.prev.fid, extra[0], extra[1])
                if self.memory_modes:
                    for ln in lits:
                        self._flash_line(ln)

    def _on_table_branch(self, uc, addr, size, ins):
        """TBB [Rn, Rm] / TBH [Rn, Rm, lsl #1]: charge the line of the table entry it reads."""
        base, _, index = ins.text.partition("[")[2].rstrip("]").partition(", ")
        rn = addr + 4 if base == "pc" else _core_reg(uc, base)
        offset = _core_reg(uc, index.split(",")[0].strip()) * (2 if ins.text.startswith("tbh") else 1)
        self._flash_line((rn + offset) >> LINE_SHIFT)

    def _on_flash_read(self, uc, access, addr, size, value, _data):
        self._flash_line(addr >> LINE_SHIFT)

    def _flash_line(self, line: int) -> None:
        d1, d2 = self.art.data(line), self.pess.data(line)
        self.c1 += d1
        self.c2 += d2
        e = self.excl[self.prev.fid + 1]
        e[1] += d1
        e[2] += d2

    # --- call-stack tracker --------------------------------------------------------------
    def _track_flow(self, uc, p, b, addr) -> None:
        stack = self.stack
        if p.fall == _NOBLOCK_FALL:  # first block of a run: the called function's root frame
            self._push(uc, b.fid, None)
            return
        while stack and stack[-1][1] == addr:
            self._pop()
        if p.flow == FLOW_CALL:
            self._push(uc, b.fid, p.fall)
        elif b.fid != p.fid and addr in self.starts:
            # A jump into another function's first instruction: a tail call.
            self._push(uc, b.fid, stack[-1][1] if stack else None)

    def _push(self, uc, fid, ret) -> None:
        if fid == self.entry_fid and not any(f[0] == fid for f in self.stack):
            self._new_eval_accumulators()
            self._entry_sp = uc.reg_read(R.UC_ARM_REG_SP)
            # Cold flash caches at every evaluation: the worst case of a control loop in which
            # other code runs between steps.
            self.art, self.pess = ArtModel(), PessimisticModel()
        self.stack.append((fid, ret, self.c0, self.c1, self.c2, self.c3))

    def _pop(self) -> None:
        fid, _ret, s0, s1, s2, s3 = self.stack.pop()
        d = (self.c0 - s0, self.c1 - s1, self.c2 - s2, self.c3 - s3)
        acc = self.incl[fid + 1]
        acc[0] += d[0]
        acc[1] += d[1]
        acc[2] += d[2]
        acc[3] += d[3]
        self.ncalls[fid + 1] += 1
        self.per_call.setdefault(fid, []).append(d[0])
        if fid == self.entry_fid and not any(f[0] == fid for f in self.stack):
            self._close_evaluation(d)

    def _close_evaluation(self, total) -> None:
        ev = Evaluation(total=total, sp=self._entry_sp)
        for i, n in enumerate(self.ncalls):
            if n or any(self.excl[i]):
                fid = i - 1
                ev.calls[fid] = n
                ev.incl[fid] = list(self.incl[i])
                ev.excl[fid] = list(self.excl[i])
                ev.per_call[fid] = self.per_call.get(fid, [])
        self.evaluations.append(ev)

    # --- runs ----------------------------------------------------------------------------
    def run(self, fn: str, args: tuple = (), max_insns: int = 50_000_000) -> tuple[int, int, int]:
        """Call fn under the profiler; returns its strict cycles per mode (ideal, art, pessimistic);
        `lenient` then holds the same under the lenient table."""
        self._reset_run()
        self.machine.call(fn, args, max_insns=max_insns)
        self._finish()
        self.lenient = lenient_modes((self.c0, self.c1, self.c2, self.c3))
        return self.c0, self.c1, self.c2

    def _finish(self) -> None:
        """The last return goes to the magic address, where no block runs: pop what is left."""
        while self.stack:
            self._pop()
