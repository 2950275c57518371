"""docs/reference/outputs.md's table of run.json's fields is what the code writes (issue 32, item 2:
the reference tested against the code): every field a real run writes, and every field the command
line adds only in some runs, has its row; no row names a field nobody writes."""
from __future__ import annotations

import re

from suite import ROOT

OUTPUTS = ROOT / "docs" / "reference" / "outputs.md"
# where the fields a run adds only in some runs are written
WRITERS = [ROOT / "emulator" / "frontends" / name for name in ("cli.py", "output.py")]


def documented() -> set[str]:
    rows = re.findall(r"^\| (`[a-z_]+`(?:, `[a-z_]+`)*) \|", OUTPUTS.read_text(), re.MULTILINE)
    return {name for row in rows for name in re.findall(r"`([a-z_]+)`", row)}


def test_every_run_json_field_has_its_row(firmware_run):
    _, _, summary = firmware_run
    written = set(summary) | {name for path in WRITERS
                              for name in re.findall(r'summary\["([a-z_]+)"\] =', path.read_text())}
    table = documented()
    assert written - table == set(), "run.json fields the reference does not describe"
    assert table - written == set(), "rows for fields nobody writes"
