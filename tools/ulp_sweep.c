/*
 * ulp_sweep.c - error of codegen/csrc/sg_math.c against the host's double libm (not flight code).
 *
 *   ulp_sweep range  FUNC LO HI          all float32 bit patterns u in [LO, HI)
 *   ulp_sweep sample FUNC SEED N         N random argument pairs (atan2f, powf_pos)
 *
 * Prints one line of key=value fields that tools/ulp_sweep.py merges across processes.
 * Error unit: ulp of the float32 result, ulp(r) = 2^(max(ilogb r, -126) - 23) of the exact
 * (double) reference r; a result whose reference rounds to +-Inf, NaN or is exactly 0 must
 * match in class/bits instead and is counted in `special_bad` otherwise.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sg_math.h"

typedef float (*fn1)(float);
typedef double (*ref1)(double);

static float f_of(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static uint32_t u_of(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

typedef struct {
    double max_ulp;
    uint32_t arg_x, arg_y;
    uint64_t n, gt_half, gt_one, special_bad, outside_bad, outside_n;
} stats_t;

/* Error in ulp of `got` against the exact value `ref`; negative means "class mismatch". */
static double ulp_error(float got, double ref)
{
    float rf = (float)ref;
    if (isnan(ref)) {
        return isnan(got) ? 0.0 : -1.0;
    }
    if (isinf(rf) || ref == 0.0) {
        return u_of(got) == u_of(rf) ? 0.0 : -1.0;
    }
    if (!isfinite(got)) {
        return -1.0;
    }
    int e = ilogb(ref);
    double ulp = ldexp(1.0, (e < -126 ? -126 : e) - 23);
    return fabs((double)got - ref) / ulp;
}

static void account(stats_t *s, float got, double ref, uint32_t ax, uint32_t ay)
{
    double err = ulp_error(got, ref);
    s->n++;
    if (err < 0.0) {
        if (s->special_bad == 0) {
            fprintf(stderr, "special mismatch: x=%08x y=%08x got=%08x ref=%a\n",
                    (unsigned)ax, (unsigned)ay, (unsigned)u_of(got), ref);
        }
        s->special_bad++;
        return;
    }
    s->gt_half += err > 0.5;
    s->gt_one += err > 1.0;
    if (err > s->max_ulp) {
        s->max_ulp = err;
        s->arg_x = ax;
        s->arg_y = ay;
    }
}

static double ref_tanh(double x) { return tanh(x); }
static double ref_exp(double x) { return exp(x); }
static double ref_log(double x) { return log(x); }
static double ref_sin(double x) { return sin(x); }
static double ref_cos(double x) { return cos(x); }
static double ref_asin(double x) { return asin(x); }
static double ref_sqrt(double x) { return sqrt(x); }

static int lookup1(const char *name, fn1 *f, ref1 *r, int *trig)
{
    static const struct { const char *name; fn1 f; ref1 r; int trig; } tab[] = {
        {"tanhf", sg_tanhf, ref_tanh, 0}, {"expf", sg_expf, ref_exp, 0},
        {"logf", sg_logf, ref_log, 0},    {"sinf", sg_sinf, ref_sin, 1},
        {"cosf", sg_cosf, ref_cos, 1},    {"asinf", sg_asinf, ref_asin, 0},
        {"sqrtf", sg_sqrtf, ref_sqrt, 0},
    };
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++) {
        if (strcmp(name, tab[i].name) == 0) {
            *f = tab[i].f;
            *r = tab[i].r;
            *trig = tab[i].trig;
            return 1;
        }
    }
    return 0;
}

/* sin/cos beyond SG_TRIG_MAX_ARG: only "finite and in [-1, 1]" is promised. */
static void account_outside(stats_t *s, float got, float x)
{
    s->outside_n++;
    int ok = isinf(x) ? isnan(got) : (isfinite(got) && got >= -1.0f && got <= 1.0f);
    s->outside_bad += !ok;
}

static void sweep_range(const char *name, uint64_t lo, uint64_t hi, stats_t *s)
{
    fn1 f;
    ref1 r;
    int trig;
    if (!lookup1(name, &f, &r, &trig)) {
        fprintf(stderr, "unknown function %s\n", name);
        exit(2);
    }
    for (uint64_t u = lo; u < hi; u++) {
        float x = f_of((uint32_t)u);
        float got = f(x);
        if (trig && !(fabsf(x) <= SG_TRIG_MAX_ARG) && !isnan(x)) {
            account_outside(s, got, x);
            continue;
        }
        account(s, got, r((double)x), (uint32_t)u, 0);
    }
}

static uint64_t rng_state;

static uint32_t rng32(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (uint32_t)(rng_state >> 16);
}

/* Half random bit patterns, half "ordinary" magnitudes 2^-30..2^30 of random sign. */
static float random_arg(void)
{
    uint32_t u = rng32();
    if (rng32() & 1u) {
        return f_of(u);
    }
    float m = 1.0f + (float)(u & 0xffffu) / 65536.0f;
    float x = ldexpf(m, (int)(rng32() % 61u) - 30);
    return (u >> 31) ? -x : x;
}

static void sample_atan2(uint64_t n, stats_t *s)
{
    for (uint64_t i = 0; i < n; i++) {
        float y = random_arg(), x = random_arg();
        account(s, sg_atan2f(y, x), atan2((double)y, (double)x), u_of(y), u_of(x));
    }
}

/* powf_pos: x > 0 random, y scaled so that |y ln x| <= lim; the bound depends on lim. */
static void sample_pow(uint64_t n, double lim, stats_t *s)
{
    for (uint64_t i = 0; i < n; i++) {
        float x = fabsf(random_arg());
        if (!(x > 0.0f) || isinf(x)) {
            continue;
        }
        double lx = log((double)x);
        double v = ((double)rng32() / 4294967296.0 * 2.0 - 1.0) * lim;
        float y = (float)(lx != 0.0 ? v / lx : v);
        account(s, sg_powf_pos(x, y), pow((double)x, (double)y), u_of(x), u_of(y));
    }
}

static void print_stats(const char *name, const stats_t *s)
{
    printf("func=%s n=%llu max_ulp=%.6f arg_x=%08x arg_y=%08x gt_half=%llu gt_one=%llu "
           "special_bad=%llu outside_n=%llu outside_bad=%llu\n",
           name, (unsigned long long)s->n, s->max_ulp, (unsigned)s->arg_x, (unsigned)s->arg_y,
           (unsigned long long)s->gt_half, (unsigned long long)s->gt_one,
           (unsigned long long)s->special_bad, (unsigned long long)s->outside_n,
           (unsigned long long)s->outside_bad);
}

int main(int argc, char **argv)
{
    stats_t s;
    memset(&s, 0, sizeof s);
    if (argc == 5 && strcmp(argv[1], "range") == 0) {
        sweep_range(argv[2], strtoull(argv[3], NULL, 0), strtoull(argv[4], NULL, 0), &s);
    } else if (argc == 5 && strcmp(argv[1], "sample") == 0) {
        rng_state = strtoull(argv[3], NULL, 0) * 0x9e3779b97f4a7c15ull + 1u;
        uint64_t n = strtoull(argv[4], NULL, 0);
        if (strcmp(argv[2], "atan2f") == 0) {
            sample_atan2(n, &s);
        } else if (strncmp(argv[2], "powf_pos:", 9) == 0) {
            sample_pow(n, strtod(argv[2] + 9, NULL), &s);
        } else {
            fprintf(stderr, "unknown sampled function %s\n", argv[2]);
            return 2;
        }
    } else {
        fprintf(stderr, "usage: ulp_sweep range FUNC LO HI | sample FUNC SEED N\n");
        return 2;
    }
    print_stats(argv[2], &s);
    return 0;
}
