"""Cortex-M4 cycle costs of one decoded instruction (SPEC section 7, TRM table 3-1, FPU table).

Costs are for zero wait states. What depends on execution (a conditional branch taken, an
instruction skipped inside an IT block, a load pipelined behind the previous one, flash wait
states) is resolved by the caller from the fields of `Cost`; see docs/cycle-model.md.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from capstone import arm_const as A

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
_DIV = {A.ARM_INS_SDIV, A.ARM_INS_UDIV}
_CALLS = {A.ARM_INS_BL, A.ARM_INS_BLX}
_TABLE_BRANCH = {A.ARM_INS_TBB, A.ARM_INS_TBH}
_CBZ = {A.ARM_INS_CBZ, A.ARM_INS_CBNZ}

_CORE_REG = re.compile(r"^(r\d+|sb|sl|fp|ip|sp|lr|pc)$")

# Control-flow kinds, used by the call-stack tracker and for the taken-branch penalty.
FLOW_NONE, FLOW_CALL, FLOW_JUMP, FLOW_COND = 0, 1, 2, 3


@dataclass(frozen=True)
class Cost:
    """Static timing facts of one instruction."""

    cycles: int            # cost when executed, zero wait states, not pipelined, not taken
    flow: int              # FLOW_*: how it changes the PC
    taken_extra: int       # added when a conditional branch is taken (P), else 0
    load: bool             # single-register load: a following independent ld/st pipelines
    ldst: bool             # single-register load or store: can pipeline behind a load
    addr_regs: frozenset   # registers forming the address (ld/st only)
    load_writes: frozenset # registers a load writes (destination and base write-back)
    it_count: int          # for IT: how many following instructions it makes conditional


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


def _n_words(insn) -> int:
    """Words moved by a VLDM/VSTM/VPUSH/VPOP register list (a D register is two)."""
    n = 0
    for name in _operand_regs(insn):
        n += 2 if name.startswith("d") else 1 if name.startswith("s") else 0
    return n


def _multi_count(insn) -> tuple[int, bool]:
    """Registers transferred by LDM/STM/PUSH/POP and whether PC is among them.

    For LDM/STM the first register operand is the base, not part of the list.
    """
    regs = _operand_regs(insn)
    if insn.id not in (A.ARM_INS_PUSH, A.ARM_INS_POP):
        regs = regs[1:]
    return len(regs), "pc" in regs


def _writes_pc(insn) -> bool:
    _, written = insn.regs_access()
    return A.ARM_REG_PC in written or "pc" in _operand_regs(insn)[:1]


def _is_conditional(insn) -> bool:
    return insn.cc not in (A.ARM_CC_AL, A.ARM_CC_INVALID)


def cost_of(insn) -> Cost:
    """Timing facts of one Capstone instruction (detail mode)."""
    iid = insn.id
    it_count = len(insn.mnemonic.split(".")[0]) - 1 if iid == A.ARM_INS_IT else 0
    kw = dict(flow=FLOW_NONE, taken_extra=0, load=False, ldst=False, addr_regs=frozenset(),
              load_writes=frozenset(), it_count=it_count)

    if iid in _SINGLE_LOADS or iid in _SINGLE_STORES:
        is_load = iid in _SINGLE_LOADS
        addr = _mem_regs(insn)
        writes = set()
        if is_load:
            writes.add(_operand_regs(insn)[0])
        if insn.writeback:
            writes |= {insn.reg_name(op.mem.base) for op in insn.operands
                       if op.type == A.ARM_OP_MEM}
        if "pc" in writes:  # LDR pc: blocking load plus refill, never pipelined
            return Cost(2 + P, **{**kw, "flow": FLOW_JUMP})
        double = iid in (A.ARM_INS_VLDR, A.ARM_INS_VSTR) and _operand_regs(insn)[0].startswith("d")
        if double:  # VLDR.64/VSTR.64: two words, not pipelined (like LDRD)
            return Cost(3, **kw)
        kw.update(load=is_load, ldst=True, addr_regs=addr, load_writes=frozenset(writes))
        return Cost(2, **kw)
    if iid in _DOUBLE_LDST:
        return Cost(3, **kw)
    if iid in _MULTI:
        n, pc = _multi_count(insn)
        if pc:
            return Cost(1 + n + P, **{**kw, "flow": FLOW_JUMP})
        return Cost(1 + n, **kw)
    if iid in _VMULTI:
        return Cost(1 + _n_words(insn), **kw)
    if iid in _FP_14:
        return Cost(14, **kw)
    if iid in _FP_MAC:
        return Cost(3, **kw)
    if iid == A.ARM_INS_VMOV:
        regs = _operand_regs(insn)
        core = any(_CORE_REG.match(r) for r in regs)
        fp = any(r[0] in "sd" and r[1:].isdigit() for r in regs)
        return Cost(2 if core and fp else 1, **kw)
    if iid in _DIV:
        return Cost(DIV_CYCLES, **kw)
    return _control_flow(insn, kw)


def _control_flow(insn, kw) -> Cost:
    iid = insn.id
    rest = {k: v for k, v in kw.items() if k not in ("flow", "taken_extra")}
    if iid in _CALLS:
        return Cost(1 + P, FLOW_CALL, 0, **rest)
    if iid in _TABLE_BRANCH:
        return Cost(2 + P, FLOW_JUMP, 0, **rest)
    if iid in _CBZ:
        return Cost(1, FLOW_COND, P, **rest)
    if iid == A.ARM_INS_B:
        if _is_conditional(insn):
            return Cost(1, FLOW_COND, P, **rest)
        return Cost(1 + P, FLOW_JUMP, 0, **rest)
    if iid == A.ARM_INS_BX or _writes_pc(insn):
        return Cost(1 + P, FLOW_JUMP, 0, **rest)
    # ALU, MOV, CMP, IT, MUL/MLA/long multiplies, other FPU operations, barriers: 1.
    return Cost(1, **kw)
