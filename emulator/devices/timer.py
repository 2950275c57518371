"""TIMER0-2 (0x502D_0000, 0x502E_0000, 0x502F_0000): Synopsys DesignWare APB timers, four channels each.

The register map is the Kendryte SDK's (timer.h `kendryte_timer_t`): per channel (0x14 apart)
load_count, current_value, control, eoi, intr_stat; then the block's intr_stat (0xA0), eoi
(0xA4), raw_intr_stat (0xA8), comp_version (0xAC) and each channel's load_count2 (0xB0 + 4 n).
control: bit 0 enable, bit 1 user-defined mode (reload load_count; 0: free-running, reload
0xFFFF_FFFF after the first count), bit 2 interrupt mask, bit 3 PWM.

A channel counts down at the timer clock from load_count when enabled; reaching zero raises its
interrupt (the raw status, seen in intr_stat unless masked) and reloads. As the SDK and Linux's
dw_apb_timer program it, a count of N lasts N clocks (timer_set_interval: N = interval / clock
period; dw_apb_clockevent: N = clock / HZ). In PWM mode the channel alternates load_count and
load_count2 and its toggle output (FPIOA TIMERn_TOGGLE1-4) is low through a load_count count and
high through a load_count2 one (pwm_set_frequency: load_count = period - duty, load_count2 =
duty). Reading a channel's eoi clears its interrupt, the block's eoi every channel's. Channels 0
and 1 share the block's first interrupt line, 2 and 3 its second (PLIC 14 + 2 n and 15 + 2 n,
timer.c's diagram). The clock is SYSCTL's: IN0 (26 MHz) or PLL0 (clk_sel0 bit 13 + n) /
((clk_th2 byte n + 1) x 2) (sysctl.c, SYSCTL_CLOCK_TIMERn). A running channel keeps the clock
it had when it was last written to or enabled: the SDK sets the clock before it starts a timer.
comp_version reads 0 (its value on the K210 is not published).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..memory_map import K210_BLOCKS
from ..vtime import NEVER, Time, cycles_in, cycles_time
from .mmio import Peripheral, Register
from .ports import Ports

CHANNELS = 4
CHANNEL_STRIDE = 0x14
LOAD_COUNT, CURRENT_VALUE, CONTROL, EOI, INTR_STAT = 0x00, 0x04, 0x08, 0x0C, 0x10
BLOCK_INTR_STAT, BLOCK_EOI, RAW_INTR_STAT, COMP_VERSION, LOAD_COUNT2 = 0xA0, 0xA4, 0xA8, 0xAC, 0xB0
CR_ENABLE, CR_USER_MODE, CR_INTERRUPT_MASK, CR_PWM = 1, 2, 4, 8
FREE_RUNNING_RELOAD = 0xFFFF_FFFF
# Toggles told at one advance at most: beyond, a PWM far faster than anything looks at is not
# logged edge by edge (the scheduler stops at each toggle, so this is only a bound)
MAX_TOGGLES_HEARD = 10_000


def channel_register(channel: int, offset: int) -> int:
    return CHANNEL_STRIDE * channel + offset


@dataclass
class _Count:
    """A running channel's plan: a count of `first` ticks of a clock at `hz` from `start`, then the
    counts of `cycle` over and over; `levels` are the toggle output's during `first` and each of
    `cycle`. (A count of 0 is taken as 1: the counter reloads on the next clock.) Every count's end
    is a number of ticks from `start` (time_of), so none depends on the rounding of those before."""
    start: Time
    hz: int
    first: int
    first_level: int
    cycle: tuple[int, ...]
    cycle_levels: tuple[int, ...]

    def time_of(self, ticks: int) -> Time:
        """When `ticks` ticks from `start` have passed."""
        return self.start + cycles_time(ticks, self.hz)

    def position(self, now: Time) -> tuple[int, int, int, Time | None]:
        """At `now`: (the toggle level, the tick the current count began at (from `start`), its
        length in ticks, when the last count ended or None)."""
        # the ticks wholly passed by `now`: a count of n from tick b has ended iff passed >= b + n
        passed = cycles_in(now - self.start, self.hz)
        if passed < self.first:
            return self.first_level, 0, self.first, None
        cycle = tuple(max(length, 1) for length in self.cycle)
        began = self.first + (passed - self.first) // sum(cycle) * sum(cycle)
        for length, level in zip(cycle, self.cycle_levels):
            if passed < began + length:
                return level, began, length, self.time_of(began)
            began += length
        return self.cycle_levels[0], began, cycle[0], self.time_of(began)

    def next_end(self, now: Time) -> Time:
        _, began, length, _ = self.position(now)
        return self.time_of(began + length)


class DwTimer(Peripheral):
    """One of TIMER0-2."""

    REGISTERS = {
        **{channel_register(n, off): Register(f"{name}{n}", writable=writable, readable=readable)
           for n in range(CHANNELS)
           for off, name, writable, readable in ((LOAD_COUNT, "load_count", True, True),
                                                 (CURRENT_VALUE, "current_value", False, True),
                                                 (CONTROL, "control", True, True), (EOI, "eoi", False, True),
                                                 (INTR_STAT, "intr_stat", False, True))},
        BLOCK_INTR_STAT: Register("intr_stat", writable=False), BLOCK_EOI: Register("eoi", writable=False),
        RAW_INTR_STAT: Register("raw_intr_stat", writable=False), COMP_VERSION: Register("comp_version", writable=False),
        **{LOAD_COUNT2 + 4 * n: Register(f"load_count2_{n}") for n in range(CHANNELS)},
    }

    def __init__(self, index: int, ports: Ports, clock_hz: Callable[[], int]) -> None:
        """index: 0, 1 or 2. clock_hz: the timer clock SYSCTL gives this block."""
        self.index = index
        self.NAME = f"TIMER{index}"
        block = K210_BLOCKS[self.NAME]
        self.GATE, self.BASE, self.SIZE = block.gate, block.base, block.size
        self.clock_hz = clock_hz
        super().__init__(ports)
        self._counts: list[_Count | None] = [None] * CHANNELS
        # -NEVER: earlier than any time
        self._cleared = [-NEVER] * CHANNELS          # when each channel's interrupt was last cleared
        self._ended_before = [-NEVER] * CHANNELS     # the last count's end under an earlier plan
        # hears each change of a PWM channel's toggle output: (channel, time, level); set by the wiring
        self.on_toggle: Callable[[int, Time, int], None] = lambda channel, at, level: None
        self._toggles_heard = [-NEVER] * CHANNELS    # the time up to which on_toggle has heard them

    def reset(self, now: Time) -> None:
        super().reset(now)
        self._counts = [None] * CHANNELS
        self._cleared = [-NEVER] * CHANNELS
        self._ended_before = [-NEVER] * CHANNELS

    # --- counting ----------------------------------------------------------------------------------

    def _control(self, channel: int) -> int:
        return self.values[channel_register(channel, CONTROL)]

    def _loads(self, channel: int) -> tuple[int, int]:
        return self.values[channel_register(channel, LOAD_COUNT)], self.values[LOAD_COUNT2 + 4 * channel]

    def _plan(self, channel: int, now: Time, first: int, first_level: int) -> None:
        """The channel counts `first` ticks from `now` at `first_level`, then as its registers say."""
        control = self._control(channel)
        load, load2 = self._loads(channel)
        hz = self.clock_hz()
        if not control & CR_ENABLE or hz <= 0:
            self._counts[channel] = None
            return
        if control & CR_PWM:
            cycle, levels = ((load2, load), (1, 0)) if first_level == 0 else ((load, load2), (0, 1))
        elif control & CR_USER_MODE:
            cycle, levels = (load,), (0,)
        else:
            cycle, levels = (FREE_RUNNING_RELOAD,), (0,)
        self._counts[channel] = _Count(now, hz, max(first, 0), first_level, cycle, levels)

    def _state(self, channel: int, now: Time) -> tuple[int, int, int]:
        """(the counter's value, the toggle output, whether its raw interrupt is set) at `now`."""
        count = self._counts[channel]
        if count is None:
            return 0, 0, self._raw_of(channel, None)
        level, began, length, last_end = count.position(now)
        elapsed = cycles_in(now - count.start, count.hz) - began
        return max(length - elapsed, 0), level, self._raw_of(channel, last_end)

    def _raw_of(self, channel: int, last_end: Time | None) -> int:
        ended = max(self._ended_before[channel], -NEVER if last_end is None else last_end)
        return 1 if ended > self._cleared[channel] else 0

    def toggle_level(self, channel: int, now: Time) -> int:
        """The channel's toggle output (FPIOA TIMERn_TOGGLE1 + channel)."""
        if not self._control(channel) & CR_PWM:
            return 0
        return self._state(channel, now)[1]

    def _raw(self, now: Time) -> int:
        return sum(self._state(n, now)[2] << n for n in range(CHANNELS))

    def _status(self, now: Time) -> int:
        return sum(1 << n for n in range(CHANNELS)
                   if not self._control(n) & CR_INTERRUPT_MASK and self._state(n, now)[2])

    def _quiet(self) -> bool:
        """No channel counting and no interrupt left uncleared (the PLIC asks on every sample)."""
        return not any(self._counts) and all(e <= c for e, c in zip(self._ended_before, self._cleared))

    def irq_lines(self) -> int:
        """Bit 0: the line of channels 0 and 1 (PLIC 14 + 2 n), bit 1: that of channels 2 and 3."""
        if self._quiet():
            return 0
        status = self._status(self.ports.clock.now())
        return (1 if status & 3 else 0) | (2 if status & 12 else 0)

    def next_event_time(self, now: Time) -> Time | None:
        """The next count's end of a channel whose end matters outside a read: an unmasked interrupt.
        (A PWM output's edges are told with their own times whenever the timer is advanced, every
        turn of the harts: they need no turn of their own.)"""
        if not any(self._counts):
            return None
        times = []
        for channel, count in enumerate(self._counts):
            control = self._control(channel)
            if count is not None and not control & CR_INTERRUPT_MASK:
                times.append(count.next_end(now))
        return min(times) if times else None

    def advance(self, now: Time) -> None:
        """Tells on_toggle each change of a PWM output up to `now`, with its own time."""
        if not any(self._counts):
            return
        for channel, count in enumerate(self._counts):
            if count is None or not self._control(channel) & CR_PWM:
                continue
            at = max(self._toggles_heard[channel], count.start)
            for _ in range(MAX_TOGGLES_HEARD):
                end = count.next_end(at)
                if end > now:
                    break
                self.on_toggle(channel, end, count.position(end)[0])
                at = end
            self._toggles_heard[channel] = now

    # --- registers ---------------------------------------------------------------------------------

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        if offset < CHANNELS * CHANNEL_STRIDE:
            channel, field = divmod(offset, CHANNEL_STRIDE)
            if field == CURRENT_VALUE:
                return self._state(channel, now)[0]
            if field == INTR_STAT:
                return 1 if self._status(now) >> channel & 1 else 0
            if field == EOI:
                self._clear(channel, now)
                return 0
            return self.values[offset]
        if offset == BLOCK_INTR_STAT:
            return self._status(now)
        if offset == RAW_INTR_STAT:
            return self._raw(now)
        if offset == BLOCK_EOI:
            for channel in range(CHANNELS):
                self._clear(channel, now)
            return 0
        return self.values[offset]

    def _clear(self, channel: int, now: Time) -> None:
        self.took_on_read = True
        self._cleared[channel] = now
        self.ports.irq_changed(now)

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        channel = offset // CHANNEL_STRIDE if offset < CHANNELS * CHANNEL_STRIDE else (offset - LOAD_COUNT2) // 4
        was_enabled = bool(self._control(channel) & CR_ENABLE)
        remaining, level, _ = self._state(channel, now)
        if self._counts[channel] is not None:
            last_end = self._counts[channel].position(now)[3]
            if last_end is not None:
                self._ended_before[channel] = max(self._ended_before[channel], last_end)
        self.values[offset] = value
        control = self._control(channel)
        if not control & CR_ENABLE:
            self._counts[channel] = None
        elif not was_enabled:
            self._plan(channel, now, self._loads(channel)[0], 0)     # enabled: load_count is loaded
        else:
            self._plan(channel, now, remaining, level)              # new values: from the next reload
        self.ports.irq_changed(now)
        self._toggles_heard[channel] = now
        self.on_toggle(channel, now, self.toggle_level(channel, now))
