/* Start-up and I/O of the QEMU image, without a C library: the vector table, a reset handler
 * that fills .data and .bss and turns the FPU on before `main` (the library is built for
 * thumbv7em-none-eabihf: hardware single precision, float arguments in FPU registers), and
 * ARM semihosting (`bkpt 0xAB`) for text output and QEMU's exit status. */
#include <stdint.h>
#include "startup.h"

extern uint32_t stack_top, data_start, data_end, data_load, bss_start, bss_end;
int main(void);

/* Semihosting call `op` with argument `arg` (what QEMU's `-semihosting-config
 * enable=on,target=native` answers). */
static int semihost(int op, const void *arg) {
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void put(const char *s) { semihost(0x04 /* SYS_WRITE0 */, s); }

void exit_qemu(int ok) {
    /* SYS_EXIT with ADP_Stopped_ApplicationExit (QEMU exits 0) or
     * ADP_Stopped_RunTimeErrorUnknown (QEMU exits 1). */
    semihost(0x18, (const void *)(uintptr_t)(ok ? 0x20026 : 0x20023));
    for (;;) {
        __asm__ volatile("wfi");
    }
}

static void fault(void) { exit_qemu(0); }

void reset_handler(void) {
    for (uint32_t *s = &data_load, *d = &data_start; d < &data_end;) {
        *d++ = *s++;
    }
    for (uint32_t *d = &bss_start; d < &bss_end;) {
        *d++ = 0;
    }
    /* CPACR: full access to CP10 and CP11 (the FPU), before any floating-point instruction. */
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20;
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    exit_qemu(main() == 0);
}

/* Initial stack pointer, reset, then NMI, HardFault and the other exceptions: all end the run
 * as a failure. */
__attribute__((section(".vector_table"), used)) void (*const vectors[16])(void) = {
    (void (*)(void))&stack_top, reset_handler, fault, fault, fault, fault, fault, 0, 0, 0, 0,
    fault, fault, 0, fault, fault,
};
