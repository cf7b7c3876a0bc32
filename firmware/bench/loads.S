#include "common.inc"

@ bench: bench_loads_dependent
@ lenient: 9
@ strict: 9
@   ldr r1, [r0]                          2 (LDR)                    = 2
@   ldr r2, [r1]                          2 (address is the result of the previous load: no pipelining) = 2
@                                         strict: the same (the AGU stall is for an address an ALU
@                                         instruction computed; a load result is this rule)
@   ldr r3, [r2]                          2 (same)                   = 2
@   bx lr                                 1 + P                      = 3
BENCH bench_loads_dependent
  ldr r1, [r0]
  ldr r2, [r1]
  ldr r3, [r2]
  bx lr
END bench_loads_dependent

@ bench: bench_loads_independent
@ lenient: 11
@ strict: 12
@   ldr r1, [r0]                          2 (LDR)                    = 2
@   ldr r2, [r0, #4]                      1 (independent load after a load pipelines: 2 - 1) = 1
@   ldr r3, [r0, #8]                      1 (same)                   = 1
@   str r1, [r0, #12]                     1 (store after a load pipelines: 2 - 1) = 1
@                                         strict: 1 (STR, TRM 3.3.3), + 1 (the next one loads) = 2
@   ldr r1, [r0, #16]                     2 (nothing pipelines after a store) = 2
@   adds r2, r2, r3                       1 (ALU)                    = 1
@   bx lr                                 1 + P                      = 3
BENCH bench_loads_independent
  ldr r1, [r0]
  ldr r2, [r0, #4]
  ldr r3, [r0, #8]
  str r1, [r0, #12]
  ldr r1, [r0, #16]
  adds r2, r2, r3
  bx lr
END bench_loads_independent

@ bench: bench_fp_loads
@ lenient: 9
@ strict: 10
@   vldr s0, [r0]                         2 (VLDR)                   = 2
@   vldr s1, [r0, #4]                     1 (pipelined behind a load, as LDR) = 1
@   vstr s0, [r0, #8]                     1 (store behind a load)    = 1
@                                         strict: 1, + 1 (the next one loads) = 2
@   vldr s2, [r0, #12]                    2 (nothing pipelines after a store) = 2
@   bx lr                                 1 + P                      = 3
BENCH bench_fp_loads
  vldr s0, [r0]
  vldr s1, [r0, #4]
  vstr s0, [r0, #8]
  vldr s2, [r0, #12]
  bx lr
END bench_fp_loads

@ bench: bench_ldm_stm
@ lenient: 27
@ strict: 27
@   push {r4-r7}                          1 + N, N = 4               = 5
@   ldm r0, {r1-r3}                       1 + 3                      = 4
@   stm r0, {r1-r3}                       1 + 3                      = 4
@   ldrd r4, r5, [r0]                     3 (LDRD, never pipelined)  = 3
@   strd r4, r5, [r0, #16]                3 (STRD)                   = 3
@   pop {r4-r7}                           1 + 4 (no PC)              = 5
@   bx lr                                 1 + P                      = 3
BENCH bench_ldm_stm
  push {r4-r7}
  ldm r0, {r1-r3}
  stm r0, {r1-r3}
  ldrd r4, r5, [r0]
  strd r4, r5, [r0, #16]
  pop {r4-r7}
  bx lr
END bench_ldm_stm

@ bench: bench_vldm_vstm
@ lenient: 29
@ strict: 29
@   vpush {s16-s19}                       1 + N, N = 4               = 5
@   vldm r0, {s0-s3}                      1 + 4                      = 5
@   vstm r0, {s0-s3}                      1 + 4                      = 5
@   vpush {d8}                            1 + 2 (one double = 2 words) = 3
@   vpop {d8}                             1 + 2                      = 3
@   vpop {s16-s19}                        1 + 4                      = 5
@   bx lr                                 1 + P                      = 3
BENCH bench_vldm_vstm
  vpush {s16-s19}
  vldm r0, {s0-s3}
  vstm r0, {s0-s3}
  vpush {d8}
  vpop {d8}
  vpop {s16-s19}
  bx lr
END bench_vldm_vstm
