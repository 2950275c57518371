"""The K210's address map as every layer of the model sees it: where SRAM is, and where the
harts start. (Each device's own base address is in its register table, devices/*.py.)"""
from __future__ import annotations

SRAM_BASE = 0x8000_0000
SRAM_UNCACHED_BASE = 0x4000_0000      # the same bytes, not through the data cache
SRAM_SIZE = 8 * 1024 * 1024          # 6 MiB SRAM0/SRAM1 + 2 MiB AI SRAM
GENERAL_SRAM_SIZE = 6 * 1024 * 1024
RESET_PC = SRAM_BASE                 # where both harts start when the mask ROM hands over


def is_sram(address: int) -> bool:
    """Whether `address` is in SRAM, through either view."""
    return SRAM_BASE <= address < SRAM_BASE + SRAM_SIZE or SRAM_UNCACHED_BASE <= address < SRAM_UNCACHED_BASE + SRAM_SIZE
