"""The end of a run that the firmware does not ask for: trap grace periods, error reports, hangs.

A trap handler that may never return, and the firmware's fatal error report, get a grace period
of virtual time before the run ends with them; a run in which no hart can make progress (every
hart asleep with nothing that could wake it, or no frame for the hang budget) ends with a hang
report naming where each hart is, what the devices wait for and the most recent warnings. A mixin
of Scheduler (scheduler.py), which holds the state it uses (_trap_deadline, _error_report,
_last_frame_time) and checks the deadlines between turns.
"""
from __future__ import annotations

from unicorn import riscv_const as rv

from ..cpu.hart import Hart, HartState
from ..errors import FirmwareReportedError, FirmwareTrap, HangDetected
from .elf import symbolize
from .traps import Traps
from ..vtime import PS_PER_MS, Time, to_seconds

TRAP_GRACE = 500 * PS_PER_MS      # virtual time the firmware's trap handler gets to report
WARNINGS_IN_HANG_REPORT = 6       # the most recent distinct warnings a hang report repeats


class Deadlines:
    """Scheduler's grace periods and hang detection, and the reports a run ends with."""

    # besides the board (scheduler.py's Board protocol), what it uses of Scheduler:
    harts: list[Hart]
    time: Time
    hang_budget: Time
    traps: Traps
    _draining: bool
    until: Time | None
    _last_frame_time: Time
    _error_report: tuple[int, str] | None
    _trap_deadline: Time | None

    def _open_grace(self) -> None:
        """A trap handler that may never return gets the grace period to report before the run ends."""
        self._trap_deadline = self.time + TRAP_GRACE

    def firmware_reported_error(self, code: int, line: str) -> None:
        """The firmware printed its fatal error report: the run ends after the grace period."""
        if self._error_report is None:
            self._error_report = (code, line)
            self._trap_deadline = self.time + TRAP_GRACE

    def _report_pending(self) -> bool:
        """An error report or a --stop-on-trap exception waits for its grace period to end the run
        (--until's time does not cut it short; a trap handler that has not returned does not hold
        up --until, whose time is the user's)."""
        return self._trap_deadline is not None and (self.traps.report is not None or self._error_report is not None)

    def _check_deadlines(self) -> None:
        if self._trap_deadline is not None:
            everyone_waits = all(h.state is not HartState.RUNNING for h in self.harts) and \
                self.board.next_device_event(self.time) is None
            if self.traps.report is not None or self._error_report is not None:
                if self.time >= self._trap_deadline or everyone_waits:
                    if self.traps.report is not None:
                        raise FirmwareTrap(self.traps.report + " (the firmware's trap handler has run; see the console)")
                    code, line = self._error_report
                    raise FirmwareReportedError(f"the firmware reported: {line}", code)
            elif everyone_waits:
                self._report_hang("every hart sleeps in wfi and no device will ever raise an interrupt")
            elif self.time >= self._trap_deadline or not any(h.open_trap for h in self.harts):
                # the handler returned, or runs on as the program's own code: the run goes on
                self._trap_deadline = None
        if self.time - self._last_frame_time > self.hang_budget and not self._draining and self.until is None:
            self._report_hang(f"no frame reached the LCD for {to_seconds(self.hang_budget):g} s of virtual time")

    def _report_hang(self, why: str) -> None:
        """Ends the run: no hart can make progress. When a hart is in a trap handler it never
        returned from, the exception is what ended the program (a handler that reports and parks
        the harts, as most firmware's does for an exception it cannot handle): a trap."""
        board = self.board
        open_traps = [h.open_trap for h in self.harts if h.open_trap is not None]
        if open_traps:
            raise FirmwareTrap(f"{'; '.join(open_traps)}; the trap handler did not return, and then {why} "
                               f"(see the console)")
        lines = [why]
        if self.traps.last is not None:
            lines.append(f"the last exception taken (its handler returned): {self.traps.last}")
        for hart in self.harts:
            where = symbolize(board.image.symbols, hart.pc)
            state = hart.state.value
            if hart.wait is not None:
                state += f" ({hart.wait.describe()})"
            spins = hart.state is HartState.RUNNING and hart.in_idle_loop()
            lines.append(f"hart {hart.hart_id}: {state} at pc 0x{hart.pc:08x}"
                         f"{f' <{where}>' if where else ''} ({board.disassemble_at(hart.pc)}), "
                         f"mie 0x{hart.csr(rv.UC_RISCV_REG_MIE):x}, mip 0x{board.mip(hart.hart_id, self.time):x}"
                         f"{'; it spins in a loop that changes nothing (only an interrupt can end it)' if spins else ''}")
        for peripheral in board.peripherals:
            text = peripheral.describe_wait()
            if text:
                lines.append(text)
        lines.append(f"LCD: {board.lcd.frames_captured} frames captured, display "
                     f"{'on' if board.lcd.display_on else 'off'}, {'asleep' if board.lcd.sleeping else 'awake'}")
        recent = board.recent_warnings(WARNINGS_IN_HANG_REPORT)
        if recent:
            lines.append(f"the most recent warnings (of {len(board.warnings)} in the run, every one in run.json):")
            lines.extend(f"  {text}" for text in recent)
        raise HangDetected("\n  ".join(lines))
