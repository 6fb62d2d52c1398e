/* startup.c - vector table and reset code for the Arm MPS2 boards
 * (AN385: Cortex-M3, AN386: Cortex-M4F), as QEMU models them.
 *
 * At reset the core loads SP from word 0 of the vector table and PC from
 * word 1 (the table sits at address 0, VTOR's reset value). reset_handler
 * then
 *   1. enables the FPU (full access for CP10 and CP11 in CPACR) when the
 *      code is built for one (__ARM_FP): this must happen before the first
 *      floating-point instruction, so it is written in assembly in a naked
 *      function, where the compiler cannot place one;
 *   2. copies .data from its load address in SSRAM1 to SSRAM2/3 and zeroes
 *      .bss (symbols from mps2.ld);
 *   3. opens newlib's semihosting handles (what rdimon's crt0 would do;
 *      this program is linked with -nostartfiles), calls main and passes
 *      its status to exit, which flushes stdout and ends the emulation by
 *      the semihosting SYS_EXIT call.
 * A fault ends the emulation too, with a failure status, instead of
 * spinning until the caller's timeout.
 */
#include <stdint.h>
#include <stdlib.h>

/* Provided by mps2.ld. */
extern uint32_t __data_load[], __data_start[], __data_end[];
extern uint32_t __bss_start__[], __bss_end__[];
extern uint32_t __stack_top[];

int main(void);
void initialise_monitor_handles(void); /* newlib's librdimon */

void reset_handler(void);
void start(void) __attribute__((noreturn, used));
static void fault_handler(void);

typedef void (*Handler)(void);

/* The Armv7-M vector table: initial stack pointer, 15 system exceptions,
   then the board's 32 interrupts (all unused here). */
typedef struct VectorTable {
    uint32_t *initial_sp;
    Handler reset, nmi, hard_fault, mem_manage, bus_fault, usage_fault;
    Handler reserved1[4];
    Handler svcall, debug_monitor, reserved2, pendsv, systick;
    Handler irq[32];
} VectorTable;

__attribute__((section(".vectors"), used))
static const VectorTable vectors = {
    __stack_top,
    reset_handler, fault_handler, fault_handler, fault_handler, fault_handler, fault_handler,
    {0, 0, 0, 0},
    fault_handler, fault_handler, 0, fault_handler, fault_handler,
    {0},
};

__attribute__((naked)) void reset_handler(void)
{
#ifdef __ARM_FP
    /* CPACR (0xE000ED88) bits 20-23: CP10 and CP11 full access. The barriers
       make the new setting visible before any FPU instruction. */
    __asm volatile("movw r0, #0xED88\n\t"
                   "movt r0, #0xE000\n\t"
                   "ldr r1, [r0]\n\t"
                   "orr r1, r1, #(0xF << 20)\n\t"
                   "str r1, [r0]\n\t"
                   "dsb\n\t"
                   "isb\n\t"
                   "b start");
#else
    __asm volatile("b start");
#endif
}

void start(void)
{
    uint32_t *src = __data_load, *dst = __data_start;

    while (dst < __data_end)
        *dst++ = *src++;
    for (dst = __bss_start__; dst < __bss_end__; dst++)
        *dst = 0;
    initialise_monitor_handles();
    exit(main());
}

/* newlib's __libc_init_array and __libc_fini_array call these; the
   crti.o/crtn.o that would define them are left out by -nostartfiles, and
   this program has no constructors or destructors. */
void _init(void);
void _fini(void);
void _init(void) {}
void _fini(void) {}

/* Semihosting SYS_EXIT (0x18) with ADP_Stopped_RunTimeErrorUnknown: QEMU
   exits with status 1. BKPT 0xAB is the Armv7-M semihosting trap. */
static void fault_handler(void)
{
    __asm volatile("mov r0, #0x18\n\t"
                   "movw r1, #0x0023\n\t"
                   "movt r1, #0x0002\n\t"
                   "bkpt #0xAB" ::: "r0", "r1", "memory");
    for (;;)
        ;
}
