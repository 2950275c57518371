"""The Sipeed Maix Dock: a K210 (two harts, SRAM, peripherals) wired to an ST7789V LCD.

This module builds the board and connects its parts; each part is a module of its own:
the clock and scheduler (scheduler.py: virtual time, the harts and their turns,
deadlines, hang detection), the bus (bus.py: address decoding and the rules of an
access), the Dock's wiring (wiring.py: the LCD port and SD slot routed through FPIOA)
and one module per device. The board also collects the run's warnings and the
console, and routes interrupt lines to the PLIC and the harts.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from . import bootrom
from ..cpu.privileged import find_csr_sites
from ..cpu import riscv
from .bus import Bus
from ..devices.clint import Clint
from ..cpu.disasm import disassemble_one
from ..devices.dmac import Dmac
from .elf import LoadedImage
from .flash_image import FlashImage
from .raw_image import load_firmware, load_program
from ..errors import BadInput, BoardStop, UnmodelledAccess
from ..devices.fpioa import FUNC_UART1_RX, FUNC_UART1_TX, FUNC_UARTHS_RX, FUNC_UARTHS_TX, PAD_COUNT, Fpioa
from ..devices.fft import Fft
from ..devices.otp import Otp
from ..devices.gpio import Gpio
from ..devices.gpiohs import Gpiohs
from ..cpu.hart import ENGINE_FAST, ENGINES, Hart
from .memory import Sram
from ..memory_map import K210_BLOCKS, RESET_PC, SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE, is_sram, sram_views
from ..devices.mmio import Peripheral
from ..devices.ports import Ports
from ..devices.plic import Plic
from ..devices.ports import SerialInput
from ..devices.plic import m_context as plic_m_context
from ..devices.plic import s_context as plic_s_context
from .scheduler import (DEFAULT_HANG_BUDGET, DEFAULT_QUANTUM, HARTS, FrameRecord, RunResult,  # noqa: F401
                        Scheduler)  # FrameRecord and RunResult: the board's results, imported from here
from ..devices.sdcard import READ_ACCESS_TIME, SdCard, SdImage
from ..cpu.shared_memory import find_poll_loops
from ..cpu.time_loops import find_idle_loops, find_time_loops
from ..devices.spi import DWC_SSI, SpiController
from ..devices.w25q128 import W25Q128
from ..devices.st7789v import ST7789V
from ..cpu.caches import HartCaches
from ..cpu.timing import MISPREDICT_PENALTY, REDIRECT_BUBBLE, TIMING_IPC1, TIMING_MODELS, TIMING_ROCKET, build_table
from ..devices.sysctl import Sysctl
from ..devices.timer import DwTimer
from ..devices.uart import DwUart
from ..devices.rtc import Rtc
from ..devices.sha256 import Sha256
from ..devices.wdt import DwWatchdog
from ..devices.uarths import Uarths
from .pins import ExternalPins, PinChange
from .wiring import LCD_8080, ChipPins, DockWiring, LcdPort, RoutedInput, SdSlot
from .write_watch import WriteWatch
from ..vtime import PS_PER_MS, Time, ms
from k210_common.firmware_errors import CONSOLE_PREFIX

# a fatal error's console line, "error <code> <words>", as firmware/include/errors.inc describes it
FIRMWARE_ERROR_PREFIX = CONSOLE_PREFIX.encode()
# What a run keeps of each UART's output for run.json; beyond it only the count goes on
MAX_UART_OUTPUT = 1 << 20
# Distinct warnings kept in a run's list: a firmware that keeps doing something new and wrong
# must not flood the console and run.json; those beyond are only counted.
MAX_DISTINCT_WARNINGS = 100


class SchedulerClock:
    """The devices' Clock and MtimeCounter ports (devices/ports.py): the scheduler's clock. The
    devices are made first (the scheduler starts from the CPU clock they set), so the board hands
    the scheduler to this port once it exists."""

    def __init__(self) -> None:
        self.scheduler: Scheduler | None = None

    def cpu_hz(self) -> int:
        return self.scheduler.cpu_hz()

    def now(self) -> Time:
        return self.scheduler.time

    def mtime(self, now: Time) -> int:
        return self.scheduler.mtime(now)

    def set_mtime(self, value: int, now: Time) -> None:
        self.scheduler.set_mtime(value, now)

    def time_of_mtime(self, value: int) -> Time | None:
        return self.scheduler.time_of_mtime(value)


@dataclass
class WarningRecord:
    """One distinct warning of a run: what, when it was first and last given, how often."""
    text: str
    first: Time
    last: Time
    count: int = 1

    def describe(self) -> str:
        line = f"[{self.first / PS_PER_MS:10.3f} ms] {self.text}"
        if self.count > 1:
            line += f" ({self.count} times in all, the last at {ms(self.last)})"
        return line


class Board:
    """A Maix Dock running one firmware image."""

    def __init__(self, firmware: str | None, *, flash: FlashImage | None = None, quantum: int = DEFAULT_QUANTUM,
                 hang_budget: Time = DEFAULT_HANG_BUDGET,
                 console: Callable[[int], None] | None = None,
                 on_frame: Callable[[FrameRecord, np.ndarray], None] | None = None,
                 on_warning: Callable[[str], None] | None = None, permissive: bool = False,
                 sd_image: str | None = None, sd_writable: bool = False,
                 sd_faults: frozenset[str] = frozenset(), sd_access_time: Time = READ_ACCESS_TIME,
                 check_writes: bool = False, strict: bool = False,
                 lcd_interface: str = LCD_8080, cold: bool = False, timing: str = TIMING_ROCKET,
                 engine: str = ENGINE_FAST, pins: list[PinChange] = (), otp: bytes | None = None,
                 otp_source: str = "") -> None:
        """firmware: an ELF or a raw .bin, copied into SRAM; or None: boot the program in `flash` as the
        mask ROM does (flash_image.py).
        flash: the on-board SPI flash's content (--flash).
        check_writes: stop with StrayWrite at the first store (a hart's or a DMA channel's) into
        SRAM outside the firmware's buffers (write_watch.py; a checker, not hardware behaviour).
        strict: stop at the first access a register table does not take as it is, or that no device
        answers, instead of answering it as the K210's bus does with a warning (bus.py); and have the
        LCD and the SD card enforce their datasheets' waits instead of warning only.
        lcd_interface: the LCD's bus, the Dock's 8-bit parallel panel or a 4-line serial module
        (wiring.py, LCD_INTERFACES).
        cold: start from the reset value of every register, instead of the state the mask ROM
        leaves when it jumps to the program (bootrom.py).
        timing: what an instruction costs: "rocket" (the K210's Rocket core, timing.py, with its L1 caches, caches.py), "rocket-nocache" (every access a hit) or "ipc1"
        (one cycle each).
        pins: levels driven on pads from outside at given times (pins.py, --pin).
        otp: the OTP's content (--otp; None: blank), `otp_source` naming where it came from.
        engine: "fast" runs each hart on our interpreter of the code in SRAM where it can, handing
        the rest to Unicorn, "precise" on Unicorn alone, counting each instruction (hart.py,
        _fast_engine.c); what runs and every count are the same."""
        if timing not in TIMING_MODELS:
            raise ValueError(f"unknown timing model {timing!r}: one of {', '.join(TIMING_MODELS)}")
        if engine not in ENGINES:
            raise ValueError(f"unknown engine {engine!r}: one of {', '.join(ENGINES)}")
        self.engine = engine
        self.timing = timing
        self.permissive = permissive   # unimplemented registers of modelled devices warn instead of stopping
        self.on_frame = on_frame or (lambda record, image: None)
        self.on_warning = on_warning or (lambda text: None)
        self._warning_records: dict[str, WarningRecord] = {}
        self._warnings_unlisted = 0
        self.memory = Sram()
        self.clock = SchedulerClock()
        ports = Ports(clock=self.clock, warn=self.warn, irq_changed=self.interrupts_may_have_changed,
                      catch_up=self.advance_devices, signal=self.signal,
                      wiring_changed=lambda now: self.wiring.changed(now))
        reset_chip = lambda cause, at: self.scheduler.request_reset(cause, at)   # noqa: E731
        self.sysctl = Sysctl(ports, clock_changed=lambda now: self.scheduler.clock_changed(now),
                             reset_block=self.reset_peripheral, reset_chip=reset_chip)
        self.fpioa = Fpioa(ports)
        self.pins = ExternalPins(pins, on_change=lambda at: self.wiring.changed(at))
        self.gpiohs = Gpiohs(ports, pad_inputs=lambda first, count: self.wiring.pad_inputs(first, count))
        self.gpio = Gpio(ports, pad_inputs=lambda first, count: self.wiring.pad_inputs(first, count))
        self._console = console or (lambda byte: None)
        self._console_line = bytearray()
        self.console_byte_time: Time = 0                   # when the console's last byte was out
        self._line_began: Time = 0                         # when the line under way began
        self.completed_line_began: Time = -1               # when the last complete line began (-1: none)
        self.console_lines: list[tuple[Time, str]] = []    # (virtual time the line ended, text)
        self.uart_output: dict[str, bytearray] = {}       # what each UART sent, wherever it went
        self.uarths = Uarths(ports, on_byte=lambda byte: self._serial_out(self.uarths, FUNC_UARTHS_TX, byte))
        self.uarts = [DwUart(n, ports, source_hz=self.sysctl.apb0_hz,
                             on_byte=lambda byte, n=n: self._serial_out(self.uarts[n - 1], FUNC_UART1_TX + 2 * (n - 1),
                                                                        byte))
                      for n in (1, 2, 3)]
        self.timers = [DwTimer(n, ports, clock_hz=lambda n=n: self.sysctl.timer_hz(n)) for n in range(3)]
        self.watchdogs = [DwWatchdog(n, ports, clock_hz=lambda n=n: self.sysctl.wdt_hz(n), reset_chip=reset_chip)
                          for n in range(2)]
        self.rtc = Rtc(ports, pulse=lambda at: self.plic.latch(K210_BLOCKS["RTC"].irqs[0], at))
        self.sha256 = Sha256(ports)
        self.fft = Fft(ports)
        self.otp = Otp(ports, otp, otp_source)
        self.clint = Clint(ports, counter=self.clock)
        self.plic = Plic(ports, high_sources=self._high_sources)
        self.spi0 = SpiController(0, ports, source_hz=lambda: self.sysctl.spi_source_hz(0))
        self.spi1 = SpiController(1, ports, source_hz=lambda: self.sysctl.spi_source_hz(1))
        self.spi3 = SpiController(3, ports, source_hz=lambda: self.sysctl.spi_source_hz(3), layout=DWC_SSI)
        # the on-board flash: SPI3's pads are its own (not routed through FPIOA), chip select 0
        self.flash = flash if flash is not None else FlashImage.erased()
        self.flash_chip = W25Q128(self.flash.data, warn=self.warn)
        self.spi3.device_for_ss = lambda ss: self.flash_chip if ss == 0 else None
        # the harts' L1 caches (caches.py)
        self.caches = [HartCaches() for _ in range(HARTS)] if timing == TIMING_ROCKET else None
        if self.caches is not None:
            self.caches[0].pair_with(self.caches[1])
        self.dmac = Dmac(ports, self.memory, requests=self.sysctl.dma_request,
                         peripherals={"spi0": self.spi0, "spi1": self.spi1, "spi3": self.spi3, "sha": self.sha256,
                                      **{uart.GATE: uart for uart in self.uarts}})
        self.peripherals: list[Peripheral] = [self.sysctl, self.fpioa, self.gpiohs, self.gpio, self.uarths, *self.uarts, *self.timers, *self.watchdogs, self.rtc, self.sha256, self.fft,
                                              self.otp, self.clint, self.plic, self.dmac, self.spi0, self.spi1, self.spi3]
        if self.caches is not None:
            self.sysctl.apb_changed = self._time_devices
            self._time_devices()
        self._interrupting = [(p, K210_BLOCKS[p.NAME].irqs) for p in self.peripherals if K210_BLOCKS[p.NAME].irqs]
        self.signals = None                    # a vcd.SignalLog with --vcd
        # the blocks a DMA channel serves advance before the DMAC, which completes what they finished
        self.timed_devices = [self.uarths, self.spi0, self.spi1, self.spi3, *self.uarts, self.dmac, self.sysctl, self.clint,
                              *self.timers, *self.watchdogs, self.rtc, self.pins]
        self.cold = cold
        if not cold:
            bootrom.hand_over(self.sysctl, self.fpioa, self.uarths)    # before the scheduler reads the CPU clock
        self.scheduler = Scheduler(self, quantum, hang_budget)
        self.clock.scheduler = self.scheduler
        self.timing_warnings: dict[str, int] = {}     # broken datasheet waits, per rule (run.json)
        self.lcd = ST7789V(on_frame=self.scheduler.frame_captured,
                           on_warning=lambda now, text: self.warn(f"ST7789V: {text}", now), strict=strict,
                           on_rule=lambda kind, now, text: self.timing_rule_broken(kind, f"ST7789V: {text}", now))
        self.sd_image = SdImage(sd_image, writable=sd_writable, warn=self.warn) if sd_image else None
        sd_card = SdCard(self.sd_image, warn=self.warn, faults=sd_faults, strict=strict, access_time=sd_access_time,
                         on_rule=lambda kind, now, text: self.timing_rule_broken(kind, text, now)
                         ) if self.sd_image else None
        chip = ChipPins(self.sysctl, self.fpioa, self.gpiohs, self.gpio, self.spi0, self.spi1, tuple(self.timers))
        self.wiring = DockWiring(chip, ports, self.lcd, lcd_interface, sd_card,
                                 on_lcd_delivery=self.scheduler.lcd_data_delivered,
                                 outside=lambda: (self.pins.version, self.pins.levels))
        for n, timer in enumerate(self.timers):
            timer.on_toggle = lambda channel, at, level, n=n: self.wiring.timer_toggled(n, channel, at, level)
        self.spi0.device_for_ss = self.wiring.spi0_device
        self.spi1.device_for_ss = self.wiring.spi1_device
        self.bus = Bus(self, strict)
        self.write_watch: WriteWatch | None = None
        self.booted_from_flash = firmware is None
        if firmware is None:
            if flash is None:
                raise ValueError("a Board needs a firmware file or a flash to boot from")
            self.image: LoadedImage = load_program(flash.boot_program(), self.memory)
            firmware = f"the program in {flash.path}"
        else:
            self.image = load_firmware(firmware, self.memory)
        # the program as loaded: what the mask ROM copies into SRAM again after a chip reset
        self._program = [(segment.address, bytes(self.memory.read(segment.address, segment.size)))
                         for segment in self.image.segments]
        if self.image.entry != RESET_PC:
            self.warn(f"ELF entry is 0x{self.image.entry:x}, but the K210 starts both harts at 0x{RESET_PC:x}")
        # The code is scanned where it is linked and in the other view of SRAM as well: the CSR
        # instructions the board answers (mhartid above all) and the loops it skips are found by
        # address, and code linked at the uncached alias 0x4000_0000 starts at 0x8000_0000
        # (memory_map.sram_views)
        sites, loops, time_loops = [], {}, []
        for address, code in self.image.code_ranges:
            for view in sram_views(address, len(code)):
                sites.extend(find_csr_sites(code, view))
                for loop in [*find_poll_loops(code, view), *find_idle_loops(code, view)]:
                    loops.setdefault(loop.head, loop)
                time_loops.extend(find_time_loops(code, view))
        loops = list(loops.values())
        self.cycle_table = build_table(self.image.code_ranges) if timing != TIMING_IPC1 else None
        for index, hart in enumerate(self.harts):
            self.bus.attach(hart)
            hart.install_cycle_table(self.cycle_table)
            hart.install_caches(None if self.caches is None else self.caches[index])
            hart.intercept_csr_sites(sites)
            hart.install_poll_loops(loops)
            hart.install_time_loops(time_loops)
            if engine == ENGINE_FAST:
                hart.enable_fast_engine(self.memory.address)
            hart.pc = RESET_PC
        if check_writes:
            self.write_watch = WriteWatch(self.image, self.memory, HARTS, firmware)
            for hart in self.harts:
                self.write_watch.attach(hart)
            self.memory.write_check = self.bus.check_dma_write
            if not self.write_watch.complete:
                self.warn(f"--check-writes: {firmware} has no {', '.join(self.write_watch.layout.missing)}: "
                          f"only stores into code and constants (its read-only segments) are checked")

    # --- the scheduler's state, as the rest of the model and the tests see it -----------------

    @property
    def harts(self) -> list[Hart]:
        return self.scheduler.harts

    @property
    def time(self) -> Time:
        return self.scheduler.time

    @time.setter
    def time(self, value: Time) -> None:
        self.scheduler.time = value

    @property
    def frames(self) -> list[FrameRecord]:
        return self.scheduler.frames

    def _time_devices(self) -> None:
        """What an access to each device's registers costs the harts (caches.py), from its bus and the
        APB clocks SYSCTL sets."""
        dividers = self.sysctl.apb_dividers()
        for caches in self.caches or ():
            caches.time_devices([(p.BASE, p.SIZE, caches.figures.device(K210_BLOCKS[p.NAME].bus, dividers))
                                 for p in self.peripherals])

    def loop_cycles_bound(self, instructions: int) -> int:
        """Cycles within which `instructions` instructions of a loop surely run (a hart woken
        from a poll loop gets one iteration before the storer goes on): one each under ipc1; under
        the Rocket model each may stall up to 3 cycles on a load, and miss in the caches (the loop's
        own line moves to the hart that stored to it), and the loop's branch may be mispredicted and
        its head wait for the second half of its fetch."""
        if self.timing == TIMING_IPC1:
            return instructions
        if self.caches is None:
            return 3 * instructions + MISPREDICT_PENALTY
        return (3 + self.caches[0].figures.worst_instruction) * instructions + MISPREDICT_PENALTY + REDIRECT_BUBBLE

    @property
    def quantum(self) -> int:
        return self.scheduler.quantum

    @property
    def hang_budget(self) -> Time:
        return self.scheduler.hang_budget

    @hang_budget.setter
    def hang_budget(self, value: Time) -> None:
        self.scheduler.hang_budget = value

    @property
    def _frames_wanted(self) -> int:
        return self.scheduler.frames_wanted

    @_frames_wanted.setter
    def _frames_wanted(self, value: int) -> None:
        self.scheduler.frames_wanted = value

    @property
    def last_exception(self) -> str | None:
        """The last synchronous exception a hart took, described (None: none yet)."""
        return self.scheduler.traps.last

    @property
    def host_time_in_harts(self) -> float:
        return self.scheduler.host_time_in_harts

    @property
    def device_writes(self) -> dict[str, list[int]]:
        return self.bus.device_writes

    @property
    def lcd_port(self) -> LcdPort:
        return self.wiring.lcd_port

    @property
    def sd_slot(self) -> SdSlot | None:
        return self.wiring.sd_slot

    def run(self, frames: int, progress: Callable[["Board"], None] | None = None) -> RunResult:
        """Runs until `frames` frames have been shown. Raises a BoardStop subclass otherwise."""
        return self.scheduler.run(frames, progress)

    def run_until(self, until: Time, progress: Callable[["Board"], None] | None = None) -> RunResult:
        """Runs until virtual time `until`, frames or not (Scheduler.run_until)."""
        return self.scheduler.run_until(until, progress)

    def signal(self, at: Time, name: str, value: int | None) -> None:
        """A pin changed (wiring.py, spi.py): logged for --vcd when a log is attached."""
        if self.signals is not None:
            self.signals.record(at, name, value)

    def stop_run(self, error: BoardStop) -> None:
        """Ends the run with `error` once the current instruction has completed: for watchers
        outside the harts (--expect, --fail-on). The first reason recorded counts."""
        self.scheduler.stop(error)
        if self.scheduler.current is not None:
            self.scheduler.current.request_stop()

    def finish_console_line(self, limit: Time | None = None) -> None:
        """After run(): lets the console line begun after the last frame end (Scheduler's doc)."""
        if limit is None:
            self.scheduler.finish_console_line()
        else:
            self.scheduler.finish_console_line(limit)

    def _step(self) -> None:
        self.scheduler.step()

    def grab_at(self, at: Time, action: Callable[["Board"], None]) -> None:
        """Calls action(board) once the board's virtual time reaches `at` (a framebuffer grab)."""
        self.scheduler.grab_at(at, action)

    # --- wiring -----------------------------------------------------------------------

    def drive_pad(self, pad: int, level: int | None, at: Time | None = None) -> PinChange:
        """Drives a pad from outside from now on, as a --pin change would (a key pressed in the live
        view, frontends/view.py): `level` 0 or 1, or None to let go of it. Called between turns. It
        takes effect at the board's time, or at `at` if that is later, and never before a time a hart
        has already run to, so that no hart has read the pad's old level after the change; a change
        at the board's time takes effect at once. Returns the change (its time), which run.json's
        `pins` lists with the --pin changes once played."""
        if not 0 <= pad < PAD_COUNT:
            raise ValueError(f"pad {pad} does not exist")
        if level not in (0, 1, None):
            raise ValueError(f"level {level!r} is not 0, 1 or None")
        now = max(self.time, *(hart.time for hart in self.harts))
        change = PinChange(now if at is None else max(at, now), pad, level)
        self.pins.add(change)
        if change.at <= self.time:
            self.pins.advance(self.time)
        return change

    @property
    def pad_changes(self) -> list[tuple[Time, int, int | None]]:
        """Every change of a pad's GPIOHS/GPIO level: (virtual time, pad, level or None)."""
        return self.wiring.pad_changes

    def reset_peripheral(self, name: str, now: Time) -> None:
        """SYSCTL peri_reset released a block: it returns to its reset state."""
        target = {"spi0": self.spi0, "spi1": self.spi1, "spi3": self.spi3, "dma": self.dmac, "fpioa": self.fpioa,
                  "gpio": self.gpio, **{block.GATE: block for block in (*self.uarts, *self.timers, *self.watchdogs, self.rtc,
                                                    self.sha256, self.fft, self.otp)}}.get(name)
        if target is not None:
            self.advance_devices(now)
            target.reset(now)

    def reset_chip(self, cause: str, at: Time) -> None:
        """The whole chip resets (a watchdog, SYSCTL's soft_reset; the scheduler resets the harts):
        every block as at power-on, then as the mask ROM leaves it (unless the board started cold),
        the program in SRAM again as the ROM copies it from flash (the rest of SRAM keeps what it
        held), SYSCTL's reset_status saying why. The Dock's LCD and card are not the chip's: they
        keep their state."""
        for peripheral in self.peripherals:
            peripheral.reset(at)
        for caches in self.caches or ():
            caches.reset()
        if not self.cold:
            bootrom.hand_over(self.sysctl, self.fpioa, self.uarths)
        if self.caches is not None:
            self._time_devices()       # SYSCTL's APB dividers as reset left them
        self.sysctl.record_reset(cause)
        if self.booted_from_flash:
            # the ROM boots what the flash holds now; the model's code analyses (poll loops, cycle
            # table, decoded blocks) belong to the program it booted first
            try:
                program = self.flash.boot_program()
            except BadInput as error:
                raise UnmodelledAccess(f"chip reset at {ms(at)}: the ROM would not boot the flash any "
                                       f"more ({error}); its ISP mode is not modelled") from None
            if program != self._program[0][1]:
                raise UnmodelledAccess(f"chip reset at {ms(at)}: the program in the flash has changed "
                                       f"since the run booted it, and booting a rewritten program is not modelled")
        for address, data in self._program:
            self.memory.load(address, data)
        self.wiring.changed(at)

    def disassemble_at(self, pc: int) -> str:
        """The instruction at pc as text ('?' style output when pc is not in SRAM)."""
        code = b""
        if is_sram(pc):
            base = SRAM_BASE if pc >= SRAM_BASE else SRAM_UNCACHED_BASE
            code = self.memory.read(pc, min(4, base + SRAM_SIZE - pc))
        return disassemble_one(code, pc)

    # --- console -------------------------------------------------------------------------

    def connect_serial_input(self, source: SerialInput) -> None:
        """What the host types into the Dock's USB-serial bridge (--uart-input): it reaches whichever
        UART FPIOA routes to pad 4 (wiring.RoutedInput)."""
        self.uarths.input = RoutedInput(source, self.fpioa, FUNC_UARTHS_RX)
        for n, uart in enumerate(self.uarts):
            uart.input = RoutedInput(source, self.fpioa, FUNC_UART1_RX + 2 * n)

    def _serial_out(self, uart: Uarths | DwUart, tx_function: int, byte: int) -> None:
        """A byte left a UART's transmitter: kept for run.json, and the console's when FPIOA routes
        that UART's TX to pad 5, the USB-serial bridge's (the console is what the Dock's USB port
        shows, whichever UART drives it)."""
        record = self.uart_output.setdefault(uart.NAME, bytearray())
        if len(record) < MAX_UART_OUTPUT:
            record.append(byte)
        if self.wiring.console_transmitter() == tx_function:
            self._console_byte(byte, uart.last_byte_time)

    def _console_byte(self, byte: int, at: Time) -> None:
        """Console output (`at`: when the byte's stop bit was out); a line `error <code> ...` is the
        firmware's fatal error report."""
        self.console_byte_time = at
        self._console(byte)
        if not self._console_line:
            self._line_began = at
        if byte != 10:
            self._console_line.append(byte)
            return
        line = bytes(self._console_line).rstrip(b"\r")
        self._console_line.clear()
        self.completed_line_began = self._line_began
        self.console_lines.append((at, line.decode("ascii", "replace")))
        if line.startswith(FIRMWARE_ERROR_PREFIX):
            words = line.decode("ascii", "replace")
            code = words.split()[1] if len(words.split()) > 1 else ""
            if code.isdigit():
                self.scheduler.firmware_reported_error(int(code), words)

    def close(self) -> None:
        """Releases the SD card image (flushing it when writes were allowed) and the harts' block caches."""
        if self.sd_image is not None:
            self.sd_image.close()
        for hart in self.harts:
            hart.close()

    # --- warnings ------------------------------------------------------------------------

    def warn(self, text: str, now: Time | None = None) -> None:
        """Every device's warnings come here (`now`: the virtual time the device noticed it,
        else the board's). A warning given again with the same text is counted, not repeated:
        on_warning hears only its first occurrence."""
        at = self.time if now is None else now
        record = self._warning_records.get(text)
        if record is not None:
            record.count += 1
            record.last = max(record.last, at)
            return
        if len(self._warning_records) >= MAX_DISTINCT_WARNINGS:
            self._warnings_unlisted += 1
            return
        record = WarningRecord(text, at, at)
        self._warning_records[text] = record
        self.on_warning(record.describe())

    def timing_rule_broken(self, kind: str, text: str, now: Time) -> None:
        """A device noticed firmware breaking one of its datasheet's waits (kind: the rule): a
        warning, and a count per rule for run.json's timing_warnings."""
        self.timing_warnings[kind] = self.timing_warnings.get(kind, 0) + 1
        self.warn(text, now)

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
        records = sorted(self._warning_records.values(), key=lambda record: record.last)[-count:]
        return [record.describe() for record in records]

    # --- interrupts --------------------------------------------------------------------

    def _high_sources(self) -> list[int]:
        """PLIC sources whose interrupt line is high right now (each block's lines, wired to the
        sources memory_map.K210_BLOCKS gives)."""
        high = []
        for device, sources in self._interrupting:
            lines = device.irq_lines()
            if lines:
                high.extend(source for line, source in enumerate(sources) if lines >> line & 1)
        return high

    def mip(self, h: int, now: Time, mask: int = ~0) -> int:
        """The hart's pending interrupt bits; only those in `mask` are computed (sampling the
        PLIC is the expensive part, and a hart that has MEIE clear does not need it)."""
        value = 0
        if mask >> riscv.IRQ_MSI & 1 and self.clint.msip(h):
            value |= 1 << riscv.IRQ_MSI
        if mask >> riscv.IRQ_MTI & 1 and self.clint.timer_pending(h, now):
            value |= 1 << riscv.IRQ_MTI
        if mask >> riscv.IRQ_MEI & 1 and self.plic.external_pending(plic_m_context(h)):
            value |= 1 << riscv.IRQ_MEI
        if mask >> riscv.IRQ_SEI & 1 and self.plic.external_pending(plic_s_context(h)):
            value |= 1 << riscv.IRQ_SEI
        return value | (self.harts[h].soft_mip & mask)     # SSIP, STIP: written by software

    def interrupts_may_have_changed(self, now: Time | None = None) -> None:
        """A device changed an interrupt input at `now` (see Scheduler)."""
        self.scheduler.interrupts_may_have_changed(now)

    # --- devices ------------------------------------------------------------------------

    def advance_devices(self, now: Time) -> None:
        for device in self.timed_devices:
            device.advance(now)

    def earliest_frame_capture(self, now: Time) -> Time:
        """A time before which advancing the devices cannot capture a frame: the LCD, on SPI0, needs a
        byte at least for each cell it has not been written since its last frame (a 12-bit pixel
        takes one and a half)."""
        bytes_per_frame = max(1, self.spi0.frame_bits // 8)
        return self.spi0.earliest_delivery(-(-self.lcd.cells_missing() // bytes_per_frame), now)

    def devices_a_store_moves(self, peripheral: Peripheral) -> tuple | None:
        """The timed devices whose next event a store to `peripheral` can bring forward: the block
        itself, and the DMAC for a block it serves (a store can start a handshake); None: any of them
        (SYSCTL's clocks and resets reach every block, the DMAC's channels every block it serves).
        Between turns the board's next event bounds every turn, so only these can move before it."""
        if peripheral is self.sysctl or peripheral is self.dmac:
            return None
        if peripheral in self.dmac.peripherals.values():
            return (peripheral, self.dmac)
        return (peripheral,)

    def next_device_event(self, now: Time, past_quiet_console: bool = False) -> Time | None:
        """The first moment after `now` a device changes state by itself; with past_quiet_console,
        the console's quiet bytes (Uarths.quiet_byte_ends) do not count."""
        # (a plain loop: the scheduler asks this several times a turn)
        earliest = None
        for device in self.timed_devices:
            if past_quiet_console and device is self.uarths:
                t = device.next_loud_event_time(now)
            else:
                t = device.next_event_time(now)
            if t is not None and t > now and (earliest is None or t < earliest):
                earliest = t
        return earliest
