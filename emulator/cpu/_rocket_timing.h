/*
 * Rocket's branch predictor and its iterative multiplier/divider as both counters time them
 * (_insn_counter.c for the precise engine, _fast_engine.c for the fast one): inline in each, since
 * the fast engine resolves a control transfer every few instructions.
 */
#ifndef K210_ROCKET_TIMING_H
#define K210_ROCKET_TIMING_H
#include "_counter.h"

static inline uint32_t btb_bucket(uint64_t pc)
{
    return (uint32_t)((pc >> 1) ^ (pc >> 8)) & (BTB_INDEX_BUCKETS - 1);
}

/* The BTB entry holding `pc`, or -1 (a fully associative look-up, through the index). */
static inline int btb_find(const predictor_t *p, uint64_t pc)
{
    for (uint32_t i = btb_bucket(pc); p->index[i]; i = (i + 1) & (BTB_INDEX_BUCKETS - 1)) {
        int slot = p->index[i] - 1;
        if (p->pc[slot] == pc)
            return slot;
    }
    return -1;
}

static inline void btb_index_insert(predictor_t *p, uint64_t pc, int slot)
{
    uint32_t i = btb_bucket(pc);
    while (p->index[i])
        i = (i + 1) & (BTB_INDEX_BUCKETS - 1);
    p->index[i] = (uint8_t)(slot + 1);
}

/* Takes `pc` out of the index, moving later members of its probe run back into the gap. */
static inline void btb_index_remove(predictor_t *p, uint64_t pc)
{
    uint32_t i = btb_bucket(pc);
    while (p->pc[p->index[i] - 1] != pc)
        i = (i + 1) & (BTB_INDEX_BUCKETS - 1);
    uint32_t gap = i;
    for (uint32_t j = (i + 1) & (BTB_INDEX_BUCKETS - 1); p->index[j]; j = (j + 1) & (BTB_INDEX_BUCKETS - 1)) {
        uint32_t home = btb_bucket(p->pc[p->index[j] - 1]);
        /* j's entry may fill the gap when its home bucket is not in (gap, j] (cyclically) */
        int home_in_range = gap <= j ? (gap < home && home <= j) : (gap < home || home <= j);
        if (!home_in_range) {
            p->index[gap] = p->index[j];
            gap = j;
        }
    }
    p->index[gap] = 0;
}

/* A branch that hit in the BTB went `taken` (1) or not: its 2-bit BHT entry and the global history learn it. */
static inline void bht_learn(predictor_t *p, uint32_t bht_index, int taken)
{
    uint8_t v = p->bht[bht_index];
    uint8_t v1 = (v >> 1) & 1, v0 = v & 1;
    p->bht[bht_index] = (uint8_t)((taken << 1) | ((v1 & v0) | ((v1 | v0) & taken)));
    p->history = ((uint32_t)taken << (BHT_BITS - 1)) | (p->history >> 1);
}

/* What a control transfer costs beyond its own cycle and what the predictor learns from it, in
 * general: every kind, hit or miss (resolve_transfer takes the common conditional-branch cases
 * itself). `hit`: the transfer's BTB entry or -1. */
static __attribute__((noinline)) uint64_t resolve_any_transfer(insn_counter_t *c, uint64_t pc, uint32_t e, int kind,
                                                               uint64_t next, int hit)
{
    predictor_t *p = &c->predictor;
    uint64_t fallthrough = pc + (E_SIZE4(e) ? 4 : 2);
    int taken = next != fallthrough || kind != KIND_BRANCH;
    int predicted_taken = 0;
    uint64_t predicted_target = 0;
    uint32_t bht_index = (uint32_t)((pc >> 1) ^ p->history) & (BHT_ENTRIES - 1);
    if (hit >= 0) {
        predicted_taken = p->is_jump[hit] || (p->bht[bht_index] & 1);
        predicted_target = p->target[hit];
        if (p->is_return[hit] && p->ras_count > 0)
            predicted_target = p->ras[p->ras_pos];
    }
    int mispredicted = taken != predicted_taken || (taken && predicted_target != next);
    if (c->caches != NULL) {
        /* Rocket compares the pc the frontend fetched next with the one the transfer computed
         * (Rocket.scala, mem_wrong_npc): a transfer to the very next instruction, which the frontend
         * fetched anyway, is no misprediction (and installs no BTB entry). The pipeline-only model
         * (--timing rocket-nocache) keeps the misprediction it has always charged: issue 31 asks it
         * to stay as it was. */
        uint64_t predicted_next = (hit >= 0 && predicted_taken) ? predicted_target : fallthrough;
        mispredicted = predicted_next != next;
    }
    if (hit >= 0 && kind == KIND_BRANCH)
        bht_learn(p, bht_index, taken);
    if (taken && mispredicted) {
        int slot = hit;
        if (slot < 0) {
            slot = (int)p->next_replace;
            p->next_replace = (p->next_replace + 1) % BTB_ENTRIES;
            if (p->valid[slot])
                btb_index_remove(p, p->pc[slot]);
            btb_index_insert(p, pc, slot);
        }
        p->valid[slot] = 1;
        p->pc[slot] = pc;
        p->target[slot] = next;
        p->is_jump[slot] = kind != KIND_BRANCH;
        p->is_return[slot] = kind == KIND_JALR && E_RETURN(e);
    }
    if ((kind == KIND_JAL || kind == KIND_JALR) && E_CALL(e)) {
        if (p->ras_count < RAS_ENTRIES)
            p->ras_count++;
        p->ras_pos = (p->ras_pos + 1) % RAS_ENTRIES;
        p->ras[p->ras_pos] = fallthrough;
    } else if (kind == KIND_JALR && E_RETURN(e) && hit >= 0 && p->ras_count > 0) {
        p->ras_count--;
        p->ras_pos = (p->ras_pos + RAS_ENTRIES - 1) % RAS_ENTRIES;
    }
    if (!mispredicted)
        return 0;
    c->mispredicts++;
    return MISPREDICT_PENALTY;
}

/* Cycles the control transfer at `pc` (its table entry `e`) costs beyond its own, now that the
 * next instruction's address `next` shows where it went; the predictor learns as Rocket's does.
 * Inline for the cases a conditional branch takes most (the fast engine resolves one every few
 * instructions): not taken with no BTB entry (predicted not taken, nothing learns), and a BTB
 * hit whose branch was predicted right (the BHT and the history learn); resolve_any_transfer
 * for everything else, with the same outcome. */
static inline uint64_t resolve_transfer(insn_counter_t *c, uint64_t pc, uint32_t e, int kind, uint64_t next)
{
    if (kind == KIND_FLUSH)
        return 0;     /* (its flush is the table's extra; the predictor takes no part) */
    predictor_t *p = &c->predictor;
    int hit = btb_find(p, pc);
    if (kind == KIND_BRANCH) {
        int taken = next != pc + (E_SIZE4(e) ? 4 : 2);
        if (hit < 0) {
            if (!taken)
                return 0;
        } else if (!p->is_jump[hit] && !(p->is_return[hit] && p->ras_count > 0)) {
            uint32_t bht_index = (uint32_t)((pc >> 1) ^ p->history) & (BHT_ENTRIES - 1);
            int predicted_taken = p->bht[bht_index] & 1;
            if (taken == predicted_taken && (!taken || p->target[hit] == next)) {
                bht_learn(p, bht_index, taken);
                return 0;
            }
        }
    }
    return resolve_any_transfer(c, pc, e, kind, next, hit);
}

/* Rocket's frontend fetches 4 bytes a cycle (RocketCoreParams: fetchWidth 2 parcels of 16 bits when the
 * core has RVC) and its IBuf (IBuf.scala) issues a 32-bit instruction only once it has both halves. After
 * a redirect (a transfer taken, predicted or not, or any mispredicted one), the packet fetched at a
 * target 2 mod 4 holds only the first half of a 32-bit instruction there, which waits a cycle for the
 * next packet. Returns that cycle for the transfer or flush at `pc` (entry `e`, `penalty` its misprediction's
 * cycles) whose next instruction is the `next_size`-byte one at `next`. Charged with the caches only
 * (the frontend's fetch is modelled with the instruction cache: --timing rocket-nocache is the
 * pipeline alone, as it was). A flush (a CSR write, mret, fence.i: KIND_FLUSH) refetches too; a
 * trap's entry is not charged it (mtvec is 4-aligned). */
static inline uint64_t redirect_bubble(const insn_counter_t *c, uint64_t pc, uint32_t e, int kind, uint64_t next,
                                       uint32_t next_size, uint64_t penalty)
{
    if (c->caches == NULL || next_size != 4 || !(next & 2))
        return 0;
    /* (a jump to the very next instruction, predicted right, redirects nothing) */
    int redirected = kind == KIND_FLUSH || next != pc + (E_SIZE4(e) ? 4 : 2) || penalty != 0;
    return redirected ? REDIRECT_BUBBLE : 0;
}

static inline int msb(uint64_t x)   /* hardware Log2: index of the highest set bit, 0 for 0 */
{
    return x ? 63 - __builtin_clzll(x) : 0;
}

/* Rocket's iterative MulDiv (Multiplier.scala) with the big core's parameters: mulUnroll 8,
 * mulEarlyOut, divEarlyOut. Returns the result latency: cycles from the instruction's issue to
 * the issue of one that waits for the result. Its states: an optional cycle negating the
 * inputs, the iterations, an optional cycle moving the remainder and one negating the result,
 * then the response (written back through the long-latency port). */
static inline uint64_t muldiv_latency(uint32_t e, uint64_t a, uint64_t b, int is_div)
{
    int lhs_signed = E_LHS_SIGNED(e), rhs_signed = E_RHS_SIGNED(e), hi = E_HI(e);
    if (E_WORD(e)) {   /* the 32-bit forms sign- (or zero-) extend their inputs to 64 bits */
        a = lhs_signed ? (uint64_t)(int64_t)(int32_t)a : (uint32_t)a;
        b = rhs_signed ? (uint64_t)(int64_t)(int32_t)b : (uint32_t)b;
    }
    int lhs_sign = lhs_signed && (a >> 63);
    int rhs_sign = rhs_signed && (b >> 63);
    uint64_t cycles = 1;                       /* the request, in the execute stage */
    if (!is_div) {
        if (lhs_sign) {
            cycles++;
            a = -a;
        }
        uint64_t iterations = 8;               /* 64 bits, 8 a cycle */
        if (!hi) {
            for (uint64_t n = 1; n < 7; n++)   /* early out once the multiplier's rest is zero */
                if ((a >> (8 * n)) == 0) {
                    iterations = n + 1;
                    break;
                }
        }
        cycles += iterations + (hi ? 1 : 0);
        return cycles;
    }
    int neg_out = hi ? lhs_sign : lhs_sign != rhs_sign;
    if (lhs_sign || rhs_sign)
        cycles++;
    if (lhs_sign)
        a = -a;
    if (rhs_sign)
        b = -b;
    uint64_t iterations = 65;                  /* count 0..64, one quotient bit each */
    if (b != 0) {
        int divisor_msb = msb(b), dividend_msb = msb(a);
        int zero = divisor_msb > dividend_msb;
        int position = (63 + divisor_msb - dividend_msb) & 63;
        if (position > 0 || zero) {
            int shift = zero ? 63 : position;
            iterations = 1 + (uint64_t)(64 - shift + 1);
        }
    } else if (!hi) {
        neg_out = 0;
    }
    cycles += iterations + (hi ? 1 : 0) + (neg_out ? 1 : 0);
    return cycles;
}

#endif
