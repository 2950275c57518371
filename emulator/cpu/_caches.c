/*
 * The DMA's side of SRAM with the harts' data caches in front of it (_caches.h's l1_memory_t): what a
 * DMA read finds and where a DMA write lands, a line at a time. The DMAC's model calls these through
 * dma_view.py for every transfer it carries out while the caches are modelled.
 */
#include <stdint.h>
#include <string.h>

#include "_caches.h"

#define LINE (1u << L1_LINE_SHIFT)

/* Whether a hart's data cache holds the line at SRAM offset `offset`. */
static int l1_held(const l1_memory_t *m, uint64_t offset)
{
    uint64_t line = ((m->cached_base + offset) >> L1_LINE_SHIFT) + 1;
    uint32_t set = (uint32_t)(line - 1) & (L1_SETS - 1);
    for (int h = 0; h < 2; h++)
        if (m->harts[h] != NULL && l1_find(&m->harts[h]->dcache, set, line) >= 0)
            return 1;
    return 0;
}

/*
 * A DMA read of `length` bytes at SRAM offset `offset` into `out`: SRAM's bytes, which for a line a
 * hart holds written are those from before its stores (the DMA does not see into the caches).
 */
__attribute__((visibility("default")))
void l1_dma_read(l1_memory_t *m, uint64_t offset, uint64_t length, uint8_t *out)
{
    while (length > 0) {
        uint64_t index = offset >> L1_LINE_SHIFT;
        uint64_t n = LINE - (offset & (LINE - 1));
        if (n > length)
            n = length;
        if (m->shadowed[index]) {
            if (memcmp(m->sram + offset, m->view + offset, n) != 0)
                m->stale_reads++;
            memcpy(out, m->sram + offset, n);
        } else {
            memcpy(out, m->view + offset, n);
        }
        out += n;
        offset += n;
        length -= n;
    }
}

/*
 * A DMA write of `length` bytes from `data` at SRAM offset `offset`: to SRAM. Where a hart's data cache
 * holds the line, the hart goes on seeing its copy (until the line leaves the cache and is fetched
 * again), and a dirty copy written back later replaces what the DMA wrote, as on the chip.
 */
__attribute__((visibility("default")))
void l1_dma_write(l1_memory_t *m, uint64_t offset, const uint8_t *data, uint64_t length)
{
    while (length > 0) {
        uint64_t index = offset >> L1_LINE_SHIFT, start = index << L1_LINE_SHIFT;
        uint64_t n = LINE - (offset & (LINE - 1));
        if (n > length)
            n = length;
        if (l1_held(m, offset)) {
            if (!m->shadowed[index]) {
                memcpy(m->sram + start, m->view + start, LINE);
                m->shadowed[index] = 1;
            }
            if (memcmp(m->view + offset, data, n) != 0)
                m->stale_writes++;
            memcpy(m->sram + offset, data, n);
        } else {
            if (m->shadowed[index]) {    /* a line that left the caches since: SRAM's bytes are the view's now */
                memcpy(m->view + start, m->sram + start, LINE);
                m->shadowed[index] = 0;
            }
            memcpy(m->view + offset, data, n);
        }
        data += n;
        offset += n;
        length -= n;
    }
}
