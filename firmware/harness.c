/* Batch runner: one adapter step per record, records packed back to back. */
#include <stdint.h>

#include "harness.h"

/* Linker-defined record arena in SRAM (stm32f417.ld). */
extern uint8_t _sarena[];

volatile uint32_t harness_count;

void harness_reset(void)
{
    adapter_reset();
}

uint32_t harness_run(const uint8_t *in, uint8_t *out, uint32_t n)
{
    uint32_t i;
    for (i = 0u; i < n; ++i) {
        adapter_step(in, out);
        in += adapter_in_bytes;
        out += adapter_out_bytes;
    }
    return n;
}

/* On a board: inputs at the start of the arena, outputs right after them. */
int main(void)
{
    const uint32_t n = harness_count;
    harness_reset();
    (void)harness_run(_sarena, _sarena + n * adapter_in_bytes, n);
    return 0;
}
