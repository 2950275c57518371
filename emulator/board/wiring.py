"""The Maix Dock's wiring: which device sees which signal, derived from what the firmware programmed.

As on the real board, the LCD sees SPI0 frames only through the chip select that
FPIOA routes to pad 36, and its reset and D/C lines are whatever GPIOHS or slow-GPIO
lines FPIOA routes to pads 37 and 38. The SD slot is on SPI1 through pads 26-28, its
chip select on pad 29 as SPI1's own slave select or as a GPIOHS or GPIO line. Every
change of the level a GPIOHS or GPIO line drives onto a pad is logged with its virtual
time (`pad_changes`), for tests and run.json.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import HardwareMisuse
from ..vtime import Time
from ..devices.fpioa import (FUNC_TIMER0_TOGGLE1, FUNC_GPIO0, FUNC_GPIOHS0, FUNC_SPI0_D0, FUNC_SPI0_SCLK, FUNC_SPI0_SS0, FUNC_SPI1_D0,
                    FUNC_SPI1_D1, FUNC_SPI1_SCLK, FUNC_SPI1_SS0, PAD_COUNT)
from ..devices.fpioa import Fpioa
from ..devices.gpio import LINES as GPIO_LINES
from ..devices.gpio import Gpio
from ..devices.gpiohs import Gpiohs
from ..devices.ports import Ports, SerialInput
from ..devices.sdcard import SdCard
from ..devices.spi import SpiController
from ..devices.st7789v import ST7789V
from ..devices.sysctl import Sysctl
from ..devices.timer import CHANNELS as TIMER_CHANNELS
from .maix_dock import (PAD_CONSOLE_RX, PAD_CONSOLE_TX, PAD_LCD_CS, PAD_LCD_DC, PAD_LCD_RST, PAD_LCD_SCLK, PAD_SD_CS,
                        PAD_SD_MISO, PAD_SD_MOSI, PAD_SD_SCLK)
from ..devices.timer import DwTimer

# The LCD's bus: the Dock's panel (8-bit MCU interface) or a 4-line serial ST7789V module
LCD_8080, LCD_SPI = "8080", "spi"
LCD_INTERFACES = (LCD_8080, LCD_SPI)
SD_IDENTIFICATION_MAX_HZ = 400_000
SD_DEFAULT_SPEED_MAX_HZ = 25_000_000
FPIOA_PU, FPIOA_PD = 1 << 16, 1 << 17      # a pad's pull-up and pull-down (fpioa.h io_config)
# Pad changes kept for run.json and tests; a firmware that toggles pins for ever must not
# fill the host's memory: beyond this many only the count goes on
MAX_PAD_CHANGES = 100_000


@dataclass(frozen=True)
class ChipPins:
    """The K210 blocks whose pins the Dock's wiring follows."""
    sysctl: Sysctl
    fpioa: Fpioa
    gpiohs: Gpiohs
    gpio: Gpio
    spi0: SpiController
    spi1: SpiController
    timers: tuple[DwTimer, ...]


TIMER_TOGGLES = 3 * TIMER_CHANNELS


def is_gpio_line(function: int) -> bool:
    """Whether an FPIOA function is a GPIOHS or slow-GPIO line (software-driven)."""
    return FUNC_GPIOHS0 <= function < FUNC_GPIOHS0 + 32 or FUNC_GPIO0 <= function < FUNC_GPIO0 + GPIO_LINES


def is_driven_output(function: int) -> bool:
    """Whether an FPIOA function drives a level the pad log follows: a GPIOHS or GPIO line, or a
    timer's PWM toggle output."""
    return is_gpio_line(function) or FUNC_TIMER0_TOGGLE1 <= function < FUNC_TIMER0_TOGGLE1 + TIMER_TOGGLES


class LcdPort:
    """The Dock's LCD connector: SPI0's chip select and clock through FPIOA, reset and D/C on
    GPIOHS or GPIO lines through FPIOA, and the data lines as the panel's interface has them.
    The Dock's own panel (LCD_8080) has an 8-bit MCU bus: SPI0's eight data lines in the octal
    frame format, its clock the write strobe, one byte per clock. A 4-line serial ST7789V
    module on the same pins (LCD_SPI, --lcd-interface spi) takes SPI0's data line 0 (the pad
    FPIOA gives SPI0_D0) in the standard frame format, one bit per clock, most significant
    first. Either way each frame reaches the panel as its bytes, the most significant first,
    with D/C as it is when the frame's last bit is out."""

    def __init__(self, chip: ChipPins, lcd: ST7789V, interface: str, pad_level: Callable[[int], int | None],
                 on_delivery: Callable[[Time], None]) -> None:
        """pad_level: the level a line drives on a pad (DockWiring.pad_level). on_delivery: data
        reached the LCD at this time."""
        if interface not in LCD_INTERFACES:
            raise ValueError(f"LCD interface {interface!r}: one of {', '.join(LCD_INTERFACES)}")
        self.chip = chip
        self.lcd = lcd
        self.interface = interface
        self.pad_level = pad_level
        self.on_delivery = on_delivery

    def spi_select(self, selected: bool, now: Time) -> None:
        self.lcd.set_chip_select(selected, now)

    def _check_data_lines(self, lanes: int) -> None:
        chip = self.chip
        if self.interface == LCD_8080:
            if lanes != 8:
                raise HardwareMisuse(
                    f"SPI0 sends to the LCD in the {lanes}-line format; the Dock's LCD has an 8-bit parallel "
                    f"bus that latches SPI0's eight data lines on every clock (octal frame format, ctrlr0[22:21] "
                    f"= 3; a 4-line serial ST7789V module instead is --lcd-interface spi)")
            if not chip.sysctl.spi_dvp_data_enabled():
                raise HardwareMisuse("SPI0 sends to the LCD with SYSCTL misc.spi_dvp_data_enable (bit 10) clear: "
                                     "the upper data lines do not reach the LCD")
            return
        if lanes != 1:
            raise HardwareMisuse(f"SPI0 sends to the LCD in the {lanes}-line format; a 4-line serial ST7789V "
                                 f"(--lcd-interface spi) takes one data line (standard frame format, "
                                 f"ctrlr0[22:21] = 0)")
        if not chip.fpioa.pads_with_function(FUNC_SPI0_D0):
            raise HardwareMisuse("SPI0 sends to the 4-line serial LCD but no pad carries SPI0_D0 (FPIOA "
                                 "function 4), its data line")

    def spi_transfer(self, data: np.ndarray, lanes: int, now: Time) -> np.ndarray:
        if self.chip.fpioa.function_of_pad(PAD_LCD_SCLK) != FUNC_SPI0_SCLK:
            raise HardwareMisuse("SPI0 sends to the LCD but pad 39 (LCD WRX/clock) is not routed to SPI0_SCLK")
        self._check_data_lines(lanes)
        dc = self.pad_level(PAD_LCD_DC)
        if dc is None:
            raise HardwareMisuse("SPI0 sends to the LCD but its D/C line (pad 38) is not a driven GPIOHS or "
                                 "GPIO output")
        self.on_delivery(now)
        self.lcd.write(data, dc, now)
        return np.zeros(len(data), dtype=np.uint8)


class SdSlot:
    """The Dock's micro SD slot on SPI1: MISO, clock and MOSI through FPIOA (pads 26-28),
    chip select on pad 29 as SPI1's own slave select or as a GPIOHS or GPIO line."""

    def __init__(self, chip: ChipPins, card: SdCard, pad_level: Callable[[int], int | None],
                 warn: Callable[[str], None]) -> None:
        self.chip = chip
        self.card = card
        self.pad_level = pad_level
        self.warn = warn
        self._warned_clock = False

    def cs_is_gpio(self) -> bool:
        """Whether pad 29 carries a GPIOHS or GPIO line (software chip select)."""
        return is_gpio_line(self.chip.fpioa.function_of_pad(PAD_SD_CS))

    def spi_select(self, selected: bool, now: Time) -> None:
        if not self.cs_is_gpio():
            self.card.set_selected(selected, now)

    def gpio_changed(self, now: Time) -> None:
        if self.cs_is_gpio():
            level = self.pad_level(PAD_SD_CS)
            self.card.set_selected(level == 0, now)

    def spi_transfer(self, data: np.ndarray, lanes: int, now: Time) -> np.ndarray:
        fpioa = self.chip.fpioa
        if fpioa.function_of_pad(PAD_SD_SCLK) != FUNC_SPI1_SCLK or fpioa.function_of_pad(PAD_SD_MOSI) != FUNC_SPI1_D0:
            return np.full(len(data), 0xFF, dtype=np.uint8)   # the card sees no clock or no data
        if lanes != 1:
            raise HardwareMisuse(f"SPI1 talks to the SD card in a {lanes}-line format; SPI mode uses one data line")
        self._check_clock()
        spi1 = self.chip.spi1
        reply = self.card.exchange(data, now, lambda i: spi1.byte_clocked_at(i, now))
        if fpioa.function_of_pad(PAD_SD_MISO) != FUNC_SPI1_D1:
            return np.full(len(data), 0xFF, dtype=np.uint8)   # nothing routes the card's answer back
        return reply

    def _check_clock(self) -> None:
        hz = self.chip.spi1.sclk_hz()
        limit = SD_DEFAULT_SPEED_MAX_HZ if self.card.initialised else SD_IDENTIFICATION_MAX_HZ
        if hz > limit * 1.0001 and not self._warned_clock:
            self._warned_clock = True
            phase = "in default speed mode" if self.card.initialised else "before initialisation completes"
            self.warn(f"SD card clocked at {hz / 1e6:.3f} MHz {phase} (the card allows {limit / 1e6:g} MHz)")


class RoutedInput:
    """What the host sends the Dock's USB-serial bridge (--uart-input) reaches a UART's receiver
    only while FPIOA routes that UART's RX function to pad 4, as on the board (the SDK's start-up
    routes UART3 there, the mask ROM UARTHS)."""

    def __init__(self, source: SerialInput, fpioa: Fpioa, rx_function: int) -> None:
        self.source = source
        self.fpioa = fpioa
        self.rx_function = rx_function

    def _routed(self) -> bool:
        return self.fpioa.function_of_pad(PAD_CONSOLE_RX) == self.rx_function

    @property
    def may_grow(self) -> bool:
        return self._routed() and self.source.may_grow

    def has_byte(self, virtual_now: Time) -> bool:
        return self._routed() and self.source.has_byte(virtual_now)

    def pop(self) -> int:
        return self.source.pop()

    def put_back(self, byte: int) -> None:
        self.source.put_back(byte)


class DockWiring:
    """Routes SPI chip selects and GPIOHS and GPIO lines to the LCD and the SD slot through FPIOA."""

    def __init__(self, chip: ChipPins, ports: Ports, lcd: ST7789V, lcd_interface: str, sd_card: SdCard | None,
                 on_lcd_delivery: Callable[[Time], None], outside: Callable[[], tuple[int, dict[int, int]]]) -> None:
        """ports: the catch-up of the devices before pins change, warnings and the --vcd pins;
        on_lcd_delivery: data reached the LCD at this time; outside: the pads driven from outside
        (--pin), as (a version that changes with them, pad -> level)."""
        self.chip = chip
        self.outside = outside
        self._pad_inputs: dict[tuple[int, int], tuple[tuple[int, int], tuple[int, int, int, int]]] = {}
        self.ports = ports
        self.lcd = lcd
        self.lcd_port = LcdPort(chip, lcd, lcd_interface, self.pad_level, on_lcd_delivery)
        self.sd_slot = SdSlot(chip, sd_card, self.pad_level, ports.warn) if sd_card is not None else None
        self._lcd_reset_level = 1
        self._pad_levels: list[int | None] = [None] * PAD_COUNT
        self._driven_pads: set[int] = set()        # the pads whose _pad_levels entry is not None
        self._line_pads: tuple[int, tuple[int, ...]] = (-1, ())   # (FPIOA routing version, pads carrying a line)
        self.pad_changes: list[tuple[Time, int, int | None]] = []   # (virtual time, pad, level or None)
        self.pad_change_count = 0

    def logged_pad_level(self, pad: int) -> int | None:
        """The level the pad log (pad_changes, --vcd) last gave the pad (None: undriven)."""
        return self._pad_levels[pad]

    def spi0_device(self, ss: int) -> LcdPort | None:
        """The LCD answers on SPI0 when pad 36 carries SPI0's slave select ss."""
        if self.chip.fpioa.function_of_pad(PAD_LCD_CS) == FUNC_SPI0_SS0 + ss:
            return self.lcd_port
        return None

    def spi1_device(self, ss: int) -> SdSlot | None:
        """The SD slot answers on SPI1 when pad 29 carries SPI1's slave select ss, or a GPIOHS
        or GPIO line (then the card itself decides, from that line, whether it is selected)."""
        if self.sd_slot is None:
            return None
        function = self.chip.fpioa.function_of_pad(PAD_SD_CS)
        if function == FUNC_SPI1_SS0 + ss or self.sd_slot.cs_is_gpio():
            return self.sd_slot
        return None

    def pad_inputs(self, first: int, count: int) -> tuple[int, int, int, int]:
        """For FPIOA functions first .. first + count - 1 (bit i: function first + i), what their
        pads give them: (driven from outside, those levels, pulled up, pulled down), from the pad
        FPIOA routes each to (devices/ports.py PadInputs). Kept until the routing or the outside
        changes: GPIOHS asks on every read."""
        fpioa = self.chip.fpioa
        version, levels = self.outside()
        key = (fpioa.routing_version, version)
        cached = self._pad_inputs.get((first, count))
        if cached is not None and cached[0] == key:
            return cached[1]
        outside = levels_out = up = down = 0
        for i in range(count):
            pads = fpioa.pads_with_function(first + i)
            if not pads:
                continue
            pad = pads[0]
            if pad in levels:
                outside |= 1 << i
                levels_out |= levels[pad] << i
            config = fpioa.values[4 * pad]
            up |= (1 if config & FPIOA_PU else 0) << i
            down |= (1 if config & FPIOA_PD else 0) << i
        answer = (outside, levels_out, up, down)
        self._pad_inputs[(first, count)] = (key, answer)
        return answer

    def console_transmitter(self) -> int:
        """The FPIOA function on pad 5, whose bytes the USB-serial bridge hears (the console)."""
        return self.chip.fpioa.function_of_pad(PAD_CONSOLE_TX)

    def gpiohs_level_on_pad(self, pad: int) -> int | None:
        """The level a GPIOHS output drives on a pad, or None when no GPIOHS line drives it."""
        function = self.chip.fpioa.function_of_pad(pad)
        if FUNC_GPIOHS0 <= function < FUNC_GPIOHS0 + 32:
            return self.chip.gpiohs.driven_level(function - FUNC_GPIOHS0)
        return None

    def pad_level(self, pad: int, now: Time | None = None) -> int | None:
        """The level a GPIOHS or slow-GPIO line drives on a pad, or None when none drives it."""
        function = self.chip.fpioa.function_of_pad(pad)
        if FUNC_GPIOHS0 <= function < FUNC_GPIOHS0 + 32:
            return self.chip.gpiohs.driven_level(function - FUNC_GPIOHS0)
        if FUNC_GPIO0 <= function < FUNC_GPIO0 + GPIO_LINES:
            return self.chip.gpio.driven_level(function - FUNC_GPIO0)
        if FUNC_TIMER0_TOGGLE1 <= function < FUNC_TIMER0_TOGGLE1 + TIMER_TOGGLES:
            timer, channel = divmod(function - FUNC_TIMER0_TOGGLE1, TIMER_CHANNELS)
            return self.chip.timers[timer].toggle_level(channel, self.ports.clock.now() if now is None else now)
        return None

    def driven_levels(self) -> dict[int, int]:
        """The pads a GPIOHS or GPIO line or a PWM output drives now, with their levels (as the pad
        log last saw them)."""
        return {pad: self._pad_levels[pad] for pad in sorted(self._driven_pads)}

    def input_pads(self) -> list[int]:
        """The pads FPIOA routes to a GPIOHS or GPIO line that the chip does not drive: where a
        level driven from outside reaches the firmware (a key, a switch)."""
        fpioa = self.chip.fpioa
        return [pad for pad in range(PAD_COUNT)
                if is_gpio_line(fpioa.function_of_pad(pad)) and self.pad_level(pad) is None]

    def timer_toggled(self, timer: int, channel: int, at: Time, level: int) -> None:
        """A PWM output changed at `at` (the timer tells each change with its own time): the pads
        FPIOA routes it to follow, in the pad log and --vcd."""
        function = FUNC_TIMER0_TOGGLE1 + TIMER_CHANNELS * timer + channel
        for pad in self.chip.fpioa.pads_with_function(function):
            self._record_pad(pad, level, at)

    def _log_pad_changes(self, now: Time) -> None:
        # Only a pad that carries a GPIOHS or GPIO line can be driven now, and only one driven at the
        # last look can have stopped being driven: the others stay undriven (None) either way.
        fpioa = self.chip.fpioa
        version, line_pads = self._line_pads
        if version != fpioa.routing_version:
            line_pads = tuple(pad for pad in range(PAD_COUNT) if is_driven_output(fpioa.function_of_pad(pad)))
            self._line_pads = (fpioa.routing_version, line_pads)
        for pad in sorted(self._driven_pads.union(line_pads)):
            self._record_pad(pad, self.pad_level(pad, now), now)

    def _record_pad(self, pad: int, level: int | None, now: Time) -> None:
        if level != self._pad_levels[pad]:
            self._pad_levels[pad] = level
            if level is None:
                self._driven_pads.discard(pad)
            else:
                self._driven_pads.add(pad)
            self.ports.signal(now, f"pad{pad:02d}", level)
            self.pad_change_count += 1
            if len(self.pad_changes) < MAX_PAD_CHANGES:
                self.pad_changes.append((now, pad, level))

    def changed(self, now: Time) -> None:
        """FPIOA or a GPIOHS or GPIO output changed: the pad log, the LCD's reset pin, the SPI
        chip selects, the SD card's software chip select and the GPIO block's edge detection
        follow."""
        chip = self.chip
        self.ports.catch_up(now)
        self._log_pad_changes(now)
        level = self.pad_level(PAD_LCD_RST)
        level = 1 if level is None else level
        if level != self._lcd_reset_level:
            self._lcd_reset_level = level
            self.lcd.set_reset_pin(level, now)
        chip.spi0.wiring_changed(now)
        chip.spi1.wiring_changed(now)
        if self.sd_slot is not None:
            self.sd_slot.gpio_changed(now)
        chip.gpio.wiring_changed(now)
        chip.gpiohs.wiring_changed(now)
