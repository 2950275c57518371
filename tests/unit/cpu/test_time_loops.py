"""Loops that wait for time by reading mcycle (cpu/time_loops.py): the iterations that cannot end
the loop are counted without being run, and everything the hart and the board show is what
running them would have shown: registers, instructions, cycles, mispredictions, stalls, time."""
from __future__ import annotations

import time

import pytest

from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE
from emulator.cpu.time_loops import decode, find_time_loops
from emulator.vtime import PS_PER_MS
from k210_fixtures import make_board, program, reg, run_to_done

# the SDK's usleep: while (read_cycle() - start < n) continue; (here 2 ms at 26 MHz, 52,000 cycles)
USLEEP = """
    csrr    s0, mcycle
    li      s1, 52000
1:  csrr    t0, mcycle
    sub     t0, t0, s0
    bltu    t0, s1, 1b
    csrr    s2, mcycle
    csrr    s3, minstret
"""


def state(board) -> dict:
    hart = board.harts[0]
    return {"registers": [reg(board, name) for name in ("s0", "s1", "s2", "s3", "t0")], "executed": hart.executed,
            "cycles": hart.cycles, "mispredicts": hart.mispredicts, "stalls": hart.stall_cycles, "pc": hart.pc}


def run(source: str, engine: str, skip: bool) -> tuple[dict, float, int]:
    board = make_board(program(source), engine=engine)
    if not skip:
        for hart in board.harts:
            hart.time_loops.clear()
    started = time.process_time()
    run_to_done(board, max_time_s=0.1)
    return state(board), time.process_time() - started, board.harts[0].iterations_skipped


@pytest.mark.parametrize("engine", [ENGINE_FAST, ENGINE_PRECISE])
def test_skipping_a_usleep_loop_changes_nothing_the_program_sees(engine):
    skipped, skipped_time, iterations = run(USLEEP, engine, True)
    ran, ran_time, none = run(USLEEP, engine, False)
    assert skipped == ran
    assert iterations > none + 1000          # (both skip the spin at `done` alike)
    assert 52000 <= reg_value(skipped, 2) - reg_value(skipped, 0) < 52100


def reg_value(state: dict, index: int) -> int:
    return state["registers"][index]


def test_the_finder_takes_the_sdk_usleep_and_nothing_that_carries_a_value(tmp_path):
    from k210_fixtures import build_elf
    from elftools.elf.elffile import ELFFile
    elf = build_elf(""".globl _start
_start:
    csrr    s0, mcycle
wait:
    csrr    t0, mcycle
    sub     t0, t0, s0
    bltu    t0, s1, wait
count:
    csrr    t0, mcycle
    addi    s4, s4, 1                    # carries a value: not only waiting
    bltu    t0, s1, count
load:
    csrr    t0, mcycle
    ld      t1, 0(s0)                    # a load: not this module's
    bltu    t0, t1, load
""")
    with open(elf, "rb") as handle:
        text = ELFFile(handle).get_section_by_name(".text")
        code, base = text.data(), text["sh_addr"]
    loops = find_time_loops(code, base)
    assert len(loops) == 1 and loops[0].body == 3
    assert decode(code, 0, base).kind == "time"


@pytest.mark.parametrize("engine", [ENGINE_FAST, ENGINE_PRECISE])
def test_running_alone_the_wait_is_skipped_to_the_next_event_with_the_same_results(engine):
    """board.run_until (as the command line runs): a hart alone skips its wait up to the next thing
    that can happen, here run_until's end; the same state as running every iteration."""
    states = []
    for skip in (True, False):
        board = make_board(program(USLEEP), engine=engine)
        if not skip:
            for hart in board.harts:
                hart.time_loops.clear()
        board.run_until(4 * PS_PER_MS)
        states.append((state(board), board.time, board.harts[0].time))
    assert states[0] == states[1]


# the SDK's msleep(1000) at 26 MHz: 26 million cycles of waiting
MSLEEP_1S = USLEEP.replace("li      s1, 52000", "li      s1, 26000000")


@pytest.mark.parametrize("engine", [ENGINE_FAST, ENGINE_PRECISE])
def test_a_hart_alone_skips_a_long_wait_past_its_turns(engine, monkeypatch):
    """With hart 1 asleep and nothing due before the wait ends, the skip goes past the turn's end in
    one go (Scheduler._alone_until): a second of msleep takes a handful of turns, not one a
    quantum, and ends where turn-by-turn skipping ends: mcycle and minstret read after the loop, the
    registers, mispredictions and stalls. Where run_until's end falls in the spin after it agrees
    too: time is whole picoseconds, a hart's reckoned from where it last stood still, whatever the turns."""
    from emulator.board import scheduler as schedmod
    results = []
    for beyond in (True, False):
        board = make_board(program(MSLEEP_1S), engine=engine)
        turns = []
        original = schedmod.Scheduler._turn
        monkeypatch.setattr(schedmod.Scheduler, "_turn", lambda self, *a, **k: (turns.append(1), original(self, *a, **k)))
        if not beyond:
            monkeypatch.setattr(schedmod.Scheduler, "_alone_until", lambda self, *a: None)
        board.run_until(1010 * PS_PER_MS)
        monkeypatch.undo()
        results.append((state(board), board.harts[0].time, len(turns)))
    (alone, alone_time, alone_turns), (turn_by_turn, turn_time, many_turns) = results
    assert alone["registers"] == turn_by_turn["registers"]          # s2, s3: mcycle and minstret after the loop
    assert (alone["mispredicts"], alone["stalls"]) == (turn_by_turn["mispredicts"], turn_by_turn["stalls"])
    assert alone["executed"] == turn_by_turn["executed"]
    assert 26_000_000 <= reg_value(alone, 2) - reg_value(alone, 0) < 26_000_100
    assert alone_time == turn_time
    assert alone_turns < 50 < 1000 < many_turns


# A store sets an event off before a long wait: three bytes into UARTHS's transmit FIFO and its
# watermark interrupt enabled (PLIC source 33, MIE set); the interrupt must come once the FIFO has
# drained below 2, not after the wait (the reviewer's case of 2026-11-28).
IRQ_DURING_A_WAIT = """
    la      t0, handler
    csrw    mtvec, t0
    li      s5, 0
    li      a1, 0x0C000000
    li      t0, 1
    sw      t0, 132(a1)                 # source 33 (UARTHS) priority 1
    li      t1, 0x0C002004
    li      t0, 2
    sw      t0, 0(t1)                   # enabled for context 0
    li      t1, 0x0C200000
    sw      zero, 0(t1)
    li      t0, 0x800
    csrw    mie, t0
    csrsi   mstatus, 8
    li      a0, 0x38000000
    li      t0, 0x20001                 # txen, watermark 2
    sw      t0, 8(a0)
    li      t0, 0x41
    sw      t0, 0(a0)
    sw      t0, 0(a0)
    sw      t0, 0(a0)
    li      t0, 1
    sw      t0, 16(a0)                  # ie: txwm
    csrr    s0, mcycle
    li      s1, 40000000
1:  csrr    t0, mcycle
    sub     t0, t0, s0
    bltu    t0, s1, 1b
    csrr    s2, mcycle
    j       done
    .balign 4
handler:
    csrr    s5, mcycle
    csrw    mie, zero
    mret
"""


def test_an_interrupt_a_store_set_off_is_not_skipped_past(monkeypatch):
    from emulator.board import scheduler as schedmod
    taken = []
    for beyond in (True, False):
        board = make_board(program(IRQ_DURING_A_WAIT), cold=False)
        if not beyond:
            monkeypatch.setattr(schedmod.Scheduler, "_alone_until", lambda self, *a: None)
        board.run_until(150 * PS_PER_MS)
        monkeypatch.undo()
        taken.append((reg(board, "s5") - reg(board, "s0"), reg(board, "s2") - reg(board, "s0")))
    # the interrupt at the same cycle, and the wait's end too: time is whole picoseconds, a hart's
    # reckoned from where it last stood still, so ten thousand turns end where one long skip does
    # (with float time, turn by turn came a cycle short)
    assert taken[0] == taken[1]
    assert 0 < taken[0][0] < 100_000
    assert 40_000_000 <= taken[1][1]


# --- loops that only spin (time_loops.find_idle_loops): `1: j 1b` -----------------------------------

# A timer interrupt every 100 ms (mtime ticks at 26 MHz / 50) taken out of a `j .` spin: the handler
# counts them in s5 and keeps the mcycle and minstret of the last one, then the hart spins again.
TIMER_OUT_OF_A_SPIN = """
    la      t0, handler
    csrw    mtvec, t0
    li      s5, 0
    li      a0, 0x02004000              # CLINT mtimecmp (hart 0)
    li      a1, 0x0200BFF8              # CLINT mtime
    li      a2, 52000                   # 100 ms of mtime
    ld      t0, 0(a1)
    add     t0, t0, a2
    sd      t0, 0(a0)
    li      t0, 0x80                    # MTIE
    csrw    mie, t0
    csrsi   mstatus, 8
spin:
    j       spin
    .balign 4
handler:
    addi    s5, s5, 1
    csrr    s6, mcycle
    csrr    s7, minstret
    csrr    s8, mepc
    ld      t0, 0(a0)
    add     t0, t0, a2
    sd      t0, 0(a0)
    mret
"""

# Both harts end in a spin that nothing can end (MIE clear): neither is ever alone, both inert.
BOTH_HARTS_SPIN = """
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, 2f
1:  j       1b
2:  li      t1, 5                       # register arithmetic that carries nothing over
    j       2b
"""


def spin_state(board) -> tuple:
    return tuple((hart.executed, hart.cycles, hart.mispredicts, hart.stall_cycles, hart.pc, hart.time,
                  [reg(board, name, hart.hart_id) for name in ("s5", "s6", "s7", "s8", "t1")])
                 for hart in board.harts) + (board.time,)


def count_turns(monkeypatch) -> list:
    """The scheduler's turns from the end of the lockstep at reset on (512 turns of 2 cycles while
    both harts run: shared_memory.RACE_WINDOW_CYCLES)."""
    from emulator.board import scheduler as schedmod
    turns = []
    original = schedmod.Scheduler._turn

    def turn(self, *args, **kwargs):
        if self.time >= self._race_until:
            turns.append(1)
        return original(self, *args, **kwargs)
    monkeypatch.setattr(schedmod.Scheduler, "_turn", turn)
    return turns


@pytest.mark.parametrize("engine", [ENGINE_FAST, ENGINE_PRECISE])
@pytest.mark.parametrize("source", ["timer", "both"])
def test_a_spin_that_changes_nothing_is_skipped_to_the_next_event_with_exact_counts(engine, source, monkeypatch):
    """issue 32, item 8: a hart in `1: j 1b` that nothing but an interrupt can take out of it skips
    its iterations past its turns' ends up to the next thing that can happen (a device event, here
    the timer's interrupt, or run_until's end), with the other hart asleep or spinning too, counting
    every one: instructions, cycles, the interrupts' mcycle, minstret and mepc, the times, as turn
    by turn (before, 1,300 turns a second of virtual time at 26 MHz)."""
    from emulator.board import scheduler as schedmod
    from k210_fixtures import build_elf
    elf = program(TIMER_OUT_OF_A_SPIN) if source == "timer" else build_elf(BOTH_HARTS_SPIN)
    results = []
    for beyond in (True, False):
        board = make_board(elf, engine=engine)
        turns = count_turns(monkeypatch)
        if not beyond:
            monkeypatch.setattr(schedmod.Scheduler, "_alone_until", lambda self, *a: None)
        board.run_until(1050 * PS_PER_MS)
        monkeypatch.undo()
        results.append((spin_state(board), len(turns), board.harts[0].iterations_skipped))
    (skipped, few, iterations), (turn_by_turn, many, _) = results
    assert skipped == turn_by_turn
    assert few < 100 < 500 < many
    assert iterations > 20_000_000
    if source == "timer":
        assert skipped[0][6][0] == 10                         # ten interrupts in 1.05 s
        assert skipped[0][6][3] == symbol_of(board, "spin")  # each taken out of the spin


def symbol_of(board, name: str) -> int:
    from k210_fixtures import symbol
    return symbol(board, name)


@pytest.mark.parametrize("both", [False, True])
def test_a_program_ending_in_a_spin_ends_promptly_with_the_hang_report(both, monkeypatch):
    """With nothing left to happen, a program whose last word is `j .` ends with the hang report
    (after the hang budget of virtual time) in a handful of turns, not 25,000 a virtual second."""
    from emulator.errors import HangDetected
    from emulator.vtime import PS_PER_S
    from k210_fixtures import build_elf
    board = make_board(build_elf(BOTH_HARTS_SPIN) if both else program(""))
    board.hang_budget = 5 * PS_PER_S
    turns = count_turns(monkeypatch)
    with pytest.raises(HangDetected) as stop:
        board.run(1)
    assert len(turns) < 50
    assert "hart 0: running" in str(stop.value) and "spins in a loop that changes nothing" in str(stop.value)
    assert board.harts[0].executed > 5 * 26_000_000 // 4      # its iterations counted (c.j: a few cycles each)
