"""The board's clock and scheduler: virtual time, the harts and their turns, deadlines, hangs.

Harts run in turn, in quanta of CPU cycles (what each instruction costs is timing.py's:
the K210's Rocket core by default, one cycle per instruction with --timing ipc1), and a
quantum never runs past the next moment a device changes state by itself (by more than the
cycles of the instruction in flight), so
interrupts and DMA completions are seen on time. A hart that sleeps in WFI, or that
keeps polling a device register that cannot change before the next device event,
costs no host time: the scheduler moves time forward instead. A hart that polls SRAM
waits until another hart's store (or a DMA write) changes what it reads, and then runs
before the storer goes on; after such a hand-over, and at reset, the harts run in
lockstep for a moment (shared_memory.py).

mcycle and mtime are integrals of the CPU clock over virtual time; a clock change
(SYSCTL) starts a new epoch. Exceptions enter the firmware's trap handler and the run goes on.
A run ends when the requested frames have been shown, or with a BoardStop: the firmware's fatal
error report (after a grace period), a trap that ended the program (its handler never returned
and then no hart could go on), a trap storm, a hang, or a stop recorded by the bus. A chip reset
(a watchdog, SYSCTL's soft_reset) is carried out between turns (Board.reset_chip).
"""
from __future__ import annotations

import time as host_time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable, Protocol

import numpy as np
import unicorn
from unicorn import riscv_const as rv

from ..cpu import shared_memory
from ..cpu.native import QUIET_ENDS_MAX, AlonePlan, PairPlan
from .deadlines import Deadlines
from .sram_waits import SramWaits
from .traps import Traps
from ..errors import BoardStop, FirmwareTrap
from ..cpu.hart import CsrContext, Hart, HartState, RunEnd
from ..memory_map import RESET_PC
from ..vtime import NEVER, PS_PER_MS, PS_PER_S, Time, cycles_in, cycles_reaching, cycles_time, ms

if TYPE_CHECKING:
    from ..devices.mmio import Peripheral
    from ..devices.st7789v import ST7789V
    from ..devices.sysctl import Sysctl
    from ..devices.uarths import Uarths
    from .elf import LoadedImage
    from .memory import Sram

HARTS = 2
DEFAULT_QUANTUM = 20_000          # CPU cycles per hart per turn
DEFAULT_HANG_BUDGET = 5 * PS_PER_S   # virtual time without a new frame before a run counts as hung
POLL_REPEATS = 8                  # identical reads at one pc before a hart counts as polling
# After the last requested frame the run goes on this long at most, so that the console line
# the firmware begins after that frame (this firmware's "frame N") is not cut off.
CONSOLE_DRAIN = 5 * PS_PER_MS
MTIME_DIVIDER = 50                # mtime ticks at CPU clock / 50
NO_POLL = (-1, -1, -1, 0)
UNLIMITED_FRAMES = 1 << 62        # run_until: no frame count ends a turn
# The most turns _go_on_alone runs on one call: the run loops look at the host's clock (progress
# reports) and at the trap deadline between calls, a firmware that spins alone without devices
# would otherwise run in one call until the hang budget.
MAX_TURNS_ALONE = 256
# _go_on_paired's tries cost the host a look at the interrupts and the next device event: after a try
# that ran fewer than two turns, the next 1, 2, 4 ... up to this many tries are let pass (the turns
# they would have run run one by one, with the same outcome)
PAIR_BACKOFF_MAX = 64


@dataclass
class FrameRecord:
    index: int
    virtual_time_s: float            # when its last data reached the LCD (a report: seconds)
    instructions: list[int]          # per hart, since the previous frame
    instructions_total: list[int]    # per hart, since reset
    host_time_s: float
    cycles: list[int] = field(default_factory=list)         # per hart, executing, since the previous frame
    cycles_total: list[int] = field(default_factory=list)   # per hart, executing, since reset
    host_cpu_s: float = 0.0          # the process's CPU time since the run began (host_time_s: wall)


@dataclass
class RunResult:
    exit: str
    message: str
    frames: list[FrameRecord]
    virtual_time_s: float
    instructions: list[int]
    host_time_s: float
    warnings: list[str] = field(default_factory=list)
    cycles: list[int] = field(default_factory=list)   # per hart: cycles spent executing (not asleep)


class TurnObserver(Protocol):
    """What the bus does around a hart's turn (bus.py), and what it counts (traps.py's storm watch)."""

    device_writes: dict[str, list[int]]

    def turn_begins(self, hart: Hart) -> None: ...

    def turn_ended(self, hart: Hart) -> BoardStop | None: ...

    def is_sram(self, address: int) -> bool: ...


class Board(Protocol):
    """What the scheduler asks of the board it runs (dock.py's Board): its parts, the interrupt
    and device-event questions that span the devices, and its reports."""

    bus: TurnObserver
    memory: "Sram"
    image: "LoadedImage"
    lcd: "ST7789V"
    sysctl: "Sysctl"
    uarths: "Uarths"
    peripherals: "list[Peripheral]"
    on_frame: Callable[[FrameRecord, np.ndarray], None]
    completed_line_began: Time
    warnings: list[str]

    def mip(self, h: int, now: Time, mask: int = ~0) -> int: ...

    def next_device_event(self, now: Time, past_quiet_console: bool = False) -> Time | None: ...

    def advance_devices(self, now: Time) -> None: ...

    def earliest_frame_capture(self, now: Time) -> Time: ...

    def loop_cycles_bound(self, instructions: int) -> int: ...

    def disassemble_at(self, pc: int) -> str: ...

    def recent_warnings(self, count: int) -> list[str]: ...

    def reset_chip(self, cause: str, at: Time) -> None: ...

    def interrupts_may_have_changed(self, now: Time | None = None) -> None: ...


class Scheduler(SramWaits, Deadlines):
    """Owns virtual time and the harts; runs them in turns between device events (harts waiting
    on SRAM: sram_waits.py; grace periods and hangs: deadlines.py)."""

    def __init__(self, board: Board, quantum: int, hang_budget: Time) -> None:
        self.board = board
        self.quantum = quantum
        self.hang_budget = hang_budget
        self.time: Time = 0
        self.delivery_time: Time = 0                      # when data last reached the LCD
        # clock epochs: cycles and mtime are integrals of the CPU clock over virtual time
        self._epoch_time: Time = 0
        self._epoch_cycles = 0
        self._epoch_mtime = 0
        self._hz = board.sysctl.cpu_hz()
        # per-run state
        self.frames: list[FrameRecord] = []
        self.frames_wanted = 0
        self._last_frame_time: Time = 0
        self._last_frame_instret = [0] * HARTS
        self._last_frame_cycles = [0] * HARTS
        self._start_host_clocks()
        self.until: Time | None = None                    # run_until's end: virtual time, not frames
        self.pending_stop: BoardStop | None = None        # ends the run at the end of the turn
        self._draining = False                            # finish_console_line is running
        self._frame_while_draining = False
        self.current: Hart | None = None                  # the hart whose turn it is
        self.turn_horizon: Time = 0
        # per hart: (time, cycle count) when its time was last set other than by running, since when
        # its time is that plus the time of the cycles it has run (hart_now): exact, whatever the turns
        self._anchor: list[tuple[Time, int]] = [(0, 0)] * HARTS
        self._poll = [NO_POLL] * HARTS
        self._grabs: list[tuple[Time, Callable[["Board"], None]]] = []
        self.host_time_in_harts = 0.0                     # host seconds spent executing guest code
        self.traps = Traps(board)                         # exceptions and interrupts entering mtvec
        self._error_report: tuple[int, str] | None = None
        self._trap_deadline: Time | None = None           # a grace period before the run may end
        self.reset_requested: tuple[str, Time] | None = None    # a chip reset, carried out after the turn
        self.resets: list[tuple[Time, str]] = []          # (virtual time, cause) of every chip reset
        self.harts = [Hart(h, CsrContext(mcycle=self._mcycle_reader(h), mip=self._mip_reader(h)))
                      for h in range(HARTS)]
        # both harts start together: what one stores at once the other may be polling already
        self._race_until = cycles_time(shared_memory.RACE_WINDOW_CYCLES, self._hz)
        self._priority: tuple[Hart, int] | None = None    # a hart woken by a store, and its turn's length
        # per hart: the poll loop it last came round without waiting, and what that loop read then
        self._poll_seen: dict[int, tuple[int, list[bytes], int]] = {}   # hart: (loop head, what it read, executed)
        self._alone_plan = AlonePlan()
        self._pair_plan = PairPlan()
        self.pairing = True           # both harts' turns run in C between device events (_go_on_paired)
        self.paired_turns = 0         # statistics: the turns _go_on_paired ran
        self._pair_backoff = 0        # tries to let pass after one that ran fewer than two turns
        self._pair_skip = 0           # tries still to let pass

    def _start_host_clocks(self) -> None:
        """A run's host time counts from here, wall and CPU (FrameRecord, RunResult)."""
        self._host_start = host_time.perf_counter()
        self._host_cpu_start = host_time.process_time()

    def _mcycle_reader(self, h: int) -> Callable[[], int]:
        return lambda: self.cycles(self.hart_now(self.harts[h]))

    def _mip_reader(self, h: int) -> Callable[[], int]:
        return lambda: self.board.mip(h, self.hart_now(self.harts[h]))

    def stop(self, error: BoardStop) -> None:
        """Records why the run ends (the first reason counts); the run ends after this turn."""
        if self.pending_stop is None:
            self.pending_stop = error

    # --- virtual clock -----------------------------------------------------------------

    def cpu_hz(self) -> int:
        return self._hz

    def hart_now(self, hart: Hart) -> Time:
        """The virtual time a hart has reached (mid-turn: counting its instructions so far)."""
        if hart is self.current:
            return self.time_at_cycles(hart, hart.cycles)
        return hart.time

    def time_at_cycles(self, hart: Hart, cycles: int) -> Time:
        """When a running hart's cycle count reaches `cycles`: its anchor's time and the time of the
        cycles since (rounded up once, from the anchor, so never depending on where turns ended)."""
        time, start = self._anchor[hart.hart_id]
        return time + cycles_time(cycles - start, self._hz)

    def cycles_until(self, hart: Hart, time: Time) -> int:
        """The least cycle count at which the hart's time (time_at_cycles) is `time` or later."""
        anchor, start = self._anchor[hart.hart_id]
        return start + cycles_reaching(time - anchor, self._hz)

    def turn_clock(self, hart: Hart) -> tuple[Time, int, int]:
        """The running hart's time is t + cycles_time(cycles - start, hz) (time_at_cycles): (t, start, hz)."""
        time, start = self._anchor[hart.hart_id]
        return time, start, self._hz

    def move_hart(self, hart: Hart, time: Time) -> None:
        """A hart's time moves on other than by running (it slept, waited, polled, was reset): it
        goes on from here."""
        if time != hart.time:
            hart.time = time
            self._anchor[hart.hart_id] = (time, hart.cycles)

    def cycles(self, now: Time) -> int:
        return self._epoch_cycles + cycles_in(now - self._epoch_time, self._hz)

    def mtime(self, now: Time) -> int:
        return self._epoch_mtime + cycles_in(now - self._epoch_time, self._hz) // MTIME_DIVIDER

    def time_of_mtime(self, value: int) -> Time | None:
        if value >= 1 << 63:
            return None
        return self._epoch_time + cycles_time((value - self._epoch_mtime) * MTIME_DIVIDER, self._hz)

    def set_mtime(self, value: int, now: Time) -> None:
        self._rebase(now)
        self._epoch_mtime = value

    def _rebase(self, now: Time) -> None:
        self._epoch_cycles = self.cycles(now)
        self._epoch_mtime = self.mtime(now)
        self._epoch_time = now

    def lcd_data_delivered(self, now: Time) -> None:
        """Data reached the LCD at `now` (a frame's time is when its last data arrived)."""
        self.delivery_time = now

    def clock_changed(self, now: Time) -> None:
        """SYSCTL changed the CPU clock: later cycles take the new cycle time. Every hart's time is
        anchored where it is (the running one's at the change), its later cycles at the new rate."""
        self._rebase(now)
        for hart in self.harts:
            self._anchor[hart.hart_id] = (self.hart_now(hart), hart.cycles)
        self._hz = self.board.sysctl.cpu_hz()
        if self.current is not None:
            self.current.request_stop()

    # --- polling ----------------------------------------------------------------------------

    def note_poll(self, hart: Hart, pc: int, address: int, value: int) -> None:
        """Repeated identical reads of one register from one pc: the hart is polling. It
        stops for the rest of its turn; time, not its loop, is what will change the value."""
        last_pc, last_address, last_value, repeats = self._poll[hart.hart_id]
        if (pc, address, value) == (last_pc, last_address, last_value):
            repeats += 1
            if repeats >= POLL_REPEATS:
                hart.polling = True
                hart.request_stop()
                repeats = 0
        else:
            repeats = 1
        self._poll[hart.hart_id] = (pc, address, value, repeats)

    def poll_count(self, hart: Hart, pc: int, address: int, value: int) -> int:
        """How many identical reads note_poll has counted that this one would continue (0: none)."""
        last_pc, last_address, last_value, repeats = self._poll[hart.hart_id]
        return repeats if (pc, address, value) == (last_pc, last_address, last_value) else 0

    def repeats_answered(self, hart: Hart, pc: int, address: int, value: int, repeats: int, polling: bool) -> None:
        """The fast engine answered the same read again itself (Hart.arm_repeats), counting the
        reads as note_poll does: its count now, and whether it found the hart polling."""
        self._poll[hart.hart_id] = (pc, address, value, repeats)
        if polling:
            hart.polling = True
            hart.request_stop()

    def forget_poll(self, hart: Hart) -> None:
        """A store to a device: whatever the hart polled next may change because of it."""
        self._poll[hart.hart_id] = NO_POLL

    # --- interrupts ---------------------------------------------------------------------------

    def interrupts_may_have_changed(self, now: Time | None = None) -> None:
        """A device changed an interrupt input at `now`: sleeping harts it concerns wake
        then, and a running hart with interrupts enabled ends its turn to take it."""
        self._wake_sleepers(self.time if now is None else now)
        hart = self.current
        if hart is not None:
            hart.time_skip_limit = None             # the turn's long-skip limit predates the change
        if hart is not None and hart.interrupts_enabled():
            hart.request_stop()

    def _wake_sleepers(self, now: Time) -> None:
        """Harts asleep in wfi with an enabled interrupt pending wake; so do harts polling SRAM when
        they would take the interrupt (privileged.py: takeable_interrupts)."""
        for hart in self.harts:
            if hart.state is HartState.RUNNING:
                continue
            if hart.state is HartState.WAITING:
                enabled = hart.takeable_interrupts()
            else:
                enabled = hart.reg(rv.UC_RISCV_REG_MIE)   # wfi wakes on any enabled interrupt
            if enabled and self.board.mip(hart.hart_id, now, enabled):
                if hart.state is HartState.WAITING:
                    self._end_wait(hart, now, by_store=False)
                hart.state = HartState.RUNNING
                self.move_hart(hart, max(hart.time, now))

    # --- frames and grabs ---------------------------------------------------------------------

    def frame_captured(self, image: np.ndarray) -> None:
        if self._draining:
            # a frame beyond the requested ones: not recorded, and the drain ends here
            self._frame_while_draining = True
            if self.current is not None:
                self.current.request_stop()
            return
        totals = [h.instret for h in self.harts]
        cycles = [h.cycles for h in self.harts]
        record = FrameRecord(
            index=len(self.frames),
            virtual_time_s=self.delivery_time / PS_PER_S,
            instructions=[t - last for t, last in zip(totals, self._last_frame_instret)],
            instructions_total=totals,
            host_time_s=host_time.perf_counter() - self._host_start,
            host_cpu_s=host_time.process_time() - self._host_cpu_start,
            cycles=[c - last for c, last in zip(cycles, self._last_frame_cycles)],
            cycles_total=cycles,
        )
        self._last_frame_instret = totals
        self._last_frame_cycles = cycles
        self._last_frame_time = self.delivery_time
        self.frames.append(record)
        self.board.on_frame(record, image)
        if len(self.frames) >= self.frames_wanted and self.current is not None and self._trap_deadline is None:
            self.current.request_stop()

    def grab_at(self, at: Time, action: Callable[["Board"], None]) -> None:
        """Calls action(board) once the board's virtual time reaches `at` (a framebuffer grab)."""
        if self.current is not None:
            self.current.time_skip_limit = None     # asked mid-turn: the turn's long-skip limit predates it
        self._grabs.append((at, action))
        self._grabs.sort(key=lambda item: item[0])

    def _run_grabs(self) -> None:
        while self._grabs and self._grabs[0][0] <= self.time:
            _, action = self._grabs.pop(0)
            action(self.board)

    # --- the run loop --------------------------------------------------------------------------

    def run(self, frames: int, progress: Callable[["Board"], None] | None = None) -> RunResult:
        """Runs until `frames` frames have been shown. Raises a BoardStop subclass otherwise."""
        self.frames_wanted = frames
        self._start_host_clocks()
        last_progress = 0.0
        # a firmware that reported an error or trapped is given its grace period even when
        # its error screen was the last frame asked for: the run ends with that error
        while len(self.frames) < frames or self._trap_deadline is not None:
            self.step(go_on_alone=True)
            if self._grabs:
                self._run_grabs()
            if progress is not None and host_time.perf_counter() - last_progress > 0.5:
                last_progress = host_time.perf_counter()
                progress(self.board)
        return RunResult("ok", f"{len(self.frames)} frames shown", self.frames, self.time / PS_PER_S,
                         [h.instret for h in self.harts], host_time.perf_counter() - self._host_start,
                         self.board.warnings, [h.cycles for h in self.harts])

    def run_until(self, until: Time, progress: Callable[["Board"], None] | None = None) -> RunResult:
        """Runs until virtual time `until` (--until), for firmware whose output is
        its console or its pins rather than frames: frames shown meanwhile are recorded but end
        nothing, and no frame budget applies. Once every hart sleeps in wfi with nothing that
        could ever wake it, time moves straight on to `until`. A trap, an error report or a
        stop recorded by a device ends the run as in run()."""
        self.frames_wanted = UNLIMITED_FRAMES
        self.until = until
        self._start_host_clocks()
        last_progress = 0.0
        idle_since: Time | None = None
        while self.time < until or self._report_pending():
            if not self._report_pending() and self.waits_for_outside():
                since = self.time
                if self._idle_to(until):
                    idle_since = since
                    break
                continue
            self.step(go_on_alone=True)
            if self._grabs:
                self._run_grabs()
            if progress is not None and host_time.perf_counter() - last_progress > 0.5:
                last_progress = host_time.perf_counter()
                progress(self.board)
        message = f"ran until {ms(until)} of virtual time; {len(self.frames)} frames shown"
        if idle_since is not None:
            message += f"; from {ms(idle_since)} every hart slept in wfi with nothing that could wake it"
        return RunResult("ok", message, self.frames, self.time / PS_PER_S, [h.instret for h in self.harts],
                         host_time.perf_counter() - self._host_start, self.board.warnings,
                         [h.cycles for h in self.harts])

    def _idle_to(self, until: Time) -> bool:
        """Nothing moves by itself (waits_for_outside): time moves on to the next grab before `until`,
        which may set something going (a script's send; False: the caller looks again), or else
        straight to `until` (True)."""
        if self._grabs and self._grabs[0][0] < until:
            self._set_time(max(self.time, self._grabs[0][0]))
            self._run_grabs()
            return False
        self._set_time(until)
        if self._grabs:
            self._run_grabs()
        return True

    def waits_for_outside(self) -> bool:
        """No hart runs and no device will do anything by itself: only something from outside (a pad
        driven, a byte sent to a UART) can set the board going again."""
        return not any(h.state is HartState.RUNNING for h in self.harts) and \
            self.board.next_device_event(self.time) is None

    def run_slice(self, until: Time, frames: int = UNLIMITED_FRAMES, last: bool = False) -> bool:
        """Runs until virtual time `until`, or until `frames` frames have been shown in all, for a
        caller that runs the board a piece at a time and looks at other things in between (the live
        view, frontends/view.py: its page's controls, its pacing to the host's clock). As in
        run_until no frame budget applies (the board is watched), and a board on which nothing can
        happen any more moves straight on to `until`; as in run(), a trap handler's grace period is
        run out before `frames` end the run. `last`: `until` is the run's end, which, as in
        run_until, an error report waiting out its grace period goes past. A trap, an error report
        or a stop ends the run as in run(). Returns whether the run may end here: `frames` shown, or
        with `last`, `until` reached."""
        self.frames_wanted = frames
        before, self.until = self.until, until
        try:
            while self.time < until or (last and self._report_pending()):
                if len(self.frames) >= frames and self._trap_deadline is None:
                    return True
                if not self._report_pending() and self.waits_for_outside():
                    if self._idle_to(until):
                        break
                    continue
                self.step(go_on_alone=True)
                if self._grabs:
                    self._run_grabs()
        finally:
            self.until = before
        return (len(self.frames) >= frames and self._trap_deadline is None) or last

    def finish_console_line(self, limit: Time = CONSOLE_DRAIN) -> None:
        """After run(): runs on until the first console line begun after the last frame was
        shown has ended (this firmware's hart 1 reports "frame N" once frame N is sent, after
        the LCD has it), for at most `limit` of virtual time, so that the console of an N-frame
        run ends with its last frame's line. Frames shown meanwhile are not recorded and end
        it; so does a firmware that will never do anything again. A trap or error report
        meanwhile gets its grace period and ends the run as in run(). Kept out of run() so
        that a run's instruction counts up to its last frame (the bench's) do not change."""
        frame_time = self._last_frame_time
        deadline = self.time + limit
        self._draining, self._frame_while_draining = True, False
        self.frames_wanted = len(self.frames) + 1     # turn() moves time on as before a frame
        try:
            while (self.board.completed_line_began < frame_time and self.time < deadline
                   and not self._frame_while_draining and self._trap_deadline is None):
                if not any(h.state is HartState.RUNNING for h in self.harts) and \
                        self.board.next_device_event(self.time) is None:
                    break
                self.step()
                if self._grabs:
                    self._run_grabs()
        finally:
            self._draining = False
            self.frames_wanted = len(self.frames)
        while self._trap_deadline is not None:
            self.step()

    def step(self, go_on_alone: bool = False) -> None:
        """One turn (see _turn; with go_on_alone, a hart running alone may run the turns after it
        as well, _go_on_alone); a stop recorded by a device outside a hart's turn (a stray DMA write
        while every hart sleeps) ends the run here. Single turns for whoever steps the board and
        looks at it in between (the tests, the GDB server's wait for a connection)."""
        self._turn(go_on_alone)
        if self.reset_requested is not None:
            self._reset_chip()
        if self.pending_stop is not None:
            raise self.pending_stop

    def request_reset(self, cause: str, at: Time) -> None:
        """A watchdog or SYSCTL's soft_reset resets the chip at `at`: carried out after the turn,
        when no hart is in the middle of an instruction (a hart running asks to stop)."""
        if self.reset_requested is None:
            self.reset_requested = (cause, at)
        if self.current is not None:
            self.current.request_stop()

    def _reset_chip(self) -> None:
        """Every hart back at the reset pc, as the mask ROM jumps there after a reset, with
        everything it was waiting for forgotten; the board resets the devices (Board.reset_chip)."""
        cause, at = self.reset_requested
        self.reset_requested = None
        for hart in self.harts:
            if hart.wait is not None:
                self._end_wait(hart, at, by_store=False)
        self.board.reset_chip(cause, at)
        self.clock_changed(at)
        for hart in self.harts:
            hart.reset(RESET_PC)
            hart.time = max(hart.time, at)
            self._anchor[hart.hart_id] = (hart.time, hart.cycles)   # (whether or not its time moved)
        self.traps.chip_reset()
        self._trap_deadline = None
        self._poll = [NO_POLL] * HARTS
        self._poll_seen.clear()
        self._priority = None
        self._race_until = max(self._race_until, at + cycles_time(shared_memory.RACE_WINDOW_CYCLES, self._hz))
        self.resets.append((at, cause))
        self.board.interrupts_may_have_changed(at)

    def _turn(self, go_on_alone: bool = False) -> None:
        """One turn: the running hart that is furthest behind in virtual time runs until
        its quantum ends, the next device event, or one quantum past the other hart."""
        board = self.board
        running = [h for h in self.harts if h.state is HartState.RUNNING]
        if not running:
            # every hart sleeps in wfi (or waits on SRAM): time moves on to the next thing a device does
            wake = board.next_device_event(self.time)
            if self.until is not None and (wake is None or wake > self.until):
                wake = max(self.until, self.time)   # run_until ends there; nothing happens before
            if wake is None:
                if any(h.state is HartState.WAITING for h in self.harts):
                    self._report_hang("no hart runs: every hart sleeps in wfi or polls memory that nothing "
                                      "will change, and no device will ever raise an interrupt")
                self._report_hang("every hart sleeps in wfi and no device will ever raise an interrupt")
            if self._grabs and self.time < self._grabs[0][0] < wake:
                wake = self._grabs[0][0]   # stop at a requested grab rather than jump past it
            self._set_time(wake)
            self._check_deadlines()
            return
        hart, priority_turn = min(running, key=lambda h: (h.time, h.hart_id)), 0
        if self._priority is not None:
            if self._priority[0] in running:
                hart, priority_turn = self._priority
            self._priority = None
        self.traps.take_interrupt(hart)
        t0, start = hart.time, hart.cycles
        outer = self._outer_bound(t0, board.next_device_event(t0))
        horizon = min(self.time_at_cycles(hart, start + self.quantum), outer)
        instruction_limit = None
        alone = False
        if priority_turn:
            # one iteration of the loop it woke in, counted in instructions: its cycles vary, and a
            # turn longer than the iteration would run the woken hart on past what the storer does next
            horizon = min(horizon, self.time_at_cycles(hart, start + self.board.loop_cycles_bound(priority_turn)))
            instruction_limit = priority_turn
        elif t0 < self._race_until:
            # lockstep: a hart behind catches up exactly, one level with the others runs RACE_TURN
            # cycles (an instruction of several cycles runs whole), so that every cycle is run by
            # each hart in turn, lowest hart first
            for other in running:
                if other is not hart:
                    horizon = min(horizon, other.time if other.time > t0 else
                                  self.time_at_cycles(hart, start + shared_memory.RACE_TURN))
        else:
            for other in running:
                if other is not hart:
                    horizon = min(horizon, other.time + cycles_time(self.quantum, self._hz))
            alone = go_on_alone and all(other is hart or self._inert(other) for other in running)
        budget = max(1, self.cycles_until(hart, horizon) - start)
        self.turn_horizon = self.time_at_cycles(hart, start + budget)
        precise_runs, device_accesses = hart.precise_runs, hart.device_accesses
        hart.time_skip_limit = self._alone_until(hart, t0, outer) if alone else None
        self._run_hart(hart, budget, instruction_limit)
        hart.time_skip_limit = None
        if self.pending_stop is not None:
            raise self.pending_stop
        hart.time = self.time_at_cycles(hart, hart.cycles)
        clean = hart.precise_runs == precise_runs and hart.device_accesses == device_accesses
        if alone and clean:
            horizon = self._go_on_alone(hart, t0, outer, horizon)
        if self._finish_turn(hart, horizon) and go_on_alone and not alone and clean and not priority_turn:
            self._go_on_paired()

    def _finish_turn(self, hart: Hart, horizon: Time) -> bool:
        """After a hart's turn (up to `horizon`): a wfi with an interrupt pending falls through, harts
        waiting on what it stored wake, a hart that polls waits for the next device event, and the
        board catches up with the running harts. False when the frames asked for are all shown (the
        board's time then moves on to the last one's delivery, and no more turns are run here)."""
        board = self.board
        if hart.state is HartState.ASLEEP:
            # a wfi with an enabled interrupt already pending falls through (the privileged spec:
            # WFI resumes when an enabled interrupt is pending, whenever it became so); without
            # this the hart would only wake at the next change of an interrupt input
            enabled = hart.reg(rv.UC_RISCV_REG_MIE)
            if enabled and board.mip(hart.hart_id, hart.time, enabled):
                hart.state = HartState.RUNNING
        self._check_waiters(hart.time, storer=hart)
        if hart.polling:
            # nothing the hart's loop does will change what it polls before the next device
            # event: it waits until then (or the end of its turn) without executing
            hart.polling = False
            event = board.next_device_event(hart.time)
            self.move_hart(hart, max(hart.time, min(event, horizon) if event is not None else horizon))
        if len(self.frames) >= self.frames_wanted and self._trap_deadline is None:
            self.time = max(self.time, self.delivery_time)
            return False
        running = [h.time for h in self.harts if h.state is HartState.RUNNING]
        if running:
            self._catch_up_to(min(running))
        self._check_deadlines()
        return True

    def _outer_bound(self, t0: Time, event: Time | None) -> Time:
        """What bounds every turn from t0 until one of them happens: the device event `event`
        (the board's next after t0), a grab, run_until's end (NEVER: none)."""
        outer = NEVER
        if event is not None:
            outer = min(outer, event)
        if self._grabs and self._grabs[0][0] > t0:
            outer = min(outer, self._grabs[0][0])
        if self.until is not None and self.until > t0:
            outer = min(outer, self.until)
        return outer

    def _stop_turns_at(self, outer: Time, now: Time) -> Time:
        """Where turns run without the board (from `now`, bounded by `outer`) must stop: `outer`, the
        first moment the LCD could capture a frame, the hang budget's end (unless run_until's)."""
        stop_at = min(outer, self.board.earliest_frame_capture(now))
        if self.until is None:
            stop_at = min(stop_at, self._last_frame_time + self.hang_budget)
        return stop_at

    def _alone_until(self, hart: Hart, t0: Time, outer: Time) -> int | None:
        """The cycle count up to which a time loop (usleep, msleep) or a loop that only spins (`j .`)
        may be skipped past the turn's end:
        where a turn from t0 would end at the first thing that can happen (`outer`: a device event,
        a grab, run_until's end; a frame capture; the hang budget), while the other harts sleep in
        wfi, wait on SRAM or spin in a loop that changes nothing (_inert; neither loop stores
        anything that could wake them) and nothing else holds the turns short. The turns in between would each begin with the board as it is and end with
        only time moved on; the skip ends the turn, and the next one goes on from the loop's exit.
        None: the skip stops at the turn's end."""
        if self._trap_deadline is not None or self._draining or hart.polling or \
                any(other.state is HartState.RUNNING and not self._inert(other) for other in self.harts
                    if other is not hart):
            return None
        stop_at = self._stop_turns_at(outer, t0)
        if stop_at >= NEVER or stop_at <= t0:
            return None
        return max(hart.cycles + 1, self.cycles_until(hart, stop_at))

    def _inert(self, hart: Hart) -> bool:
        """Whether a running hart that is not the one whose turn it is can do nothing another hart
        or a device would see before the next device event: it spins in a loop that changes nothing
        (Hart.in_idle_loop: no load, store or CSR access, no way out but a trap) and no interrupt
        it would take is pending (privileged spec, 3.1.9: an M-mode interrupt is taken when its mip
        and mie bits are set and mstatus.MIE is, or the hart is below M-mode; what
        takeable_interrupts gives). Only a device event (or a store by a hart that is not inert)
        can then change what it does, and those bound the turns past whose end a hart may skip
        (_alone_until): for the skip it is as good as asleep."""
        if not hart.in_idle_loop():
            return False
        takeable = hart.takeable_interrupts()
        return not (takeable and self.board.mip(hart.hart_id, hart.time, takeable))

    def _go_on_alone(self, hart: Hart, t0: Time, outer: Time, horizon: Time) -> Time:
        """The hart ran a turn alone on the fast engine, the others asleep in wfi, and nothing in it
        needed the board (no device access, CSR, trap or wfi: the precise engine did not run, and the
        fast one left no device access to the bus). Until
        one of its turns does, the next turns would begin with the same state of the board and end
        with the devices only moving on in time: no interrupt can come before the next device event
        (`outer` bounds those), no frame be captured before the LCD has the bytes for it, nobody
        else runs. So the hart runs them here, one after another, each exactly the turn _turn would
        give it (the same budget, from the same time), without moving the devices on between them,
        which is what costs the host time; the last one ends where _turn goes on as usual. Returns
        the horizon of the last turn run (`horizon`, that of the turn _turn ran, when it ran none;
        `t0`: when that turn began, `outer` what bounded it)."""
        if self._trap_deadline is not None or self._draining or self._priority is not None or \
                hart.state is not HartState.RUNNING or hart.polling or not hart.fast_usable() or \
                any(other.state is not HartState.ASLEEP for other in self.harts if other is not hart):
            return horizon
        plan = self._alone_plan
        # the console's quiet bytes bound the turns as any device event does, but their ends need no
        # board: the turns run on past them (each still ends at one it reaches, as _turn would end it),
        # and the UART hears them all, each at its own time, when the board next moves the devices on
        quiet = self.board.uarths.quiet_byte_ends()
        if len(quiet) > QUIET_ENDS_MAX:
            quiet = ()              # (more than the plan holds: they bound the turns as other events do)
        plan.ticks = len(quiet)
        plan.tick_ends[:plan.ticks] = quiet
        if plan.ticks:
            outer = self._outer_bound(t0, self.board.next_device_event(t0, past_quiet_console=True))
        stop_at = self._stop_turns_at(outer, hart.time)
        if hart.time >= stop_at:
            return horizon
        plan.anchor_time, plan.anchor_cycles = self._anchor[hart.hart_id]
        plan.hz, plan.quantum, plan.outer, plan.stop_at = self._hz, self.quantum, outer, stop_at
        plan.max_turns = MAX_TURNS_ALONE
        started = host_time.perf_counter()
        hart.run_alone(plan)
        self.host_time_in_harts += host_time.perf_counter() - started
        self.turn_horizon = self.time_at_cycles(hart, plan.start_cycles + plan.budget)
        if not plan.handed_over:
            hart.time = plan.end_time
            return plan.horizon
        self._finish_handed_over(hart, plan)
        return plan.horizon

    def _finish_handed_over(self, hart: Hart, plan: AlonePlan | PairPlan) -> None:
        """The last of the turns run in C (`plan`'s, `hart`'s) stopped for the board: the board catches
        up with its start, as between any two turns (the UART hears the bytes that ended before it; the
        board's time is the turn's start for whatever reads it: a trap's grace period, a warning's
        time), and it goes on as _run_hart would have run it from its start."""
        hart.time = plan.t0
        self._set_time(plan.t0)
        self._check_deadlines()
        self._run_hart(hart, plan.budget, since=(plan.start_executed, plan.start_cycles))
        if self.pending_stop is not None:
            raise self.pending_stop
        hart.time = self.time_at_cycles(hart, hart.cycles)

    def _go_on_paired(self) -> None:
        """Both harts run on the fast engine, between turns, and the turn just run needed no board (as
        for _go_on_alone). Until a turn does, each next turn would begin with the same state of the
        board and end with the devices only moving on in time: no interrupt can come before the next
        device event, none is pending that either hart would take (it would be taken at the start of
        its turn), no frame can be captured before the LCD has its bytes, and neither hart is in a
        race window (lockstep), polls or spins in a loop that only waits (_turn skips those). So the
        turns run here, in C, each exactly the turn _turn would give (the hart furthest behind, its
        horizon a quantum of its cycles or a quantum past the other hart's time), without moving the
        devices on between them; the last one ends where _turn would go on (issue 31: both harts
        drawing had cost a return to Python and the devices moved on every quantum, 400 a frame)."""
        if self._trap_deadline is not None or self._draining or self._priority is not None or \
                self.pending_stop is not None or self.reset_requested is not None or not self.pairing:
            return
        if self._pair_skip:
            self._pair_skip -= 1      # the last tries ran a turn or none: this one is let pass
            return
        turns = self._pair_run()
        if turns >= 2:
            self._pair_backoff = 0
        else:
            self._pair_backoff = min(2 * self._pair_backoff or 1, PAIR_BACKOFF_MAX)
            self._pair_skip = self._pair_backoff

    def _pair_run(self) -> int:
        """_go_on_paired's turns, when they may run: how many ran."""
        harts = self.harts
        if len(harts) != 2 or any(h.state is not HartState.RUNNING or h.polling or not h.fast_usable()
                                  for h in harts):
            return 0
        t0 = min(h.time for h in harts)
        if t0 < self._race_until or any(hart.in_idle_loop() for hart in harts):
            return 0
        if (self._grabs and self._grabs[0][0] <= t0) or (self.until is not None and self.until <= t0):
            return 0      # a grab is due, or run_until's end is reached: the run loop sees to it first
        for hart in harts:
            takeable = hart.takeable_interrupts()
            if takeable and self.board.mip(hart.hart_id, hart.time, takeable):
                return 0
        outer = self._outer_bound(t0, self.board.next_device_event(t0))
        stop_at = self._stop_turns_at(outer, t0)
        if t0 >= stop_at:
            return 0
        plan = self._pair_plan
        for hart in harts:
            n = hart.hart_id
            plan.anchor_time[n], plan.anchor_cycles[n] = self._anchor[n]
            plan.time[n], plan.pc[n] = hart.time, hart.pc
        plan.hz, plan.quantum, plan.outer, plan.stop_at = self._hz, self.quantum, outer, stop_at
        plan.max_turns = MAX_TURNS_ALONE
        started = host_time.perf_counter()
        harts[0].run_pair(harts[1], plan)
        self.host_time_in_harts += host_time.perf_counter() - started
        self.paired_turns += plan.turns
        if not plan.handed_over:
            for hart in harts:
                hart.time = plan.time[hart.hart_id]
            self._catch_up_to(min(hart.time for hart in harts))
            self._check_deadlines()
            return plan.turns
        last = harts[plan.last]
        for hart in harts:
            hart.time = plan.time[hart.hart_id]
        self.turn_horizon = self.time_at_cycles(last, plan.start_cycles + plan.budget)
        self._finish_handed_over(last, plan)
        self._finish_turn(last, plan.horizon)
        return plan.turns

    def _catch_up_to(self, target: Time) -> None:
        """Moves the board's time on to `target` (the earliest time a running hart has reached), one
        device event at a time while a hart sleeps: a sleeper an event wakes on the way wakes at
        that event's time and the board's time stays there, so that it runs from its own wake-up,
        not from where the others have got to (a hart woken by another's store in the middle of
        the other's turn, gone back to sleep with a timer due before the other's turn ends). On the
        chip a hart in wfi resumes as soon as an enabled interrupt is pending (privileged spec
        1.9.1, 3.2.3), and the CLINT raises MTIP once mtime >= mtimecmp (SiFive's CLINT, which the
        K210's is; the SDK's clint.c relies on it): at the timer's own moment."""
        while any(h.state is not HartState.RUNNING for h in self.harts):
            event = self.board.next_device_event(self.time)
            if event is None or event >= target:
                break
            self._set_time(event)
            if any(h.state is HartState.RUNNING and h.time < target for h in self.harts):
                return
        self._set_time(target)

    def _set_time(self, now: Time) -> None:
        """Moves the board's time (the earliest time a running hart has reached) forward:
        devices catch up and sleeping harts with a pending enabled interrupt wake."""
        if now > self.time:
            self.time = now
        self.board.advance_devices(self.time)
        self._check_waiters(self.time)
        self._wake_sleepers(self.time)

    def _run_hart(self, hart: Hart, budget: int, instruction_limit: int | None = None,
                  since: tuple[int, int] | None = None) -> None:
        """Runs one turn of a hart, `budget` CPU cycles and at most `instruction_limit` instructions
        (its time is then time_at_cycles of its cycle count). `since`: the turn began earlier, with the hart's executed
        instructions and cycles at these counts (_go_on_alone ran its start)."""
        bus = self.board.bus
        self.current = hart
        bus.turn_begins(hart)
        before, cycles_before = since if since is not None else (hart.executed, hart.cycles)
        started = host_time.perf_counter()
        end = None
        try:
            while True:
                # every instruction takes at least a cycle: the cycle budget bounds the instructions too
                remaining = budget - (hart.cycles - cycles_before)
                instructions = remaining if instruction_limit is None else \
                    min(remaining, instruction_limit - (hart.executed - before))
                end, _ = hart.run(instructions, remaining)
                if end is not RunEnd.POLL:
                    break
                if self._begin_wait(hart, before):
                    break
                # a device poll, or a loop not yet proven in this turn: the turn goes on as if
                # nothing had stopped it, unless something else asked for its end
                if hart.stop_requested or hart.polling or hart.cycles - cycles_before >= budget or \
                        (instruction_limit is not None and hart.executed - before >= instruction_limit):
                    end = RunEnd.STOPPED
                    break
            if end is RunEnd.WFI and self._stopped_by_a_watch(hart):
                end = RunEnd.STOPPED       # the run ended at a watched store, not at a wfi before it
        except unicorn.UcError as error:
            hart.pc = hart.reg(rv.UC_RISCV_REG_PC)
            if hart.pending_exception is not None:
                end = RunEnd.EXCEPTION     # the bus turned the access into an access fault
            elif self.pending_stop is None:
                if error.errno == unicorn.UC_ERR_INSN_INVALID and (hart.read_u16(hart.pc) == 0x9002 or
                                                                    hart.read_u32(hart.pc) == 0x00100073):
                    hart.note_breakpoint()
                    end = RunEnd.EXCEPTION
                else:
                    self.pending_stop = FirmwareTrap(f"hart {hart.hart_id} at pc 0x{hart.pc:08x} "
                                                     f"({self.board.disassemble_at(hart.pc)}): {error}")
        finally:
            self.current = None
            self.host_time_in_harts += host_time.perf_counter() - started
        stray = bus.turn_ended(hart)
        if stray is not None:
            self.pending_stop = stray
        if self.pending_stop is None:
            if end is RunEnd.WFI:
                hart.state = HartState.ASLEEP
            elif end is RunEnd.EXCEPTION:
                self.traps.deliver_exception(hart, self._open_grace)
