"""Capstone decoding cached per address, and basic blocks with a precomputed static cost."""
from __future__ import annotations

import re
from dataclasses import dataclass

import capstone
from unicorn import UcError

from tools.errors import ToolError
from tools.m4.elf import Image
from capstone.arm_const import ARM_OP_IMM

from tools.m4.timing import FLOW_COND, FLOW_NONE, Cost, cost_of, entry_extra, pair

LINE_SHIFT = 4  # 128-bit flash lines (ART accelerator, flash read width)


@dataclass(frozen=True)
class Insn:
    addr: int
    size: int
    text: str
    cost: Cost
    target: int | None = None   # immediate branch or call target
    conditional: bool = False   # condition code of its own (B<cond>); IT-conditional ones are not


@dataclass
class Block:
    """One dynamic basic block (a Unicorn translation block) with everything static precomputed."""

    addr: int
    size: int
    n: int                # instructions, including ones an IT block may skip
    cost: int             # strict zero-wait-state cycles when no IT instruction executes and no branch is taken
    cost_l: int           # the same under the lenient table
    fall: int             # fall-through address
    flow: int             # FLOW_* of the last instruction (tracker and taken penalty)
    cond_pen: int         # added when the last instruction is a conditional branch and is taken
    fid: int              # function index in Image.functions, -1 if none
    lines: tuple          # flash lines fetched, in order (empty outside flash)
    head: tuple           # (Cost, inside an IT block) of the first instruction
    tail: tuple           # (Cost, inside an IT block) of the last instruction
    entry_s: int          # strict cycles added when a taken branch lands here
    lits: tuple = ()      # flash lines of the literal-pool words its unconditional loads read, in order


class Decoder:
    """Decodes the image's code once per address."""

    def __init__(self, image: Image, flash: tuple[int, int], read=None):
        self.image = image
        self.read = read  # memory reader for code outside the image (e.g. placed in SRAM)
        self.flash = flash
        self.cs = capstone.Cs(capstone.CS_ARCH_ARM, capstone.CS_MODE_THUMB | capstone.CS_MODE_MCLASS)
        self.cs.detail = True
        self._insns: dict[int, Insn] = {}
        self.it_scanned: dict[int, tuple[int, int]] = {}  # filled by scan_it before the first run
        self.it_blocks: dict[int, list] = {}

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
        cost = cost_of(decoded)
        target = None
        if cost.flow != FLOW_NONE:
            imms = [op.imm for op in decoded.operands if op.type == ARM_OP_IMM]
            target = imms[-1] if imms else None
        ins = Insn(addr, decoded.size, f"{decoded.mnemonic} {decoded.op_str}".strip(), cost, target,
                   cost.flow == FLOW_COND)
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
        return self.summarise(addr, size, insns)

    def summarise(self, addr: int, size: int, insns: list[Insn]) -> Block:
        cost_s = cost_l = 0
        it_left, prev, prev_it, head, lits = 0, None, False, None, []
        for ins in insns:
            c = ins.cost
            # Inside an IT block opened in this block, or (a block split by Unicorn) one
            # opened before it, as the static scan found.
            in_it = it_left > 0 or ins.addr in self.it_scanned
            if in_it:
                # Charged 1 as if skipped; a code hook adds the rest when it executes.
                it_left = max(it_left - 1, 0)
                cost_s += 1
                cost_l += 1
            else:
                cost_s += c.strict
                cost_l += c.cycles
                it_left = c.it_count
                lits += literal_lines(ins)
            if prev is not None:
                ds, dl = pair(prev, c, prev_it, in_it)
                cost_s += ds
                cost_l += dl
            if head is None:
                head = (c, in_it)
            prev, prev_it = c, in_it
        last = insns[-1].cost
        cond_pen = last.taken_extra if (last.flow == FLOW_COND and not prev_it) else 0
        lines = ()
        if self.flash[0] <= addr < self.flash[1]:
            lines = tuple(range(addr >> LINE_SHIFT, ((addr + size - 1) >> LINE_SHIFT) + 1))
        return Block(addr, size, len(insns), cost_s, cost_l, addr + size, last.flow, cond_pen,
                     self.image.function_index(addr), lines, head, (last, prev_it),
                     entry_extra(insns[0].cost, addr), tuple(lits))

    def scan_it(self, start: int, size: int) -> dict[int, tuple[int, int]]:
        """IT-conditional instructions of a code range: {addr: (strict, lenient) extra cycles
        when executed} (executed cost - 1, the skipped cost; an executed branch in an IT block
        is taken). Also records each IT block in `it_blocks`: {IT address: [(member address,
        condition, (strict, lenient) extra, whether an earlier member may change the flags,
        whether it may, the literal lines it reads)]}."""
        out, members, it_at, cond_pattern = {}, 0, None, ""
        for ins in self.linear(start, size):
            c = ins.cost
            if members:
                k = len(self.it_blocks[it_at])
                cond = cond_pattern[0] if cond_pattern[k + 1] == "t" else _INVERSE[cond_pattern[0]]
                extra = (c.strict + c.taken_extra - 1, c.cycles + c.taken_extra - 1)
                flags_changed = any(m[4] for m in self.it_blocks[it_at])
                self.it_blocks[it_at].append((ins.addr, cond, extra, flags_changed, _sets_apsr(ins.text),
                                              literal_lines(ins)))
                out[ins.addr] = extra
                members -= 1
                continue
            if c.it_count:
                mnem, _, cond = ins.text.partition(" ")
                members, it_at = c.it_count, ins.addr
                # the condition, then "t" / "e" for each member (the first is always "t")
                cond_pattern = [cond.strip(), "t", *mnem[2:]]
                self.it_blocks[it_at] = []
        self.it_scanned.update(out)
        return out


# Condition codes, their inverses, and whether NZCV (bits 31..28) satisfies each.
_INVERSE = {"eq": "ne", "ne": "eq", "cs": "cc", "hs": "lo", "cc": "cs", "lo": "hs", "mi": "pl", "pl": "mi",
            "vs": "vc", "vc": "vs", "hi": "ls", "ls": "hi", "ge": "lt", "lt": "ge", "gt": "le", "le": "gt",
            "al": "al"}


def condition_holds(cond: str, psr: int) -> bool:
    n, z, c, v = (psr >> 31) & 1, (psr >> 30) & 1, (psr >> 29) & 1, (psr >> 28) & 1
    return {"eq": z == 1, "ne": z == 0, "cs": c == 1, "hs": c == 1, "cc": c == 0, "lo": c == 0,
            "mi": n == 1, "pl": n == 0, "vs": v == 1, "vc": v == 0, "hi": c == 1 and z == 0,
            "ls": c == 0 or z == 1, "ge": n == v, "lt": n != v, "gt": z == 0 and n == v,
            "le": z == 1 or n != v, "al": True}[cond]


def _sets_apsr(text: str) -> bool:
    """Whether an instruction may write the condition flags (then later IT members' conditions
    are not known at the IT instruction)."""
    mnem = text.split()[0]
    return (mnem.startswith(("cmp", "cmn", "tst", "teq", "msr")) or text.startswith("vmrs apsr_nzcv")
            or (len(mnem) > 1 and mnem.split(".")[0].endswith("s") and not mnem.startswith(("vmrs", "vabs", "vmls",
                                                                                               "vnmls", "vfms", "vfnms"))))


_LOADS = re.compile(r"^(ldr|ldm|pop|vldr|vldm|vpop|tbb|tbh)")


def words_read(ins: Insn) -> int:
    """Words an instruction reads from memory (0 for everything but loads)."""
    mnem = ins.text.split()[0]
    if not _LOADS.match(mnem):
        return 0
    if mnem.startswith(("ldm", "pop", "vldm", "vpop")):
        return ins.cost.cycles - 1 - (2 if "pc" in ins.text and mnem.startswith(("ldm", "pop")) else 0)
    return 2 if mnem.startswith("ldrd") or re.match(r"vldr\S* d", ins.text) else 1


def literal_address(ins: Insn) -> int:
    """Address a PC-relative load reads (Align(PC, 4) + imm)."""
    m = re.search(r"\[pc, #(-?0x[0-9a-f]+|-?\d+)\]", ins.text)
    if not m:
        raise ToolError(f"cannot read the literal address of 0x{ins.addr:08x} ({ins.text})")
    return ((ins.addr + 4) & ~3) + int(m.group(1), 0)


def literal_lines(ins: Insn) -> tuple:
    """128-bit flash lines a PC-relative load reads, one per word, in order (empty otherwise)."""
    if "pc" not in ins.cost.addr_regs or not re.search(r"\[pc, #", ins.text) or not words_read(ins):
        return ()
    a = literal_address(ins)
    return tuple((a + 4 * k) >> LINE_SHIFT for k in range(words_read(ins)))
