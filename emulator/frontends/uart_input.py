"""--uart-input: what the host sends to UARTHS's receiver through the Dock's USB serial bridge.

A file, or standard input when it is a pipe, is read whole before the run. Standard input
from a terminal is interactive: what the user types is sent as it is typed (the terminal in
cbreak mode, so that each key goes at once and the firmware does its own echo), and the
board's virtual time is kept from running ahead of the host's clock, so that a firmware
waiting for a key waits in real time rather than skipping its timeouts.
"""
from __future__ import annotations

import os
import select
import sys
import time
from collections import deque
from pathlib import Path

from ..errors import BadInput

STDIN = "-"
POLL_S = 0.05              # longest single host wait while the board waits for a key


class UartInput:
    """A queue of bytes for the receiver; interactive ones grow while the run goes on."""

    def __init__(self, data: bytes = b"", interactive_fd: int | None = None) -> None:
        self._bytes: deque[int] = deque(data)
        self.total = len(data)
        self._fd = interactive_fd
        self._saved_terminal = None
        self._eof = interactive_fd is None
        self._host_start = time.monotonic()
        if interactive_fd is not None:
            import termios
            import tty
            self._saved_terminal = termios.tcgetattr(interactive_fd)
            tty.setcbreak(interactive_fd, termios.TCSANOW)     # keys typed ahead are kept

    @staticmethod
    def open(source: str) -> "UartInput":
        """A file's bytes, piped standard input's, or a terminal's keys (`-` on a terminal)."""
        if source == STDIN:
            if sys.stdin.isatty():
                return UartInput(interactive_fd=sys.stdin.fileno())
            return UartInput(sys.stdin.buffer.read())
        path = Path(source)
        if not path.is_file():
            raise BadInput(f"--uart-input {source}: no such file")
        try:
            return UartInput(path.read_bytes())
        except OSError as error:
            raise BadInput(f"--uart-input {source}: cannot read it ({error.strerror or error})") from None

    @property
    def interactive(self) -> bool:
        return self._fd is not None

    @property
    def may_grow(self) -> bool:
        """More bytes may still come (a terminal that has not reached end of input)."""
        return not self._eof

    def has_byte(self, virtual_now: float) -> bool:
        if self._fd is not None and not self._eof:
            self._pace(virtual_now)
        return bool(self._bytes)

    def pop(self) -> int:
        return self._bytes.popleft()

    def put_back(self, byte: int) -> None:
        self._bytes.appendleft(byte)

    def _pace(self, virtual_now: float) -> None:
        """Takes what the user has typed; waits (for a key at most) while virtual time is
        ahead of the host's clock."""
        ahead = virtual_now - (time.monotonic() - self._host_start)
        timeout = min(max(ahead, 0.0), POLL_S) if not self._bytes else 0.0
        ready, _, _ = select.select([self._fd], [], [], timeout)
        if ready:
            chunk = os.read(self._fd, 1024)
            if not chunk:
                self._eof = True
            self._bytes.extend(chunk)
            self.total += len(chunk)

    def close(self) -> None:
        """Gives the terminal back as it was."""
        if self._saved_terminal is not None:
            import termios
            termios.tcsetattr(self._fd, termios.TCSADRAIN, self._saved_terminal)
            self._saved_terminal = None
