/* STM32F417 start-up: vector table, .data/.bss initialisation, FPU on, FPSCR to IEEE defaults.
 *
 * No HAL and no CMSIS: the three system registers used are written by address (ARMv7-M ARM,
 * B3.2). The clock tree is left at reset (HSI 16 MHz): the cycle model counts cycles, and the
 * flash wait states it charges are a model parameter, not something this code configures. */
#include <stdint.h>

#include "harness.h"

extern uint32_t _sidata[], _sdata[], _edata[], _sbss[], _ebss[], _estack[];
extern uint32_t _sitables[], _stables[], _etables[];

#define SCB_CPACR  (*(volatile uint32_t *)0xE000ED88u)
#define FPU_FPDSCR (*(volatile uint32_t *)0xE000EF3Cu)

/* CP10 and CP11 full access (CPACR bits 20..23). */
#define CPACR_CP10_CP11_FULL (0xFu << 20)
/* FPSCR: RMode = 00 (round to nearest even), FZ = 0, DN = 0, AHP = 0, no flags. */
#define FPSCR_IEEE 0u

void Reset_Handler(void);
void Default_Handler(void);

/* .data, the constant tables and .bss are initialised word by word through volatile pointers so
 * that GCC cannot turn the loops into memcpy/memset calls (we link without the C library). The
 * tables are copied only when the linker script placed them in RAM (load address != address). */
static void init_memory(void)
{
    volatile uint32_t *src = _sidata;
    volatile uint32_t *dst = _sdata;
    while (dst < _edata) {
        *dst++ = *src++;
    }
    src = _sitables;
    dst = _stables;
    if (src != dst) {
        while (dst < _etables) {
            *dst++ = *src++;
        }
    }
    for (dst = _sbss; dst < _ebss; ) {
        *dst++ = 0u;
    }
}

static void enable_fpu(void)
{
    SCB_CPACR |= CPACR_CP10_CP11_FULL;
    __asm__ volatile ("dsb\n\tisb" ::: "memory");
    /* Exception entries inherit FPDSCR; keep them on the same IEEE settings. */
    FPU_FPDSCR = FPSCR_IEEE;
    __asm__ volatile ("vmsr fpscr, %0" : : "r" (FPSCR_IEEE) : "memory");
}

/* Everything Reset_Handler does before main; the emulator calls it directly. */
void system_init(void)
{
    init_memory();
    enable_fpu();
}

void Reset_Handler(void)
{
    system_init();
    (void)main();
    for (;;) {
        __asm__ volatile ("bkpt #0");
    }
}

/* Any fault or unexpected interrupt stops at a breakpoint: the emulator reports it, a debugger
 * on the board halts there. */
void Default_Handler(void)
{
    for (;;) {
        __asm__ volatile ("bkpt #1");
    }
}

/* 16 Cortex-M4 system entries + 82 STM32F417 interrupts (RM0090 table 61). Entry 0 is the
 * initial stack pointer, stored as an address; reserved entries are 0. */
#define D ((uintptr_t)Default_Handler)
#define D8 D, D, D, D, D, D, D, D

__attribute__((section(".isr_vector"), used))
const uintptr_t vector_table[16 + 82] = {
    (uintptr_t)_estack, (uintptr_t)Reset_Handler,
    D, D, D, D, D,          /* NMI, HardFault, MemManage, BusFault, UsageFault */
    0u, 0u, 0u, 0u,         /* reserved */
    D, D,                   /* SVCall, DebugMonitor */
    0u,                     /* reserved */
    D, D,                   /* PendSV, SysTick */
    D8, D8, D8, D8, D8, D8, D8, D8, D8, D8, D, D,   /* IRQ0..IRQ81 */
};
