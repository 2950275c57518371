/*
 * Native instruction counter for the board model's harts.
 *
 * Unicorn does not count guest instructions, and a Python hook on every
 * instruction runs at a few MIPS. This code hook runs in native code on
 * every instruction: it counts it, and stops the engine before the first
 * instruction past the quantum's budget. The board reads the count through
 * ctypes, so minstret/mcycle and per-frame counts are exact.
 *
 * It is built as a (method-less) Python extension only so that pip builds
 * it with the package; Python never calls into it, ctypes hands the address
 * of count_instruction to uc_hook_add.
 */
#include <Python.h>
#include <stdint.h>

typedef int (*uc_stop_fn)(void *uc);

typedef struct {
    uint64_t executed;   /* instructions started since the hart's reset */
    uint64_t limit;      /* stop before executing instruction number limit+1 */
    uc_stop_fn stop;     /* uc_emu_stop from the loaded libunicorn */
} insn_counter_t;

PyMODINIT_FUNC PyInit__insn_counter(void);

__attribute__((visibility("default")))
void count_instruction(void *uc, uint64_t address, uint32_t size, insn_counter_t *counter)
{
    (void)address;
    (void)size;
    if (counter->executed >= counter->limit) {
        counter->stop(uc);
        return;
    }
    counter->executed++;
}

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_insn_counter",
    "Native per-instruction counting hook (used through ctypes).", -1, NULL,
};

PyMODINIT_FUNC PyInit__insn_counter(void)
{
    return PyModule_Create(&module);
}
