/* core_portme.c: CoreMark's port to QEMU's -M virt machine, the same program as the K210 port
 * (../core_portme.c, whose header this one shares: the same seeds, data block and types), so that
 * QEMU's time for it can be set beside the board model's (tools/coremark.py). Output on virt's
 * ns16550 UART through picolibc's printf; CoreMark's seconds from the CLINT's mtime, which QEMU
 * runs at 10 MHz of its virtual clock (the host's clock, without -icount). At the end the port
 * prints minstret, which is the count of instructions retired only under -icount (QEMU otherwise
 * returns the host's time-stamp counter there): tools/coremark.py counts the program that way. */
#include <stdio.h>

#include "coremark.h"

#define UART0_BASE 0x10000000UL        /* virt's ns16550a, byte registers (reg-shift 0) */
#define UART_THR 0                     /* transmit holding register */
#define UART_LSR 5                     /* line status register */
#define UART_LSR_THRE (1u << 5)        /* the transmit holding register is empty */
#define CLINT_MTIME 0x0200BFF8UL
#define MTIME_HZ 10000000u             /* virt's CLINT timebase (its device tree's timebase-frequency) */

#include "core_seeds.h"   /* the run types' seeds, shared by both ports */

static CORE_TICKS started, stopped;

/* uart_putc: writes byte c to the UART once its transmit holding register is empty (QEMU's always
 * is; a real 16550 need not be). */
static void uart_putc(char c)
{
    volatile uint8_t *uart = (volatile uint8_t *)UART0_BASE;
    while (!(uart[UART_LSR] & UART_LSR_THRE))
        ;
    uart[UART_THR] = (uint8_t)c;
}

/* console_put: picolibc's output hook for stdout (file unused); returns the byte written. No '\r'
 * before '\n': the tool reads QEMU's standard output, not a terminal. */
static int console_put(char c, FILE *file)
{
    (void)file;
    uart_putc(c);
    return (unsigned char)c;
}

static FILE console = FDEV_SETUP_STREAM(console_put, NULL, NULL, _FDEV_SETUP_WRITE);
FILE *const stdout = &console;
FILE *const stderr = &console;

/* mtime_now: the CLINT's mtime, in ticks of MTIME_HZ. */
static CORE_TICKS mtime_now(void)
{
    return *(volatile uint64_t *)CLINT_MTIME;
}

/* instret_now: minstret (instructions retired under -icount; see the comment at the top). */
static uint64_t instret_now(void)
{
    uint64_t value;
    __asm__ volatile("csrr %0, minstret" : "=r"(value));
    return value;
}

void start_time(void) { started = mtime_now(); }
void stop_time(void) { stopped = mtime_now(); }
CORE_TICKS get_time(void) { return stopped - started; }
secs_ret time_in_secs(CORE_TICKS ticks) { return (secs_ret)ticks / (secs_ret)MTIME_HZ; }

void portable_init(core_portable *p, int *argc, char *argv[])
{
    (void)argc;
    (void)argv;
    printf("CoreMark on QEMU virt, hart 0: mtime at %u Hz\n", MTIME_HZ);
    p->portable_id = 1;
}

void portable_fini(core_portable *p)
{
    printf("minstret at the end: %llu\n", (unsigned long long)instret_now());
    p->portable_id = 0;
}
