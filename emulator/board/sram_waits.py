"""Harts that poll SRAM (shared_memory.py): the scheduler's side of their waits.

A hart that comes round a poll loop reading only SRAM, on memory as it was one iteration ago,
waits without executing, with a store watch on the other harts over what it reads; a store that
changes it (or a DMA write) wakes it, and it runs before the storer goes on, the harts then
racing in lockstep for a moment. A mixin of Scheduler (scheduler.py), which holds the state it
uses (_poll_seen, _race_until, _priority) and calls these between and within turns.
"""
from __future__ import annotations

from typing import Callable

import unicorn
from unicorn import riscv_const as rv

from ..cpu import shared_memory
from ..cpu.hart import Hart, HartState
from ..memory_map import SRAM_BASE, SRAM_UNCACHED_BASE
from ..vtime import Time, cycles_time


class SramWaits:
    """Scheduler's waits of harts polling SRAM: begin, end, wake on a store, the watches' hits."""

    # besides the board (scheduler.py's Board protocol), what it uses of Scheduler:
    harts: list[Hart]
    _hz: int
    _race_until: Time
    _priority: tuple[Hart, int] | None
    _poll_seen: dict[int, tuple[int, list[bytes], int]]

    hart_now: Callable[[Hart], Time]
    move_hart: Callable[[Hart, Time], None]

    def _begin_wait(self, hart: Hart, turn_start: int) -> bool:
        """The hart came round a poll loop again: when the loop reads only SRAM, and it ran its
        last iteration on memory as it is now (the iteration ran in this turn, so nothing else
        wrote meanwhile; or, in lockstep, what it reads was the same one iteration ago), the
        hart waits, with a store watch on the other harts over what it reads. False: it goes on."""
        loop, slot = hart.take_poll_report()
        if not loop.loads:
            hart.skip_idle(loop)    # it only spins: nothing to wait for, its iterations are counted
            return False
        spans = shared_memory.polled_spans(loop, lambda r: hart.reg(rv.UC_RISCV_REG_X0 + r))
        if spans is None:
            slot.ignore = 1     # it polls a device: the bus's poll detection is for those
            return False
        memory = self.board.memory.bytes
        seen = [memory[o:o + w].tobytes() for o, w in spans]
        previous = self._poll_seen.get(hart.hart_id)
        self._poll_seen[hart.hart_id] = (loop.head, seen, hart.executed)
        # (the earlier look counts only if it was one iteration ago: the hart may have left the loop
        # and come back to it since, and what it saw then says nothing about what it reads now)
        if hart.executed - loop.body <= turn_start and previous != (loop.head, seen, hart.executed - loop.body):
            # the last iteration began before this turn: the next one decides. Meanwhile the harts
            # run in lockstep, since what it polls may be about to change for a moment only
            self._race_until = max(self._race_until,
                                   self.hart_now(hart) + cycles_time(shared_memory.RACE_WINDOW_CYCLES, self._hz))
            return False
        del self._poll_seen[hart.hart_id]
        wait = shared_memory.Wait(loop, spans, seen)
        for other in self.harts:
            if other is hart:
                continue
            watch = shared_memory.StoreWatch(other.counter_address, 0, 0)
            handles = [other.add_native_hook(unicorn.UC_HOOK_MEM_WRITE, shared_memory.STORE_WATCH_HOOK, watch,
                                             view + offset, view + offset + width - 1, "a store watch")
                       for offset, width in spans for view in (SRAM_BASE, SRAM_UNCACHED_BASE)]
            wait.watches.append((other, watch, handles))
        hart.wait = wait
        hart.state = HartState.WAITING
        return True

    def _end_wait(self, hart: Hart, now: Time, by_store: bool) -> None:
        """A waiting hart runs again from `now`; woken by a store, it runs before the storer goes on
        (one whole iteration of its loop), and the harts race in lockstep for a moment."""
        wait = hart.wait
        for other, _, handles in wait.watches:
            for handle in handles:
                other.remove_hook(handle)
        hart.wait = None
        hart.state = HartState.RUNNING
        self.move_hart(hart, max(hart.time, now))
        self._race_until = max(self._race_until, hart.time + cycles_time(shared_memory.RACE_WINDOW_CYCLES, self._hz))
        if by_store:
            self._priority = (hart, max(shared_memory.RACE_TURN, wait.loop.body))

    def _check_waiters(self, now: Time, storer: Hart | None = None) -> None:
        """Waiting harts whose SRAM changed wake at `now` (after `storer`'s turn: at its store)."""
        memory = self.board.memory.bytes
        for hart in self.harts:
            if hart.state is not HartState.WAITING:
                continue
            wait = hart.wait
            stored = False
            for other, watch, _ in wait.watches:
                if other is storer and watch.hits:
                    stored, watch.hits = True, 0
            if any(memory[o:o + w].tobytes() != seen for (o, w), seen in zip(wait.spans, wait.seen)):
                self._end_wait(hart, now, by_store=stored)

    def _stopped_by_a_watch(self, hart: Hart) -> bool:
        return any(other is hart and watch.hits for waiter in self.harts if waiter.wait is not None
                   for other, watch, _ in waiter.wait.watches)
