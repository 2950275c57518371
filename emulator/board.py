"""The Sipeed Maix Dock: a K210 (two harts, SRAM, peripherals) wired to an ST7789V LCD.

The board owns the virtual clock. Harts run in turn, in quanta of instructions
(one instruction per CPU clock cycle), and a quantum never runs past the next
moment a device changes state by itself, so interrupts and DMA completions are
seen on time. A hart that sleeps in WFI, or that keeps polling a device register
that cannot change before the next device event, costs no host time: the board
moves time forward instead.

Wiring is derived from what the firmware programmed, as on the real board: the
LCD sees SPI0 frames only through the chip select that FPIOA routes to pad 36,
and its reset and D/C lines are the GPIOHS lines routed to pads 37 and 38.
"""
from __future__ import annotations

import math
import time as host_time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import unicorn
from unicorn import riscv_const as rv

from . import hart as hartmod
from .clint import Clint
from .disasm import disassemble_one
from .dmac import Dmac
from .elf import RESET_PC, LoadedImage, load_elf, symbolize
from .errors import (BoardStop, FirmwareReportedError, FirmwareTrap, HangDetected, HardwareMisuse, StrayWrite,
                     UnmodelledAccess)
from .fpioa import (FUNC_GPIOHS0, FUNC_SPI0_SCLK, FUNC_SPI0_SS0, FUNC_SPI1_D0, FUNC_SPI1_D1, FUNC_SPI1_SCLK,
                    FUNC_SPI1_SS0, Fpioa)
from .gpiohs import Gpiohs
from .hart import CsrContext, Hart, HartState, RunEnd
from .memory import SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE, Sram
from .mmio import Peripheral
from .sdcard import SdCard, SdImage
from .plic import SOURCE_DMA0, SOURCE_GPIOHS0, SOURCE_SPI0, SOURCE_SPI1, SOURCE_UARTHS, Plic
from .spi import SpiController
from .st7789v import ST7789V
from .sysctl import Sysctl
from .uarths import Uarths
from .write_watch import WriteWatch, describe as describe_stray

HARTS = 2
DEFAULT_QUANTUM = 20_000          # instructions per hart per turn
DEFAULT_HANG_BUDGET_S = 5.0       # virtual seconds without a new frame before a run counts as hung
TRAP_GRACE_S = 0.5                # virtual time the firmware's trap handler gets to report
POLL_REPEATS = 8                  # identical reads at one pc before a hart counts as polling
# After the last requested frame the run goes on this long at most, so that the console line
# the firmware begins after that frame (this firmware's "frame N") is not cut off.
CONSOLE_DRAIN_S = 5e-3
# Distinct warnings kept in a run's list: a firmware that keeps doing something new and wrong
# must not flood the console and run.json; those beyond are only counted.
MAX_DISTINCT_WARNINGS = 100
WARNINGS_IN_HANG_REPORT = 6       # the most recent distinct warnings a hang report repeats
MTIME_DIVIDER = 50                # mtime ticks at CPU clock / 50

# Maix Dock pads
PAD_LCD_CS, PAD_LCD_RST, PAD_LCD_DC, PAD_LCD_SCLK = 36, 37, 38, 39
PAD_SD_MISO, PAD_SD_SCLK, PAD_SD_MOSI, PAD_SD_CS = 26, 27, 28, 29
SD_IDENTIFICATION_MAX_HZ = 400_000
SD_DEFAULT_SPEED_MAX_HZ = 25_000_000
FIRMWARE_ERROR_PREFIX = b"error "

# Blocks of the K210 the model knows by name but does not implement (for clear messages)
KNOWN_UNMODELLED = [
    (0x5020_0000, 0x1000, "GPIO (the slow GPIO block)"), (0x5021_0000, 0x1_0000, "UART1"),
    (0x5022_0000, 0x1_0000, "UART2"), (0x5023_0000, 0x1_0000, "UART3"), (0x5024_0000, 0x1_0000, "SPI slave"),
    (0x5025_0000, 0x3_0000, "I2S"), (0x5028_0000, 0x3_0000, "I2C"), (0x502C_0000, 0x1_0000, "SHA256"),
    (0x502D_0000, 0x3_0000, "timers"), (0x5040_0000, 0x2_0000, "WDT"), (0x5042_0000, 0x1_0000, "OTP"),
    (0x5043_0000, 0x1_0000, "DVP"), (0x5045_0000, 0x1_0000, "AES"), (0x5046_0000, 0x1_0000, "RTC"),
    (0x5400_0000, 0x100_0000, "SPI3 (on-board flash)"), (0x5000_0000 + 0x1000, 0xF000, "DMAC (past its registers)"),
    (0x5100_0000, 0x100_0000, "SPI2"), (0x4080_0000, 0x100_0000, "KPU"), (0x4200_0000, 0x100_0000, "FFT"),
    (0x8800_0000, 0x2_0000, "boot ROM"),
]


@dataclass
class FrameRecord:
    index: int
    virtual_time_s: float
    instructions: list[int]          # per hart, since the previous frame
    instructions_total: list[int]    # per hart, since reset
    host_time_s: float


@dataclass
class WarningRecord:
    """One distinct warning of a run: what, when it was first and last given, how often."""
    text: str
    first_s: float
    last_s: float
    count: int = 1

    def describe(self) -> str:
        line = f"[{self.first_s * 1e3:10.3f} ms] {self.text}"
        if self.count > 1:
            line += f" ({self.count} times in all, the last at {self.last_s * 1e3:.3f} ms)"
        return line


@dataclass
class RunResult:
    exit: str
    message: str
    frames: list[FrameRecord]
    virtual_time_s: float
    instructions: list[int]
    host_time_s: float
    warnings: list[str] = field(default_factory=list)


def _bits(word: int, high: int, low: int) -> int:
    return (word >> low) & ((1 << (high - low + 1)) - 1)


def _signed(value: int, bits: int) -> int:
    return value - (1 << bits) if value >> (bits - 1) & 1 else value


def decode_memory_access(word: int) -> tuple[int, int, int] | None:
    """(bytes moved, base register, offset) of an RV64GC load/store/AMO, or None."""
    if word & 3 != 3:                         # compressed
        op, funct3 = word & 3, _bits(word, 15, 13)
        if op == 0 and funct3 in (1, 2, 3, 5, 6, 7):          # c.fld c.lw c.ld c.fsd c.sw c.sd
            rs1 = 8 + _bits(word, 9, 7)
            if funct3 in (2, 6):
                imm = _bits(word, 12, 10) << 3 | _bits(word, 6, 6) << 2 | _bits(word, 5, 5) << 6
                return 4, rs1, imm
            return 8, rs1, _bits(word, 12, 10) << 3 | _bits(word, 6, 5) << 6
        if op == 2 and funct3 in (1, 2, 3):                    # c.fldsp c.lwsp c.ldsp
            if funct3 == 2:
                return 4, 2, _bits(word, 12, 12) << 5 | _bits(word, 6, 4) << 2 | _bits(word, 3, 2) << 6
            return 8, 2, _bits(word, 12, 12) << 5 | _bits(word, 6, 5) << 3 | _bits(word, 4, 2) << 6
        if op == 2 and funct3 in (5, 6, 7):                    # c.fsdsp c.swsp c.sdsp
            if funct3 == 6:
                return 4, 2, _bits(word, 12, 9) << 2 | _bits(word, 8, 7) << 6
            return 8, 2, _bits(word, 12, 10) << 3 | _bits(word, 9, 7) << 6
        return None
    opcode, funct3, rs1 = word & 0x7F, _bits(word, 14, 12), _bits(word, 19, 15)
    if opcode in (0x03, 0x07):                                 # loads
        return 1 << (funct3 & 3), rs1, _signed(word >> 20, 12)
    if opcode in (0x23, 0x27):                                 # stores
        return 1 << (funct3 & 3), rs1, _signed(_bits(word, 31, 25) << 5 | _bits(word, 11, 7), 12)
    if opcode == 0x2F:                                         # AMOs and LR/SC
        return (8 if funct3 == 3 else 4), rs1, 0
    return None


class LcdPort:
    """The Dock's LCD connector: SPI0's eight data lines, chip select and clock through
    FPIOA, reset and D/C on GPIOHS lines through FPIOA."""

    def __init__(self, board: "Board", lcd: ST7789V) -> None:
        self.board = board
        self.lcd = lcd

    def spi_select(self, selected: bool, now: float) -> None:
        self.lcd.set_chip_select(selected, now)

    def spi_transfer(self, data: np.ndarray, lanes: int, now: float) -> np.ndarray:
        board = self.board
        if board.fpioa.function_of_pad(PAD_LCD_SCLK) != FUNC_SPI0_SCLK:
            raise HardwareMisuse("SPI0 sends to the LCD but pad 39 (LCD WRX/clock) is not routed to SPI0_SCLK")
        if lanes != 8:
            raise HardwareMisuse(f"SPI0 sends to the LCD in a {lanes}-line format; the Dock's LCD takes SPI0's "
                                 f"eight data lines (octal frame format, ctrlr0[22:21] = 3)")
        if not board.sysctl.spi_dvp_data_enabled():
            raise HardwareMisuse("SPI0 sends to the LCD with SYSCTL misc.spi_dvp_data_enable (bit 10) clear: "
                                 "the upper data lines do not reach the LCD")
        dc = board.gpiohs_level_on_pad(PAD_LCD_DC)
        if dc is None:
            raise HardwareMisuse("SPI0 sends to the LCD but its D/C line (pad 38) is not a driven GPIOHS output")
        board.delivery_time = now
        self.lcd.write(data, dc, now)
        return np.zeros(len(data), dtype=np.uint8)


class SdSlot:
    """The Dock's micro SD slot on SPI1: MISO, clock and MOSI through FPIOA (pads 26-28),
    chip select on pad 29 as SPI1's own slave select or as a GPIOHS line."""

    def __init__(self, board: "Board", card: SdCard) -> None:
        self.board = board
        self.card = card
        self._warned_clock = False

    def cs_is_gpiohs(self) -> bool:
        function = self.board.fpioa.function_of_pad(PAD_SD_CS)
        return FUNC_GPIOHS0 <= function < FUNC_GPIOHS0 + 32

    def spi_select(self, selected: bool, now: float) -> None:
        if not self.cs_is_gpiohs():
            self.card.set_selected(selected, now)

    def gpio_changed(self, now: float) -> None:
        if self.cs_is_gpiohs():
            level = self.board.gpiohs_level_on_pad(PAD_SD_CS)
            self.card.set_selected(level == 0, now)

    def spi_transfer(self, data: np.ndarray, lanes: int, now: float) -> np.ndarray:
        fpioa = self.board.fpioa
        if fpioa.function_of_pad(PAD_SD_SCLK) != FUNC_SPI1_SCLK or fpioa.function_of_pad(PAD_SD_MOSI) != FUNC_SPI1_D0:
            return np.full(len(data), 0xFF, dtype=np.uint8)   # the card sees no clock or no data
        if lanes != 1:
            raise HardwareMisuse(f"SPI1 talks to the SD card in a {lanes}-line format; SPI mode uses one data line")
        self._check_clock()
        reply = self.card.exchange(data, now)
        if fpioa.function_of_pad(PAD_SD_MISO) != FUNC_SPI1_D1:
            return np.full(len(data), 0xFF, dtype=np.uint8)   # nothing routes the card's answer back
        return reply

    def _check_clock(self) -> None:
        hz = self.board.spi1.sclk_hz()
        limit = SD_DEFAULT_SPEED_MAX_HZ if self.card.initialised else SD_IDENTIFICATION_MAX_HZ
        if hz > limit * 1.0001 and not self._warned_clock:
            self._warned_clock = True
            phase = "in default speed mode" if self.card.initialised else "before initialisation completes"
            self.board.warn(f"SD card clocked at {hz / 1e6:.3f} MHz {phase} (the card allows {limit / 1e6:g} MHz)")


class Board:
    """A Maix Dock running one firmware image."""

    def __init__(self, firmware: str, *, quantum: int = DEFAULT_QUANTUM,
                 hang_budget_s: float = DEFAULT_HANG_BUDGET_S,
                 console: Callable[[int], None] | None = None,
                 on_frame: Callable[[FrameRecord, np.ndarray], None] | None = None,
                 on_warning: Callable[[str], None] | None = None, permissive: bool = False,
                 sd_image: str | None = None, sd_writable: bool = False,
                 sd_faults: frozenset[str] = frozenset(), check_writes: bool = False) -> None:
        """check_writes: stop with StrayWrite at the first store (a hart's or a DMA channel's) into
        SRAM outside the firmware's buffers (write_watch.py; a checker, not hardware behaviour)."""
        self.quantum = quantum
        self.permissive = permissive   # unimplemented registers of modelled devices warn instead of stopping
        self.hang_budget_s = hang_budget_s
        self.on_frame = on_frame or (lambda record, image: None)
        self.on_warning = on_warning or (lambda text: None)
        self._warning_records: dict[str, WarningRecord] = {}
        self._warnings_unlisted = 0
        self.time = 0.0
        self.delivery_time = 0.0
        self.memory = Sram()
        self.sysctl = Sysctl(self)
        self.fpioa = Fpioa(self)
        self.gpiohs = Gpiohs(self)
        self._console = console or (lambda byte: None)
        self._console_line = bytearray()
        self._line_began = 0.0                             # when the line under way began
        self._completed_line_began = float("-inf")         # when the last complete line began
        self.console_lines: list[tuple[float, str]] = []   # (virtual time the line ended, text)
        self.uarths = Uarths(self, on_byte=self._console_byte)
        self.clint = Clint(self)
        self.plic = Plic(self, high_sources=self._high_sources)
        self.dmac = Dmac(self)
        self.spi0 = SpiController(0, self)
        self.spi1 = SpiController(1, self)
        self.peripherals: list[Peripheral] = [self.sysctl, self.fpioa, self.gpiohs, self.uarths, self.clint,
                                              self.plic, self.dmac, self.spi0, self.spi1]
        self.timed_devices = [self.uarths, self.spi0, self.spi1, self.dmac, self.sysctl, self.clint]
        self._timed_set = set(self.timed_devices)
        self.lcd = ST7789V(on_frame=self._frame_captured,
                           on_warning=lambda now, text: self.warn(f"ST7789V: {text}", now))
        self.lcd_port = LcdPort(self, self.lcd)
        self.spi0.device_for_ss = self._spi0_device
        self.sd_image = SdImage(sd_image, writable=sd_writable, warn=self.warn) if sd_image else None
        self.sd_slot = SdSlot(self, SdCard(self.sd_image, warn=self.warn, faults=sd_faults)) if self.sd_image else None
        self.spi1.device_for_ss = self._spi1_device
        self._lcd_reset_level = 1
        # clock epochs: cycles and mtime are integrals of the CPU clock over virtual time
        self._epoch_time = 0.0
        self._epoch_cycles = 0
        self._epoch_mtime = 0
        self._hz = self.sysctl.cpu_hz()
        # per-run state
        self.frames: list[FrameRecord] = []
        self._frames_wanted = 0
        self._last_frame_time = 0.0
        self._last_frame_instret = [0] * HARTS
        self._host_start = host_time.perf_counter()
        self._stop: BoardStop | None = None
        self._draining = False                            # finish_console_line is running
        self._frame_while_draining = False
        self._current: Hart | None = None
        self._quantum_t0 = 0.0
        self._turn_hz = self._hz
        self._turn_horizon = 0.0
        self._quantum_start = [0] * HARTS
        self._poll = [(-1, -1, -1, 0)] * HARTS
        self._split: list[tuple[int, int, int] | None] = [None] * HARTS
        self._accesses: dict[int, tuple[int, int, int]] = {}
        self._faulting_pc: list[int | None] = [None] * HARTS
        self.device_writes: dict[str, list[int]] = {}   # stores per device, per hart
        self._grabs: list[tuple[float, Callable[["Board"], None]]] = []
        self.host_time_in_harts = 0.0                     # host seconds spent executing guest code
        self._trap_report: str | None = None
        self._error_report: tuple[int, str] | None = None
        self._trap_deadline: float | None = None
        self.image: LoadedImage = load_elf(firmware, self.memory)
        if self.image.entry != RESET_PC:
            self.warn(f"ELF entry is 0x{self.image.entry:x}, but the K210 starts both harts at 0x{RESET_PC:x}")
        sites = []
        for address, code in self.image.code_ranges:
            sites.extend(hartmod.find_csr_sites(code, address))
        self.harts = [Hart(h, CsrContext(mcycle=self._mcycle_reader(h), mip=self._mip_reader(h))) for h in range(HARTS)]
        for hart in self.harts:
            self._map(hart)
            hart.intercept_csr_sites(sites)
            hart.pc = RESET_PC
        self.write_watch: WriteWatch | None = None
        if check_writes:
            self.write_watch = WriteWatch(self.image, self.memory, HARTS, firmware)
            for hart in self.harts:
                self.write_watch.attach(hart)
            self.memory.write_check = self._check_dma_write
            if not self.write_watch.complete:
                self.warn(f"--check-writes: {firmware} has no {', '.join(self.write_watch.layout.missing)}: "
                          f"only stores into code and constants (its read-only segments) are checked")

    # --- construction -----------------------------------------------------------------

    def _map(self, hart: Hart) -> None:
        uc = hart.uc
        uc.mem_map_ptr(SRAM_BASE, SRAM_SIZE, unicorn.UC_PROT_ALL, self.memory.address)
        uc.mem_map_ptr(SRAM_UNCACHED_BASE, SRAM_SIZE, unicorn.UC_PROT_ALL, self.memory.address)
        for peripheral in self.peripherals:
            uc.mmio_map(peripheral.BASE, peripheral.SIZE,
                        self._mmio_reader(hart, peripheral), None, self._mmio_writer(hart, peripheral), None)
        uc.hook_add(unicorn.UC_HOOK_MEM_UNMAPPED | unicorn.UC_HOOK_MEM_FETCH_PROT | unicorn.UC_HOOK_MEM_READ_PROT
                    | unicorn.UC_HOOK_MEM_WRITE_PROT, self._unmapped(hart))

    def _mcycle_reader(self, h: int) -> Callable[[], int]:
        return lambda: self.cycles(self.hart_now(self.harts[h]))

    def _mip_reader(self, h: int) -> Callable[[], int]:
        return lambda: self.mip(h, self.hart_now(self.harts[h]))

    # --- virtual clock -----------------------------------------------------------------

    def cpu_hz(self) -> float:
        return self._hz

    def hart_now(self, hart: Hart) -> float:
        """The virtual time a hart has reached (mid-turn: counting its instructions so far)."""
        if hart is self._current:
            return self._quantum_t0 + (hart.executed - self._quantum_start[hart.hart_id]) / self._turn_hz
        return hart.time

    def cycles(self, now: float) -> int:
        return self._epoch_cycles + int((now - self._epoch_time) * self._hz + 1e-6)

    def mtime(self, now: float) -> int:
        return self._epoch_mtime + int((now - self._epoch_time) * self._hz / MTIME_DIVIDER + 1e-6)

    def time_of_mtime(self, value: int) -> float | None:
        if value >= 1 << 63:
            return None
        return self._epoch_time + (value - self._epoch_mtime) * MTIME_DIVIDER / self._hz

    def set_mtime(self, value: int, now: float) -> None:
        self._rebase(now)
        self._epoch_mtime = value

    def _rebase(self, now: float) -> None:
        self._epoch_cycles = self.cycles(now)
        self._epoch_mtime = self.mtime(now)
        self._epoch_time = now

    def clock_changed(self, now: float) -> None:
        """SYSCTL changed the CPU clock: later instructions take the new cycle time."""
        self._rebase(now)
        self._hz = self.sysctl.cpu_hz()
        if self._current is not None:
            self._current.request_stop()

    # --- wiring -----------------------------------------------------------------------

    def _spi0_device(self, ss: int):
        if self.fpioa.function_of_pad(PAD_LCD_CS) == FUNC_SPI0_SS0 + ss:
            return self.lcd_port
        return None

    def _spi1_device(self, ss: int):
        """The SD slot answers on SPI1 when pad 29 carries SPI1's slave select ss, or a GPIOHS
        line (then the card itself decides, from that line, whether it is selected)."""
        if self.sd_slot is None:
            return None
        function = self.fpioa.function_of_pad(PAD_SD_CS)
        if function == FUNC_SPI1_SS0 + ss or self.sd_slot.cs_is_gpiohs():
            return self.sd_slot
        return None

    def gpiohs_level_on_pad(self, pad: int) -> int | None:
        function = self.fpioa.function_of_pad(pad)
        if FUNC_GPIOHS0 <= function < FUNC_GPIOHS0 + 32:
            return self.gpiohs.driven_level(function - FUNC_GPIOHS0)
        return None

    def wiring_changed(self, now: float) -> None:
        self.advance_devices(now)
        level = self.gpiohs_level_on_pad(PAD_LCD_RST)
        level = 1 if level is None else level
        if level != self._lcd_reset_level:
            self._lcd_reset_level = level
            self.lcd.set_reset_pin(level, now)
        self.spi0.wiring_changed(now)
        self.spi1.wiring_changed(now)
        if self.sd_slot is not None:
            self.sd_slot.gpio_changed(now)

    def spi_by_name(self, name: str) -> SpiController:
        return {"spi0": self.spi0, "spi1": self.spi1}[name]

    def reset_peripheral(self, name: str, now: float) -> None:
        """SYSCTL peri_reset released a block: it returns to its reset state."""
        target = {"spi0": self.spi0, "spi1": self.spi1, "dma": self.dmac, "fpioa": self.fpioa}.get(name)
        if target is not None:
            self.advance_devices(now)
            target.reset(now)

    def _console_byte(self, byte: int) -> None:
        """Console output; a line `error <code> ...` is the firmware's fatal error report."""
        self._console(byte)
        if not self._console_line:
            self._line_began = self.uarths.last_byte_time
        if byte != 10:
            self._console_line.append(byte)
            return
        line = bytes(self._console_line).rstrip(b"\r")
        self._console_line.clear()
        self._completed_line_began = self._line_began
        self.console_lines.append((self.uarths.last_byte_time, line.decode("ascii", "replace")))
        if line.startswith(FIRMWARE_ERROR_PREFIX) and self._error_report is None:
            words = line.decode("ascii", "replace")
            code = words.split()[1] if len(words.split()) > 1 else ""
            if code.isdigit():
                self._error_report = (int(code), words)
                self._trap_deadline = self.time + TRAP_GRACE_S

    def close(self) -> None:
        """Releases the SD card image (flushing it when writes were allowed)."""
        if self.sd_image is not None:
            self.sd_image.close()

    def warn(self, text: str, now: float | None = None) -> None:
        """Every device's warnings come here (`now`: the virtual time the device noticed it,
        else the board's). A warning given again with the same text is counted, not repeated:
        on_warning hears only its first occurrence."""
        at = self.time if now is None else now
        record = self._warning_records.get(text)
        if record is not None:
            record.count += 1
            record.last_s = max(record.last_s, at)
            return
        if len(self._warning_records) >= MAX_DISTINCT_WARNINGS:
            self._warnings_unlisted += 1
            return
        record = WarningRecord(text, at, at)
        self._warning_records[text] = record
        self.on_warning(record.describe())

    @property
    def warnings(self) -> list[str]:
        """The run's warnings, one line per distinct text in the order first given, with how
        often and until when each recurred."""
        lines = [record.describe() for record in self._warning_records.values()]
        if self._warnings_unlisted:
            lines.append(f"{self._warnings_unlisted} further warnings not listed (only the first "
                         f"{MAX_DISTINCT_WARNINGS} distinct ones are)")
        return lines

    @property
    def repeated_warnings(self) -> list[str]:
        """The warnings given more than once, with their counts (on_warning heard each once)."""
        return [record.describe() for record in self._warning_records.values() if record.count > 1]

    def recent_warnings(self, count: int) -> list[str]:
        """The `count` distinct warnings most recently given, oldest first."""
        records = sorted(self._warning_records.values(), key=lambda record: record.last_s)[-count:]
        return [record.describe() for record in records]

    # --- interrupts --------------------------------------------------------------------

    def _high_sources(self) -> list[int]:
        """PLIC sources whose interrupt line is high right now."""
        high = []
        if self.spi0.irq_line():
            high.append(SOURCE_SPI0)
        if self.spi1.irq_line():
            high.append(SOURCE_SPI1)
        high.extend(SOURCE_DMA0 + n for n in range(6) if self.dmac.irq_line(n))
        if self.uarths.irq_line():
            high.append(SOURCE_UARTHS)
        lines = self.gpiohs.irq_lines()
        high.extend(SOURCE_GPIOHS0 + n for n in range(32) if lines >> n & 1)
        return high

    def mip(self, h: int, now: float, mask: int = ~0) -> int:
        """The hart's pending interrupt bits; only those in `mask` are computed (sampling the
        PLIC is the expensive part, and a hart that has MEIE clear does not need it)."""
        value = 0
        if mask >> hartmod.IRQ_MSI & 1 and self.clint.msip(h):
            value |= 1 << hartmod.IRQ_MSI
        if mask >> hartmod.IRQ_MTI & 1 and self.clint.timer_pending(h, now):
            value |= 1 << hartmod.IRQ_MTI
        if mask >> hartmod.IRQ_MEI & 1 and self.plic.external_pending(h):
            value |= 1 << hartmod.IRQ_MEI
        return value

    def interrupts_may_have_changed(self, now: float | None = None) -> None:
        """A device changed an interrupt input at `now`: sleeping harts it concerns wake
        then, and a running hart with interrupts enabled ends its turn to take it."""
        self._wake_sleepers(self.time if now is None else now)
        hart = self._current
        if hart is not None and hart.reg(rv.UC_RISCV_REG_MSTATUS) & hartmod.MSTATUS_MIE:
            hart.request_stop()

    # --- devices ------------------------------------------------------------------------

    def advance_devices(self, now: float) -> None:
        for device in self.timed_devices:
            device.advance(now)

    def next_device_event(self, now: float) -> float | None:
        times = [t for t in (d.next_event_time(now) for d in self.timed_devices) if t is not None and t > now]
        return min(times) if times else None

    # --- memory-mapped I/O dispatch --------------------------------------------------------

    def _describe_access(self, hart: Hart, address: int, size: int, direction: str, pc: int | None = None) -> str:
        """'hart H at pc P <symbol> (instruction): <direction> of N bytes at A'; the pc is the
        hart's current one unless given (a store the run has already gone past)."""
        if pc is None:
            pc = hart.uc.reg_read(rv.UC_RISCV_REG_PC)
        code = bytes(hart.uc.mem_read(pc, 4)) if self._is_sram(pc) else b""
        where = symbolize(self.image.symbols, pc)
        where = f" <{where}>" if where else ""
        return (f"hart {hart.hart_id} at pc 0x{pc:08x}{where} ({disassemble_one(code, pc)}): "
                f"{direction} of {size} bytes at 0x{address:08x}")

    def _is_device(self, address: int) -> bool:
        return any(p.BASE <= address < p.BASE + p.SIZE for p in self.peripherals)

    @staticmethod
    def _is_sram(address: int) -> bool:
        return SRAM_BASE <= address < SRAM_BASE + SRAM_SIZE or SRAM_UNCACHED_BASE <= address < SRAM_UNCACHED_BASE + SRAM_SIZE

    def _fail(self, hart: Hart, error: BoardStop, address: int, size: int, direction: str) -> None:
        if self.permissive and isinstance(error, UnmodelledAccess) and self._is_device(address):
            self.warn(f"{self._describe_access(hart, address, size, direction)}: {error.args[0]} "
                      f"(permissive: loads read 0, stores are ignored)")
            return
        if self._stop is None:
            error.args = (f"{self._describe_access(hart, address, size, direction)}: {error.args[0]}",)
            self._stop = error
        hart.request_stop()

    def _check_dma_write(self, address: int, length: int, writer: str) -> None:
        """--check-writes for the DMAC: a write outside the firmware's buffers ends the run (the
        current hart's turn ends after its instruction; between turns, _step raises)."""
        stray = self.write_watch.check_dma(address, length)
        if stray is None or self._stop is not None:
            return
        self._stop = StrayWrite(f"{writer}: write of {length} bytes at 0x{address:08x}..0x{address + length - 1:08x}: "
                                f"{describe_stray(stray)}")
        if self._current is not None:
            self._current.request_stop()

    def _gate_check(self, peripheral: Peripheral) -> None:
        gate = getattr(peripheral, "GATE", None)
        if gate is None or gate in self.sysctl.usable:
            return
        if not self.sysctl.gate_open(gate):
            raise HardwareMisuse(f"{peripheral.NAME} accessed while its clock is gated "
                                 f"(SYSCTL clk_en_peri / clk_en_cent): enable its clock first")
        if self.sysctl.in_reset(gate):
            raise HardwareMisuse(f"{peripheral.NAME} accessed while held in reset (SYSCTL peri_reset)")

    def _access(self, hart: Hart, pc: int) -> tuple[int, int, int]:
        """(width, base register, offset) of the load/store at pc, decoded once per pc.
        Unicorn splits a 64-bit or misaligned MMIO access into several callbacks; the
        instruction says what the hart really did."""
        access = self._accesses.get(pc)
        if access is None:
            access = decode_memory_access(hart.read_u32(pc)) or (4, 0, 0)
            self._accesses[pc] = access
        return access

    def _misaligned(self, hart: Hart, pc: int, width: int, rs1: int, imm: int, is_store: bool) -> bool:
        """A misaligned device access raises the misaligned-access exception, as on the K210;
        the rest of the instruction's callbacks are ignored."""
        if self._faulting_pc[hart.hart_id] == pc:
            return True
        base = hart.reg(rv.UC_RISCV_REG_X0 + rs1) if rs1 else 0
        address = (base + imm) & (2**64 - 1)
        if address % width == 0:
            return False
        hart.pending_exception = hartmod.PendingException(6 if is_store else 4, pc, address)
        hart.retired_adjust += 1
        hart.request_stop()
        self._faulting_pc[hart.hart_id] = pc
        return True

    def _mmio_reader(self, hart: Hart, peripheral: Peripheral):
        def read(uc, offset, size, user_data):
            if self._stop is not None:
                return 0
            pc = hart.reg(rv.UC_RISCV_REG_PC)
            pending = self._split[hart.hart_id]
            if pending is not None and pending[:2] == (pc, offset):
                self._split[hart.hart_id] = None
                return pending[2]
            now = self.hart_now(hart)
            width, rs1, imm = self._access(hart, pc)
            if self._misaligned(hart, pc, width, rs1, imm, False):
                return 0
            try:
                self._gate_check(peripheral)
                value = peripheral.read(offset, width, now)
            except BoardStop as error:
                self._fail(hart, error, peripheral.BASE + offset, width, "load")
                return 0
            if width == 8 and size == 4:
                self._split[hart.hart_id] = (pc, offset + 4, value >> 32)
                value &= 0xFFFF_FFFF
            self._note_poll(hart, pc, offset + peripheral.BASE, value)
            return value
        return read

    def _mmio_writer(self, hart: Hart, peripheral: Peripheral):
        def write(uc, offset, size, value, user_data):
            if self._stop is not None:
                return
            pc = hart.reg(rv.UC_RISCV_REG_PC)
            width, rs1, imm = self._access(hart, pc)
            if self._misaligned(hart, pc, width, rs1, imm, True):
                return
            if width == 8 and size == 4:
                pending = self._split[hart.hart_id]
                if pending is None or pending[:2] != (pc, offset):
                    self._split[hart.hart_id] = (pc, offset + 4, value & 0xFFFF_FFFF)
                    return
                self._split[hart.hart_id] = None
                offset, value = offset - 4, pending[2] | (value & 0xFFFF_FFFF) << 32
            now = self.hart_now(hart)
            self._poll[hart.hart_id] = (-1, -1, -1, 0)
            self.device_writes.setdefault(peripheral.NAME, [0] * HARTS)[hart.hart_id] += 1
            try:
                self._gate_check(peripheral)
                peripheral.write(offset, width, value, now)
            except BoardStop as error:
                self._fail(hart, error, peripheral.BASE + offset, width, "store")
                return
            # a store that makes a device do something before this turn's planned end (start a
            # transfer, set a timer) ends the turn, so the next one stops at that event
            # A hart with interrupts enabled must take an interrupt the moment its device raises
            # it: a store that schedules something before this turn's planned end ends the turn.
            # (Without mstatus.MIE nothing can preempt the hart; status reads are exact in any
            # case, and sleeping harts wake at the event's own time.)
            if peripheral in self._timed_set and hart.reg(rv.UC_RISCV_REG_MSTATUS) & hartmod.MSTATUS_MIE:
                event = self.next_device_event(now)
                if event is not None and event < self._turn_horizon:
                    hart.request_stop()
        return write

    def _note_poll(self, hart: Hart, pc: int, address: int, value: int) -> None:
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

    def _unmapped(self, hart: Hart):
        def hook(uc, access, address, size, value, user_data):
            fetch = access in (unicorn.UC_MEM_FETCH_UNMAPPED, unicorn.UC_MEM_FETCH_PROT)
            write = access in (unicorn.UC_MEM_WRITE_UNMAPPED, unicorn.UC_MEM_WRITE_PROT)
            name = next((n for base, length, n in KNOWN_UNMODELLED if base <= address < base + length), None)
            if fetch:
                error: BoardStop = FirmwareTrap(
                    f"hart {hart.hart_id}: instruction fetch from 0x{address:08x}, which is not memory "
                    f"(jumped from around pc 0x{uc.reg_read(rv.UC_RISCV_REG_PC):08x})")
                if self._stop is None:
                    self._stop = error
                return False
            reason = (f"{name}, which the board model does not implement" if name
                      else "no device or memory answers at this address")
            self._fail(hart, UnmodelledAccess(reason), address, size, "store" if write else "load")
            return False
        return hook

    # --- frames ---------------------------------------------------------------------------

    def _frame_captured(self, image: np.ndarray) -> None:
        if self._draining:
            # a frame beyond the requested ones: not recorded, and the drain ends here
            self._frame_while_draining = True
            if self._current is not None:
                self._current.request_stop()
            return
        totals = [h.instret for h in self.harts]
        record = FrameRecord(
            index=len(self.frames),
            virtual_time_s=self.delivery_time,
            instructions=[t - last for t, last in zip(totals, self._last_frame_instret)],
            instructions_total=totals,
            host_time_s=host_time.perf_counter() - self._host_start,
        )
        self._last_frame_instret = totals
        self._last_frame_time = self.delivery_time
        self.frames.append(record)
        self.on_frame(record, image)
        if len(self.frames) >= self._frames_wanted and self._current is not None and self._trap_deadline is None:
            self._current.request_stop()

    # --- the run loop ----------------------------------------------------------------------

    def grab_at(self, at_s: float, action: Callable[["Board"], None]) -> None:
        """Calls action(board) once the board's virtual time reaches at_s (a framebuffer grab)."""
        self._grabs.append((at_s, action))
        self._grabs.sort(key=lambda item: item[0])

    def _run_grabs(self) -> None:
        while self._grabs and self._grabs[0][0] <= self.time:
            _, action = self._grabs.pop(0)
            action(self)

    def run(self, frames: int, progress: Callable[["Board"], None] | None = None) -> RunResult:
        """Runs until `frames` frames have been shown. Raises a BoardStop subclass otherwise."""
        self._frames_wanted = frames
        self._host_start = host_time.perf_counter()
        last_progress = 0.0
        # a firmware that reported an error or trapped is given its grace period even when
        # its error screen was the last frame asked for: the run ends with that error
        while len(self.frames) < frames or self._trap_deadline is not None:
            self._step()
            if self._grabs:
                self._run_grabs()
            if progress is not None and host_time.perf_counter() - last_progress > 0.5:
                last_progress = host_time.perf_counter()
                progress(self)
        return RunResult("ok", f"{len(self.frames)} frames shown", self.frames, self.time,
                         [h.instret for h in self.harts], host_time.perf_counter() - self._host_start,
                         self.warnings)

    def finish_console_line(self, limit_s: float = CONSOLE_DRAIN_S) -> None:
        """After run(): runs on until the first console line begun after the last frame was
        shown has ended (this firmware's hart 1 reports "frame N" once frame N is sent, after
        the LCD has it), for at most limit_s of virtual time, so that the console of an N-frame
        run ends with its last frame's line. Frames shown meanwhile are not recorded and end
        it; so does a firmware that will never do anything again. A trap or error report
        meanwhile gets its grace period and ends the run as in run(). Kept out of run() so
        that a run's instruction counts up to its last frame (the bench's) do not change."""
        frame_time = self._last_frame_time
        deadline = self.time + limit_s
        self._draining, self._frame_while_draining = True, False
        self._frames_wanted = len(self.frames) + 1     # _turn moves time on as before a frame
        try:
            while (self._completed_line_began < frame_time and self.time < deadline
                   and not self._frame_while_draining and self._trap_deadline is None):
                if not any(h.state is HartState.RUNNING for h in self.harts) and \
                        self.next_device_event(self.time) is None:
                    break
                self._step()
                if self._grabs:
                    self._run_grabs()
        finally:
            self._draining = False
            self._frames_wanted = len(self.frames)
        while self._trap_deadline is not None:
            self._step()

    def _step(self) -> None:
        """One turn (see _turn); a stop recorded by a device outside a hart's turn (a stray
        DMA write while every hart sleeps) ends the run here."""
        self._turn()
        if self._stop is not None:
            raise self._stop

    def _turn(self) -> None:
        """One turn: the running hart that is furthest behind in virtual time runs until
        its quantum ends, the next device event, or one quantum past the other hart."""
        running = [h for h in self.harts if h.state is HartState.RUNNING]
        if not running:
            # every hart sleeps in wfi: time moves on to the next thing a device does
            wake = self.next_device_event(self.time)
            if wake is None:
                self._report_hang("every hart sleeps in wfi and no device will ever raise an interrupt")
            if self._grabs and self.time < self._grabs[0][0] < wake:
                wake = self._grabs[0][0]   # stop at a requested grab rather than jump past it
            self._set_time(wake)
            self._check_deadlines()
            return
        hart = min(running, key=lambda h: (h.time, h.hart_id))
        self._take_interrupt(hart)
        t0 = hart.time
        hz = self._hz
        horizon = t0 + self.quantum / hz
        event = self.next_device_event(t0)
        if event is not None:
            horizon = min(horizon, event)
        if self._grabs and self._grabs[0][0] > t0:
            horizon = min(horizon, self._grabs[0][0])
        for other in running:
            if other is not hart:
                horizon = min(horizon, other.time + self.quantum / hz)
        budget = max(1, math.ceil((horizon - t0) * hz - 1e-9))
        self._turn_horizon = t0 + budget / hz
        ran = self._run_hart(hart, t0, budget, hz)
        if self._stop is not None:
            raise self._stop
        hart.time = t0 + ran / hz
        if hart.polling:
            # nothing the hart's loop does will change what it polls before the next device
            # event: it waits until then (or the end of its turn) without executing
            hart.polling = False
            event = self.next_device_event(hart.time)
            hart.time = max(hart.time, min(event, horizon) if event is not None else horizon)
        if len(self.frames) >= self._frames_wanted and self._trap_deadline is None:
            self.time = max(self.time, self.delivery_time)
            return
        running = [h.time for h in self.harts if h.state is HartState.RUNNING]
        if running:
            self._set_time(min(running))
        self._check_deadlines()

    def _set_time(self, now: float) -> None:
        """Moves the board's time (the earliest time a running hart has reached) forward:
        devices catch up and sleeping harts with a pending enabled interrupt wake."""
        if now > self.time:
            self.time = now
        self.advance_devices(self.time)
        self._wake_sleepers(self.time)

    def _wake_sleepers(self, now: float) -> None:
        for hart in self.harts:
            if hart.state is not HartState.ASLEEP:
                continue
            enabled = hart.reg(rv.UC_RISCV_REG_MIE)
            if enabled and self.mip(hart.hart_id, now, enabled):
                hart.state = HartState.RUNNING
                hart.time = max(hart.time, now)

    def _take_interrupt(self, hart: Hart) -> None:
        """Before a turn: a pending enabled interrupt with mstatus.MIE set enters mtvec."""
        if not hart.reg(rv.UC_RISCV_REG_MSTATUS) & hartmod.MSTATUS_MIE:
            return
        enabled = hart.reg(rv.UC_RISCV_REG_MIE)
        pending = self.mip(hart.hart_id, hart.time, enabled) & enabled
        for irq in (hartmod.IRQ_MEI, hartmod.IRQ_MSI, hartmod.IRQ_MTI):
            if pending >> irq & 1:
                hart.enter_trap(hartmod.CAUSE_INTERRUPT | irq, hart.pc, 0)
                return

    def _run_hart(self, hart: Hart, t0: float, budget: int, hz: float) -> int:
        """Runs one turn of a hart; returns how many instructions it executed."""
        self._current = hart
        self._faulting_pc[hart.hart_id] = None
        self._quantum_t0 = t0
        self._turn_hz = hz
        self._quantum_start[hart.hart_id] = hart.executed
        started = host_time.perf_counter()
        before = hart.executed
        end = None
        try:
            end, _ = hart.run(budget)
        except unicorn.UcError as error:
            hart.pc = hart.uc.reg_read(rv.UC_RISCV_REG_PC)
            if self._stop is None:
                if error.errno == unicorn.UC_ERR_INSN_INVALID and (hart.read_u16(hart.pc) == 0x9002 or
                                                                    hart.read_u32(hart.pc) == 0x00100073):
                    hart.note_breakpoint()
                    end = RunEnd.EXCEPTION
                else:
                    code = bytes(hart.uc.mem_read(hart.pc, 4)) if self._is_sram(hart.pc) else b""
                    self._stop = FirmwareTrap(f"hart {hart.hart_id} at pc 0x{hart.pc:08x} "
                                              f"({disassemble_one(code, hart.pc)}): {error}")
        finally:
            self._current = None
            self.host_time_in_harts += host_time.perf_counter() - started
        stray = self.write_watch.stray_store(hart) if self.write_watch is not None else None
        if stray is not None:
            # the hart stopped right after the stray store, so nothing it did later this turn
            # can have been recorded: the store is what ends the run
            access = self._describe_access(hart, stray.address, stray.size, "store", stray.pc)
            self._stop = StrayWrite(f"{access}: {describe_stray(stray)}")
        ran = hart.executed - before
        if self._stop is None:
            if end is RunEnd.WFI:
                hart.state = HartState.ASLEEP
            elif end is RunEnd.EXCEPTION:
                self._deliver_exception(hart)
        return ran

    def _deliver_exception(self, hart: Hart) -> None:
        exc = hart.pending_exception
        hart.pending_exception = None
        code = bytes(hart.uc.mem_read(exc.epc, 4)) if self._is_sram(exc.epc) else b""
        where = symbolize(self.image.symbols, exc.epc)
        report = (f"hart {hart.hart_id}: {hartmod.EXCEPTION_NAMES.get(exc.cause, f'exception {exc.cause}')} "
                  f"at pc 0x{exc.epc:08x}{f' <{where}>' if where else ''} ({disassemble_one(code, exc.epc)}), "
                  f"mtval 0x{exc.tval:x}")
        mtvec = hart.csr(rv.UC_RISCV_REG_MTVEC)
        if self._trap_report is not None:
            raise FirmwareTrap(f"{self._trap_report}; then, in the trap handler, {report}")
        if mtvec & ~3 == 0 or not self._is_sram(mtvec & ~3):
            raise FirmwareTrap(f"{report}; mtvec = 0x{mtvec:x} points at no trap handler")
        self._trap_report = report
        self._trap_deadline = self.time + TRAP_GRACE_S
        hart.enter_trap(exc.cause, exc.epc, exc.tval)

    def _check_deadlines(self) -> None:
        if self._trap_deadline is not None:
            everyone_waits = all(h.state is not HartState.RUNNING for h in self.harts) and \
                self.next_device_event(self.time) is None
            if self.time >= self._trap_deadline or everyone_waits:
                if self._trap_report is not None:
                    raise FirmwareTrap(self._trap_report + " (the firmware's trap handler has run; see the console)")
                code, line = self._error_report
                raise FirmwareReportedError(f"the firmware reported: {line}", code)
        if self.time - self._last_frame_time > self.hang_budget_s and not self._draining:
            self._report_hang(f"no frame reached the LCD for {self.hang_budget_s:g} s of virtual time")

    def _report_hang(self, why: str) -> None:
        lines = [why]
        for hart in self.harts:
            code = bytes(hart.uc.mem_read(hart.pc, 4)) if self._is_sram(hart.pc) else b""
            where = symbolize(self.image.symbols, hart.pc)
            lines.append(f"hart {hart.hart_id}: {hart.state.value} at pc 0x{hart.pc:08x}"
                         f"{f' <{where}>' if where else ''} ({disassemble_one(code, hart.pc)}), "
                         f"mie 0x{hart.csr(rv.UC_RISCV_REG_MIE):x}, mip 0x{self.mip(hart.hart_id, self.time):x}")
        for peripheral in self.peripherals:
            text = peripheral.describe_wait()
            if text:
                lines.append(text)
        lines.append(f"LCD: {self.lcd.frames_captured} frames captured, display "
                     f"{'on' if self.lcd.display_on else 'off'}, {'asleep' if self.lcd.sleeping else 'awake'}")
        recent = self.recent_warnings(WARNINGS_IN_HANG_REPORT)
        if recent:
            lines.append(f"the most recent warnings (of {len(self.warnings)} in the run, every one in run.json):")
            lines.extend(f"  {text}" for text in recent)
        raise HangDetected("\n  ".join(lines))
