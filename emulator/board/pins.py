"""What drives the Dock's pads from outside: a key pressed, a signal generator (--pin, --pin-file).

A schedule of changes, each a pad, a level (0, 1, or None: let go, the pad floats) and a virtual
time. The board advances it like a device: at each change the Dock's wiring follows (GPIOHS and
GPIO lines routed to that pad see the level, their edge and level interrupts included). A line
the chip drives itself reads its own output; an undriven pad reads its pull (FPIOA's pad pull-up
or pull-down, or GPIOHS's own), else 0.
"""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..devices.fpioa import PAD_COUNT
from ..errors import BadInput
from ..vtime import Time, from_seconds, to_seconds

LEVELS = {"0": 0, "1": 1, "z": None, "Z": None}


@dataclass(frozen=True)
class PinChange:
    at: Time             # virtual time
    pad: int
    level: int | None    # None: the outside lets go of the pad

    def describe(self) -> str:
        return f"{self.pad}={'z' if self.level is None else self.level}@{to_seconds(self.at):g}"


def parse_pin(text: str) -> PinChange:
    """PAD=LEVEL@SECONDS (LEVEL 0, 1 or z); ValueError with what is wrong."""
    pad_part, sep, rest = text.partition("=")
    level_part, sep2, time_part = rest.partition("@")
    if not sep or not sep2:
        raise ValueError(f"{text!r}: expected PAD=LEVEL@SECONDS, e.g. 16=0@0.5")
    return _change(pad_part, level_part, time_part, text)


def _change(pad_text: str, level_text: str, time_text: str, what: str) -> PinChange:
    try:
        pad = int(pad_text)
    except ValueError:
        raise ValueError(f"{what}: the pad {pad_text!r} is not a number") from None
    if not 0 <= pad < PAD_COUNT:
        raise ValueError(f"{what}: pad {pad} does not exist (the K210 has pads 0 to {PAD_COUNT - 1})")
    if level_text not in LEVELS:
        raise ValueError(f"{what}: the level {level_text!r} is not 0, 1 or z")
    try:
        at = float(time_text)
    except ValueError:
        raise ValueError(f"{what}: the time {time_text!r} is not a number of seconds") from None
    if not 0 <= at < math.inf:
        raise ValueError(f"{what}: the time must be 0 or more seconds, and finite")
    return PinChange(from_seconds(at), pad, LEVELS[level_text])


def load_schedule(path: Path) -> list[PinChange]:
    """A schedule file: a change a line, `SECONDS PAD LEVEL`; `#` starts a comment. BadInput naming
    the file and line for anything else."""
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as error:
        raise BadInput(f"--pin-file {path}: cannot be read ({error})") from None
    changes = []
    for number, line in enumerate(text.splitlines(), 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        if len(words) != 3:
            raise BadInput(f"{path}:{number}: expected SECONDS PAD LEVEL, found {line.strip()!r}")
        try:
            changes.append(_change(words[1], words[2], words[0], f"{path}:{number}"))
        except ValueError as error:
            raise BadInput(str(error)) from None
    return changes


class ExternalPins:
    """The schedule, played as virtual time passes (a timed device of the board)."""

    def __init__(self, changes: list[PinChange], on_change: Callable[[Time], None]) -> None:
        """on_change: the levels changed at this time (the board's wiring follows)."""
        self._pending = sorted(changes, key=lambda change: change.at)
        self.levels: dict[int, int] = {}          # pads driven from outside now
        self.version = 0                          # changes whenever `levels` does
        self.on_change = on_change
        self.played: list[PinChange] = []

    def add(self, change: PinChange) -> None:
        """A change more, driven from outside while the board runs (Board.drive_pad): after the
        changes already due at its time or before."""
        bisect.insort_right(self._pending, change, key=lambda pending: pending.at)

    def next_event_time(self, now: Time) -> Time | None:
        return self._pending[0].at if self._pending else None

    def advance(self, now: Time) -> None:
        while self._pending and self._pending[0].at <= now:
            at = self._pending[0].at
            while self._pending and self._pending[0].at == at:
                change = self._pending.pop(0)
                if change.level is None:
                    self.levels.pop(change.pad, None)
                else:
                    self.levels[change.pad] = change.level
                self.played.append(change)
            self.version += 1
            self.on_change(at)
