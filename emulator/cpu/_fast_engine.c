/*
 * The fast engine: an RV64IMAFDC interpreter for the harts' code in SRAM.
 *
 * Unicorn runs the firmware's drawing at about 6 ns an instruction with no hook at all, 11-15 ns
 * with the per-instruction counter; a frame of the default card is a million instructions on
 * hart 0, so the board model could not keep up with the Dock through Unicorn, however it counted.
 * This interpreter decodes each straight run of instructions once into a block (block_t: its code
 * bytes are compared with a kept copy before it runs, once per epoch, so that code written later is
 * decoded again), executes it on the hart's registers held here, and counts and times each
 * instruction exactly as _insn_counter.c's count_instruction does, with the same counter, cycle
 * table and branch predictor (_rocket_timing.h).
 *
 * An integer load or store that is naturally aligned and falls in a device window (fast_set_windows)
 * is counted and then left to the caller (STOP_DEVICE, the access described in the state's `dev`):
 * the board carries it out with the hart's registers still held here, and fast_resume completes it
 * (a load's value into its register) and goes on. A device access therefore costs a return to
 * Python, not a run of the precise engine with the registers moved there and back.
 *
 * What it does not carry out it hands to the precise engine (Unicorn with the per-instruction
 * counter, hart.py), before counting the instruction: any other access outside SRAM (a misaligned
 * one, which traps or is split as Unicorn splits it; one outside the windows), CSR instructions (but reads of mhartid), wfi, ecall, ebreak, mret, fence.i, LR/SC and AMOs,
 * instructions it does not know (the precise engine raises the illegal-instruction exception),
 * floating point on a NaN operand, with a rounding mode other than round-to-nearest-even where the
 * result is rounded (conversions to integers take any mode), or with the FPU off. Registers move
 * between the engines at each hand-over (fast_run loads them from Unicorn and stores them back).
 *
 * Floating point is the host's (IEEE 754 binary32/64, round to nearest even), through C99's <fenv.h>
 * so that any host builds it: its exception flags accumulate in the host's floating-point
 * environment while the engine runs and are added to fflags when it stops. RISC-V detects tininess
 * after rounding, as x86-64 SSE does; a host that detects it before rounding (AArch64, FPCR.AH = 0)
 * would raise underflow where the K210 does not, so there the operations that round hand over to
 * the precise engine (host_tiny_before_rounding). Results follow Unicorn 2.1.4
 * (QEMU 5.0) where it departs from the RISC-V spec of today: single-precision results other
 * than loads are not NaN-boxed, and single-precision operands are the low 32 bits whatever the
 * upper half holds. tests/unit/cpu/test_fast_engine.py compares this engine with the precise one.
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <fenv.h>

#include "_counter.h"
#include "_fast_engine.h"
#include "_host_fp.h"
#include "_rocket_timing.h"
#include "_turns.h"
#include "_write_check.h"


/* Unicorn's register ids (unicorn/riscv.h) */
#define UC_X1 2
#define UC_FFLAGS 41
#define UC_FRM 42
#define UC_MSTATUS 116
#define UC_F0 158
#define UC_PC 190

/* The guest computes in the host's default environment (FE_DFL_ENV): every exception masked, round
 * to nearest even, no flush-to-zero or denormals-are-zero, the flags clear (whatever a library
 * loaded in the process may have set: the results must be IEEE's, as QEMU's softfloat gives them). */

#define MSTATUS_FS (3ull << 13)
#define MSTATUS_SD (1ull << 63)

/* RISC-V fflags bits */
#define FF_NX 1
#define FF_UF 2
#define FF_OF 4
#define FF_DZ 8
#define FF_NV 16

/* Every operation the interpreter carries out (HANDOFF: none, the precise engine's). */
#define OPERATIONS(X) \
    X(HANDOFF) X(BLOCK_END) X(MHARTID) X(LUI) X(AUIPC) X(JAL) X(JALR) X(BEQ) X(BNE) X(BLT) X(BGE) X(BLTU) X(BGEU) X(LB) X(LH) \
    X(LW) X(LD) X(LBU) X(LHU) X(LWU) X(SB) X(SH) X(SW) X(SD) X(ADDI) X(SLTI) X(SLTIU) X(XORI) X(ORI) \
    X(ANDI) X(SLLI) X(SRLI) X(SRAI) X(ADD) X(SUB) X(SLL) X(SLT) X(SLTU) X(XOR) X(SRL) X(SRA) X(OR) \
    X(AND) X(ADDIW) X(SLLIW) X(SRLIW) X(SRAIW) X(ADDW) X(SUBW) X(SLLW) X(SRLW) X(SRAW) X(MUL) \
    X(MULH) X(MULHSU) X(MULHU) X(DIV) X(DIVU) X(REM) X(REMU) X(MULW) X(DIVW) X(DIVUW) X(REMW) \
    X(REMUW) X(FENCE) X(FLW) X(FLD) X(FSW) X(FSD) X(FADD_S) X(FSUB_S) X(FMUL_S) X(FDIV_S) X(FSQRT_S) \
    X(FMADD_S) X(FMSUB_S) X(FNMSUB_S) X(FNMADD_S) X(FSGNJ_S) X(FSGNJN_S) X(FSGNJX_S) X(FMIN_S) \
    X(FMAX_S) X(FEQ_S) X(FLT_S) X(FLE_S) X(FCLASS_S) X(FMV_X_W) X(FMV_W_X) X(FCVT_W_S) X(FCVT_WU_S) \
    X(FCVT_L_S) X(FCVT_LU_S) X(FCVT_S_W) X(FCVT_S_WU) X(FCVT_S_L) X(FCVT_S_LU) X(FADD_D) X(FSUB_D) \
    X(FMUL_D) X(FDIV_D) X(FSQRT_D) X(FMADD_D) X(FMSUB_D) X(FNMSUB_D) X(FNMADD_D) X(FSGNJ_D) \
    X(FSGNJN_D) X(FSGNJX_D) X(FMIN_D) X(FMAX_D) X(FEQ_D) X(FLT_D) X(FLE_D) X(FCLASS_D) X(FMV_X_D) \
    X(FMV_D_X) X(FCVT_W_D) X(FCVT_WU_D) X(FCVT_L_D) X(FCVT_LU_D) X(FCVT_D_W) X(FCVT_D_WU) \
    X(FCVT_D_L) X(FCVT_D_LU) X(FCVT_S_D) X(FCVT_D_S)

#define OP_ENUM(name) OP_##name,
enum { OPERATIONS(OP_ENUM) OP_COUNT };
#undef OP_ENUM

/* One decoded instruction. rd 32 is where writes to x0 go (x[0] stays 0). */
typedef struct {
    uint64_t pc;       /* its address (OP_BLOCK_END: the next block's) */
    int64_t imm;
    uint32_t entry;    /* the cycle table's entry for its address */
    uint16_t op;
    uint16_t cost;     /* its cycles known statically: 1 + the entry's extra */
    uint8_t rd, rs1, rs2, rs3, rm;
    uint8_t len;       /* 2 or 4 */
    uint8_t timing;    /* what COUNT does beyond adding `cost` (T_ flags; a transfer's handler sees to
                          T_TRANSFER itself) */
} insn_t;

/* insn_t.timing: a control transfer (resolved when the next instruction shows where it went), a
 * multiply or divide (its latency depends on its operands), the head of a poll loop */
#define T_TRANSFER 1
#define T_MULDIV 2
#define T_LOOP_HEAD 4
#define T_FETCH 8       /* with the caches, a block's first instruction, the first in a new line, or one
                           that straddles two lines: the instruction cache looks (none without: no time
                           spent on it) */

/* A straight run of decoded instructions from `pc` up to a jump (a conditional branch taken leaves
 * it in the middle), an instruction for
 * the precise engine, BLOCK_MAX instructions or the end of SRAM; then an OP_BLOCK_END (not
 * counted). Entered only after its code bytes were compared with the copy kept here, so that
 * code written since (by a hart or a DMA) is decoded again: once in each epoch, a stretch in which
 * nothing but the interpreter itself wrote SRAM and it wrote none of the decoded code (an epoch
 * begins with each call of the interpreter and with each such store of its own). */
#define BLOCK_MAX 32
typedef struct {
    uint64_t pc;
    uint32_t bytes;    /* code bytes it covers */
    uint32_t count;    /* instructions, OP_BLOCK_END not included */
    uint64_t checked;  /* the fast_state's epoch in which its code was last compared */
    uint8_t code[BLOCK_MAX * 4 + 8];   /* zeros after `bytes` (same_code reads whole words) */
    insn_t insns[BLOCK_MAX + 1];
} block_t;

#define BLOCK_INDEX_BITS 16
#define BLOCK_INDEX_SLOTS (1u << BLOCK_INDEX_BITS)
#define BLOCK_ARENA (4096u)   /* blocks decoded before the index is emptied and decoding starts over */

typedef int (*uc_reg_batch_fn)(void *uc, int *regs, void **values, int count);

#define MAX_WINDOWS 64

/* A device access the interpreter stopped at (STOP_DEVICE), counted but not carried out. */
typedef struct {
    uint64_t address;
    uint64_t value;      /* a store's value */
    uint64_t next_pc;
    uint32_t width;      /* bytes */
    uint32_t is_store;
    uint32_t window;     /* which of fast_set_windows' windows */
    uint32_t rd;         /* a load's destination (32: x0's sink) */
    uint32_t sign_bits;  /* a load's width in bits to sign-extend from; 0: zero-extended */
    uint32_t pad;
} device_access_t;

/* The last device load, which the bus says would give the same value, changing nothing, while the
 * hart's cycle count is below `until` and no other device access comes between: the same load again is answered here, counted as a poll as
 * Scheduler.note_poll counts it (a hart polling a status register does it many times a byte). */
typedef struct {
    uint64_t pc, address, value;   /* the load, and the value the device gave (before extension) */
    uint64_t until;                /* the hart's cycle count at which that stops (hart.py works it out: no
                                      float arithmetic here, where the guest's environment collects flags) */
    uint32_t width, armed;
    uint32_t repeats, needed;      /* note_poll's count of identical reads so far, POLL_REPEATS */
    uint32_t answered, polling;    /* out: loads answered here; the count reached `needed` */
} repeat_t;

/* hart.py's _FastHead mirrors the fields up to `rep` */
typedef struct fast_state {
    uint64_t x[33];
    uint64_t f[32];
    uint64_t pc;
    uint64_t mstatus;
    uint64_t fflags, frm;
    device_access_t dev;
    repeat_t rep;
    uint32_t windows;        /* device windows in window_base/window_end */
    uint32_t devices_here;   /* during a run: device accesses stop with STOP_DEVICE (else hand over) */
    uint64_t window_base[MAX_WINDOWS], window_end[MAX_WINDOWS];
    fenv_t host_env;         /* the host's floating-point environment while the guest's is in place */
    uint64_t epoch;          /* see block_t.checked */
    const uint8_t *code_lo, *code_hi;   /* the SRAM bytes some decoded block covers lie in [lo, hi) */
    uint8_t *sram;
    uint64_t size, base, alias;
    uint64_t hart_id;
    uc_reg_batch_fn read_batch, write_batch;
    uint64_t instructions;   /* statistics: instructions this engine ran */
    uint64_t handoffs;       /* and the times it handed the hart over */
    uint64_t blocks_built;   /* and the blocks it decoded */
    uint32_t blocks_used;    /* of the arena */
    int fp_written;          /* during a run: an FP register was written */
    uint64_t soft_flags;     /* during a run: fflags raised by conversions worked out here */
    uint64_t entry_fflags, entry_mstatus;   /* at the run's start */
    write_watch_t *write_watch;   /* --check-writes: this hart's store check (NULL: none) */
    block_t *index[BLOCK_INDEX_SLOTS];   /* by start address, direct-mapped */
    block_t arena[BLOCK_ARENA];
} fast_state_t;

__attribute__((visibility("default")))
fast_state_t *fast_state_new(uint64_t hart_id, uint8_t *sram, uint64_t size, uint64_t base, uint64_t alias,
                             void *read_batch, void *write_batch)
{
    fast_state_t *f = calloc(1, sizeof *f);
    if (f == NULL)
        return NULL;
    f->hart_id = hart_id;
    f->sram = sram;
    f->size = size;
    f->base = base;
    f->alias = alias;
    f->read_batch = (uc_reg_batch_fn)read_batch;
    f->write_batch = (uc_reg_batch_fn)write_batch;
    f->code_lo = sram + size;
    f->code_hi = sram;
    return f;
}

__attribute__((visibility("default")))
void fast_state_free(fast_state_t *f)
{
    free(f);
}

/* The counter's tables (poll loops, cycle table) changed: decode everything again. */
__attribute__((visibility("default")))
void fast_forget_decodings(fast_state_t *f)
{
    memset(f->index, 0, sizeof f->index);
    f->blocks_used = 0;
    f->code_lo = f->sram + f->size;
    f->code_hi = f->sram;
}

/* The device windows (physical addresses base..end-1) whose aligned integer accesses the interpreter
 * leaves to the caller (STOP_DEVICE); at most MAX_WINDOWS (returns 0 if more). */
__attribute__((visibility("default")))
int fast_set_windows(fast_state_t *f, const uint64_t *bases, const uint64_t *ends, uint32_t count)
{
    if (count > MAX_WINDOWS)
        return 0;
    for (uint32_t i = 0; i < count; i++) {
        f->window_base[i] = bases[i];
        f->window_end[i] = ends[i];
    }
    f->windows = count;
    return 1;
}

/* The window holding `width` bytes at `a`, or -1. */
static inline int device_window(const fast_state_t *f, uint64_t a, uint64_t width)
{
    for (uint32_t i = 0; i < f->windows; i++)
        if (a >= f->window_base[i] && a + width <= f->window_end[i])
            return (int)i;
    return -1;
}

/* --check-writes: the interpreter checks its SRAM stores against `watch` (write_watch.py) as the precise
 * engine's hook does; NULL: it checks none. */
__attribute__((visibility("default")))
void fast_set_write_watch(fast_state_t *f, write_watch_t *watch)
{
    f->write_watch = watch;
}

__attribute__((visibility("default")))
void fast_statistics(const fast_state_t *f, uint64_t out[3])
{
    out[0] = f->instructions;
    out[1] = f->handoffs;
    out[2] = f->blocks_built;
}

/* The host address of `width` bytes of SRAM (`size` bytes at `sram`) at guest address `a` in
 * either view, or NULL. */
static inline uint8_t *sram_at(uint8_t *sram, uint64_t size, uint64_t base, uint64_t alias, uint64_t a,
                               uint64_t width)
{
    uint64_t o = a - base;
    if (o <= size - width)
        return sram + o;
    o = a - alias;
    if (o <= size - width)
        return sram + o;
    return NULL;
}

/* --- decoding ------------------------------------------------------------------------------- */

static int64_t sext(uint64_t value, int bits)
{
    return (int64_t)(value << (64 - bits)) >> (64 - bits);
}

/* A loaded value of `width` bytes as the load extends it (sign_bits: its sign bit's place + 1; 0: zero-extended). */
static inline uint64_t extend(uint64_t value, uint64_t width, uint32_t sign_bits)
{
    if (width < 8)
        value &= (1ull << (8 * width)) - 1;
    return sign_bits ? (uint64_t)sext(value, (int)sign_bits) : value;
}

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

static uint32_t b_type(int32_t offset, uint32_t rs2, uint32_t rs1, uint32_t f3)
{
    uint32_t o = (uint32_t)offset;
    return ((o >> 12) & 1) << 31 | ((o >> 5) & 0x3F) << 25 | rs2 << 20 | rs1 << 15 | f3 << 12
           | ((o >> 1) & 0xF) << 8 | ((o >> 11) & 1) << 7 | 0x63;
}

static uint32_t j_type(int32_t offset, uint32_t rd)
{
    uint32_t o = (uint32_t)offset;
    return ((o >> 20) & 1) << 31 | ((o >> 1) & 0x3FF) << 21 | ((o >> 11) & 1) << 20 | ((o >> 12) & 0xFF) << 12
           | rd << 7 | 0x6F;
}

/* RVC: the 32-bit instruction a compressed one stands for (unprivileged spec, "C" Standard
 * Extension, RV64 forms); 0 for reserved and illegal encodings and c.ebreak (the precise engine
 * raises their exceptions). */
static uint32_t expand_compressed(uint16_t h)
{
    uint32_t op = h & 3, f3 = h >> 13;
    uint32_t rd = (h >> 7) & 31, rs2 = (h >> 2) & 31;
    uint32_t rdp = 8 + ((h >> 2) & 7), rs1p = 8 + ((h >> 7) & 7);
    int32_t imm6 = (int32_t)sext(((h >> 7) & 0x20) | ((h >> 2) & 0x1F), 6);
    if (op == 0) {
        uint32_t off_w = ((h >> 7) & 0x38) | ((h << 1) & 0x40) | ((h >> 4) & 4);
        uint32_t off_d = ((h >> 7) & 0x38) | ((h << 1) & 0xC0);
        switch (f3) {
        case 0: {   /* c.addi4spn */
            uint32_t nz = ((h >> 7) & 0x30) | ((h >> 1) & 0x3C0) | ((h >> 4) & 4) | ((h >> 2) & 8);
            return nz ? i_type((int32_t)nz, 2, 0, rdp, 0x13) : 0;
        }
        case 1: return i_type((int32_t)off_d, rs1p, 3, rdp, 0x07);   /* c.fld */
        case 2: return i_type((int32_t)off_w, rs1p, 2, rdp, 0x03);   /* c.lw */
        case 3: return i_type((int32_t)off_d, rs1p, 3, rdp, 0x03);   /* c.ld */
        case 5: return s_type(off_d, rdp, rs1p, 3, 0x27);             /* c.fsd */
        case 6: return s_type(off_w, rdp, rs1p, 2, 0x23);             /* c.sw */
        case 7: return s_type(off_d, rdp, rs1p, 3, 0x23);             /* c.sd */
        default: return 0;
        }
    }
    if (op == 1) {
        switch (f3) {
        case 0: return i_type(imm6, rd, 0, rd, 0x13);                  /* c.addi, c.nop */
        case 1: return rd ? i_type(imm6, rd, 0, rd, 0x1B) : 0;        /* c.addiw */
        case 2: return i_type(imm6, 0, 0, rd, 0x13);                   /* c.li */
        case 3:
            if (rd == 2) {                                             /* c.addi16sp */
                int32_t nz = (int32_t)sext(((h >> 3) & 0x200) | ((h >> 2) & 0x10) | ((h << 1) & 0x40)
                                           | ((h << 4) & 0x180) | ((h << 3) & 0x20), 10);
                return nz ? i_type(nz, 2, 0, 2, 0x13) : 0;
            }
            return imm6 ? ((uint32_t)(imm6 << 12) | rd << 7 | 0x37) : 0;   /* c.lui */
        case 4: {
            uint32_t f2 = (h >> 10) & 3;
            uint32_t shamt = ((h >> 7) & 0x20) | ((h >> 2) & 0x1F);
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
        case 5: {                                                                  /* c.j */
            int32_t o = (int32_t)sext(((h >> 1) & 0x800) | ((h >> 7) & 0x10) | ((h >> 1) & 0x300)
                                      | ((h << 2) & 0x400) | ((h >> 1) & 0x40) | ((h << 1) & 0x80)
                                      | ((h >> 2) & 0xE) | ((h << 3) & 0x20), 12);
            return j_type(o, 0);
        }
        default: {                                                                 /* c.beqz, c.bnez */
            int32_t o = (int32_t)sext(((h >> 4) & 0x100) | ((h >> 7) & 0x18) | ((h << 1) & 0xC0)
                                      | ((h >> 2) & 6) | ((h << 3) & 0x20), 9);
            return b_type(o, 0, rs1p, f3 == 6 ? 0 : 1);
        }
        }
    }
    if (op == 2) {
        uint32_t shamt = ((h >> 7) & 0x20) | ((h >> 2) & 0x1F);
        switch (f3) {
        case 0: return i_type((int32_t)shamt, rd, 1, rd, 0x13);                          /* c.slli */
        case 1: return i_type((int32_t)(((h >> 7) & 0x20) | ((h >> 2) & 0x18) | ((h << 4) & 0x1C0)), 2, 3, rd,
                              0x07);                                                     /* c.fldsp */
        case 2: return rd ? i_type((int32_t)(((h >> 7) & 0x20) | ((h >> 2) & 0x1C) | ((h << 4) & 0xC0)), 2, 2, rd,
                                   0x03) : 0;                                            /* c.lwsp */
        case 3: return rd ? i_type((int32_t)(((h >> 7) & 0x20) | ((h >> 2) & 0x18) | ((h << 4) & 0x1C0)), 2, 3,
                                   rd, 0x03) : 0;                                        /* c.ldsp */
        case 4:
            if (!(h & 0x1000)) {
                if (rs2 == 0)
                    return rd ? i_type(0, rd, 0, 0, 0x67) : 0;    /* c.jr */
                return r_type(0, rs2, 0, 0, rd, 0x33);             /* c.mv */
            }
            if (rs2 == 0)
                return rd ? i_type(0, rd, 0, 1, 0x67) : 0;         /* c.jalr; c.ebreak: the precise engine */
            return r_type(0, rs2, rd, 0, rd, 0x33);                /* c.add */
        case 5: return s_type(((h >> 7) & 0x38) | ((h >> 1) & 0x1C0), rs2, 2, 3, 0x27);   /* c.fsdsp */
        case 6: return s_type(((h >> 7) & 0x3C) | ((h >> 1) & 0xC0), rs2, 2, 2, 0x23);    /* c.swsp */
        case 7: return s_type(((h >> 7) & 0x38) | ((h >> 1) & 0x1C0), rs2, 2, 3, 0x23);   /* c.sdsp */
        }
    }
    return 0;
}

static uint16_t decode_op_imm(uint32_t f3, uint32_t w, int wide)
{
    uint32_t top6 = w >> 26, top7 = w >> 25;
    if (wide) {
        switch (f3) {
        case 0: return OP_ADDI;
        case 1: return top6 == 0 ? OP_SLLI : OP_HANDOFF;
        case 2: return OP_SLTI;
        case 3: return OP_SLTIU;
        case 4: return OP_XORI;
        case 5: return top6 == 0 ? OP_SRLI : top6 == 0x10 ? OP_SRAI : OP_HANDOFF;
        case 6: return OP_ORI;
        default: return OP_ANDI;
        }
    }
    switch (f3) {
    case 0: return OP_ADDIW;
    case 1: return top7 == 0 ? OP_SLLIW : OP_HANDOFF;
    case 5: return top7 == 0 ? OP_SRLIW : top7 == 0x20 ? OP_SRAIW : OP_HANDOFF;
    default: return OP_HANDOFF;
    }
}

static uint16_t decode_op(uint32_t f3, uint32_t f7, int wide)
{
    if (f7 == 1) {
        static const uint16_t m64[8] = {OP_MUL, OP_MULH, OP_MULHSU, OP_MULHU, OP_DIV, OP_DIVU, OP_REM, OP_REMU};
        static const uint16_t m32[8] = {OP_MULW, OP_HANDOFF, OP_HANDOFF, OP_HANDOFF, OP_DIVW, OP_DIVUW, OP_REMW,
                                        OP_REMUW};
        return wide ? m64[f3] : m32[f3];
    }
    if (wide) {
        if (f7 == 0) {
            static const uint16_t ops[8] = {OP_ADD, OP_SLL, OP_SLT, OP_SLTU, OP_XOR, OP_SRL, OP_OR, OP_AND};
            return ops[f3];
        }
        if (f7 == 0x20)
            return f3 == 0 ? OP_SUB : f3 == 5 ? OP_SRA : OP_HANDOFF;
        return OP_HANDOFF;
    }
    if (f7 == 0)
        return f3 == 0 ? OP_ADDW : f3 == 1 ? OP_SLLW : f3 == 5 ? OP_SRLW : OP_HANDOFF;
    if (f7 == 0x20)
        return f3 == 0 ? OP_SUBW : f3 == 5 ? OP_SRAW : OP_HANDOFF;
    return OP_HANDOFF;
}

/* OP-FP (0x53): funct7 names the operation and its format (bit 25: double). */
static uint16_t decode_op_fp(uint32_t w)
{
    uint32_t f7 = w >> 25, f3 = (w >> 12) & 7, rs2 = (w >> 20) & 31;
    int d = f7 & 1;
    switch (f7 >> 2) {
    case 0x00: return d ? OP_FADD_D : OP_FADD_S;
    case 0x01: return d ? OP_FSUB_D : OP_FSUB_S;
    case 0x02: return d ? OP_FMUL_D : OP_FMUL_S;
    case 0x03: return d ? OP_FDIV_D : OP_FDIV_S;
    case 0x0B: return rs2 ? OP_HANDOFF : d ? OP_FSQRT_D : OP_FSQRT_S;
    case 0x04:
        if (f3 > 2)
            return OP_HANDOFF;
        return d ? (uint16_t)(OP_FSGNJ_D + f3) : (uint16_t)(OP_FSGNJ_S + f3);
    case 0x05:
        if (f3 > 1)
            return OP_HANDOFF;
        return d ? (f3 ? OP_FMAX_D : OP_FMIN_D) : (f3 ? OP_FMAX_S : OP_FMIN_S);
    case 0x08:   /* fcvt.s.d (f7 0x20), fcvt.d.s (f7 0x21) */
        if (f7 == 0x20 && rs2 == 1)
            return OP_FCVT_S_D;
        if (f7 == 0x21 && rs2 == 0)
            return OP_FCVT_D_S;
        return OP_HANDOFF;
    case 0x14: {
        static const uint16_t s[3] = {OP_FLE_S, OP_FLT_S, OP_FEQ_S}, dd[3] = {OP_FLE_D, OP_FLT_D, OP_FEQ_D};
        if (f3 > 2)
            return OP_HANDOFF;
        return d ? dd[f3] : s[f3];
    }
    case 0x18:
        if (rs2 > 3)
            return OP_HANDOFF;
        return d ? (uint16_t)(OP_FCVT_W_D + rs2) : (uint16_t)(OP_FCVT_W_S + rs2);
    case 0x1A:
        if (rs2 > 3)
            return OP_HANDOFF;
        return d ? (uint16_t)(OP_FCVT_D_W + rs2) : (uint16_t)(OP_FCVT_S_W + rs2);
    case 0x1C:
        if (rs2 != 0)
            return OP_HANDOFF;
        if (f3 == 0)
            return d ? OP_FMV_X_D : OP_FMV_X_W;
        if (f3 == 1)
            return d ? OP_FCLASS_D : OP_FCLASS_S;
        return OP_HANDOFF;
    case 0x1E:
        if (rs2 != 0 || f3 != 0)
            return OP_HANDOFF;
        return d ? OP_FMV_D_X : OP_FMV_W_X;
    default:
        return OP_HANDOFF;
    }
}

/* The OP-FP operations whose result can round into the subnormal range (and so underflow). */
static int rounds_below_normal(uint16_t op)
{
    switch (op) {
    case OP_FADD_S: case OP_FSUB_S: case OP_FMUL_S: case OP_FDIV_S: case OP_FSQRT_S:
    case OP_FADD_D: case OP_FSUB_D: case OP_FMUL_D: case OP_FDIV_D: case OP_FSQRT_D:
    case OP_FCVT_S_D:
        return 1;
    default:
        return 0;
    }
}

static void decode(const insn_counter_t *c, insn_t *in, uint64_t pc, uint32_t fetched)
{
    memset(in, 0, sizeof *in);
    in->pc = pc;
    uint32_t w;
    if ((fetched & 3) != 3) {
        in->len = 2;
        w = expand_compressed((uint16_t)fetched);
    } else {
        in->len = 4;
        w = fetched;
    }
    uint32_t e = table_entry(c, pc);
    in->entry = e;
    in->cost = (uint16_t)(1 + E_EXTRA(e));
    int kind = (int)E_KIND(e);
    if (kind == KIND_MUL || kind == KIND_DIV)
        in->timing |= T_MULDIV;
    else if (kind != KIND_PLAIN)
        in->timing |= T_TRANSFER;
    if (loop_at(c, pc) != NULL)
        in->timing |= T_LOOP_HEAD;
    in->op = OP_HANDOFF;
    if (w == 0)
        return;
    uint32_t opcode = w & 0x7F, f3 = (w >> 12) & 7, f7 = w >> 25;
    uint32_t rd = (w >> 7) & 31;
    in->rd = (uint8_t)rd;
    in->rs1 = (uint8_t)((w >> 15) & 31);
    in->rs2 = (uint8_t)((w >> 20) & 31);
    in->rs3 = (uint8_t)(w >> 27);
    in->rm = (uint8_t)f3;
    int64_t imm_i = sext(w >> 20, 12);
    int64_t imm_s = sext(((w >> 25) << 5) | ((w >> 7) & 31), 12);
    uint16_t op = OP_HANDOFF;
    int writes_x = 0;
    switch (opcode) {
    case 0x37: op = OP_LUI; in->imm = sext(w & 0xFFFFF000u, 32); writes_x = 1; break;
    case 0x17: op = OP_AUIPC; in->imm = sext(w & 0xFFFFF000u, 32); writes_x = 1; break;
    case 0x6F:
        op = OP_JAL;
        in->imm = sext(((w >> 31) << 20) | (((w >> 12) & 0xFF) << 12) | (((w >> 20) & 1) << 11)
                       | (((w >> 21) & 0x3FF) << 1), 21);
        writes_x = 1;
        break;
    case 0x67:
        if (f3 == 0) {
            op = OP_JALR;
            in->imm = imm_i;
            writes_x = 1;
        }
        break;
    case 0x63: {
        static const uint16_t ops[8] = {OP_BEQ, OP_BNE, OP_HANDOFF, OP_HANDOFF, OP_BLT, OP_BGE, OP_BLTU, OP_BGEU};
        op = ops[f3];
        in->imm = sext(((w >> 31) << 12) | (((w >> 7) & 1) << 11) | (((w >> 25) & 0x3F) << 5)
                       | (((w >> 8) & 0xF) << 1), 13);
        break;
    }
    case 0x03: {
        static const uint16_t ops[8] = {OP_LB, OP_LH, OP_LW, OP_LD, OP_LBU, OP_LHU, OP_LWU, OP_HANDOFF};
        op = ops[f3];
        in->imm = imm_i;
        writes_x = 1;
        break;
    }
    case 0x23: {
        static const uint16_t ops[8] = {OP_SB, OP_SH, OP_SW, OP_SD, OP_HANDOFF, OP_HANDOFF, OP_HANDOFF, OP_HANDOFF};
        op = ops[f3];
        in->imm = imm_s;
        break;
    }
    case 0x13:
    case 0x1B:
        op = decode_op_imm(f3, w, opcode == 0x13);
        in->imm = (op == OP_SLLI || op == OP_SRLI || op == OP_SRAI) ? (int64_t)((w >> 20) & 63)
                  : (op == OP_SLLIW || op == OP_SRLIW || op == OP_SRAIW) ? (int64_t)((w >> 20) & 31) : imm_i;
        writes_x = 1;
        break;
    case 0x33:
    case 0x3B:
        op = decode_op(f3, f7, opcode == 0x33);
        writes_x = 1;
        break;
    case 0x73:
        /* a read of mhartid that writes nothing (csrr, csrrs/csrrc with x0 or a zero immediate), at
         * a site the board answers (hart.py finds them in the program; elsewhere the precise engine
         * leaves it to Unicorn, which reads 0): a constant. Every other system instruction and CSR
         * access is the precise engine's */
        if ((w >> 20) == 0xF14 && (f3 == 2 || f3 == 3 || f3 == 6 || f3 == 7) && ((w >> 15) & 31) == 0
                && is_csr_site(c, pc)) {
            op = OP_MHARTID;
            writes_x = 1;
        }
        break;
    case 0x0F:
        if (f3 == 0)
            op = OP_FENCE;   /* one hart's own accesses are in order; fence.i: the precise engine */
        break;
    case 0x07:
        op = f3 == 2 ? OP_FLW : f3 == 3 ? OP_FLD : OP_HANDOFF;
        in->imm = imm_i;
        break;
    case 0x27:
        op = f3 == 2 ? OP_FSW : f3 == 3 ? OP_FSD : OP_HANDOFF;
        in->imm = imm_s;
        break;
    case 0x43: case 0x47: case 0x4B: case 0x4F: {
        uint32_t fmt = (w >> 25) & 3;
        int which = (int)((opcode >> 2) & 3);   /* fmadd, fmsub, fnmsub, fnmadd */
        if (host_tiny_before_rounding())
            break;                              /* they round: see the file's notes */
        if (fmt == 0)
            op = (uint16_t)(OP_FMADD_S + which);
        else if (fmt == 1)
            op = (uint16_t)(OP_FMADD_D + which);
        break;
    }
    case 0x53:
        op = decode_op_fp(w);
        if (rounds_below_normal(op) && host_tiny_before_rounding())
            op = OP_HANDOFF;
        switch (op) {
        case OP_FEQ_S: case OP_FLT_S: case OP_FLE_S: case OP_FCLASS_S: case OP_FMV_X_W:
        case OP_FCVT_W_S: case OP_FCVT_WU_S: case OP_FCVT_L_S: case OP_FCVT_LU_S:
        case OP_FEQ_D: case OP_FLT_D: case OP_FLE_D: case OP_FCLASS_D: case OP_FMV_X_D:
        case OP_FCVT_W_D: case OP_FCVT_WU_D: case OP_FCVT_L_D: case OP_FCVT_LU_D:
            writes_x = 1;
        default:
            break;
        }
        break;
    default:
        break;   /* AMOs, SYSTEM, anything else: the precise engine */
    }
    in->op = op;
    if (writes_x && rd == 0)
        in->rd = 32;
}

/* Conditional branches do not end a block: the way not taken goes on in it (fewer block entries,
 * each of which looks the block up and compares its code). */
static int ends_block(uint16_t op)
{
    return op == OP_HANDOFF || op == OP_JAL || op == OP_JALR;
}

/* Decodes the block at `pc` (its code starts at `code`, `room` bytes before the end of SRAM). */
static block_t *build_block(fast_state_t *f, const insn_counter_t *c, uint64_t pc, const uint8_t *code,
                            uint64_t room)
{
    if (f->blocks_used == BLOCK_ARENA) {
        memset(f->index, 0, sizeof f->index);
        f->blocks_used = 0;
    }
    block_t *b = &f->arena[f->blocks_used++];
    f->blocks_built++;
    b->pc = pc;
    b->checked = f->epoch;
    uint32_t n = 0, offset = 0;
    while (n < BLOCK_MAX && offset + 4 <= room) {
        uint32_t fetched;
        memcpy(&fetched, code + offset, 4);
        insn_t *in = &b->insns[n++];
        decode(c, in, pc + offset, fetched);
        if (c->caches != NULL && (n == 1 || ((pc + offset) >> L1_LINE_SHIFT) != ((in[-1].pc) >> L1_LINE_SHIFT)
                                  || ((pc + offset) >> L1_LINE_SHIFT) != ((pc + offset + in->len - 1) >> L1_LINE_SHIFT)))
            in->timing |= T_FETCH;   /* (Hart.install_caches has the blocks decoded again) */
        offset += in->len;
        if (ends_block(in->op))
            break;
    }
    b->count = n;
    b->bytes = offset;
    if (code < f->code_lo)
        f->code_lo = code;
    if (code + offset > f->code_hi)
        f->code_hi = code + offset;
    memset(b->code, 0, sizeof b->code);
    memcpy(b->code, code, offset);
    insn_t *end = &b->insns[n];
    memset(end, 0, sizeof *end);
    end->op = OP_BLOCK_END;
    end->pc = pc + offset;
    f->index[(pc >> 1) & (BLOCK_INDEX_SLOTS - 1)] = b;
    return b;
}

/* Whether the code at `code` is still what block `b` was decoded from (a word at a time: blocks
 * are a few words long, and memcmp's call and generality cost more than the comparison). */
static inline int same_code(const block_t *b, const uint8_t *code, uint64_t room)
{
    uint32_t n = b->bytes, i = 0;
    for (; i + 8 <= n; i += 8) {
        uint64_t now, then;
        memcpy(&now, code + i, 8);
        memcpy(&then, b->code + i, 8);
        if (now != then)
            return 0;
    }
    if (i < n) {
        uint64_t now = 0, then;
        if (room - i >= 8)
            memcpy(&now, code + i, 8);          /* a fixed-size copy: one load */
        else
            memcpy(&now, code + i, room - i);   /* the block ends by SRAM's end: no reading past it */
        memcpy(&then, b->code + i, 8);
        uint64_t mask = ~0ull >> (64 - 8 * (n - i));
        if ((now ^ then) & mask)
            return 0;
    }
    return 1;
}

/* The decoded block at `pc`, decoding it (again) when needed; NULL for code outside SRAM. */
static inline __attribute__((always_inline)) block_t *block_at(fast_state_t *f, const insn_counter_t *c,
                                                                 uint64_t pc)
{
    uint64_t o = pc - f->base;
    if (o > f->size - 4) {
        o = pc - f->alias;
        if (o > f->size - 4)
            return NULL;   /* code outside SRAM (or its last two bytes) */
    }
    const uint8_t *code = f->sram + o;
    block_t *b = f->index[(pc >> 1) & (BLOCK_INDEX_SLOTS - 1)];
    if (b != NULL && b->pc == pc && (b->checked == f->epoch || same_code(b, code, f->size - o))) {
        b->checked = f->epoch;
        return b;
    }
    return build_block(f, c, pc, code, f->size - o);
}

/* --- floating point ---------------------------------------------------------------------- */

static inline float as_f32(uint64_t v)
{
    uint32_t u = (uint32_t)v;
    float r;
    memcpy(&r, &u, 4);
    return r;
}

static inline double as_f64(uint64_t v)
{
    double r;
    memcpy(&r, &v, 8);
    return r;
}

/* A single-precision result as Unicorn 2.1.4 leaves it in the register: zero-extended; a NaN the
 * canonical one. */
static inline uint64_t from_f32(float r)
{
    uint32_t u;
    memcpy(&u, &r, 4);
    if ((u & 0x7FFFFFFF) > 0x7F800000)
        u = 0x7FC00000;
    return u;
}

static inline uint64_t from_f64(double r)
{
    uint64_t u;
    memcpy(&u, &r, 8);
    if ((u & 0x7FFFFFFFFFFFFFFFull) > 0x7FF0000000000000ull)
        u = 0x7FF8000000000000ull;
    return u;
}

static inline int nan32(uint64_t v)
{
    return ((uint32_t)v & 0x7FFFFFFF) > 0x7F800000;
}

static inline int nan64(uint64_t v)
{
    return (v & 0x7FFFFFFFFFFFFFFFull) > 0x7FF0000000000000ull;
}

/* The RISC-V flags the host's environment has collected. */
static uint64_t flags_from_host(int raised)
{
    uint64_t flags = 0;
    if (raised & FE_INVALID) flags |= FF_NV;
    if (raised & FE_DIVBYZERO) flags |= FF_DZ;
    if (raised & FE_OVERFLOW) flags |= FF_OF;
    if (raised & FE_UNDERFLOW) flags |= FF_UF;
    if (raised & FE_INEXACT) flags |= FF_NX;
    return flags;
}

/* `v` (not a NaN) rounded toward zero to an integral value by clearing its fraction bits: exact, so
 * it raises no host flag. trunc, floor and ceil may raise inexact: GCC expands them inline through
 * cvttsd2si on x86-64 without SSE4.1, and an inexact raised there reached fflags next to the invalid
 * of a conversion out of range (fcvt.wu.s of -0.3 rounding down: NV, not NV and NX). */
static inline double trunc_quietly(double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    int e = (int)((u >> 52) & 0x7FF) - 1023;
    if (e >= 52)
        return v;                                   /* integral already, or an infinity */
    u &= e < 0 ? 1ull << 63 : ~((1ull << (52 - e)) - 1);    /* below 1: a zero of v's sign */
    memcpy(&v, &u, 8);
    return v;
}

/* `v` (not a NaN) rounded to an integral value in rounding mode rm (0 RNE, 1 RTZ, 2 RDN, 3 RUP,
 * 4 RMM), raising no host flag (the caller works out fflags). The integral t is below 2^52 in
 * magnitude where t - 1 or t + 1 is taken: exact. */
static inline double round_integral(double v, int rm)
{
    double t;
    switch (rm) {
    case 0: return nearbyint(v);   /* the host rounds to nearest even; nearbyint raises nothing */
    case 1: return trunc_quietly(v);
    case 2: t = trunc_quietly(v); return t > v ? t - 1.0 : t;
    case 3: t = trunc_quietly(v); return t < v ? t + 1.0 : t;
    default: return round(v);      /* halves away from zero (glibc's round raises nothing) */
    }
}

/* A non-NaN value converted to an integer in [lo, hi_exclusive) with rounding mode rm, saturating
 * and raising invalid out of range, inexact otherwise when the value was not integral (softfloat's
 * rules). The rounding functions and the conversion of an integral value in range raise no host
 * flag, so the flags are worked out here. */
static inline int64_t convert_to_integer(double v, int rm, double lo, double hi_exclusive, int64_t lo_value,
                                         int64_t hi_value, int is_unsigned, uint64_t *flags)
{
    double r = round_integral(v, rm);
    if (r < lo) {
        *flags |= FF_NV;
        return lo_value;
    }
    if (r >= hi_exclusive) {
        *flags |= FF_NV;
        return hi_value;
    }
    if (r != v)
        *flags |= FF_NX;
    return is_unsigned ? (int64_t)(uint64_t)r : (int64_t)r;
}

static uint64_t classify(int sign, int exp_all_ones, int exp_zero, int frac_zero, int quiet)
{
    if (exp_all_ones) {
        if (frac_zero)
            return sign ? 1u << 0 : 1u << 7;
        return quiet ? 1u << 9 : 1u << 8;
    }
    if (exp_zero) {
        if (frac_zero)
            return sign ? 1u << 3 : 1u << 4;
        return sign ? 1u << 2 : 1u << 5;
    }
    return sign ? 1u << 1 : 1u << 6;
}

static uint64_t fclass32(uint64_t v)
{
    uint32_t u = (uint32_t)v, e = (u >> 23) & 0xFF, m = u & 0x7FFFFF;
    return classify((int)(u >> 31), e == 0xFF, e == 0, m == 0, (int)((m >> 22) & 1));
}

static uint64_t fclass64(uint64_t v)
{
    uint64_t e = (v >> 52) & 0x7FF, m = v & 0xFFFFFFFFFFFFFull;
    return classify((int)(v >> 63), e == 0x7FF, e == 0, m == 0, (int)((m >> 51) & 1));
}

/* --- the interpreter --------------------------------------------------------------------- */

static const int x_ids[31] = {
    2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30,
    31, 32};

static void load_state(fast_state_t *f, void *uc)
{
    int ids[31 + 32 + 4];
    void *values[31 + 32 + 4];
    int n = 0;
    for (int i = 0; i < 31; i++) {
        ids[n] = x_ids[i];
        values[n++] = &f->x[i + 1];
    }
    for (int i = 0; i < 32; i++) {
        ids[n] = UC_F0 + i;
        values[n++] = &f->f[i];
    }
    ids[n] = UC_PC; values[n++] = &f->pc;
    ids[n] = UC_MSTATUS; values[n++] = &f->mstatus;
    ids[n] = UC_FFLAGS; values[n++] = &f->fflags;
    ids[n] = UC_FRM; values[n++] = &f->frm;
    f->read_batch(uc, ids, values, n);
    f->x[0] = 0;
}

static void store_state(fast_state_t *f, void *uc, int fp_written, uint64_t old_fflags, uint64_t old_mstatus)
{
    int ids[31 + 32 + 3];
    void *values[31 + 32 + 3];
    int n = 0;
    for (int i = 0; i < 31; i++) {
        ids[n] = x_ids[i];
        values[n++] = &f->x[i + 1];
    }
    if (fp_written) {
        for (int i = 0; i < 32; i++) {
            ids[n] = UC_F0 + i;
            values[n++] = &f->f[i];
        }
    }
    ids[n] = UC_PC; values[n++] = &f->pc;
    if (f->fflags != old_fflags) {
        ids[n] = UC_FFLAGS;
        values[n++] = &f->fflags;
    }
    if (f->mstatus != old_mstatus) {
        ids[n] = UC_MSTATUS;
        values[n++] = &f->mstatus;
    }
    f->write_batch(uc, ids, values, n);
}

/* interpret's bound on `cycles` below which neither limit can be reached (cycles grow at least as fast as
 * the instructions executed) */
static inline uint64_t limit_check(uint64_t executed, uint64_t cycles, uint64_t limit, uint64_t cycle_limit)
{
    if (executed >= limit || cycles >= cycle_limit)
        return cycles;
    /* (no sum that could wrap: the limits may be near 2^64, lifted) */
    return limit - executed < cycle_limit - cycles ? cycles + (limit - executed) : cycle_limit;
}

/*
 * Runs the hart from f->pc (its registers in `f`) until an instruction needs the precise engine
 * (STOP_HANDOFF: f->pc names it, not counted), a device access is left to the caller (STOP_DEVICE:
 * f->pc names it, counted; f->dev describes it) or the counter's limits are reached (STOP_LIMIT; a
 * poll loop's head lowers the limit as count_instruction does). The host's environment collects the
 * floating-point flags meanwhile (the callers set the guest's and collect them: no float arithmetic
 * of the board's own belongs in here).
 */
static int interpret(fast_state_t *f, insn_counter_t *c)
{
    f->epoch++;   /* SRAM may have been written since the last call: code is compared again */
    uint64_t *x = f->x;
    uint64_t *fr = f->f;
    uint64_t pc = f->pc;
    const int fpu_on = (f->mstatus & MSTATUS_FS) != 0;
    uint64_t executed = c->executed, cycles = c->cycles;
    /* the run's stall cycles are what its cycles hold beyond one an instruction and the mispredictions'
     * penalties: worked out once, at the end */
    const uint64_t start_cycles = cycles, start_mispredicts = c->mispredicts;
    const uint64_t cycle_limit = c->cycle_limit;
    uint64_t limit = c->limit;   /* (a poll loop's head or a poll answered here lowers it during the call) */
    /* One comparison an instruction instead of two: while cycles < check, neither limit is reached (every
     * instruction adds one to `executed` and at least one to `cycles`); at check, both are looked at and
     * check moves on. Whatever lowers `limit` sets check = cycles. */
    uint64_t check = limit_check(executed, cycles, limit, cycle_limit);
    uint64_t block_epoch = 0;    /* f->epoch when the current block was entered */
    const uint64_t start = executed;
    int pending_kind = c->pending_kind;
    uint64_t pending_pc = c->pending_pc;
    uint32_t pending_entry = c->pending_entry;
    /* A control transfer is resolved as soon as the instruction after it is sure to start (the limits
     * cannot stop it, and it is the next one either engine counts): its penalty is charged when that
     * instruction is counted, as count_instruction charges it, so every count and limit is as if the
     * transfer had waited for it. The transfer's own handler or the next block's entry resolves it, not
     * each instruction's COUNT (a third of the interpreter's time under --timing rocket went there). */
    uint32_t pending_penalty = c->pending_penalty;
    const uint64_t entry_penalty = pending_penalty;
    l1_caches_t *const kc = c->caches;
    int why;

#define HAND_OVER() do { pc = in->pc; why = STOP_HANDOFF; goto out; } while (0)
/* on to the next instruction of the block; each starts only below the counter's limits (limits_reached) */
#define DISPATCH() do { \
        if (cycles >= check) \
            goto limits_reached; \
        goto *dispatch[in->op]; \
    } while (0)
/* the transfer counted last (its table entry says it is one) waits for where it went */
#define TRANSFER_PENDING() do { \
        if (in->timing & T_TRANSFER) { \
            pending_kind = (int)E_KIND(in->entry); \
            pending_pc = in->pc; \
            pending_entry = in->entry; \
        } \
    } while (0)
/* the transfer at `from` (entry `e`, kind `k`) went to `next`, the `size`-byte instruction that starts next:
 * its misprediction's cycles and the fetch's, due when that instruction is counted */
#define RESOLVE(from, e, k, next, size) do { \
        uint64_t penalty_ = resolve_transfer(c, from, e, k, next); \
        pending_penalty = (uint32_t)(penalty_ + redirect_bubble(c, from, e, k, next, size, penalty_)); \
    } while (0)
#define RESOLVE_PENDING(next, size) do { \
        RESOLVE(pending_pc, pending_entry, pending_kind, next, size); \
        pending_kind = 0; \
    } while (0)
#define NEXT() do { in++; DISPATCH(); } while (0)
/* the rounding mode an FP instruction uses (7: frm's) */
#define RM() ((in->rm == 7) ? (int)f->frm : (int)in->rm)
#define NEED_FPU() do { if (!fpu_on) HAND_OVER(); } while (0)
#define NEED_RNE() do { if (!fpu_on || RM() != 0) HAND_OVER(); } while (0)
#define NEED_VALID_RM() do { if (!fpu_on || RM() > 4) HAND_OVER(); } while (0)
/* Counts and times the instruction exactly as count_instruction does, its operands still unwritten; the
 * timing flags in `handled` are the handler's own business (a transfer's: TRANSFER_PENDING). */
#define COUNT_BUT(handled) do { \
        executed++; \
        cycles += in->cost; \
        if (pending_penalty) { \
            cycles += pending_penalty; \
            pending_penalty = 0; \
        } \
        if (in->timing & ~(handled)) { \
            uint32_t e = in->entry; \
            if (in->timing & T_FETCH) \
                cycles += l1_fetch_insn(kc, table_key(in->pc), in->len); \
            if (in->timing & T_MULDIV) { \
                uint64_t latency = muldiv_latency(e, x[E_RS1(e)], x[E_RS2(e)], E_KIND(e) == KIND_DIV); \
                uint64_t distance = E_DIST(e); \
                cycles += latency > distance ? latency - distance : 0; \
            } else if (in->timing & ~(handled) & T_TRANSFER) { \
                /* (the table calls an instruction that is no jump a transfer: code written since it was \
                 * made) resolved where the next instruction starts: limits_reached */ \
                pending_kind = (int)E_KIND(e); \
                pending_pc = in->pc; \
                pending_entry = e; \
                check = cycles; \
            } \
            if (in->timing & T_LOOP_HEAD) { \
                poll_loop_t *loop = loop_at(c, in->pc); \
                if (!loop->ignore && executed - loop->last == loop->body && c->poll_report == 0) { \
                    c->poll_report = in->pc; \
                    c->limit = limit = executed; \
                    check = cycles; \
                } \
                loop->last = executed; \
            } \
        } \
    } while (0)
#define COUNT() COUNT_BUT(0)
/* an SRAM access through the data cache (_caches.h) */
#define CACHED(a, storing) do { if (kc != NULL) cycles += l1_data(kc, a, storing); } while (0)
/* a store into decoded code: its blocks are compared with their code again at their next entry */
#define WROTE(h, width) do { if ((h) < f->code_hi && (h) + (width) > f->code_lo) f->epoch++; } while (0)
/* --check-writes: the first store outside the hart's buffers is recorded (it has landed, as with the precise
 * engine's hook), and the hart stops before its next instruction */
#define WATCHED(a, h, width) do { \
        write_watch_t *watch_ = f->write_watch; \
        if (watch_ != NULL && !watch_->stray) { \
            uint64_t region_, next_; \
            if (write_check_strays(watch_, (uint64_t)((h) - sram), width, &region_, &next_)) { \
                write_check_record(watch_, a, width, in->pc, region_, next_); \
                c->limit = limit = executed; \
                check = cycles; \
            } \
        } \
    } while (0)
/* an aligned access in a device window: counted, described in f->dev, left to the caller */
#define DEVICE(nbytes, storing, stored, dest_reg, sign_from) do { \
        if ((a & (nbytes - 1)) == 0 && f->devices_here) { \
            int w = device_window(f, a, nbytes); \
            if (w >= 0) { \
                COUNT(); \
                CACHED(a, storing); \
                if (!(storing) && f->rep.armed && in->pc == f->rep.pc && a == f->rep.address \
                        && nbytes == f->rep.width && cycles < f->rep.until) { \
                    f->rep.answered++; \
                    if (++f->rep.repeats >= f->rep.needed) { \
                        f->rep.polling = 1;   /* note_poll: the hart polls; its turn ends here */ \
                        f->rep.repeats = 0; \
                        if (executed < limit) { \
                            c->limit = limit = executed; \
                            check = cycles; \
                        } \
                    } \
                    x[dest_reg] = extend(f->rep.value, nbytes, sign_from); \
                    NEXT(); \
                } \
                f->dev.address = a; \
                f->dev.value = (stored); \
                f->dev.next_pc = in->pc + in->len; \
                f->dev.width = nbytes; \
                f->dev.is_store = storing; \
                f->dev.window = (uint32_t)w; \
                f->dev.rd = dest_reg; \
                f->dev.sign_bits = sign_from; \
                pc = in->pc; \
                why = STOP_DEVICE; \
                goto out; \
            } \
        } \
        HAND_OVER(); \
    } while (0)
#define XLOAD(type, width, sign) do { \
        uint64_t a = x[in->rs1] + (uint64_t)in->imm; \
        uint8_t *h = sram_at(sram, size, base, alias, a, width); \
        if (h == NULL || (a & (width - 1))) { \
            if (h == NULL) DEVICE(width, 0, 0, in->rd, sign); \
            HAND_OVER(); \
        } \
        COUNT(); \
        CACHED(a, 0); \
        type v; \
        memcpy(&v, h, width); \
        x[in->rd] = (uint64_t)v; \
        NEXT(); \
    } while (0)
#define XSTORE(width) do { \
        uint64_t a = x[in->rs1] + (uint64_t)in->imm; \
        uint8_t *h = sram_at(sram, size, base, alias, a, width); \
        if (h == NULL || (a & (width - 1))) { \
            if (h == NULL) DEVICE(width, 1, x[in->rs2], 0, 0); \
            HAND_OVER(); \
        } \
        COUNT(); \
        CACHED(a, 1); \
        uint64_t v = x[in->rs2]; \
        memcpy(h, &v, width); \
        WROTE(h, width); \
        WATCHED(a, h, width); \
        NEXT(); \
    } while (0)
#define LOAD(type, width, dest) do { \
        uint64_t a = x[in->rs1] + (uint64_t)in->imm; \
        uint8_t *h = sram_at(sram, size, base, alias, a, width); \
        if (h == NULL || (a & (width - 1))) HAND_OVER(); \
        COUNT(); \
        CACHED(a, 0); \
        type v; \
        memcpy(&v, h, width); \
        dest; \
        NEXT(); \
    } while (0)
#define STORE(width, value) do { \
        uint64_t a = x[in->rs1] + (uint64_t)in->imm; \
        uint8_t *h = sram_at(sram, size, base, alias, a, width); \
        if (h == NULL || (a & (width - 1))) HAND_OVER(); \
        COUNT(); \
        CACHED(a, 1); \
        uint64_t v = (value); \
        memcpy(h, &v, width); \
        WROTE(h, width); \
        WATCHED(a, h, width); \
        NEXT(); \
    } while (0)
/* not taken: on in the block, unless the interpreter stored into decoded code since the block began
 * (QEMU ends its translated blocks at branches, so the code after one runs as it is now) */
#define BRANCH(cond) do { \
        COUNT_BUT(T_TRANSFER); \
        if (cond) { \
            pc = in->pc + (uint64_t)in->imm; \
            TRANSFER_PENDING(); \
            goto next_block; \
        } \
        if (f->epoch != block_epoch) { \
            pc = in->pc + in->len; \
            TRANSFER_PENDING(); \
            goto next_block; \
        } \
        if (in->timing & T_TRANSFER) { \
            /* the next instruction, in this block, starts unless the limits stop it first */ \
            if (cycles < check && in[1].op != OP_BLOCK_END) \
                RESOLVE(in->pc, in->entry, (int)E_KIND(in->entry), in->pc + in->len, in[1].len); \
            else \
                TRANSFER_PENDING(); \
        } \
        NEXT(); \
    } while (0)
#define ALU(expr) do { COUNT(); x[in->rd] = (expr); NEXT(); } while (0)
#define W(expr) ((uint64_t)(int64_t)(int32_t)(uint32_t)(expr))
/* single precision: operands must not be NaNs (the precise engine has QEMU's NaN rules) */
#define S1 as_f32(fr[in->rs1])
#define S2 as_f32(fr[in->rs2])
#define S3 as_f32(fr[in->rs3])
#define D1 as_f64(fr[in->rs1])
#define D2 as_f64(fr[in->rs2])
#define D3 as_f64(fr[in->rs3])
#define NO_NAN_S2() do { if (nan32(fr[in->rs1]) || nan32(fr[in->rs2])) HAND_OVER(); } while (0)
#define NO_NAN_S3() do { if (nan32(fr[in->rs1]) || nan32(fr[in->rs2]) || nan32(fr[in->rs3])) HAND_OVER(); } while (0)
#define NO_NAN_D2() do { if (nan64(fr[in->rs1]) || nan64(fr[in->rs2])) HAND_OVER(); } while (0)
#define NO_NAN_D3() do { if (nan64(fr[in->rs1]) || nan64(fr[in->rs2]) || nan64(fr[in->rs3])) HAND_OVER(); } while (0)
#define FRES(expr) do { COUNT(); fr[in->rd] = (expr); f->fp_written = 1; NEXT(); } while (0)
#define XRES(expr) do { COUNT(); x[in->rd] = (expr); NEXT(); } while (0)

#define OP_LABEL(name) &&L_OP_##name,
    static const void *const dispatch[OP_COUNT] = { OPERATIONS(OP_LABEL) };
#undef OP_LABEL
    const uint64_t base = f->base, alias = f->alias, size = f->size;
    uint8_t *const sram = f->sram;
    insn_t *in;
next_block:
    block_epoch = f->epoch;
    {
        block_t *b = block_at(f, c, pc);
        if (b == NULL) {
            why = STOP_HANDOFF;   /* code outside SRAM: the precise engine decides what happens */
            goto out;
        }
        in = b->insns;
    }
    if (pending_kind && cycles < check)
        RESOLVE_PENDING(pc, in->len);
    DISPATCH();
limits_reached:
    /* cycles >= check: a limit may be reached before the instruction at `in` */
    if (executed >= limit || cycles >= cycle_limit) {
        pc = in->pc;
        why = STOP_LIMIT;
        goto out;
    }
    check = limit_check(executed, cycles, limit, cycle_limit);
    if (pending_kind && in->op != OP_BLOCK_END)
        RESOLVE_PENDING(in->pc, in->len);   /* (a block's end: next_block resolves it, the next block found) */
    goto *dispatch[in->op];
    {
        L_OP_BLOCK_END:
            pc = in->pc;
            goto next_block;
        L_OP_MHARTID: ALU(f->hart_id);
        L_OP_LUI: ALU((uint64_t)in->imm);
        L_OP_AUIPC: ALU(in->pc + (uint64_t)in->imm);
        L_OP_JAL: {
            COUNT_BUT(T_TRANSFER);
            x[in->rd] = in->pc + in->len;
            pc = in->pc + (uint64_t)in->imm;
            TRANSFER_PENDING();
            goto next_block;
        }
        L_OP_JALR: {
            COUNT_BUT(T_TRANSFER);
            uint64_t target = (x[in->rs1] + (uint64_t)in->imm) & ~(uint64_t)1;
            x[in->rd] = in->pc + in->len;
            pc = target;
            TRANSFER_PENDING();
            goto next_block;
        }
        L_OP_BEQ: BRANCH(x[in->rs1] == x[in->rs2]);
        L_OP_BNE: BRANCH(x[in->rs1] != x[in->rs2]);
        L_OP_BLT: BRANCH((int64_t)x[in->rs1] < (int64_t)x[in->rs2]);
        L_OP_BGE: BRANCH((int64_t)x[in->rs1] >= (int64_t)x[in->rs2]);
        L_OP_BLTU: BRANCH(x[in->rs1] < x[in->rs2]);
        L_OP_BGEU: BRANCH(x[in->rs1] >= x[in->rs2]);
        L_OP_LB: XLOAD(int8_t, 1, 8);
        L_OP_LH: XLOAD(int16_t, 2, 16);
        L_OP_LW: XLOAD(int32_t, 4, 32);
        L_OP_LD: XLOAD(uint64_t, 8, 0);
        L_OP_LBU: XLOAD(uint8_t, 1, 0);
        L_OP_LHU: XLOAD(uint16_t, 2, 0);
        L_OP_LWU: XLOAD(uint32_t, 4, 0);
        L_OP_SB: XSTORE(1);
        L_OP_SH: XSTORE(2);
        L_OP_SW: XSTORE(4);
        L_OP_SD: XSTORE(8);
        L_OP_ADDI: ALU(x[in->rs1] + (uint64_t)in->imm);
        L_OP_SLTI: ALU((int64_t)x[in->rs1] < in->imm);
        L_OP_SLTIU: ALU(x[in->rs1] < (uint64_t)in->imm);
        L_OP_XORI: ALU(x[in->rs1] ^ (uint64_t)in->imm);
        L_OP_ORI: ALU(x[in->rs1] | (uint64_t)in->imm);
        L_OP_ANDI: ALU(x[in->rs1] & (uint64_t)in->imm);
        L_OP_SLLI: ALU(x[in->rs1] << in->imm);
        L_OP_SRLI: ALU(x[in->rs1] >> in->imm);
        L_OP_SRAI: ALU((uint64_t)((int64_t)x[in->rs1] >> in->imm));
        L_OP_ADD: ALU(x[in->rs1] + x[in->rs2]);
        L_OP_SUB: ALU(x[in->rs1] - x[in->rs2]);
        L_OP_SLL: ALU(x[in->rs1] << (x[in->rs2] & 63));
        L_OP_SLT: ALU((int64_t)x[in->rs1] < (int64_t)x[in->rs2]);
        L_OP_SLTU: ALU(x[in->rs1] < x[in->rs2]);
        L_OP_XOR: ALU(x[in->rs1] ^ x[in->rs2]);
        L_OP_SRL: ALU(x[in->rs1] >> (x[in->rs2] & 63));
        L_OP_SRA: ALU((uint64_t)((int64_t)x[in->rs1] >> (x[in->rs2] & 63)));
        L_OP_OR: ALU(x[in->rs1] | x[in->rs2]);
        L_OP_AND: ALU(x[in->rs1] & x[in->rs2]);
        L_OP_ADDIW: ALU(W(x[in->rs1] + (uint64_t)in->imm));
        L_OP_SLLIW: ALU(W((uint32_t)x[in->rs1] << in->imm));
        L_OP_SRLIW: ALU(W((uint32_t)x[in->rs1] >> in->imm));
        L_OP_SRAIW: ALU(W((int32_t)x[in->rs1] >> in->imm));
        L_OP_ADDW: ALU(W(x[in->rs1] + x[in->rs2]));
        L_OP_SUBW: ALU(W(x[in->rs1] - x[in->rs2]));
        L_OP_SLLW: ALU(W((uint32_t)x[in->rs1] << (x[in->rs2] & 31)));
        L_OP_SRLW: ALU(W((uint32_t)x[in->rs1] >> (x[in->rs2] & 31)));
        L_OP_SRAW: ALU(W((int32_t)x[in->rs1] >> (x[in->rs2] & 31)));
        L_OP_MUL: ALU(x[in->rs1] * x[in->rs2]);
        L_OP_MULH: ALU((uint64_t)(((__int128)(int64_t)x[in->rs1] * (__int128)(int64_t)x[in->rs2]) >> 64));
        L_OP_MULHSU:
            ALU((uint64_t)(((__int128)(int64_t)x[in->rs1] * (__int128)(unsigned __int128)x[in->rs2]) >> 64));
        L_OP_MULHU: ALU((uint64_t)(((unsigned __int128)x[in->rs1] * (unsigned __int128)x[in->rs2]) >> 64));
        L_OP_DIV: {
            int64_t a = (int64_t)x[in->rs1], b = (int64_t)x[in->rs2];
            ALU(b == 0 ? UINT64_MAX : (a == INT64_MIN && b == -1) ? (uint64_t)a : (uint64_t)(a / b));
        }
        L_OP_DIVU: {
            uint64_t a = x[in->rs1], b = x[in->rs2];
            ALU(b == 0 ? UINT64_MAX : a / b);
        }
        L_OP_REM: {
            int64_t a = (int64_t)x[in->rs1], b = (int64_t)x[in->rs2];
            ALU(b == 0 ? (uint64_t)a : (a == INT64_MIN && b == -1) ? 0 : (uint64_t)(a % b));
        }
        L_OP_REMU: {
            uint64_t a = x[in->rs1], b = x[in->rs2];
            ALU(b == 0 ? a : a % b);
        }
        L_OP_MULW: ALU(W((uint32_t)x[in->rs1] * (uint32_t)x[in->rs2]));
        L_OP_DIVW: {
            int32_t a = (int32_t)x[in->rs1], b = (int32_t)x[in->rs2];
            ALU(b == 0 ? UINT64_MAX : (a == INT32_MIN && b == -1) ? W(a) : W(a / b));
        }
        L_OP_DIVUW: {
            uint32_t a = (uint32_t)x[in->rs1], b = (uint32_t)x[in->rs2];
            ALU(b == 0 ? UINT64_MAX : W(a / b));
        }
        L_OP_REMW: {
            int32_t a = (int32_t)x[in->rs1], b = (int32_t)x[in->rs2];
            ALU(b == 0 ? W(a) : (a == INT32_MIN && b == -1) ? 0 : W(a % b));
        }
        L_OP_REMUW: {
            uint32_t a = (uint32_t)x[in->rs1], b = (uint32_t)x[in->rs2];
            ALU(b == 0 ? W(a) : W(a % b));
        }
        L_OP_FENCE: COUNT(); NEXT();

        /* --- floating point --- */
        L_OP_FLW: NEED_FPU(); LOAD(uint32_t, 4, (fr[in->rd] = 0xFFFFFFFF00000000ull | v, f->fp_written = 1));
        L_OP_FLD: NEED_FPU(); LOAD(uint64_t, 8, (fr[in->rd] = v, f->fp_written = 1));
        L_OP_FSW: NEED_FPU(); STORE(4, fr[in->rs2]);
        L_OP_FSD: NEED_FPU(); STORE(8, fr[in->rs2]);

        L_OP_FADD_S: NEED_RNE(); NO_NAN_S2(); FRES(from_f32(S1 + S2));
        L_OP_FSUB_S: NEED_RNE(); NO_NAN_S2(); FRES(from_f32(S1 - S2));
        L_OP_FMUL_S: NEED_RNE(); NO_NAN_S2(); FRES(from_f32(S1 * S2));
        L_OP_FDIV_S: NEED_RNE(); NO_NAN_S2(); FRES(from_f32(S1 / S2));
        L_OP_FSQRT_S: NEED_RNE(); if (nan32(fr[in->rs1])) HAND_OVER(); FRES(from_f32(sqrtf(S1)));
        L_OP_FMADD_S: NEED_RNE(); NO_NAN_S3(); FRES(from_f32(fmaf(S1, S2, S3)));
        L_OP_FMSUB_S: NEED_RNE(); NO_NAN_S3(); FRES(from_f32(fmaf(S1, S2, -S3)));
        L_OP_FNMSUB_S: NEED_RNE(); NO_NAN_S3(); FRES(from_f32(fmaf(-S1, S2, S3)));
        L_OP_FNMADD_S: NEED_RNE(); NO_NAN_S3(); FRES(from_f32(fmaf(-S1, S2, -S3)));
        /* QEMU 5.0's sign injections work on the whole register: bits 31..63 from rs2 */
        L_OP_FSGNJ_S: NEED_FPU(); FRES((fr[in->rs2] & ~0x7FFFFFFFull) | (fr[in->rs1] & 0x7FFFFFFFull));
        L_OP_FSGNJN_S: NEED_FPU(); FRES((~fr[in->rs2] & ~0x7FFFFFFFull) | (fr[in->rs1] & 0x7FFFFFFFull));
        L_OP_FSGNJX_S: NEED_FPU(); FRES(fr[in->rs1] ^ (fr[in->rs2] & ~0x7FFFFFFFull));
        L_OP_FMIN_S: {
            NEED_FPU(); NO_NAN_S2();
            float a = S1, b = S2;
            FRES(from_f32((a < b || (a == b && signbit(a))) ? a : b));
        }
        L_OP_FMAX_S: {
            NEED_FPU(); NO_NAN_S2();
            float a = S1, b = S2;
            FRES(from_f32((a > b || (a == b && !signbit(a))) ? a : b));
        }
        L_OP_FEQ_S: NEED_FPU(); NO_NAN_S2(); XRES(S1 == S2);
        L_OP_FLT_S: NEED_FPU(); NO_NAN_S2(); XRES(S1 < S2);
        L_OP_FLE_S: NEED_FPU(); NO_NAN_S2(); XRES(S1 <= S2);
        L_OP_FCLASS_S: NEED_FPU(); XRES(fclass32(fr[in->rs1]));
        L_OP_FMV_X_W: NEED_FPU(); XRES(W(fr[in->rs1]));
        L_OP_FMV_W_X: NEED_FPU(); FRES(x[in->rs1]);   /* QEMU 5.0 on RV64: the whole register */
        L_OP_FCVT_W_S: NEED_VALID_RM(); if (nan32(fr[in->rs1])) HAND_OVER();
            XRES(W(convert_to_integer(S1, RM(), -2147483648.0, 2147483648.0, INT32_MIN, INT32_MAX, 0, &f->soft_flags)));
        L_OP_FCVT_WU_S: NEED_VALID_RM(); if (nan32(fr[in->rs1])) HAND_OVER();
            XRES(W(convert_to_integer(S1, RM(), 0.0, 4294967296.0, 0, UINT32_MAX, 1, &f->soft_flags)));
        L_OP_FCVT_L_S: NEED_VALID_RM(); if (nan32(fr[in->rs1])) HAND_OVER();
            XRES((uint64_t)convert_to_integer(S1, RM(), -0x1p63, 0x1p63, INT64_MIN, INT64_MAX, 0, &f->soft_flags));
        L_OP_FCVT_LU_S: NEED_VALID_RM(); if (nan32(fr[in->rs1])) HAND_OVER();
            XRES((uint64_t)convert_to_integer(S1, RM(), 0.0, 0x1p64, 0, (int64_t)UINT64_MAX, 1, &f->soft_flags));
        L_OP_FCVT_S_W: NEED_RNE(); FRES(from_f32((float)(int32_t)x[in->rs1]));
        L_OP_FCVT_S_WU: NEED_RNE(); FRES(from_f32((float)(uint32_t)x[in->rs1]));
        L_OP_FCVT_S_L: NEED_RNE(); FRES(from_f32((float)(int64_t)x[in->rs1]));
        L_OP_FCVT_S_LU: NEED_RNE(); FRES(from_f32((float)x[in->rs1]));

        L_OP_FADD_D: NEED_RNE(); NO_NAN_D2(); FRES(from_f64(D1 + D2));
        L_OP_FSUB_D: NEED_RNE(); NO_NAN_D2(); FRES(from_f64(D1 - D2));
        L_OP_FMUL_D: NEED_RNE(); NO_NAN_D2(); FRES(from_f64(D1 * D2));
        L_OP_FDIV_D: NEED_RNE(); NO_NAN_D2(); FRES(from_f64(D1 / D2));
        L_OP_FSQRT_D: NEED_RNE(); if (nan64(fr[in->rs1])) HAND_OVER(); FRES(from_f64(sqrt(D1)));
        L_OP_FMADD_D: NEED_RNE(); NO_NAN_D3(); FRES(from_f64(fma(D1, D2, D3)));
        L_OP_FMSUB_D: NEED_RNE(); NO_NAN_D3(); FRES(from_f64(fma(D1, D2, -D3)));
        L_OP_FNMSUB_D: NEED_RNE(); NO_NAN_D3(); FRES(from_f64(fma(-D1, D2, D3)));
        L_OP_FNMADD_D: NEED_RNE(); NO_NAN_D3(); FRES(from_f64(fma(-D1, D2, -D3)));
        L_OP_FSGNJ_D: NEED_FPU(); FRES((fr[in->rs2] & (1ull << 63)) | (fr[in->rs1] & ~(1ull << 63)));
        L_OP_FSGNJN_D: NEED_FPU(); FRES((~fr[in->rs2] & (1ull << 63)) | (fr[in->rs1] & ~(1ull << 63)));
        L_OP_FSGNJX_D: NEED_FPU(); FRES(fr[in->rs1] ^ (fr[in->rs2] & (1ull << 63)));
        L_OP_FMIN_D: {
            NEED_FPU(); NO_NAN_D2();
            double a = D1, b = D2;
            FRES(from_f64((a < b || (a == b && signbit(a))) ? a : b));
        }
        L_OP_FMAX_D: {
            NEED_FPU(); NO_NAN_D2();
            double a = D1, b = D2;
            FRES(from_f64((a > b || (a == b && !signbit(a))) ? a : b));
        }
        L_OP_FEQ_D: NEED_FPU(); NO_NAN_D2(); XRES(D1 == D2);
        L_OP_FLT_D: NEED_FPU(); NO_NAN_D2(); XRES(D1 < D2);
        L_OP_FLE_D: NEED_FPU(); NO_NAN_D2(); XRES(D1 <= D2);
        L_OP_FCLASS_D: NEED_FPU(); XRES(fclass64(fr[in->rs1]));
        L_OP_FMV_X_D: NEED_FPU(); XRES(fr[in->rs1]);
        L_OP_FMV_D_X: NEED_FPU(); FRES(x[in->rs1]);
        L_OP_FCVT_W_D: NEED_VALID_RM(); if (nan64(fr[in->rs1])) HAND_OVER();
            XRES(W(convert_to_integer(D1, RM(), -2147483648.0, 2147483648.0, INT32_MIN, INT32_MAX, 0, &f->soft_flags)));
        L_OP_FCVT_WU_D: NEED_VALID_RM(); if (nan64(fr[in->rs1])) HAND_OVER();
            XRES(W(convert_to_integer(D1, RM(), 0.0, 4294967296.0, 0, UINT32_MAX, 1, &f->soft_flags)));
        L_OP_FCVT_L_D: NEED_VALID_RM(); if (nan64(fr[in->rs1])) HAND_OVER();
            XRES((uint64_t)convert_to_integer(D1, RM(), -0x1p63, 0x1p63, INT64_MIN, INT64_MAX, 0, &f->soft_flags));
        L_OP_FCVT_LU_D: NEED_VALID_RM(); if (nan64(fr[in->rs1])) HAND_OVER();
            XRES((uint64_t)convert_to_integer(D1, RM(), 0.0, 0x1p64, 0, (int64_t)UINT64_MAX, 1, &f->soft_flags));
        L_OP_FCVT_D_W: NEED_RNE(); FRES(from_f64((double)(int32_t)x[in->rs1]));
        L_OP_FCVT_D_WU: NEED_RNE(); FRES(from_f64((double)(uint32_t)x[in->rs1]));
        L_OP_FCVT_D_L: NEED_RNE(); FRES(from_f64((double)(int64_t)x[in->rs1]));
        L_OP_FCVT_D_LU: NEED_RNE(); FRES(from_f64((double)x[in->rs1]));
        L_OP_FCVT_S_D: NEED_RNE(); if (nan64(fr[in->rs1])) HAND_OVER(); FRES(from_f32((float)D1));
        L_OP_FCVT_D_S: NEED_VALID_RM(); if (nan32(fr[in->rs1])) HAND_OVER(); FRES(from_f64((double)S1));
        L_OP_HANDOFF:
            HAND_OVER();
    }
out:
    f->pc = pc;
    f->instructions += executed - start;
    if (why == STOP_HANDOFF)
        f->handoffs++;
    c->executed = executed;
    c->cycles = cycles;
    c->pending_kind = pending_kind;
    c->pending_pc = pending_pc;
    c->pending_entry = pending_entry;
    c->pending_penalty = pending_penalty;
    /* (a penalty carried in was a misprediction of an earlier run; one carried out is this run's) */
    c->stall_cycles += (cycles + pending_penalty - entry_penalty - start_cycles) - (executed - start) -
                       MISPREDICT_PENALTY * (c->mispredicts - start_mispredicts);
    if (executed != start)
        c->last_pc = 0;   /* the precise engine's last instruction is no longer the hart's last */
    return why;
#undef HAND_OVER
#undef NEXT
#undef RM
#undef NEED_FPU
#undef NEED_RNE
#undef NEED_VALID_RM
#undef COUNT
#undef COUNT_BUT
#undef TRANSFER_PENDING
#undef RESOLVE_PENDING
#undef RESOLVE
#undef CACHED
#undef LOAD
#undef STORE
#undef DEVICE
#undef WROTE
#undef XLOAD
#undef XSTORE
#undef BRANCH
#undef ALU
#undef W
#undef FRES
#undef XRES
}

/* The guest's environment in place of the host's, and back: the flags the guest raised meanwhile
 * are kept, so that Python running between (a device access) adds none. */
static void enter_guest_fp(fast_state_t *f)
{
    fegetenv(&f->host_env);
    fesetenv(FE_DFL_ENV);
}

static void leave_guest_fp(fast_state_t *f)
{
    f->soft_flags |= flags_from_host(fetestexcept(FE_ALL_EXCEPT));
    fesetenv(&f->host_env);
}

/* Before the interpreter runs: the hart's registers from the precise engine. */
static void begin_run(fast_state_t *f, void *uc, uint64_t from)
{
    load_state(f, uc);
    f->pc = from;
    f->fp_written = 0;
    f->soft_flags = 0;
    f->entry_fflags = f->fflags;
    f->entry_mstatus = f->mstatus;
}

/* After it: the flags it raised into fflags, the FPU state dirty if it wrote an FP register (as QEMU
 * marks it), the registers back to the precise engine. */
static void end_run(fast_state_t *f, void *uc)
{
    f->fflags |= f->soft_flags;
    if (f->fp_written && (f->mstatus & MSTATUS_FS) != MSTATUS_FS)
        f->mstatus |= MSTATUS_FS | MSTATUS_SD;
    store_state(f, uc, f->fp_written, f->entry_fflags, f->entry_mstatus);
}

/* Interprets from f->pc; a stop other than at a device access ends the run. */
static int interpret_on(fast_state_t *f, insn_counter_t *c, void *uc)
{
    enter_guest_fp(f);
    int why = interpret(f, c);
    leave_guest_fp(f);
    if (why != STOP_DEVICE)
        end_run(f, uc);
    return why;
}

/*
 * Runs the hart whose precise engine is `uc` from `from` until an instruction needs the precise
 * engine (STOP_HANDOFF: the instruction is not counted), the counter's limits are reached
 * (STOP_LIMIT; a poll loop's head lowers the limit as count_instruction does), or a device access
 * (STOP_DEVICE). The registers are read from `uc` first; they are written back, the pc too (f->pc),
 * when the run ends: at a device access it has not ended, and the caller carries the access out and
 * calls fast_resume (or fast_abandon). Python reaches both through fast_step (_insn_counter.c).
 */
static int fast_run(fast_state_t *f, insn_counter_t *c, void *uc, uint64_t from)
{
    begin_run(f, uc, from);
    f->devices_here = f->windows != 0;
    f->rep.armed = 0;
    return interpret_on(f, c, uc);
}

/* After STOP_DEVICE: completes the access (a load's `value`, as the instruction extends it, into its
 * register) and goes on as fast_run does. */
static int fast_resume(fast_state_t *f, insn_counter_t *c, void *uc, uint64_t value)
{
    device_access_t *d = &f->dev;
    if (!d->is_store)
        f->x[d->rd] = extend(value, d->width, d->sign_bits);
    f->pc = d->next_pc;
    return interpret_on(f, c, uc);
}

/* (_fast_engine.h) */
int fast_step(fast_state_t *f, insn_counter_t *c, void *uc, uint64_t arg, int resume, uint64_t out[6])
{
    int why = resume ? fast_resume(f, c, uc, arg) : fast_run(f, c, uc, arg);
    if (why == STOP_DEVICE) {
        out[0] = f->dev.window;
        out[1] = f->dev.address;
        out[2] = f->dev.width;
        out[3] = f->dev.is_store;
        out[4] = f->dev.value;
        out[5] = f->pc;
    }
    return why;
}

/* After STOP_DEVICE: ends the run with the access not carried out (it trapped, or the board failed):
 * the registers back to the precise engine, the pc at the access. */
__attribute__((visibility("default")))
void fast_abandon(fast_state_t *f, void *uc)
{
    end_run(f, uc);
}

/* (_fast_engine.h) */
void fast_begin_turns(fast_state_t *f, void *uc, uint64_t from)
{
    begin_run(f, uc, from);
    f->devices_here = 0;   /* a device access ends the turns: the scheduler finishes that turn */
}

int fast_turn(fast_state_t *f, insn_counter_t *c)
{
    enter_guest_fp(f);   /* (the interpreter's host arithmetic must not raise the guest's flags) */
    int why = interpret(f, c);
    leave_guest_fp(f);
    return why;
}

int fast_wrote_astray(const fast_state_t *f)
{
    return f->write_watch != NULL && f->write_watch->stray;
}

uint64_t fast_end_turns(fast_state_t *f, void *uc)
{
    end_run(f, uc);
    return f->pc;
}

/* The sizes of the structures native.py mirrors for ctypes (tests/unit/cpu/test_native_layout.py checks the
 * mirrors against them and against the field names here): predictor_t, insn_counter_t,
 * device_access_t, repeat_t, fast_state_t up to `windows` (the head Python reads), alone_plan_t, pair_plan_t,
 * and the caches' l1_cache_t and l1_caches_t. */
__attribute__((visibility("default")))
void struct_sizes_for_tests(uint64_t out[9])
{
    out[6] = sizeof(l1_cache_t);
    out[7] = sizeof(l1_caches_t);
    out[0] = sizeof(predictor_t);
    out[1] = sizeof(insn_counter_t);
    out[2] = sizeof(device_access_t);
    out[3] = sizeof(repeat_t);
    out[4] = offsetof(fast_state_t, windows);
    out[5] = sizeof(alone_plan_t);
    out[8] = sizeof(pair_plan_t);
}
