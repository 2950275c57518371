"""--vcd: the Dock's pins over virtual time as a Value Change Dump (IEEE 1364), which GTKWave
and sigrok (PulseView) open, so that firmware can be timed as on the bench, with an LED pin
and a scope.

Signals, as the board model knows them:
- `padNN`: the level a GPIOHS or slow-GPIO line drives on FPIOA pad NN (z while none does):
  LEDs (pads 12-14), the LCD's reset (37) and D/C (38), the SD card's select when a GPIO line
  drives it, any pin firmware toggles for timing;
- `spi0_ss_n`, `spi1_ss_n`: each controller's slave select (low while it is enabled and
  `ser` selects a slave);
- `spi0_sclk`, `spi1_sclk`: the serial clock as bursts: high while frames are on the wire,
  low between; one pulse per burst instead of every edge (a 10 MHz clock over seconds would
  be hundreds of millions of lines; the burst's length and the frame count give the rate).

Events are kept in memory and written when the run ends, sorted by time, in picoseconds. Every
signal's value when the log began (time 0 of a run) comes first, in a `$dumpvars` section, as IEEE
1364-2005 describes the four-state VCD (clause 18.2: the section beginning with the $dumpvars
keyword lists the initial values of all variables dumped; the standard's example file begins its
value changes with `#0 $dumpvars ... $end`): `z` for a pad no line drives yet, so that a viewer
shows the pad undriven, not `x`, until its first change.
"""
from __future__ import annotations

from pathlib import Path
from typing import IO

from ..devices.fpioa import PAD_COUNT
from ..errors import BadInput
from ..vtime import Time

# the model's own unit (vtime.py): every change is dumped at its exact time
TIMESCALE = "1ps"


def open_vcd(path: Path) -> IO[str]:
    """The VCD file, opened before the run: a path that cannot be written is bad input."""
    try:
        return path.open("w")
    except OSError as error:
        raise BadInput(f"--vcd {path}: cannot write it ({error.strerror or error})") from None


def _level(value: int | None) -> str:
    return "z" if value is None else str(value)


class SignalLog:
    """Value changes of named one-bit signals (0, 1, or None for undriven) from `start` on, and each
    signal's value at `start` (`initial`; a signal it does not name is undriven then)."""

    def __init__(self, start: Time = 0, initial: dict[str, int | None] | None = None) -> None:
        self.start = start
        self.initial: dict[str, int | None] = dict(initial or {})
        self.events: list[tuple[Time, int, str, int | None]] = []   # (time, order, signal, value)
        self._last: dict[str, int | None] = dict(self.initial)

    def record(self, at: Time, signal: str, value: int | None) -> None:
        if self._last.get(signal, "unset") == value:
            return
        self._last[signal] = value
        self.events.append((at, len(self.events), signal, value))

    def write(self, out: IO[str], end: Time) -> int:
        """Writes the dump (and closes `out`): every signal that changed, its value at the start in
        `$dumpvars`, then its changes. Returns the number of value changes written after `$dumpvars`."""
        events = sorted(self.events)
        names = sorted({signal for _, _, signal, _ in events})
        codes = {name: _identifier(n) for n, name in enumerate(names)}
        at_start = {name: self.initial.get(name) for name in names}
        changes = []
        for at, _, signal, value in events:
            if at <= self.start:
                at_start[signal] = value         # (set as the log began: part of the initial values)
            else:
                changes.append((at, signal, value))
        out.write("$comment Sipeed Maix Dock board model (python -m emulator run --vcd) $end\n")
        out.write(f"$timescale {TIMESCALE} $end\n$scope module dock $end\n")
        for name in names:
            out.write(f"$var wire 1 {codes[name]} {name} $end\n")
        out.write("$upscope $end\n$enddefinitions $end\n")
        out.write(f"#{self.start}\n$dumpvars\n")
        for name in names:
            out.write(f"{_level(at_start[name])}{codes[name]}\n")
        out.write("$end\n")
        current = self.start
        for at, signal, value in changes:
            if at != current:
                out.write(f"#{at}\n")
                current = at
            out.write(f"{_level(value)}{codes[signal]}\n")
        if end > current:
            out.write(f"#{end}\n")
        out.close()
        return len(changes)


def attach(board) -> SignalLog:
    """A log for the board's pins from the board's time on: the pads' levels then (undriven, z, at
    reset: no GPIOHS or GPIO line drives a pad before FPIOA routes one to it), the slave selects'
    idle level and the clocks low."""
    log = SignalLog(board.time, {f"pad{pad:02d}": board.wiring.logged_pad_level(pad) for pad in range(PAD_COUNT)})
    board.signals = log
    for controller in (board.spi0, board.spi1):
        log.record(board.time, f"spi{controller.index}_ss_n", 0 if controller._ss_low else 1)
        log.record(board.time, f"spi{controller.index}_sclk", 0)
    return log


def _identifier(index: int) -> str:
    """VCD identifier codes: printable ASCII 33..126, as short as possible."""
    chars = []
    while True:
        index, digit = divmod(index, 94)
        chars.append(chr(33 + digit))
        if index == 0:
            return "".join(chars)
        index -= 1
