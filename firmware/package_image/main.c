/* main() of the minimal firmware image around a flight package: the self-test, then one
 * reference step, as a firmware team would call them at start-up. Generic over the package:
 * SG_PKG is its name (stare -> stare_selftest, stare_state_t, ...). */
#include <stdint.h>

#define SG_CAT2(a, b) a##b
#define SG_CAT(a, b) SG_CAT2(a, b)
#define SG_STR2(x) #x
#define SG_STR(x) SG_STR2(x)
#define SG_FN(suffix) SG_CAT(SG_PKG, suffix)

#include SG_STR(SG_CAT(SG_PKG, _selftest.h))

/* Read by the emulator (or a debugger on the board) after main returns. */
volatile int32_t sg_image_result = -1;
volatile uint32_t sg_image_status;

#if defined(SG_IMAGE_ARM)
#include "harness.h"   /* startup.c's prototypes (system_init, main) */
#else
#include <stdio.h>
#endif

int main(void)
{
    SG_FN(_state_t) state;
    SG_FN(_input_t) input;
    SG_FN(_output_t) output;
    const int32_t mismatches = (int32_t)SG_FN(_selftest)();
    SG_FN(_selftest_reference)(&state, &input);
    SG_FN(_step)(&state, &input, &output);
    sg_image_status = output.status;
    sg_image_result = mismatches;
#if !defined(SG_IMAGE_ARM)
    printf("selftest mismatches: %d\n", (int)mismatches);
#endif
    return mismatches == 0 ? 0 : 1;
}
