/*
 * The scheduler's turns, run here while none of them needs the board (scheduler.py: _go_on_alone for a
 * hart running alone, _go_on_paired for both harts running): each turn exactly as Scheduler._turn
 * would give it, the devices left where they are until the last, which is what costs the host time
 * between turns (a return to Python, the devices moved on, the next turn worked out).
 */
#include <stdint.h>

#include "_counter.h"
#include "_fast_engine.h"
#include "_turns.h"

#define PS_PER_S 1000000000000ULL

/* vtime.cycles_time: how long `cycles` cycles at `hz` take, rounded up to a picosecond */
static int64_t cycles_time(uint64_t cycles, uint64_t hz)
{
    unsigned __int128 ps = (unsigned __int128)cycles * PS_PER_S;
    return (int64_t)((ps + hz - 1) / hz);
}

/* Scheduler.time_at_cycles: the time at cycle count `cycles` of a hart whose clock is anchored at
 * (anchor_time, anchor_cycles) */
static int64_t time_at(int64_t anchor_time, uint64_t anchor_cycles, uint64_t hz, uint64_t cycles)
{
    return anchor_time + cycles_time(cycles - anchor_cycles, hz);
}

/* Scheduler.cycles_until: the least cycle count at which that hart's time is `time` or later */
static uint64_t cycles_until(int64_t anchor_time, uint64_t anchor_cycles, uint64_t hz, int64_t time)
{
    int64_t since = time - anchor_time - 1;
    if (since < 0)
        return anchor_cycles;
    unsigned __int128 whole = (unsigned __int128)(uint64_t)since * hz / PS_PER_S;
    return anchor_cycles + (uint64_t)whole + 1;
}

/* Scheduler._turn's budget: the cycles up to `until`, one at least */
static uint64_t turn_budget(uint64_t until, uint64_t cycles)
{
    return until > cycles + 1 ? until - cycles : 1;
}

/* The turn about to run, in a plan's out fields (alone_plan_t's and pair_plan_t's alike) */
#define RECORD_TURN(plan, t0_, horizon_, budget_, c_) do { \
        (plan)->t0 = (t0_); \
        (plan)->horizon = (horizon_); \
        (plan)->budget = (budget_); \
        (plan)->start_cycles = (c_)->cycles; \
        (plan)->start_executed = (c_)->executed; \
        (plan)->turns++; \
    } while (0)

/* Runs a turn of `budget` cycles with the counter's limits set as Hart.run sets them; whether it
 * stopped before its end for the board (a hand-over, a poll loop come round, a stray store) */
static int turn_handed_over(struct fast_state *f, insn_counter_t *c, uint64_t budget)
{
    c->limit = c->executed + budget;
    c->cycle_limit = c->cycles + budget;
    int why = fast_turn(f, c);
    return why != STOP_LIMIT || c->poll_report != 0 || fast_wrote_astray(f);
}

static int64_t plan_time_at(const alone_plan_t *plan, uint64_t cycles)
{
    return time_at(plan->anchor_time, plan->anchor_cycles, plan->hz, cycles);
}

static uint64_t plan_cycles_until(const alone_plan_t *plan, int64_t time)
{
    return cycles_until(plan->anchor_time, plan->anchor_cycles, plan->hz, time);
}

/*
 * Runs the turns the scheduler would give a hart running alone, one after another, while none needs
 * the board: each turn's budget from its start time as Scheduler._turn works it out, the counter's
 * limits set as Hart.run sets them, the next turn beginning when the last ended. Stops after the turn
 * that ends at or past stop_at, after max_turns, or inside a turn that hands over. Returns the pc.
 */
__attribute__((visibility("default")))
uint64_t fast_run_alone(struct fast_state *f, insn_counter_t *c, void *uc, uint64_t from, alone_plan_t *plan)
{
    fast_begin_turns(f, uc, from);
    int64_t t0 = plan_time_at(plan, c->cycles);
    uint64_t tick = 0;     /* the first of tick_ends not yet passed */
    plan->turns = 0;
    plan->handed_over = 0;
    for (;;) {
        /* the board's next event after t0, as the scheduler would find it: ticks up to t0 have passed */
        while (tick < plan->ticks && plan->tick_ends[tick] <= t0)
            tick++;
        int64_t horizon = plan_time_at(plan, c->cycles + plan->quantum);
        if (plan->outer < horizon)
            horizon = plan->outer;
        if (tick < plan->ticks && plan->tick_ends[tick] < horizon)
            horizon = plan->tick_ends[tick];
        uint64_t budget = turn_budget(plan_cycles_until(plan, horizon), c->cycles);
        RECORD_TURN(plan, t0, horizon, budget, c);
        if (turn_handed_over(f, c, budget)) {
            plan->handed_over = 1;
            break;
        }
        t0 = plan_time_at(plan, c->cycles);
        plan->end_time = t0;
        if (t0 >= plan->stop_at || plan->turns >= plan->max_turns)
            break;
    }
    return fast_end_turns(f, uc);
}

/*
 * Runs the turns the scheduler gives both harts while both run, one after another, while none needs
 * the board: each turn to the hart furthest behind (the lower first when level), its horizon a
 * quantum of its own cycles, or a quantum past the other hart's time, or `outer`, whichever comes
 * first, its budget and the counter's limits as Scheduler._turn and Hart.run set them. The devices
 * do not move on between the turns (nothing happens before `outer`: the scheduler's own bound on
 * every turn until then, as for a hart alone). Stops before the turn that would begin at or past
 * stop_at, after max_turns, or inside a turn that hands over (plan->last names its hart). Each hart's
 * pc is in plan->pc.
 */
__attribute__((visibility("default")))
void fast_run_pair(struct fast_state *f0, struct fast_state *f1, insn_counter_t *c0, insn_counter_t *c1, void *uc0,
                   void *uc1, pair_plan_t *plan)
{
    struct fast_state *const f[2] = {f0, f1};
    insn_counter_t *const c[2] = {c0, c1};
    fast_begin_turns(f0, uc0, plan->pc[0]);
    fast_begin_turns(f1, uc1, plan->pc[1]);
    const int64_t quantum_time = cycles_time(plan->quantum, plan->hz);
    plan->turns = 0;
    plan->handed_over = 0;
    while (plan->turns < plan->max_turns) {
        int h = plan->time[1] < plan->time[0];
        int64_t t0 = plan->time[h];
        if (t0 >= plan->stop_at)
            break;
        insn_counter_t *k = c[h];
        int64_t horizon = time_at(plan->anchor_time[h], plan->anchor_cycles[h], plan->hz, k->cycles + plan->quantum);
        if (plan->outer < horizon)
            horizon = plan->outer;
        if (plan->time[1 - h] + quantum_time < horizon)
            horizon = plan->time[1 - h] + quantum_time;
        uint64_t budget = turn_budget(cycles_until(plan->anchor_time[h], plan->anchor_cycles[h], plan->hz, horizon),
                                      k->cycles);
        plan->last = (uint64_t)h;
        RECORD_TURN(plan, t0, horizon, budget, k);
        if (turn_handed_over(f[h], k, budget)) {
            plan->handed_over = 1;
            break;
        }
        plan->time[h] = time_at(plan->anchor_time[h], plan->anchor_cycles[h], plan->hz, k->cycles);
    }
    plan->pc[0] = fast_end_turns(f0, uc0);
    plan->pc[1] = fast_end_turns(f1, uc1);
}
