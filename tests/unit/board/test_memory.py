"""SRAM (emulator/board/memory.py): every board's SRAM starts with the same power-on pattern, and what
one board writes is its own (each SRAM is a private copy-on-write mapping of that pattern)."""
from __future__ import annotations

import numpy as np

from emulator.board.memory import POWER_ON_SEED, Sram, power_on_pattern
from emulator.memory_map import SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE


def test_each_sram_starts_with_the_power_on_pattern_and_keeps_its_own_writes():
    pattern = power_on_pattern(POWER_ON_SEED)
    first, second = Sram(), Sram()
    assert first.bytes.size == SRAM_SIZE and np.array_equal(first.bytes, pattern)
    assert len(np.unique(pattern[:4096])) > 200          # random bytes, not a fill
    first.load(SRAM_BASE + 0x10_0000, b"abc")
    first.bytes[SRAM_SIZE - 1] ^= 0xFF
    assert first.read(SRAM_UNCACHED_BASE + 0x10_0000, 3) == b"abc"        # both views, one buffer
    assert first.bytes[SRAM_SIZE - 1] == pattern[SRAM_SIZE - 1] ^ 0xFF
    for other in (second, Sram()):                        # made before the writes and after them
        assert other.read(SRAM_BASE + 0x10_0000, 3) == pattern[0x10_0000:0x10_0003].tobytes()
        assert np.array_equal(other.bytes, pattern)
    assert not pattern.flags.writeable


def test_an_sram_without_a_seed_starts_cleared():
    sram = Sram(fill_seed=None)
    assert sram.bytes.size == SRAM_SIZE and not sram.bytes.any()
    sram.load(SRAM_BASE, b"\x01")
    assert not Sram(fill_seed=None).bytes.any()
