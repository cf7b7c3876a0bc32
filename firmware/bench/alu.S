#include "common.inc"

@ bench: bench_alu_chain
@ lenient: 13
@ strict: 13
@   movs, adds, eors, lsls, subs          5 x 1 (ALU)                = 5
@   mul, mla                              2 x 1 (MUL/MLA)            = 2
@   orr, and, cmp                         3 x 1 (ALU)                = 3
@   bx lr                                 1 + P                      = 3
BENCH bench_alu_chain
  movs r1, #1
  adds r1, r1, #2
  eors r1, r1, r0
  lsls r1, r1, #1
  subs r1, r1, #3
  mul r1, r1, r1
  mla r1, r1, r1, r1
  orr r1, r1, #4
  and r1, r1, #0xff
  cmp r1, #0
  bx lr
END bench_alu_chain
