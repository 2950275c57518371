"""TIMER0-2, DesignWare APB timers (devices/timer.py): counts as the Kendryte SDK's timer.c and
pwm.c program them, the clock SYSCTL gives them, interrupts on PLIC 14-19, PWM toggle outputs on
the pads FPIOA routes them to."""
from __future__ import annotations

import pytest

from emulator.devices import timer as tm
from emulator.devices.fpioa import FUNC_TIMER0_TOGGLE1
from emulator.devices.plic import SOURCE_TIMER0A
from emulator.vtime import PS_PER_MS, PS_PER_US, cycles_time
from k210_fixtures import idle_elf, make_board, program, reg, run_to_done  # noqa: F401

TIMER_HZ = 26_000_000 // 2       # a cold board: IN0 / ((clk_th2 byte + 1) x 2)
US, MS = PS_PER_US, PS_PER_MS


@pytest.fixture
def board(idle_elf):
    return make_board(idle_elf)


def channel(offset: int, n: int) -> int:
    return tm.channel_register(n, offset)


def start(timer, n: int, load: int, control: int, now: int = 0, load2: int | None = None) -> None:
    """timer_set_interval, then timer_set_enable (or pwm_set_enable's control word)."""
    timer.write(channel(tm.LOAD_COUNT, n), 4, load, now)
    if load2 is not None:
        timer.write(tm.LOAD_COUNT2 + 4 * n, 4, load2, now)
    timer.write(channel(tm.CONTROL, n), 4, control, now)


def test_the_timer_clock_is_sysctls(board):
    assert board.sysctl.timer_hz(0) == TIMER_HZ
    board.sysctl.write(0x40, 4, 3 << 8, 0)                         # clk_th2: timer1's threshold 3
    assert board.sysctl.timer_hz(1) == 26_000_000 // 8
    board.sysctl.write(0x20, 4, 1 << (13 + 2), 0)                   # clk_sel0: timer2 from PLL0
    assert board.sysctl.timer_hz(2) == board.sysctl.pll_hz(0x08) // 2


def test_user_mode_counts_down_interrupts_and_reloads(board):
    timer = board.timers[0]
    load = 13_000                                                  # 1 ms at 13 MHz
    start(timer, 1, load, tm.CR_ENABLE | tm.CR_USER_MODE)
    assert timer.read(channel(tm.CURRENT_VALUE, 1), 4, 250 * US) == load - 3250
    assert timer.next_event_time(0) == MS
    assert timer.read(tm.BLOCK_INTR_STAT, 4, MS - 1) == 0         # a picosecond before the end
    assert timer.read(tm.BLOCK_INTR_STAT, 4, MS) == 0b10
    assert timer.read(channel(tm.INTR_STAT, 1), 4, MS) == 1
    board.time = MS
    assert SOURCE_TIMER0A in board._high_sources()                # channels 0-1: TIMER0A, source 14
    assert timer.read(channel(tm.CURRENT_VALUE, 1), 4, 1500 * US) == load - 6500   # reloaded at 1 ms
    timer.read(channel(tm.EOI, 1), 4, 1500 * US)                   # reading eoi clears it
    assert timer.read(tm.RAW_INTR_STAT, 4, 1500 * US) == 0
    assert timer.next_event_time(1500 * US) == 2 * MS
    assert timer.read(tm.RAW_INTR_STAT, 4, 2 * MS - 1) == 0
    assert timer.read(tm.RAW_INTR_STAT, 4, 2 * MS) == 0b10


def test_channels_2_and_3_raise_the_second_line(board):
    timer = board.timers[2]
    start(timer, 3, 130, tm.CR_ENABLE | tm.CR_USER_MODE)
    board.time = 10 * US                                           # 130 ticks at 13 MHz
    assert timer.irq_lines() == 0b10
    assert SOURCE_TIMER0A + 2 * 2 + 1 in board._high_sources()    # TIMER2B, source 19


def test_a_masked_channel_sets_only_its_raw_status_and_free_running_reloads_all_ones(board):
    timer = board.timers[1]
    start(timer, 0, 1300, tm.CR_ENABLE | tm.CR_INTERRUPT_MASK)   # free-running
    assert timer.next_event_time(0) is None                        # nothing outside a read
    t = 100 * US                                                   # 1300 ticks at 13 MHz
    assert timer.read(tm.RAW_INTR_STAT, 4, t - 1) == 0
    assert timer.read(tm.RAW_INTR_STAT, 4, t) == 1 and timer.read(tm.BLOCK_INTR_STAT, 4, t) == 0
    assert timer.read(channel(tm.CURRENT_VALUE, 0), 4, t + cycles_time(1, TIMER_HZ)) == 0xFFFF_FFFF - 1
    timer.read(tm.BLOCK_EOI, 4, t)                                 # the block's eoi clears every channel
    assert timer.read(tm.RAW_INTR_STAT, 4, t) == 0


def test_disabling_keeps_the_status_until_eoi(board):
    timer = board.timers[0]
    start(timer, 0, 13, tm.CR_ENABLE | tm.CR_USER_MODE)
    t = US                                                         # 13 ticks at 13 MHz
    timer.write(channel(tm.CONTROL, 0), 4, tm.CR_INTERRUPT_MASK, t)    # the SDK's single shot: off
    assert timer.read(tm.RAW_INTR_STAT, 4, 2 * t) == 1
    assert timer.read(channel(tm.CURRENT_VALUE, 0), 4, 2 * t) == 0
    timer.read(channel(tm.EOI, 0), 4, 2 * t)
    assert timer.read(tm.RAW_INTR_STAT, 4, 3 * t) == 0


def test_pwm_toggles_its_pad_low_for_load_count_high_for_load_count2(board):
    """pwm_set_frequency(1 kHz, duty 0.25) at 13 MHz: load_count 9750 (low), load_count2 3250 (high);
    pwm_set_enable's control word; the toggle output routed to pad 24."""
    board.fpioa.write(4 * 24, 4, FUNC_TIMER0_TOGGLE1 + 4 * 1 + 2 | 1 << 12, 0)     # TIMER1_TOGGLE3
    timer = board.timers[1]
    start(timer, 2, 9750, tm.CR_INTERRUPT_MASK | tm.CR_PWM | tm.CR_USER_MODE | tm.CR_ENABLE, load2=3250)
    assert timer.next_event_time(0) is None              # edges need no turn of their own
    board.advance_devices(3 * MS)                          # told with their own times, 3 ms's included
    edges = [(at, level) for at, pad, level in board.pad_changes if pad == 24]
    assert edges == [(0, 0), (750 * US, 1), (1000 * US, 0), (1750 * US, 1), (2000 * US, 0), (2750 * US, 1),
                     (3000 * US, 0)]
    assert board.wiring.pad_level(24, 2900 * US) == 1


def test_a_program_takes_timer_interrupts_through_the_plic():
    """TIMER0 channel 0 every 100 us, user mode; the handler claims source 14, reads the channel's
    eoi, completes and counts; five interrupts, then the program stops the timer."""
    board = make_board(program("""
        li      s0, 0x50440000
        lw      t0, 0x28(s0)
        ori     t0, t0, 1 << 3
        sw      t0, 0x28(s0)                 # APB0
        lw      t0, 0x2C(s0)
        li      t1, 1 << 21
        or      t0, t0, t1
        sw      t0, 0x2C(s0)                 # TIMER0's clock
        la      t0, handler
        csrw    mtvec, t0
        li      s1, 0x0C000000
        li      t0, 1
        sw      t0, 14 * 4(s1)               # priority[14]
        li      t1, 0x0C002000
        li      t0, 1 << 14
        sw      t0, 0(t1)                    # context 0 enables 14
        li      s2, 0x502D0000
        li      t0, 1300
        sw      t0, 0x00(s2)                 # load_count: 100 us at 13 MHz
        li      t0, 3
        sw      t0, 0x08(s2)                 # user mode, enabled, unmasked
        li      t0, 1 << 11
        csrw    mie, t0
        csrsi   mstatus, 8
        li      s3, 0
    1:  li      t0, 5
        blt     s3, t0, 1b
        li      t0, 4
        sw      t0, 0x08(s2)                 # off
        csrr    s4, mcycle
        j       done
        .balign 4
    handler:
        li      t1, 0x0C200004
        lw      t2, 0(t1)                    # claim
        lw      t3, 0x0C(s2)                 # channel 0's eoi
        sw      t2, 0(t1)                    # complete
        addi    s3, s3, 1
        mv      s5, t2
        mret
    """), quantum=500)
    run_to_done(board, max_time_s=0.01)
    assert reg(board, "s3") == 5 and reg(board, "s5") == 14
    # the fifth interrupt came at 500 us after the timer started
    assert 500e-6 < reg(board, "s4") / 26e6 < 520e-6
