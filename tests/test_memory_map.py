"""memory_map.K210_BLOCKS is the one home of the K210's address map: every block the board builds
sits where it says, with its clock gate, its interrupt lines wired to its PLIC sources; no two
blocks, modelled or known by name, overlap."""
from __future__ import annotations

from emulator.devices.sysctl import PERI_BITS
from emulator.memory_map import K210_BLOCKS, K210_UNMODELLED, SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE
from k210_fixtures import board, idle_elf  # noqa: F401


def test_the_board_builds_every_block_where_the_map_says(board):
    built = {p.NAME: p for p in board.peripherals}
    assert set(built) == set(K210_BLOCKS)
    for name, block in K210_BLOCKS.items():
        device = built[name]
        assert (device.BASE, device.SIZE, getattr(device, "GATE", None)) == (block.base, block.size, block.gate), name
        assert block.gate is None or block.gate in PERI_BITS, name


def test_no_two_blocks_overlap():
    ranges = sorted([(b.base, b.base + b.size, n) for n, b in K210_BLOCKS.items()]
                    + [(base, base + size, n) for base, size, n in K210_UNMODELLED]
                    + [(SRAM_BASE, SRAM_BASE + SRAM_SIZE, "SRAM"), (SRAM_UNCACHED_BASE, SRAM_UNCACHED_BASE + SRAM_SIZE, "SRAM")])
    for (_, end, name), (start, _, other) in zip(ranges, ranges[1:]):
        assert end <= start, f"{name} overlaps {other}"


def test_every_interrupt_line_reaches_its_source(board):
    """Each block's lines, raised one at a time, reach the PLIC as the sources the map gives."""
    sources = [s for block in K210_BLOCKS.values() for s in block.irqs]
    assert len(sources) == len(set(sources)) and set(sources) <= set(range(1, 66))
    for device, _ in board._interrupting:
        device.irq_lines = lambda: 0             # (SPI0 and SPI1 raise theirs at reset: FIFOs empty)
    assert board._high_sources() == []
    for device, wired in board._interrupting:
        for line, source in enumerate(wired):
            device.irq_lines = lambda line=line: 1 << line
            assert board._high_sources() == [source], device.NAME
        device.irq_lines = lambda: 0
