/*
 * Native instruction counter for the board model's harts.
 *
 * Unicorn does not count guest instructions, and a Python hook on every
 * instruction runs at a few MIPS. This code hook runs in native code on
 * every instruction: it counts it, and stops the engine before the first
 * instruction past the quantum's budget. The board reads the count through
 * ctypes, so minstret/mcycle and per-frame counts are exact. It also notices
 * a hart coming round a poll loop (below).
 *
 * It is built as a (method-less) Python extension only so that pip builds
 * it with the package; Python never calls into it, ctypes hands the address
 * of count_instruction to uc_hook_add.
 */
#include <Python.h>
#include <stdint.h>

typedef int (*uc_stop_fn)(void *uc);

/* A loop that can only be polling memory (shared_memory.py finds them in the firmware). */
typedef struct {
    uint64_t head;       /* address of its first instruction; 0: an empty slot of the table */
    uint64_t body;       /* instructions in one iteration, the backward branch included */
    uint64_t last;       /* `executed` at the head's previous execution */
    uint64_t ignore;     /* set by Python: the loop polls a device, not SRAM */
} poll_loop_t;

typedef struct {
    uint64_t executed;   /* instructions started since the hart's reset */
    uint64_t limit;      /* stop before executing instruction number limit+1 */
    uc_stop_fn stop;     /* uc_emu_stop from the loaded libunicorn */
    poll_loop_t *loops;  /* the poll loops, a table indexed by (address >> 1) & loop_mask; or NULL */
    uint64_t loop_mask;
    uint64_t poll_report; /* head of the loop the hart came round again (0: none since Python looked) */
} insn_counter_t;

PyMODINIT_FUNC PyInit__insn_counter(void);

/*
 * Poll loops are noticed here rather than by a hook of their own on each loop head: Unicorn
 * walks its whole list of code hooks on every instruction, so each extra hook costs every
 * instruction, where this costs a table look-up. When a loop head comes round again exactly
 * `body` instructions after its previous execution, the hart has run one whole iteration and is
 * about to run another: it is polling. The loop is reported and the run ends after the head.
 */
__attribute__((visibility("default")))
void count_instruction(void *uc, uint64_t address, uint32_t size, insn_counter_t *counter)
{
    (void)size;
    if (counter->executed >= counter->limit) {
        counter->stop(uc);
        return;
    }
    counter->executed++;
    if (counter->loops != NULL) {
        poll_loop_t *loop = &counter->loops[(address >> 1) & counter->loop_mask];
        if (loop->head == address) {
            if (!loop->ignore && counter->executed - loop->last == loop->body && counter->poll_report == 0) {
                counter->poll_report = address;
                counter->limit = counter->executed;
            }
            loop->last = counter->executed;
        }
    }
}

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_insn_counter",
    "Native per-instruction counting hook (used through ctypes).", -1, NULL,
};

PyMODINIT_FUNC PyInit__insn_counter(void)
{
    return PyModule_Create(&module);
}
