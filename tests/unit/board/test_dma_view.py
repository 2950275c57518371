"""SRAM as the DMA sees it behind the harts' data caches (emulator/board/dma_view.py, _caches.c): the
K210's DMAC is not coherent with them. The Kendryte SDK stages every DMA buffer in the uncached view
for that reason (its "Fix cache" change); here a small program stores and loads through the cached
view while the test reads and writes as the DMAC does, through the port the DMAC uses."""
from __future__ import annotations

import numpy as np

from emulator.memory_map import SRAM_BASE, SRAM_UNCACHED_BASE
from k210_fixtures import build_elf, make_board, reg, run_until, symbol

PROGRAM = """
    .option norelax
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, park
    la      s0, buffer
    li      t0, 0x1122334455667788
    sd      t0, 0(s0)               # in the data cache, dirty
    li      s5, 0x80600000          # AI SRAM, outside the program (a reset does not load it again)
    sd      t0, 0(s5)
step1:
    j       step1                   # (the test looks, then moves the hart on)
after1:
    .insn   i 0x0F, 1, x0, x0, 0    # FENCE.I: written back
step2:
    j       step2
after2:
    ld      s1, 8(s0)               # in the data cache, read-only
step3:
    j       step3                   # (the DMA writes the buffer)
after3:
    ld      s2, 8(s0)               # the cached copy still
    .insn   i 0x0F, 1, x0, x0, 0
    ld      s3, 8(s0)               # fetched again: the DMA's bytes
    li      t0, 0x0A0B0C0D
    sd      t0, 16(s0)              # dirty again
step4:
    j       step4                   # (the DMA writes the same line)
after4:
    .insn   i 0x0F, 1, x0, x0, 0    # the hart's dirty line goes back over the DMA's bytes
    ld      s4, 24(s0)
done:
    j       done
park:
    csrw    mie, zero
1:  wfi
    j       1b
    .data
    .balign 64
buffer: .dword 0, 0, 0, 0, 0, 0, 0, 0
"""


def go_to(board, label: str, then: str | None = None) -> None:
    if then is not None:
        board.harts[0].pc = symbol(board, then)
    run_until(board, lambda b: b.harts[0].pc == symbol(b, label), max_time_s=0.01)


def dma_read(board, address: int, length: int = 8) -> int:
    return int(board.dma_memory.read_items(address, 8, length // 8, False)[0])


def test_the_dma_reads_sram_not_the_caches_and_its_writes_wait_for_the_caches_to_let_go():
    board = make_board(build_elf(PROGRAM))
    buffer = symbol(board, "buffer")
    go_to(board, "step1")
    assert board.caches[0].dirty(buffer)
    assert board.memory.read(buffer, 8) == (0x1122334455667788).to_bytes(8, "little")   # what the hart sees
    assert dma_read(board, buffer) == 0                                                # SRAM: before the store
    assert dma_read(board, buffer - SRAM_BASE + SRAM_UNCACHED_BASE) == 0                # either view, the same SRAM
    assert any("the DMA read" in line and "not yet written back" in line for line in board.warnings)
    go_to(board, "step2", then="after1")
    assert not board.caches[0].holds(buffer)
    assert dma_read(board, buffer) == 0x1122334455667788                               # FENCE.I wrote it back
    go_to(board, "step3", then="after2")
    board.dma_memory.write_items(buffer + 8, 8, np.array([0x99], dtype=np.uint64), False, "DMAC channel 1")
    assert any("DMAC channel 1 wrote" in line for line in board.warnings)
    go_to(board, "step4", then="after3")
    assert reg(board, "s1") == 0 and reg(board, "s2") == 0 and reg(board, "s3") == 0x99
    board.dma_memory.write_items(buffer + 24, 8, np.array([0x77], dtype=np.uint64), False, "DMAC channel 1")
    assert dma_read(board, buffer + 24) == 0x77
    go_to(board, "done", then="after4")
    # the hart's line, written back whole, holds its zeros where the DMA had written
    assert reg(board, "s4") == 0 and dma_read(board, buffer + 24) == 0
    assert dma_read(board, buffer + 16) == 0x0A0B0C0D


def test_without_the_caches_the_dma_sees_what_the_harts_see():
    board = make_board(build_elf(PROGRAM), timing="rocket-nocache")
    assert board.dma_memory is None and board.dmac.memory is board.memory


def test_a_chip_reset_loses_what_the_caches_held():
    board = make_board(build_elf(PROGRAM))
    buffer = symbol(board, "buffer")
    go_to(board, "step1")
    before = bytes(board.dma_memory.sram[0x600000:0x600008]) if board.dma_memory.shadowed[0x600000 // 64] else None
    assert before is not None and before != (0x1122334455667788).to_bytes(8, "little")
    board.reset_chip("soft", board.time)
    assert board.memory.read(0x80600000, 8) == before      # the store never reached SRAM
    assert not board.dma_memory.shadowed.any() and not board.caches[0].holds(buffer)
