"""Capstone decoding cached per address, and basic blocks with a precomputed static cost."""
from __future__ import annotations

from dataclasses import dataclass

import capstone
from unicorn import UcError

from tools.errors import ToolError
from tools.m4.elf import Image
from tools.m4.timing import FLOW_COND, Cost, cost_of

LINE_SHIFT = 4  # 128-bit flash lines (ART accelerator, flash read width)


@dataclass(frozen=True)
class Insn:
    addr: int
    size: int
    text: str
    cost: Cost


@dataclass
class Block:
    """One dynamic basic block (a Unicorn translation block) with everything static precomputed."""

    addr: int
    size: int
    n: int                # instructions, including ones an IT block may skip
    cost: int             # zero-wait-state cycles when no IT instruction executes and no branch is taken
    fall: int             # fall-through address
    flow: int             # FLOW_* of the last instruction (tracker and taken penalty)
    cond_pen: int         # added when the last instruction is a conditional branch and is taken
    fid: int              # function index in Image.functions, -1 if none
    lines: tuple          # flash lines fetched, in order (empty outside flash)
    tail_load: frozenset | None  # registers written by a final single load, if any
    head_addr: frozenset | None  # address registers of a leading single load/store, if any


class Decoder:
    """Decodes the image's code once per address."""

    def __init__(self, image: Image, flash: tuple[int, int], read=None):
        self.image = image
        self.read = read  # memory reader for code outside the image (e.g. placed in SRAM)
        self.flash = flash
        self.cs = capstone.Cs(capstone.CS_ARCH_ARM, capstone.CS_MODE_THUMB | capstone.CS_MODE_MCLASS)
        self.cs.detail = True
        self._insns: dict[int, Insn] = {}
        self.it_scanned: dict[int, int] = {}  # filled by scan_it before the first run

    def insn(self, addr: int) -> Insn:
        hit = self._insns.get(addr)
        if hit is not None:
            return hit
        if self._readable(addr, 2):
            code = self.image.read(addr, 4) if self._readable(addr, 4) else self.image.read(addr, 2)
        elif self.read is not None:
            code = self._read_outside(addr)
        else:
            raise ToolError(f"no code at 0x{addr:08x}")
        decoded = next(self.cs.disasm(code, addr, 1), None)
        if decoded is None:
            raise ToolError(f"cannot decode the instruction at 0x{addr:08x}")
        ins = Insn(addr, decoded.size, f"{decoded.mnemonic} {decoded.op_str}".strip(), cost_of(decoded))
        self._insns[addr] = ins
        return ins

    def _read_outside(self, addr: int) -> bytes:
        for size in (4, 2):  # a 16-bit instruction may end its memory region
            try:
                return self.read(addr, size)
            except UcError:  # unmapped
                continue
        raise ToolError(f"no code at 0x{addr:08x}")

    def _readable(self, addr: int, size: int) -> bool:
        return any(s.addr <= addr and addr + size <= s.addr + len(s.data) for s in self.image.segments)

    def linear(self, start: int, size: int) -> list[Insn]:
        """Instructions of a function by linear sweep (literal pools may decode as junk)."""
        out, addr, end = [], start, start + size
        while addr < end:
            try:
                ins = self.insn(addr)
            except ToolError:
                addr += 2
                continue
            out.append(ins)
            addr += ins.size
        return out

    def block(self, addr: int, size: int) -> Block:
        insns, a = [], addr
        while a < addr + size:
            ins = self.insn(a)
            insns.append(ins)
            a += ins.size
        return self._summarise(addr, size, insns)

    def _summarise(self, addr: int, size: int, insns: list[Insn]) -> Block:
        cost, it_left, prev_load, last_in_it = 0, 0, None, False
        head_addr = None
        for i, ins in enumerate(insns):
            c = ins.cost
            # Inside an IT block opened in this block, or (a block split by Unicorn) one
            # opened before it, as the static scan found.
            last_in_it = it_left > 0 or ins.addr in self.it_scanned
            if last_in_it:
                # Charged 1 as if skipped; a code hook adds the rest when it executes.
                it_left = max(it_left - 1, 0)
                cost += 1
                prev_load = None
                continue
            pipelined = c.ldst and prev_load is not None and not (c.addr_regs & prev_load)
            cost += c.cycles - 1 if pipelined else c.cycles
            if i == 0 and c.ldst:
                head_addr = c.addr_regs
            prev_load = c.load_writes if c.load else None
            it_left = c.it_count
        last = insns[-1].cost
        tail_load = last.load_writes if (last.load and not last_in_it) else None
        cond_pen = last.taken_extra if (last.flow == FLOW_COND and not last_in_it) else 0
        lines = ()
        if self.flash[0] <= addr < self.flash[1]:
            lines = tuple(range(addr >> LINE_SHIFT, ((addr + size - 1) >> LINE_SHIFT) + 1))
        return Block(addr, size, len(insns), cost, addr + size, last.flow, cond_pen,
                     self.image.function_index(addr), lines, tail_load, head_addr)

    def scan_it(self, start: int, size: int) -> dict[int, int]:
        """IT-conditional instructions of a code range: {addr: extra cycles when executed}
        (executed cost - 1, the skipped cost; an executed branch in an IT block is taken)."""
        out, it_left = {}, 0
        for ins in self.linear(start, size):
            c = ins.cost
            if it_left:
                it_left -= 1
                out[ins.addr] = c.cycles + c.taken_extra - 1
                continue
            it_left = c.it_count
        self.it_scanned.update(out)
        return out
