/*
 * Native store checker for the board model's --check-writes (see write_watch.py).
 *
 * A Python UC_HOOK_MEM_WRITE callback on every store would cost more than
 * the firmware's whole frame, so the check runs here, as a native
 * UC_HOOK_MEM_WRITE callback bounded to one SRAM view (the board installs one
 * per view and per hart). Python fills the table of regions; this code only
 * finds the region each stored byte falls in and, on the first store outside
 * what the hart may write, records it and ends the run before the next
 * instruction, the way Hart.request_stop does: through the hart's native
 * instruction counter (its limit drops to its count). uc_emu_stop is not used:
 * from a memory callback it would stop the engine with the pc still on the
 * store, and the instruction counts would no longer be exact. The store itself
 * lands: this is a watchpoint, not memory protection (the K210 has none here).
 *
 * It is built as a (method-less) Python extension only so that pip builds it
 * with the package; Python never calls into it, ctypes hands the address of
 * check_write to uc_hook_add.
 */
#include <Python.h>
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

/* The first two fields of _insn_counter.c's insn_counter_t. */
typedef struct {
    uint64_t executed;
    uint64_t limit;
} counter_head_t;

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
    /* the first stray store, filled here */
    uint64_t stray;                 /* 0 until a store went astray */
    uint64_t address, size, pc, region, heap_next;
} write_watch_t;

PyMODINIT_FUNC PyInit__write_watch(void);

static uint64_t live_heap_next(const write_watch_t *watch)
{
    uint64_t value;
    memcpy(&value, watch->sram + watch->heap_next_offset, sizeof value);
    return value;
}

/* End of the allocated part of a heap region: heap_next, as an SRAM offset, clamped to
 * the region (a heap_next that points at neither view, e.g. before heap_init, has handed
 * out nothing). */
static uint64_t heap_allocated_end(const watch_region_t *region, uint64_t next, const write_watch_t *watch)
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

static void record(write_watch_t *watch, void *uc, uint64_t address, int size, uint64_t region, uint64_t next)
{
    uint64_t pc = 0;
    watch->reg_read(uc, (int)watch->pc_register, &pc);
    watch->address = address;
    watch->size = (uint64_t)size;
    watch->pc = pc;
    watch->region = region;
    watch->heap_next = next;
    watch->stray = 1;
    /* the counter's next call (the next instruction) stops the engine without counting it */
    watch->counter->limit = watch->counter->executed;
}

__attribute__((visibility("default")))
int check_write(void *uc, int type, uint64_t address, int size, int64_t value, write_watch_t *watch)
{
    (void)type;
    (void)value;
    if (watch->stray)
        return 0;
    /* the hook is bounded to one view: the lower base is the uncached one */
    uint64_t offset = address - (address >= watch->cached_base ? watch->cached_base : watch->uncached_base);
    uint64_t end = offset + (uint64_t)size;
    uint64_t next = 0;
    for (uint64_t i = 0; i < watch->region_count; i++) {
        const watch_region_t *region = &watch->regions[i];
        if (offset >= region->hi)
            continue;
        uint64_t allowed_end = region->lo;
        if (region->rule == RULE_ALLOW) {
            allowed_end = region->hi;
        } else if (region->rule == RULE_HEAP) {
            next = live_heap_next(watch);
            allowed_end = heap_allocated_end(region, next, watch);
        }
        if (offset < allowed_end)
            offset = allowed_end;
        if (offset >= end)
            return 0;
        if (offset < region->hi) {
            record(watch, uc, address, size, i, next);
            return 0;
        }
    }
    return 0;
}

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_write_watch",
    "Native store checker for --check-writes (used through ctypes).", -1, NULL,
};

PyMODINIT_FUNC PyInit__write_watch(void)
{
    return PyModule_Create(&module);
}
