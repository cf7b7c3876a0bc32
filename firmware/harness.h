/* Harness contract between the host (emulator or debugger) and one generated entry point.
 *
 * The host writes N input records into SRAM, calls harness_run(in, out, N) and reads N output
 * records back. An adapter (rendered from firmware/adapters/<kind>.c.j2) maps one record to
 * one call of the entry point and owns any controller state; harness_reset() re-initialises
 * that state. Records are raw bytes whose layout the adapter's types define (float32 arrays,
 * little-endian). See firmware/README.md. */
#ifndef HARNESS_H
#define HARNESS_H

#include <stdint.h>

/* Implemented by the adapter. */
extern const uint32_t adapter_in_bytes;
extern const uint32_t adapter_out_bytes;
void adapter_reset(void);
void adapter_step(const void *in, void *out);

/* Implemented by harness.c; called by the host. */
void harness_reset(void);
uint32_t harness_run(const uint8_t *in, uint8_t *out, uint32_t n);

/* Number of records main() processes from the arena (set by a debugger on a board). */
extern volatile uint32_t harness_count;

/* Implemented by startup.c. */
void system_init(void);
int main(void);

#endif /* HARNESS_H */
