"""One K210 hart: a Unicorn RV64GC engine plus what Unicorn does not do by itself.

Unicorn executes the instructions; this module adds the parts of a K210 hart that Unicorn 2.1.4
leaves out (it counts no instructions, reads mhartid as 0 on every engine, enters no trap vector
and ends a run at wfi):

- an exact instruction count (a native per-instruction hook, `_insn_counter.c`), and the
  cycles the instructions take on the K210's Rocket core (the same hook, from timing.py's table;
  without a table one cycle each),
- the CSRs the board answers (`mhartid`, `mcycle`, `minstret`, `mip`, the trap and delegation
  registers, the trigger): the native counter stops before every CSR instruction that names them
  and privileged.py carries it out (a code hook per such instruction would cost every instruction:
  Unicorn walks all its code hooks on each one),
- synchronous exceptions and interrupts entering their trap vector as the K210's Rocket does
  (privileged.py), delivered by the board between runs,
- `wfi`, which ends a run: the board keeps the hart asleep until an enabled
  interrupt is pending;
- poll loops on SRAM, which end a run too: the board keeps the hart waiting until
  what it polls changes (shared_memory.py);
- the fast engine (`_fast_engine.c`), which runs what it can of M-mode code in SRAM itself.
"""
from __future__ import annotations

import ctypes
import enum
import weakref
from dataclasses import dataclass
from typing import Callable

import unicorn
from unicorn import riscv_const as rv
from unicorn.unicorn_py3 import unicorn as _ucpy

from . import shared_memory, timing
from ..vtime import NEVER, Time, cycles_reaching
from .native import (COUNT_HOOK, NO_LIMIT, AlonePlan, Counter, FastHead, add_native_hook, address_table,
                     counter_lib, fast_step)
from .privileged import COUNTER_BITS, MSTATUS_RESET, PendingException, PrivilegedArchitecture
from .riscv import (CAUSE_BREAKPOINT, CAUSE_ECALL_U, CAUSE_ILLEGAL_INSTRUCTION, CAUSE_LOAD_MISALIGNED,
                    CAUSE_STORE_MISALIGNED, INSN_WFI, PRIV_M, PRIV_S, PRIV_U)
from .caches import HartCaches
from .time_loops import LoopSkipper, TimeLoop
from .triggers import TriggerUnit
from ..memory_map import SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE

_NOT_CSRS = frozenset([rv.UC_RISCV_REG_PC, *range(rv.UC_RISCV_REG_X0, rv.UC_RISCV_REG_X31 + 1),
                       *range(rv.UC_RISCV_REG_F0, rv.UC_RISCV_REG_F31 + 1)])

# A device access the fast engine leaves to the board: (hart, window index, address, width in bytes,
# is a store, the stored value, pc) -> the loaded value (0 for a store)
DeviceAccess = Callable[["Hart", int, int, int, bool, int, int], int]
# The fast engine answered an armed load again (arm_repeats): (hart, pc, address, value, the poll
# count now, whether it reached the count that makes the hart a poller)
RepeatsAnswered = Callable[["Hart", int, int, int, int, bool], None]


ENGINE_FAST, ENGINE_PRECISE = "fast", "precise"
ENGINES = (ENGINE_FAST, ENGINE_PRECISE)
# Instructions the precise engine runs after the fast one handed it the hart. A hand-over is mostly
# one instruction (an atomic, a CSR, wfi) amid code the fast engine runs, and a run of the precise
# engine costs tens of microseconds whatever it runs: 4 (a lock's lr/bnez/sc/bnez) measured the
# least precise time a frame on the default card (0.24 ms, against 1.17 with 32, 0.34 with 1).
PRECISE_STRETCH = 4
# When the fast engine runs fewer than PRECISE_STRETCH instructions between two hand-overs, the hart
# hands over nearly every instruction (one spinning on a lock's lr.w while the other hart holds it:
# millions of hand-overs in a run that ends in an error, hart 0 sending its console lines at the
# UART's pace). The next stretch is then twice as long, up to PRECISE_STRETCH_MAX (a wrong guess
# costs one stretch run on Unicorn); a fast run any longer brings it back to PRECISE_STRETCH. Only
# host time changes: both engines run, count and time alike.
PRECISE_STRETCH_MAX = 4096
_UC_EMU_STOP = ctypes.cast(_ucpy.uclib.uc_emu_stop, ctypes.c_void_p).value
_UC_REG_READ = ctypes.cast(_ucpy.uclib.uc_reg_read, ctypes.c_void_p).value
_UC_REG_READ_BATCH = ctypes.cast(_ucpy.uclib.uc_reg_read_batch, ctypes.c_void_p).value
_UC_REG_WRITE_BATCH = ctypes.cast(_ucpy.uclib.uc_reg_write_batch, ctypes.c_void_p).value


class HartState(enum.Enum):
    RUNNING = "running"
    ASLEEP = "asleep (wfi)"
    WAITING = "polling memory"     # stalled in a poll loop on SRAM (shared_memory.py)


class RunEnd(enum.Enum):
    """Why `Hart.run` returned."""

    BUDGET = "budget"          # the instruction budget is used up
    WFI = "wfi"                # the hart executed wfi
    EXCEPTION = "exception"    # a synchronous exception is waiting in `pending_exception`
    STOPPED = "stopped"        # the board asked the hart to stop early (poll stall, clock change)
    POLL = "poll"              # the hart came round a poll loop again (take_poll_report names it)


@dataclass
class CsrContext:
    """What a CSR read needs from the board at the moment of the read."""

    mcycle: Callable[[], int]
    mip: Callable[[], int]


class Hart(PrivilegedArchitecture):
    """A hart of the K210. The board maps memory and MMIO into `uc` and calls `run`."""

    def __init__(self, hart_id: int, csr_context: CsrContext) -> None:
        self.hart_id = hart_id
        self.uc = unicorn.Uc(unicorn.UC_ARCH_RISCV, unicorn.UC_MODE_RISCV64)
        self.uc.reg_write(rv.UC_RISCV_REG_MSTATUS, MSTATUS_RESET)
        self.csr_context = csr_context
        self.state = HartState.RUNNING
        self.time: Time = 0      # virtual time the hart has reached (asleep: when it went to sleep)
        self.polling = False     # set during a turn when the board saw it poll an unchanging register
        self.pc = 0
        self.pending_exception: PendingException | None = None
        # the exception this hart's trap handler is handling, until it returns with mret or sret (the board
        # tells a trap that ends the program from one the program handles: scheduler.py)
        self.open_trap: str | None = None
        # the mode the hart runs in: it changes only at a trap (enter_trap) and at mret, both carried
        # out here. Unicorn answers a CSR read or write only in a mode allowed to make it, so the
        # model makes its own accesses to M-mode CSRs in M-mode (_as_machine)
        self.privilege = PRIV_M
        self.stop_requested = False
        self.retired_adjust = 0   # instructions counted by the hook that did not retire (trapped)
        self.minstret_offset = 0  # set by firmware writes to minstret
        self.mcycle_offset = 0
        self._counter = Counter(0, 0, _UC_EMU_STOP, None, 0, 0, 0, NO_LIMIT, None, 0, 0, _UC_REG_READ,
                                 rv.UC_RISCV_REG_X0)
        self._cycle_table: timing.CycleTable | None = None   # kept alive while the counter reads it
        self.caches: HartCaches | None = None        # the L1 caches the counters charge (caches.py)
        self.skipper = LoopSkipper(self._counter)
        self._counter_hook = self.add_native_hook(unicorn.UC_HOOK_CODE, COUNT_HOOK, self._counter, 1, 0,
                                                  "the instruction counter")
        self._csr_words: dict[int, int] = {}          # address -> instruction word of each CSR site
        self.time_loops: dict[int, TimeLoop] = {}     # by the address of their time read (time_loops.py)
        self._turn_limit = NO_LIMIT
        # the cycle count a time loop's skip may reach past the turn's end (the scheduler's to set,
        # for a hart that runs alone with nothing happening before then); None: the turn's end
        self.time_skip_limit: int | None = None
        self._csr_table: ctypes.Array | None = None   # the counter's table of CSR sites, kept alive here
        self.csr_listeners: list[Callable[["Hart", int], None]] = []   # called before a CSR site is carried out
        self.poll_loops: dict[int, tuple[shared_memory.PollLoop, shared_memory.LoopSlot]] = {}
        self._loop_slots: ctypes.Array | None = None   # the counter's table of poll loops, kept alive here
        self._idle_spans: list[tuple[int, int]] = []   # [head, branch] of each loop that only spins
        self.wait: shared_memory.Wait | None = None   # what the hart polls while WAITING
        self.uc.hook_add(unicorn.UC_HOOK_INTR, self._on_exception)
        self._reg_value = ctypes.c_uint64()
        self._reg_ref = ctypes.byref(self._reg_value)
        # the fast engine (enable_fast_engine), and the hooks that keep a hart on the precise one
        self._fast_state: int | None = None
        self._fast_head: FastHead | None = None
        self._hooks_needing_precision: set[int] = set()
        self.precise_runs = 0     # runs of the precise engine (the scheduler sees whether a turn had any)
        self._precise_stretch = PRECISE_STRETCH
        self.device_accesses = 0  # device accesses the fast engine left to the board (likewise)
        self._device_access: DeviceAccess | None = None
        self._device_windows: list[tuple[int, int]] = []
        self._write_watch: ctypes.Structure | None = None   # --check-writes (attach_write_watch)
        self._repeats_answered: RepeatsAnswered | None = None
        self._holding = False     # the fast engine holds the registers during a device access
        self.triggers = TriggerUnit()
        self.soft_mip = 0         # mip's SSIP and STIP as software wrote them (privileged.py)
        self.counter_enables = {PRIV_U: COUNTER_BITS, PRIV_S: COUNTER_BITS}   # mucounteren, mscounteren
        self._trigger_hook: int | None = None   # watches every instruction while a trigger is armed
        # device windows' callbacks (map_device), by the index Unicorn hands back as user data
        self._windows_read: list[Callable] = []
        self._windows_write: list[Callable] = []
        self._window_thunks: tuple | None = None

    def add_native_hook(self, kind: int, callback: int, user_data: ctypes.Structure, begin: int, end: int,
                        what: str) -> int:
        """Installs a C function (its address) as a Unicorn hook of `kind` for addresses
        begin..end (inclusive; begin > end: everywhere), called with a pointer to `user_data`,
        which the caller keeps alive as long as the hook. `what` names it in the error.
        Returns the hook's handle (for remove_hook)."""
        handle = add_native_hook(self.uc, kind, callback, user_data, begin, end, f"{what} on hart {self.hart_id}")
        if callback is not COUNT_HOOK:
            # the fast engine does not carry other hooks (store watches, the write checker)
            self._hooks_needing_precision.add(handle)
        return handle

    def add_hook(self, kind: int, callback: Callable, user_data: object, begin: int = 1, end: int = 0) -> int:
        """A Python hook added while the hart may already have run: Unicorn 2.1.4 decides when it
        translates code which instructions call hooks, and code translated before the hook was
        added may never call it, so the translations are dropped. Returns the hook's handle."""
        handle = self.uc.hook_add(kind, callback, user_data, begin, end)
        self.uc.ctl_flush_tb()
        self._hooks_needing_precision.add(handle)
        return handle

    def remove_hook(self, handle: int) -> None:
        """Removes a hook add_native_hook installed."""
        self._hooks_needing_precision.discard(handle)
        _ucpy.uclib.uc_hook_del(self.uc._uch, ctypes.c_size_t(handle))

    def delete_hook(self, handle: int) -> None:
        """Removes a Python hook add_hook or add_stop_hook installed."""
        self._hooks_needing_precision.discard(handle)
        self.uc.hook_del(handle)

    # --- the fast engine ---------------------------------------------------------------

    def trap_misaligned(self, sram_address: int) -> None:
        """Has the precise engine's counter raise the misaligned-address exceptions Rocket raises and
        Unicorn does not (_insn_counter.c): it reads the code from SRAM's host buffer at
        `sram_address`. (The fast engine hands every access that is not naturally aligned to the
        precise engine.)"""
        counter = self._counter
        counter.sram_base, counter.sram_alias, counter.sram_size = SRAM_BASE, SRAM_UNCACHED_BASE, SRAM_SIZE
        counter.sram = sram_address

    def enable_fast_engine(self, sram_address: int) -> None:
        """Gives the hart a second engine, an interpreter of the code in SRAM (_fast_engine.c; SRAM is
        the host buffer at `sram_address`, both views), that runs the hart whenever no hook needs the
        precise engine and counts and times each instruction as the precise engine's counter does.
        It hands the hart over before what it does not carry out itself: device accesses, CSRs,
        wfi, traps, atomics, floating point on NaNs or in other rounding modes. Counts, cycles and
        every stop stay what the precise engine alone would give."""
        state = counter_lib.fast_state_new(self.hart_id, sram_address, SRAM_SIZE, SRAM_BASE, SRAM_UNCACHED_BASE,
                                            _UC_REG_READ_BATCH, _UC_REG_WRITE_BATCH)
        if not state:
            raise MemoryError("cannot allocate the fast engine")
        self._fast_state = state
        self._fast_head = FastHead.from_address(state)
        self._counter_at = ctypes.addressof(self._counter)     # (fast_step takes addresses)
        self._uc_at = self.uc._uch.value
        # freed with the hart (Board.close frees it at once)
        self._free_fast_state = weakref.finalize(self, counter_lib.fast_state_free, state)
        self._give_windows()
        self._give_write_watch()

    def attach_devices(self, windows: list[tuple[int, int]], access: DeviceAccess,
                       repeats_answered: RepeatsAnswered | None = None) -> None:
        """Has the fast engine leave the naturally aligned integer loads and stores that fall in
        `windows` ((base, end) physical address ranges, the devices the bus maps) to `access`, with the
        hart's registers still held by it: a device access costs a call, not a run of the precise
        engine. `access` gets the window's index in `windows`. Other accesses outside SRAM (misaligned,
        FP, elsewhere) still go to the precise engine. `repeats_answered` hears of the loads the
        fast engine answered again itself (arm_repeats), before anything else reaches the board."""
        self._device_windows = list(windows)
        self._device_access = access
        self._repeats_answered = repeats_answered
        self._give_windows()

    def attach_write_watch(self, watch: ctypes.Structure, check: int, views: list[tuple[int, int]],
                           what: str) -> None:
        """--check-writes: `check` (a C function's address, _write_watch.c's check_write) checks the
        precise engine's stores in `views` ((first, last) addresses) against `watch` (its
        write_watch_t, which the caller keeps alive); the fast engine checks its own stores against
        the same table (_write_check.h), so the hart stays on it. After a stray store `watch.stray`
        is set and the hart stops before its next instruction, on either engine."""
        for first, last in views:
            add_native_hook(self.uc, unicorn.UC_HOOK_MEM_WRITE, check, watch, first, last,
                             f"{what} on hart {self.hart_id}")
        self._write_watch = watch
        self._give_write_watch()

    def _give_write_watch(self) -> None:
        if self._fast_state is not None and self._write_watch is not None:
            counter_lib.fast_set_write_watch(self._fast_state, ctypes.byref(self._write_watch))

    def _stray_store_made(self) -> bool:
        return self._write_watch is not None and bool(self._write_watch.stray)

    def _give_windows(self) -> None:
        """Hands the device windows to the fast engine once both exist (the bus may attach first)."""
        if self._fast_state is None or not self._device_windows:
            return
        count = len(self._device_windows)
        bases = (ctypes.c_uint64 * count)(*(base for base, _ in self._device_windows))
        ends = (ctypes.c_uint64 * count)(*(end for _, end in self._device_windows))
        if not counter_lib.fast_set_windows(self._fast_state, bases, ends, count):
            raise ValueError(f"the fast engine takes at most 64 device windows, not {count}")

    def close(self) -> None:
        """Frees the fast engine."""
        if self._fast_state is not None:
            self._free_fast_state()
            self._fast_state = None

    def fast_statistics(self) -> dict[str, int]:
        """The fast engine's figures: instructions it ran, times it handed the hart over, blocks it
        decoded (again after a change of their code or a collision in its index)."""
        if self._fast_state is None:
            return {}
        out = (ctypes.c_uint64 * 3)()
        counter_lib.fast_statistics(self._fast_state, out)
        return {"instructions": out[0], "handoffs": out[1], "blocks_decoded": out[2]}

    def forget_decodings(self) -> None:
        """Drops the fast engine's decoded blocks: it decodes its instructions again (the counter's tables
        changed; the bench decoding afresh for each timed run)."""
        if self._fast_state is not None:
            counter_lib.fast_forget_decodings(self._fast_state)

    def arm_repeats(self, pc: int, address: int, width: int, value: int, until: Time, clock: tuple[Time, int, int],
                    repeats: int, needed: int) -> None:
        """During a device access the fast engine stopped at (a load of `width` bytes at `address` by
        the instruction at `pc`, which gave `value`): the same load again gives the same value and
        changes nothing while the hart's time is before `until` (clock: the hart's anchor time, anchor
        cycles and frequency, as Scheduler.time_at_cycles works the time out) and no other device access comes
        between. The fast engine answers it so itself, counting each as a poll from `repeats` on; at
        `needed` the hart polls, and its run ends there (the board hears it through repeats_answered)."""
        rep = self._fast_head.rep
        rep.pc, rep.address, rep.width, rep.value = pc, address, width, value
        rep.until = _first_cycle_at(until, *clock)
        rep.repeats, rep.needed, rep.answered, rep.polling, rep.armed = repeats, needed, 0, 0, 1

    def _run_fast(self, pc: int) -> int:
        """Runs the hart on the fast engine from `pc` until it reaches the counter's limits or an
        instruction it hands over, carrying out the device accesses it stops at on the way; the
        precise engine holds the hart's registers again after it. Returns the pc to go on from."""
        state, counter, uc = self._fast_state, self._counter_at, self._uc_at
        rep = self._fast_head.rep
        stop = fast_step(state, counter, uc, pc, False)    # the stop, or a device access (fast_step)
        while True:
            at_device = stop.__class__ is tuple
            if rep.armed:
                rep.armed = 0     # armed for one stretch of the interpreter: the board may change anything now
                if rep.answered:
                    self._holding = at_device
                    self._repeats_answered(self, rep.pc, rep.address, rep.value, rep.repeats, bool(rep.polling))
                    self._holding = False
            if not at_device:
                break
            _, window, address, width, is_store, stored, access_pc = stop
            self.device_accesses += 1
            self._holding = True
            try:
                value = self._device_access(self, window, address, width, bool(is_store), stored, access_pc)
            except BaseException:
                self._holding = False
                counter_lib.fast_abandon(state, self.uc._uch)
                raise
            self._holding = False
            if self.pending_exception is not None:
                # (defensive: the bus raises no exception for the aligned accesses it gets here today)
                counter_lib.fast_abandon(state, self.uc._uch)    # the access trapped: it does not complete
                break
            stop = fast_step(state, counter, uc, value, True)
        return self._fast_head.pc

    def run_fast_stretch(self, pc: int) -> int:
        """Runs the fast engine alone from `pc` until it hands the hart over or the counter's limits are
        reached, and returns the pc it stopped at (the bench timing the interpreter by itself; the
        board runs it through run)."""
        return self._run_fast(pc)

    def fast_usable(self) -> bool:
        """Whether the hart runs on the fast engine (it has one and no hook needs the precise one)."""
        return self._fast_usable()

    def run_alone(self, plan: AlonePlan) -> None:
        """Runs the turns `plan` describes on the fast engine, from `self.pc` (fast_run_alone)."""
        self.stop_requested = False
        self.pc = counter_lib.fast_run_alone(self._fast_state, ctypes.byref(self._counter), self.uc._uch, self.pc,
                                              ctypes.byref(plan))

    def run_pair(self, other: "Hart", plan) -> None:
        """Runs the turns `plan` (native.PairPlan) describes on the fast engine, this hart (hart 0) and
        `other` (hart 1) from their pcs, which the plan gives back (fast_run_pair)."""
        self.stop_requested = other.stop_requested = False
        counter_lib.fast_run_pair(self._fast_state, other._fast_state, ctypes.byref(self._counter),
                                  ctypes.byref(other._counter), self.uc._uch, other.uc._uch, ctypes.byref(plan))
        self.pc, other.pc = plan.pc[0], plan.pc[1]

    def _fast_usable(self) -> bool:
        # below M-mode Unicorn gives no CSR to the fast engine's register load (mstatus: FS), and
        # CSR accesses are the precise engine's anyway: S- and U-mode code runs there
        return self._fast_state is not None and not self._hooks_needing_precision and self.privilege == PRIV_M

    def install_poll_loops(self, loops: list[shared_memory.PollLoop]) -> None:
        """Hands the native counter the loops that can only be polling (shared_memory.py): it ends
        a run with RunEnd.POLL when the hart comes round one of them again."""
        if not loops:
            return
        slots, mask = shared_memory.loop_table(loops)
        self._loop_slots = slots
        for loop in loops:
            self.poll_loops[loop.head] = (loop, slots[(shared_memory.table_key(loop.head) >> 1) & mask])
        self._idle_spans = [(loop.head, loop.branch) for loop, _ in self.poll_loops.values() if not loop.loads]
        self._counter.loop_mask = mask
        self._counter.loops = ctypes.addressof(slots)
        self.forget_decodings()

    def install_time_loops(self, loops: list[TimeLoop]) -> None:
        """The loops that wait for time (time_loops.py): at their time read, the hart skips the
        iterations that cannot end the loop (time_loops.LoopSkipper)."""
        self.time_loops.update((loop.site, loop) for loop in loops)

    def skip_idle(self, loop: shared_memory.PollLoop) -> None:
        """The hart came round a loop that only spins again (time_loops.find_idle_loops): its
        iterations are counted without being run, up to the turn's end, or past it up to
        time_skip_limit (the scheduler's: the hart runs alone and nothing happens before then)
        unless a debug trigger is armed (skipped iterations would not be watched)."""
        beyond = None if self.triggers.armed else self.time_skip_limit
        self.skipper.at_idle(loop, self._turn_limit, beyond)

    def in_idle_loop(self) -> bool:
        """Whether the hart's pc is inside a loop that only spins (time_loops.find_idle_loops): a
        straight run of register arithmetic closed by a jump back, with no way out but an interrupt
        (or a reset), and no load, store or CSR access on the way."""
        pc = self.pc
        return any(head <= pc <= branch for head, branch in self._idle_spans)

    @property
    def iterations_skipped(self) -> int:
        """Loop iterations counted without being run (time_loops.py)."""
        return self.skipper.iterations

    def install_cycle_table(self, table: timing.CycleTable | None) -> None:
        """Has the native counter charge the cycles `table` gives (timing.py) instead of one
        cycle per instruction; None: one cycle each (--timing ipc1)."""
        self._cycle_table = table
        self.forget_decodings()
        if table is None:
            self._counter.table = None
            return
        self._counter.table = table.entries.ctypes.data
        self._counter.table_base = table.base
        self._counter.table_end = table.end

    def install_caches(self, caches: HartCaches | None) -> None:
        """Has both engines' counters charge the L1 caches' misses (caches.py); None: every access
        hits (--timing rocket-nocache and ipc1)."""
        self.caches = caches
        self._counter.caches = None if caches is None else ctypes.pointer(caches.state)
        self.forget_decodings()     # the fast engine marks the fetches the caches look at as it decodes

    def reset(self, pc: int) -> None:
        """A chip reset: the hart in M-mode at `pc` with its registers and the trap CSRs at 0,
        interrupts off, mcycle and minstret counting from 0 (Rocket's counters reset)."""
        uc = self.uc
        if self.privilege != PRIV_M:
            uc.reg_write(rv.UC_RISCV_REG_PRIV, PRIV_M)
            self.privilege = PRIV_M
        for register in range(rv.UC_RISCV_REG_X1, rv.UC_RISCV_REG_X31 + 1):
            uc.reg_write(register, 0)
        for register in range(rv.UC_RISCV_REG_F0, rv.UC_RISCV_REG_F31 + 1):
            uc.reg_write(register, 0)
        uc.reg_write(rv.UC_RISCV_REG_MSTATUS, MSTATUS_RESET)
        for register in (rv.UC_RISCV_REG_MIE, rv.UC_RISCV_REG_MTVEC, rv.UC_RISCV_REG_MEPC,
                         rv.UC_RISCV_REG_MCAUSE, rv.UC_RISCV_REG_MTVAL, rv.UC_RISCV_REG_MSCRATCH,
                         rv.UC_RISCV_REG_MIDELEG, rv.UC_RISCV_REG_MEDELEG):
            uc.reg_write(register, 0)
        self.mcycle_offset = -self.csr_context.mcycle()
        self.minstret_offset = -self.instret
        self.pending_exception = None
        self.open_trap = None
        self.polling = False
        self.skipper.forget()
        self.triggers.reset()
        self._watch_triggers()
        self.soft_mip = 0
        self.counter_enables = {PRIV_U: COUNTER_BITS, PRIV_S: COUNTER_BITS}
        self.forget_pending_transfer()
        self.forget_decodings()
        self.pc = pc
        self.state = HartState.RUNNING

    def forget_pending_transfer(self) -> None:
        """A trap or interrupt enters mtvec: the control transfer the counter last saw does not
        lead to the next instruction it will see, so it is not resolved (no misprediction)."""
        self._counter.pending_kind = 0
        self._counter.pending_penalty = 0

    def take_poll_report(self) -> tuple[shared_memory.PollLoop, shared_memory.LoopSlot]:
        """The poll loop the last run stopped for (and clears the report)."""
        head = self._counter.poll_report
        self._counter.poll_report = 0
        return self.poll_loops[head]

    @property
    def counter_address(self) -> int:
        """Host address of the native instruction counter (u64 executed, then u64 limit): a
        native hook ends the run after the current instruction by setting limit = executed."""
        return ctypes.addressof(self._counter)

    def _as_machine(self, access: Callable[[], int]) -> int:
        """Runs a Unicorn CSR access as M-mode does it, whatever mode the hart is in."""
        if self.privilege == PRIV_M:
            return access()
        self.uc.reg_write(rv.UC_RISCV_REG_PRIV, PRIV_M)
        try:
            return access()
        finally:
            self.uc.reg_write(rv.UC_RISCV_REG_PRIV, self.privilege)

    def reg(self, register: int) -> int:
        """A register's value, read straight through Unicorn's C API (the MMIO paths call
        this on every device access, where the Python wrapper's overhead shows), or from the fast
        engine while it holds the registers (a device access it left to the board)."""
        if self._holding:
            return self._held_reg(register)
        if self.privilege != PRIV_M and register not in _NOT_CSRS:
            return self._as_machine(lambda: self.uc.reg_read(register))
        _ucpy.uclib.uc_reg_read(self.uc._uch, register, self._reg_ref)
        return self._reg_value.value

    def _held_reg(self, register: int) -> int:
        """A register's value while the fast engine holds them (a device access it left to the bus)."""
        head = self._fast_head
        if rv.UC_RISCV_REG_X0 <= register <= rv.UC_RISCV_REG_X31:
            return head.x[register - rv.UC_RISCV_REG_X0] if register != rv.UC_RISCV_REG_X0 else 0
        if rv.UC_RISCV_REG_F0 <= register <= rv.UC_RISCV_REG_F31:
            return head.f[register - rv.UC_RISCV_REG_F0]
        if register == rv.UC_RISCV_REG_PC:
            return head.pc
        if register == rv.UC_RISCV_REG_MSTATUS:
            return head.mstatus
        if register in (rv.UC_RISCV_REG_FFLAGS, rv.UC_RISCV_REG_FRM, rv.UC_RISCV_REG_FCSR):
            raise RuntimeError("fcsr read while the fast engine holds the registers")
        _ucpy.uclib.uc_reg_read(self.uc._uch, register, self._reg_ref)   # a CSR the fast engine never writes
        return self._reg_value.value

    # --- counters --------------------------------------------------------------------

    @property
    def executed(self) -> int:
        """Instructions started since reset (the hook's count)."""
        return self._counter.executed

    @property
    def cycles(self) -> int:
        """CPU cycles the instructions started since reset take (the timing model's; equal to
        `executed` under --timing ipc1). Time asleep or waiting is not in it."""
        return self._counter.cycles

    @property
    def mispredicts(self) -> int:
        return self._counter.mispredicts

    @property
    def stall_cycles(self) -> int:
        """Cycles beyond one per instruction charged for stalls and flushes (not mispredictions)."""
        return self._counter.stall_cycles

    @property
    def instret(self) -> int:
        """Instructions retired since reset (what minstret counts)."""
        return self._counter.executed - self.retired_adjust

    # --- running ---------------------------------------------------------------------

    def run(self, budget: int, cycle_budget: int | None = None) -> tuple[RunEnd, int]:
        """Runs at most `budget` instructions from `self.pc`, and no instruction starts once
        `cycle_budget` cycles have been used (the last one may take a few cycles past it, as an
        instruction in flight does). Returns why it stopped and how many instructions ran."""
        counter = self._counter
        self._turn_limit = counter.executed + budget   # (skip_idle's bound, even when nothing runs here)
        if counter.poll_report:
            return RunEnd.POLL, 0     # run_alone stopped at a poll loop's head: nothing runs before it is seen
        if self._stray_store_made():
            return RunEnd.STOPPED, 0  # run_alone stopped after a stray store: the board ends the run
        start = counter.executed
        turn_limit = counter.limit = start + budget
        self._turn_limit = turn_limit             # (the precise engine's stretches stop before it)
        counter.cycle_limit = NO_LIMIT if cycle_budget is None else counter.cycles + cycle_budget
        self.stop_requested = False
        pc = self.pc
        while True:
            precise_limit = turn_limit
            if self._fast_usable():
                fast_from = counter.executed
                pc = self._run_fast(pc)
                if counter.poll_report or self.stop_requested or self.pending_exception is not None or \
                        self._stray_store_made():
                    break
                if counter.executed >= turn_limit or counter.cycles >= counter.cycle_limit:
                    self.pc = pc
                    return RunEnd.BUDGET, counter.executed - start
                # handed over: the precise engine runs the instruction, and a few more
                self._precise_stretch = (min(2 * self._precise_stretch, PRECISE_STRETCH_MAX)
                                         if counter.executed - fast_from < PRECISE_STRETCH else PRECISE_STRETCH)
                precise_limit = min(turn_limit, counter.executed + self._precise_stretch)
            counter.limit = precise_limit
            self._run_precise(pc)
            pc = self.reg(rv.UC_RISCV_REG_PC)
            if precise_limit < turn_limit and counter.limit == precise_limit and counter.executed >= precise_limit \
                    and not (self.stop_requested or self.pending_exception is not None or counter.poll_report
                             or counter.cycles >= counter.cycle_limit or self._slept_at(pc)):
                counter.limit = turn_limit    # the stretch the precise engine was given is done: back to fast
                continue
            if counter.limit == precise_limit:
                counter.limit = turn_limit
            break
        ran = self._counter.executed - start
        self.pc = self.reg(rv.UC_RISCV_REG_PC)
        if self.pending_exception is not None:
            return RunEnd.EXCEPTION, ran
        if self._counter.poll_report:
            return RunEnd.POLL, ran
        # a wfi ends the engine's run after it, even as the budget's last instruction (a turn
        # boundary must not make the hart skip its sleep)
        if ran > 0 and not self.stop_requested and self.read_u32(self.pc - 4) == INSN_WFI:
            return RunEnd.WFI, ran
        if ran >= budget or self._counter.cycles >= self._counter.cycle_limit:
            return RunEnd.BUDGET, ran
        return RunEnd.STOPPED, ran

    def _run_precise(self, pc: int) -> None:
        """Runs the precise engine from `pc` until its counter stops it, carrying out the CSR
        instructions the board answers on the way."""
        counter = self._counter
        self.precise_runs += 1
        while True:
            self.uc.emu_start(pc, 0)
            if counter.misaligned_pc:
                # the counter stopped before a misaligned access: counted, not retired, it traps
                cause = CAUSE_STORE_MISALIGNED if counter.misaligned_store else CAUSE_LOAD_MISALIGNED
                self.pending_exception = PendingException(cause, counter.misaligned_pc, counter.misaligned_address)
                self.retired_adjust += 1
                counter.misaligned_pc = 0
                return
            site = counter.csr_report
            if not site:
                return
            # the counter stopped at a CSR the board answers: it is counted and timed, not executed
            counter.csr_report = 0
            for listener in self.csr_listeners:
                listener(self, site)
            pc = self._carry_out_csr(site, self._csr_words[site])
            if self.pending_exception is not None or counter.poll_report or self.stop_requested or \
                    counter.executed >= counter.limit or counter.cycles >= counter.cycle_limit:
                self.uc.reg_write(rv.UC_RISCV_REG_PC, pc)
                return

    def _slept_at(self, pc: int) -> bool:
        """Whether the precise engine's last instruction was a wfi just before `pc`."""
        return self._counter.last_pc == pc - 4 and self.read_u32(pc - 4) == INSN_WFI

    def lift_limits(self, instructions: int | None = None) -> None:
        """The next engine run has no cycle limit, no instruction limit (or stops after
        `instructions` more) and does not stop at the CSRs the board answers (Unicorn answers them:
        mhartid reads 0, right for hart 0 only): the bench measuring Unicorn itself on hart 0. The
        board's own runs are not possible after this."""
        self._counter.limit = NO_LIMIT if instructions is None else self._counter.executed + instructions
        self._counter.cycle_limit = NO_LIMIT
        self._counter.csr_sites = None

    def remove_counter(self) -> None:
        """Takes the native counter out (the bench measuring Unicorn without it): the hart counts
        nothing from here on, so the board cannot run it any more."""
        self.remove_hook(self._counter_hook)

    def request_stop(self) -> None:
        """Ends the current run once the current instruction has completed: the native
        counter stops the engine before the next instruction starts. (uc.emu_stop called
        from an MMIO callback makes Unicorn 2.1.4 run the accessing instruction again when
        the hart resumes: a store would be repeated, a FIFO popped twice.)"""
        self.stop_requested = True
        self._counter.limit = min(self._counter.limit, self._counter.executed)

    def read_u32(self, address: int) -> int:
        try:
            return int.from_bytes(self.uc.mem_read(address, 4), "little")
        except unicorn.UcError:
            return 0

    def read_u16(self, address: int) -> int:
        try:
            return int.from_bytes(self.uc.mem_read(address, 2), "little")
        except unicorn.UcError:
            return 0

    # --- exceptions and interrupts ---------------------------------------------------

    def _on_exception(self, uc: unicorn.Uc, intno: int, user_data: object) -> None:
        # Unicorn 2.1.4 moves the pc 4 bytes past the faulting instruction before calling
        # this hook, whatever the instruction's length (a 2-byte c.unimp too), so the
        # faulting instruction is always at pc - 4.
        epc = uc.reg_read(rv.UC_RISCV_REG_PC) - 4
        # QEMU reports every ecall as U-mode's number; the cause says the mode it came from
        cause = CAUSE_ECALL_U + self.privilege if intno == CAUSE_ECALL_U else intno
        tval = 0
        if cause == CAUSE_ILLEGAL_INSTRUCTION:
            low = self.read_u16(epc)
            tval = low if low & 3 != 3 else self.read_u32(epc)
        self.pending_exception = PendingException(cause, epc, tval)
        self.retired_adjust += 1
        uc.emu_stop()

    def note_breakpoint(self) -> None:
        """Unicorn ends a run with an error at ebreak; turn that into the breakpoint exception."""
        self.pc = self.uc.reg_read(rv.UC_RISCV_REG_PC)
        self.pending_exception = PendingException(CAUSE_BREAKPOINT, self.pc, self.pc)

    def wake(self) -> None:
        """The hart runs on (a trap taken from wfi or a wait)."""
        self.state = HartState.RUNNING

    def csr(self, reg: int) -> int:
        return self._as_machine(lambda: self.uc.reg_read(reg))

    def set_reg(self, register: int, value: int) -> None:
        """Writes a register (x, f, pc or a Unicorn CSR) of a hart that is not running (a debugger)."""
        if register == rv.UC_RISCV_REG_PC:
            self.pc = value
        if self.privilege != PRIV_M and register not in _NOT_CSRS:
            self.set_csr(register, value)
        else:
            self.uc.reg_write(register, value)

    # --- what the bus maps into the hart's engines ---------------------------------------

    def map_memory(self, address: int, size: int, host_address: int) -> None:
        """Memory at `address` (SRAM, or one of its views) backed by host memory at `host_address`."""
        self.uc.mem_map_ptr(address, size, unicorn.UC_PROT_ALL, host_address)

    def map_device(self, address: int, size: int, read: Callable, write: Callable) -> None:
        """A device window: loads call read(uc, offset, width, None), stores
        write(uc, offset, width, value, None), as Unicorn's MMIO callbacks do.

        One pair of native callbacks serves every window of the hart, told apart by the window's
        index: the binding's own mmio_map makes a pair a window (two dozen windows a hart, a quarter
        of a board's making) and calls through two more Python frames each access."""
        if self._window_thunks is None:
            self._window_thunks = (_ucpy.MMIO_READ_CFUNC(self._window_read),
                                   _ucpy.MMIO_WRITE_CFUNC(self._window_write))
        index = len(self._windows_read)
        self._windows_read.append(read)
        self._windows_write.append(write)
        status = _ucpy.uclib.uc_mmio_map(self.uc._uch, address, size, self._window_thunks[0], index,
                                         self._window_thunks[1], index)
        if status != unicorn.UC_ERR_OK:
            raise unicorn.UcError(status)

    def _window_read(self, handle, offset: int, size: int, index: int | None) -> int:
        try:
            return self._windows_read[index or 0](self.uc, offset, size, None)
        except BaseException as error:      # as the binding's own callbacks: stop, raised by emu_start
            self._hook_failed(error)
            return 0

    def _window_write(self, handle, offset: int, size: int, value: int, index: int | None) -> None:
        try:
            self._windows_write[index or 0](self.uc, offset, size, value, None)
        except BaseException as error:
            self._hook_failed(error)

    def _hook_failed(self, error: BaseException) -> None:
        """What the binding does with an exception in a callback (unicorn 2.1.4's uccallback, which
        map_device no longer goes through; pyproject.toml pins that version): the first is kept in
        the binding's own _hook_exception, emulation stops, and emu_start raises it."""
        if self.uc._hook_exception is None:
            self.uc._hook_exception = error
        self.uc.emu_stop()

    def on_unmapped(self, callback: Callable) -> None:
        """Accesses and fetches where nothing is mapped (or not as asked) call
        callback(uc, access, address, size, value, user_data)."""
        self.uc.hook_add(unicorn.UC_HOOK_MEM_UNMAPPED | unicorn.UC_HOOK_MEM_FETCH_PROT | unicorn.UC_HOOK_MEM_READ_PROT
                         | unicorn.UC_HOOK_MEM_WRITE_PROT, callback)

    def code_written(self, start: int, end: int) -> None:
        """Code in [start, end) may have changed from outside the harts (a debugger's write): what
        either engine decoded from it is dropped."""
        self.uc.ctl_remove_cache(start, end)
        self.forget_decodings()

    def set_csr(self, reg: int, value: int) -> None:
        """Writes a Unicorn CSR as M-mode does (a debugger's write), whatever mode the hart is in."""
        if self.privilege != PRIV_M:
            self.uc.reg_write(rv.UC_RISCV_REG_PRIV, PRIV_M)
        try:
            self.uc.reg_write(reg, value)
        finally:
            if self.privilege != PRIV_M:
                self.uc.reg_write(rv.UC_RISCV_REG_PRIV, self.privilege)

    # --- CSR interception --------------------------------------------------------------

    def intercept_csr_sites(self, sites: list[tuple[int, int]]) -> None:
        """Has the native counter stop before each (address, instruction word) that accesses an
        intercepted CSR, so that `run` carries it out."""
        self._csr_words.update(sites)
        if not self._csr_words:
            return
        table, mask = address_table(list(self._csr_words))
        self._csr_table = table
        self._counter.csr_sites = ctypes.addressof(table)
        self._counter.csr_mask = mask
        self.forget_decodings()

    def add_stop_hook(self, callback: Callable, user_data: object, begin: int, end: int) -> int:
        """A Python code hook (a debugger's breakpoint or step) that runs before the native
        counter on every instruction of begin..end: Unicorn calls code hooks in the order they
        were added and skips the rest once one stops the engine, so an instruction the hook
        stops before is neither counted nor timed. The counter is added again after it."""
        self.remove_hook(self._counter_hook)
        handle = self.uc.hook_add(unicorn.UC_HOOK_CODE, callback, user_data, begin, end)
        self._counter_hook = self.add_native_hook(unicorn.UC_HOOK_CODE, COUNT_HOOK, self._counter, 1, 0,
                                                  "the instruction counter")
        self.uc.ctl_flush_tb()   # see add_hook
        self._hooks_needing_precision.add(handle)
        return handle


def _first_cycle_at(until: Time, anchor: Time, start: int, hz: int) -> int:
    """The least cycle count c at which the hart's time anchor + cycles_time(c - start, hz)
    (Scheduler.time_at_cycles) is `until` or later; NO_LIMIT if never."""
    if until >= NEVER:
        return NO_LIMIT
    return min(start + cycles_reaching(until - anchor, hz), NO_LIMIT)
