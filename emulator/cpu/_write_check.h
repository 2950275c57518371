/*
 * The store check of --check-writes (write_watch.py), shared by the precise engine's native
 * UC_HOOK_MEM_WRITE callback (_write_watch.c) and the fast engine's stores (_fast_engine.c), so
 * that a store goes astray by the same rule whichever engine runs it.
 */
#ifndef WRITE_CHECK_H
#define WRITE_CHECK_H

#include <stdint.h>
#include <string.h>

#define WATCH_MAX_REGIONS 24

/* What a region allows; the same numbers as write_watch.py's Rule. */
enum { RULE_ALLOW = 0, RULE_FORBID = 1, RULE_HEAP = 2 };

typedef int (*uc_reg_read_fn)(void *uc, int regid, void *value);

typedef struct {
    uint64_t lo, hi;    /* SRAM offsets, [lo, hi); the regions tile the whole SRAM in order */
    uint64_t rule;      /* RULE_HEAP: allowed below the live heap_next, forbidden from there */
} watch_region_t;

/* The first two fields of _counter.h's insn_counter_t. */
typedef struct {
    uint64_t executed;
    uint64_t limit;
} counter_head_t;

/* write_watch.py's _Watch, field for field */
typedef struct {
    /* set up by write_watch.py */
    uint64_t cached_base, uncached_base, sram_size;
    const uint8_t *sram;            /* the host buffer behind both views */
    uint64_t heap_next_offset;      /* SRAM offset of the firmware's u64 heap_next */
    counter_head_t *counter;        /* this hart's instruction counter */
    uc_reg_read_fn reg_read;        /* uc_reg_read from the loaded libunicorn */
    int64_t pc_register;            /* UC_RISCV_REG_PC */
    uint64_t region_count;
    watch_region_t regions[WATCH_MAX_REGIONS];
    /* the first stray store, filled by write_check_record */
    uint64_t stray;                 /* 0 until a store went astray */
    uint64_t address, size, pc, region, heap_next;
} write_watch_t;

static inline uint64_t write_check_heap_next(const write_watch_t *watch)
{
    uint64_t value;
    memcpy(&value, watch->sram + watch->heap_next_offset, sizeof value);
    return value;
}

/* End of the allocated part of a heap region: heap_next, as an SRAM offset, clamped to
 * the region (a heap_next that points at neither view, e.g. before heap_init, has handed
 * out nothing). */
static inline uint64_t write_check_allocated_end(const watch_region_t *region, uint64_t next,
                                                 const write_watch_t *watch)
{
    uint64_t offset;
    if (next >= watch->cached_base && next - watch->cached_base <= watch->sram_size)
        offset = next - watch->cached_base;
    else if (next >= watch->uncached_base && next - watch->uncached_base <= watch->sram_size)
        offset = next - watch->uncached_base;
    else
        return region->lo;
    if (offset < region->lo)
        return region->lo;
    return offset < region->hi ? offset : region->hi;
}

/* Whether a store of `size` bytes at SRAM offset `offset` leaves what the hart may write; if so,
 * the region it hits first and heap_next as it was read into *region and *next. */
static inline int write_check_strays(const write_watch_t *watch, uint64_t offset, uint64_t size,
                                     uint64_t *region_hit, uint64_t *next_seen)
{
    uint64_t end = offset + size;
    uint64_t next = 0;
    for (uint64_t i = 0; i < watch->region_count; i++) {
        const watch_region_t *region = &watch->regions[i];
        if (offset >= region->hi)
            continue;
        uint64_t allowed_end = region->lo;
        if (region->rule == RULE_ALLOW) {
            allowed_end = region->hi;
        } else if (region->rule == RULE_HEAP) {
            next = write_check_heap_next(watch);
            allowed_end = write_check_allocated_end(region, next, watch);
        }
        if (offset < allowed_end)
            offset = allowed_end;
        if (offset >= end)
            return 0;
        if (offset < region->hi) {
            *region_hit = i;
            *next_seen = next;
            return 1;
        }
    }
    return 0;
}

/* Records the first stray store (the caller then stops the hart before its next instruction). */
static inline void write_check_record(write_watch_t *watch, uint64_t address, uint64_t size, uint64_t pc,
                                      uint64_t region, uint64_t next)
{
    watch->address = address;
    watch->size = size;
    watch->pc = pc;
    watch->region = region;
    watch->heap_next = next;
    watch->stray = 1;
}

#endif
