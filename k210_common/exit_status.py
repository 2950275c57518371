"""The exit statuses of every command of the project, in one table.

`python -m emulator`, `python -m sdcard_image`, `python -m reference`, tools/flash.py and
tools/regen_goldens.py share these numbers: a status means the same whichever command returns
it, so a script or CI can read it without knowing which command ran. Each command says which
rows it returns, and when, in a mapping code -> its own words (`details`); its `--help`
epilog (`help_epilog`) and its table in docs/reference/ (`markdown_table`, checked by
tests/unit/shared/test_exit_status.py) are generated from that mapping and this table.

New statuses are appended (13 on): the board model's 0-12 are in use in scripts and CI. A run
ended by a signal returns 128 + its number, as shells report it (130 for SIGINT, 143 for SIGTERM).
"""
from __future__ import annotations

import textwrap
from collections.abc import Mapping
from dataclasses import dataclass

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_USAGE = 2
EXIT_TRAP = 3
EXIT_HANG = 4
EXIT_UNMODELLED = 5
EXIT_BAD_INPUT = 6
EXIT_MISUSE = 7
EXIT_FIRMWARE_ERROR = 8
EXIT_GOLDEN_MISMATCH = 9
EXIT_STRAY_WRITE = 10
EXIT_FAIL_ON = 11
EXIT_EXPECT_UNMET = 12
EXIT_OUTPUT_EXISTS = 13
EXIT_CARD_TOO_SMALL = 14
EXIT_CORRUPT_CARD = 15
EXIT_WRITE_FAILED = 16
EXIT_KFLASH_FAILED = 17
EXIT_INTERRUPTED = 130      # 128 + SIGINT
EXIT_TERMINATED = 143       # 128 + SIGTERM


@dataclass(frozen=True)
class ExitStatus:
    code: int
    name: str       # also the board model's `kind` of a run's end in run.json
    meaning: str    # what it means for any command; a command's details say when it returns it


TABLE: tuple[ExitStatus, ...] = (
    ExitStatus(EXIT_OK, "ok", "the command did what was asked"),
    ExitStatus(EXIT_INTERNAL, "internal", "an internal error (a bug: please report it with the command line)"),
    ExitStatus(EXIT_USAGE, "usage", "bad command line"),
    ExitStatus(EXIT_TRAP, "trap", "the firmware trapped"),
    ExitStatus(EXIT_HANG, "hang", "the firmware hung: no frame, or every hart waits forever"),
    ExitStatus(EXIT_UNMODELLED, "unmodelled", "the firmware touched hardware the board model does not implement"),
    ExitStatus(EXIT_BAD_INPUT, "bad-input", "an input file or folder the command line names cannot be used"),
    ExitStatus(EXIT_MISUSE, "misuse", "the firmware used hardware in a way the real K210 does not"),
    ExitStatus(EXIT_FIRMWARE_ERROR, "firmware-error", "the firmware reported a fatal error on its console"),
    ExitStatus(EXIT_GOLDEN_MISMATCH, "golden-mismatch", "a frame differs from its golden"),
    ExitStatus(EXIT_STRAY_WRITE, "stray-write", "a store landed outside the firmware's buffers"),
    ExitStatus(EXIT_FAIL_ON, "fail-on", "the console printed a text named as failure"),
    ExitStatus(EXIT_EXPECT_UNMET, "expect-unmet", "the console did not print every expected text"),
    ExitStatus(EXIT_OUTPUT_EXISTS, "output-exists", "the output exists and was not to be replaced"),
    ExitStatus(EXIT_CARD_TOO_SMALL, "card-too-small", "the content does not fit in the card image"),
    ExitStatus(EXIT_CORRUPT_CARD, "corrupt-card", "a card image is not an MBR-partitioned FAT32 card, or is damaged"),
    ExitStatus(EXIT_WRITE_FAILED, "write-failed", "an output could not be written"),
    ExitStatus(EXIT_KFLASH_FAILED, "kflash-failed", "kflash could not write the firmware to the board"),
    ExitStatus(EXIT_INTERRUPTED, "interrupted", "stopped by Ctrl-C (SIGINT)"),
    ExitStatus(EXIT_TERMINATED, "terminated", "stopped by SIGTERM"),
)

BY_CODE: dict[int, ExitStatus] = {status.code: status for status in TABLE}

HELP_WIDTH = 100        # the epilogs' line length, as the commands' hand-wrapped help had it
_HELP_INDENT = 5        # "NNN  " before each row's text


def _checked(details: Mapping[int, str]) -> list[int]:
    """The codes of `details` in order; a code outside the table is a programming error."""
    unknown = sorted(set(details) - set(BY_CODE))
    if unknown:
        raise ValueError(f"exit statuses {unknown} are not in k210_common/exit_status.py's TABLE")
    return sorted(details)


def help_epilog(details: Mapping[int, str]) -> str:
    """The "exit status:" epilog of a command's --help: one row per status it returns, its
    number, name and the command's own words for when it returns it (written for docs/reference/:
    its `code` quotes are dropped here)."""
    lines = ["exit status:"]
    for code in _checked(details):
        text = f"{BY_CODE[code].name}: {details[code]}".replace("`", "")
        lines += textwrap.wrap(text, HELP_WIDTH, initial_indent=f"{code:>3}  ",
                               subsequent_indent=" " * _HELP_INDENT, break_on_hyphens=False)
    return "\n".join(lines) + "\n"


def markdown_table(details: Mapping[int, str]) -> str:
    """A command's exit statuses as docs/reference/'s table (the same rows as its --help)."""
    rows = ["| status | name | when |", "|---|---|---|"]
    rows += [f"| {code} | {BY_CODE[code].name} | {details[code]} |" for code in _checked(details)]
    return "\n".join(rows) + "\n"


def shared_markdown_table(commands: Mapping[str, Mapping[int, str]]) -> str:
    """The whole table as docs/reference/exit-statuses.md shows it, with the commands that return each status."""
    for details in commands.values():
        _checked(details)
    rows = ["| status | name | meaning | returned by |", "|---|---|---|---|"]
    for status in TABLE:
        users = ", ".join(command for command, details in commands.items() if status.code in details)
        rows.append(f"| {status.code} | {status.name} | {status.meaning} | {users} |")
    return "\n".join(rows) + "\n"
