/* clint.c: mtime, hart 0's mtimecmp, and delays that sleep on the timer. */
#include "drivers.h"
#include "k210.h"

uint64_t mtime_now(void) { return mmio_read64(CLINT_BASE + CLINT_MTIME); }

uint64_t mtime_per_second(void) { return cpu_hz() / CLINT_MTIME_DIVIDER; }

void mtimecmp_set(uint64_t when) { mmio_write64(CLINT_BASE + CLINT_MTIMECMP0, when); }

/* Waits `us` microseconds asleep: mtimecmp at the end, the timer interrupt enabled in mie
 * but not globally (mstatus.MIE stays clear: no trap), and wfi, which wakes once the timer
 * interrupt is pending. Only for code that runs with mstatus.MIE clear. */
void delay_us(uint32_t us)
{
    uint64_t end = mtime_now() + (mtime_per_second() * us + 999999) / 1000000;
    unsigned long enabled = read_csr(mie);
    mtimecmp_set(end);
    set_csr(mie, MIE_MTIE);
    while (mtime_now() < end)
        __asm__ volatile("wfi");
    mtimecmp_set(UINT64_MAX);
    clear_csr(mie, MIE_MTIE & ~enabled);
}
