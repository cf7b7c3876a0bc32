"""The cycle profiler: block hooks with static costs, dynamic corrections, a call-stack tracker.

Per executed block: its precomputed zero-wait-state cost, plus P if the previous block ended in
a conditional branch that was taken (known from this block's address), minus 1 if it starts
with a load/store pipelined behind the previous block's final load (fall-through only), plus
the flash stalls of each memory model. IT-conditional instructions are charged 1 statically
(their skipped cost); a code hook on each costlier one adds the rest when it executes (Unicorn
fires no hook for skipped ones). All three memory modes are costed in the same run.

Calls are BL/BLX into a block (frame pushed, return address = fall-through of the call);
tail calls are jumps to another function's first instruction (frame pushed with the caller's
return address); frames pop when execution reaches their return address.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from unicorn import UC_HOOK_BLOCK, UC_HOOK_CODE, UC_HOOK_MEM_READ
from unicorn import arm_const as R

from tools.m4.decode import LINE_SHIFT, Decoder
from tools.m4.elf import Image
from tools.m4.machine import FLASH, Machine
from tools.m4.memory import ArtModel, PessimisticModel
from tools.m4.timing import FLOW_CALL

MODES = ("ideal", "art", "pessimistic")
_NOBLOCK_FALL = -1


@dataclass
class Evaluation:
    """Cycles of one call of the entry function, per mode index (0 ideal, 1 art, 2 pessimistic)."""

    total: tuple
    sp: int                                       # SP at the entry call
    calls: dict = field(default_factory=dict)     # fid -> number of calls
    incl: dict = field(default_factory=dict)      # fid -> [c0, c1, c2] summed over calls
    excl: dict = field(default_factory=dict)      # fid -> [c0, c1, c2]
    per_call: dict = field(default_factory=dict)  # fid -> list of ideal inclusive per call


class _Prev:
    """Stands in for 'the previous block' at the start of a run."""

    fall = _NOBLOCK_FALL
    flow = 0
    cond_pen = 0
    tail_load = None
    fid = -1


class Profiler:
    def __init__(self, image: Image, entry: str, memory_modes: bool = True):
        self.image = image
        self.entry_fid = image.functions.index(image.function(entry))
        self.dec = Decoder(image, (FLASH[0], FLASH[0] + FLASH[1]))
        self.memory_modes = memory_modes
        self.art, self.pess = ArtModel(), PessimisticModel()
        self.blocks: dict[int, object] = {}
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
            for addr, extra in self.dec.scan_it(f.start, f.size).items():
                if extra > 0:
                    uc.hook_add(UC_HOOK_CODE, self._on_it_executed, extra, addr, addr)
        if self.memory_modes:
            uc.hook_add(UC_HOOK_MEM_READ, self._on_flash_read, None, FLASH[0], FLASH[0] + FLASH[1] - 1)

    def _reset_run(self) -> None:
        self.c0 = self.c1 = self.c2 = 0
        self.prev = _Prev()
        self.stack: list[tuple] = []
        self._new_eval_accumulators()

    def _new_eval_accumulators(self) -> None:
        n = len(self.image.functions) + 1
        self.excl = [[0, 0, 0] for _ in range(n)]
        self.incl = [[0, 0, 0] for _ in range(n)]
        self.ncalls = [0] * n
        self.per_call: dict[int, list] = {}

    # --- hooks (hot path) ----------------------------------------------------------------
    def _on_block(self, uc, addr, size, _data):
        b = self.blocks.get(addr)
        if b is None or b.size != size:
            b = self.blocks[addr] = self.dec.block(addr, size)
        p = self.prev
        if addr != p.fall:
            if p.cond_pen:
                self._charge(p.fid, p.cond_pen, p.cond_pen, p.cond_pen)
            self._track_flow(uc, p, b, addr)
        cost = b.cost
        if p.tail_load is not None and b.head_addr is not None and addr == p.fall \
                and not (b.head_addr & p.tail_load):
            cost -= 1
        c1 = c2 = cost
        if self.memory_modes and b.lines:
            c1 += self.art.fetch(b.lines)
            c2 += self.pess.fetch(b.lines)
        self.c0 += cost
        self.c1 += c1
        self.c2 += c2
        e = self.excl[b.fid + 1]
        e[0] += cost
        e[1] += c1
        e[2] += c2
        self.insns += b.n
        self.prev = b

    def _charge(self, fid, d0, d1, d2):
        self.c0 += d0
        self.c1 += d1
        self.c2 += d2
        e = self.excl[fid + 1]
        e[0] += d0
        e[1] += d1
        e[2] += d2

    def _on_it_executed(self, uc, addr, size, extra):
        self._charge(self.prev.fid, extra, extra, extra)

    def _on_flash_read(self, uc, access, addr, size, value, _data):
        line = addr >> LINE_SHIFT
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
        self.stack.append((fid, ret, self.c0, self.c1, self.c2))

    def _pop(self) -> None:
        fid, _ret, s0, s1, s2 = self.stack.pop()
        d = (self.c0 - s0, self.c1 - s1, self.c2 - s2)
        acc = self.incl[fid + 1]
        acc[0] += d[0]
        acc[1] += d[1]
        acc[2] += d[2]
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
        """Call fn under the profiler; returns its total cycles per mode (ideal, art, pessimistic)."""
        self._reset_run()
        self.machine.call(fn, args, max_insns=max_insns)
        self._finish()
        return self.c0, self.c1, self.c2

    def _finish(self) -> None:
        """The last return goes to the magic address, where no block runs: pop what is left."""
        while self.stack:
            self._pop()
