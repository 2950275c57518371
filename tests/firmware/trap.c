/* trap.c: what a trap nobody expects does: report it on the console and stop. A program
 * that takes interrupts defines its own trap_handler. */
#include <stdio.h>

#include "drivers.h"
#include "k210.h"

/* The saved register x`number` in the frame, or NULL for one trap_entry does not save. */
uint64_t *trap_frame_register(struct trap_frame *frame, int number)
{
    if (number == 1)
        return &frame->ra;
    if (number >= 5 && number <= 7)
        return &frame->t0 + (number - 5);
    if (number >= 28 && number <= 31)
        return &frame->t3 + (number - 28);
    if (number >= 10 && number <= 17)
        return &frame->a[number - 10];
    return NULL;
}

uintptr_t __attribute__((weak)) trap_handler(uintptr_t mcause, uintptr_t mepc, uintptr_t mtval,
                                             struct trap_frame *frame)
{
    (void)frame;
    printf("trap: mcause 0x%lx mepc 0x%lx mtval 0x%lx\n", (unsigned long)mcause, (unsigned long)mepc,
           (unsigned long)mtval);
    clear_csr(mstatus, MSTATUS_MIE);
    for (;;)
        __asm__ volatile("wfi");
    return mepc;
}
