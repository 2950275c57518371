/* trap.c: what a trap nobody expects does: report it on the console and stop. A program
 * that takes interrupts defines its own trap_handler. */
#include <stdio.h>

#include "k210.h"

uintptr_t __attribute__((weak)) trap_handler(uintptr_t mcause, uintptr_t mepc, uintptr_t mtval)
{
    printf("trap: mcause 0x%lx mepc 0x%lx mtval 0x%lx\n", (unsigned long)mcause, (unsigned long)mepc,
           (unsigned long)mtval);
    clear_csr(mstatus, MSTATUS_MIE);
    for (;;)
        __asm__ volatile("wfi");
    return mepc;
}
