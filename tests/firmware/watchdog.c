/* watchdog.c: WDT0 in interrupt-first mode left unfed: its interrupt, then the chip reset, after
 * which the program starts again and finds the watchdog in SYSCTL's reset_status. */
#include <stdio.h>

#include "drivers.h"
#include "k210.h"

#define CONSOLE_BAUD 115200u

uintptr_t trap_handler(uintptr_t mcause, uintptr_t mepc, uintptr_t mtval, struct trap_frame *frame)
{
    (void)frame;
    (void)mtval;
    if (mcause == (MCAUSE_INTERRUPT | IRQ_M_EXTERNAL) && plic_claim() == IRQ_WDT0) {
        printf("watchdog interrupt: not fed, not cleared\n");
        clear_csr(mie, MIE_MEIE);            /* the interrupt stays set: the next timeout resets */
        return mepc;
    }
    printf("trap: mcause 0x%lx\n", (unsigned long)mcause);
    for (;;)
        __asm__ volatile("wfi");
}

int main(void)
{
    clock_enable(CLOCK_FPIOA);
    fpioa_set_function(PAD_UARTHS_RX, FUNC_UARTHS_RX);
    fpioa_set_function(PAD_UARTHS_TX, FUNC_UARTHS_TX);
    uarths_init(CONSOLE_BAUD);
    uint32_t cause = reset_status();
    if (cause & SYSCTL_RESET_STS_WDT0) {
        printf("restarted by the watchdog\n");     /* (reading it cleared the cause) */
        return 0;
    }
    /* wdt_init's way, TOP 0: 2^16 clocks a timeout */
    clock_enable(CLOCK_WDT0);
    plic_enable(IRQ_WDT0, 1);
    mmio_write32(WDT0_BASE + WDT_TORR, 0);
    mmio_write32(WDT0_BASE + WDT_CRR, WDT_RESTART);
    mmio_write32(WDT0_BASE + WDT_CR, WDT_CR_INTERRUPT_FIRST | WDT_CR_ENABLE);
    printf("watchdog started: %lu ms a timeout\n", (unsigned long)((1u << 16) * 1000ull / wdt_hz()));
    set_csr(mie, MIE_MEIE);
    set_csr(mstatus, MSTATUS_MIE);
    for (;;)
        __asm__ volatile("wfi");
}
