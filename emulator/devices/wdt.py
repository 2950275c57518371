"""WDT0, WDT1 (0x5040_0000, 0x5041_0000): Synopsys DesignWare APB watchdog timers.

Registers as the Kendryte SDK's wdt.h has them: cr (0x00: bit 0 enable, bit 1 response mode,
0 = reset the chip at a timeout, 1 = interrupt first and reset at the next timeout if the
interrupt is still set; bits 4:2 the reset pulse length), torr (0x04: bits 3:0 the timeout
TOP, bits 7:4 the first timeout's), ccvr (0x08, the counter), crr (0x0C: writing 0x76 restarts
the counter and clears the interrupt), stat (0x10), eoi (0x14: reading it clears the interrupt
and leaves the counter alone), prot_level (0x1C), the component parameters (0xE4-0xF4, read 0
here: not published for the K210), comp_version (0xF8, 0) and comp_type (0xFC, the DesignWare
watchdog's 0x4457_0120).

A timeout lasts 2^(16 + TOP) watchdog clocks (the SDK's wdt_init returns 2^(TOP + 17) clocks,
an interrupt timeout and the reset one after it; Linux's dw_wdt.c computes the same), the clock
being IN0 (26 MHz) / ((clk_th6 byte n + 1) x 2) (sysctl.c, SYSCTL_CLOCK_WDTn). Once enabled the
watchdog cannot be disabled but by a reset (DW_apb_wdt; Linux's dw_wdt.c keeps a watchdog it
cannot stop "running" for the same reason): the SDK's wdt_stop clears cr bit 0 to no effect.
A reset is the chip's: the board resets (Board.chip_reset) and SYSCTL's reset_status says the
watchdog did it. PLIC sources 21 and 22.
"""
from __future__ import annotations

from typing import Callable

from ..memory_map import K210_BLOCKS
from ..vtime import Time, cycles_in, cycles_time
from .mmio import Peripheral, Register
from .ports import Ports

CR, TORR, CCVR, CRR, STAT, EOI, PROT_LEVEL = 0x00, 0x04, 0x08, 0x0C, 0x10, 0x14, 0x1C
COMP_PARAMS = (0xE4, 0xE8, 0xEC, 0xF0, 0xF4)
COMP_VERSION, COMP_TYPE = 0xF8, 0xFC
CR_ENABLE, CR_INTERRUPT_FIRST = 1, 2
RESTART = 0x76
WDT_TYPE = 0x4457_0120


class DwWatchdog(Peripheral):
    """One of WDT0-1."""

    REGISTERS = {
        CR: Register("cr"), TORR: Register("torr"), CCVR: Register("ccvr", writable=False),
        CRR: Register("crr", readable=False), STAT: Register("stat", writable=False),
        EOI: Register("eoi", writable=False), PROT_LEVEL: Register("prot_level", reset=2),
        **{offset: Register(f"comp_param_{5 - n}", writable=False) for n, offset in enumerate(COMP_PARAMS)},
        COMP_VERSION: Register("comp_version", writable=False),
        COMP_TYPE: Register("comp_type", writable=False, reset=WDT_TYPE),
    }

    def __init__(self, index: int, ports: Ports, clock_hz: Callable[[], int],
                 reset_chip: Callable[[str, Time], None]) -> None:
        """index: 0 or 1. clock_hz: the watchdog clock SYSCTL gives it. reset_chip: the chip
        resets, because of this watchdog (its name), at this time."""
        self.index = index
        self.NAME = f"WDT{index}"
        block = K210_BLOCKS[self.NAME]
        self.GATE, self.BASE, self.SIZE = block.gate, block.base, block.size
        self.clock_hz = clock_hz
        self.reset_chip = reset_chip
        super().__init__(ports)
        self._clear()

    def _clear(self) -> None:
        # The timeouts since the counter was last restarted (enabled, crr) follow one another at
        # the watchdog clock: the end of each is counted in that clock's cycles from the restart,
        # never by adding rounded timeout lengths. None: not enabled.
        self._origin: Time | None = None           # when they began
        self._hz = 0                               # the clock they are counted in
        self._before = 0                           # clocks from _origin to the current timeout's start
        self._clocks = 0                           # the current timeout's length in clocks
        self._interrupt = False

    def reset(self, now: Time) -> None:
        super().reset(now)
        self._clear()

    def _timeout_clocks(self, first: bool) -> int:
        top = self.values[TORR] >> (4 if first else 0) & 0xF
        return 1 << (16 + top)

    def _restart(self, now: Time, first: bool = False) -> None:
        """The counter starts a timeout at `now`: a new run of timeouts begins there."""
        self._origin, self._hz, self._before = now, self.clock_hz(), 0
        self._clocks = self._timeout_clocks(first)

    def _next_timeout(self, at: Time) -> None:
        """The current timeout ended at `at` and the counter goes on with the next: in the same run
        while the clock is unchanged, else a new run from `at`."""
        if self.clock_hz() != self._hz:
            self._restart(at)
            return
        self._before += self._clocks
        self._clocks = self._timeout_clocks(False)

    def _timeout_end(self) -> Time | None:
        """When the current timeout ends (None: not enabled)."""
        if self._origin is None or self._hz <= 0:
            return None                            # not enabled, or no clock: no timeout ever ends
        return self._origin + cycles_time(self._before + self._clocks, self._hz)

    def advance(self, now: Time) -> None:
        while (at := self._timeout_end()) is not None and at <= now:
            if self.values[CR] & CR_INTERRUPT_FIRST and not self._interrupt:
                self._interrupt = True
                self._next_timeout(at)
                self.ports.irq_changed(at)
                continue
            self._origin = None
            self.reset_chip(self.NAME, at)          # resets this watchdog too
            return

    def next_event_time(self, now: Time) -> Time | None:
        return self._timeout_end()

    def irq_line(self) -> bool:
        return self._interrupt

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        self.advance(now)
        if offset == CCVR:
            end = self._timeout_end()
            if end is None:
                return 0
            return max(0, min(0xFFFF_FFFF, cycles_in(end - now, self.clock_hz())))
        if offset == STAT:
            return 1 if self._interrupt else 0
        if offset == EOI:
            if self._interrupt:
                self._interrupt = False
                self.took_on_read = True
                self.ports.irq_changed(now)
            return 0
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        self.advance(now)
        if offset == CRR:
            if value & 0xFF == RESTART and self._origin is not None:
                self._restart(now)
                if self._interrupt:
                    self._interrupt = False
                    self.ports.irq_changed(now)
            return
        if offset == CR:
            enabled = self.values[CR] & CR_ENABLE
            self.values[CR] = value | enabled          # enable sticks until a reset
            if not enabled and value & CR_ENABLE:
                self._restart(now, first=True)
            return
        self.values[offset] = value

    def describe_wait(self) -> str | None:
        return None
