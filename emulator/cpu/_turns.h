/*
 * The scheduler's turns run in C while no turn needs the board (_turns.c): the plans Python fills in
 * and reads back (native.py's AlonePlan and PairPlan mirror them).
 */
#ifndef K210_TURNS_H
#define K210_TURNS_H
#include <stdint.h>

#define QUIET_ENDS_MAX 16    /* native.py's */

/* The scheduler's turns of a hart running alone (scheduler.py, _go_on_alone), as fast_run_alone runs
 * them: in, the hart's clock and what bounds the turns; out, where the last one began and how it ended.
 * Times are whole picoseconds (vtime.py), the arithmetic the scheduler's, exact in both. */
typedef struct {
    int64_t anchor_time;    /* the hart's time is anchor_time + cycles_time(cycles - anchor_cycles, hz) */
    uint64_t anchor_cycles;
    uint64_t hz;
    uint64_t quantum;   /* cycles a turn */
    int64_t outer;      /* no turn runs past it (a device event, a grab, the run's end) */
    int64_t stop_at;    /* no turn begins at or after it */
    uint64_t max_turns;
    int64_t t0;         /* out: when the last turn began */
    int64_t horizon;    /* out: the last turn's horizon */
    uint64_t budget;    /* out: its cycle budget */
    uint64_t start_cycles, start_executed;   /* out: the counter when it began */
    uint64_t turns;     /* out: turns begun */
    uint64_t handed_over;   /* out: 1 when the last turn stopped before its end (the pc needs the precise
                               engine, or a poll loop came round): the scheduler finishes it */
    int64_t end_time;   /* out, handed_over 0: when the last turn ended */
    /* Device events that bound the turns as `outer` does but need no board between them (the console's
     * bytes leaving the UART while nothing else hears them: Uarths.quiet_byte_ends): the first `ticks`
     * of tick_ends, in order. */
    int64_t tick_ends[QUIET_ENDS_MAX];
    uint64_t ticks;
} alone_plan_t;

/* The scheduler's turns of both harts running (scheduler.py, _go_on_paired), as fast_run_pair runs them. */
typedef struct {
    int64_t anchor_time[2];     /* hart h's time is anchor_time[h] + cycles_time(cycles - anchor_cycles[h], hz) */
    uint64_t anchor_cycles[2];
    int64_t time[2];            /* in: each hart's time; out: each hart's time after its last whole turn */
    uint64_t hz;
    uint64_t quantum;           /* cycles a turn, and how far a hart may run past the other */
    int64_t outer;              /* no turn runs past it (a device event, a grab, the run's end) */
    int64_t stop_at;            /* no turn begins at or after it */
    uint64_t max_turns;
    uint64_t pc[2];             /* out: where each hart goes on */
    uint64_t last;              /* out: the hart that ran the last turn */
    int64_t t0;                 /* out: when the last turn began */
    int64_t horizon;            /* out: the last turn's horizon */
    uint64_t budget;            /* out: its cycle budget */
    uint64_t start_cycles, start_executed;   /* out: the counter of its hart when it began */
    uint64_t turns;             /* out: turns begun */
    uint64_t handed_over;       /* out: as alone_plan_t's, for the last turn */
} pair_plan_t;

#endif
