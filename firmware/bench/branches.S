#include "common.inc"

@ bench: bench_branches
@ expect: 32
@   movs r1, #4                           1                          = 1
@   loop: subs r1, r1, #1                 4 iterations x 1           = 4
@         bne loop                        3 taken x (1 + P) + 1 not taken x 1 = 10
@   cbz r1, 1f                            taken (r1 = 0): 1 + P      = 3
@   cbnz r1, 2f                           not taken: 1               = 1
@   b 3f                                  1 + P                      = 3
@   mov r12, lr                           1                          = 1
@   bl leaf                               1 + P                      = 3
@   leaf: bx lr                           1 + P                      = 3
@   bx r12                                1 + P                      = 3
BENCH bench_branches
  movs r1, #4
0:
  subs r1, r1, #1
  bne 0b
  cbz r1, 1f
  nop
1:
  cbnz r1, 2f
  b 3f
2:
  nop
3:
  mov r12, lr
  bl 4f
  bx r12
4:
  bx lr
END bench_branches

@ bench: bench_tbb
@ expect: 8
@   movs r1, #1                           1                          = 1
@   tbb [pc, r1]                          2 + P                      = 4
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
@ expect: 21
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
