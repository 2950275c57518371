"""Writes the exit-status tables of docs/reference/ and sdcard_image/README.md from
k210_common/exit_status.py and each command's EXIT_STATUS_DETAILS, so that they cannot drift from the commands' --help.

    python -m tools.exit_status_tables            (from the project's root: rewrites the tables)
    python -m tools.exit_status_tables --check    (exit 1, naming each table that differs)

A table is the lines after a marker line `<!-- exit statuses: COMMAND -->` up to the first
line that is not a table row; COMMAND is `all` for the shared table (every status and the
commands that return it) or one of COMMANDS. tests/unit/shared/test_exit_status.py runs the check.
"""
from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Mapping
from pathlib import Path

from k210_common.exit_status import markdown_table, shared_markdown_table

ROOT = Path(__file__).resolve().parent.parent
#: The files that hold marked tables (docs/reference/exit-statuses.md the shared one, docs/reference/options.md
#: the board model's, docs/reference/reference-renderer.md the reference's, sdcard_image/README.md the card tool's).
READMES = (ROOT / "docs" / "reference" / "exit-statuses.md", ROOT / "docs" / "reference" / "options.md",
           ROOT / "docs" / "reference" / "reference-renderer.md", ROOT / "sdcard_image" / "README.md")
MARKER = re.compile(r"^<!-- exit statuses: (\S+) -->$")


# the keys of the markers, and how each command is run (the shared table's last column)
COMMANDS = {"emulator": "python -m emulator", "sdcard_image": "python -m sdcard_image",
            "reference": "python -m reference", "flash": "tools/flash.py", "regen_goldens": "tools/regen_goldens.py"}


def command_details() -> dict[str, Mapping[int, str]]:
    """Each command's statuses and when it returns them, by its key in COMMANDS."""
    # imported here: the board model's command line loads the whole model
    from emulator.frontends.options import EXIT_STATUS_DETAILS as emulator
    from reference.cli import EXIT_STATUS_DETAILS as reference
    from sdcard_image.cli import EXIT_STATUS_DETAILS as sdcard_image
    from tools.flash import EXIT_STATUS_DETAILS as flash
    from tools.regen_goldens import EXIT_STATUS_DETAILS as regen_goldens
    return {"emulator": emulator, "sdcard_image": sdcard_image, "reference": reference, "flash": flash,
            "regen_goldens": regen_goldens}


def table_for(key: str, commands: Mapping[str, Mapping[int, str]]) -> str:
    if key == "all":
        return shared_markdown_table({COMMANDS[name]: details for name, details in commands.items()})
    if key not in commands:
        raise KeyError(f"<!-- exit statuses: {key} -->: no such command (all, {', '.join(commands)})")
    return markdown_table(commands[key])


def rewritten(text: str, commands: Mapping[str, Mapping[int, str]]) -> tuple[str, list[str]]:
    """The text with every marked table regenerated, and the keys of the tables found."""
    lines = text.split("\n")
    out: list[str] = []
    keys: list[str] = []
    index = 0
    while index < len(lines):
        line = lines[index]
        out.append(line)
        index += 1
        marker = MARKER.match(line)
        if marker is None:
            continue
        keys.append(marker.group(1))
        while index < len(lines) and lines[index].startswith("|"):
            index += 1
        out += table_for(marker.group(1), commands).rstrip("\n").split("\n")
    return "\n".join(out), keys


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.exit_status_tables", description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="only say which tables differ (exit 1 if any)")
    args = parser.parse_args(argv)
    commands = command_details()
    stale = []
    for readme in READMES:
        text = readme.read_text()
        new, keys = rewritten(text, commands)
        if new != text:
            stale.append(readme)
            if not args.check:
                readme.write_text(new)
        print(f"{readme.relative_to(ROOT)}: tables {', '.join(keys) or 'none'}"
              f"{' (differ)' if new != text and args.check else ' (rewritten)' if new != text else ''}")
    return 1 if stale and args.check else 0


if __name__ == "__main__":
    sys.exit(main())
