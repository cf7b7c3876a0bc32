#include "common.inc"

@ bench: bench_it_blocks
@ lenient: 20
@ strict: 20
@ Instructions skipped inside an IT block cost 1 (Unicorn runs no hook for them).
@   movs r1, #0 ; cmp r1, #0              2 x 1                      = 2
@   ite eq                                1                          = 1
@   moveq r2, #1 (runs) ; movne r2, #2 (skipped)  1 + 1              = 2
@   itt ne                                1                          = 1
@   ldrne r3, [r0] ; ldrne r3, [r0, #4]   both skipped: 1 + 1        = 2
@   ite eq                                1                          = 1
@   ldreq r3, [r0] (runs: LDR 2) ; addne r3, r3, #1 (skipped: 1)     = 3
@   cmp r1, #1 ; it eq                    2 x 1                      = 2
@   bxeq lr (skipped: not taken)          1                          = 1
@   cmp r1, #0 ; it eq                    2 x 1                      = 2
@   bxeq lr (runs: taken, 1 + P)          3                          = 3
BENCH bench_it_blocks
  movs r1, #0
  cmp r1, #0
  ite eq
  moveq r2, #1
  movne r2, #2
  itt ne
  ldrne r3, [r0]
  ldrne r3, [r0, #4]
  ite eq
  ldreq r3, [r0]
  addne r3, r3, #1
  cmp r1, #1
  it eq
  bxeq lr
  cmp r1, #0
  it eq
  bxeq lr
  bkpt #2
END bench_it_blocks

@ bench: bench_it_flash_read
@ lenient: 13
@ strict: 14
@ An IT-conditional load from flash, then a translation block that starts with the IT block's
@ condition false: that first instruction must run (profile.py clears the IT state Unicorn leaves
@ behind a memory hook inside an IT block; without it `movs r0, #1` is skipped and r0 stays 0).
@   movs r0, #0 ; cmp r0, #0              2 x 1                      = 2
@   it eq                                 1                          = 1
@   vldreq s0, 2f (runs: literal)         lenient 2, strict 3        = 2 | 3
@   cmp r0, #1                            1                          = 1
@   b 1f (taken, 1 + P; 16-bit target)    3                          = 3
@   movs r0, #1                           1                          = 1
@   bx lr                                 1 + P                      = 3
BENCH bench_it_flash_read
  movs r0, #0
  cmp r0, #0
  it eq
  vldreq s0, 2f
  cmp r0, #1
  b 1f
1:
  movs r0, #1
  bx lr
  .p2align 2
2:
  .word 0x3f800000
END bench_it_flash_read
