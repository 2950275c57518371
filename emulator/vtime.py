"""Virtual time: whole picoseconds since power-on, in Python ints.

Every time and duration inside the model is an int count of picoseconds (`Time`), and every
clock rate an int count of hertz, so that arithmetic on them is exact: the moment a device
event falls on, or the cycle a hart has reached, is the same whatever the turns were that led
there (a float sum of per-turn times is not: it depended on where turns ended, in the last
digits). A picosecond is fine enough: the K210's fastest clock (PLL0 at 800 MHz) ticks every
1,250 ps, and a duration computed from a clock is rounded once, by less than a picosecond.

Durations made of clock cycles are rounded up (`cycles_time`): the time by which that many whole
cycles have passed. Counts of cycles in a time are rounded down (`cycles_in`): the cycles that
have wholly passed. The two round-trip: cycles_in(cycles_time(n, hz), hz) == n for every hz
below 1 THz.

Seconds (floats) appear only at the edges: options the user gives (--until 0.5), and what the
model reports (run.json, messages, VCD time stamps).
"""
from __future__ import annotations

Time = int                     # picoseconds since power-on (a duration: picoseconds)

PS_PER_S = 10 ** 12
PS_PER_MS = 10 ** 9
PS_PER_US = 10 ** 6
PS_PER_NS = 10 ** 3
# "never" where an int is needed (a min() over event times, a bound no event reaches): later than
# any time a run can reach (about 53 days of virtual time), and still exact in a C int64.
NEVER: Time = 1 << 62


def cycles_time(cycles: int, hz: int) -> Time:
    """How long `cycles` cycles of a clock at `hz` take: rounded up to a whole picosecond."""
    return -((-cycles * PS_PER_S) // hz)


def cycles_in(duration: Time, hz: int) -> int:
    """How many whole cycles of a clock at `hz` pass in `duration` (rounded down)."""
    return (duration * hz) // PS_PER_S


def cycles_reaching(duration: Time, hz: int) -> int:
    """The fewest whole cycles of a clock at `hz` whose time (cycles_time) is `duration` or more
    (0 for a duration of 0 or less): where a count must stop to have reached a moment."""
    return max(0, cycles_in(duration - 1, hz) + 1)


def from_seconds(seconds: float) -> Time:
    """A time the user gave in seconds, to the nearest picosecond."""
    return round(seconds * PS_PER_S)


def to_seconds(time: Time) -> float:
    """A time for a report, in seconds."""
    return time / PS_PER_S


def ms(time: Time) -> str:
    """A time for a message: milliseconds with three decimals, as the model's messages give them."""
    return f"{time / PS_PER_MS:.3f} ms"
