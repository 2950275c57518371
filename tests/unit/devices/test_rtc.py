"""The RTC (devices/rtc.py) as the Kendryte SDK's rtc.c drives it: rtc_init (unprotected, counting
IN0's 26 MHz, count from 1, running), setting the time in setting mode, the calendar moving on a
second per initial_count cycles (minutes, days, months, leap years, the week day), tick and alarm
interrupts as pulses the PLIC's gateway latches (source 20)."""
from __future__ import annotations

import pytest

from emulator.devices import rtc as r
from emulator.devices.plic import SOURCE_RTC
from emulator.vtime import PS_PER_S, PS_PER_US, cycles_time
from k210_fixtures import idle_elf, make_board  # noqa: F401

S = PS_PER_S

SETTING, RUNNING = r.WRITE_ENABLE, r.READ_ENABLE
OPEN = 0xFF << 13 | 0xFF << 21 | r.INITIAL_COUNT_MASK | r.INTERRUPT_REGISTER_MASK   # rtc_protect_set(0)


@pytest.fixture
def rtc(idle_elf):
    board = make_board(idle_elf)
    return board, board.rtc


def init(rtc, now=0):
    """rtc_init, then rtc_timer_set(2024, 2, 28, 23, 59, 58) (a Wednesday)."""
    rtc.write(r.REGISTER_CTRL, 4, OPEN, now)
    rtc.write(r.REGISTER_CTRL, 4, OPEN | SETTING, now)
    rtc.write(r.INITIAL_COUNT, 4, r.CLOCK_HZ, now)
    rtc.write(r.CURRENT_COUNT, 4, 1, now)
    rtc.write(r.DATE, 4, 3 | 28 << 8 | 2 << 16 | 24 << 20, now)
    rtc.write(r.TIME, 4, 58 << 10 | 59 << 16 | 23 << 24, now)
    rtc.write(r.EXTENDED, 4, 20, now)
    rtc.write(r.REGISTER_CTRL, 4, OPEN | RUNNING, now)


def when(rtc, now):
    date, time = rtc.read(r.DATE, 4, now), rtc.read(r.TIME, 4, now)
    return (rtc.read(r.EXTENDED, 4, now) & 0x1F, date >> 20, date >> 16 & 0xF, date >> 8 & 0x1F, date & 7,
            time >> 24 & 0x1F, time >> 16 & 0x3F, time >> 10 & 0x3F)


def test_the_calendar_moves_on_a_second_per_initial_count_cycles(rtc):
    board, clock = rtc
    init(clock)
    assert when(clock, 0) == (20, 24, 2, 28, 3, 23, 59, 58)
    assert clock.read(r.CURRENT_COUNT, 4, S // 2) == 13_000_001
    assert when(clock, S - 1) == (20, 24, 2, 28, 3, 23, 59, 58)        # a picosecond before the second
    assert when(clock, S) == (20, 24, 2, 28, 3, 23, 59, 59)
    assert when(clock, 2 * S) == (20, 24, 2, 29, 4, 0, 0, 0)             # a leap year's 29 February
    assert clock.read(r.EXTENDED, 4, 5 * S // 2) & 0x20                  # leap year
    assert when(clock, (2 + 86400) * S) == (20, 24, 3, 1, 5, 0, 0, 0)


def test_paused_and_setting_the_calendar_stands_and_writes_need_setting_mode(rtc):
    board, clock = rtc
    init(clock)
    clock.write(r.REGISTER_CTRL, 4, OPEN, S // 2)                         # paused
    assert when(clock, 10 * S) == (20, 24, 2, 28, 3, 23, 59, 58)
    clock.write(r.TIME, 4, 0, 10 * S)                                     # not setting: ignored
    assert when(clock, 10 * S)[-1] == 58
    clock.write(r.REGISTER_CTRL, 4, OPEN | RUNNING, 10 * S)
    assert when(clock, 10 * S + S // 2 - 1) == (20, 24, 2, 28, 3, 23, 59, 58)
    assert when(clock, 10 * S + S // 2) == (20, 24, 2, 28, 3, 23, 59, 59)  # half a second was left


def test_tick_every_second_and_an_alarm_are_pulses_the_plic_latches(rtc):
    board, clock = rtc
    init(clock)
    clock.write(r.REGISTER_CTRL, 4, OPEN | SETTING, 0)
    clock.write(r.ALARM_TIME, 4, 0 << 10 | 0 << 16 | 0 << 24, 0)        # midnight
    clock.write(r.INTERRUPT_CTRL, 4, r.ALARM_ENABLE | (r.MASK_SECOND | r.MASK_MINUTE | r.MASK_HOUR) << 24, 0)
    clock.write(r.REGISTER_CTRL, 4, OPEN | RUNNING, 0)
    assert clock.next_event_time(0) == S
    clock.advance(S)                                                      # 23:59:59: no alarm
    assert SOURCE_RTC not in board.plic.pending
    start = clock.next_event_time(S)
    assert start == 2 * S
    clock.advance(start - 1)
    assert SOURCE_RTC not in board.plic.pending
    clock.advance(start)                                                  # midnight: the alarm's pulse
    assert SOURCE_RTC in board.plic.pending and not clock.irq_line()     # latched; no level to hold
    board.plic.write(4 * SOURCE_RTC, 4, 1, start)
    board.plic.write(0x2000, 4, 1 << SOURCE_RTC, start)
    assert board.plic.read(0x20_0004, 4, start + PS_PER_US) == SOURCE_RTC
    board.plic.write(0x20_0004, 4, SOURCE_RTC, start + PS_PER_US)        # complete
    assert SOURCE_RTC not in board.plic.pending
    clock.write(r.REGISTER_CTRL, 4, OPEN | SETTING, 3 * S)
    clock.write(r.INTERRUPT_CTRL, 4, r.TICK_ENABLE, 3 * S)                # every second
    clock.write(r.REGISTER_CTRL, 4, OPEN | RUNNING, 3 * S)
    for second in (4 * S, 5 * S):
        tick = clock.next_event_time(second - S // 2)
        assert tick == second
        board.plic.pending.discard(SOURCE_RTC)
        clock.advance(tick)
        assert SOURCE_RTC in board.plic.pending


def test_from_its_reset_date_the_calendar_still_counts(rtc):
    """A program that sets only the time (as timers.c does) finds the calendar counting from the
    reset date, year 00."""
    board, clock = rtc
    clock.write(r.REGISTER_CTRL, 4, OPEN | SETTING, 0)
    clock.write(r.INITIAL_COUNT, 4, r.CLOCK_HZ, 0)
    clock.write(r.CURRENT_COUNT, 4, 1, 0)
    clock.write(r.TIME, 4, 59 << 10 | 59 << 16 | 23 << 24, 0)
    clock.write(r.REGISTER_CTRL, 4, OPEN | RUNNING, 0)
    assert when(clock, S) == (0, 0, 1, 2, 1, 0, 0, 0)                   # 00-01-02, the next day


def test_each_second_begins_counted_from_the_start_not_from_the_second_before(idle_elf):
    """A second of initial_count cycles that is no whole number of picoseconds: the k-th second
    begins k x initial_count cycles after the calendar started (rounded up once), whether its tick
    was told second by second or all at once."""
    per = r.CLOCK_HZ // 7 + 3                        # a seventh of a second and 3 cycles
    heard = []
    for stepwise in (True, False):
        board = make_board(idle_elf)
        clock = board.rtc
        pulses = []
        clock.pulse = pulses.append
        init(clock)
        clock.write(r.REGISTER_CTRL, 4, OPEN | SETTING, 0)
        clock.write(r.INITIAL_COUNT, 4, per, 0)
        clock.write(r.INTERRUPT_CTRL, 4, r.TICK_ENABLE, 0)
        clock.write(r.REGISTER_CTRL, 4, OPEN | RUNNING, 0)
        if stepwise:
            while len(pulses) < 50:
                clock.advance(clock.next_event_time(pulses[-1] if pulses else 0))
        else:
            clock.advance(cycles_time(50 * per, r.CLOCK_HZ))
        heard.append(pulses)
    assert heard[0] == heard[1] == [cycles_time(k * per, r.CLOCK_HZ) for k in range(1, 51)]
