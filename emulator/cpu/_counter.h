/*
 * What the board model's native counting hooks share: the counter each hart hands its hooks
 * (hart.py mirrors it with ctypes: keep the two in step), the cycle table's entry layout
 * (timing.py writes the entries), the state of Rocket's branch predictor (_rocket_timing.h times
 * the transfers and the multiplier).
 * _insn_counter.c counts for the precise engine (Unicorn), _fast_engine.c for the fast one.
 */
#ifndef K210_COUNTER_H
#define K210_COUNTER_H
#include <stdint.h>

#include "_caches.h"

typedef int (*uc_stop_fn)(void *uc);

/* A loop that can only be polling memory (shared_memory.py finds them in the firmware). */
typedef struct {
    uint64_t head;       /* address of its first instruction; 0: an empty slot of the table */
    uint64_t body;       /* instructions in one iteration, the backward branch included */
    uint64_t last;       /* `executed` at the head's previous execution */
    uint64_t ignore;     /* set by Python: the loop polls a device, not SRAM */
} poll_loop_t;

typedef int (*uc_reg_read_fn)(void *uc, int regid, void *value);

/* Rocket's branch predictor (rocket-chip e8c8d2af7, BTB.scala): a fully associative BTB with
 * round-robin replacement, written only when a taken control transfer was mispredicted; a BHT of
 * 2-bit entries indexed by pc ^ global history, consulted and updated only for branches that hit
 * in the BTB; a return-address stack. */
#define BTB_ENTRIES 40
#define BHT_BITS 7
#define BHT_ENTRIES (1 << BHT_BITS)
#define RAS_ENTRIES 2
#define BTB_INDEX_BUCKETS 128   /* a power of two, over 2 x BTB_ENTRIES */

typedef struct {
    uint64_t pc[BTB_ENTRIES];
    uint64_t target[BTB_ENTRIES];
    uint8_t valid[BTB_ENTRIES];
    uint8_t is_jump[BTB_ENTRIES];     /* jal/jalr: predicted taken without the BHT */
    uint8_t is_return[BTB_ENTRIES];   /* target from the RAS */
    uint8_t bht[BHT_ENTRIES];
    uint64_t ras[RAS_ENTRIES];
    uint32_t next_replace;
    uint32_t history;
    uint32_t ras_count;
    uint32_t ras_pos;
    /* Not Rocket's: an index to find a pc among the BTB's entries without comparing all 40
     * (linear probing; each bucket holds an entry's number + 1, 0 when empty). */
    uint8_t index[BTB_INDEX_BUCKETS];
} predictor_t;

typedef struct {
    uint64_t executed;   /* instructions started since the hart's reset */
    uint64_t limit;      /* stop before executing instruction number limit+1 */
    uc_stop_fn stop;     /* uc_emu_stop from the loaded libunicorn */
    poll_loop_t *loops;  /* the poll loops, a table indexed by (table_key(address) >> 1) & loop_mask; or NULL */
    uint64_t loop_mask;
    uint64_t poll_report; /* head of the loop the hart came round again (0: none since Python looked) */
    /* --- cycles (timing.py) --- */
    uint64_t cycles;      /* CPU cycles the started instructions take (= executed without a table) */
    uint64_t cycle_limit; /* stop before an instruction starts once cycles >= cycle_limit */
    const uint32_t *table; /* one entry per 2-byte slot of [table_base, table_end); NULL: one cycle each */
    uint64_t table_base;
    uint64_t table_end;
    uc_reg_read_fn reg_read;
    int32_t reg_x0;       /* Unicorn's register id of x0 (x1.. follow) */
    int32_t pending_kind; /* a control transfer waiting for the next pc to be resolved (0: none) */
    uint64_t pending_pc;
    uint32_t pending_entry;
    uint32_t pending_penalty; /* the fast engine's: a transfer resolved, its cycles due at the next instruction */
    uint64_t mispredicts; /* statistics for the bench and the tests */
    uint64_t stall_cycles;
    predictor_t predictor;
    /* --- CSR instructions the board answers itself (hart.py) --- */
    const uint64_t *csr_sites; /* their table_keys, a table indexed by (key >> 1) & csr_mask; or NULL */
    uint64_t csr_mask;
    uint64_t csr_report;  /* the site the run stopped at, counted but not executed (0: none) */
    uint64_t last_pc;     /* the precise engine's last counted instruction */
    /* --- misaligned loads and stores, which Rocket traps on and Unicorn carries out --- */
    const uint8_t *sram;  /* SRAM's host buffer (where the code is read from); NULL: no check */
    uint64_t sram_base;   /* SRAM's two views and their size */
    uint64_t sram_alias;
    uint64_t sram_size;
    uint64_t misaligned_pc;      /* the access the run stopped before, counted, not executed (0: none) */
    uint64_t misaligned_address;
    uint64_t misaligned_store;   /* 1: a store or AMO (mcause 6), 0: a load or LR (mcause 4) */
    /* --- the L1 caches (_caches.h; NULL: none, as under --timing ipc1 and rocket-nocache) --- */
    l1_caches_t *caches;
} insn_counter_t;

/* A table entry (timing.py writes them; keep the two in step). */
#define E_EXTRA(e)     ((e) & 0xFF)          /* cycles beyond the first, known statically */
#define E_KIND(e)      (((e) >> 8) & 7)
#define E_SIZE4(e)     (((e) >> 11) & 1)
#define E_RS1(e)       (((e) >> 12) & 31)
#define E_RS2(e)       (((e) >> 17) & 31)
#define E_WORD(e)      (((e) >> 22) & 1)     /* mul/div: a *W instruction */
#define E_LHS_SIGNED(e) (((e) >> 23) & 1)
#define E_HI(e)        (((e) >> 24) & 1)     /* mulh*, rem* */
#define E_DIST(e)      (((e) >> 25) & 31)    /* mul/div: instructions to the first that must wait for it */
#define E_RHS_SIGNED(e) (((e) >> 30) & 1)    /* mul/div */
#define E_CALL(e)      (((e) >> 30) & 1)     /* jal/jalr writing a link register */
#define E_RETURN(e)    (((e) >> 31) & 1)     /* jalr through a link register, not writing one */

enum { KIND_PLAIN = 0, KIND_BRANCH = 1, KIND_JAL = 2, KIND_JALR = 3, KIND_MUL = 4, KIND_DIV = 5,
       KIND_FLUSH = 6 /* a CSR write, mret, fence.i: the next instruction is refetched, nothing predicted */ };

#define MISPREDICT_PENALTY 3   /* redirect from the memory stage (Rocket.scala take_pc_mem) */
#define REDIRECT_BUBBLE 1      /* a 32-bit instruction 2 mod 4 after a redirect waits for its second half
                                  (_rocket_timing.h redirect_bubble) */


/* The counter's tables, as both counters look them up, by table_key: an address in SRAM's
 * uncached view (0x4000_0000, 8 MiB: memory_map.py) as the same bytes' address in the cached one
 * (0x8000_0000), so that code runs alike in both views, whichever it was linked for
 * (shared_memory.py's table_key: the two must agree). */
#define TABLE_SRAM_CACHED 0x80000000ull
#define TABLE_SRAM_UNCACHED 0x40000000ull
#define TABLE_SRAM_SIZE (8ull << 20)

static inline uint64_t table_key(uint64_t address)
{
    return address - TABLE_SRAM_UNCACHED < TABLE_SRAM_SIZE ? address - TABLE_SRAM_UNCACHED + TABLE_SRAM_CACHED
                                                           : address;
}

static inline int is_csr_site(const insn_counter_t *c, uint64_t address)
{
    uint64_t key = table_key(address);
    return c->csr_sites != NULL && c->csr_sites[(key >> 1) & c->csr_mask] == key;
}

/* The poll loop whose head is at `address` (NULL: none) */
static inline poll_loop_t *loop_at(const insn_counter_t *c, uint64_t address)
{
    if (c->loops == NULL)
        return NULL;
    uint64_t key = table_key(address);
    poll_loop_t *loop = &c->loops[(key >> 1) & c->loop_mask];
    return loop->head == key ? loop : NULL;
}

static inline uint32_t table_entry(const insn_counter_t *c, uint64_t address)
{
    if (c->table == NULL || address < c->table_base || address >= c->table_end)
        return 0;
    return c->table[(address - c->table_base) >> 1];
}

/*
 * The memory access of an RV64GC load, store, LR/SC or AMO (`size` its length: 2 compressed, 4):
 * returns its width in bytes (0: not such an instruction) and sets its base register, offset and
 * whether it writes. The Python copy is cpu/decode.py's decode_memory_access; a test checks the two
 * agree on every instruction word it draws.
 */
static inline uint32_t bits_of(uint32_t word, int high, int low)
{
    return (word >> low) & ((1u << (high - low + 1)) - 1);
}

static inline int memory_access_of(uint32_t word, uint32_t size, uint32_t *rs1, int64_t *offset, int *is_store)
{
    if (size == 2) {
        uint32_t op = word & 3, funct3 = bits_of(word, 15, 13);
        *is_store = funct3 >= 5;
        if (op == 0 && funct3 != 0 && funct3 != 4) {          /* c.fld c.lw c.ld c.fsd c.sw c.sd */
            *rs1 = 8 + bits_of(word, 9, 7);
            if (funct3 == 2 || funct3 == 6) {
                *offset = bits_of(word, 12, 10) << 3 | bits_of(word, 6, 6) << 2 | bits_of(word, 5, 5) << 6;
                return 4;
            }
            *offset = bits_of(word, 12, 10) << 3 | bits_of(word, 6, 5) << 6;
            return 8;
        }
        if (op == 2 && funct3 >= 1 && funct3 <= 3) {          /* c.fldsp c.lwsp c.ldsp */
            *rs1 = 2;
            if (funct3 == 2) {
                *offset = bits_of(word, 12, 12) << 5 | bits_of(word, 6, 4) << 2 | bits_of(word, 3, 2) << 6;
                return 4;
            }
            *offset = bits_of(word, 12, 12) << 5 | bits_of(word, 6, 5) << 3 | bits_of(word, 4, 2) << 6;
            return 8;
        }
        if (op == 2 && funct3 >= 5) {                          /* c.fsdsp c.swsp c.sdsp */
            *rs1 = 2;
            if (funct3 == 6) {
                *offset = bits_of(word, 12, 9) << 2 | bits_of(word, 8, 7) << 6;
                return 4;
            }
            *offset = bits_of(word, 12, 10) << 3 | bits_of(word, 9, 7) << 6;
            return 8;
        }
        return 0;
    }
    uint32_t opcode = word & 0x7F, funct3 = bits_of(word, 14, 12);
    *rs1 = bits_of(word, 19, 15);
    if (opcode == 0x03 || opcode == 0x07) {                    /* loads */
        *is_store = 0;
        *offset = (int64_t)(int32_t)word >> 20;
        return 1u << (funct3 & 3);
    }
    if (opcode == 0x23 || opcode == 0x27) {                    /* stores */
        *is_store = 1;
        *offset = (int64_t)(((int32_t)word >> 25) << 5 | (int32_t)bits_of(word, 11, 7));
        return 1u << (funct3 & 3);
    }
    if (opcode == 0x2F && (funct3 == 2 || funct3 == 3)) {      /* LR/SC and AMOs */
        *is_store = bits_of(word, 31, 27) != 0x02;             /* all but LR write */
        *offset = 0;
        return funct3 == 3 ? 8 : 4;
    }
    return 0;
}

#endif
