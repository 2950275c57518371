"""docs/reference/memory-limits.md's memory limits are what the firmware gives (tools/memory_limits.py: the replay of its
heap allocations that tests/slow/test_extremes.py holds against the firmware on the board model)."""
from __future__ import annotations

from tools import memory_limits


def test_the_readmes_memory_limits_are_the_firmwares(firmware, capsys):
    assert memory_limits.main(["--firmware", str(firmware), "--check"]) == 0, capsys.readouterr().out


def test_one_more_of_each_is_an_error_12_naming_its_block(firmware):
    rows = memory_limits.compute(firmware)
    assert len(rows) == 14
    assert all(row.one_more.startswith("error 12 model too large for memory (") for row in rows)
