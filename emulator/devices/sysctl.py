"""SYSCTL (0x5044_0000): PLLs, clock selects, clock gates, thresholds, resets, DMA selects.

The model computes the CPU clock and every SPI clock from what the firmware
programmed, and refuses what the real chip cannot do: running the CPU from
PLL0 before it locked, or reprogramming PLL0 while the CPU runs from it.

Register offsets follow the Kendryte standalone SDK's `sysctl_t`. Note: the
facts sheet lists peri_reset at 0x60; the SDK has peri_reset at 0x34 and the
reset-source status at 0x60, and the SDK is what runs on real boards.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..errors import HardwareMisuse
from ..memory_map import K210_BLOCKS
from ..vtime import PS_PER_US, Time
from .mmio import Peripheral, Register, field
from .ports import Ports

OSC_HZ = 26_000_000
# The PLL datasheet figure is not public; the SDK polls the lock bits. 50 us is
# well inside what such PLLs need and short enough not to distort start-up time.
PLL_LOCK_TIME: Time = 50 * PS_PER_US

PLL0, PLL1, PLL2 = 0x08, 0x0C, 0x10
PLL_LOCK = 0x18
CLK_SEL0 = 0x20
CLK_EN_CENT = 0x28
CLK_EN_PERI = 0x2C
SOFT_RESET = 0x30
PERI_RESET = 0x34
CLK_TH0 = 0x38
CLK_TH1 = 0x3C
MISC = 0x54
DMA_SEL0, DMA_SEL1 = 0x64, 0x68

# pll register fields
PLL_CLKR = (0, 4)
PLL_CLKF = (4, 6)
PLL_CLKOD = (10, 4)
PLL_RESET_BIT = 20
PLL_PWRD_BIT = 21
PLL_BYPASS_BIT = 23
PLL_OUT_EN_BIT = 25

# clk_en_cent bits
CENT_CPU, CENT_SRAM0, CENT_SRAM1, CENT_APB0, CENT_APB1, CENT_APB2 = range(6)
# clk_en_peri bits
PERI_BITS = {
    "rom": 0, "dma": 1, "ai": 2, "dvp": 3, "fft": 4, "gpio": 5, "spi0": 6, "spi1": 7,
    "spi2": 8, "spi3": 9, "i2s0": 10, "i2s1": 11, "i2s2": 12, "i2c0": 13, "i2c1": 14,
    "i2c2": 15, "uart1": 16, "uart2": 17, "uart3": 18, "aes": 19, "fpioa": 20,
    "timer0": 21, "timer1": 22, "timer2": 23, "wdt0": 24, "wdt1": 25, "sha": 26, "otp": 27,
    "rtc": 29,
}
# which APB bus each gated peripheral hangs off (the SDK's sysctl_clock_bus_en)
PERI_BUS = {"gpio": CENT_APB0, "fpioa": CENT_APB0, "spi0": CENT_APB2, "spi1": CENT_APB2,
            "spi2": CENT_APB0, "spi3": None, "dma": None,
            "uart1": CENT_APB0, "uart2": CENT_APB0, "uart3": CENT_APB0,
            "timer0": CENT_APB0, "timer1": CENT_APB0, "timer2": CENT_APB0,
            "wdt0": CENT_APB1, "wdt1": CENT_APB1, "rtc": CENT_APB1, "sha": CENT_APB0}
CLK_TH2 = 0x40
CLK_TH6 = 0x50
RESET_STATUS = 0x60
RESET_STS_CLR = 1
# reset_status's cause bits (sysctl.h sysctl_reset_status_t)
RESET_CAUSE_BITS = {"pin": 1 << 1, "WDT0": 1 << 2, "WDT1": 1 << 3, "soft": 1 << 4}
SPI3_CLK_SEL_BIT = 12        # clk_sel0: SPI3's source, 0 IN0, 1 PLL0
TIMER0_CLK_SEL_BIT = 13      # clk_sel0: timer n's source, 0 IN0, 1 PLL0

# DMA request codes selected by dma_sel (SDK sysctl_dma_select_t): the ones of modelled blocks
# sysctl_dma_select_t (the SDK's sysctl.h): which request a DMA handshake interface is given
DMA_REQUESTS = {0: ("spi0", "rx"), 1: ("spi0", "tx"), 2: ("spi1", "rx"), 3: ("spi1", "tx"),
                4: ("spi2", "rx"), 5: ("spi2", "tx"), 6: ("spi3", "rx"), 7: ("spi3", "tx"),
                8: ("i2c0", "rx"), 9: ("i2c0", "tx"), 10: ("i2c1", "rx"), 11: ("i2c1", "tx"),
                12: ("i2c2", "rx"), 13: ("i2c2", "tx"),
                14: ("uart1", "rx"), 15: ("uart1", "tx"), 16: ("uart2", "rx"), 17: ("uart2", "tx"),
                18: ("uart3", "rx"), 19: ("uart3", "tx"),
                20: ("aes", "tx"), 21: ("sha", "tx"), 22: ("ai", "rx"), 23: ("fft", "rx"), 24: ("fft", "tx"),
                25: ("i2s0", "tx"), 26: ("i2s0", "rx"), 27: ("i2s1", "tx"), 28: ("i2s1", "rx"),
                29: ("i2s2", "tx"), 30: ("i2s2", "rx")}


@dataclass
class PllState:
    """Time the PLL's reset was last released while powered (None: not running)."""

    running_since: Time | None = None


# the registers `usable` follows (gate_open, in_reset): a write to any other leaves it as it is
_GATE_REGISTERS = frozenset((CLK_EN_CENT, CLK_EN_PERI, PERI_RESET))


class Sysctl(Peripheral):
    NAME = "SYSCTL"
    BASE = K210_BLOCKS["SYSCTL"].base
    SIZE = K210_BLOCKS["SYSCTL"].size
    REGISTERS = {
        0x00: Register("git_id", writable=False, reset=0x0000_0000),
        0x04: Register("clk_freq", writable=False, reset=OSC_HZ),
        PLL0: Register("pll0", reset=(1 << PLL_PWRD_BIT)),
        PLL1: Register("pll1"),
        PLL2: Register("pll2"),
        0x14: Register("resv5"),
        PLL_LOCK: Register("pll_lock"),
        0x1C: Register("rom_error", writable=False),
        CLK_SEL0: Register("clk_sel0"),
        0x24: Register("clk_sel1"),
        CLK_EN_CENT: Register("clk_en_cent", reset=(1 << CENT_CPU) | (1 << CENT_SRAM0) | (1 << CENT_SRAM1)),
        CLK_EN_PERI: Register("clk_en_peri", reset=1 << PERI_BITS["rom"]),
        SOFT_RESET: Register("soft_reset"),
        PERI_RESET: Register("peri_reset"),
        CLK_TH0: Register("clk_th0"),
        CLK_TH1: Register("clk_th1"),
        0x40: Register("clk_th2"),
        0x44: Register("clk_th3"),
        0x48: Register("clk_th4"),
        0x4C: Register("clk_th5"),
        0x50: Register("clk_th6"),
        MISC: Register("misc"),
        0x58: Register("peri"),
        0x5C: Register("spi_sleep"),
        0x60: Register("reset_status", reset=1),
        DMA_SEL0: Register("dma_sel0"),
        DMA_SEL1: Register("dma_sel1"),
        0x6C: Register("power_sel"),
    }

    def __init__(self, ports: Ports, clock_changed: Callable[[Time], None],
                 reset_block: Callable[[str, Time], None], reset_chip: Callable[[str, Time], None]) -> None:
        """clock_changed: the CPU clock changed at this time (the board's clock follows it).
        reset_block: peri_reset released the block of this name (PERI_BITS) at this time.
        reset_chip: soft_reset resets the whole chip (cause "soft") at this time."""
        super().__init__(ports)
        self.clock_changed = clock_changed
        self.apb_changed: Callable[[], None] | None = None   # an APB clock divider changed (the bus's timing)
        self.reset_block = reset_block
        self.reset_chip = reset_chip
        self.usable: set[str] = set()   # gates open and not in reset, kept current on writes
        # PLL0 comes out of reset powered and running (at 26 MHz: all dividers 0), so it
        # reads as locked; PLL1/PLL2 are off until firmware powers them.
        self.plls = {PLL0: PllState(-PLL_LOCK_TIME), PLL1: PllState(), PLL2: PllState()}
        self.slip_sticky = {PLL0: False, PLL1: False, PLL2: False}

    def reset(self, now: Time) -> None:
        """A chip reset: every register as at power-on (PLL0 running at reset, the others off); the
        reset status keeps its cause bits (reset_status), which the board sets after this."""
        status = self.values[RESET_STATUS]
        super().reset(now)
        self.values[RESET_STATUS] = status
        self.plls = {PLL0: PllState(now - PLL_LOCK_TIME), PLL1: PllState(), PLL2: PllState()}
        self.slip_sticky = {PLL0: False, PLL1: False, PLL2: False}
        self._update_usable()

    def record_reset(self, cause: str) -> None:
        """The chip was reset by `cause` (a RESET_CAUSE_BITS key): its bit is set in reset_status
        until firmware clears the bits (reset_sts_clr)."""
        self.values[RESET_STATUS] |= RESET_CAUSE_BITS[cause]

    # --- clocks the rest of the board asks for -------------------------------------------

    def pll_locked(self, reg: int, now: Time) -> bool:
        since = self.plls[reg].running_since
        return since is not None and now - since >= PLL_LOCK_TIME

    # Every clock is a whole number of hertz (the SDK's sysctl_clock_get_freq answers in uint32_t
    # too): a PLL's output and each divider's are rounded down, so that times computed from them
    # (vtime.cycles_time) are exact integer arithmetic.

    def pll_hz(self, reg: int) -> int:
        """The PLL's output: OSC x NF / (NR x OD) (NR = clkr + 1, NF = clkf + 1, OD = clkod + 1),
        or the oscillator when bypassed."""
        value = self.values[reg]
        if value & (1 << PLL_BYPASS_BIT):
            return OSC_HZ
        clkr, clkf, clkod = field(value, *PLL_CLKR), field(value, *PLL_CLKF), field(value, *PLL_CLKOD)
        return OSC_HZ * (clkf + 1) // ((clkr + 1) * (clkod + 1))

    def cpu_hz(self) -> int:
        sel = self.values[CLK_SEL0]
        if not sel & 1:
            return OSC_HZ
        return self.pll_hz(PLL0) // (2 << field(sel, 1, 2))

    def apb0_hz(self) -> int:
        """APB0's clock: ACLK / (clk_sel0.apb0_clk_sel + 1) (the SDK's sysctl_clock_get_freq,
        SYSCTL_CLOCK_APB0; apb0_clk_sel is clk_sel0[5:3]). UART1-3 count their bit times in it."""
        return self.cpu_hz() // (field(self.values[CLK_SEL0], 3, 3) + 1)

    def apb_dividers(self) -> tuple[int, int, int]:
        """What ACLK is divided by for APB0, APB1 and APB2: clk_sel0's apb0/1/2_clk_sel ([5:3], [8:6],
        [11:9]) + 1 (sysctl_clock_get_freq, SYSCTL_CLOCK_APBn)."""
        sel = self.values[CLK_SEL0]
        return (field(sel, 3, 3) + 1, field(sel, 6, 3) + 1, field(sel, 9, 3) + 1)

    def wdt_hz(self, index: int) -> int:
        """WDTn's clock: IN0 / ((clk_th6 byte n + 1) x 2) (sysctl_clock_get_freq, SYSCTL_CLOCK_WDTn)."""
        return OSC_HZ // ((field(self.values[CLK_TH6], 8 * index, 8) + 1) * 2)

    def timer_hz(self, index: int) -> int:
        """TIMERn's clock: IN0 or PLL0 (clk_sel0 bit 13 + n) / ((clk_th2 byte n + 1) x 2) (the SDK's
        sysctl_clock_get_freq, SYSCTL_CLOCK_TIMERn)."""
        source = self.pll_hz(PLL0) if self.values[CLK_SEL0] >> (TIMER0_CLK_SEL_BIT + index) & 1 else OSC_HZ
        return source // ((field(self.values[CLK_TH2], 8 * index, 8) + 1) * 2)

    def spi_source_hz(self, index: int) -> int:
        """SPIn source clock = source / ((clk_th1 byte n + 1) * 2), the source PLL0, or for SPI3
        IN0 or PLL0 as clk_sel0.spi3_clk_sel says (the SDK's sysctl_clock_get_freq; its spi_init
        selects PLL0 for SPI3)."""
        threshold = field(self.values[CLK_TH1], 8 * index, 8)
        source = self.pll_hz(PLL0)
        if index == 3 and not self.values[CLK_SEL0] >> SPI3_CLK_SEL_BIT & 1:
            source = OSC_HZ
        return source // ((threshold + 1) * 2)

    def gate_open(self, name: str) -> bool:
        """Whether the named peripheral's clock gate and its bus gate are both on."""
        peri_bit = PERI_BITS.get(name)
        if peri_bit is not None and not self.values[CLK_EN_PERI] >> peri_bit & 1:
            return False
        bus = PERI_BUS.get(name)
        return bus is None or bool(self.values[CLK_EN_CENT] >> bus & 1)

    def refresh_usable(self) -> None:
        """After the register table was filled from outside (bootrom.py): which gates are usable."""
        self._update_usable()

    def _update_usable(self) -> None:
        self.usable = {name for name in PERI_BITS if self.gate_open(name) and not self.in_reset(name)}

    def in_reset(self, name: str) -> bool:
        bit = PERI_BITS.get(name)
        return bit is not None and bool(self.values[PERI_RESET] >> bit & 1)

    def spi_dvp_data_enabled(self) -> bool:
        return bool(self.values[MISC] >> 10 & 1)

    def dma_request(self, handshake: int) -> tuple[str, str] | None:
        """The peripheral request (device, direction) routed to DMA handshake interface n."""
        if handshake < 5:
            code = field(self.values[DMA_SEL0], 6 * handshake, 6)
        else:
            code = field(self.values[DMA_SEL1], 0, 6)
        return DMA_REQUESTS.get(code)

    # --- register behaviour ----------------------------------------------------------------

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        if offset == PLL_LOCK:
            value = 0
            for pll, lock_shift in ((PLL0, 0), (PLL1, 8), (PLL2, 16)):
                if self.pll_locked(pll, now):
                    value |= (3 if pll == PLL0 else 1) << lock_shift
                if self.slip_sticky[pll]:
                    value |= 1 << (lock_shift + 2)
            return value
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        self._write_register(offset, reg, value, now)
        if offset in _GATE_REGISTERS:
            self._update_usable()

    def _write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        if offset in self.plls:
            if offset == PLL0 and self.values[CLK_SEL0] & 1 and value != self.values[PLL0]:
                raise HardwareMisuse(
                    "SYSCTL.pll0 changed while the CPU (ACLK) runs from PLL0; switch ACLK to the "
                    "26 MHz oscillator first (clk_sel0.aclk_sel = 0), as the SDK does"
                )
            old = self.values[offset]
            self.values[offset] = value
            powered = bool(value >> PLL_PWRD_BIT & 1)
            in_reset = bool(value >> PLL_RESET_BIT & 1)
            changed_config = (old ^ value) & 0x000F_FFFF
            if not powered or in_reset or changed_config:
                self.plls[offset].running_since = None
            if powered and not in_reset and (old >> PLL_RESET_BIT & 1 or self.plls[offset].running_since is None):
                self.plls[offset].running_since = now
            return
        if offset == PLL_LOCK:
            for pll, lock_shift in ((PLL0, 0), (PLL1, 8), (PLL2, 16)):
                if value >> (lock_shift + 2) & 1:
                    self.slip_sticky[pll] = False
            return
        if offset == CLK_SEL0:
            if value & 1 and not self.values[CLK_SEL0] & 1:
                if not self.pll_locked(PLL0, now):
                    raise HardwareMisuse("SYSCTL.clk_sel0: ACLK switched to PLL0 before PLL0 locked (pll_lock[1:0] != 3)")
                if not self.values[PLL0] >> PLL_OUT_EN_BIT & 1:
                    raise HardwareMisuse("SYSCTL.clk_sel0: ACLK switched to PLL0 while PLL0's output is disabled (out_en = 0)")
            old_hz, old_apb = self.cpu_hz(), self.apb_dividers()
            self.values[CLK_SEL0] = value
            if self.cpu_hz() != old_hz:
                self.clock_changed(now)
            if self.apb_dividers() != old_apb and self.apb_changed is not None:
                self.apb_changed()
            return
        if offset == SOFT_RESET:
            self.values[offset] = value & 1
            if value & 1:
                self.reset_chip("soft", now)           # the whole chip, SYSCTL included
            return
        if offset == RESET_STATUS:
            causes = 0 if value & RESET_STS_CLR else self.values[RESET_STATUS] & ~RESET_STS_CLR
            self.values[RESET_STATUS] = causes | (value & RESET_STS_CLR)
            return
        if offset == PERI_RESET:
            released = self.values[PERI_RESET] & ~value
            self.values[PERI_RESET] = value
            for name, bit in PERI_BITS.items():
                if released >> bit & 1:
                    self.reset_block(name, now)
            return
        self.values[offset] = value

    def next_event_time(self, now: Time) -> Time | None:
        times = [s.running_since + PLL_LOCK_TIME for s in self.plls.values()
                 if s.running_since is not None and now < s.running_since + PLL_LOCK_TIME]
        return min(times) if times else None
