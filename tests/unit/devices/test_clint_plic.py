"""CLINT (msip, mtimecmp, mtime at CPU clock / 50) and PLIC (priorities, threshold,
enables, claim/complete gateways, an M-mode and an S-mode context per hart): facts sheet section 1."""
from __future__ import annotations

import pytest

from emulator.devices import clint as c
from emulator.devices import plic as p
from emulator.errors import UnmodelledAccess
from emulator.cpu.riscv import IRQ_MEI, IRQ_MSI, IRQ_MTI, IRQ_SEI
from emulator.vtime import PS_PER_MS, PS_PER_S, PS_PER_US, cycles_time
from k210_fixtures import board, idle_elf  # noqa: F401

CPU_HZ = 26_000_000
US, MS, S = PS_PER_US, PS_PER_MS, PS_PER_S


# --- CLINT -------------------------------------------------------------------------------

def test_msip_per_hart_bit_zero_only(board):
    cl = board.clint
    cl.write(c.MSIP + 4, 4, 1, 0)
    assert cl.msip(1) and not cl.msip(0)
    assert board.mip(1, 0) >> IRQ_MSI & 1
    assert not board.mip(0, 0) >> IRQ_MSI & 1
    assert cl.read(c.MSIP + 4, 4, 0) == 1
    cl.write(c.MSIP + 4, 4, 0xFFFF_FFFE, 0)           # only bit 0 exists
    assert not cl.msip(1)
    assert cl.read(c.MSIP + 4, 4, 0) == 0


def test_mtime_ticks_at_cpu_clock_over_50(board):
    cl = board.clint
    assert cl.read(c.MTIME, 8, 0) == 0
    assert cl.read(c.MTIME, 8, MS) == 520           # 26 MHz / 50 * 1 ms
    assert cl.read(c.MTIME, 8, S // 2) == 260_000
    ten_ticks = cycles_time(10 * 50, CPU_HZ)                # when the 500th CPU clock has passed
    assert cl.read(c.MTIME, 8, ten_ticks - 1) == 9
    assert cl.read(c.MTIME, 8, ten_ticks) == 10


def test_mtime_follows_a_cpu_clock_change(board):
    """After ACLK moves to PLL0 (403 MHz) mtime counts 403e6 / 50 per second."""
    s = board.sysctl
    s.write(0x08, 4, 30 << 4 | 1 << 20 | 1 << 21 | 1 << 25, 0)
    s.write(0x08, 4, 30 << 4 | 1 << 21 | 1 << 25, US)
    t_switch = MS
    before = board.clint.read(c.MTIME, 8, t_switch)
    s.write(0x20, 4, 1, t_switch)
    assert board.clint.read(c.MTIME, 8, t_switch + MS) == before + 8060


def test_mtime_can_be_written(board):
    cl = board.clint
    cl.write(c.MTIME, 8, 1000, MS)
    assert cl.read(c.MTIME, 8, MS) == 1000
    assert cl.read(c.MTIME, 8, 2 * MS) == 1520


def test_mtime_halves(board):
    cl = board.clint
    cl.write(c.MTIME, 8, 0x1_0000_0000 + 5, 0)
    assert cl.read(c.MTIME, 4, 0) == 5
    assert cl.read(c.MTIME + 4, 4, 0) == 1
    # a 32-bit write of the low half keeps the running high half
    cl.write(c.MTIME, 4, 7, MS)
    assert cl.read(c.MTIME, 8, MS) == 0x1_0000_0007
    cl.write(c.MTIME + 4, 4, 2, MS)
    assert cl.read(c.MTIME, 8, MS) == 0x2_0000_0007


def test_mtimecmp_64_bit_and_32_bit_halves(board):
    cl = board.clint
    assert cl.read(c.MTIMECMP, 8, 0) == c.ALL_ONES       # no timer interrupt after reset
    cl.write(c.MTIMECMP + 8, 8, 0x1234_5678_9ABC_DEF0, 0)
    assert cl.read(c.MTIMECMP + 8, 8, 0) == 0x1234_5678_9ABC_DEF0
    assert cl.read(c.MTIMECMP + 8, 4, 0) == 0x9ABC_DEF0
    assert cl.read(c.MTIMECMP + 12, 4, 0) == 0x1234_5678
    # the SDK-safe 32-bit sequence: high = all ones, low, high
    cl.write(c.MTIMECMP + 4, 4, 0xFFFF_FFFF, 0)
    cl.write(c.MTIMECMP, 4, 0x0000_0200, 0)
    cl.write(c.MTIMECMP + 4, 4, 0x0000_0001, 0)
    assert cl.read(c.MTIMECMP, 8, 0) == 0x1_0000_0200
    assert cl.read(c.MTIMECMP + 8, 8, 0) == 0x1234_5678_9ABC_DEF0     # hart 1's untouched


def test_timer_pending_when_mtime_reaches_mtimecmp(board):
    cl = board.clint
    cl.write(c.MTIMECMP, 8, 520, 0)
    assert not cl.timer_pending(0, MS - 1)                 # a picosecond before mtime reaches 520
    assert cl.timer_pending(0, MS)
    assert not cl.timer_pending(1, S)
    assert cl.next_event_time(0) == MS
    assert board.mip(0, 2 * MS) >> IRQ_MTI & 1
    cl.write(c.MTIMECMP, 8, c.ALL_ONES, 2 * MS)         # acknowledge by moving mtimecmp
    assert not cl.timer_pending(0, 2 * MS)
    assert cl.next_event_time(2 * MS) is None


def test_clint_unknown_offset(board):
    with pytest.raises(UnmodelledAccess):
        board.clint.read(0x8, 4, 0)                      # no msip for a third hart
    with pytest.raises(UnmodelledAccess):
        board.clint.read(0x4010, 8, 0)


# --- PLIC --------------------------------------------------------------------------------

class Lines:
    """Stand-in for the board's interrupt sources: a set of high lines."""

    def __init__(self, plic) -> None:
        self.high: set[int] = set()
        plic.high_sources = lambda: sorted(self.high)


def enable(plic, context, *sources, now=0):
    words = [0] * p.WORDS
    for s in sources:
        words[s // 32] |= 1 << (s % 32)
    for w, value in enumerate(words):
        plic.write(p.ENABLE + p.ENABLE_STRIDE * context + 4 * w, 4, value, now)


def priority(plic, source, value, now=0):
    plic.write(p.PRIORITY + 4 * source, 4, value, now)


def claim(plic, context, now=0) -> int:
    return plic.read(p.CLAIM + p.CONTEXT_STRIDE * context, 4, now)


def complete(plic, context, source, now=0):
    plic.write(p.CLAIM + p.CONTEXT_STRIDE * context, 4, source, now)


def threshold(plic, context, value, now=0):
    plic.write(p.THRESHOLD + p.CONTEXT_STRIDE * context, 4, value, now)


@pytest.fixture
def plic(board):
    lines = Lines(board.plic)
    board.plic.lines = lines
    return board.plic


def test_priority_registers_hold_three_bits(plic):
    priority(plic, 1, 0xFF)
    assert plic.read(p.PRIORITY + 4, 4, 0) == 7
    priority(plic, 65, 3)
    assert plic.read(p.PRIORITY + 4 * 65, 4, 0) == 3


def test_claim_returns_highest_priority_then_lowest_id(plic):
    plic.lines.high |= {2, 27, 33, 40}
    for s, prio in ((2, 3), (27, 5), (33, 5), (40, 1)):
        priority(plic, s, prio)
    enable(plic, 0, 2, 27, 33, 40)
    assert plic.read(p.PENDING, 4, 0) == 1 << 2 | 1 << 27
    assert plic.read(p.PENDING + 4, 4, 0) == 1 << 1 | 1 << 8
    assert claim(plic, 0) == 27                   # 27 and 33 tie at 5: lowest id
    assert claim(plic, 0) == 33
    assert claim(plic, 0) == 2
    assert claim(plic, 0) == 40
    assert claim(plic, 0) == 0                    # nothing left


def test_claim_clears_pending_and_a_high_line_pends_again_only_after_complete(plic):
    plic.lines.high.add(33)
    priority(plic, 33, 1)
    enable(plic, 0, 33)
    assert plic.external_pending(0)
    assert claim(plic, 0) == 33
    assert plic.read(p.PENDING + 4, 4, 0) == 0    # claim cleared the pending bit
    assert not plic.external_pending(0)           # line still high, but being served
    assert claim(plic, 0) == 0
    complete(plic, 0, 33)
    assert plic.read(p.PENDING + 4, 4, 0) == 1 << 1
    assert plic.external_pending(0)
    assert claim(plic, 0) == 33
    plic.lines.high.clear()                       # device quiet before complete
    complete(plic, 0, 33)
    assert not plic.external_pending(0)
    assert claim(plic, 0) == 0


def test_pending_is_latched_even_if_the_line_drops(plic):
    plic.lines.high.add(2)
    priority(plic, 2, 1)
    enable(plic, 0, 2)
    plic.sample()
    plic.lines.high.clear()
    assert claim(plic, 0) == 2


def test_threshold_masks_priorities_at_or_below_it(plic):
    plic.lines.high |= {1, 2}
    priority(plic, 1, 2)
    priority(plic, 2, 4)
    enable(plic, 0, 1, 2)
    threshold(plic, 0, 4)
    assert not plic.external_pending(0)
    assert claim(plic, 0) == 0
    threshold(plic, 0, 3)
    assert claim(plic, 0) == 2
    assert claim(plic, 0) == 0                    # source 1 (priority 2) stays masked
    threshold(plic, 0, 1)
    assert claim(plic, 0) == 1


def test_priority_zero_never_interrupts(plic):
    plic.lines.high.add(5)
    enable(plic, 0, 5)
    assert not plic.external_pending(0)
    assert claim(plic, 0) == 0


def test_disabled_sources_are_not_claimed(plic):
    plic.lines.high |= {3, 34}
    priority(plic, 3, 7)
    priority(plic, 34, 1)
    enable(plic, 0, 34)
    assert claim(plic, 0) == 34
    assert claim(plic, 0) == 0
    enable(plic, 0, 3, 34)
    assert claim(plic, 0) == 3


def test_contexts_belong_to_harts_m_mode_first(plic, board):
    """Context 2h is hart h's MEIP, 2h + 1 its SEIP (SDK plic.h: 0x100 of enables and 0x2000 of
    threshold/claim per core; Linux's K210 device tree since "fix broken IRQs on hart1")."""
    assert (p.m_context(0), p.s_context(0), p.m_context(1), p.s_context(1)) == (0, 1, 2, 3)
    plic.lines.high |= {1, 2}
    priority(plic, 1, 1)
    priority(plic, 2, 1)
    enable(plic, 2, 2)                            # hart 1's M-mode context takes source 2
    assert not board.mip(0, 0) & (1 << IRQ_MEI | 1 << IRQ_SEI)
    assert board.mip(1, 0) >> IRQ_MEI & 1
    assert not board.mip(1, 0) >> IRQ_SEI & 1
    enable(plic, 0, 1)
    assert board.mip(0, 0) >> IRQ_MEI & 1
    assert claim(plic, 2) == 2
    assert claim(plic, 0) == 1
    threshold(plic, 2, 7)
    assert plic.read(p.THRESHOLD, 4, 0) == 0      # per-context threshold
    complete(plic, 2, 2)
    assert not plic.external_pending(2)           # hart 1's threshold masks it now
    # the SDK's addresses for core 1: enables at 0x2000 + 0x100, threshold at 0x200000 + 0x2000
    assert plic.read(0x2000 + 0x100, 4, 0) == 1 << 2
    assert plic.read(0x20_0000 + 0x2000, 4, 0) == 7


@pytest.mark.parametrize("hart", [0, 1])
def test_s_mode_context_raises_seip_not_meip(plic, board, hart):
    plic.lines.high.add(33)
    priority(plic, 33, 1)
    enable(plic, p.s_context(hart), 33)
    assert board.mip(hart, 0) >> IRQ_SEI & 1
    assert not board.mip(hart, 0) >> IRQ_MEI & 1
    assert not board.mip(1 - hart, 0) & (1 << IRQ_MEI | 1 << IRQ_SEI)
    assert claim(plic, p.m_context(hart)) == 0    # not enabled in the M-mode context
    assert claim(plic, p.s_context(hart)) == 33
    assert not board.mip(hart, 0) >> IRQ_SEI & 1


def test_board_sources_reach_the_plic(board):
    """GPIOHS line 0 rising edge with rise_ie -> PLIC source 34 -> MEIP of hart 0."""
    from emulator.devices import gpiohs as g
    gp = board.gpiohs
    priority(board.plic, 34, 1)
    enable(board.plic, 0, 34)
    gp.write(g.INPUT_EN, 4, 1, 0)
    gp.write(g.OUTPUT_EN, 4, 1, 0)
    gp.write(g.RISE_IE, 4, 1, 0)
    assert not board.mip(0, 0) >> IRQ_MEI & 1
    gp.write(g.OUTPUT_VAL, 4, 1, US)
    assert board.mip(0, US) >> IRQ_MEI & 1
    assert claim(board.plic, 0, US) == 34
    gp.write(g.RISE_IP, 4, 1, 2 * US)             # acknowledge at the device
    complete(board.plic, 0, 34, 2 * US)
    assert not board.mip(0, 2 * US) >> IRQ_MEI & 1


def test_plic_unknown_offset(board):
    board.plic.write(0x0, 4, 5, 0)                # source 0's priority is there and stays 0
    assert board.plic.read(0x0, 4, 0) == 0
    with pytest.raises(UnmodelledAccess):
        board.plic.read(p.THRESHOLD + 4 * p.CONTEXT_STRIDE, 4, 0)     # no fifth context
    with pytest.raises(UnmodelledAccess, match="read-only"):
        board.plic.write(p.PENDING, 4, 1, 0)
