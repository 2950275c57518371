"""RTC (0x5046_0000): the K210's real-time clock, a calendar that counts seconds.

The register map and its use are the Kendryte SDK's (rtc.h `rtc_t`, rtc.c): date (0x00: week
2:0, day 12:8, month 19:16, year 31:20, two digits), time (0x04: second 15:10, minute 21:16,
hour 28:24), alarm_date and alarm_time (0x08, 0x0C, the same fields), initial_count (0x10: clock
cycles a second), current_count (0x14: the cycle within the second), interrupt_ctrl (0x18: tick
enable bit 0, alarm enable bit 1, tick mode 3:2 every second, minute, hour or day, alarm
compare mask 31:24 with bit 1 second ... bit 7 year), register_ctrl (0x1C: read enable bit 0,
write enable bit 1: running 01, setting 10, paused 00; the write masks of the time 20:13, of the
alarm 28:21, of initial_count bit 29 and of interrupt_ctrl bit 30) and extended (0x28: century
4:0, leap year bit 5).

The calendar runs while register_ctrl says running: current_count counts the RTC's clock (IN0,
26 MHz, as rtc_init programs initial_count from SYSCTL_CLOCK_IN0) from 1 to initial_count, and
each time it gets there the calendar moves on a second (rtc_init sets current_count to 1).
While setting, what is written takes effect where the write masks allow (rtc_protect_set(0)
opens them all); paused, the calendar stands. The tick interrupt comes at the start of every
second, minute, hour or day (tick mode), the alarm interrupt at the start of the second whose
fields the compare mask selects match the alarm's; each is a pulse (the SDK's handler clears
nothing in the RTC), which the PLIC's gateway latches as pending (source 20): the `pulse` port.
"""
from __future__ import annotations

import calendar
from dataclasses import dataclass
from datetime import datetime, timedelta
from typing import Callable

from ..memory_map import K210_BLOCKS
from ..vtime import Time, cycles_in, cycles_time
from .mmio import Peripheral, Register
from .ports import Ports

DATE, TIME, ALARM_DATE, ALARM_TIME, INITIAL_COUNT, CURRENT_COUNT = 0x00, 0x04, 0x08, 0x0C, 0x10, 0x14
INTERRUPT_CTRL, REGISTER_CTRL, EXTENDED = 0x18, 0x1C, 0x28
CLOCK_HZ = 26_000_000                # IN0
GREGORIAN_CYCLE = 400
READ_ENABLE, WRITE_ENABLE = 1, 2
INITIAL_COUNT_MASK, INTERRUPT_REGISTER_MASK = 1 << 29, 1 << 30
TICK_ENABLE, ALARM_ENABLE = 1, 2
# alarm compare mask bits (rtc_mask_t): 1 second, 2 minute, 3 hour, 4 week, 5 day, 6 month, 7 year
MASK_SECOND, MASK_MINUTE, MASK_HOUR, MASK_WEEK, MASK_DAY, MASK_MONTH, MASK_YEAR = (1 << n for n in range(1, 8))


@dataclass
class Calendar:
    """The RTC's date and time, as its registers hold them."""
    century: int = 0
    year: int = 0            # two digits
    month: int = 1
    day: int = 1
    week: int = 0            # 0 Sunday
    hour: int = 0
    minute: int = 0
    second: int = 0

    def plus(self, seconds: int) -> "Calendar":
        # (400 years on: the Gregorian calendar repeats every 400 years, and Python's starts at year 1)
        year = 100 * self.century + self.year + GREGORIAN_CYCLE
        try:
            start = datetime(year, self.month, self.day, self.hour, self.minute, self.second)
        except ValueError:
            return self            # a date the calendar cannot hold (31 April, month 0): it stands
        moment = start + timedelta(seconds=seconds)
        days = (moment.date() - start.date()).days
        year = moment.year - GREGORIAN_CYCLE
        return Calendar(year // 100, year % 100, moment.month, moment.day, (self.week + days) % 7,
                        moment.hour, moment.minute, moment.second)

    def date_word(self) -> int:
        return self.week | self.day << 8 | self.month << 16 | self.year << 20

    def time_word(self) -> int:
        return self.second << 10 | self.minute << 16 | self.hour << 24

    def leap(self) -> bool:
        return calendar.isleap(100 * self.century + self.year)


def _date_fields(word: int) -> dict[str, int]:
    return {"week": word & 7, "day": word >> 8 & 0x1F, "month": word >> 16 & 0xF, "year": word >> 20 & 0xFFF}


def _time_fields(word: int) -> dict[str, int]:
    return {"second": word >> 10 & 0x3F, "minute": word >> 16 & 0x3F, "hour": word >> 24 & 0x1F}


class Rtc(Peripheral):
    NAME = "RTC"
    BASE = K210_BLOCKS["RTC"].base
    SIZE = K210_BLOCKS["RTC"].size
    GATE = K210_BLOCKS["RTC"].gate
    REGISTERS = {
        DATE: Register("date"), TIME: Register("time"), ALARM_DATE: Register("alarm_date"),
        ALARM_TIME: Register("alarm_time"), INITIAL_COUNT: Register("initial_count"),
        CURRENT_COUNT: Register("current_count"), INTERRUPT_CTRL: Register("interrupt_ctrl"),
        REGISTER_CTRL: Register("register_ctrl"), 0x20: Register("reserved0"), 0x24: Register("reserved1"),
        EXTENDED: Register("extended"),
    }

    def __init__(self, ports: Ports, pulse: Callable[[Time], None]) -> None:
        """pulse: the interrupt line pulses at this time (the PLIC's gateway latches it)."""
        super().__init__(ports)
        self.pulse = pulse
        self._clear()

    def _clear(self) -> None:
        self.calendar = Calendar()
        self._since: Time | None = None        # running: when current_count had `_count`
        self._count = 0
        # the seconds after _since whose start advance has told (the k-th begins _second_start(k)):
        # each is counted in RTC clocks from _since, never by adding rounded second lengths
        self._told = 0

    def reset(self, now: Time) -> None:
        super().reset(now)
        self._clear()

    # --- the calendar as time goes on ---------------------------------------------------------------

    def _per_second(self) -> int:
        return max(self.values[INITIAL_COUNT], 1)

    def _running(self) -> bool:
        return self.values[REGISTER_CTRL] & 3 == READ_ENABLE

    def _run(self, since: Time) -> None:
        """The calendar runs from `since` on, current_count then being `_count`."""
        self._since, self._told = since, 0

    def _position(self, now: Time) -> tuple[int, int]:
        """(whole seconds the calendar has moved on since the last second advance told (since
        _since if none), current_count now)."""
        if self._since is None:
            return 0, self._count
        # cycles since the start of the second current at _since
        total = self._before() + cycles_in(now - self._since, CLOCK_HZ)
        per = self._per_second()
        return total // per - self._told, total % per + 1

    def _before(self) -> int:
        """Cycles of the second current at _since that had passed by then."""
        return max(self._count, 1) - 1

    def _settle(self, now: Time) -> None:
        """Folds the time run since _since into the calendar (before anything changes)."""
        if self._since is None:
            return
        seconds, count = self._position(now)
        if seconds:
            self.calendar = self.calendar.plus(seconds)
        self._count = count
        self._run(now)

    def _second_start(self, k: int) -> Time:
        """When the k-th second after _since begins (the first: 1)."""
        return self._since + cycles_time(k * self._per_second() - self._before(), CLOCK_HZ)

    def _second_after(self, now: Time) -> int:
        """k of the first second after _since to begin after `now`."""
        return (self._before() + cycles_in(now - self._since, CLOCK_HZ)) // self._per_second() + 1

    def _second_starts(self, now: Time) -> Time | None:
        """When the next second begins after `now` (None: the calendar stands)."""
        if self._since is None:
            return None
        return self._second_start(self._second_after(now))

    # --- interrupts ------------------------------------------------------------------------------------

    def _interrupting(self, moment: Calendar) -> bool:
        """Whether the second `moment` begins with a tick or an alarm."""
        control = self.values[INTERRUPT_CTRL]
        if control & TICK_ENABLE:
            mode = control >> 2 & 3
            if (mode == 0 or (moment.second == 0 and (mode == 1 or (moment.minute == 0 and
                                                                   (mode == 2 or moment.hour == 0))))):
                return True
        if control & ALARM_ENABLE:
            mask = control >> 24
            alarm = {**_date_fields(self.values[ALARM_DATE]), **_time_fields(self.values[ALARM_TIME])}
            checks = ((MASK_SECOND, moment.second, alarm["second"]), (MASK_MINUTE, moment.minute, alarm["minute"]),
                      (MASK_HOUR, moment.hour, alarm["hour"]), (MASK_WEEK, moment.week, alarm["week"]),
                      (MASK_DAY, moment.day, alarm["day"]), (MASK_MONTH, moment.month, alarm["month"]),
                      (MASK_YEAR, moment.year, alarm["year"]))
            if mask & 0xFE and all(mine == wanted for bit, mine, wanted in checks if mask & bit):
                return True
        return False

    def next_event_time(self, now: Time) -> Time | None:
        if self._since is None or not self.values[INTERRUPT_CTRL] & (TICK_ENABLE | ALARM_ENABLE):
            return None
        return self._second_starts(now)

    def advance(self, now: Time) -> None:
        """Interrupt pulses at the seconds that begin up to `now`, each raised at its own time."""
        if self._since is None or not self.values[INTERRUPT_CTRL] & (TICK_ENABLE | ALARM_ENABLE):
            return
        while True:
            # the second after the last told, or (none told yet) the first to begin after _since
            k = self._told + 1 if self._told else self._second_after(self._since)
            start = self._second_start(k)
            if start > now:
                return
            self.calendar = self.calendar.plus(1)
            self._told = k
            if self._interrupting(self.calendar):
                self.pulse(start)

    # --- registers -------------------------------------------------------------------------------------

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        self.advance(now)
        moment = self.calendar.plus(self._position(now)[0]) if self._since is not None else self.calendar
        if offset == DATE:
            return moment.date_word()
        if offset == TIME:
            return moment.time_word()
        if offset == CURRENT_COUNT:
            return self._position(now)[1]
        if offset == EXTENDED:
            return moment.century | (0x20 if moment.leap() else 0)
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        self.advance(now)
        self._settle(now)
        control = self.values[REGISTER_CTRL]
        if offset == REGISTER_CTRL:
            self.values[offset] = value
            if self._running():
                self._run(now)
            else:
                self._since = None
            return
        if not control & WRITE_ENABLE:
            return                               # not in setting mode: the write is ignored
        if offset in (DATE, TIME):
            mask = control >> 13 & 0xFF
            fields = _date_fields(value) if offset == DATE else _time_fields(value)
            bits = {"second": MASK_SECOND, "minute": MASK_MINUTE, "hour": MASK_HOUR, "week": MASK_WEEK,
                    "day": MASK_DAY, "month": MASK_MONTH, "year": MASK_YEAR}
            for name, field_value in fields.items():
                if mask & bits[name]:
                    setattr(self.calendar, name, field_value)
        elif offset in (ALARM_DATE, ALARM_TIME):
            if control >> 21 & 0xFF:
                self.values[offset] = value
        elif offset == INITIAL_COUNT:
            if control & INITIAL_COUNT_MASK:
                self.values[offset] = value
        elif offset == CURRENT_COUNT:
            if control & INITIAL_COUNT_MASK:
                self._count = value
        elif offset == INTERRUPT_CTRL:
            if control & INTERRUPT_REGISTER_MASK:
                self.values[offset] = value
        elif offset == EXTENDED:
            self.calendar.century = value & 0x1F
        else:
            self.values[offset] = value
        self.ports.irq_changed(now)
