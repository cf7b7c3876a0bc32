/*
 * sg_math.h - deterministic float32 math for the generated flight code (staregen).
 *
 * Every function is a fixed sequence of IEEE-754 single-precision operations (range
 * reduction + minimax polynomial), no libm, no double, no per-platform tables, so the
 * x86-64 (SSE) and Cortex-M4F (FPv4-SP) builds and the numpy twin codegen/detmath.py
 * give the same bits. Requires round-to-nearest, FZ=0 (subnormals kept), and the flags of
 * firmware/flags.py (-ffp-contract=off above all: no fused multiply-add).
 *
 * Max error vs a float64 reference (ulp of the float32 result), measured exhaustively over
 * all 2^32 inputs by tools/ulp_sweep.py (sampled for the two-argument functions):
 *   tanh 1.47, exp 1.19, log 0.84, sin 1.02 and cos 1.03 (|x| <= SG_TRIG_MAX_ARG), asin 1.20,
 *   sqrt 0.5 (correctly rounded), atan2 1.53 (sampled); pow see below.
 * Published bounds: 2 ulp (3 for atan2). docs/math.md has the table, the methods, the domains
 * and the Cortex-M4 cycle estimates.
 *
 * NaN in gives NaN out (sign/payload unspecified). Other special values follow C99 Annex F
 * unless stated.
 */
#ifndef SG_MATH_H
#define SG_MATH_H

/* tanh(x) (MATLAB tansig(n) = 2/(1+exp(-2n)) - 1); odd, |result| <= 1, exactly +-1 for
 * |x| >= 9, exactly x for |x| < 2^-12. Table-driven, no division (the network's hot path). */
float sg_tanhf(float x);

/* e^x; +Inf above 88.7228317, +0 below -103.972076 (results may be subnormal). */
float sg_expf(float x);

/* ln(x); -Inf at +-0, NaN for x < 0, +Inf at +Inf. Subnormal x handled. */
float sg_logf(float x);

/* sin/cos of x in radians. Accurate (see docs/math.md) for |x| <= SG_TRIG_MAX_ARG;
 * beyond it the result is finite and in [-1, 1] but not accurate. NaN for +-Inf. */
#define SG_TRIG_MAX_ARG 0x1.0p+13f
float sg_sinf(float x);
float sg_cosf(float x);

/* atan2(y, x) in [-pi, pi], all signed-zero / infinity cases as C99 Annex F. */
float sg_atan2f(float y, float x);

/* asin(x) for x in [-1, 1]; NaN outside. */
float sg_asinf(float x);

/* Correctly rounded square root (VSQRT / sqrtss); NaN for x < 0, sqrt(-0) = -0. */
float sg_sqrtf(float x);

/* x^y for x >= 0 as exp(y*ln x): x^0 = 1 and 1^y = 1 for every y (also NaN); 0^y = 0 for
 * y > 0, +Inf for y < 0; NaN for x < 0 or NaN. Error grows with |y ln x|: docs/math.md. */
float sg_powf_pos(float x, float y);

#endif /* SG_MATH_H */
