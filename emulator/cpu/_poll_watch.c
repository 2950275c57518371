/*
 * Native store watch for a hart polling SRAM (see shared_memory.py).
 *
 * A memory-write hook bounded to the bytes a waiting hart polls, installed on the other hart
 * while it waits. A store there ends the storing hart's run right after the store, through the
 * hart's native instruction counter as Hart.request_stop does (uc_emu_stop from a memory
 * callback would leave the pc on the store and the instruction counts inexact), so that the
 * poller sees the value before the storer's next instruction could overwrite it.
 *
 * It is built as a (method-less) Python extension only so that pip builds it with the package;
 * Python never calls into it, ctypes hands the function's address to uc_hook_add.
 */
#include <Python.h>
#include <stdint.h>

/* The first two fields of _insn_counter.c's insn_counter_t. */
typedef struct {
    uint64_t executed;
    uint64_t limit;
} counter_head_t;

typedef struct {
    counter_head_t *counter;   /* the storing hart's instruction counter */
    uint64_t hits;             /* stores seen since Python last cleared it */
    uint64_t address;          /* the last one's address */
} store_watch_t;

PyMODINIT_FUNC PyInit__poll_watch(void);

__attribute__((visibility("default")))
void store_watch(void *uc, int type, uint64_t address, int size, int64_t value, store_watch_t *watch)
{
    (void)uc;
    (void)type;
    (void)size;
    (void)value;
    watch->hits++;
    watch->address = address;
    if (watch->counter->limit > watch->counter->executed)
        watch->counter->limit = watch->counter->executed;
}

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_poll_watch",
    "Native store watch for harts polling SRAM (used through ctypes).", -1, NULL,
};

PyMODINIT_FUNC PyInit__poll_watch(void)
{
    return PyModule_Create(&module);
}
