"""The L1 caches (emulator/cpu/caches.py, _caches.h) on small firmware: what a loop over an array costs
in mcycle, as the firmware reads it, against what the caches' rules and figures say it costs.

The expected misses come from ReferenceCache below, the rules written again from their sources
(rocket-chip 2017: 64 sets of 8 ways, the victim named by Chisel's LFSR16 whether or not a way is
empty, a load's line read-only and a store to it a second miss, dirty victims written back), so a
change to either side shows here. The figures each miss costs are caches.py's, with their sources
there."""
from __future__ import annotations

import pytest

from emulator.cpu.caches import LINE_BYTES, ROCKET_L1
from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE
from emulator.cpu.timing import REDIRECT_BUBBLE, TIMING_ROCKET, TIMING_ROCKET_NOCACHE
from emulator.memory_map import SRAM_BASE, SRAM_UNCACHED_BASE
from both_engines import run_on_both, state
from k210_fixtures import build_elf, make_board, program, reg, run_to_done, run_until, symbol

SETS, WAYS = 64, 8
CACHE_BYTES = SETS * WAYS * LINE_BYTES


class ReferenceCache:
    """The data cache's rules, for predicting misses: (address >> 6) + 1 per way, a writable flag, the
    LFSR moved on at every grant."""

    def __init__(self) -> None:
        self.lines = [[0] * WAYS for _ in range(SETS)]
        self.writable = [[False] * WAYS for _ in range(SETS)]
        self.lfsr = 1
        self.misses = self.write_backs = 0

    def _step(self) -> None:
        v = self.lfsr
        self.lfsr = (v >> 1) | (((v ^ (v >> 2) ^ (v >> 3) ^ (v >> 5)) & 1) << 15)

    def access(self, address: int, store: bool) -> None:
        line, index = (address >> 6) + 1, (address >> 6) % SETS
        ways = self.lines[index]
        if line in ways:
            way = ways.index(line)
            if store and not self.writable[index][way]:
                self.misses += 1                 # write permission: a second grant
                self._step()
                self.writable[index][way] = True
            return
        self.misses += 1
        way = self.lfsr & (WAYS - 1)
        self._step()
        if ways[way] and self.writable[index][way]:
            self.write_backs += 1
        ways[way], self.writable[index][way] = line, store

    def cycles(self) -> int:
        return self.misses * ROCKET_L1.data_fill + self.write_backs * ROCKET_L1.write_back


# walk(a0 = first address, a1 = lines, a2 = 1 to store after each load): one access per line. Each
# call sits in a line of code of its own, and walk's line is fetched before the first call (the code
# after it, in the same line, runs first), so between two mcycle reads no fetch misses. All of it in
# 4-byte instructions, 4-aligned: no jump or branch leads to one 2 mod 4, which waits a cycle for its
# second half (the frontend's fetch, timing.py; not the caches').
WALK = """
    .option norvc
    j       start
    .balign 64
walk:
1:  ld      t0, 0(a0)
    beqz    a2, 2f
    sd      t0, 0(a0)
2:  addi    a0, a0, 64
    addi    a1, a1, -1
    bnez    a1, 1b
    ret
start:
{body}
"""


def measured(calls: list[tuple[int, int, int]]) -> str:
    """Calls of walk, each between two mcycle reads into s2k and s2k+1 (s2..s11: five calls at most)."""
    lines = []
    for n, (start, count, store) in enumerate(calls):
        lines += ["    .balign 64", f"    li      a0, {start}", f"    li      a1, {count}", f"    li      a2, {store}",
                  f"    csrr    s{2 + 2 * n}, mcycle", "    call    walk", f"    csrr    s{3 + 2 * n}, mcycle"]
    return WALK.format(body="\n".join(lines))


ARRAY = f".balign 4096\narray: .zero {3 * CACHE_BYTES}"


def run_walks(calls: list[tuple[int, int, int]], timing: str = TIMING_ROCKET, engine: str = ENGINE_FAST) -> list[int]:
    """The cycles of each call, as the firmware read them."""
    board = make_board(program(measured(calls), data=ARRAY), timing=timing, engine=engine)
    run_to_done(board, max_time_s=0.5)
    return [reg(board, f"s{3 + 2 * n}") - reg(board, f"s{2 + 2 * n}") for n in range(len(calls))]


def cache_cycles(calls: list[tuple[int, int, int]], engine: str = ENGINE_FAST) -> list[int]:
    """What the caches add to each call: its cycles against the same call's without them (the
    pipeline and the branch predictor see the same instructions either way)."""
    return [cached - plain for cached, plain in
            zip(run_walks(calls, engine=engine), run_walks(calls, TIMING_ROCKET_NOCACHE, engine), strict=True)]


def array_base() -> int:
    board = make_board(program(measured([]), data=ARRAY))
    return symbol(board, "array")


def test_a_line_per_set_misses_once():
    """4 KiB, one line in each set: the first walk misses on every line (the refill and the replay,
    caches.py's data_fill), the second on none, whatever the victims."""
    base = array_base()
    assert cache_cycles([(base, 64, 0), (base, 64, 0)]) == [64 * ROCKET_L1.data_fill, 0]


def test_an_array_twice_the_cache_costs_what_the_rules_say():
    """64 KiB walked twice: the second walk misses too, on the lines the first walk's random victims
    threw out (half or more: 16 lines for each set's 8 ways)."""
    base = array_base()
    model = ReferenceCache()
    expected = []
    for _ in range(2):
        before = model.cycles()
        for address in range(base, base + 2 * CACHE_BYTES, LINE_BYTES):
            model.access(address, store=False)
        expected.append(model.cycles() - before)
    assert expected[0] == 1024 * ROCKET_L1.data_fill
    assert 512 * ROCKET_L1.data_fill <= expected[1] < expected[0]
    assert cache_cycles([(base, 1024, 0), (base, 1024, 0)]) == expected


def test_a_store_to_a_line_only_read_misses_again_and_dirty_victims_are_written_back():
    """A load takes its line read-only (TileLink's Branch), so storing to it misses once more for
    write permission; loading and storing across twice the cache writes dirty victims back."""
    base = array_base()
    calls = [(base, 64, 0), (base, 64, 1), (base, 64, 1), (base + CACHE_BYTES, 1024, 1), (base + CACHE_BYTES, 1024, 1)]
    model = ReferenceCache()
    expected = []
    for start, count, store in calls:
        before = model.cycles()
        for address in range(start, start + count * LINE_BYTES, LINE_BYTES):
            model.access(address, store=False)
            if store:
                model.access(address, store=True)
        expected.append(model.cycles() - before)
    assert expected[1] == 64 * ROCKET_L1.data_fill and expected[2] == 0
    assert model.write_backs > 0
    assert cache_cycles(calls) == expected


def test_the_uncached_view_costs_a_round_trip_every_access():
    """The same 4 KiB through 0x4000_0000: no line is kept, each load is a bus round trip."""
    base = array_base() - SRAM_BASE + SRAM_UNCACHED_BASE
    assert cache_cycles([(base, 64, 0), (base, 64, 0)]) == [64 * ROCKET_L1.uncached] * 2


def test_both_engines_count_the_same_misses():
    base = array_base()
    calls = [(base, 1024, 1), (base, 1024, 0), (base + 4096, 64, 1)]
    assert run_walks(calls, engine=ENGINE_PRECISE) == run_walks(calls, engine=ENGINE_FAST)


SLED = """
    csrr    s2, mcycle
    call    sled
    csrr    s3, mcycle
    csrr    s4, mcycle
    call    sled
    csrr    s5, mcycle
    j       done
    .balign 4096
    .skip   2048
    .option push
    .option norvc
sled:
    .rept   511
    nop
    .endr
    ret
    .option pop
"""


@pytest.mark.parametrize("engine", [ENGINE_FAST, ENGINE_PRECISE])
def test_code_is_fetched_into_the_instruction_cache_once(engine):
    """2 KiB of code (32 lines, in 32 sets) run twice: the first run fetches every line (caches.py's
    fetch_fill each), the second none; the call's own line may be thrown out by the first run's
    victims and fetched again."""
    cycles = {}
    for timing in (TIMING_ROCKET, TIMING_ROCKET_NOCACHE):
        board = make_board(program(SLED), timing=timing, engine=engine)
        run_to_done(board, max_time_s=0.1)
        cycles[timing] = (reg(board, "s3") - reg(board, "s2"), reg(board, "s5") - reg(board, "s4"))
    cold, warm = cycles[TIMING_ROCKET]
    assert warm == cycles[TIMING_ROCKET_NOCACHE][1]
    misses = (cold - cycles[TIMING_ROCKET_NOCACHE][0]) / ROCKET_L1.fetch_fill
    assert misses in (32, 33)


# A 4-byte jump whose second half lies in the next line, a line nothing else of runs: line S holds the
# measured code and is fetched before the first mcycle read; the jump sits at byte 62 of line A (2 mod 4:
# after the jump to it, the frontend's fetch waits for its second half too, REDIRECT_BUBBLE).
STRADDLE = """
    j       start
    .balign 64
start:
    nop
    csrr    s2, mcycle
    j       straddler
back:
    csrr    s3, mcycle
    j       9f
    .balign 64
    .option push
    .option norvc
    .skip   62
straddler:
    j       back
    .option pop
9:
"""


@pytest.mark.parametrize("engine", [ENGINE_FAST, ENGINE_PRECISE])
def test_an_instruction_across_two_lines_waits_for_both(engine):
    """The jump cannot issue before both of its halves are in: it pays for line A and line B, though
    nothing else of B runs (before: B's fill was charged to the next instruction, here never)."""
    cycles = {}
    for timing in (TIMING_ROCKET, TIMING_ROCKET_NOCACHE):
        board = make_board(program(STRADDLE), timing=timing, engine=engine)
        run_to_done(board, max_time_s=0.1)
        cycles[timing] = reg(board, "s3") - reg(board, "s2")
    assert cycles[TIMING_ROCKET] - cycles[TIMING_ROCKET_NOCACHE] == 2 * ROCKET_L1.fetch_fill + REDIRECT_BUBBLE


def test_the_figures_come_from_the_bus_and_the_pipeline():
    """caches.py's figures from their parts: 8 beats of 8 bytes a line, the round trip, Rocket's
    replay and the instruction cache's latency."""
    assert ROCKET_L1.data_fill == 6 + 8 + 4 and ROCKET_L1.write_back == 6 + 8
    assert ROCKET_L1.fetch_fill == 6 + 8 + 2 and ROCKET_L1.uncached == 6 + 1 + 4


COHERENCE = """
    .option norelax
    .globl _start
_start:
    csrr    t0, mhartid
    la      s0, shared
    bnez    t0, hart1
    li      t1, 7
    sd      t1, 0(s0)               # hart 0 holds the line dirty
    li      t1, 0x02000004          # CLINT msip[1]: wake hart 1
    li      t2, 1
    sw      t2, 0(t1)
done:
    j       done
hart1:
    li      t0, 8                   # MSIE
    csrw    mie, t0
    wfi
    j       1f
    .balign 64                      # what is measured, in one line of code: no fetch misses
1:  csrr    s2, mcycle
    ld      t1, 0(s0)               # a miss that waits for hart 0's write-back
    csrr    s3, mcycle
    ld      t1, 0(s0)               # a hit
    csrr    s4, mcycle
    sd      t1, 0(s0)               # write permission: hart 0's copy, clean now, is dropped
    csrr    s5, mcycle
    sd      t1, 0(s0)
    csrr    s6, mcycle
hart1_done:
    j       hart1_done
    .data
    .balign 64
shared: .dword 0
"""


def test_the_harts_caches_are_coherent():
    """A line hart 0 wrote: hart 1's load waits for hart 0's write-back (the hub probes hart 0's cache),
    and hart 1's store then needs write permission, which drops hart 0's copy."""
    spans = {}
    for timing in (TIMING_ROCKET, TIMING_ROCKET_NOCACHE):
        board = make_board(build_elf(COHERENCE), timing=timing)
        run_until(board, lambda b: b.harts[1].pc == symbol(b, "hart1_done"), max_time_s=0.01)
        spans[timing] = [reg(board, f"s{n + 1}", hart=1) - reg(board, f"s{n}", hart=1) for n in range(2, 6)]
        if timing == TIMING_ROCKET:
            shared = symbol(board, "shared")
            assert board.caches[1].dirty(shared) and not board.caches[0].holds(shared)
    added = [cached - plain for cached, plain in zip(spans[TIMING_ROCKET], spans[TIMING_ROCKET_NOCACHE])]
    assert added == [ROCKET_L1.data_fill + ROCKET_L1.write_back, 0, ROCKET_L1.data_fill, 0]


MIXED = """
    la      s0, array
    li      t0, 5
    amoadd.w t1, t0, (s0)               # an AMO: write permission
    addi    s1, s0, 64
1:  lr.w    t2, (s1)                    # LR takes its line writable, so that SC hits
    addi    t2, t2, 1
    sc.w    t3, t2, (s1)
    bnez    t3, 1b
    c.ld    a0, 128(s0)                 # compressed
    c.sd    a0, 136(s0)
    .insn   i 0x0F, 1, x0, x0, 0        # FENCE.I: written back, both caches emptied
    li      t4, 0x40000000 - 0x80000000
    add     t4, s0, t4
    ld      a1, 64(t4)                  # the uncached view
    sd      a1, 200(t4)
    ld      a2, 64(s0)                  # fetched again after the flush
"""


def test_both_engines_charge_atomics_lr_sc_fence_i_and_the_uncached_view_alike():
    precise, fast = run_on_both(MIXED, data=ARRAY)
    assert state(precise) == state(fast)
    assert precise.harts[0].cycles == fast.harts[0].cycles
    assert [c.statistics() for c in precise.caches] == [c.statistics() for c in fast.caches]
    stats = fast.caches[0].statistics()
    assert stats.flushes == 1 and stats.uncached_accesses == 2


LR_SC = """
    la      s0, array
    csrr    s2, mcycle
1:  lr.d    t2, (s0)
    addi    t2, t2, 1
    sc.d    t3, t2, (s0)
    bnez    t3, 1b
    csrr    s3, mcycle
"""


def test_lr_acquires_its_line_writable_so_that_sc_hits():
    """rocket-chip's isWriteIntent counts LR: one miss for the pair, not a second for write permission."""
    cycles = {}
    for timing in (TIMING_ROCKET, TIMING_ROCKET_NOCACHE):
        board = make_board(program(LR_SC, data=ARRAY), timing=timing)
        run_to_done(board)
        cycles[timing] = reg(board, "s3") - reg(board, "s2")
    assert cycles[TIMING_ROCKET] - cycles[TIMING_ROCKET_NOCACHE] == ROCKET_L1.data_fill
