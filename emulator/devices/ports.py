"""What a device is given instead of the board: ports, as QEMU's devices get qemu_irq lines and
link properties, and Renode's peripherals their constructor arguments. A device's constructor
names the ports it uses; the board (board/dock.py) makes them. No device module imports the
board, and a device can be built and driven on its own with ports a test makes.

`Ports` holds what every memory-mapped block may use. The protocols below it are the peers a
device talks to that are not device modules themselves (the clock's CLINT counter, the DMAC's
memory, a UART's host-side input).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np

from ..vtime import Time


class Clock(Protocol):
    """The board's virtual clock as devices see it."""

    def cpu_hz(self) -> int:
        """The CPU clock now (SYSCTL's ACLK), in whole hertz: what bus, UARTHS and CLINT rates follow."""

    def now(self) -> Time:
        """The board's virtual time, for a question asked outside an access (an interrupt line's level)."""


@dataclass(frozen=True)
class Ports:
    """What every block may use."""

    clock: Clock
    # a warning, with the virtual time the device noticed it (None: the board's time)
    warn: Callable[[str, Time | None], None]
    # an interrupt line of this device may have changed at this time: the board samples the lines
    # (each device's irq_line) and wakes or interrupts the harts
    irq_changed: Callable[[Time], None]
    # brings every timed device up to this time, before an access whose answer depends on them
    catch_up: Callable[[Time], None]
    # a pin changed: (time, signal name, level or None for high impedance), for --vcd
    signal: Callable[[Time, str, int | None], None]
    # something the Dock's wiring follows changed at this time (a pad's routing, a driven level)
    wiring_changed: Callable[[Time], None]


class PadInputs(Protocol):
    """What reaches a block's input lines from their pads: for the FPIOA functions first ..
    first + count - 1, bit i for function first + i, (driven from outside, the outside's levels,
    pulled up, pulled down) by the pad FPIOA routes the function to (the Dock's wiring)."""

    def __call__(self, first: int, count: int) -> tuple[int, int, int, int]: ...


class MtimeCounter(Protocol):
    """The CLINT's mtime, which counts at CPU clock / 50 across clock changes: the board's clock
    keeps it, as an integral of the CPU clock over virtual time."""

    def mtime(self, now: Time) -> int: ...

    def set_mtime(self, value: int, now: Time) -> None: ...

    def time_of_mtime(self, value: int) -> Time | None:
        """When mtime reaches `value` at today's clock (None: never)."""


class DmaMemory(Protocol):
    """What the DMAC reads and writes: SRAM, item by item."""

    def read_items(self, address: int, width: int, count: int, fixed: bool) -> np.ndarray: ...

    def write_items(self, address: int, width: int, values: np.ndarray, fixed: bool, writer: str) -> None: ...


class SerialInput(Protocol):
    """What the host sends a UART's receiver (--uart-input)."""

    may_grow: bool          # an interactive terminal: more may come later

    def has_byte(self, virtual_now: Time) -> bool: ...

    def pop(self) -> int: ...

    def put_back(self, byte: int) -> None:
        """A byte a receiver took but never finished (it was reset mid-byte) goes first again."""
