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
 *   sqrt 0.5 (correctly rounded), atan2 1.53 (sampled); pow see below; sg_powf_fused (fast path,
 *   sampled) 1.59 at y = 0.8, <= 1.2 + |y| in general.
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

/* sg_tanhf with every argument class inline (no call at all), the same bits: inside [2^-12, 9)
 * the shared table polynomial; NaN and |x| < 2^-12 (also +-0, subnormals: d wraps around) give
 * x itself, |x| >= 9 and +-Inf give +-1 from the sign bit, exactly sg_tanh_outside's rule. For
 * code whose tanh arguments often saturate (the tanh law's torque). */
static inline float sg_inline_tanhf_full(float x)
{
    sg_bits_t b;
    uint32_t d;
    b.f = x;
    d = (b.u << 1) - (SG_TANH_FIRST << (24u - SG_TANH_M));
    if (__builtin_expect(d < (SG_TANH_N << (24u - SG_TANH_M)), 1)) {
        return sg_tanh_poly(sg_tanh_tab[d >> (24u - SG_TANH_M)], x, b.u);
    }
    if (d > 0xff000000u - (SG_TANH_FIRST << (24u - SG_TANH_M))) {
        return x;
    }
    b.u = (b.u & 0x80000000u) | 0x3f800000u;
    return b.f;
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

/* ---- sg_powf_fused: x^y for x > 0 in one pass (no call to log and exp) ----------------
 * x = 2^k m, m in [sqrt(1/2), sqrt 2) from the bits, f = m - 1 (exact), log2 m = f P(f) (P of
 * degree 7, absolute error 4.9e-8); y = yh + yl with yh the top 12 significant bits of y, so
 * th = yh k is exact; t = th + (yl k + y log2 m), n = round(t) by the magic add, r = (th - n) +
 * (yl k + y log2 m) in [-0.5, 0.5], 2^r = 1 + r Q(r) (Q of degree 5, relative error 3.0e-9),
 * the result's exponent assembled by adding n << 23 to the bits (exact). Fast path for x a
 * positive normal float and |t| < 125 (the result then normal); everything else (x <= 0,
 * subnormal, +Inf, NaN, y non-finite, |y log2 x| >= 125) returns sg_powf_pos(x, y). Measured
 * error and cycles: docs/math.md. Static inline: with a constant y the split folds away. */
#define SG_POWF_FUSED_MAX_T 125.0f
/* log2(1+f)/f = c0 + f (c1 + ... + f c7), stored c7 .. c0; (2^r - 1)/r = e0 + r (e1 + ... + r e5),
 * stored e5 .. e0 (tools: docs/math.md). Defined in sg_math.c: one copy, loaded as groups. */
extern const float sg_powf_fused_tab[14];

#if defined(__GNUC__)
#define SG_ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#define SG_ALWAYS_INLINE inline
#endif

static SG_ALWAYS_INLINE float sg_powf_fused(float x, float y)
{
    sg_bits_t bx, by, bt;
    uint32_t ix;
    float kf, f, p, lm, yh, yl, th, tl, t, nf, r, q;
    bx.f = x;
    if (__builtin_expect(bx.u - 0x00800000u >= 0x7f000000u, 0)) {
        return sg_powf_pos(x, y); /* not a positive normal finite float */
    }
    ix = bx.u + (0x3f800000u - 0x3f3504f3u);
    kf = (float)((int32_t)(ix >> 23) - 127);
    bx.u = (ix & 0x007fffffu) + 0x3f3504f3u;
    f = bx.f - 1.0f;
    {
        const float *c = sg_powf_fused_tab;
        const float c7 = c[0], c6 = c[1], c5 = c[2], c4 = c[3], c3 = c[4], c2 = c[5], c1 = c[6], c0 = c[7];
        SG_LOADS_DONE();
        p = c7;
        p = p * f + c6;
        p = p * f + c5;
        p = p * f + c4;
        p = p * f + c3;
        p = p * f + c2;
        p = p * f + c1;
        p = p * f + c0;
    }
    lm = f * p;
    by.f = y;
    by.u &= 0xfffff000u;
    yh = by.f;
    yl = y - yh;
    th = yh * kf;
    tl = yl * kf + y * lm;
    t = th + tl;
    /* |y| <= 31/32 implies |t| <= 124 for every normal x: with such a constant y (the tanh law's)
     * the compiler drops the test on t; the fast-path set is the same either way. */
    if (__builtin_expect(!(__builtin_fabsf(y) <= 0x1.fp-1f) && !(__builtin_fabsf(t) < SG_POWF_FUSED_MAX_T), 0)) {
        return sg_powf_pos(x, y);
    }
    bt.f = t + 0x1.8p+23f;
    nf = bt.f - 0x1.8p+23f;
    r = (th - nf) + tl;
    {
        const float *e = sg_powf_fused_tab + 8;
        const float e5 = e[0], e4 = e[1], e3 = e[2], e2 = e[3], e1 = e[4], e0 = e[5];
        SG_LOADS_DONE();
        q = e5;
        q = q * r + e4;
        q = q * r + e3;
        q = q * r + e2;
        q = q * r + e1;
        q = q * r + e0;
    }
    bx.f = 1.0f + r * q;
    bx.u += bt.u << 23;
    return bx.f;
}

#endif /* SG_MATH_H */
