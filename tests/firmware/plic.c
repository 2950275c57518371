/* plic.c: external interrupts to hart 0's M-mode context (context 0 on the K210; hart h's is 2 h). */
#include "drivers.h"
#include "k210.h"

/* A source's priority, its enable bit in context 0, threshold 0. */
void plic_enable(int source, uint32_t priority)
{
    mmio_write32(PLIC_BASE + PLIC_PRIORITY + 4u * (uint32_t)source, priority);
    uintptr_t enable = PLIC_BASE + PLIC_ENABLE0 + 4u * ((uint32_t)source / 32);
    mmio_write32(enable, mmio_read32(enable) | 1u << (source % 32));
    mmio_write32(PLIC_BASE + PLIC_THRESHOLD0, 0);
}

int plic_claim(void) { return (int)mmio_read32(PLIC_BASE + PLIC_CLAIM0); }

void plic_complete(int source) { mmio_write32(PLIC_BASE + PLIC_CLAIM0, (uint32_t)source); }
