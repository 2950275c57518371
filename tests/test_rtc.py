"""The RTC (devices/rtc.py) as the Kendryte SDK's rtc.c drives it: rtc_init (unprotected, counting
IN0's 26 MHz, count from 1, running), setting the time in setting mode, the calendar moving on a
second per initial_count cycles (minutes, days, months, leap years, the week day), tick and alarm
interrupts as pulses the PLIC's gateway latches (source 20)."""
from __future__ import annotations

import pytest

from emulator.devices import rtc as r
from emulator.devices.plic import SOURCE_RTC
from k210_fixtures import idle_elf, make_board  # noqa: F401

SETTING, RUNNING = r.WRITE_ENABLE, r.READ_ENABLE
OPEN = 0xFF << 13 | 0xFF << 21 | r.INITIAL_COUNT_MASK | r.INTERRUPT_REGISTER_MASK   # rtc_protect_set(0)


@pytest.fixture
def rtc(idle_elf):
    board = make_board(idle_elf)
    return board, board.rtc


def init(rtc, now=0.0):
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
    assert when(clock, 0.0) == (20, 24, 2, 28, 3, 23, 59, 58)
    assert clock.read(r.CURRENT_COUNT, 4, 0.5) == 13_000_001
    assert when(clock, 1.0 - 1e-7) == (20, 24, 2, 28, 3, 23, 59, 58)
    assert when(clock, 1.0 + 1e-7) == (20, 24, 2, 28, 3, 23, 59, 59)
    assert when(clock, 2.0 + 1e-7) == (20, 24, 2, 29, 4, 0, 0, 0)        # a leap year's 29 February
    assert clock.read(r.EXTENDED, 4, 2.5) & 0x20                         # leap year
    assert when(clock, 2.0 + 86400 + 1e-6) == (20, 24, 3, 1, 5, 0, 0, 0)


def test_paused_and_setting_the_calendar_stands_and_writes_need_setting_mode(rtc):
    board, clock = rtc
    init(clock)
    clock.write(r.REGISTER_CTRL, 4, OPEN, 0.5)                            # paused
    assert when(clock, 10.0) == (20, 24, 2, 28, 3, 23, 59, 58)
    clock.write(r.TIME, 4, 0, 10.0)                                       # not setting: ignored
    assert when(clock, 10.0)[-1] == 58
    clock.write(r.REGISTER_CTRL, 4, OPEN | RUNNING, 10.0)
    assert when(clock, 10.6) == (20, 24, 2, 28, 3, 23, 59, 59)           # half a second was left


def test_tick_every_second_and_an_alarm_are_pulses_the_plic_latches(rtc):
    board, clock = rtc
    init(clock)
    clock.write(r.REGISTER_CTRL, 4, OPEN | SETTING, 0.0)
    clock.write(r.ALARM_TIME, 4, 0 << 10 | 0 << 16 | 0 << 24, 0.0)      # midnight
    clock.write(r.INTERRUPT_CTRL, 4, r.ALARM_ENABLE | (r.MASK_SECOND | r.MASK_MINUTE | r.MASK_HOUR) << 24, 0.0)
    clock.write(r.REGISTER_CTRL, 4, OPEN | RUNNING, 0.0)
    assert clock.next_event_time(0.0) == pytest.approx(1.0)
    clock.advance(1.0)                                                    # 23:59:59: no alarm
    assert SOURCE_RTC not in board.plic.pending
    start = clock.next_event_time(1.0)
    assert start == pytest.approx(2.0)
    clock.advance(start)                                                  # midnight: the alarm's pulse
    assert SOURCE_RTC in board.plic.pending and not clock.irq_line()     # latched; no level to hold
    board.plic.write(4 * SOURCE_RTC, 4, 1, start)
    board.plic.write(0x2000, 4, 1 << SOURCE_RTC, start)
    assert board.plic.read(0x20_0004, 4, start + 1e-6) == SOURCE_RTC
    board.plic.write(0x20_0004, 4, SOURCE_RTC, start + 1e-6)             # complete
    assert SOURCE_RTC not in board.plic.pending
    clock.write(r.REGISTER_CTRL, 4, OPEN | SETTING, 3.0)
    clock.write(r.INTERRUPT_CTRL, 4, r.TICK_ENABLE, 3.0)                  # every second
    clock.write(r.REGISTER_CTRL, 4, OPEN | RUNNING, 3.0)
    for second in (4.0, 5.0):
        tick = clock.next_event_time(second - 0.5)
        assert tick == pytest.approx(second)
        board.plic.pending.discard(SOURCE_RTC)
        clock.advance(tick)
        assert SOURCE_RTC in board.plic.pending


def test_from_its_reset_date_the_calendar_still_counts(rtc):
    """A program that sets only the time (as timers.c does) finds the calendar counting from the
    reset date, year 00."""
    board, clock = rtc
    clock.write(r.REGISTER_CTRL, 4, OPEN | SETTING, 0.0)
    clock.write(r.INITIAL_COUNT, 4, r.CLOCK_HZ, 0.0)
    clock.write(r.CURRENT_COUNT, 4, 1, 0.0)
    clock.write(r.TIME, 4, 59 << 10 | 59 << 16 | 23 << 24, 0.0)
    clock.write(r.REGISTER_CTRL, 4, OPEN | RUNNING, 0.0)
    assert when(clock, 1.0 + 1e-7) == (0, 0, 1, 2, 1, 0, 0, 0)          # 00-01-02, the next day
