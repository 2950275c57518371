"""The harts side by side (emulator/cpu/shared_memory.py): what one hart stores, the other sees as soon
as it would on the chip, even a flag set for a few instructions only."""
from __future__ import annotations

import pytest

from emulator.errors import HangDetected
from emulator.cpu.hart import HartState
from emulator.cpu.shared_memory import find_poll_loops
from emulator.cpu.caches import ROCKET_L1
from emulator.cpu.timing import MISPREDICT_PENALTY, REDIRECT_BUBBLE, TIMING_ROCKET_NOCACHE
from k210_fixtures import build_elf, make_board, reg, run_until, symbol

ROUNDS = 300

# Hart 0 hands hart 1 a flag ROUNDS times: it stores the round's number, keeps it there for six
# instructions, clears it and waits for hart 1's acknowledgement. Hart 1 polls the flag, adds up
# what it sees and acknowledges each round. DELAY instructions of hart 0's own work come before
# each round, so that with a long delay hart 1 is long waiting when the flag comes.
HAND_OVER = """
    .option norelax
    .equ    ROUNDS, {rounds}
    .equ    DELAY, {delay}
    .globl _start
_start:
    csrr    t0, mhartid
    la      s0, flag
    la      s1, ack
    li      s2, ROUNDS
    bnez    t0, hart1
    li      s3, 1                   # s3 = round
    csrr    s6, mcycle
1:  li      t2, DELAY
2:  beqz    t2, 3f                  # hart 0's own work
    addi    t2, t2, -1
    j       2b
3:  sw      s3, 0(s0)               # the flag, for six instructions
    nop
    nop
    nop
    nop
    nop
    sw      zero, 0(s0)
4:  lw      t1, 0(s1)               # until hart 1 acknowledges this round
    bne     t1, s3, 4b
    addi    s3, s3, 1
    ble     s3, s2, 1b
    csrr    s7, mcycle
done:
    j       done
hart1:
    li      s3, 0                   # s3 = rounds seen, s5 = sum of the flags seen
5:  lw      t1, 0(s0)               # until a flag comes
    beqz    t1, 5b
    add     s5, s5, t1
    addi    s3, s3, 1
    sw      t1, 0(s1)
6:  lw      t1, 0(s0)               # until it is gone again
    bnez    t1, 6b
    blt     s3, s2, 5b
hart1_done:
    j       hart1_done
    .data
    .balign 8
flag:   .word 0
ack:    .word 0
"""


def hand_over_board(delay: int):
    board = make_board(build_elf(HAND_OVER.format(rounds=ROUNDS, delay=delay)))
    run_until(board, lambda b: b.harts[0].pc == symbol(b, "done") and b.harts[1].pc == symbol(b, "hart1_done"),
              max_time_s=0.1, max_steps=200_000)
    return board


@pytest.mark.parametrize("delay", [0, 1000])
def test_a_flag_set_for_six_instructions_is_seen_every_time(delay):
    """Before: turns of 20,000 instructions; hart 0 set and cleared the flag within one of its turns,
    hart 1 never saw it, and both waited for each other for ever. Now hart 1 sees every round: in
    lockstep right after a hand-over, and, waiting on the flag long before it comes (delay), woken by
    the store itself."""
    board = hand_over_board(delay)
    assert reg(board, "s3", hart=1) == ROUNDS
    assert reg(board, "s5", hart=1) == ROUNDS * (ROUNDS + 1) // 2       # each round once, in order
    # as soon as on the chip: a round costs hart 0 its own work (3 cycles a step), the six cycles of
    # the flag and a few for the acknowledgement (13 in all), not a turn; the Rocket timing adds the
    # mispredicted exits of the delay and acknowledgement loops and the latter's load-use stall, and
    # the caches the line of flag and acknowledgement moving between the harts (caches.py): each of
    # hart 0's two stores of the flag needs write permission back from hart 1, which read the line
    # meanwhile, and its load of the acknowledgement misses once or twice, waiting for hart 1's
    # write-back: at most four misses a round, each with a write-back; and the frontend, a cycle where
    # a jump or branch taken leads to a 4-byte instruction 2 mod 4 (with DELAY 1000 the delay loop's
    # head each step and two other targets a round; with 0 the acknowledgement loop's head each time
    # round: a few)
    per_round = (reg(board, "s7", hart=0) - reg(board, "s6", hart=0)) / ROUNDS
    coherence = 4 * (ROCKET_L1.data_fill + ROCKET_L1.write_back)
    fetch = REDIRECT_BUBBLE * (delay + 3)
    assert per_round <= 3 * delay + 16 + 2 * MISPREDICT_PENALTY + 1 + coherence + fetch, per_round


def test_a_hart_waiting_on_sram_costs_no_instructions():
    """Hart 1 waits on the flag while hart 0 works: it is stalled, not spinning, so its instruction
    count stays small however long hart 0 takes."""
    board = hand_over_board(1000)
    # per round: the two poll loops come round a few times before they wait, plus the round's own work
    assert board.harts[1].instret < 20 * ROUNDS, board.harts[1].instret
    assert board.harts[0].instret > 3 * 1000 * ROUNDS


POLL_NOTHING_CHANGES = """
    .option norelax
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, park
    la      s0, flag
1:  lw      t1, 0(s0)
    beqz    t1, 1b
done:
    j       done
park:
    csrw    mie, zero
2:  wfi
    j       2b
    .data
    .balign 8
flag:   .word 0
"""


def test_polling_memory_nothing_will_change_is_a_hang_that_says_so():
    board = make_board(build_elf(POLL_NOTHING_CHANGES))
    with pytest.raises(HangDetected) as info:
        run_until(board, lambda b: False, max_time_s=1.0)
    report = str(info.value)
    assert "no hart runs: every hart sleeps in wfi or polls memory that nothing will change" in report
    flag = symbol(board, "flag")
    assert (f"hart 0: polling memory (waits for another hart or a DMA write to change 0x{flag:08x} "
            f"(4 bytes, 00000000))") in report
    assert board.harts[0].state is HartState.WAITING


# Hart 0 polls a flag in SRAM with the machine timer interrupt enabled; the handler sets the flag.
POLL_WITH_AN_INTERRUPT = """
    .option norelax
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, park
    la      t0, handler
    csrw    mtvec, t0
    li      t0, 0x0200BFF8
    ld      t1, 0(t0)
    addi    t1, t1, 1000                # 1000 ticks = 50,000 cycles from now
    li      t0, 0x02004000
    sd      t1, 0(t0)
    li      t0, 1 << 7                  # MTIE
    csrw    mie, t0
    csrsi   mstatus, 8                  # MIE
    la      s0, flag
1:  lw      t1, 0(s0)
    beqz    t1, 1b
    csrr    s8, minstret
done:
    j       done
    .balign 4
handler:
    li      t0, 1
    sw      t0, 0(s0)
    li      t0, -1
    li      t1, 0x02004000
    sd      t0, 0(t1)                   # no further timer interrupt
    csrr    s9, mcycle
    mret
park:
    csrw    mie, zero
2:  wfi
    j       2b
    .data
    .balign 8
flag:   .word 0
"""


def test_an_interrupt_reaches_a_hart_waiting_on_sram():
    board = make_board(build_elf(POLL_WITH_AN_INTERRUPT))
    run_until(board, lambda b: b.harts[0].pc == symbol(b, "done"), max_time_s=0.01)
    assert reg(board, "s9") >= 50_000                       # the handler ran when the timer fired
    assert reg(board, "s8") < 200                            # and the poll loop waited, not spun


@pytest.mark.parametrize("source, polls", [
    ("1: lw t1, 0(s0)\n beqz t1, 1b", True),
    ("1: lw t1, 0(s0)\n andi t1, t1, 4\n beqz t1, 1b", True),
    ("1: ld t1, 8(s0)\n lw t2, 0(t1)\n bne t2, a1, 1b", True),     # through a pointer it also reads
    ("1: c.lw a5, 0(a0)\n c.beqz a5, 1b", True),
    ("1: lw t1, 0(s0)\n addi t2, t2, 1\n beqz t1, 1b", False),     # counts: iterations differ
    ("1: lw t1, 0(s0)\n sw t1, 4(s0)\n beqz t1, 1b", False),       # stores
    ("1: addi t0, t0, -1\n bnez t0, 1b", False),                   # reads no memory
    ("1: lw t1, 0(s0)\n csrr t2, mcycle\n beqz t1, 1b", False),    # reads a CSR
])
def test_which_loops_can_only_be_polling(source, polls):
    elf = build_elf(".option norelax\n.globl _start\n_start:\n" + source + "\n")
    from emulator.board.elf import load_elf
    from emulator.board.memory import Sram
    image = load_elf(elf, Sram(fill_seed=None))
    loops = [loop for address, code in image.code_ranges for loop in find_poll_loops(code, address)]
    assert bool(loops) is polls


# FreeRTOS's cross-core critical section, as LoBo's MicroPython runs it on both cores: hart 0 takes a
# spinlock (spin while it is held, then amoswap), raises a request, releases the lock and waits for
# the request to be served; hart 1 takes the same lock to serve it, then goes about its own work
# (WORK instructions) and comes back to the lock. Each hart leaves the lock's poll loop and comes
# back to it many times.
SPINLOCK = """
    .option norelax
    .equ    ROUNDS, {rounds}
    .equ    WORK, {work}
    .globl _start
_start:
    csrr    t0, mhartid
    la      s0, lock
    la      s1, request
    li      s2, ROUNDS
    li      a1, -1
    bnez    t0, hart1
    li      s3, 0
1:  call    take
    li      t1, 1
    sw      t1, 0(s1)               # the request
    fence
    sw      zero, 0(s0)             # release
2:  lw      t1, 0(s1)               # until hart 1 has served it
    bnez    t1, 2b
    addi    s3, s3, 1
    blt     s3, s2, 1b
done:
    j       done
hart1:
    li      s3, 0
3:  call    take
    lw      t1, 0(s1)
    beqz    t1, 4f
    sw      zero, 0(s1)             # served
    addi    s3, s3, 1
4:  fence
    sw      zero, 0(s0)             # release
    li      t2, WORK
5:  addi    t2, t2, -1
    bnez    t2, 5b
    blt     s3, s2, 3b
hart1_done:
    j       hart1_done
take:
6:  lw      t1, 0(s0)               # while it is held
    bnez    t1, 6b
    mv      t1, a1
    amoswap.w.aq t1, t1, (s0)
    bnez    t1, 6b
    ret
    .data
    .balign 8
lock:    .word 0
request: .word 0
"""


@pytest.mark.parametrize("work", [3, 40, 400])
def test_harts_taking_turns_at_a_spinlock_never_lose_a_wake_up(work):
    """Hart 1 came back to the lock's poll loop, and the model took its last look at the lock, from
    when it left the loop the time before, as if it were one iteration ago: it waited on a lock
    already free, while hart 0 waited for it, for ever.
    Without the caches (rocket-nocache): with them, hart 0's look at the lock misses (the line is in
    hart 1's cache, dirty) and takes longer than hart 1's three instructions of work, so hart 1 takes
    the lock back every time and hart 0 starves, as it would on a chip with those latencies: the
    lock is not fair. What is tested here is that no wake-up is lost."""
    board = make_board(build_elf(SPINLOCK.format(rounds=ROUNDS, work=work)), timing=TIMING_ROCKET_NOCACHE)
    run_until(board, lambda b: b.harts[0].pc == symbol(b, "done") and b.harts[1].pc == symbol(b, "hart1_done"),
              max_time_s=0.2, max_steps=400_000)
    assert reg(board, "s3", hart=0) == ROUNDS and reg(board, "s3", hart=1) == ROUNDS


WOKEN_MID_TURN = """
    .option norelax
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, hart1
    li      t3, 50000                   # past the harts' lockstep at reset
2:  addi    t3, t3, -1
    bnez    t3, 2b
    li      t1, 0x02000004              # CLINT msip[1]: wake hart 1 ...
    li      t2, 1
    sw      t2, 0(t1)
    li      t3, 2000000                 # ... and compute on for many turns
1:  addi    t3, t3, -1
    bnez    t3, 1b
done:
    j       done
hart1:
    li      t0, 8                       # MSIE
    csrw    mie, t0
    wfi
    li      t1, 0x02000004
    sw      zero, 0(t1)
    li      t2, 0x0200BFF8              # mtime
    ld      t3, 0(t2)
    addi    t3, t3, 6                   # 6 ticks: 300 cycles
    li      t4, 0x02004008              # mtimecmp[1]
    sd      t3, 0(t4)
    li      t0, 0x80                    # MTIE
    csrw    mie, t0
    csrr    s0, mcycle
    wfi
    csrr    s1, mcycle
    sub     s2, s1, s0
hart1_done:
    j       hart1_done
"""


def test_a_hart_woken_mid_turn_wakes_at_its_timer_not_at_the_others_turn_end():
    """Hart 0 wakes hart 1 early in a turn of 20,000 cycles and computes on; hart 1 sets a timer
    300 cycles ahead and sleeps. It wakes when mtime reaches mtimecmp, though hart 0's turn runs on
    far past that (Scheduler._catch_up_to): the firmware's 10 us LCD reset pulse lasted 48 us
    when the sleeper woke at the board's time, the end of the other hart's turn."""
    board = make_board(build_elf(WOKEN_MID_TURN))
    run_until(board, lambda b: b.harts[1].pc == symbol(b, "hart1_done"), max_time_s=0.2)
    assert 250 <= reg(board, "s2", hart=1) <= 320      # 6 ticks from within the tick mtime read
