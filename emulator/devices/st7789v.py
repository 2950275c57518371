"""Sitronix ST7789V LCD controller (240 x 320 panel, 4-line SPI), as the board sees it.

The board drives four wires and this model reacts to them the way the chip does:

* RESX  -> `set_reset_pin`      (active low hardware reset)
* CSX   -> `set_chip_select`    (chip select)
* D/CX plus the SPI bytes -> `write` (dc=0: every byte is a command; dc=1: every
  byte is a parameter of the last command or, after RAMWR, pixel data)

What the panel shows is `shown_image()`, a (240, 320, 3) RGB picture oriented the
way a person sees the Maix Dock (landscape, 320 wide). Every time the firmware has
written every GRAM cell since the last captured frame, the model captures a frame
and calls `on_frame` with that picture.

Timing and protocol mistakes do not stop the run: the chip itself does not
complain either. They are collected as strings in `warnings` and, when the
owner gives `on_warning`, handed to it as they happen (the board puts them
among the run's warnings).

The datasheet's waits (TIMING_RULES: the RESX pulse width, 5 ms after a reset
and after SLPIN/SLPOUT before the next command, 120 ms between SLPOUT and SLPIN)
are checked on every command. Real panels evidently run firmware that ignores
them (issue 10: SWRESET, SLPOUT ... DISPON within microseconds), so by default a
command that comes too soon is carried out, with a warning; with `strict` the
rule is enforced the way the datasheet leaves the part free to: the command is
ignored, and a RESX pulse shorter than tRW does not reset the chip. Each broken
rule is also reported to `on_rule` (kind, time, text), which the board counts.

Supported commands (everything else is ignored, parameters included, as the chip
ignores commands it does not know):

    code  name     params  effect
    0x00  NOP      0       nothing, but ends a RAMWR
    0x01  SWRESET  0       registers to defaults (GRAM kept); 5 ms busy
    0x10  SLPIN    0       sleep in (panel black); 5 ms settle
    0x11  SLPOUT   0       sleep out; 5 ms settle
    0x12  PTLON    0       partial mode (recorded only)
    0x13  NORON    0       normal mode
    0x20  INVOFF   0       colour inversion off
    0x21  INVON    0       colour inversion on (of what is shown; GRAM unchanged)
    0x28  DISPOFF  0       panel black
    0x29  DISPON   0       panel shows GRAM
    0x2A  CASET    4       XS hi, XS lo, XE hi, XE lo
    0x2B  RASET    4       YS hi, YS lo, YE hi, YE lo
    0x2C  RAMWR    stream  pixel data into the window
    0x36  MADCTL   1       MY MX MV ML BGR MH
    0x3A  COLMOD   1       pixel format (0x55 16-bit, 0x66 18-bit, 0x53 12-bit)

GRAM representation (the `gram` property): a (320, 240) uint32 array, indexed
[row, column] of the physical panel, each cell an 18-bit colour packed as
R6 << 12 | G6 << 6 | B6 (6 bits per channel, as the chip stores it).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import functools

import numpy as np

from ..vtime import NEVER, PS_PER_MS, PS_PER_US, Time, ms

# --- command codes (datasheet "System Function Command Table 1") ---------------------

NOP = 0x00
SWRESET = 0x01
SLPIN = 0x10
SLPOUT = 0x11
PTLON = 0x12
NORON = 0x13
INVOFF = 0x20
INVON = 0x21
DISPOFF = 0x28
DISPON = 0x29
CASET = 0x2A
RASET = 0x2B
RAMWR = 0x2C
MADCTL = 0x36
COLMOD = 0x3A

COMMAND_NAMES: dict[int, str] = {
    NOP: "NOP",
    SWRESET: "SWRESET",
    SLPIN: "SLPIN",
    SLPOUT: "SLPOUT",
    PTLON: "PTLON",
    NORON: "NORON",
    INVOFF: "INVOFF",
    INVON: "INVON",
    DISPOFF: "DISPOFF",
    DISPON: "DISPON",
    CASET: "CASET",
    RASET: "RASET",
    RAMWR: "RAMWR",
    MADCTL: "MADCTL",
    COLMOD: "COLMOD",
}

# Commands whose effect waits for a fixed number of parameter bytes.
PARAMETER_COUNT: dict[int, int] = {CASET: 4, RASET: 4, MADCTL: 1, COLMOD: 1}

# --- MADCTL bits ---------------------------------------------------------------------

MADCTL_MY = 0x80   # row address order (bottom to top)
MADCTL_MX = 0x40   # column address order (right to left)
MADCTL_MV = 0x20   # row/column exchange
MADCTL_ML = 0x10   # vertical refresh order: no effect on a still image
MADCTL_BGR = 0x08  # data is B, G, R: swap red and blue on the way into GRAM
MADCTL_MH = 0x04   # horizontal refresh order: no effect on a still image

# --- COLMOD: D2..D0 select the format of the MCU (SPI) interface ----------------------
# D6..D4 select the RGB-interface format, which does not matter on SPI, so
# 0x55 and 0x05 are both 16-bit for this wiring (datasheet COLMOD description).

COLMOD_12BIT = 0b011
COLMOD_16BIT = 0b101
COLMOD_18BIT = 0b110
SUPPORTED_COLMOD_FORMATS = (COLMOD_12BIT, COLMOD_16BIT, COLMOD_18BIT)

# --- timing (datasheet AC characteristics and command descriptions) ------------------

RESET_BUSY: Time = 5 * PS_PER_MS         # after SWRESET or RESX release: commands are not accepted
SLEEP_SETTLE: Time = 5 * PS_PER_MS       # after SLPIN/SLPOUT: supplies and clocks still settling
SLEEP_TOGGLE: Time = 120 * PS_PER_MS     # SLPIN<->SLPOUT minimum spacing
RESET_PULSE_MIN: Time = 10 * PS_PER_US   # tRW: shorter RESX pulses are not guaranteed to reset
# "long ago": what the waits are measured from before anything happened (no wait is pending then,
# and a first SLPIN/SLPOUT comes more than 120 ms after it)
LONG_AGO: Time = -NEVER

# The datasheet's waits, by the kind the board counts them under (run.json's timing_warnings).
# Sitronix ST7789V datasheet (version 1.3, 2014/03): "Reset Timing" (tRW, the RESX low pulse,
# at least 10 us; wait 5 ms after releasing RESX before sending commands), the descriptions of
# SWRESET (01h: wait 5 ms before the next command), SLPIN (10h) and SLPOUT (11h) (wait 5 ms
# before the next command; 120 ms after SLPOUT before SLPIN, and after SLPIN before SLPOUT).
RULE_RESET_PULSE = "ST7789V RESX pulse shorter than 10 us"
RULE_AFTER_RESET = "ST7789V command within 5 ms of a reset"
RULE_AFTER_SLEEP = "ST7789V command within 5 ms of SLPIN/SLPOUT"
RULE_SLEEP_TOGGLE = "ST7789V SLPIN/SLPOUT within 120 ms of the last sleep change"
TIMING_RULES = (RULE_RESET_PULSE, RULE_AFTER_RESET, RULE_AFTER_SLEEP, RULE_SLEEP_TOGGLE)

PIXELS = 240 * 320
DEFERRED_LIMIT = 1 << 22   # pixel bytes kept back at most (a small window rewritten over and over)
# Seed of the power-up GRAM noise: real GRAM powers up random, a fixed seed keeps
# runs reproducible while still showing garbage if firmware never clears the screen.
POWER_ON_GRAM_SEED = 0x7789
# Above this many pointer positions a window's address table is not cached
# (CASET/RASET accept 16-bit addresses; 65536 x 65536 positions would not fit).
WINDOW_CACHE_LIMIT = 1 << 20


@dataclass
class Registers:
    """The controller's register state that the model implements; reset values
    are the datasheet's "after H/W reset" and "after S/W reset" column."""

    madctl: int = 0x00
    colmod: int = 0x66
    xs: int = 0x0000
    xe: int = 0x00EF
    ys: int = 0x0000
    ye: int = 0x013F
    sleeping: bool = True
    display_on: bool = False
    inverted: bool = False
    normal_mode: bool = True   # False after PTLON (partial mode)


@dataclass(frozen=True)
class _WindowGeometry:
    """Everything that decides where a pointer position lands in GRAM."""

    xs: int
    width: int
    ys: int
    height: int
    mv: bool
    mx: bool
    my: bool


class ST7789V:
    """Sitronix ST7789V on a 4-line SPI bus, driving a 240 x 320 panel."""

    WIDTH = 240   # physical GRAM columns
    HEIGHT = 320  # physical GRAM rows

    def __init__(self, on_frame: Callable[[np.ndarray], None] | None = None,
                 on_warning: Callable[[Time, str], None] | None = None, strict: bool = False,
                 on_rule: Callable[[str, Time, str], None] | None = None) -> None:
        """on_warning(now, message) hears every warning as it is given; on_rule(kind, now,
        message) hears, instead, each broken timing rule (kind: one of TIMING_RULES). strict:
        enforce the timing rules (see the module comment) instead of warning only."""
        self.on_frame = on_frame
        self.on_warning = on_warning
        self.strict = strict
        self.on_rule = on_rule
        self.warnings: list[str] = []
        self.frames_captured = 0

        self._regs = Registers()
        rng = np.random.default_rng(POWER_ON_GRAM_SEED)
        self._gram = rng.integers(0, 1 << 18, PIXELS, dtype=np.uint32)  # flat, row * 240 + column
        self._covered = np.zeros(PIXELS, dtype=bool)
        self._covered_count = 0
        self._deferred: list[np.ndarray] = []     # pixel bytes received and not yet stored
        self._deferred_bytes = 0

        self._resx_high = True
        self._resx_low_since: Time = 0
        self._before_reset: tuple | None = None   # (registers, last sleep change) when RESX fell
        # The board owns CSX; until it drives the pin the bus is assumed selected.
        self._selected = True

        # No constraint at power-up: the chip is ready when the board starts.
        self._busy_until = LONG_AGO
        self._busy_reason = ""
        self._settle_until = LONG_AGO
        self._settle_reason = ""
        self._last_sleep_change = LONG_AGO

        self._command: int | None = None      # command whose parameters are being received
        self._params: list[int] = []
        self._surplus_warned = False
        self._ram_write = False
        self._pointer = 0                     # position inside the window, 0 .. window size - 1
        self._pending = np.zeros(0, dtype=np.uint8)   # bytes (or 12-bit nibbles) of an incomplete pixel

        self._window_key: _WindowGeometry | None = None
        self._window_cells: np.ndarray | None = None
        self._window_all_on_panel = True
        # for a window of the whole panel: where each cell's colour comes from in the window's
        # pointer order (the inverse of _window_cells), made at the first whole frame
        self._window_sources: np.ndarray | None = None

    # --- read-only state for tests and tools ------------------------------------------

    @property
    def sleeping(self) -> bool:
        return self._regs.sleeping

    @property
    def display_on(self) -> bool:
        return self._regs.display_on

    @property
    def inverted(self) -> bool:
        return self._regs.inverted

    @property
    def normal_mode(self) -> bool:
        return self._regs.normal_mode

    @property
    def madctl(self) -> int:
        return self._regs.madctl

    @property
    def colmod(self) -> int:
        return self._regs.colmod

    @property
    def window(self) -> tuple[int, int, int, int]:
        """(XS, XE, YS, YE) as last set by CASET/RASET, in logical coordinates."""
        return (self._regs.xs, self._regs.xe, self._regs.ys, self._regs.ye)

    @property
    def registers(self) -> Registers:
        """A copy of the whole register state."""
        return replace(self._regs)

    @property
    def gram(self) -> np.ndarray:
        """Physical GRAM, (320 rows, 240 columns) of packed 18-bit colours
        R6 << 12 | G6 << 6 | B6 (read-only view)."""
        self._store_deferred_pixels()
        view = self._gram.reshape(self.HEIGHT, self.WIDTH).view()
        view.flags.writeable = False
        return view

    # --- pins ----------------------------------------------------------------------------

    def set_reset_pin(self, level: int, now: Time) -> None:
        """RESX, active low. The falling edge resets the registers (GRAM keeps its
        content); commands are refused until 5 ms after the rising edge."""
        high = bool(level)
        if high == self._resx_high:
            return
        self._store_deferred_pixels()
        self._resx_high = high
        if not high:
            self._resx_low_since = now
            self._before_reset = (replace(self._regs), self._last_sleep_change)
            self._reset_registers(now)
            return
        pulse = now - self._resx_low_since
        if pulse < RESET_PULSE_MIN:
            text = (f"RESX low pulse of {pulse / PS_PER_US:.2f} us is shorter than "
                    f"the {RESET_PULSE_MIN // PS_PER_US} us the datasheet requires")
            if self.strict and self._before_reset is not None:
                # not a valid reset: the chip keeps the state it had before the pulse
                self._regs, self._last_sleep_change = self._before_reset
                self._rule(RULE_RESET_PULSE, now, f"{text}: not taken as a reset (--strict)")
                return
            self._rule(RULE_RESET_PULSE, now, f"{text}; taken as a reset (--strict would not)")
        self._busy_until = now + RESET_BUSY
        self._busy_reason = f"RESX release at {_ms(now)}"

    def set_chip_select(self, selected: bool, now: Time) -> None:
        """CSX. Deselecting pauses the transfer: a RAMWR and a half-received
        parameter list carry on after re-selection, but the bits of a pixel that
        was not complete are lost."""
        self._store_deferred_pixels()
        self._selected = bool(selected)
        if not self._selected:
            self._pending = self._pending[:0]

    # --- the bus ---------------------------------------------------------------------------

    def write(self, data: np.ndarray, dc: int, now: Time) -> None:
        """Bytes clocked in with one D/C level: dc=0 commands, dc=1 parameters or pixels."""
        if isinstance(data, (bytes, bytearray, memoryview)):
            data = np.frombuffer(data, dtype=np.uint8)
        data = np.asarray(data, dtype=np.uint8).ravel()
        if data.size == 0:
            return
        if not self._resx_high:
            self._warn(now, f"{data.size} byte(s) sent while RESX is low: ignored")
            return
        if not self._selected:
            self._warn(now, f"{data.size} byte(s) sent while CSX is high: ignored")
            return
        if dc == 0:
            self._store_deferred_pixels()
            for code in data.tolist():
                self._receive_command(code, now)
        else:
            self._receive_data(data, now)

    # --- what the panel shows ---------------------------------------------------------------

    def shown_image(self) -> np.ndarray:
        """(240, 320, 3) uint8 RGB as seen on the Maix Dock: PNG pixel (x, y) is
        GRAM row 319 - x, column y. Black while sleeping or with the display off."""
        self._store_deferred_pixels()
        if self._regs.sleeping or not self._regs.display_on:
            return np.zeros((self.WIDTH, self.HEIGHT, 3), dtype=np.uint8)
        upright = self._gram.reshape(self.HEIGHT, self.WIDTH)[::-1, :].T
        # one look-up a pixel (the board takes a picture at every frame): the RGB bytes of 4-byte
        # pixels, a view whose fourth byte is left out
        pixels = np.take(_rgb888_of_gram_colours(self._regs.inverted), upright)
        return pixels.view(np.uint8).reshape(self.WIDTH, self.HEIGHT, 4)[:, :, :3]

    # --- commands ------------------------------------------------------------------------

    def _receive_command(self, code: int, now: Time) -> None:
        name = _command_name(code)
        if self._command in PARAMETER_COUNT and len(self._params) < PARAMETER_COUNT[self._command]:
            self._warn(now, f"{_command_name(self._command)} got {len(self._params)} of "
                              f"{PARAMETER_COUNT[self._command]} parameters before {name}: ignored")
        # A new command always ends the previous one, RAMWR included.
        self._command = None
        self._params = []
        self._surplus_warned = False
        self._ram_write = False
        self._pending = self._pending[:0]

        if now < self._busy_until:
            if self.strict:
                self._rule(RULE_AFTER_RESET, now, f"{name} ignored: chip busy for 5 ms after {self._busy_reason}")
                return
            self._rule(RULE_AFTER_RESET, now, f"{name} sent within 5 ms after {self._busy_reason}: "
                                                f"carried out (--strict ignores it, as the chip may)")
        elif now < self._settle_until:
            if self.strict:
                self._rule(RULE_AFTER_SLEEP, now, f"{name} ignored: sent within 5 ms after {self._settle_reason}")
                return
            self._rule(RULE_AFTER_SLEEP, now, f"{name} sent within 5 ms after {self._settle_reason}: "
                                                f"carried out (--strict ignores it, as the chip may)")

        self._command = code
        if code not in PARAMETER_COUNT:
            self._execute(code, [], now)

    def _receive_data(self, data: np.ndarray, now: Time) -> None:
        if self._ram_write:
            self._receive_pixel_bytes(data)
            return
        code = self._command
        if code is None or code not in COMMAND_NAMES:
            return  # no accepted command, or one the chip does not know: bytes are dropped
        needed = PARAMETER_COUNT.get(code, 0) - len(self._params)
        if needed > 0:
            self._params.extend(data[:needed].tolist())
            if len(self._params) == PARAMETER_COUNT[code]:
                self._execute(code, self._params, now)
        if data.size > max(needed, 0) and not self._surplus_warned:
            self._surplus_warned = True
            self._warn(now, f"{_command_name(code)} takes {PARAMETER_COUNT.get(code, 0)} "
                              f"parameter(s); extra data bytes ignored")

    def _execute(self, code: int, params: list[int], now: Time) -> None:
        regs = self._regs
        if code == NOP:
            pass
        elif code == SWRESET:
            self._software_reset(now)
        elif code == SLPIN:
            self._sleep(True, now)
        elif code == SLPOUT:
            self._sleep(False, now)
        elif code == PTLON:
            regs.normal_mode = False
        elif code == NORON:
            regs.normal_mode = True
        elif code == INVOFF:
            regs.inverted = False
        elif code == INVON:
            regs.inverted = True
        elif code == DISPOFF:
            regs.display_on = False
        elif code == DISPON:
            regs.display_on = True
        elif code == CASET:
            regs.xs, regs.xe = _address_pair(params)
        elif code == RASET:
            regs.ys, regs.ye = _address_pair(params)
        elif code == RAMWR:
            self._ram_write = True
            self._pointer = 0
        elif code == MADCTL:
            regs.madctl = params[0]
        elif code == COLMOD:
            if params[0] & 0x07 in SUPPORTED_COLMOD_FORMATS:
                regs.colmod = params[0]
            else:
                self._warn(now, f"COLMOD 0x{params[0]:02X} selects no supported SPI pixel "
                                  f"format; keeping 0x{regs.colmod:02X}")

    def _software_reset(self, now: Time) -> None:
        self._reset_registers(now)
        self._busy_until = now + RESET_BUSY
        self._busy_reason = f"SWRESET at {_ms(now)}"

    def _reset_registers(self, now: Time) -> None:
        """Shared by RESX and SWRESET: defaults, sleep in, display off; GRAM kept."""
        if not self._regs.sleeping:
            # Reset from sleep-out is a sleep-in as far as the 120 ms SLPOUT rule goes.
            self._last_sleep_change = now
        self._regs = Registers()
        self._command = None
        self._params = []
        self._ram_write = False
        self._pending = self._pending[:0]
        self._settle_until = LONG_AGO

    def _sleep(self, enter: bool, now: Time) -> None:
        name = "SLPIN" if enter else "SLPOUT"
        if enter != self._regs.sleeping:
            since = now - self._last_sleep_change
            if since < SLEEP_TOGGLE:
                text = f"{name} only {ms(since)} after the last sleep change; the datasheet asks for 120 ms"
                if self.strict:
                    self._rule(RULE_SLEEP_TOGGLE, now, f"{text}: ignored (--strict)")
                    return
                self._rule(RULE_SLEEP_TOGGLE, now, f"{text}: carried out (--strict ignores it)")
            self._last_sleep_change = now
        self._regs.sleeping = enter
        self._settle_until = now + SLEEP_SETTLE
        self._settle_reason = f"{name} at {_ms(now)}"

    # --- pixels ---------------------------------------------------------------------------

    def _receive_pixel_bytes(self, data: np.ndarray) -> None:
        """Pixel bytes of a RAMWR. Decoding them costs the host most per call, not per byte, so
        they are kept until they could finish a frame (cells_missing reaches 0: with the part of
        a pixel carried over, they could make as many pixels as there are cells to write), or
        until anything else reaches the chip or someone looks at GRAM; then stored in one go, in
        the order they came, which captures a frame in the same call as storing them at once would."""
        self._deferred.append(np.array(data, dtype=np.uint8))
        self._deferred_bytes += data.size
        if self.cells_missing() == 0 or self._deferred_bytes > DEFERRED_LIMIT:
            self._store_deferred_pixels()

    def _store_deferred_pixels(self) -> None:
        if not self._deferred:
            return
        chunks, self._deferred, self._deferred_bytes = self._deferred, [], 0
        self._decode_and_store(chunks[0] if len(chunks) == 1 else np.concatenate(chunks))

    def _decode_and_store(self, data: np.ndarray) -> None:
        """Turns wire bytes into packed 18-bit colours, carrying an incomplete
        pixel over to the next call, and stores them."""
        fmt = self._regs.colmod & 0x07
        if fmt == COLMOD_12BIT:
            # 12-bit pixels straddle byte boundaries, so work in nibbles: 3 per pixel.
            units = np.empty(data.size * 2, dtype=np.uint8)
            units[0::2] = data >> 4
            units[1::2] = data & 0x0F
            per_pixel = 3
        else:
            units = data
            per_pixel = 2 if fmt == COLMOD_16BIT else 3
        if self._pending.size:
            units = np.concatenate((self._pending, units))
        count = units.size // per_pixel
        self._pending = units[count * per_pixel:].copy()
        if count == 0:
            return
        if fmt == COLMOD_16BIT:
            # a 16-bit pixel is two bytes, big-endian on the wire: one look-up gives its GRAM colour
            pairs = np.ascontiguousarray(units[:count * 2]).view(">u2")
            # (np.take: less than half the host time of indexing with the array here)
            self._store_pixels(np.take(_colours_of_16_bit_pixels(bool(self._regs.madctl & MADCTL_BGR)), pairs))
            return
        fields = units[:count * per_pixel].reshape(count, per_pixel).astype(np.uint32)
        red, green, blue = _decode_pixels(fields, fmt)
        if self._regs.madctl & MADCTL_BGR:
            red, blue = blue, red
        self._store_pixels((red << 12) | (green << 6) | blue)

    def _store_pixels(self, colours: np.ndarray) -> None:
        """Writes colours at the pointer, wrapping from (XE, YE) back to (XS, YS)."""
        geometry = self._geometry()
        size = geometry.width * geometry.height
        done = 0
        while done < colours.size:
            run = min(colours.size - done, size - self._pointer)
            cells = self._cells_for(geometry, self._pointer, run)
            self._write_cells(cells, colours[done:done + run])
            self._pointer = (self._pointer + run) % size
            done += run

    def _write_cells(self, cells: np.ndarray, colours: np.ndarray) -> None:
        """Stores colours in GRAM cells (all distinct, -1 = off the panel) in wire
        order, capturing a frame the moment the last uncovered cell is written."""
        if not self._window_all_on_panel:
            on_panel = cells >= 0
            cells, colours = cells[on_panel], colours[on_panel]
        elif self._covered_count == 0 and cells.size == PIXELS:
            # a whole-panel window written whole from nothing covered: every cell once, the last
            # one completes the frame (the common case: a firmware sending frame after frame). The
            # cells are then the window's, all of them: GRAM is its colours gathered in cell order
            # (a gather costs the host about half what storing through the cells does)
            if self._window_sources is None:
                self._window_sources = np.empty(PIXELS, dtype=np.intp)
                self._window_sources[cells] = np.arange(PIXELS)
            np.take(colours, self._window_sources, out=self._gram)
            self._capture_frame()
            return
        while cells.size:
            fresh = ~self._covered[cells]
            fresh_count = int(np.count_nonzero(fresh))
            missing = PIXELS - self._covered_count
            if fresh_count < missing:
                self._gram[cells] = colours
                self._covered[cells] = True
                self._covered_count += fresh_count
                return
            last = int(np.searchsorted(np.cumsum(fresh), missing))
            self._gram[cells[:last + 1]] = colours[:last + 1]
            self._capture_frame()
            cells, colours = cells[last + 1:], colours[last + 1:]

    def cells_missing(self) -> int:
        """At least how many GRAM cells are still to be written before the next frame is captured:
        those not written since the last capture, less one for each pixel the bytes kept back make
        (each pixel writes one cell at most; the next capture is at least this many pixels away).
        The bytes kept back are all in the current pixel format: a COLMOD, like any command, stores
        them first."""
        if self._regs.colmod & 0x07 == COLMOD_12BIT:
            pixels = (self._pending.size + 2 * self._deferred_bytes) // 3     # nibbles, 3 a pixel
        else:
            per_pixel = 2 if self._regs.colmod & 0x07 == COLMOD_16BIT else 3
            pixels = (self._pending.size + self._deferred_bytes) // per_pixel
        return max(0, PIXELS - self._covered_count - pixels)

    def _capture_frame(self) -> None:
        self._covered[:] = False
        self._covered_count = 0
        self.frames_captured += 1
        if self.on_frame is not None:
            self.on_frame(self.shown_image())

    # --- address mapping ------------------------------------------------------------------

    def _geometry(self) -> _WindowGeometry:
        regs = self._regs
        # The datasheet requires XS <= XE and YS <= YE and leaves the opposite
        # undefined; the model lets the pointer wrap right after the start
        # address, i.e. a one-column (one-row) window, so the mistake is visible.
        return _WindowGeometry(
            xs=regs.xs, width=max(regs.xe - regs.xs + 1, 1),
            ys=regs.ys, height=max(regs.ye - regs.ys + 1, 1),
            mv=bool(regs.madctl & MADCTL_MV),
            mx=bool(regs.madctl & MADCTL_MX),
            my=bool(regs.madctl & MADCTL_MY),
        )

    def _cells_for(self, geometry: _WindowGeometry, start: int, count: int) -> np.ndarray:
        """Flat GRAM indices of pointer positions start .. start+count-1 (no wrap)."""
        size = geometry.width * geometry.height
        if geometry != self._window_key:
            self._window_key = geometry
            self._window_cells = self._window_sources = None
            if size <= WINDOW_CACHE_LIMIT:
                self._window_cells = _map_positions(geometry, np.arange(size, dtype=np.int64))
                self._window_all_on_panel = bool(self._window_cells.min() >= 0)
            else:
                self._window_all_on_panel = False
        if self._window_cells is not None:
            return self._window_cells[start:start + count]
        return _map_positions(geometry, np.arange(start, start + count, dtype=np.int64))

    # --- bookkeeping --------------------------------------------------------------------

    def _warn(self, now: Time, message: str) -> None:
        self.warnings.append(f"ST7789V at {_ms(now)}: {message}")
        if self.on_warning is not None:
            self.on_warning(now, message)

    def _rule(self, kind: str, now: Time, message: str) -> None:
        """A timing rule broken (kind: one of TIMING_RULES): a warning, heard by on_rule when given."""
        self.warnings.append(f"ST7789V at {_ms(now)}: {message}")
        if self.on_rule is not None:
            self.on_rule(kind, now, message)
        elif self.on_warning is not None:
            self.on_warning(now, message)


# --- helpers --------------------------------------------------------------------------


def _map_positions(geometry: _WindowGeometry, positions: np.ndarray) -> np.ndarray:
    """Pointer positions -> flat physical GRAM index (row * 240 + column).

    The pointer walks x from XS to XE, then the next y. Logical (x, y) is
    physical (column, row) = (y, x) with MV, else (x, y); MX mirrors the
    column, MY the row. Datasheet: data whose address is beyond the panel is
    ignored, so such positions get -1 and are skipped while the pointer still
    advances over them.
    """
    x = geometry.xs + positions % geometry.width
    y = geometry.ys + positions // geometry.width
    logical_width, logical_height = (ST7789V.HEIGHT, ST7789V.WIDTH) if geometry.mv \
        else (ST7789V.WIDTH, ST7789V.HEIGHT)
    on_panel = (x < logical_width) & (y < logical_height)
    column, row = (y, x) if geometry.mv else (x, y)
    if geometry.mx:
        column = ST7789V.WIDTH - 1 - column
    if geometry.my:
        row = ST7789V.HEIGHT - 1 - row
    cells = row * ST7789V.WIDTH + column
    cells[~on_panel] = -1
    return cells


@functools.lru_cache(maxsize=2)
def _colours_of_16_bit_pixels(bgr: bool) -> np.ndarray:
    """The packed 18-bit GRAM colour of every 16-bit pixel value by _decode_pixels' rule, red and
    blue swapped when MADCTL's BGR bit is set (65,536 entries, read-only)."""
    def channel(values: np.ndarray, which: int) -> np.ndarray:
        # the 6-bit level of one channel for pixel values that set only that channel's field
        return _decode_pixels(np.stack((values >> 8, values & 0xFF), axis=1), COLMOD_16BIT)[which]
    red = channel(np.arange(32, dtype=np.uint32) << 11, 0)
    green = channel(np.arange(64, dtype=np.uint32) << 5, 1)
    blue = channel(np.arange(32, dtype=np.uint32), 2)
    # a pixel value is its red field, then green, then blue (RRRRRGGG GGGBBBBB); with BGR the
    # red and blue fields' levels trade places in GRAM
    red_shift, blue_shift = (0, 12) if bgr else (12, 0)
    return _table_of_fields((red, red_shift), (green, 6), (blue, blue_shift))


@functools.lru_cache(maxsize=2)
def _rgb888_of_gram_colours(inverted: bool) -> np.ndarray:
    """What the panel shows for every packed 18-bit GRAM colour: bytes R, G, B and 0 of a
    little-endian uint32 (2^18 entries, read-only). Each 6-bit channel becomes 8 bits with its
    top two bits repeated below (0 and full scale exact); INVON shows 255 minus that."""
    six = np.arange(64, dtype=np.uint32)
    eight = (six << 2) | (six >> 4)
    if inverted:
        eight = 255 - eight
    # a GRAM colour is its red field, then green, then blue; R is the picture's first byte
    return _table_of_fields((eight, 0), (eight, 8), (eight, 16))


def _table_of_fields(*fields: tuple[np.ndarray, int]) -> np.ndarray:
    """A read-only look-up table for values made of bit fields, the first field the most
    significant: fields are (the entry for each value of the field, the shift at which that
    entry goes into the table's uint32 entry), and the table's entry for a value is the sum
    of its fields' entries so shifted."""
    table = np.zeros((), dtype=np.uint32)
    for axis, (entries, shift) in enumerate(fields):
        shape = [1] * len(fields)
        shape[axis] = entries.size
        table = table | (entries.astype(np.uint32).reshape(shape) << shift)
    table = table.reshape(-1)
    table.flags.writeable = False
    return table


def _decode_pixels(fields: np.ndarray, fmt: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wire fields (one row per pixel, uint32) -> 6-bit R, G, B as GRAM stores them."""
    if fmt == COLMOD_16BIT:
        value = (fields[:, 0] << 8) | fields[:, 1]      # RRRRRGGG GGGBBBBB
        red5, green6, blue5 = value >> 11, (value >> 5) & 0x3F, value & 0x1F
        # 5 -> 6 bits: the MSB doubles as the LSB, so 0 and full scale stay exact.
        return (red5 << 1) | (red5 >> 4), green6, (blue5 << 1) | (blue5 >> 4)
    if fmt == COLMOD_12BIT:
        # 4 -> 6 bits by repeating the top bits, the same rule as for 5 -> 6.
        red4, green4, blue4 = fields[:, 0], fields[:, 1], fields[:, 2]
        return (red4 << 2) | (red4 >> 2), (green4 << 2) | (green4 >> 2), (blue4 << 2) | (blue4 >> 2)
    # 18-bit: one byte per channel, the lower two bits are don't-care.
    return fields[:, 0] >> 2, fields[:, 1] >> 2, fields[:, 2] >> 2


def _address_pair(params: list[int]) -> tuple[int, int]:
    """CASET/RASET parameters: start hi, start lo, end hi, end lo."""
    return (params[0] << 8) | params[1], (params[2] << 8) | params[3]


def _command_name(code: int) -> str:
    return f"{COMMAND_NAMES.get(code, 'command')} (0x{code:02X})"


def _ms(now: Time) -> str:
    return f"t={ms(now)}"
