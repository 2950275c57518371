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


# --- the copies the firmware needs (assembly and C), checked against the map ---------------------

import re  # noqa: E402

from suite import ROOT  # noqa: E402



def header_values(path, pattern: str) -> dict[str, int]:
    return {name: int(value, 0) for name, value in re.findall(pattern, path.read_text(), re.MULTILINE)}


def test_the_firmware_headers_agree_with_the_map():
    """firmware/include/k210.inc (our assembly firmware) and tests/firmware/k210.h (the C test
    firmware) copy block addresses and PLIC sources from the map: every copy, in each file, matches
    it (a block's name and _BASE; the first interrupt line of the blocks they name)."""
    headers = {
        "k210.inc": header_values(ROOT / "firmware" / "include" / "k210.inc",
                                  r"^\s*\.equ\s+(\w+),\s*(0x[0-9A-Fa-f]+|\d+)\s*(?:#.*)?$"),
        "k210.h": header_values(ROOT / "tests" / "firmware" / "k210.h",
                                r"^#define\s+(\w+)\s+(0x[0-9A-Fa-f]+|\d+)u?\s*(?:/\*.*)?$")}
    first_line = {"PLIC_SRC_SPI0": "SPI0", "PLIC_SRC_DMA0": "DMAC", "PLIC_SRC_UARTHS": "UARTHS",
                  "IRQ_TIMER0A": "TIMER0", "IRQ_RTC": "RTC", "IRQ_WDT0": "WDT0", "IRQ_GPIOHS0": "GPIOHS"}
    checked = 0
    for file, values in headers.items():
        for name, value in values.items():
            if name.endswith("_BASE") and name[:-5] in K210_BLOCKS:
                assert value == K210_BLOCKS[name[:-5]].base, f"{file}: {name}"
                checked += 1
            if name in first_line:
                assert value == K210_BLOCKS[first_line[name]].irqs[0], f"{file}: {name}"
                checked += 1
    assert checked >= 27


def test_the_firmware_headers_pads_are_the_dock_s():
    """Every PAD_ number in k210.inc and k210.h is the Dock's (board/maix_dock.py), by name."""
    from emulator.board.maix_dock import DOCK_PADS, PAD_ALIASES
    files = {"k210.inc": (ROOT / "firmware" / "include" / "k210.inc", r"^\s*\.equ\s+PAD_(\w+),\s*(\d+)"),
             "k210.h": (ROOT / "tests" / "firmware" / "k210.h", r"^#define\s+PAD_(\w+)\s+(\d+)")}
    checked = 0
    for file, (path, pattern) in files.items():
        for name, value in header_values(path, pattern).items():
            if name.startswith("WORD") or name.endswith("SHIFT"):
                continue
            key = PAD_ALIASES.get(name, name)
            assert key in DOCK_PADS, f"{file}: PAD_{name} is no pad of the Dock's table"
            assert int(value) == DOCK_PADS[key].number, f"{file}: PAD_{name}"
            checked += 1
    assert checked >= 18


def test_the_firmware_headers_map_is_generated_from_the_map(capsys):
    """The block addresses and PLIC sources in k210.inc and k210.h are tools/k210_map.py's output
    from K210_BLOCKS, as it would write them now."""
    from tools import k210_map
    assert k210_map.main(["--check"]) == 0, capsys.readouterr().out
