/*
 * What _fast_engine.c offers the rest of the counter's extension (_insn_counter.c calls fast_step
 * for hart.py): its stops and its Python-facing entry point.
 */
#ifndef K210_FAST_ENGINE_H
#define K210_FAST_ENGINE_H
#include <stdint.h>

#include "_counter.h"

/* fast_run's answers */
#define STOP_HANDOFF 1   /* the instruction at pc needs the precise engine */
#define STOP_LIMIT 2     /* the counter's instruction or cycle limit is reached */
#define STOP_DEVICE 3    /* the load or store at pc, counted, accesses a device: see `dev` */

struct fast_state;

/* fast_run (resume 0, `arg` the pc) or fast_resume (resume 1, `arg` the loaded value); at STOP_DEVICE,
 * `out` holds the access: window, address, width, is_store, the stored value, its pc. */
int fast_step(struct fast_state *f, insn_counter_t *c, void *uc, uint64_t arg, int resume, uint64_t out[6]);

/* A stretch of turns (_turns.c): the hart's registers from the precise engine, its device accesses
 * handed over; a turn to the counter's limits (a stop); whether --check-writes saw a stray store; the
 * registers back, and the pc. */
void fast_begin_turns(struct fast_state *f, void *uc, uint64_t from);
int fast_turn(struct fast_state *f, insn_counter_t *c);
int fast_wrote_astray(const struct fast_state *f);
uint64_t fast_end_turns(struct fast_state *f, void *uc);

#endif
