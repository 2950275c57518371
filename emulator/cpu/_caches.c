/*
 * The DMA and the harts' data caches (_caches.h's l1_memory_t). The K210's DMAC reaches SRAM through
 * the cores' coherence hub, which probes the caches for it as for a hart's acquire (rocket-chip 2017's
 * TLBroadcast: a Get probes every cache to Branch, a Put to Nothing): what a DMA reads is what the
 * harts last stored, even in a dirty line, and a DMA's write drops every cached copy of the line, so
 * the harts read the DMA's bytes. docs/design/timing.md ("DMA and the caches") gives the programs that
 * ran on Docks which show it. Only the caches' state changes here (SRAM is one copy in the model):
 * the hart's next access to such a line misses, or a store to it asks for write permission again.
 */
#include <stdint.h>
#include <string.h>

#include "_caches.h"

#define LINE (1u << L1_LINE_SHIFT)

/* Each line of [offset, offset + length) of SRAM, probed in every hart's data cache. */
static void l1_dma_probe(l1_memory_t *m, uint64_t offset, uint64_t length, int write)
{
    if (length == 0)
        return;
    uint64_t first = (m->cached_base + offset) >> L1_LINE_SHIFT;
    uint64_t last = (m->cached_base + offset + length - 1) >> L1_LINE_SHIFT;
    for (uint64_t number = first; number <= last; number++) {
        uint64_t line = number + 1;
        uint32_t set = (uint32_t)number & (L1_SETS - 1);
        for (int h = 0; h < 2; h++) {
            l1_caches_t *c = m->harts[h];
            if (c == NULL)
                continue;
            l1_cache_t *d = &c->dcache;
            int way = l1_find(d, set, line);
            if (way < 0)
                continue;
            uint32_t slot = set * L1_WAYS + (uint32_t)way;
            if (d->writable[slot]) {
                d->writable[slot] = 0;      /* written back: the DMA reads, or overwrites, SRAM's bytes */
                d->write_backs++;
                m->write_backs++;
                if (d->hot_writable[L1_HOT_SLOT(line)] == line)
                    d->hot_writable[L1_HOT_SLOT(line)] = 0;
            }
            if (write) {
                d->line[slot] = 0;
                l1_forget(d, line);
                m->invalidations++;
            }
        }
    }
}

/* A DMA read of `length` bytes at SRAM offset `offset`: dirty copies are written back first. */
__attribute__((visibility("default")))
void l1_dma_read(l1_memory_t *m, uint64_t offset, uint64_t length)
{
    l1_dma_probe(m, offset, length, 0);
}

/* A DMA write of `length` bytes at SRAM offset `offset`: every cached copy of its lines goes. */
__attribute__((visibility("default")))
void l1_dma_write(l1_memory_t *m, uint64_t offset, uint64_t length)
{
    l1_dma_probe(m, offset, length, 1);
}
