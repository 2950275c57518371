"""WDT0-1, DesignWare APB watchdogs (devices/wdt.py), and the chip reset they and SYSCTL's
soft_reset cause (Board.reset_chip): the harts start again at 0x8000_0000, the blocks as the mask
ROM leaves them, the program copied in again, reset_status saying why, the run going on."""
from __future__ import annotations

import pytest

from emulator.devices import sysctl as sc
from emulator.devices import wdt as w
from emulator.devices.plic import SOURCE_WDT0
from emulator.vtime import PS_PER_MS, cycles_time
from k210_fixtures import build_elf, idle_elf, make_board, reg, run_until  # noqa: F401

WDT_HZ = 26_000_000 // 2         # clk_th6 byte 0: IN0 / 2
TIMEOUT = cycles_time(1 << 16, WDT_HZ)   # TOP 0: 2^16 clocks, 5.04 ms
T15 = TIMEOUT * 3 // 2           # (TIMEOUT is even: these are exact)
T25 = TIMEOUT * 5 // 2
T26 = TIMEOUT * 26 // 10


@pytest.fixture
def board(idle_elf):
    return make_board(idle_elf)


def test_interrupt_first_then_a_reset_if_nobody_clears_it(board):
    wdt = board.watchdogs[0]
    assert board.sysctl.wdt_hz(0) == WDT_HZ
    wdt.write(w.CR, 4, w.CR_INTERRUPT_FIRST | w.CR_ENABLE, 0)
    assert wdt.next_event_time(0) == TIMEOUT
    wdt.advance(TIMEOUT)
    assert wdt.read(w.STAT, 4, TIMEOUT) == 1 and wdt.irq_line()
    board.time = TIMEOUT
    assert SOURCE_WDT0 in board._high_sources()
    assert board.scheduler.reset_requested is None
    wdt.advance(2 * TIMEOUT)                                   # not cleared: the chip resets
    assert board.scheduler.reset_requested == ("WDT0", cycles_time(2 << 16, WDT_HZ))   # counted from the start


def test_restarting_clears_and_eoi_clears_without_restarting(board):
    wdt = board.watchdogs[1]
    wdt.write(w.CR, 4, w.CR_INTERRUPT_FIRST | w.CR_ENABLE, 0)
    wdt.advance(TIMEOUT)
    wdt.write(w.CRR, 4, 0x12, TIMEOUT)                         # not the restart value: nothing
    assert wdt.read(w.STAT, 4, TIMEOUT) == 1
    wdt.write(w.CRR, 4, w.RESTART, T15)                        # fed: cleared, a whole timeout again
    assert wdt.read(w.STAT, 4, T15) == 0
    assert wdt.next_event_time(T15) == T25
    assert wdt.read(w.CCVR, 4, 2 * TIMEOUT) == pytest.approx((1 << 15), abs=2)
    wdt.advance(T25)
    wdt.read(w.EOI, 4, T26)                                    # cleared, the count goes on
    assert wdt.read(w.STAT, 4, T26) == 0
    assert wdt.next_event_time(T26) == T15 + cycles_time(2 << 16, WDT_HZ)   # counted from the restart


def test_once_enabled_only_a_reset_stops_it(board):
    """The SDK's wdt_stop clears cr bit 0: the DesignWare watchdog ignores that."""
    wdt = board.watchdogs[0]
    wdt.write(w.CR, 4, w.CR_ENABLE, 0)
    wdt.write(w.CR, 4, 0, PS_PER_MS)
    assert wdt.read(w.CR, 4, PS_PER_MS) & w.CR_ENABLE
    wdt.reset(2 * PS_PER_MS)
    assert not wdt.read(w.CR, 4, 2 * PS_PER_MS) & w.CR_ENABLE and wdt.next_event_time(2 * PS_PER_MS) is None


BOOTS = """
    .globl _start
_start:
    csrr    a0, mhartid
    bnez    a0, park
    li      s0, 0x80600000               # AI SRAM: the program is not there, so a reset keeps it
    la      t1, data_word
    lw      s2, 0(t1)                    # the program's own data as loaded (42)
    li      t2, 7
    sw      t2, 0(t1)                    # changed: a reset must bring 42 back
    lw      t0, 0(s0)
    li      t1, 0x600DB007
    beq     t0, t1, second               # booted before
    sw      t1, 0(s0)
    li      s1, 0x50440000
    lw      t0, 0x28(s1)
    ori     t0, t0, 1 << 4
    sw      t0, 0x28(s1)                 # APB1
    lw      t0, 0x2C(s1)
    li      t1, 1 << {gate}
    or      t0, t0, t1
    sw      t0, 0x2C(s1)                 # the watchdog's clock
{trigger}
1:  j       1b                           # nobody feeds it
second:
    li      s1, 0x50440000
    lw      s3, 0x60(s1)                 # reset_status
done:
    j       done
park:
    csrw    mie, zero
2:  wfi
    j       2b
    .data
    .balign 8
data_word: .word 42
"""


@pytest.mark.parametrize("trigger, cause", [
    ("    li      s4, 0x50400000\n    li      t0, 1\n    sw      t0, 0(s4)        # WDT0 on, reset mode", "WDT0"),
    ("    li      t0, 1\n    sw      t0, 0x30(s1)     # SYSCTL soft_reset", "soft"),
])
def test_a_reset_starts_the_program_again_with_the_cause_in_reset_status(trigger, cause):
    board = make_board(build_elf(BOOTS.replace("{trigger}", trigger).replace("{gate}", "24")),
                       cold=False, quantum=2000)
    run_until(board, lambda b: reg(b, "s3") != 0, max_time_s=0.05)
    assert int.from_bytes(board.memory.read(0x8060_0000, 4), "little") == 0x600DB007
    assert reg(board, "s2") == 42                               # the program copied in again
    assert reg(board, "s3") & sc.RESET_CAUSE_BITS[cause]
    assert [c for _, c in board.scheduler.resets] == [cause]
    if cause == "WDT0":
        assert board.scheduler.resets[0][0] == pytest.approx(TIMEOUT, rel=0.01)
    # as the ROM left it again: 390 MHz
    assert board.scheduler.cpu_hz() == 390_000_000
