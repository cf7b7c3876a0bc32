/* main() of the minimal firmware image around a flight package: the self-test, then one
 * reference step, as a firmware team would call them at start-up. Generic over the package:
 * SG_PKG is its name (stare -> stare_selftest, stare_state_t, ...).
 *
 * SG_IMAGE_SEMIHOSTING (the QEMU image): the result and the reference step's output words are
 * printed by ARM semihosting (SYS_WRITE0) and the run ends with SYS_EXIT. */
#include <stdint.h>

#define SG_CAT2(a, b) a##b
#define SG_CAT(a, b) SG_CAT2(a, b)
#define SG_STR2(x) #x
#define SG_STR(x) SG_STR2(x)
#define SG_FN(suffix) SG_CAT(SG_PKG, suffix)

#include SG_STR(SG_CAT(SG_PKG, _selftest.h))

#define SG_OUTPUT_WORDS (sizeof(SG_FN(_output_t)) / sizeof(uint32_t))

/* Read by the emulator (or a debugger on the board) after main returns. */
volatile int32_t sg_image_result = -1;
volatile uint32_t sg_image_status;
/* The reference step's output record as words: every emulator must give the same. */
volatile uint32_t sg_image_output[SG_OUTPUT_WORDS];
volatile uint32_t sg_image_output_words = (uint32_t)SG_OUTPUT_WORDS;

#if defined(SG_IMAGE_ARM)
#include "harness.h"   /* startup.c's prototypes (system_init, main) */
#else
#include <stdio.h>
#endif

#if defined(SG_IMAGE_SEMIHOSTING)
#define SG_SYS_WRITE0 0x04u
#define SG_SYS_EXIT 0x18u
#define SG_ADP_APPLICATION_EXIT 0x20026u   /* QEMU exits with status 0 */
#define SG_ADP_RUN_TIME_ERROR 0x20023u     /* any other reason: status 1 */

static void sg_semihost(uint32_t op, uint32_t arg)
{
    register uint32_t r0 __asm__("r0") = op;
    register uint32_t r1 __asm__("r1") = arg;
    __asm__ volatile ("bkpt 0xAB" : "+r" (r0) : "r" (r1) : "memory");
}

/* Characters are stored through a volatile pointer: no loop may become a libc call (no libc). */
static volatile char *sg_put_text(volatile char *p, const char *s)
{
    while (*s != '\0') {
        *p++ = *s++;
    }
    return p;
}

static volatile char *sg_put_hex(volatile char *p, uint32_t v)
{
    int shift;
    for (shift = 28; shift >= 0; shift -= 4) {
        *p++ = "0123456789abcdef"[(v >> shift) & 0xFu];
    }
    return p;
}

static volatile char *sg_put_dec(volatile char *p, int32_t v)
{
    char digits[12];
    int n = 0;
    uint32_t u = (v < 0) ? (0u - (uint32_t)v) : (uint32_t)v;
    if (v < 0) {
        *p++ = '-';
    }
    do {
        digits[n++] = (char)('0' + (u % 10u));
        u /= 10u;
    } while (u != 0u);
    while (n > 0) {
        *p++ = digits[--n];
    }
    return p;
}

/* "selftest mismatches: N\nreference output: w0 w1 ...\n" to the host, then exit. */
static void sg_report(int32_t mismatches)
{
    static char text[64 + 9u * SG_OUTPUT_WORDS];
    volatile char *p = sg_put_dec(sg_put_text(text, "selftest mismatches: "), mismatches);
    uint32_t j;
    p = sg_put_text(p, "\nreference output:");
    for (j = 0u; j < SG_OUTPUT_WORDS; ++j) {
        p = sg_put_hex(sg_put_text(p, " "), sg_image_output[j]);
    }
    p = sg_put_text(p, "\n");
    *p = '\0';
    sg_semihost(SG_SYS_WRITE0, (uint32_t)(uintptr_t)text);
    sg_semihost(SG_SYS_EXIT, (mismatches == 0) ? SG_ADP_APPLICATION_EXIT : SG_ADP_RUN_TIME_ERROR);
}
#endif

int main(void)
{
    SG_FN(_state_t) state;
    SG_FN(_input_t) input;
    union { SG_FN(_output_t) s; uint32_t w[SG_OUTPUT_WORDS]; } output;
    uint32_t j;
    const int32_t mismatches = (int32_t)SG_FN(_selftest)();
    SG_FN(_selftest_reference)(&state, &input);
    SG_FN(_step)(&state, &input, &output.s);
    for (j = 0u; j < SG_OUTPUT_WORDS; ++j) {
        sg_image_output[j] = output.w[j];
    }
    sg_image_status = output.s.status;
    sg_image_result = mismatches;
#if defined(SG_IMAGE_SEMIHOSTING)
    sg_report(mismatches);
#elif !defined(SG_IMAGE_ARM)
    printf("selftest mismatches: %d\n", (int)mismatches);
#endif
    return mismatches == 0 ? 0 : 1;
}
