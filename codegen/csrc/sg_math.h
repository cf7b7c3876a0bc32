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

#include <stdint.h>

/* tanh(x) (MATLAB tansig(n) = 2/(1+exp(-2n)) - 1); odd, |result| <= 1, exactly +-1 for
 * |x| >= 9, exactly x for |x| < 2^-12. Table-driven, no division (the network's hot path). */
float sg_tanhf(float x);

/* Marks the end of a group of loads: an empty asm statement with a memory clobber emits no
 * instruction, but GCC may not move a load written before it below it, nor code written after
 * it above it. Without it GCC's pre-RA scheduler (on at -O2 for ARM) puts every VLDR next to
 * its VMUL, and the Cortex-M4 only pipelines a load that directly follows a load (1 cycle
 * instead of 2). No effect on results. */
#if defined(__GNUC__)
#define SG_LOADS_DONE() __asm__ __volatile__("" ::: "memory")
#else
#define SG_LOADS_DONE() ((void)0)
#endif

/* ---- sg_inline_tanhf: sg_tanhf for a hot loop ------------------------------------------
 * The same function bit for bit (both use sg_tanh_index and sg_tanh_poly below), as a static
 * inline for a translation unit that calls tanh in a loop (the network path): no call, the
 * table address stays in a register. Arguments outside [2^-12, 9) (tiny, saturated, +-Inf,
 * NaN) take one unsigned compare and call sg_tanhf. */
#define SG_TANH_M 3u                              /* mantissa bits in the table index */
#define SG_TANH_FIRST ((127u - 12u) << SG_TANH_M) /* index of [2^-12, 1.125 * 2^-12) */
#define SG_TANH_N 121u                            /* intervals; the last is [8, 9) */
#define SG_TANH_COLS 6u                           /* c, c0 .. c4 */
extern const float sg_tanh_tab[SG_TANH_N][SG_TANH_COLS];

typedef union {
    float f;
    uint32_t u;
} sg_bits_t;

/* Interval of |x| from its exponent and top SG_TANH_M mantissa bits; >= SG_TANH_N outside
 * [2^-12, 9), including +-Inf and NaN. */
static inline uint32_t sg_tanh_index(uint32_t ux)
{
    return ((ux << 1) >> (24u - SG_TANH_M)) - SG_TANH_FIRST;
}

/* tanh on one interval: c0 + t (c1 + t (c2 + t (c3 + t c4))), t = |x| - c (exact), then the
 * sign of x. The six coefficients are loaded as one group (6 VLDR: 7 cycles, not 12). */
static inline float sg_tanh_poly(const float *row, float x, uint32_t ux)
{
    const float c = row[0], c0 = row[1], c1 = row[2], c2 = row[3], c3 = row[4], c4 = row[5];
    float t, p;
    SG_LOADS_DONE();
    t = __builtin_fabsf(x) - c;
    p = c4;
    p = p * t + c3;
    p = p * t + c2;
    p = p * t + c1;
    p = p * t + c0;
    return (ux >> 31) ? -p : p;
}

static inline float sg_inline_tanhf(float x)
{
    sg_bits_t b;
    uint32_t i;
    b.f = x;
    i = sg_tanh_index(b.u);
    if (__builtin_expect(i >= SG_TANH_N, 0)) {
        return sg_tanhf(x);
    }
    return sg_tanh_poly(sg_tanh_tab[i], x, b.u);
}

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
