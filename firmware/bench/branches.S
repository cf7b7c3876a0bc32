#include "common.inc"

@ bench: bench_branches
@ lenient: 34
@ strict: 34
@   movs r1, #4                           1                          = 1
@   loop: subs r1, r1, #1                 4 iterations x 1           = 4
@         bne loop                        3 taken x (1 + P) + 1 not taken x 1 = 10
@   cbz r1, 1f                            taken (r1 = 0): 1 + P      = 3
@   cbnz r1, 2f                           not taken: 1               = 1
@   b 3f                                  1 + P                      = 3
@   push {lr}                             1 + 1                      = 2
@   bl leaf                               1 + P                      = 3
@   leaf: bx lr                           1 + P                      = 3
@   pop {pc}                              1 + 1 + P                  = 4
@ strict: the same (every taken branch lands on a 16-bit instruction; no stall rule applies)
BENCH bench_branches
  movs r1, #4
0:
  subs r1, r1, #1          @ wcet: loop bound 4 lines 2
  bne 0b
  cbz r1, 1f
  nop
1:
  cbnz r1, 2f
  b 3f
2:
  nop
3:
  push {lr}
  bl 4f
  pop {pc}
4:
  bx lr
END bench_branches

@ bench: bench_tbb
@ lenient: 8
@ strict: 11
@   movs r1, #1                           1                          = 1
@   tbb [pc, r1]                          2 + P                      = 4
@                                         strict: 6 (table load, target from the loaded byte, P = 3)
@                                         + 1 (its index r1 was written by the movs just before)
@   case 1: bx lr                         1 + P                      = 3
BENCH bench_tbb
  movs r1, #1
  tbb [pc, r1]
0:
  .byte (1f - 0b) / 2, (2f - 0b) / 2
1:
  nop
2:
  bx lr
END bench_tbb

@ bench: bench_pop_pc
@ lenient: 21
@ strict: 21
@   push {r4, lr}                         1 + 2                      = 3
@   movs r4, #1                           1                          = 1
@   bl bench_pop_pc_sub                   1 + P                      = 3
@     sub: push {r4, lr}                  1 + 2                      = 3
@     sub: movs r4, #2                    1                          = 1
@     sub: pop {r4, pc}                   1 + 2 + P (PC loaded)      = 5
@   pop {r4, pc}                          1 + 2 + P                  = 5
@ (the sub-function alone: 9 inclusive = exclusive; the caller: 12 exclusive)
BENCH bench_pop_pc
  push {r4, lr}
  movs r4, #1
  bl bench_pop_pc_sub
  pop {r4, pc}
END bench_pop_pc

BENCH bench_pop_pc_sub
  push {r4, lr}
  movs r4, #2
  pop {r4, pc}
END bench_pop_pc_sub
