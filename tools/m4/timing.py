"""Cortex-M4 cycle costs of one decoded instruction, in two tables (SPEC section 7).

`lenient` is the first model: TRM r0p1 table 3-1 and the FPU instruction table, P = 2, loads
pipelining behind a load. `strict` (the default) adds the TRM's stall rules the first model left
out, each at its conservative reading (docs/cycle-model.md, "Timing-table audit"):

- an FP arithmetic result (add, subtract, multiply, MAC, divide, square root, conversion) read by
  the very next instruction: +1 (TRM 7.2.3);
- a load/store whose address register was written by the instruction just before: +1 (no
  forwarding from the ALU to the address generation unit, TRM 3.3.3);
- a taken branch to a 32-bit instruction at a halfword address: P = 3 instead of 2 (TRM 3.3.1);
- LDR/VLDR with a PC-relative (literal) address: +1 (fetch contention, TRM 3.3.3);
- LDR PC 5 (2 + P at P = 3), TBB/TBH 6;
- VMOV between one core and one S register 1 (FPU table), not 2;
- a single-register STR 1 (the data phase overlaps the next instruction), +1 when the next
  instruction accesses memory (nothing pipelines after a store); 2 with a register offset.

Costs are for zero wait states. What depends on the executed path (a conditional branch taken, an
IT-skipped instruction, the instruction that follows, flash wait states) is resolved by the caller
from the fields of `Cost`: `pair()` for two consecutive instructions, `entry_extra()` for the
target of a taken branch.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, replace

from capstone import arm_const as A

STRICT, LENIENT = "strict", "lenient"
TABLES = (STRICT, LENIENT)

# Pipeline refill after a taken branch or any write to PC (TRM: 1..3, nominal 2).
P = 2

# SDIV/UDIV take 2..12 cycles depending on the operands; the model charges the worst case.
DIV_CYCLES = 12

_SINGLE_LOADS = {A.ARM_INS_LDR, A.ARM_INS_LDRB, A.ARM_INS_LDRH, A.ARM_INS_LDRSB,
                 A.ARM_INS_LDRSH, A.ARM_INS_LDRT, A.ARM_INS_LDRBT, A.ARM_INS_LDRHT,
                 A.ARM_INS_LDRSBT, A.ARM_INS_LDRSHT, A.ARM_INS_LDREX, A.ARM_INS_LDREXB,
                 A.ARM_INS_LDREXH, A.ARM_INS_VLDR}
_SINGLE_STORES = {A.ARM_INS_STR, A.ARM_INS_STRB, A.ARM_INS_STRH, A.ARM_INS_STRT,
                  A.ARM_INS_STRBT, A.ARM_INS_STRHT, A.ARM_INS_STREX, A.ARM_INS_STREXB,
                  A.ARM_INS_STREXH, A.ARM_INS_VSTR}
_DOUBLE_LDST = {A.ARM_INS_LDRD, A.ARM_INS_STRD}
_MULTI = {A.ARM_INS_LDM, A.ARM_INS_LDMDB, A.ARM_INS_POP, A.ARM_INS_STM, A.ARM_INS_STMDB,
          A.ARM_INS_PUSH}
_VMULTI = {A.ARM_INS_VLDMIA, A.ARM_INS_VLDMDB, A.ARM_INS_VSTMIA, A.ARM_INS_VSTMDB,
           A.ARM_INS_VPUSH, A.ARM_INS_VPOP}
_FP_14 = {A.ARM_INS_VDIV, A.ARM_INS_VSQRT}
_FP_MAC = {A.ARM_INS_VMLA, A.ARM_INS_VMLS, A.ARM_INS_VNMLA, A.ARM_INS_VNMLS,
           A.ARM_INS_VFMA, A.ARM_INS_VFMS, A.ARM_INS_VFNMA, A.ARM_INS_VFNMS}
# FP arithmetic whose result costs a cycle more when the next instruction reads it (TRM 7.2.3:
# add, subtract, multiply, divide, square root, every multiply-accumulate, every conversion).
_FP_ARITH = {A.ARM_INS_VADD, A.ARM_INS_VSUB, A.ARM_INS_VMUL, A.ARM_INS_VNMUL, *_FP_MAC, *_FP_14,
             *(getattr(A, n) for n in dir(A) if n.startswith("ARM_INS_VCVT"))}
_DIV = {A.ARM_INS_SDIV, A.ARM_INS_UDIV}
_CALLS = {A.ARM_INS_BL, A.ARM_INS_BLX}
_TABLE_BRANCH = {A.ARM_INS_TBB, A.ARM_INS_TBH}
_CBZ = {A.ARM_INS_CBZ, A.ARM_INS_CBNZ}

_CORE_REG = re.compile(r"^(r\d+|sb|sl|fp|ip|sp|lr|pc)$")
_FP_REG = re.compile(r"^([sd])(\d+)$")

# Control-flow kinds, used by the call-stack tracker and for the taken-branch penalty.
FLOW_NONE, FLOW_CALL, FLOW_JUMP, FLOW_COND = 0, 1, 2, 3

_NONE = frozenset()


@dataclass(frozen=True)
class Cost:
    """Static timing facts of one instruction."""

    cycles: int            # lenient cost when executed, zero wait states, not pipelined, not taken
    strict: int            # the same under the strict table
    flow: int              # FLOW_*: how it changes the PC
    taken_extra: int       # added when a conditional branch is taken (P), else 0
    load: bool             # single-register load: a following independent ld/st pipelines
    ldst: bool             # single-register load or store: can pipeline behind a load
    addr_regs: frozenset   # core registers forming the address (every memory access)
    load_writes: frozenset # registers a single load writes (destination and base write-back)
    it_count: int          # for IT: how many following instructions it makes conditional
    size: int = 2          # bytes (a 32-bit target of a taken branch may cost P = 3)
    strict_gain: int = 1   # strict: cycles saved when pipelined behind a load
    store: bool = False    # single-register store: strict +1 when the next one accesses memory
    mem: bool = False      # accesses memory (loads, stores, multiples, table branches)
    fp_result: frozenset = _NONE   # S registers an FP arithmetic instruction writes
    fp_reads: frozenset = _NONE    # S registers read
    core_writes: frozenset = _NONE  # core registers written (a following address may wait)

    def executed(self, table: str) -> int:
        return self.strict if table == STRICT else self.cycles


def pair(prev: Cost, cur: Cost, prev_in_it: bool = False, cur_in_it: bool = False) -> tuple[int, int]:
    """(strict, lenient) cycles added when `cur` executes right after `prev` (no taken branch in
    between). Negative: `cur` pipelines behind a load. An IT-conditional instruction never
    pipelines; the strict stalls are charged whether or not it executes (the conservative choice)."""
    s = n = 0
    if prev.load and cur.ldst and not (prev_in_it or cur_in_it) and not (cur.addr_regs & prev.load_writes):
        n -= 1
        s -= cur.strict_gain
    if prev.store and cur.mem:
        s += 1
    if prev.fp_result and prev.fp_result & cur.fp_reads:
        s += 1
    if prev.core_writes and prev.core_writes & cur.addr_regs:
        s += 1
    return s, n


def entry_extra(cost: Cost, addr: int) -> int:
    """Strict cycles added when a taken branch lands on this instruction: P = 3 for a 32-bit
    instruction at a halfword address."""
    return 1 if cost.size == 4 and addr & 2 else 0


def _s_regs(name: str) -> tuple[str, ...]:
    m = _FP_REG.match(name)
    if not m:
        return ()
    n = int(m.group(2))
    return (name,) if m.group(1) == "s" else (f"s{2 * n}", f"s{2 * n + 1}")


def _register_facts(insn) -> dict:
    read, written = insn.regs_access()
    rn = [insn.reg_name(r) for r in read]
    wn = [insn.reg_name(r) for r in written]
    fp_reads = frozenset(s for r in rn for s in _s_regs(r))
    core_writes = frozenset(r for r in wn if _CORE_REG.match(r) and r != "pc")
    fp_result = frozenset(s for r in wn for s in _s_regs(r)) if insn.id in _FP_ARITH else _NONE
    return dict(fp_reads=fp_reads, core_writes=core_writes, fp_result=fp_result)


def _operand_regs(insn) -> list[str]:
    return [insn.reg_name(op.reg) for op in insn.operands if op.type == A.ARM_OP_REG]


def _mem_regs(insn) -> frozenset:
    out = set()
    for op in insn.operands:
        if op.type == A.ARM_OP_MEM:
            for r in (op.mem.base, op.mem.index):
                if r:
                    out.add(insn.reg_name(r))
    return frozenset(out)


def _has_index(insn) -> bool:
    return any(op.type == A.ARM_OP_MEM and op.mem.index for op in insn.operands)


def _n_words(insn) -> int:
    """Words moved by a VLDM/VSTM/VPUSH/VPOP register list (a D register is two)."""
    n = 0
    for name in _operand_regs(insn):
        n += 2 if name.startswith("d") else 1 if name.startswith("s") else 0
    return n


def _multi_count(insn) -> tuple[int, bool, frozenset]:
    """Registers transferred by LDM/STM/PUSH/POP, whether PC is among them, the base register.

    For LDM/STM the first register operand is the base, not part of the list.
    """
    regs = _operand_regs(insn)
    if insn.id in (A.ARM_INS_PUSH, A.ARM_INS_POP):
        base = frozenset({"sp"})
    else:
        base, regs = frozenset(regs[:1]), regs[1:]
    return len(regs), "pc" in regs, base


def _writes_pc(insn) -> bool:
    _, written = insn.regs_access()
    return A.ARM_REG_PC in written or "pc" in _operand_regs(insn)[:1]


def _is_conditional(insn) -> bool:
    return insn.cc not in (A.ARM_CC_AL, A.ARM_CC_INVALID)


def cost_of(insn) -> Cost:
    """Timing facts of one Capstone instruction (detail mode)."""
    c = _cost_of(insn)
    if c.mem and c.core_writes:
        # A load's result or a write-back base is not an ALU result: the AGU rule is for ALU
        # producers; a load feeding the next address is the no-pipelining rule instead.
        return replace(c, core_writes=_NONE)
    return c


def _cost_of(insn) -> Cost:
    iid = insn.id
    it_count = len(insn.mnemonic.split(".")[0]) - 1 if iid == A.ARM_INS_IT else 0
    kw = dict(flow=FLOW_NONE, taken_extra=0, load=False, ldst=False, addr_regs=frozenset(),
              load_writes=frozenset(), it_count=it_count, size=insn.size, **_register_facts(insn))

    if iid in _SINGLE_LOADS or iid in _SINGLE_STORES:
        return _single_ldst(insn, kw)
    if iid in _DOUBLE_LDST:
        return Cost(3, 3, **{**kw, "addr_regs": _mem_regs(insn), "mem": True})
    if iid in _MULTI:
        n, pc, base = _multi_count(insn)
        kw.update(addr_regs=base, mem=True)
        if pc:
            return Cost(1 + n + P, 1 + n + P, **{**kw, "flow": FLOW_JUMP})
        return Cost(1 + n, 1 + n, **kw)
    if iid in _VMULTI:
        base = frozenset({"sp"}) if iid in (A.ARM_INS_VPUSH, A.ARM_INS_VPOP) else frozenset(_operand_regs(insn)[:1])
        return Cost(1 + _n_words(insn), 1 + _n_words(insn), **{**kw, "addr_regs": base, "mem": True})
    if iid in _FP_14:
        return Cost(14, 14, **kw)
    if iid in _FP_MAC:
        return Cost(3, 3, **kw)
    if iid == A.ARM_INS_VMOV:
        regs = _operand_regs(insn)
        n_core = sum(1 for r in regs if _CORE_REG.match(r))
        if n_core == 0:
            return Cost(1, 1, **kw)
        # FPU table: VMOV Rt, Sn and VMOV Sn, Rt 1; the two-register forms 2.
        return Cost(2, 1 if len(regs) == 2 else 2, **kw)
    if iid in _DIV:
        return Cost(DIV_CYCLES, DIV_CYCLES, **kw)
    return _control_flow(insn, kw)


def _single_ldst(insn, kw) -> Cost:
    is_load = insn.id in _SINGLE_LOADS
    addr = _mem_regs(insn)
    writes = set()
    if is_load:
        writes.add(_operand_regs(insn)[0])
    if insn.writeback:
        writes |= {insn.reg_name(op.mem.base) for op in insn.operands if op.type == A.ARM_OP_MEM}
    kw.update(addr_regs=addr, mem=True)
    if "pc" in writes:  # LDR pc: blocking load plus refill, never pipelined
        return Cost(2 + P, 3 + P, **{**kw, "flow": FLOW_JUMP})
    double = insn.id in (A.ARM_INS_VLDR, A.ARM_INS_VSTR) and _operand_regs(insn)[0].startswith("d")
    if double:  # VLDR.64/VSTR.64: two words, not pipelined (like LDRD)
        return Cost(3, 3, **kw)
    kw.update(load=is_load, ldst=True, load_writes=frozenset(writes))
    if is_load:
        literal = "pc" in addr  # fetch contention
        return Cost(2, 3 if literal else 2, **kw)
    indexed = _has_index(insn)  # nothing pipelines after a register-offset store
    return Cost(2, 2 if indexed else 1, **{**kw, "store": True, "strict_gain": 1 if indexed else 0})


def _control_flow(insn, kw) -> Cost:
    iid = insn.id
    rest = {k: v for k, v in kw.items() if k not in ("flow", "taken_extra")}
    if iid in _CALLS:
        return Cost(1 + P, 1 + P, FLOW_CALL, 0, **rest)
    if iid in _TABLE_BRANCH:
        return Cost(2 + P, 4 + P, FLOW_JUMP, 0, **{**rest, "addr_regs": _mem_regs(insn), "mem": True})
    if iid in _CBZ:
        return Cost(1, 1, FLOW_COND, P, **rest)
    if iid == A.ARM_INS_B:
        if _is_conditional(insn):
            return Cost(1, 1, FLOW_COND, P, **rest)
        return Cost(1 + P, 1 + P, FLOW_JUMP, 0, **rest)
    if iid == A.ARM_INS_BX or _writes_pc(insn):
        return Cost(1 + P, 1 + P, FLOW_JUMP, 0, **rest)
    # ALU, MOV, CMP, IT, MUL/MLA/long multiplies, other FPU operations, barriers: 1.
    return Cost(1, 1, **kw)
