#include "common.inc"

@ bench: bench_fpu
@ expect: 48
@   vmov s0, r0                           VMOV core -> S: 2          = 2
@   vmov.f32 s1, #1.0 ; vmov.f32 s2, #2.0 VMOV immediate (fconsts): 2 x 1 = 2
@   vadd.f32, vmul.f32                    2 x 1                      = 2
@   vmla.f32                              3                          = 3
@   vfma.f32                              3                          = 3
@   vdiv.f32                              14                         = 14
@   vsqrt.f32                             14                         = 14
@   vcmp.f32 s6, #0                       1                          = 1
@   vmrs APSR_nzcv, fpscr (fmstat)        1                          = 1
@   vcvt.s32.f32                          1                          = 1
@   vmov r1, s7                           VMOV S -> core: 2          = 2
@   bx lr                                 1 + P                      = 3
BENCH bench_fpu
  vmov s0, r0
  vmov.f32 s1, #1.0
  vmov.f32 s2, #2.0
  vadd.f32 s3, s1, s2
  vmul.f32 s4, s3, s2
  vmla.f32 s4, s1, s2
  vfma.f32 s4, s1, s2
  vdiv.f32 s5, s4, s2
  vsqrt.f32 s6, s5
  vcmp.f32 s6, #0
  vmrs APSR_nzcv, fpscr
  vcvt.s32.f32 s7, s6
  vmov r1, s7
  bx lr
END bench_fpu
