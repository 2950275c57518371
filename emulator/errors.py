"""Why a run of the board model ended, and the exit status each reason gets.

Every way a run can go wrong has its own exception class and its own exit
status, so scripts and CI can tell a firmware trap from a hang from an access
to hardware the model does not implement. The numbers and their names are
k210_common/exit_status.py's, shared with the project's other commands.
"""
from __future__ import annotations

from k210_common.exit_status import (BY_CODE, EXIT_BAD_INPUT, EXIT_EXPECT_UNMET, EXIT_FAIL_ON, EXIT_FIRMWARE_ERROR,
                                     EXIT_HANG, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_MISUSE, EXIT_OK,
                                     EXIT_STRAY_WRITE, EXIT_TERMINATED, EXIT_TRAP, EXIT_UNMODELLED,
                                     EXIT_WRITE_FAILED)


class BoardStop(Exception):
    """Base of every reason that ends a run early; `exit_status` is the CLI's exit code."""

    exit_status = EXIT_INTERNAL

    @property
    def kind(self) -> str:
        """How the run ended, in run.json: the exit status's name."""
        return BY_CODE[self.exit_status].name


class FirmwareTrap(BoardStop):
    """The firmware took a synchronous exception that its own handler could not deal with."""

    exit_status = EXIT_TRAP


class HangDetected(BoardStop):
    """No frame reached the LCD within the virtual-time budget, or every hart waits forever."""

    exit_status = EXIT_HANG


class UnmodelledAccess(BoardStop):
    """A load or store hit an address or register that no model implements."""

    exit_status = EXIT_UNMODELLED


class RegisterRuleViolation(UnmodelledAccess):
    """An access a device's register table does not take as it is: no register at the offset, a
    width other than the register's, a store to a read-only or a load from a write-only register.
    By default the bus then does what the K210's bus does with such an access and warns; with
    --strict it stops the run (exit status 5), as every UnmodelledAccess does."""


class BadInput(BoardStop):
    """The firmware image (or another input file) is missing or malformed."""

    exit_status = EXIT_BAD_INPUT


class HardwareMisuse(BoardStop):
    """The firmware used a modelled device in a way the real part does not support
    (for example running the CPU from PLL0 before it locked, or touching a
    peripheral whose clock is gated)."""

    exit_status = EXIT_MISUSE


class FirmwareReportedError(BoardStop):
    """The firmware reported a fatal error of its own on the console
    (a line `error <code> <words>`), e.g. no SD card or a missing file."""

    exit_status = EXIT_FIRMWARE_ERROR

    def __init__(self, message: str, code: int) -> None:
        super().__init__(message)
        self.code = code


class StrayWrite(BoardStop):
    """With --check-writes: a store (a hart's, or a DMA channel's) landed in SRAM outside the
    firmware's buffers (see write_watch.py). Not a hardware fault: the K210 would have let it
    through; the board model's checker reports it."""

    exit_status = EXIT_STRAY_WRITE


class ConsoleExpectationsMet(BoardStop):
    """--expect: the console has printed every expected text, in order. Not a failure: the run
    ends here with status 0, as a run that showed its frames does."""

    exit_status = EXIT_OK


class ConsoleFailText(BoardStop):
    """--fail-on: the console printed a text the user named as failure."""

    exit_status = EXIT_FAIL_ON


class ConsoleExpectationUnmet(BoardStop):
    """--expect: the run reached its end (--until's time, or --budget seconds of virtual time
    without the next expected text) before the console printed every expected text."""

    exit_status = EXIT_EXPECT_UNMET


class Interrupted(BoardStop):
    """A signal asked the run to end (Ctrl-C's SIGINT, SIGTERM): it ends after the instruction
    under way and writes everything it has, as any other end does."""

    def __init__(self, signal_number: int, name: str) -> None:
        super().__init__(f"{name} received: the run was stopped there")
        self.exit_status = EXIT_TERMINATED if name == "SIGTERM" else EXIT_INTERRUPTED
        self.signal_number = signal_number


class OutputFailed(BoardStop):
    """An output the run writes as it goes (a frame, console.log, the animation, --trace-insn)
    could not be written (a full disk, a file size limit): the run stops there and writes what it
    still can, run.json first."""

    exit_status = EXIT_WRITE_FAILED


def write_failed(path, error: OSError) -> OutputFailed:
    """The stop for a failed write of `path`, naming the file and the system's reason."""
    return OutputFailed(f"cannot write {path}: {error.strerror or error}")
