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

#include "_write_check.h"

PyMODINIT_FUNC PyInit__write_watch(void);

__attribute__((visibility("default")))
int check_write(void *uc, int type, uint64_t address, int size, int64_t value, write_watch_t *watch)
{
    (void)type;
    (void)value;
    if (watch->stray)
        return 0;
    /* the hook is bounded to one view: the lower base is the uncached one */
    uint64_t offset = address - (address >= watch->cached_base ? watch->cached_base : watch->uncached_base);
    uint64_t region, next;
    if (write_check_strays(watch, offset, (uint64_t)size, &region, &next)) {
        uint64_t pc = 0;
        watch->reg_read(uc, (int)watch->pc_register, &pc);
        write_check_record(watch, address, (uint64_t)size, pc, region, next);
        /* the counter's next call (the next instruction) stops the engine without counting it */
        watch->counter->limit = watch->counter->executed;
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
