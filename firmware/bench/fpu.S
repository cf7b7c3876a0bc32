#include "common.inc"

@ bench: bench_fpu
@ lenient: 48
@ strict: 53
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
@ strict (TRM 7.2.3: an FP arithmetic result read by the next instruction costs 1 more; FPU
@ table: VMOV between a core and an S register 1):
@   vmov s0, r0 1; two fconsts 2; vadd 1 (fconsts is not arithmetic)                = 4
@   vmul s4, s3, s2 reads s3 of the vadd: 1 + 1                                      = 2
@   vmla s4 reads s4 of the vmul: 3 + 1; vfma s4 reads s4 of the vmla: 3 + 1          = 8
@   vdiv reads s4 of the vfma: 14 + 1; vsqrt reads s5 of the vdiv: 14 + 1            = 30
@   vcmp reads s6 of the vsqrt: 1 + 1; vmrs 1 (vcmp is not arithmetic); vcvt 1        = 4
@   vmov r1, s7 reads s7 of the vcvt: 1 + 1; bx lr 3                                 = 5
@                                                                       total strict = 53
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
