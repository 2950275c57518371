"""Virtual time in whole picoseconds (emulator/vtime.py): the conversions are exact, and a hart's
time does not depend on where its turns ended (Scheduler.time_at_cycles)."""
from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from emulator.vtime import NEVER, PS_PER_MS, PS_PER_S, cycles_in, cycles_reaching, cycles_time
from k210_fixtures import make_board, program, reg

# every clock the K210 can make is below 1 GHz; the oscillator's 26 MHz and odd PLL rates included
RATES = st.integers(min_value=1, max_value=999_999_999)


@given(st.integers(min_value=0, max_value=1 << 40), RATES)
def test_cycles_round_trip_through_time(cycles, hz):
    """cycles_time rounds up, cycles_in down: n cycles take a time in which exactly n have passed."""
    duration = cycles_time(cycles, hz)
    assert cycles_in(duration, hz) == cycles
    assert duration * hz >= cycles * PS_PER_S > (duration - 1) * hz


@given(st.integers(min_value=0, max_value=1 << 40), st.integers(min_value=0, max_value=1 << 40), RATES)
def test_a_split_duration_is_never_shorter_and_at_most_a_picosecond_longer(a, b, hz):
    """Two stretches rounded apart against one rounded whole: why a hart's time is reckoned from its
    anchor (time_at_cycles), never summed turn by turn."""
    whole, parts = cycles_time(a + b, hz), cycles_time(a, hz) + cycles_time(b, hz)
    assert whole <= parts <= whole + 1


@given(st.integers(min_value=-10, max_value=1 << 50), RATES)
def test_the_fewest_cycles_that_reach_a_moment(duration, hz):
    """cycles_reaching: where a turn's cycle budget must end for the hart to have reached a time."""
    n = cycles_reaching(duration, hz)
    assert cycles_time(n, hz) >= duration
    assert n == 0 or cycles_time(n - 1, hz) < duration


def test_never_is_later_than_any_run_and_fits_a_c_int64():
    assert NEVER > 50 * 24 * 3600 * PS_PER_S and NEVER < 1 << 63


LOOP = """
    li      t0, 3000000
1:  addi    t0, t0, -1
    bnez    t0, 1b
    csrr    s2, mcycle
"""


def test_a_harts_time_is_the_same_whatever_its_quantum():
    """The same program run to the same virtual time under quanta of 997 and 20,000 cycles:
    thousands of turns against a hundred, and the hart ends at the same cycle, time and
    instruction, having read the same mcycle on the way."""
    results = []
    for quantum in (997, 20_000):
        board = make_board(program(LOOP), quantum=quantum)
        board.run_until(500 * PS_PER_MS)
        hart = board.harts[0]
        results.append((hart.time, hart.cycles, hart.executed, reg(board, "s2")))
        assert hart.time == board.scheduler.time_at_cycles(hart, hart.cycles) >= 500 * PS_PER_MS
    assert results[0] == results[1]
    assert results[0][3] > 3_000_000
