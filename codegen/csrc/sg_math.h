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
 *   sampled) 1.59 at y = 0.8, <= 1.2 + |y| in general; sg_powf_tab 1.33 at y = 0.8, <= 1.2 + |y|;
 *   sg_powf_const 2.31 at y = 0.8, <= 2.5 for |y| <= 31/32; sg_logf_tab 2.88 (all sampled).
 * Published bounds: 2 ulp (3 for atan2). docs/math.md has the table, the methods, the domains
 * and the Cortex-M4 cycle estimates.
 *
 * NaN in gives NaN out (sign/payload unspecified). Other special values follow C99 Annex F
 * unless stated.
 */
#ifndef SG_MATH_H
#define SG_MATH_H

/* Build guard: refuse the compiler settings that silently change results (SPEC section 5).
 * Detected here: -ffast-math / -Ofast (__FAST_MATH__), -ffinite-math-only, excess precision
 * (FLT_EVAL_METHOD != 0, e.g. x87), and GNU C mode (-std=gnu*), whose default is
 * -ffp-contract=fast, unless the build states -ffp-contract=off by defining SG_FP_CONTRACT_OFF.
 * Not detectable by the preprocessor: -ffp-contract=fast given explicitly in ISO mode,
 * -fassociative-math / -funsafe-math-optimizations / -freciprocal-math without -ffast-math, and
 * flush-to-zero or a directed rounding mode set at run time. The package self-test
 * (<name>_selftest) catches those on the target. */
#if defined(__FAST_MATH__)
#error "sg_math: built with -ffast-math (or -Ofast): results would differ from the golden model; remove it"
#endif
#if defined(__FINITE_MATH_ONLY__) && __FINITE_MATH_ONLY__
#error "sg_math: built with -ffinite-math-only: NaN and infinity handling is required; remove it"
#endif
#if defined(__FLT_EVAL_METHOD__) && (__FLT_EVAL_METHOD__ != 0) && (__FLT_EVAL_METHOD__ != -1)
#error "sg_math: float expressions evaluated in excess precision (FLT_EVAL_METHOD != 0); use SSE / the FPU's single precision"
#endif
#if defined(__GNUC__) && !defined(__STRICT_ANSI__) && !defined(SG_FP_CONTRACT_OFF)
#error "sg_math: GNU C mode contracts a*b+c into fused multiply-adds by default; build with -std=c99, or add -ffp-contract=off -DSG_FP_CONTRACT_OFF"
#endif

/* GCC's builtins where the compiler has them (GCC, clang, armclang); otherwise, or with
 * -DSG_NO_BUILTINS (how the tests build them), portable C99 with the same bits: fabs by the sign
 * bit, sqrt correctly rounded in integer arithmetic (sg_sqrtf_c99), no branch hint. */
#if (defined(__GNUC__) || defined(__clang__)) && !defined(SG_NO_BUILTINS)
#define SG_HAVE_BUILTINS 1
#define SG_FABSF(x) __builtin_fabsf(x)
#define SG_SQRTF(x) __builtin_sqrtf(x)
#define SG_EXPECT(c, v) __builtin_expect((c), (v))
#else
#define SG_HAVE_BUILTINS 0
#define SG_FABSF(x) sg_fabsf_c99(x)
#define SG_SQRTF(x) sg_sqrtf_c99(x)
#define SG_EXPECT(c, v) ((c) ? 1 : 0)
#endif

/* With math errno on (GCC's and clang's default on most hosts) __builtin_sqrtf calls libm's sqrtf
 * for a negative argument, to set errno: the "no libm" promise would break silently. */
#if SG_HAVE_BUILTINS && !defined(__NO_MATH_ERRNO__)
#error "sg_math: math errno is on, so sqrt would call libm's sqrtf; build with -fno-math-errno"
#endif

#include <stdint.h>

/* Every constant table of the package (sg_math's, the units') lies in a section of its own,
 * SG_TABLE(".sg_tables.<table>"), so that a linker script can place the package's tables, and
 * nothing else of the firmware's read-only data, e.g. in CCM:
 *   .sg_tables : { *(.sg_tables .sg_tables.*) } > CCM AT > FLASH
 * One section per table: --gc-sections still drops an unused one. */
#if defined(__GNUC__) || defined(__clang__)
#define SG_TABLE(section_name) __attribute__((section(section_name)))
#else
#define SG_TABLE(section_name)
#endif

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
/* The same for constants that GCC would otherwise reload from the literal pool one by one next
 * to each use: the empty asm takes them in FPU registers, so their loads are issued together
 * before it (ARM hard-float only; no instruction, no effect on results). */
#if defined(__GNUC__) && defined(__arm__) && defined(__VFP_FP__) && !defined(__SOFTFP__)
#define SG_IN_REGS4(a, b, c, d) __asm__("" : "+t"(a), "+t"(b), "+t"(c), "+t"(d))
#else
#define SG_IN_REGS4(a, b, c, d) ((void)0)
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
/* d = (ux << 1) - SG_TANH_D_FIRST: the magnitude bits of x (2 per ulp) above those of 2^-12. The
 * interval is d >> SG_TANH_SHIFT (= sg_tanh_index(ux)); d >= SG_TANH_D_END outside [2^-12, 9),
 * d > SG_TANH_D_INF for NaN and for |x| < 2^-12 (d wraps around). Written out as 32-bit
 * constants (an unsigned constant expression's essential type is its smallest type, so
 * SG_TANH_FIRST << SG_TANH_SHIFT would shift a 16-bit value by 21: MISRA C:2012 12.2). */
#define SG_TANH_SHIFT (24u - SG_TANH_M)
#define SG_TANH_D_FIRST 0x73000000u /* SG_TANH_FIRST << SG_TANH_SHIFT = (127 - 12) << 24 */
#define SG_TANH_D_END 0x0f200000u   /* SG_TANH_N << SG_TANH_SHIFT = 121 << 21 */
#define SG_TANH_D_INF 0x8c000000u   /* 0xff000000 - SG_TANH_D_FIRST: d of +-Inf */
extern const float sg_tanh_tab[SG_TANH_N][SG_TANH_COLS];

typedef union {
    float f;
    uint32_t u;
} sg_bits_t;

#if !SG_HAVE_BUILTINS
/* |x| by clearing the sign bit: __builtin_fabsf's bits for every x, NaN included. */
static inline float sg_fabsf_c99(float x)
{
    sg_bits_t b;
    b.f = x;
    b.u &= 0x7fffffffu;
    return b.f;
}

/* Correctly rounded sqrt (round to nearest even) by digit-by-digit root extraction on the
 * significand: __builtin_sqrtf's bits (VSQRT / sqrtss) for every x; sg_math.c. */
float sg_sqrtf_c99(float x);
#endif

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
    const float c = row[0];
    const float c0 = row[1];
    const float c1 = row[2];
    const float c2 = row[3];
    const float c3 = row[4];
    const float c4 = row[5];
    float t;
    float p;
    SG_LOADS_DONE();
    t = SG_FABSF(x) - c;
    p = c4;
    p = (p * t) + c3;
    p = (p * t) + c2;
    p = (p * t) + c1;
    p = (p * t) + c0;
    return ((ux >> 31) != 0u) ? -p : p;
}

static inline float sg_inline_tanhf(float x)
{
    sg_bits_t b;
    uint32_t i;
    float r;
    b.f = x;
    i = sg_tanh_index(b.u);
    if (SG_EXPECT(i >= SG_TANH_N, 0) != 0) {
        r = sg_tanhf(x);
    } else {
        r = sg_tanh_poly(sg_tanh_tab[i], x, b.u);
    }
    return r;
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
    d = (b.u << 1) - SG_TANH_D_FIRST;
    if (SG_EXPECT(d < SG_TANH_D_END, 1) != 0) {
        return sg_tanh_poly(sg_tanh_tab[d >> SG_TANH_SHIFT], x, b.u);
    }
    if (d > SG_TANH_D_INF) {
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
    sg_bits_t bx;
    float result;
    bx.f = x;
    if (SG_EXPECT((bx.u - 0x00800000u) >= 0x7f000000u, 0) != 0) {
        result = sg_powf_pos(x, y); /* not a positive normal finite float */
    } else {
        sg_bits_t by;
        uint32_t ix;
        int32_t k;
        float kf;
        float f;
        float p;
        float lm;
        float yh;
        float yl;
        float th;
        float tl;
        float t;
        ix = bx.u + (0x3f800000u - 0x3f3504f3u);
        k = (int32_t)(ix >> 23) - 127;
        kf = (float)k;
        bx.u = (ix & 0x007fffffu) + 0x3f3504f3u;
        f = bx.f - 1.0f;
        {
            const float *c = sg_powf_fused_tab;
            const float c7 = c[0];
            const float c6 = c[1];
            const float c5 = c[2];
            const float c4 = c[3];
            const float c3 = c[4];
            const float c2 = c[5];
            const float c1 = c[6];
            const float c0 = c[7];
            SG_LOADS_DONE();
            p = c7;
            p = (p * f) + c6;
            p = (p * f) + c5;
            p = (p * f) + c4;
            p = (p * f) + c3;
            p = (p * f) + c2;
            p = (p * f) + c1;
            p = (p * f) + c0;
        }
        lm = f * p;
        by.f = y;
        by.u &= 0xfffff000u;
        yh = by.f;
        yl = y - yh;
        th = yh * kf;
        tl = (yl * kf) + (y * lm);
        t = th + tl;
        /* |y| <= 31/32 implies |t| <= 124 for every normal x: with such a constant y (the tanh law's)
         * the compiler drops the test on t; the fast-path set is the same either way. */
        if (SG_EXPECT(!(SG_FABSF(y) <= 0x1.fp-1f) && !(SG_FABSF(t) < SG_POWF_FUSED_MAX_T), 0) != 0) {
            result = sg_powf_pos(x, y);
        } else {
            sg_bits_t bt;
            float nf;
            float r;
            float q;
            bt.f = t + 0x1.8p+23f;
            nf = bt.f - 0x1.8p+23f;
            r = (th - nf) + tl;
            {
                const float *e = &sg_powf_fused_tab[8];
                const float e5 = e[0];
                const float e4 = e[1];
                const float e3 = e[2];
                const float e2 = e[3];
                const float e1 = e[4];
                const float e0 = e[5];
                SG_LOADS_DONE();
                q = e5;
                q = (q * r) + e4;
                q = (q * r) + e3;
                q = (q * r) + e2;
                q = (q * r) + e1;
                q = (q * r) + e0;
            }
            bx.f = 1.0f + (r * q);
            bx.u += bt.u << 23;
            result = bx.f;
        }
    }
    return result;
}

/* ---- sg_powf_tab: sg_powf_fused's domain, table-driven (fewer loads and multiplies) ------
 * A different function from sg_powf_fused (other bits, same fast-path set and fallback).
 * log2 x: ix = bits(x) + 0x4d0000, k = (ix >> 23) - 127, z = x / 2^k in
 * [0x1.66p-1, 0x1.66p+0), i = bits 18..22 of ix picks c_i (the interval's midpoint),
 * r = (z - c_i) (exact, Sterbenz) * (1/c_i), |r| < 0.0151, log2 z = log2 c_i + r (a0 + r (a1 + r a2))
 * (absolute error 3.6e-9). With Y = 32 y split as Yh (top 12 bits) + Yl: T = Yh k (exact) +
 * (Yl k + Y log2 z) = 32 y log2 x, n = round(T) by the magic add, u = (Yh k - n) + (Yl k + Y log2 z)
 * in [-0.5, 0.5], result = 2^(n >> 5) (S + S q), S = 2^((n & 31)/32) from a 32-entry table of
 * float32 bits, q = u (b0 + u (b1 + u b2)) = 2^(u/32) - 1 (error 1.3e-10). The exponent is added
 * to S's bits in the core registers. Fast path as sg_powf_fused's (x positive normal, |y log2 x|
 * < 125); else sg_powf_pos(x, y). Error and cycles: docs/math.md. */
#define SG_POWF_TAB_N 32u
extern const float sg_powf_tab_log[SG_POWF_TAB_N][3]; /* c, 1/c, log2 c */
extern const float sg_powf_tab_poly[6];                /* a0, a1, a2, b0, b1, b2 */
extern const uint32_t sg_powf_tab_exp2[SG_POWF_TAB_N]; /* bits of 2^(j/32) */

static SG_ALWAYS_INLINE float sg_powf_tab(float x, float y)
{
    sg_bits_t bx;
    float result;
    bx.f = x;
    if (SG_EXPECT((bx.u - 0x00800000u) >= 0x7f000000u, 0) != 0) {
        result = sg_powf_pos(x, y); /* not a positive normal finite float */
    } else {
        sg_bits_t by;
        uint32_t ix;
        int32_t k;
        float kf;
        float z;
        float lz;
        float y32;
        float yh;
        float yl;
        float th;
        float tl;
        float t;
        const float *row;
        ix = bx.u + (0x3f800000u - 0x3f330000u);
        k = (int32_t)(ix >> 23) - 127;
        kf = (float)k;
        row = sg_powf_tab_log[(ix >> 18) & 31u];
        bx.u = (ix & 0x007fffffu) + 0x3f330000u;
        z = bx.f;
        {
            const float c = row[0];
            const float ic = row[1];
            const float lc = row[2];
            const float a0 = sg_powf_tab_poly[0];
            const float a1 = sg_powf_tab_poly[1];
            const float a2 = sg_powf_tab_poly[2];
            float r;
            SG_LOADS_DONE();
            r = (z - c) * ic;
            lz = lc + (r * ((((a2 * r) + a1) * r) + a0));
        }
        y32 = 32.0f * y;
        by.f = y32;
        by.u &= 0xfffff000u;
        yh = by.f;
        yl = y32 - yh;
        th = yh * kf;
        tl = (yl * kf) + (y32 * lz);
        t = th + tl;
        /* |y| <= 31/32 implies |t| <= 32 * 124 for every normal x: the test on t folds away for
         * such a constant y; the fast-path set is the same either way. */
        if (SG_EXPECT(!(SG_FABSF(y) <= 0x1.fp-1f) && !(SG_FABSF(t) < (32.0f * SG_POWF_FUSED_MAX_T)), 0) != 0) {
            result = sg_powf_pos(x, y);
        } else {
            sg_bits_t bt;
            float nf;
            float u;
            float q;
            bt.f = t + 0x1.8p+23f;
            nf = bt.f - 0x1.8p+23f;
            u = (th - nf) + tl;
            {
                const float b0 = sg_powf_tab_poly[3];
                const float b1 = sg_powf_tab_poly[4];
                const float b2 = sg_powf_tab_poly[5];
                SG_LOADS_DONE();
                q = u * ((((b2 * u) + b1) * u) + b0);
            }
            bx.u = sg_powf_tab_exp2[bt.u & 31u] + ((bt.u >> 5) << 23);
            result = bx.f + (bx.f * q);
        }
    }
    return result;
}

/* ---- sg_powf_const: x^y for an exponent fixed at generation time -----------------------
 * For |y| < 1 (error bound for |y| <= 31/32), with tables built for that y by codegen/detmath.powc_tables (the
 * generator emits them with the code): x = 2^k z as in sg_powf_tab (k in [-126, 128], z in
 * interval i with midpoint c_i), r = (z - c_i) (exact) * (1/c_i), |r| < 0.0151, and
 * x^y = (c_i^y 2^(y k)) (1 + q), q = r (p0 + r (p1 + r (p2 + r p3))) = (1 + r)^y - 1 (Taylor,
 * p0 = y; truncation <= 5e-11 relative): c_i^y and 2^(y k) are float32 table entries (32 and
 * 255), so there is no exp2 at all and no range test (|y| <= 31/32 keeps every result normal;
 * closer to 1 the table's ends are clamped to the float32 range).
 * y > 0 and x = +0 or subnormal: +0, without a call (the true value is below 2^(-126 y); so a
 * caller whose x is never negative, infinite or NaN has no slow path at all). Any other x not a
 * positive normal float (-0, negative, +Inf, NaN; 0 and subnormals when y < 0): sg_powf_pos(x, y).
 * Error and cycles: docs/math.md. */
#define SG_POWC_NK 255u /* k = -126 .. 128 */
typedef struct {
    float y;                     /* the exponent */
    float p[4];                  /* p0 .. p3 */
    float row[SG_POWF_TAB_N][4]; /* c_i, 1/c_i, c_i^y, 0: one address for the three loads */
    float ek[SG_POWC_NK];        /* 2^(y k), k = -126 .. 128 */
} sg_powc_t;

static SG_ALWAYS_INLINE float sg_powf_const(float x, const sg_powc_t *t)
{
    sg_bits_t bx;
    float result;
    bx.f = x;
    if (SG_EXPECT((bx.u - 0x00800000u) >= 0x7f000000u, 0) != 0) {
        if ((t->y > 0.0f) && (bx.u < 0x00800000u)) {
            result = 0.0f; /* +0 or subnormal x, y > 0: +0 (exact at 0, below 2^(-126 y) otherwise) */
        } else {
            result = sg_powf_pos(x, t->y); /* -0, negative, +Inf, NaN; y < 0 at +0 or subnormal x */
        }
    } else {
        uint32_t ix;
        float z;
        float q;
        float s;
        const float *row;
        ix = bx.u + (0x3f800000u - 0x3f330000u);
        row = t->row[(ix >> 18) & 31u];
        /* (ix & 0x7fffff) + 0x3f330000, written so that the constant is one Thumb-2 immediate */
        bx.u = (bx.u + 0x3f800000u) - ((ix >> 23) << 23);
        z = bx.f;
        {
            const float c = row[0];
            const float ic = row[1];
            const float cy = row[2];
            const float ek = t->ek[(ix >> 23) - 1u];
            float p0 = t->p[0];
            float p1 = t->p[1];
            float p2 = t->p[2];
            float p3 = t->p[3];
            float r;
            SG_IN_REGS4(p0, p1, p2, p3); /* the four coefficient loads issued together */
            SG_LOADS_DONE();
            r = (z - c) * ic;
            q = r * ((((((p3 * r) + p2) * r) + p1) * r) + p0);
            s = cy * ek;
        }
        result = s + (s * q);
    }
    return result;
}

/* ---- sg_logf_tab: ln x, table-driven, inline --------------------------------------------
 * A different function from sg_logf (other bits). x positive normal: x = 2^k z as in
 * sg_powf_tab, r = (z - c_i) (exact) * (1/c_i) with c_i = 1 in the interval holding 1 (r = z - 1
 * exactly there), ln z = ln c_i + r (1 + r (-1/2 + r (1/3 + r (-1/4 + r/5)))) (truncation
 * <= 2e-9 relative), ln x = k ln2_hi (exact) + (k ln2_lo + ln z). Anything else (x <= 0,
 * subnormal, +Inf, NaN): sg_logf(x). Error and cycles: docs/math.md. */
extern const float sg_logf_tab_rows[SG_POWF_TAB_N][3]; /* c, 1/c, ln c */

static SG_ALWAYS_INLINE float sg_logf_tab(float x)
{
    sg_bits_t bx;
    float result;
    bx.f = x;
    if (SG_EXPECT((bx.u - 0x00800000u) >= 0x7f000000u, 0) != 0) {
        result = sg_logf(x); /* not a positive normal finite float */
    } else {
        uint32_t ix;
        int32_t k;
        float kf;
        float z;
        float lz;
        const float *row;
        ix = bx.u + (0x3f800000u - 0x3f330000u);
        k = (int32_t)(ix >> 23) - 127;
        kf = (float)k;
        row = sg_logf_tab_rows[(ix >> 18) & 31u];
        bx.u = (ix & 0x007fffffu) + 0x3f330000u;
        z = bx.f;
        {
            const float c = row[0];
            const float ic = row[1];
            const float lc = row[2];
            float r;
            SG_LOADS_DONE();
            r = (z - c) * ic;
            lz = lc + (r * ((((((((0x1.99999ap-3f * r) - 0x1.0p-2f) * r) + 0x1.555556p-2f) * r) - 0x1.0p-1f) * r) + 1.0f));
        }
        result = (kf * 0x1.62e4p-1f) + ((kf * 0x1.7f7d1cp-20f) + lz);
    }
    return result;
}

/* CRC-32 (IEEE 802.3, reflected, poly 0xEDB88320) of `bytes` bytes, continuing from `crc`
 * (0 to start): zlib.crc32(data, crc). Bitwise, no table (a table would itself need checking);
 * about 8 * 4 cycles per byte on the Cortex-M4: for the integrity checks at start-up. */
uint32_t sg_crc32(const void *data, uint32_t bytes, uint32_t crc);

/* x, or the one canonical quiet NaN 0x7FC00000 when x is a NaN. Every generated output that can
 * be NaN passes through it, so golden, x86 and ARM agree bit for bit on NaN too (x86 makes
 * negative default NaNs, ARM positive ones, and payloads propagate per target). */
#define SG_CANONICAL_NAN_BITS 0x7FC00000u
static inline float sg_canonf(float x)
{
    sg_bits_t b;
    b.f = x;
    if (x != x) {
        b.u = SG_CANONICAL_NAN_BITS;
    }
    return b.f;
}

#endif /* SG_MATH_H */
