"""What a test run may and may not touch in build/ (issue 32: `make test` overwrote build/frames
and wrote build/hello, build/blink, ...).

build/ holds the prerequisites the Makefile builds for the tests (the firmware, the C test
programs, the default card) and, besides them, the user's own outputs: `make
flash-to-emulator`'s build/frames, `make golden-check`'s build/golden-check, the folders the
commands of the README and docs/ write. A test writes its outputs into its temporary folder; `changed_outputs`
says which of the user's it touched."""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BUILD = ROOT / "build"

#: What the Makefile builds in build/ for the tests: the firmware (fw/, firmware.elf,
#: firmware.bin), the C test programs (cfw/) and the default card (assets/, card.img, and the
#: temporary file next to it that the card tool writes it through). All else is the user's.
PREREQUISITES = re.compile(r"(fw|cfw|assets|firmware\.elf|firmware\.bin|card\.img|\.card\.img\..*\.tmp)$")


def build_outputs() -> dict[str, tuple[int, int]]:
    """build/'s files and folders besides the prerequisites: path -> (size, modification time)."""
    if not BUILD.is_dir():
        return {}
    found = {}
    for top in BUILD.iterdir():
        if PREREQUISITES.match(top.name):
            continue
        for path in [top, *(top.rglob("*") if top.is_dir() and not top.is_symlink() else [])]:
            try:
                stat = path.lstat()
            except FileNotFoundError:       # removed while listed: a change the comparison sees
                continue
            found[str(path.relative_to(ROOT))] = (stat.st_size if path.is_file() else 0, stat.st_mtime_ns)
    return found


def changed_outputs(before: dict[str, tuple[int, int]]) -> list[str]:
    """The paths of build/ (prerequisites aside) written, made or removed since `before`."""
    after = build_outputs()
    return sorted(path for path in set(before) | set(after) if before.get(path) != after.get(path))
