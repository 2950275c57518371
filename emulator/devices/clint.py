"""CLINT (0x0200_0000): per-hart software interrupt (msip) and timer (mtimecmp), and mtime.

mtime ticks at CPU clock / 50 on the K210. The board's clock keeps the count across
clock changes and answers mtime (the MtimeCounter port); this model keeps msip and mtimecmp and says when each hart's
timer interrupt becomes pending. mtimecmp is not reset by the Rocket CLINT; the
model starts it at all ones (no timer interrupt pending), which is what random
power-up contents almost always amount to.
"""
from __future__ import annotations

from ..memory_map import K210_BLOCKS
from ..vtime import Time
from .mmio import BUS_TILELINK, Peripheral, Register
from .ports import MtimeCounter, Ports

HARTS = 2
HALVES = ((0, 32), (32, 32))     # mtimecmp and mtime: two 32-bit fields each
MSIP = 0x0000
MTIMECMP = 0x4000
MTIME = 0xBFF8
ALL_ONES = (1 << 64) - 1


class Clint(Peripheral):
    """Rocket's CLINT on TileLink, as rocket-chip had it before its privileged-spec-1.10 merge
    (March 2017; the K210 implements 1.9.1): every register is made of 32-bit fields (msip, the
    halves of mtimecmp and mtime), so a store narrower than 32 bits changes nothing."""

    NAME = "CLINT"
    BASE = K210_BLOCKS["CLINT"].base
    SIZE = K210_BLOCKS["CLINT"].size
    BUS = BUS_TILELINK
    REGISTERS = {
        **{MSIP + 4 * h: Register(f"msip{h}") for h in range(HARTS)},
        **{MTIMECMP + 8 * h: Register(f"mtimecmp{h}", width=8, narrow_ok=True, reset=ALL_ONES, fields=HALVES)
           for h in range(HARTS)},
        MTIME: Register("mtime", width=8, narrow_ok=True, fields=HALVES),
    }

    def __init__(self, ports: Ports, counter: MtimeCounter) -> None:
        super().__init__(ports)
        self.counter = counter

    def reset(self, now: Time) -> None:
        """A chip reset: msip and mtimecmp as at power-on, mtime from 0."""
        super().reset(now)
        self.counter.set_mtime(0, now)

    def msip(self, hart: int) -> bool:
        return bool(self.values[MSIP + 4 * hart] & 1)

    def timer_pending(self, hart: int, now: Time) -> bool:
        return self.counter.mtime(now) >= self.values[MTIMECMP + 8 * hart]

    def write(self, offset: int, size: int, value: int, now: Time) -> None:
        if size == 4 and offset in (MTIME, MTIME + 4):
            # a 32-bit store replaces one half of the running counter; the other half is
            # what mtime holds now, not what was last written
            self.values[MTIME] = self.counter.mtime(now)
        super().write(offset, size, value, now)

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        if offset == MTIME:
            return self.counter.mtime(now)
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        if offset == MTIME:
            self.counter.set_mtime(value, now)
        elif offset < MTIMECMP:
            self.values[offset] = value & 1
        else:
            self.values[offset] = value
        self.ports.irq_changed(now)

    def next_event_time(self, now: Time) -> Time | None:
        times = []
        for hart in range(HARTS):
            when = self.counter.time_of_mtime(self.values[MTIMECMP + 8 * hart])
            if when is not None and when > now:
                times.append(when)
        return min(times) if times else None
