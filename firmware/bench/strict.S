#include "common.inc"

@ One benchmark per rule of the strict table (tools/m4/timing.py, docs/cycle-model.md, "Timing-
@ table audit"). Each line gives "lenient | strict" cycles at zero wait states, P = 2; the strict
@ column applies the TRM's rule at its conservative reading.

@ bench: bench_fp_result_use
@ lenient: 12
@ strict: 13
@ TRM 7.2.3: FP arithmetic (add, subtract, multiply, divide, square root, multiply-accumulate,
@ conversions) takes one cycle longer if its result is consumed by the following instruction.
@   vmov.f32 s0, #1.0                     1 | 1
@   vadd.f32 s1, s0, s0                   1 | 1      (s0 comes from fconsts: not arithmetic)
@   vadd.f32 s2, s1, s0                   1 | 1 + 1  (reads s1 of the add just before)
@   vmul.f32 s3, s0, s0                   1 | 1      (does not read s2)
@   vadd.f32 s4, s1, s0                   1 | 1      (does not read s3)
@   vadd.f32 s5, s3, s0                   1 | 1      (s3 was produced two instructions earlier)
@   vcvt.s32.f32 s6, s4                   1 | 1      (s4 two instructions earlier)
@   vmov r1, s6                           2 | 1 + 1  (VMOV Rt, Sn is 1; reads s6 of the conversion)
@   bx lr                                 3 | 3
@   lenient 1+1+1+1+1+1+1+2+3 = 12; strict 1+1+2+1+1+1+1+2+3 = 13
BENCH bench_fp_result_use
  vmov.f32 s0, #1.0
  vadd.f32 s1, s0, s0
  vadd.f32 s2, s1, s0
  vmul.f32 s3, s0, s0
  vadd.f32 s4, s1, s0
  vadd.f32 s5, s3, s0
  vcvt.s32.f32 s6, s4
  vmov r1, s6
  bx lr
END bench_fp_result_use

@ bench: bench_agu
@ lenient: 13
@ strict: 14
@ TRM 3.3.3: the address of a load/store is generated in its first cycle; a register an ALU
@ instruction writes in the cycle just before is not forwarded to the address generation unit.
@   adds r1, r0, #4                       1 | 1
@   ldr r2, [r1]                          2 | 2 + 1  (r1 written by the instruction just before)
@   adds r3, r0, #8                       1 | 1
@   nop                                   1 | 1
@   ldr r2, [r3]                          2 | 2      (r3 written two instructions earlier)
@   mov r1, r0                            1 | 1
@   str r2, [r1, #4]                      2 | 1 + 1  (STR 1, next not a memory access; r1 just written)
@   bx lr                                 3 | 3
@   lenient 1+2+1+1+2+1+2+3 = 13; strict 1+3+1+1+2+1+2+3 = 14
BENCH bench_agu
  adds r1, r0, #4
  ldr r2, [r1]
  adds r3, r0, #8
  nop
  ldr r2, [r3]
  mov r1, r0
  str r2, [r1, #4]
  bx lr
END bench_agu

@ bench: bench_branch_align
@ lenient: 11
@ strict: 12
@ TRM 3.3.1: P, the pipeline refill, is 1..3 cycles by the alignment and width of the target; the
@ strict table takes 3 for a 32-bit instruction at a halfword address, 2 otherwise.
@ Offsets from the 16-byte aligned start:
@   0: b.n 1f                             3 | 1 + 3  (target at offset 2, 32-bit)
@   2: add.w r1, r0, #1                   1 | 1
@   6: b.n 2f                             3 | 1 + 2  (target at offset 12: word aligned)
@   8, 10: nop, nop                       skipped
@  12: add.w r1, r1, #1                   1 | 1
@  16: bx lr                              3 | 3
@   lenient 3+1+3+1+3 = 11; strict 4+1+3+1+3 = 12
BENCH bench_branch_align
  b.n 1f
1:
  add.w r1, r0, #1
  b.n 2f
  nop
  nop
2:
  add.w r1, r1, #1
  bx lr
END bench_branch_align

@ bench: bench_literal
@ lenient: 6
@ strict: 8
@ TRM 3.3.3: LDR Rx, [PC, #imm] might add a cycle because of contention with the fetch unit;
@ the strict table charges it on every PC-relative load, VLDR included.
@   ldr r1, 1f                            2 | 2 + 1
@   vldr s0, 2f                           1 | 2      (pipelined behind the load: 2 - 1 | 3 - 1)
@   bx lr                                 3 | 3
@   lenient 2+1+3 = 6; strict 3+2+3 = 8
BENCH bench_literal
  ldr r1, 1f
  vldr s0, 2f
  bx lr
  .p2align 2
1:
  .word 0x12345678
2:
  .word 0x3f800000
END bench_literal

@ bench: bench_ldr_pc
@ lenient: 11
@ strict: 12
@ TRM table 3-1: LDR PC, [Rn] is 2 + P; the strict table takes P = 3: 5.
@   adr r1, 1f                            1 | 1
@   adds r1, #1                           1 | 1      (Thumb bit)
@   str r1, [r0]                          2 | 1 + 1  (STR 1; the next instruction loads)
@   ldr pc, [r0]                          4 | 5      (r0 not written just before: no AGU stall)
@   1: bx lr                              3 | 3      (16-bit target at a word address)
@   lenient 1+1+2+4+3 = 11; strict 1+1+2+5+3 = 12
BENCH bench_ldr_pc
  adr r1, 1f
  adds r1, #1
  str r1, [r0]
  ldr pc, [r0]
  .p2align 2
1:
  bx lr
END bench_ldr_pc

@ bench: bench_vmov
@ lenient: 11
@ strict: 9
@ FPU instruction table: VMOV between one core and one single-precision register 1 cycle; the
@ two-register forms (VMOV Rt, Rt2, Dm / VMOV Sm, Sm1, Rt, Rt2) 2.
@   vmov s0, r0                           2 | 1
@   vmov r1, s1                           2 | 1
@   vmov r2, r3, d1                       2 | 2
@   vmov s4, s5, r1, r2                   2 | 2
@   bx lr                                 3 | 3
@   lenient 2+2+2+2+3 = 11; strict 1+1+2+2+3 = 9
BENCH bench_vmov
  vmov s0, r0
  vmov r1, s1
  vmov r2, r3, d1
  vmov s4, s5, r1, r2
  bx lr
END bench_vmov

@ bench: bench_store
@ lenient: 14
@ strict: 12
@ TRM 3.3.3: STR Rx, [Ry, #imm] is one cycle (the data phase overlaps the next instruction);
@ nothing pipelines after a store, so a memory access right after it waits one cycle; a store
@ with a register offset is not pipelined: 2.
@   str r0, [r0, #4]                      2 | 1      (the next is not a memory access)
@   adds r1, r0, #0                       1 | 1
@   str r1, [r0, #8]                      2 | 1 + 1  (the next is a store)
@   str r1, [r0, #12]                     2 | 1
@   movs r2, #16                          1 | 1
@   nop                                   1 | 1      (keeps r2 from the AGU rule)
@   str r1, [r0, r2]                      2 | 2      (register offset)
@   bx lr                                 3 | 3
@   lenient 2+1+2+2+1+1+2+3 = 14; strict 1+1+2+1+1+1+2+3 = 12
BENCH bench_store
  str r0, [r0, #4]
  adds r1, r0, #0
  str r1, [r0, #8]
  str r1, [r0, #12]
  movs r2, #16
  nop
  str r1, [r0, r2]
  bx lr
END bench_store
