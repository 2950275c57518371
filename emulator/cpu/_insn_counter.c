/*
 * Native instruction counter for the board model's harts.
 *
 * Unicorn does not count guest instructions, and a Python hook on every
 * instruction runs at a few MIPS. This code hook runs in native code on
 * every instruction: it counts it, and stops the engine before the first
 * instruction past the quantum's budget. The board reads the count through
 * ctypes, so minstret/mcycle and per-frame counts are exact. It also notices
 * a hart coming round a poll loop (below), counts the cycles the K210's
 * Rocket core would take (below: timing.py computes the table it reads), and
 * stops before the CSR instructions the board answers itself (hart.py).
 *
 * It is built as a Python extension so that pip builds it with the package;
 * ctypes hands the address of count_instruction to uc_hook_add. Its one
 * Python function, fast_step, runs the fast engine (below).
 */
#include <Python.h>
#include <stdint.h>

#include "_counter.h"
#include "_fast_engine.h"
#include "_rocket_timing.h"

PyMODINIT_FUNC PyInit__insn_counter(void);

static uint64_t reg(insn_counter_t *c, void *uc, uint32_t r)
{
    uint64_t value = 0;
    if (r != 0)
        c->reg_read(uc, c->reg_x0 + (int)r, &value);
    return value;
}

/*
 * Rocket traps on a misaligned load, store, LR/SC or AMO, whatever the address (rocket-chip
 * DCache.scala: xcpt.ma.ld / xcpt.ma.st from the store generator's misaligned check); Unicorn
 * carries them out. Before each instruction in SRAM its access's address is computed from the
 * base register; a misaligned one is reported and the run stops before it (hart.py raises the
 * exception: mcause 4 or 6, mtval the address).
 */
#define FENCE_I_MASK 0x707Fu    /* opcode MISC-MEM, funct3 1 */
#define LR_MASK 0xF800707Fu     /* opcode AMO, funct5 00010 (LR.W, LR.D) */
#define LR_MATCH 0x1000202Fu

static inline int is_load_reserved(uint32_t word, uint32_t size)
{
    return size == 4 && ((word & LR_MASK) == LR_MATCH || (word & LR_MASK) == (LR_MATCH | 0x1000u));
}

#define FENCE_I_MATCH 0x100Fu

/* Also charges the caches: a load's or store's data-cache access, FENCE.I's flush (the fast engine
 * hands FENCE.I over, so this hook sees every one). */
static int misaligned(insn_counter_t *c, void *uc, uint64_t address, uint32_t size, uint64_t *cache_cost)
{
    uint64_t offset_in_sram;
    if (address - c->sram_base < c->sram_size)
        offset_in_sram = address - c->sram_base;
    else if (address - c->sram_alias < c->sram_size)
        offset_in_sram = address - c->sram_alias;
    else
        return 0;
    if (offset_in_sram + size > c->sram_size)
        return 0;
    const uint8_t *code = c->sram + offset_in_sram;
    uint32_t word = (uint32_t)code[0] | (uint32_t)code[1] << 8;
    if (size == 4)
        word |= (uint32_t)code[2] << 16 | (uint32_t)code[3] << 24;
    uint32_t rs1;
    int64_t offset;
    int is_store;
    uint32_t width = (uint32_t)memory_access_of(word, size, &rs1, &offset, &is_store);
    if (width == 0) {
        if (c->caches != NULL && size == 4 && (word & FENCE_I_MASK) == FENCE_I_MATCH)
            *cache_cost = l1_fence_i(c->caches);
        return 0;
    }
    if (width == 1 && c->caches == NULL)
        return 0;
    uint64_t target = reg(c, uc, rs1) + (uint64_t)offset;
    if ((target & (width - 1)) == 0) {
        /* the data cache is charged where the access is carried out: a misaligned one traps first. LR
         * acquires its line with write permission, as a store does (rocket-chip's isWriteIntent
         * includes M_XLR), so that its SC hits. */
        if (c->caches != NULL)
            *cache_cost = l1_data(c->caches, target, is_store || is_load_reserved(word, size));
        return 0;
    }
    c->misaligned_pc = address;
    c->misaligned_address = target;
    c->misaligned_store = (uint64_t)is_store;
    return 1;
}

/* memory_access_of for the tests (tests/unit/cpu/test_hart.py checks it against cpu/decode.py): out[0] the
 * width (0: no access), out[1] the base register, out[2] the offset, out[3] whether it writes. */
__attribute__((visibility("default")))
void decode_access_for_tests(uint32_t word, uint32_t size, int64_t out[4])
{
    uint32_t rs1 = 0;
    int64_t offset = 0;
    int is_store = 0;
    out[0] = memory_access_of(word, size, &rs1, &offset, &is_store);
    out[1] = rs1;
    out[2] = offset;
    out[3] = is_store;
}

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
    if (counter->executed >= counter->limit || counter->cycles >= counter->cycle_limit) {
        counter->stop(uc);
        return;
    }
    counter->executed++;
    counter->last_pc = address;
    if (counter->table == NULL) {
        counter->cycles++;
    } else {
        uint64_t cost = 1;
        if (counter->caches != NULL) {
            uint64_t fetch = l1_fetch_insn(counter->caches, table_key(address), size);
            counter->stall_cycles += fetch;
            cost += fetch;
        }
        cost += counter->pending_penalty;   /* the fast engine resolved a transfer before handing over */
        counter->pending_penalty = 0;
        if (counter->pending_kind) {
            uint64_t penalty = resolve_transfer(counter, counter->pending_pc, counter->pending_entry,
                                                counter->pending_kind, address);
            uint64_t bubble = redirect_bubble(counter, counter->pending_pc, counter->pending_entry,
                                              counter->pending_kind, address, size, penalty);
            counter->stall_cycles += bubble;
            cost += penalty + bubble;
            counter->pending_kind = 0;
        }
        uint32_t e = table_entry(counter, address);
        if (e != 0) {
            int kind = (int)E_KIND(e);
            uint64_t extra = E_EXTRA(e);
            if (kind == KIND_MUL || kind == KIND_DIV) {
                uint64_t latency = muldiv_latency(e, reg(counter, uc, E_RS1(e)), reg(counter, uc, E_RS2(e)),
                                                  kind == KIND_DIV);
                uint64_t distance = E_DIST(e);
                extra += latency > distance ? latency - distance : 0;
            } else if (kind != KIND_PLAIN) {
                counter->pending_kind = kind;
                counter->pending_pc = address;
                counter->pending_entry = e;
            }
            counter->stall_cycles += extra;
            cost += extra;
        }
        counter->cycles += cost;
    }
    poll_loop_t *loop = loop_at(counter, address);
    if (loop != NULL) {
        if (!loop->ignore && counter->executed - loop->last == loop->body && counter->poll_report == 0) {
            counter->poll_report = address;
            counter->limit = counter->executed;
        }
        loop->last = counter->executed;
    }
    /* A CSR the board answers (mhartid, mcycle, ...): the instruction is counted and timed like
     * any other, then the engine stops before executing it, and Python carries it out. One look-up
     * here, where a code hook per site would make Unicorn walk every hook on every instruction. */
    if (is_csr_site(counter, address)) {
        counter->csr_report = address;
        counter->stop(uc);
        return;
    }
    uint64_t cache_cost = 0;
    if (counter->sram != NULL && misaligned(counter, uc, address, size, &cache_cost))
        counter->stop(uc);
    counter->cycles += cache_cost;
    counter->stall_cycles += cache_cost;
}

/*
 * fast_step(state, counter, uc, arg, resume) for hart.py: the fast engine's run (resume false, arg
 * the pc) or its resumption after a device access (resume true, arg the loaded value), called the
 * way CPython calls its own functions. A ctypes call and the six reads of the access's fields cost
 * about a microsecond and a half, as much as the rest of a device access the firmware polls.
 * Returns the stop (an int), or at a device access (window, address, width, is_store, value, pc)
 * with the stop first. The GIL is released meanwhile, as ctypes releases it.
 */
static PyObject *py_fast_step(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 5) {
        PyErr_SetString(PyExc_TypeError, "fast_step(state, counter, uc, arg, resume) takes 5 arguments");
        return NULL;
    }
    void *f = PyLong_AsVoidPtr(args[0]);
    void *c = PyLong_AsVoidPtr(args[1]);
    void *uc = PyLong_AsVoidPtr(args[2]);
    uint64_t arg = PyLong_AsUnsignedLongLongMask(args[3]);   /* modulo 2^64, as ctypes' c_uint64 takes it */
    int resume = PyObject_IsTrue(args[4]);
    if (PyErr_Occurred())
        return NULL;
    if (f == NULL || c == NULL || uc == NULL) {
        PyErr_SetString(PyExc_ValueError, "fast_step: a null state, counter or engine");
        return NULL;
    }
    uint64_t out[6];
    int why;
    Py_BEGIN_ALLOW_THREADS
    why = fast_step((struct fast_state *)f, (insn_counter_t *)c, uc, arg, resume, out);
    Py_END_ALLOW_THREADS
    if (why != STOP_DEVICE)
        return PyLong_FromLong(why);
    PyObject *result = PyTuple_New(7);
    if (result == NULL)
        return NULL;
    PyTuple_SET_ITEM(result, 0, PyLong_FromLong(why));
    for (int i = 0; i < 6; i++) {
        PyObject *item = PyLong_FromUnsignedLongLong(out[i]);
        if (item == NULL) {
            Py_DECREF(result);
            return NULL;
        }
        PyTuple_SET_ITEM(result, i + 1, item);
    }
    return result;
}

static PyMethodDef methods[] = {
    {"fast_step", (PyCFunction)(void (*)(void))py_fast_step, METH_FASTCALL,
     "fast_step(state, counter, uc, arg, resume): a stretch of the fast engine (see _insn_counter.c)"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_insn_counter",
    "Native per-instruction counting hook (used through ctypes) and the fast engine's step.", -1, methods,
};

PyMODINIT_FUNC PyInit__insn_counter(void)
{
    return PyModule_Create(&module);
}
