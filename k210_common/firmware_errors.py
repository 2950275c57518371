"""The firmware's fatal error codes, read from the firmware's own firmware/include/errors.inc.

The host tools name these errors (the card tool's checks refuse what the firmware would refuse,
"as its error 10"; the tests expect `error <code> <words>` lines and the error screens' colours).
They read them here rather than re-typing them, so a code the firmware renumbers or adds is
seen by all. errors.inc is the source: its `.equ ERR_<NAME>, <code>` and
`.equ ERR_COLOUR_<NAME>, <RGB565>` lines, which the firmware assembles, and its comment table,
which alone holds each code's console words and screen colour's name; the two are checked
against each other here, so a table that drifts from the `.equ`s fails loudly.

The file is read from the checkout this package lies in (the project is installed editable);
nothing is read until a caller asks.
"""
from __future__ import annotations

import functools
import re
from dataclasses import dataclass
from pathlib import Path

ERRORS_INC = Path(__file__).resolve().parent.parent / "firmware" / "include" / "errors.inc"
CONSOLE_PREFIX = "error "   # a fatal error's console line: "error <code> <words>[: <detail>]"

_EQU = re.compile(r"^\s*\.equ\s+ERR_(\w+),\s*(\w+)", re.M)
# "#   5   ERR_NO_FAT32      no FAT32 partition /      cyan     0x07FF  (0, 255, 255)"
_ROW = re.compile(r"^#\s+(\d+)\s+ERR_(\w+)\s+(.+?)\s+([a-z]+)\s+(0x[0-9A-Fa-f]{4})\s+\((\d+), (\d+), (\d+)\)\s*$")
# "#                         invalid BPB": the words of the row above go on
_CONTINUED = re.compile(r"^#\s{20,}(\S.*?)\s*$")


@dataclass(frozen=True)
class FirmwareError:
    code: int
    name: str                           # without ERR_: "BAD_MODEL"
    words: tuple[str, ...]              # what its console line says after the code, one of these:
                                        # ("no FAT32 partition", "invalid BPB")
    colour_name: str                    # "teal"
    rgb565: int                         # what the firmware fills the screen with
    rgb888: tuple[int, int, int]        # how the panel (and the board model's frames) show it

    @property
    def console_starts(self) -> tuple[str, ...]:
        """How its console line may start: ("error 10 bad model",)."""
        return tuple(f"{CONSOLE_PREFIX}{self.code} {words}" for words in self.words)

    def reported_by(self, line: str) -> bool:
        """Whether a console line is this error's report."""
        return line.startswith(self.console_starts)


@dataclass(frozen=True)
class FirmwareErrors:
    errors: tuple[FirmwareError, ...]   # by code, 1 on

    @property
    def codes(self) -> frozenset[int]:
        return frozenset(error.code for error in self.errors)

    def by_name(self, name: str) -> FirmwareError:
        for error in self.errors:
            if error.name == name:
                return error
        raise KeyError(f"errors.inc has no ERR_{name} (it has {', '.join(e.name for e in self.errors)})")

    def by_code(self, code: int) -> FirmwareError:
        for error in self.errors:
            if error.code == code:
                return error
        raise KeyError(f"errors.inc has no error code {code}")


def parse(text: str) -> FirmwareErrors:
    """errors.inc's errors; ValueError naming what disagrees when its table and `.equ`s differ."""
    equs = {name: int(value, 0) for name, value in _EQU.findall(text)}
    count = equs.pop("CODE_COUNT", None)
    colours = {name[len("COLOUR_"):]: value for name, value in equs.items() if name.startswith("COLOUR_")}
    codes = {name: value for name, value in equs.items() if not name.startswith("COLOUR_")}
    rows = _table_rows(text)
    if count is None or sorted(codes.values()) != list(range(1, count)):
        raise ValueError(f"errors.inc: the codes {sorted(codes.values())} are not 1 .. ERR_CODE_COUNT - 1 ({count})")
    errors = []
    for name, code in sorted(codes.items(), key=lambda item: item[1]):
        row = rows.get(code)
        if row is None or row[0] != name:
            raise ValueError(f"errors.inc: ERR_{name} = {code}, but its comment table's row {code} is {row}")
        _, words, colour_name, rgb565, rgb888 = row
        if colours.get(name) != rgb565:
            raise ValueError(f"errors.inc: ERR_COLOUR_{name} is {colours.get(name)}, its comment table says "
                             f"{rgb565:#06x}")
        # "no FAT32 partition / invalid BPB": the table's " / " separates alternatives
        errors.append(FirmwareError(code, name, tuple(words.split(" / ")), colour_name, rgb565, rgb888))
    if set(rows) != set(codes.values()):
        raise ValueError(f"errors.inc: its comment table has rows {sorted(rows)}, its .equs codes "
                         f"{sorted(codes.values())}")
    return FirmwareErrors(tuple(errors))


def _table_rows(text: str) -> dict[int, tuple[str, str, str, int, tuple[int, int, int]]]:
    """The comment table: code -> (name, words, colour name, RGB565, RGB888)."""
    rows: dict[int, tuple[str, str, str, int, tuple[int, int, int]]] = {}
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("# ----")) + 1
    last = None
    for line in lines[start:]:
        row = _ROW.match(line)
        continued = _CONTINUED.match(line)
        if row:
            code = int(row.group(1))
            rgb888 = (int(row.group(6)), int(row.group(7)), int(row.group(8)))
            rows[code] = (row.group(2), row.group(3), row.group(4), int(row.group(5), 16), rgb888)
            last = code
        elif continued and last is not None:
            name, words, colour_name, rgb565, rgb888 = rows[last]
            rows[last] = (name, f"{words} {continued.group(1)}", colour_name, rgb565, rgb888)
        else:
            break
    return rows


@functools.cache
def firmware_errors() -> FirmwareErrors:
    """The errors of the firmware in this checkout (read once)."""
    if not ERRORS_INC.is_file():
        raise FileNotFoundError(f"{ERRORS_INC}: the firmware's error codes are read from it; "
                                f"k210_common must run from the project's checkout (pip install -e)")
    return parse(ERRORS_INC.read_text())


def firmware_error(name: str) -> FirmwareError:
    """One error by its name without ERR_, e.g. firmware_error("BAD_MODEL").code == 10."""
    return firmware_errors().by_name(name)
