"""--uart-input: what the host sends to UARTHS's receiver through the Dock's USB serial bridge.

A file, a pipe or a FIFO (standard input when it is one, bash's `<(...)`) is read as the firmware
takes its bytes, a chunk at a time: its bytes count as there from the start (when the firmware
wants one and none has been read yet, the read waits for the writer), the run starts at once, and
memory stays at a chunk whatever the input's length. Standard input from a terminal is
interactive: what the user types is sent as it is typed (the terminal in cbreak mode, so that each
key goes at once and the firmware does its own echo), and the board's virtual time is kept from
running ahead of the host's clock, so that a firmware waiting for a key waits in real time rather
than skipping its timeouts.
"""
from __future__ import annotations

import os
import select
import stat
import sys
import time
from typing import Callable

from ..errors import BadInput
from ..vtime import Time, to_seconds

STDIN = "-"
POLL_S = 0.05              # longest single host wait while the board waits for a key
CHUNK = 65536              # what one read of a file or pipe takes
STOP_LOOK_S = 0.25         # how often a wait for a pipe's writer looks whether the run was asked to stop


class UartInput:
    """The bytes for the receiver: given (tests), or read from a file descriptor as they are taken."""

    def __init__(self, data: bytes = b"", fd: int | None = None, interactive: bool = False,
                 owns_fd: bool = False) -> None:
        self._buffer = bytearray(data)
        self._next = 0                      # the next byte to give in _buffer
        self.total = len(data)              # bytes taken from the source so far
        self._fd = fd
        self._interactive = interactive
        self._owns_fd = owns_fd
        self._saved_terminal = None
        self._eof = fd is None
        # a regular file's bytes are all there: its length is what run.json reports, and it does
        # not grow (a pipe's or FIFO's count as they are read)
        status = os.fstat(fd) if fd is not None else None
        self._regular = status is not None and stat.S_ISREG(status.st_mode)
        if self._regular:
            self.total = status.st_size
        self.stop_check: Callable[[], None] = lambda: None   # raises when a signal asked the run to stop
        self._host_start = time.monotonic()
        if interactive:
            import termios
            import tty
            self._saved_terminal = termios.tcgetattr(fd)
            tty.setcbreak(fd, termios.TCSANOW)     # keys typed ahead are kept

    @staticmethod
    def open(source: str) -> "UartInput":
        """A file's, pipe's or FIFO's bytes, piped standard input's, or a terminal's keys (`-` on
        a terminal)."""
        if source == STDIN:
            fd = sys.stdin.fileno()
            return UartInput(fd=fd, interactive=os.isatty(fd))
        try:
            fd = os.open(source, os.O_RDONLY)
        except FileNotFoundError:
            raise BadInput(f"--uart-input {source}: no such file") from None
        except OSError as error:
            raise BadInput(f"--uart-input {source}: cannot read it ({error.strerror or error})") from None
        if stat.S_ISDIR(os.fstat(fd).st_mode):
            os.close(fd)
            raise BadInput(f"--uart-input {source}: is a folder, not a file, pipe or FIFO")
        return UartInput(fd=fd, owns_fd=True)

    @property
    def interactive(self) -> bool:
        return self._interactive

    @property
    def may_grow(self) -> bool:
        """More bytes may still come (a pipe, FIFO or terminal that has not reached its end)."""
        return not self._eof and not self._regular

    def has_byte(self, virtual_now: Time) -> bool:
        if self._next < len(self._buffer):
            return True
        if not self._eof:
            if self._interactive:
                self._pace(virtual_now)
            else:
                self._read_waiting()
        return self._next < len(self._buffer)

    def pop(self) -> int:
        byte = self._buffer[self._next]
        self._next += 1
        return byte

    def put_back(self, byte: int) -> None:
        if self._next:
            self._next -= 1
            self._buffer[self._next] = byte
        else:
            self._buffer.insert(0, byte)

    def _read_waiting(self) -> None:
        """The next chunk, waiting for a pipe's writer as long as it takes, but looking a few
        times a second whether a signal asked the run to stop."""
        while not self._regular and not select.select([self._fd], [], [], STOP_LOOK_S)[0]:
            self.stop_check()
        self._take(os.read(self._fd, CHUNK))

    def _take(self, chunk: bytes) -> None:
        """A read's bytes after what is left; the bytes already given are dropped first."""
        if not chunk:
            self._eof = True
            return
        del self._buffer[:self._next]
        self._next = 0
        self._buffer += chunk
        if not self._regular:
            self.total += len(chunk)

    def _pace(self, virtual_now: Time) -> None:
        """Takes what the user has typed; waits (for a key at most) while virtual time is
        ahead of the host's clock."""
        ahead = to_seconds(virtual_now) - (time.monotonic() - self._host_start)
        timeout = min(max(ahead, 0.0), POLL_S)
        ready, _, _ = select.select([self._fd], [], [], timeout)
        if ready:
            self._take(os.read(self._fd, 1024))

    def close(self) -> None:
        """Gives the terminal back as it was, and the file descriptor opened for the input."""
        if self._saved_terminal is not None:
            import termios
            termios.tcsetattr(self._fd, termios.TCSADRAIN, self._saved_terminal)
            self._saved_terminal = None
        if self._owns_fd and self._fd is not None:
            os.close(self._fd)
            self._fd = None
