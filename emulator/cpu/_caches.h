/*
 * Each hart's L1 instruction and data caches, as the K210's Rocket cores have them, for timing:
 * which accesses miss and what a miss costs (caches.py sets the figures and says where each comes
 * from). Data always comes from SRAM itself (Unicorn's memory): the caches here hold tags, not data.
 *
 * Geometry: 32 KiB each (the K210 datasheet), 64-byte lines (Linux's and U-Boot's k210.dtsi),
 * 64 sets of 8 ways (Rocket's caches index a set within a 4 KiB page when the core has an MMU,
 * HellaCache.scala's `untagBits <= pgIdxBits`, so 32 KiB needs 8 ways). The victim is the way a
 * 16-bit LFSR names, advanced once per miss (Rocket's RandomReplacement, LFSR16), whether or not
 * another way of the set is empty. The data cache is write-back and write-allocate (DCache.scala's
 * voluntary write-back; a store miss acquires the whole line); its miss blocks the hart (the
 * blocking DCache that rocket-chip's DefaultConfig selects). Permissions follow TileLink as rocket-chip
 * of early 2017 has them: a load acquires a line read-only (NtoB, which the coherence hub grants as
 * Branch), so a store to a line only read so far misses again to acquire write permission (BtoT),
 * and a store miss acquires it writable at once (NtoT).
 *
 * Only SRAM's cached view (0x8000_0000, the 6 MiB and the AI SRAM's 2 MiB) goes through them; an
 * access to the uncached view (0x4000_0000) is a single bus round trip each, and so is an access to a
 * device's registers, each device window with the cost of its bus's path (caches.py). The two harts' data caches are kept coherent as the coherence hub
 * (TLBroadcast) keeps them: each acquire probes the other cache, to Branch for a load and to Nothing
 * for a store, and a dirty copy probed is written back first. The DMA is coherent with the caches
 * and leaves their state as it is (docs/design/timing.md, "DMA and the caches").
 *
 * Both counters charge the same cycles at the same instructions: the precise engine's hook
 * (_insn_counter.c) and the fast engine's interpreter (_fast_engine.c), which keeps the same state.
 */
#ifndef K210_CACHES_H
#define K210_CACHES_H
#include <stdint.h>
#include <string.h>

#define L1_SETS 64
#define L1_WAYS 8
#define L1_LINE_SHIFT 6
#define L1_HOT 512      /* the hot lines' table: a line's slot is its number's low 9 bits */
#define L1_DEVICE_WINDOWS 32   /* device windows timed: the Dock has 23 */

typedef struct {
    uint64_t line[L1_SETS * L1_WAYS];   /* (address >> 6) + 1 of the line each way holds; 0: invalid */
    uint8_t writable[L1_SETS * L1_WAYS]; /* data cache: held with write permission (TileLink's Trunk or
                                           Dirty: a store's grant, and written) rather than Branch (a load's) */
    /* Not Rocket's: lines known to be held (0: none), and known to be held writable, each in the slot
     * of its number's low bits, so that most accesses are answered by one comparison (the engines'
     * speed); a line leaving the cache or losing write permission leaves them */
    uint64_t hot[L1_HOT];
    uint64_t hot_writable[L1_HOT];
    uint32_t lfsr;          /* Rocket's LFSR16: the victim is its low 3 bits */
    uint32_t pad;
    uint64_t lookups, misses, write_backs;   /* statistics: look-ups past the hot lines; misses (a store's
                                                upgrade included); dirty lines written back */
} l1_cache_t;

typedef struct l1_caches {
    l1_cache_t icache;
    l1_cache_t dcache;
    uint64_t fetch_line;          /* the line of the instruction fetched last; 0: none */
    struct l1_caches *peer;       /* the other hart's caches (NULL: none) */
    uint64_t cached_base, cached_size;       /* SRAM's cached view */
    uint64_t uncached_base, uncached_size;   /* its uncached view */
    uint32_t data_fill;           /* cycles a data-cache miss blocks the hart, the line's refill included */
    uint32_t write_back;          /* cycles more when the victim (or the other hart's copy) is dirty */
    uint32_t fetch_fill;          /* cycles an instruction-cache miss stalls fetch */
    uint32_t uncached;            /* cycles an access to the uncached view takes beyond a hit */
    uint64_t uncached_accesses;   /* statistics */
    uint32_t flush_per_way;       /* FENCE.I's walk: cycles per way of every set */
    uint32_t acquired;            /* a line came into the data cache since its last flush (Rocket's !flushed) */
    uint64_t flushes;             /* statistics: FENCE.I flushes that walked the data cache */
    uint32_t device_windows;      /* device windows below in use */
    uint32_t pad2;
    uint64_t device_base[L1_DEVICE_WINDOWS], device_size[L1_DEVICE_WINDOWS];
    uint32_t device_cost[L1_DEVICE_WINDOWS];   /* cycles an access to the window's registers takes beyond a hit */
    uint64_t device_accesses;     /* statistics */
} l1_caches_t;

/* The way of `set` holding `line`, or -1. */
static inline int l1_find(const l1_cache_t *k, uint32_t set, uint64_t line)
{
    const uint64_t *ways = &k->line[set * L1_WAYS];
    for (int w = 0; w < L1_WAYS; w++)
        if (ways[w] == line)
            return w;
    return -1;
}

/* Chisel's LFSR16 moved on (taps 16, 14, 13, 11): Rocket's replacer.miss, once a grant completes. */
static inline void l1_lfsr_step(l1_cache_t *k)
{
    uint32_t v = k->lfsr;
    uint32_t bit = (v ^ (v >> 2) ^ (v >> 3) ^ (v >> 5)) & 1;
    k->lfsr = (v >> 1) | (bit << 15);
}

#define L1_HOT_SLOT(line) ((uint32_t)(line) & (L1_HOT - 1))

/* A line leaves (evicted or probed away): the hot lines must not name it. */
static inline void l1_forget(l1_cache_t *k, uint64_t line)
{
    if (k->hot[L1_HOT_SLOT(line)] == line)
        k->hot[L1_HOT_SLOT(line)] = 0;
    if (k->hot_writable[L1_HOT_SLOT(line)] == line)
        k->hot_writable[L1_HOT_SLOT(line)] = 0;
}

/*
 * The coherence hub's probe of the other hart's data cache when this one acquires `line` (rocket-chip
 * 2017's TLBroadcast probes every other cache): to Branch for a load (a dirty copy is written back and
 * kept read-only), to Nothing for a store (the copy is dropped, written back first if dirty). Returns
 * the cycles the write-back adds.
 */
static inline uint64_t l1_probe_peer(l1_caches_t *c, uint64_t line, uint32_t set, int store)
{
    if (c->peer == NULL)
        return 0;
    l1_cache_t *p = &c->peer->dcache;
    int way = l1_find(p, set, line);
    if (way < 0)
        return 0;
    uint32_t slot = set * L1_WAYS + (uint32_t)way;
    uint64_t cost = 0;
    if (p->writable[slot]) {
        cost = c->write_back;
        p->write_backs++;
        p->writable[slot] = 0;
    }
    if (store) {
        p->line[slot] = 0;
        l1_forget(p, line);
    } else if (p->hot_writable[L1_HOT_SLOT(line)] == line) {
        p->hot_writable[L1_HOT_SLOT(line)] = 0;
    }
    return cost;
}

/* The cycles a data-cache miss on `line` costs, the line brought in: a load's with read permission
 * (NtoB), a store's with write permission (NtoT). The victim is the way the LFSR names. */
static __attribute__((noinline, unused)) uint64_t l1_data_miss(l1_caches_t *c, uint64_t line, uint32_t set, int store)
{
    l1_cache_t *d = &c->dcache;
    uint64_t cost = c->data_fill;
    d->misses++;
    uint32_t slot = set * L1_WAYS + (d->lfsr & (L1_WAYS - 1));
    l1_lfsr_step(d);
    if (d->line[slot] != 0) {
        if (d->writable[slot]) {
            cost += c->write_back;
            d->write_backs++;
        }
        l1_forget(d, d->line[slot]);
    }
    cost += l1_probe_peer(c, line, set, store);
    c->acquired = 1;
    d->line[slot] = line;
    d->writable[slot] = (uint8_t)(store != 0);
    d->hot[L1_HOT_SLOT(line)] = line;
    if (store)
        d->hot_writable[L1_HOT_SLOT(line)] = line;
    return cost;
}

/* A store to a line held read-only: Rocket's cache misses (ClientMetadata.onAccess: a write on Branch
 * needs BtoT) and acquires write permission, which the hub grants with the line's data again. */
static __attribute__((noinline, unused)) uint64_t l1_upgrade(l1_caches_t *c, uint64_t line, uint32_t set, int way)
{
    l1_cache_t *d = &c->dcache;
    d->misses++;
    l1_lfsr_step(d);
    uint64_t cost = c->data_fill + l1_probe_peer(c, line, set, 1);
    c->acquired = 1;
    d->writable[set * L1_WAYS + (uint32_t)way] = 1;
    d->hot[L1_HOT_SLOT(line)] = line;
    d->hot_writable[L1_HOT_SLOT(line)] = line;
    return cost;
}

/* l1_data past the hot lines: the set's look-up, a miss, or the uncached view. */
static __attribute__((noinline, unused)) uint64_t l1_data_lookup(l1_caches_t *c, uint64_t address, int store)
{
    if (address - c->cached_base < c->cached_size) {
        l1_cache_t *d = &c->dcache;
        uint64_t line = (address >> L1_LINE_SHIFT) + 1;
        uint32_t set = (uint32_t)(address >> L1_LINE_SHIFT) & (L1_SETS - 1);
        d->lookups++;
        int way = l1_find(d, set, line);
        if (way < 0)
            return l1_data_miss(c, line, set, store);
        d->hot[L1_HOT_SLOT(line)] = line;
        if (!store)
            return 0;
        if (!d->writable[set * L1_WAYS + (uint32_t)way])
            return l1_upgrade(c, line, set, way);
        d->hot_writable[L1_HOT_SLOT(line)] = line;
        return 0;
    }
    if (address - c->uncached_base < c->uncached_size) {
        c->uncached_accesses++;
        return c->uncached;
    }
    for (uint32_t w = 0; w < c->device_windows; w++)
        if (address - c->device_base[w] < c->device_size[w]) {
            c->device_accesses++;
            return c->device_cost[w];
        }
    return 0;
}

/* The cycles a load or store at `address` takes beyond a cache hit (0 outside SRAM and devices). A hot
 * line is in the cached view, so an address elsewhere never matches one. */
static inline __attribute__((always_inline)) uint64_t l1_data(l1_caches_t *c, uint64_t address, int store)
{
    uint64_t line = (address >> L1_LINE_SHIFT) + 1;
    if (line == (store ? c->dcache.hot_writable[L1_HOT_SLOT(line)] : c->dcache.hot[L1_HOT_SLOT(line)]))
        return 0;
    return l1_data_lookup(c, address, store);
}

/* The cycles fetching the instruction at `pc` stalls beyond a hit (0 unless its line is a new one
 * and misses). Code in SRAM's uncached view is timed as in its cached one (table_key): which of
 * Rocket's fetch paths the K210 takes there is not documented. */
static __attribute__((noinline, unused)) uint64_t l1_fetch_lookup(l1_caches_t *c, uint64_t key, uint64_t line, uint32_t set)
{
    if (key - c->cached_base >= c->cached_size)
        return 0;
    l1_cache_t *i = &c->icache;
    uint64_t cost = 0;
    i->lookups++;
    if (l1_find(i, set, line) < 0) {
        i->misses++;
        uint32_t slot = set * L1_WAYS + (i->lfsr & (L1_WAYS - 1));
        l1_lfsr_step(i);
        if (i->line[slot] != 0)
            l1_forget(i, i->line[slot]);
        i->line[slot] = line;
        cost = c->fetch_fill;
    }
    i->hot[L1_HOT_SLOT(line)] = line;
    return cost;
}

static inline __attribute__((always_inline)) uint64_t l1_fetch(l1_caches_t *c, uint64_t key)
{
    uint64_t line = (key >> L1_LINE_SHIFT) + 1;
    if (line == c->fetch_line)
        return 0;
    c->fetch_line = line;
    if (line == c->icache.hot[L1_HOT_SLOT(line)])
        return 0;
    return l1_fetch_lookup(c, key, line, (uint32_t)(key >> L1_LINE_SHIFT) & (L1_SETS - 1));
}

/* The cycles fetching the `size`-byte instruction at `key` stalls beyond a hit: its line's, and the
 * next line's too when it straddles the two (Rocket's frontend needs both halves before it issues
 * the instruction), so a straddling jump pays for the line it never runs more of. */
static inline __attribute__((always_inline)) uint64_t l1_fetch_insn(l1_caches_t *c, uint64_t key, uint32_t size)
{
    uint64_t cost = l1_fetch(c, key);
    if (((key + size - 1) >> L1_LINE_SHIFT) != (key >> L1_LINE_SHIFT))
        cost += l1_fetch(c, key + size - 1);
    return cost;
}

/*
 * FENCE.I: Rocket's instruction cache drops every line, and its data cache (rocket-chip 2017: IDecode
 * gives FENCE.I the memory command M_FLUSH_ALL; DCache.scala's flush walk) visits every way of every
 * set, writing dirty lines back and dropping all, unless no line came in since its last flush. Returns
 * the cycles the walk and the write-backs take.
 */
static __attribute__((noinline, unused)) uint64_t l1_fence_i(l1_caches_t *c)
{
    l1_cache_t *i = &c->icache, *d = &c->dcache;
    memset(i->line, 0, sizeof i->line);
    memset(i->hot, 0, sizeof i->hot);
    c->fetch_line = 0;
    if (!c->acquired)
        return 0;
    uint64_t cost = (uint64_t)c->flush_per_way * L1_SETS * L1_WAYS;
    for (uint32_t slot = 0; slot < L1_SETS * L1_WAYS; slot++) {
        if (d->line[slot] != 0 && d->writable[slot]) {
            cost += c->write_back;
            d->write_backs++;
        }
    }
    memset(d->line, 0, sizeof d->line);
    memset(d->writable, 0, sizeof d->writable);
    memset(d->hot, 0, sizeof d->hot);
    memset(d->hot_writable, 0, sizeof d->hot_writable);
    c->acquired = 0;
    c->flushes++;
    return cost;
}

#endif
