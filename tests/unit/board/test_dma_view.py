"""The DMA and the harts' data caches (emulator/board/dma_view.py, emulator/cpu/_caches.c): the DMAC's
accesses go through the coherence hub, which probes the caches. A DMA reads what a hart stored even in
a dirty line (written back first, the hart keeping it read-only), and a DMA write drops the hart's copy
(its next load misses and reads the DMA's bytes). docs/design/timing.md says which programs that ran on
Docks show it."""
from __future__ import annotations

import numpy as np

from emulator.cpu.caches import ROCKET_L1
from emulator.cpu.timing import TIMING_ROCKET, TIMING_ROCKET_NOCACHE
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
    ld      t1, 8(s0)               # the line's other half: a hit
    j       step1
    .balign 64                      # what is measured, in lines of code already fetched
step1:
    j       step1                   # (the test has the DMA read the buffer, then moves the hart on)
after1:
    csrr    s6, mcycle
    sd      t0, 16(s0)              # read-only since the DMA's read: write permission again
    csrr    s7, mcycle
    ld      s1, 24(s0)              # a hit
step2:
    j       step2                   # (the DMA writes the buffer)
after2:
    csrr    s8, mcycle
    ld      s2, 24(s0)              # the line left the cache: a miss, and the DMA's bytes
    csrr    s9, mcycle
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


def run(timing: str):
    board = make_board(build_elf(PROGRAM), timing=timing)
    buffer = symbol(board, "buffer")
    go_to(board, "step1")
    if board.caches is not None:
        assert board.caches[0].dirty(buffer)
    seen = board.dmac.memory.read_items(buffer, 8, 1, False)
    assert int(seen[0]) == 0x1122334455667788                      # the hart's store, though in its cache
    if board.caches is not None:
        assert board.caches[0].holds(buffer) and not board.caches[0].dirty(buffer)
    go_to(board, "step2", then="after1")
    board.dmac.memory.write_items(buffer + 24, 8, np.array([0x99], dtype=np.uint64), False, "DMAC channel 1")
    if board.caches is not None:
        assert not board.caches[0].holds(buffer)
    go_to(board, "done", then="after2")
    assert reg(board, "s1") == 0 and reg(board, "s2") == 0x99
    return board, reg(board, "s7") - reg(board, "s6"), reg(board, "s9") - reg(board, "s8")


def test_the_dma_sees_what_the_harts_stored_and_its_writes_drop_their_copies():
    cached, store, load = run(TIMING_ROCKET)
    plain, store_plain, load_plain = run(TIMING_ROCKET_NOCACHE)
    assert store - store_plain == ROCKET_L1.data_fill          # write permission again, after the DMA's probe
    assert load - load_plain == ROCKET_L1.data_fill            # fetched again, after the DMA's write
    # (the store after the read made the line dirty again: the write finds it so too)
    assert cached.dma_memory.write_backs == 2 and cached.dma_memory.invalidations == 1
    assert plain.dma_memory is None and plain.dmac.memory is plain.memory
