/*
 * The fast engine's counter: whole translated blocks instead of single instructions.
 *
 * A code hook on every instruction costs Unicorn a call per instruction, about half its speed
 * on the firmware's drawing. Each hart therefore has a second engine (hart.py) whose only
 * counting hook is this block hook: Unicorn calls it once as each translated block starts, and
 * it charges the whole block at once, exactly as count_instruction would charge its instructions
 * one by one (the same counter, the same cycle table, the same predictor), or it stops the engine
 * before the block starts and hands the hart to the precise engine (the per-instruction counter),
 * which then runs the rest of the turn. It hands over when charging whole would differ from
 * counting one by one:
 *  - the block would cross the turn's instruction or cycle limit (the precise engine stops at the
 *    exact instruction);
 *  - it holds a poll-loop head or a CSR the board answers (both need the precise engine's stops),
 *    a control transfer before its last instruction, or more than BLOCK_MAX instructions;
 *  - it holds a multiply or divide whose operands cannot be worked out at the block's start (their
 *    cycles depend on the values: see below).
 * A block may also stop part-way (a device access faults in the fast engine, which maps SRAM only;
 * an exception; wfi): block_cut then takes back what was charged for the instructions that did not
 * run, and the precise engine runs them.
 *
 * Multiply and divide cycles depend on the operands. At the block's start the registers hold what
 * the block begins with; a small interpreter runs the block's integer instructions up to its last
 * multiply or divide (integer arithmetic, loads from SRAM), so the operands are known at each.
 * What it does not follow (floating point, loads after a store in the block) makes a register
 * unknown; an unknown operand hands the block over.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "_counter.h"

#define BLOCK_MAX 512   /* QEMU translates at most 512 instructions into a block */
#define HANDOFF_BLOCK 1   /* the block cannot be charged whole */
#define HANDOFF_LIMIT 2   /* the block would cross the turn's limit */

typedef struct {
    uint64_t address;     /* 0: an empty slot */
    uint32_t size;        /* bytes, as Unicorn translated it */
    uint32_t first;       /* its first instruction in the pool */
    uint16_t count;
    uint8_t whole;        /* may be charged whole */
    uint8_t muldiv;       /* holds a multiply or divide */
    uint16_t last_muldiv; /* index of the last one */
    uint32_t static_cycles; /* what its instructions cost known from the table alone: 1 + extra each */
    uint32_t static_last;   /* the same for its last instruction */
    uint32_t extras;        /* the table's extra cycles, summed */
} block_t;

typedef struct {
    uint32_t word;        /* the instruction, a compressed one expanded to its 32-bit form */
    uint32_t entry;       /* its cycle-table entry (0 outside the table) */
    uint16_t offset;      /* from the block's start */
    uint8_t size;
} binsn_t;

#define FRONT_SLOTS 512   /* a small direct-mapped cache in front of the block table */

typedef struct block_state {
    const block_t *front[FRONT_SLOTS];
    block_t *blocks;
    uint32_t mask;
    uint32_t used;
    binsn_t *pool;
    uint32_t pool_used, pool_cap;
    const uint8_t *sram;           /* the SRAM both views show, for code and for loads */
    uint64_t sram_size, sram_base, sram_alias;
    /* the block charged last, for block_cut */
    const block_t *last;
    uint32_t penalty;              /* its first instruction's misprediction penalty */
    uint32_t dynamic[BLOCK_MAX];   /* multiply and divide stalls, up to its last multiply or divide */
    int32_t pending_kind_before;
    uint64_t pending_pc_before;
    uint32_t pending_entry_before;
    transfer_undo_t undo;
    /* statistics for the bench */
    uint64_t charged_blocks, charged_instructions, handoffs[3];
} block_state_t;

/* --- the block cache --------------------------------------------------------------------- */

__attribute__((visibility("default")))
block_state_t *block_state_new(const uint8_t *sram, uint64_t sram_size, uint64_t sram_base, uint64_t sram_alias)
{
    block_state_t *s = calloc(1, sizeof *s);
    if (s == NULL)
        return NULL;
    s->mask = 1023;
    s->blocks = calloc(s->mask + 1, sizeof *s->blocks);
    s->pool_cap = 8192;
    s->pool = malloc(s->pool_cap * sizeof *s->pool);
    if (s->blocks == NULL || s->pool == NULL) {
        free(s->blocks);
        free(s->pool);
        free(s);
        return NULL;
    }
    s->sram = sram;
    s->sram_size = sram_size;
    s->sram_base = sram_base;
    s->sram_alias = sram_alias;
    return s;
}

__attribute__((visibility("default")))
void block_state_free(block_state_t *s)
{
    if (s == NULL)
        return;
    free(s->blocks);
    free(s->pool);
    free(s);
}

/* The host address of `length` bytes at guest `address` in SRAM (either view), or NULL. */
static const uint8_t *sram_at(const block_state_t *s, uint64_t address, uint64_t length)
{
    for (int view = 0; view < 2; view++) {
        uint64_t base = view ? s->sram_alias : s->sram_base;
        if (address >= base && address - base + length <= s->sram_size)
            return s->sram + (address - base);
    }
    return NULL;
}

static uint32_t slot_of(uint64_t address, uint32_t mask)
{
    return (uint32_t)((address >> 1) ^ (address >> 13)) & mask;
}

static int grow(block_state_t *s)
{
    uint32_t mask = s->mask * 2 + 1;
    block_t *blocks = calloc(mask + 1, sizeof *blocks);
    if (blocks == NULL)
        return 0;
    for (uint32_t i = 0; i <= s->mask; i++) {
        if (!s->blocks[i].address)
            continue;
        uint32_t j = slot_of(s->blocks[i].address, mask);
        while (blocks[j].address)
            j = (j + 1) & mask;
        blocks[j] = s->blocks[i];
    }
    free(s->blocks);
    s->blocks = blocks;
    s->mask = mask;
    s->last = NULL;
    memset(s->front, 0, sizeof s->front);   /* it pointed into the old table */
    return 1;
}

/* RVC: the 32-bit instruction a compressed one stands for (RISC-V unprivileged spec, chapter
 * "C" Standard Extension, RV64 forms); 0 when it is not one the fast engine follows (it then only
 * loses the register it writes, see interpret). */
static uint32_t r_type(uint32_t f7, uint32_t rs2, uint32_t rs1, uint32_t f3, uint32_t rd, uint32_t op)
{
    return f7 << 25 | rs2 << 20 | rs1 << 15 | f3 << 12 | rd << 7 | op;
}

static uint32_t i_type(int32_t imm, uint32_t rs1, uint32_t f3, uint32_t rd, uint32_t op)
{
    return ((uint32_t)imm & 0xFFF) << 20 | rs1 << 15 | f3 << 12 | rd << 7 | op;
}

static uint32_t s_type(uint32_t imm, uint32_t rs2, uint32_t rs1, uint32_t f3, uint32_t op)
{
    return (imm >> 5 & 0x7F) << 25 | rs2 << 20 | rs1 << 15 | f3 << 12 | (imm & 31) << 7 | op;
}

static uint32_t expand_rvc(uint16_t h)
{
    uint32_t op = h & 3, f3 = h >> 13;
    uint32_t rd = (h >> 7) & 31, rs2 = (h >> 2) & 31;
    uint32_t rdp = 8 + ((h >> 2) & 7), rs1p = 8 + ((h >> 7) & 7);
    int32_t imm6 = (int32_t)(((h >> 7) & 0x20) | ((h >> 2) & 0x1F));
    if (imm6 & 0x20)
        imm6 -= 64;
    if (op == 0) {
        if (f3 == 0) {   /* c.addi4spn */
            uint32_t nz = ((h >> 7) & 0x30) | ((h >> 1) & 0x3C0) | ((h >> 4) & 4) | ((h >> 2) & 8);
            return nz ? i_type((int32_t)nz, 2, 0, rdp, 0x13) : 0;
        }
        uint32_t off_w = ((h >> 7) & 0x38) | ((h << 1) & 0x40) | ((h >> 4) & 4);
        uint32_t off_d = ((h >> 7) & 0x38) | ((h << 1) & 0xC0);
        if (f3 == 2)     /* c.lw */
            return i_type((int32_t)off_w, rs1p, 2, rdp, 0x03);
        if (f3 == 3)     /* c.ld */
            return i_type((int32_t)off_d, rs1p, 3, rdp, 0x03);
        if (f3 == 6)     /* c.sw */
            return s_type(off_w, rdp, rs1p, 2, 0x23);
        if (f3 == 7)     /* c.sd */
            return s_type(off_d, rdp, rs1p, 3, 0x23);
        if (f3 == 5)     /* c.fsd */
            return s_type(off_d, rdp, rs1p, 3, 0x27);
        if (f3 == 1)     /* c.fld */
            return i_type((int32_t)off_d, rs1p, 3, rdp, 0x07);
        return 0;
    }
    if (op == 1) {
        switch (f3) {
        case 0: return i_type(imm6, rd, 0, rd, 0x13);                 /* c.addi (c.nop) */
        case 1: return rd ? i_type(imm6, rd, 0, rd, 0x1B) : 0;       /* c.addiw */
        case 2: return i_type(imm6, 0, 0, rd, 0x13);                  /* c.li */
        case 3:
            if (rd == 2) {                                            /* c.addi16sp */
                int32_t nz = (int32_t)(((h >> 3) & 0x200) | ((h >> 2) & 0x10) | ((h << 1) & 0x40)
                                       | ((h << 4) & 0x180) | ((h << 3) & 0x20));
                if (nz & 0x200)
                    nz -= 0x400;
                return i_type(nz, 2, 0, 2, 0x13);
            }
            return (uint32_t)(imm6 << 12) & 0xFFFFF000u ? ((uint32_t)(imm6 << 12) | rd << 7 | 0x37) : 0;  /* c.lui */
        case 4: {
            uint32_t f2 = (h >> 10) & 3;
            uint32_t shamt = (uint32_t)(((h >> 7) & 0x20) | ((h >> 2) & 0x1F));
            if (f2 == 0)
                return i_type((int32_t)shamt, rs1p, 5, rs1p, 0x13);               /* c.srli */
            if (f2 == 1)
                return i_type((int32_t)(shamt | 0x400), rs1p, 5, rs1p, 0x13);     /* c.srai */
            if (f2 == 2)
                return i_type(imm6, rs1p, 7, rs1p, 0x13);                         /* c.andi */
            uint32_t f = (h >> 5) & 3, rs2p = 8 + ((h >> 2) & 7);
            if (!(h & 0x1000)) {
                static const uint32_t f3s[4] = {0, 4, 6, 7};                       /* sub xor or and */
                return r_type(f == 0 ? 0x20 : 0, rs2p, rs1p, f3s[f], rs1p, 0x33);
            }
            if (f == 0)
                return r_type(0x20, rs2p, rs1p, 0, rs1p, 0x3B);                    /* c.subw */
            if (f == 1)
                return r_type(0, rs2p, rs1p, 0, rs1p, 0x3B);                       /* c.addw */
            return 0;
        }
        default: return 0;   /* c.j, c.beqz, c.bnez: transfers, the block's last */
        }
    }
    if (op == 2) {
        uint32_t shamt = (uint32_t)(((h >> 7) & 0x20) | ((h >> 2) & 0x1F));
        switch (f3) {
        case 0: return i_type((int32_t)shamt, rd, 1, rd, 0x13);                  /* c.slli */
        case 2: return i_type((int32_t)(((h >> 7) & 0x20) | ((h >> 2) & 0x1C) | ((h << 4) & 0xC0)), 2, 2, rd, 0x03);  /* c.lwsp */
        case 3: return i_type((int32_t)(((h >> 7) & 0x20) | ((h >> 2) & 0x18) | ((h << 4) & 0x1C0)), 2, 3, rd, 0x03); /* c.ldsp */
        case 1: return i_type(0, 2, 3, rd, 0x07);                                 /* c.fldsp: FP, no integer */
        case 4:
            if (!(h & 0x1000)) {
                if (rs2 == 0)
                    return 0;                                  /* c.jr */
                return r_type(0, rs2, 0, 0, rd, 0x33);         /* c.mv */
            }
            if (rs2 == 0)
                return 0;                                      /* c.ebreak, c.jalr */
            return r_type(0, rs2, rd, 0, rd, 0x33);            /* c.add */
        case 5: return s_type(((h >> 7) & 0x38) | ((h >> 1) & 0x1C0), rs2, 2, 3, 0x27);   /* c.fsdsp */
        case 6: return s_type(((h >> 7) & 0x3C) | ((h >> 1) & 0xC0), rs2, 2, 2, 0x23);    /* c.swsp */
        case 7: return s_type(((h >> 7) & 0x38) | ((h >> 1) & 0x1C0), rs2, 2, 3, 0x23);   /* c.sdsp */
        }
    }
    return 0;
}

static int is_loop_head(const insn_counter_t *c, uint64_t address)
{
    const poll_loop_t *slot = loop_slot(c, address);
    return slot != NULL && slot->head == address;
}

/* Decodes the block Unicorn translated at `address` (`size` bytes) into the cache. */
static const block_t *build(insn_counter_t *c, block_state_t *s, uint64_t address, uint32_t size)
{
    if (s->used * 2 >= s->mask && !grow(s))
        return NULL;
    uint32_t i = slot_of(address, s->mask);
    while (s->blocks[i].address && s->blocks[i].address != address)
        i = (i + 1) & s->mask;
    block_t *b = &s->blocks[i];
    if (!b->address)
        s->used++;
    memset(b, 0, sizeof *b);
    b->address = address;
    b->size = size;
    b->first = s->pool_used;
    const uint8_t *code = sram_at(s, address, size);
    if (code == NULL || size == 0)
        return b;                                   /* not whole: the precise engine runs it */
    uint32_t offset = 0, count = 0;
    int whole = 1;
    while (offset < size) {
        if (count == BLOCK_MAX || offset + 2 > size) {
            whole = 0;
            break;
        }
        uint16_t h = (uint16_t)(code[offset] | code[offset + 1] << 8);
        uint32_t length = (h & 3) == 3 ? 4 : 2;
        if (offset + length > size) {
            whole = 0;
            break;
        }
        if (s->pool_used == s->pool_cap) {
            binsn_t *pool = realloc(s->pool, 2 * s->pool_cap * sizeof *pool);
            if (pool == NULL)
                return NULL;
            s->pool = pool;
            s->pool_cap *= 2;
        }
        uint64_t at = address + offset;
        binsn_t *insn = &s->pool[s->pool_used++];
        insn->word = length == 4 ? (uint32_t)(h | (uint32_t)(code[offset + 2] | code[offset + 3] << 8) << 16)
                                 : expand_rvc(h);
        insn->entry = table_entry(c, at);
        insn->offset = (uint16_t)offset;
        insn->size = (uint8_t)length;
        int kind = (int)E_KIND(insn->entry);
        b->static_cycles += 1 + E_EXTRA(insn->entry);
        b->static_last = 1 + E_EXTRA(insn->entry);
        b->extras += E_EXTRA(insn->entry);
        if (is_loop_head(c, at) || is_csr_site(c, at))
            whole = 0;
        if ((kind == KIND_BRANCH || kind == KIND_JAL || kind == KIND_JALR) && offset + length < size)
            whole = 0;                              /* a transfer before the last instruction */
        if (kind == KIND_MUL || kind == KIND_DIV) {
            b->muldiv = 1;
            b->last_muldiv = (uint16_t)count;
        }
        offset += length;
        count++;
    }
    b->count = (uint16_t)count;
    b->whole = (uint8_t)whole;
    return b;
}

static const block_t *find_in_table(insn_counter_t *c, block_state_t *s, uint64_t address, uint32_t size)
{
    uint32_t i = slot_of(address, s->mask);
    while (s->blocks[i].address) {
        if (s->blocks[i].address == address)
            return s->blocks[i].size == size ? &s->blocks[i] : build(c, s, address, size);
        i = (i + 1) & s->mask;
    }
    return build(c, s, address, size);
}

static const block_t *find(insn_counter_t *c, block_state_t *s, uint64_t address, uint32_t size)
{
    const block_t **front = &s->front[(address >> 1) & (FRONT_SLOTS - 1)];
    if (*front != NULL && (*front)->address == address && (*front)->size == size)
        return *front;
    const block_t *b = find_in_table(c, s, address, size);
    if (b != NULL)
        *front = b;
    return b;
}

/* --- the interpreter for multiply and divide operands --------------------------------------- */

#define STORES_KEPT 32

typedef struct {
    uint64_t v[32];
    uint32_t fetched;   /* read from the engine (or written by the block) */
    uint32_t known;     /* holds a value the interpreter knows */
    /* the block's stores so far: a load that overlaps one is not followed (what it reads is not
     * in memory yet); a store to an unknown address, or too many, and no load is followed */
    uint64_t store_at[STORES_KEPT];
    uint8_t store_width[STORES_KEPT];
    uint32_t stores;
    int stores_unknown;
} regs_t;

static int get(insn_counter_t *c, void *uc, regs_t *r, uint32_t n, uint64_t *value)
{
    if (n == 0) {
        *value = 0;
        return 1;
    }
    if (!(r->fetched >> n & 1)) {
        c->reg_read(uc, c->reg_x0 + (int)n, &r->v[n]);
        r->fetched |= 1u << n;
        r->known |= 1u << n;
    }
    *value = r->v[n];
    return (int)(r->known >> n & 1);
}

static void put(regs_t *r, uint32_t n, uint64_t value, int known)
{
    if (n == 0)
        return;
    r->fetched |= 1u << n;
    r->v[n] = value;
    if (known)
        r->known |= 1u << n;
    else
        r->known &= ~(1u << n);
}

static uint64_t sext32(uint64_t x)
{
    return (uint64_t)(int64_t)(int32_t)(uint32_t)x;
}

/* RV64M, as the spec defines every case (division by zero and overflow included). */
static uint64_t m_op(uint32_t f3, uint64_t a, uint64_t b, int word)
{
    if (word) {
        int32_t x = (int32_t)a, y = (int32_t)b;
        uint32_t ux = (uint32_t)a, uy = (uint32_t)b;
        switch (f3) {
        case 0: return sext32((uint64_t)((uint32_t)x * (uint32_t)y));
        case 4: return sext32(y == 0 ? UINT64_MAX : (x == INT32_MIN && y == -1) ? (uint64_t)(int64_t)x : (uint64_t)(int64_t)(x / y));
        case 5: return sext32(uy == 0 ? UINT64_MAX : ux / uy);
        case 6: return sext32(y == 0 ? (uint64_t)(int64_t)x : (x == INT32_MIN && y == -1) ? 0 : (uint64_t)(int64_t)(x % y));
        case 7: return sext32(uy == 0 ? ux : ux % uy);
        default: return 0;
        }
    }
    int64_t x = (int64_t)a, y = (int64_t)b;
    switch (f3) {
    case 0: return a * b;
    case 1: return (uint64_t)(((__int128)x * (__int128)y) >> 64);
    case 2: return (uint64_t)(((__int128)x * (__int128)(unsigned __int128)b) >> 64);
    case 3: return (uint64_t)(((unsigned __int128)a * (unsigned __int128)b) >> 64);
    case 4: return b == 0 ? UINT64_MAX : (x == INT64_MIN && y == -1) ? a : (uint64_t)(x / y);
    case 5: return b == 0 ? UINT64_MAX : a / b;
    case 6: return b == 0 ? a : (x == INT64_MIN && y == -1) ? 0 : (uint64_t)(x % y);
    default: return b == 0 ? a : a % b;
    }
}

static uint64_t load(const block_state_t *s, uint64_t address, uint32_t f3, int *ok)
{
    static const uint32_t widths[8] = {1, 2, 4, 8, 1, 2, 4, 0};
    uint32_t width = widths[f3 & 7];
    const uint8_t *p = width ? sram_at(s, address, width) : NULL;
    if (p == NULL) {
        *ok = 0;
        return 0;
    }
    uint64_t v = 0;
    memcpy(&v, p, width);   /* the host is little-endian, like the K210 */
    *ok = 1;
    switch (f3) {
    case 0: return (uint64_t)(int64_t)(int8_t)v;
    case 1: return (uint64_t)(int64_t)(int16_t)v;
    case 2: return sext32(v);
    default: return v;
    }
}

static void note_store(insn_counter_t *c, void *uc, regs_t *r, uint32_t rs1, int64_t offset, uint32_t width)
{
    uint64_t base;
    if (!get(c, uc, r, rs1, &base) || r->stores == STORES_KEPT) {
        r->stores_unknown = 1;
        return;
    }
    r->store_at[r->stores] = base + (uint64_t)offset;
    r->store_width[r->stores++] = (uint8_t)width;
}

static int overlaps_a_store(const regs_t *r, uint64_t address, uint32_t width)
{
    if (r->stores_unknown)
        return 1;
    for (uint32_t i = 0; i < r->stores; i++)
        if (address < r->store_at[i] + r->store_width[i] && r->store_at[i] < address + width)
            return 1;
    return 0;
}

/* Runs instruction `w` at `pc` on the known registers. For a multiply or divide, also stores its
 * operands in a, b and returns 0 when they are not both known. */
static int interpret(insn_counter_t *c, void *uc, const block_state_t *s, regs_t *r, uint32_t w, uint64_t pc,
                     uint64_t *a, uint64_t *b)
{
    uint32_t op = w & 0x7F, rd = (w >> 7) & 31, f3 = (w >> 12) & 7, rs1 = (w >> 15) & 31, rs2 = (w >> 20) & 31;
    uint32_t f7 = w >> 25;
    int64_t imm_i = (int32_t)w >> 20;
    uint64_t x = 0, y = 0;
    int kx, ky;
    if (w == 0) {                       /* not followed: whatever it may write is lost */
        r->fetched = UINT32_MAX;
        r->known = 0;
        return 1;
    }
    switch (op) {
    case 0x37: put(r, rd, (uint64_t)(int64_t)(int32_t)(w & 0xFFFFF000u), 1); return 1;
    case 0x17: put(r, rd, pc + (uint64_t)(int64_t)(int32_t)(w & 0xFFFFF000u), 1); return 1;
    case 0x13: case 0x1B: {
        kx = get(c, uc, r, rs1, &x);
        uint64_t v, shamt = (uint64_t)imm_i & (op == 0x13 ? 63 : 31);
        if (op == 0x13) {
            switch (f3) {
            case 0: v = x + (uint64_t)imm_i; break;
            case 1: v = x << shamt; break;
            case 2: v = (int64_t)x < imm_i; break;
            case 3: v = x < (uint64_t)imm_i; break;
            case 4: v = x ^ (uint64_t)imm_i; break;
            case 5: v = (w >> 30) & 1 ? (uint64_t)((int64_t)x >> shamt) : x >> shamt; break;
            case 6: v = x | (uint64_t)imm_i; break;
            default: v = x & (uint64_t)imm_i; break;
            }
        } else {
            switch (f3) {
            case 0: v = sext32(x + (uint64_t)imm_i); break;
            case 1: v = sext32((uint32_t)x << shamt); break;
            case 5: v = (w >> 30) & 1 ? sext32((uint64_t)((int32_t)x >> shamt)) : sext32((uint32_t)x >> shamt); break;
            default: put(r, rd, 0, 0); return 1;
            }
        }
        put(r, rd, v, kx);
        return 1;
    }
    case 0x33: case 0x3B: {
        kx = get(c, uc, r, rs1, &x);
        ky = get(c, uc, r, rs2, &y);
        int word = op == 0x3B;
        uint64_t v;
        if (f7 == 1) {
            *a = x;
            *b = y;
            put(r, rd, m_op(f3, x, y, word), kx && ky);
            return kx && ky;
        }
        if (!word) {
            switch (f3) {
            case 0: v = f7 == 0x20 ? x - y : x + y; break;
            case 1: v = x << (y & 63); break;
            case 2: v = (int64_t)x < (int64_t)y; break;
            case 3: v = x < y; break;
            case 4: v = x ^ y; break;
            case 5: v = f7 == 0x20 ? (uint64_t)((int64_t)x >> (y & 63)) : x >> (y & 63); break;
            case 6: v = x | y; break;
            default: v = x & y; break;
            }
        } else {
            switch (f3) {
            case 0: v = sext32(f7 == 0x20 ? x - y : x + y); break;
            case 1: v = sext32((uint32_t)x << (y & 31)); break;
            case 5: v = f7 == 0x20 ? sext32((uint64_t)((int32_t)x >> (y & 31))) : sext32((uint32_t)x >> (y & 31)); break;
            default: put(r, rd, 0, 0); return 1;
            }
        }
        put(r, rd, v, kx && ky);
        return 1;
    }
    case 0x03: {
        static const uint32_t widths[8] = {1, 2, 4, 8, 1, 2, 4, 8};
        kx = get(c, uc, r, rs1, &x);
        int ok = 0;
        uint64_t v = 0;
        if (kx && !overlaps_a_store(r, x + (uint64_t)imm_i, widths[f3]))
            v = load(s, x + (uint64_t)imm_i, f3, &ok);
        put(r, rd, v, ok);
        return 1;
    }
    case 0x23: case 0x27: {
        int64_t imm_s = ((int32_t)(w & 0xFE000000u) >> 20) | (int32_t)((w >> 7) & 31);
        note_store(c, uc, r, rs1, imm_s, 1u << (f3 & 3));
        return 1;
    }
    case 0x2F:
        r->stores_unknown = 1;          /* atomics: read and write memory */
        put(r, rd, 0, 0);
        return 1;
    case 0x07: case 0x0F: case 0x43: case 0x47: case 0x4B: case 0x4F: case 0x63:
        return 1;                       /* no integer register written */
    case 0x53:
        /* compares, moves and conversions to an integer register (funct5 10100, 11000, 11100) */
        if ((w >> 27) == 0x14 || (w >> 27) == 0x18 || (w >> 27) == 0x1C)
            put(r, rd, 0, 0);
        return 1;
    case 0x6F: case 0x67:
        put(r, rd, pc + 4, 1);          /* the block's last: its link is not used in it */
        return 1;
    default:
        put(r, rd, 0, 0);
        return 1;
    }
}

/* --- the hook ------------------------------------------------------------------------------ */

static void hand_off(insn_counter_t *c, block_state_t *s, void *uc, uint64_t why)
{
    c->handoff = why;
    s->handoffs[why]++;
    s->last = NULL;
    c->stop(uc);
}

__attribute__((visibility("default")))
void count_block(void *uc, uint64_t address, uint32_t size, insn_counter_t *c)
{
    block_state_t *s = c->blocks;
    if (c->handoff)
        return;                         /* stopping already */
    const block_t *b = find(c, s, address, size);
    if (b == NULL || !b->whole) {
        hand_off(c, s, uc, HANDOFF_BLOCK);
        return;
    }
    uint32_t n = b->count;
    if (n == 0)
        return;
    if (c->executed + n > c->limit || c->cycles >= c->cycle_limit) {
        hand_off(c, s, uc, HANDOFF_LIMIT);
        return;
    }
    const binsn_t *insns = &s->pool[b->first];
    /* the multiply and divide stalls count_instruction would charge, from the operands */
    uint64_t dynamic = 0, dynamic_before_last = 0;
    if (b->muldiv) {
        regs_t r;
        r.fetched = 0;
        r.known = 0;
        r.stores = 0;
        r.stores_unknown = 0;
        for (uint32_t i = 0; i <= b->last_muldiv; i++) {
            uint64_t x = 0, y = 0;
            uint32_t e = insns[i].entry;
            int kind = (int)E_KIND(e);
            int known = interpret(c, uc, s, &r, insns[i].word, address + insns[i].offset, &x, &y);
            s->dynamic[i] = 0;
            if (kind == KIND_MUL || kind == KIND_DIV) {
                if (!known) {
                    hand_off(c, s, uc, HANDOFF_BLOCK);
                    return;
                }
                uint64_t latency = muldiv_latency(e, x, y, kind == KIND_DIV);
                uint64_t distance = E_DIST(e);
                s->dynamic[i] = (uint32_t)(latency > distance ? latency - distance : 0);
                dynamic += s->dynamic[i];
                if (i + 1 < n)
                    dynamic_before_last += s->dynamic[i];
            }
        }
    }
    s->pending_kind_before = c->pending_kind;
    s->pending_pc_before = c->pending_pc;
    s->pending_entry_before = c->pending_entry;
    s->undo.used = 0;
    uint64_t penalty = 0;
    if (c->pending_kind)
        penalty = resolve_transfer(c, c->pending_pc, c->pending_entry, c->pending_kind, address, &s->undo);
    /* count_instruction starts instruction i while the cycles before it are under the limit: the
     * last one has the most before it */
    uint64_t before_last = n == 1 ? c->cycles
                                  : c->cycles + penalty + b->static_cycles - b->static_last + dynamic_before_last;
    if (before_last >= c->cycle_limit) {
        undo_transfer(c, &s->undo);
        hand_off(c, s, uc, HANDOFF_LIMIT);
        return;
    }
    c->executed += n;
    c->cycles += b->static_cycles + penalty + dynamic;
    c->stall_cycles += b->extras + dynamic;
    uint32_t e = insns[n - 1].entry;
    int kind = (int)E_KIND(e);
    if (kind == KIND_BRANCH || kind == KIND_JAL || kind == KIND_JALR) {
        c->pending_kind = kind;
        c->pending_pc = address + insns[n - 1].offset;
        c->pending_entry = e;
    } else {
        c->pending_kind = 0;
    }
    s->last = b;
    s->penalty = (uint32_t)penalty;
    s->charged_blocks++;
    s->charged_instructions += n;
}

/*
 * The fast engine stopped with its pc at `pc` inside the block charged last (a device access
 * faulted, an exception, wfi): takes back the charge of the instructions from `pc` on, which did
 * not run. Returns how many were taken back, or -1 when `pc` is not at an instruction of that
 * block (nothing is changed then; a pc just past the block takes nothing back).
 */
__attribute__((visibility("default")))
int block_cut(insn_counter_t *c, uint64_t pc)
{
    block_state_t *s = c->blocks;
    const block_t *b = s->last;
    if (b == NULL || pc < b->address || pc > b->address + b->size)
        return pc == 0 ? -1 : 0;
    if (pc == b->address + b->size)
        return 0;
    const binsn_t *insns = &s->pool[b->first];
    uint32_t k = 0;
    while (k < b->count && b->address + insns[k].offset != pc)
        k++;
    if (k == b->count)
        return -1;
    for (uint32_t i = k; i < b->count; i++) {
        uint32_t extra = E_EXTRA(insns[i].entry) + (b->muldiv && i <= b->last_muldiv ? s->dynamic[i] : 0);
        c->executed--;
        c->cycles -= 1 + extra + (i == 0 ? s->penalty : 0);
        c->stall_cycles -= extra;
    }
    if (k == 0) {
        undo_transfer(c, &s->undo);
        c->pending_kind = s->pending_kind_before;
        c->pending_pc = s->pending_pc_before;
        c->pending_entry = s->pending_entry_before;
    } else {
        c->pending_kind = 0;
    }
    s->last = NULL;
    return (int)(b->count - k);
}

/* Statistics: blocks and instructions charged whole, hand-overs per reason. */
__attribute__((visibility("default")))
void block_statistics(const block_state_t *s, uint64_t out[5])
{
    out[0] = s->charged_blocks;
    out[1] = s->charged_instructions;
    out[2] = s->handoffs[HANDOFF_BLOCK];
    out[3] = s->handoffs[HANDOFF_LIMIT];
    out[4] = s->used;
}
