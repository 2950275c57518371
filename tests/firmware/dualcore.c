/* dualcore.c: both harts, as FreeRTOS's two-core port (MicroPython's) runs them: hart 1 started
 * by hart 0's software interrupt, each hart yielding through an ecall its own trap handler
 * serves, and a spinlock (amoswap, then a spin on the lock word) the two take turns at around a
 * shared counter, each read-modify-write inside it slowed by a few instructions. */
#include <stdio.h>

#include "drivers.h"
#include "k210.h"

#define CONSOLE_BAUD  115200u
#define ROUNDS        200
#define SYSCALL_YIELD 1000u                 /* a7 of the yield ecall */
#define MCAUSE_ECALL_M 11u

static volatile int lock;
static volatile unsigned shared, hart1_done;
static volatile unsigned rounds[2], yields[2];

static void take(void)
{
    while (__atomic_exchange_n(&lock, 1, __ATOMIC_ACQUIRE))
        while (lock)
            ;
}

static void give(void) { __atomic_store_n(&lock, 0, __ATOMIC_RELEASE); }

static void yield(void)
{
    register uintptr_t a7 __asm__("a7") = SYSCALL_YIELD;
    __asm__ volatile("ecall" : "+r"(a7) : : "memory");
}

uintptr_t trap_handler(uintptr_t mcause, uintptr_t mepc, uintptr_t mtval, struct trap_frame *frame)
{
    if (mcause == MCAUSE_ECALL_M && frame->a[7] == SYSCALL_YIELD) {
        yields[read_csr(mhartid)]++;
        return mepc + 4;
    }
    printf("trap on hart %lu: mcause 0x%lx mepc 0x%lx mtval 0x%lx\n", read_csr(mhartid), (unsigned long)mcause,
           (unsigned long)mepc, (unsigned long)mtval);
    for (;;)
        __asm__ volatile("wfi");
}

/* ROUNDS times: the counter incremented inside the lock (read, a few instructions, write), then
 * a yield. */
static void work(unsigned hart)
{
    for (int i = 0; i < ROUNDS; i++) {
        take();
        unsigned value = shared;
        for (volatile unsigned delay = 0; delay < 2 + 3 * hart; delay++)
            ;
        shared = value + 1;
        rounds[hart]++;
        give();
        yield();
    }
}

void hart1_main(void)
{
    work(1);
    hart1_done = 1;
}

int main(void)
{
    clock_enable(CLOCK_FPIOA);
    fpioa_set_function(PAD_UARTHS_RX, FUNC_UARTHS_RX);
    fpioa_set_function(PAD_UARTHS_TX, FUNC_UARTHS_TX);
    uarths_init(CONSOLE_BAUD);
    printf("hart 0 starts hart 1\n");
    mmio_write32(CLINT_BASE + CLINT_MSIP1_OFFSET, 1);
    work(0);
    while (!hart1_done)
        ;
    printf("shared %u (hart 0 %u, hart 1 %u), yields %u and %u\n", shared, rounds[0], rounds[1], yields[0], yields[1]);
    return 0;
}
