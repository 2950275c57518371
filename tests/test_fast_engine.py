"""The fast engine (hart.py, _block_counter.c) against the precise one: what runs, every count and
every time must be the same; only the host time may differ.

The fast engine charges whole translated blocks, working out multiply and divide operands with a
small interpreter at the block's start, and hands the hart to the precise engine (which counts each
instruction) for device accesses, CSRs, poll loops, exceptions and turn ends. The programs here
drive those paths: operands from loads, stores, compressed and 32-bit forms of every M instruction,
division by zero and overflow, a reservation held across a hand-over; then the firmware itself.
"""
from __future__ import annotations

import json

import pytest

from conftest import run_emulator
from emulator.hart import ENGINE_FAST, ENGINE_PRECISE
from emulator.timing import TIMING_IPC1, TIMING_ROCKET
from k210_fixtures import make_board, program, reg, run_to_done

GPRS = ["ra", "sp", "gp", "tp", "t0", "t1", "t2", "s0", "s1", "a0", "a1", "a2", "a3", "a4", "a5", "a6", "a7",
        "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "t3", "t4", "t5", "t6"]

# 300 rounds of a pseudo-random walk: each round's multiplies and divides take operands loaded from
# memory (one stored the round before), built by shifts, W forms and compressed instructions, so
# that their iterative latencies vary as the values do.
MULDIV_WALK = """
    la      s0, table
    li      s1, 300
    li      s2, 0x9E3779B97F4A7C15
    li      s3, 12345
1:  mul     s3, s3, s2                # the walk
    addi    s3, s3, 7
    srli    t0, s3, 40
    andi    t0, t0, 0x38
    add     t1, s0, t0
    ld      t2, 64(t1)                # an operand from memory, stored by an earlier round
    xori    t0, t0, 8
    add     t1, s0, t0
    sd      s3, 64(t1)                # into another slot than the load's
    lw      t3, 4(s0)
    lhu     t4, 10(s0)
    lb      t5, 17(s0)
    lbu     t6, 19(s0)
    lwu     a0, 20(s0)
    lh      a1, 26(s0)
    ld      a4, 24(s0)                # compressed loads (c.ld, c.lw) with their offsets
    lw      a5, 12(s0)
    mul     a4, a4, a5
    sd      a4, 48(s0)                # and a compressed store (c.sd), loaded back next round
    ld      a3, 48(s0)
    mul     a2, t2, t3
    mulh    a3, t2, t4
    mulhsu  a4, t5, t2
    mulhu   a5, t2, s3
    div     a6, t2, t5
    divu    a7, a0, t6
    rem     s4, t2, a1
    remu    s5, t3, t4
    mulw    s6, t2, a1
    divw    s7, t3, t5
    divuw   s8, a0, t4
    remw    s9, t2, t5
    remuw   s10, a0, a1
    c.mv    s11, t2
    c.slli  s11, 3
    c.addi  s11, -5
    mul     s11, s11, s11
    lui     ra, 0x80000
    sub     ra, zero, ra
    div     ra, ra, zero              # by zero
    li      gp, -1
    slli    tp, gp, 63
    div     tp, tp, gp                # overflow
    xor     a2, a2, a3
    xor     a2, a2, a4
    xor     a2, a2, a5
    xor     a2, a2, a6
    xor     a2, a2, a7
    sd      a2, 40(s0)
    addi    s1, s1, -1
    bnez    s1, 1b
"""

# (a page of its own: a store into a page holding translated code makes QEMU translate and run the
# storing instruction again, which the counters would each see twice)
MULDIV_DATA = """
    .balign 4096
table:
    .dword 0x0123456789ABCDEF, 0xFEDCBA9876543210, 0x00000000FFFF0000, 0x8000000000000001
    .dword 0, 0, 0, 0
    .dword 1, 2, 3, 4, 5, 6, 7, 8
"""


def run_on(engine: str, source: str, data: str = "", timing: str = TIMING_ROCKET, max_time_s: float = 0.05):
    board = make_board(program(source, data=data), timing=timing, engine=engine)
    run_to_done(board, max_time_s=max_time_s)
    return board


def state(board) -> dict:
    hart = board.harts[0]
    return {"registers": [reg(board, name) for name in GPRS], "executed": hart.executed, "cycles": hart.cycles,
            "stall_cycles": hart.stall_cycles, "mispredicts": hart.mispredicts, "pc": hart.pc}


@pytest.mark.parametrize("timing", [TIMING_ROCKET, TIMING_IPC1])
def test_multiply_and_divide_operands_are_worked_out_as_the_precise_engine_reads_them(timing):
    precise = run_on(ENGINE_PRECISE, MULDIV_WALK, MULDIV_DATA, timing)
    fast = run_on(ENGINE_FAST, MULDIV_WALK, MULDIV_DATA, timing)
    assert state(fast) == state(precise)
    charged = fast.harts[0].fast_statistics()
    # the walk ran on the fast engine (not handed over throughout), its multiplies charged there
    assert charged["instructions"] > 0.9 * fast.harts[0].executed
    if timing == TIMING_ROCKET:
        assert fast.harts[0].stall_cycles > 300 * 20     # the multiplier's and divider's iterations


# An operand loaded from where the same block stored just before: the interpreter does not follow
# it (the store has not happened when the block starts), so the block is handed over each time.
STORE_THEN_LOAD = """
    la      s0, table
    li      s1, 100
1:  mul     a2, s1, s1
    sd      a2, 32(s0)
    ld      gp, 32(s0)
    mul     gp, gp, a2
    add     s2, s2, gp
    addi    s1, s1, -1
    bnez    s1, 1b
"""


def test_an_operand_the_interpreter_cannot_follow_hands_the_block_over():
    precise = run_on(ENGINE_PRECISE, STORE_THEN_LOAD, MULDIV_DATA)
    fast = run_on(ENGINE_FAST, STORE_THEN_LOAD, MULDIV_DATA)
    assert state(fast) == state(precise)
    assert fast.harts[0].fast_statistics()["instructions"] > 0.9 * fast.harts[0].executed


RESERVATION = """
    la      s0, word
    li      s1, 50
    li      s2, 0x02000000 + 0xBFF8   # CLINT mtime: a device access hands the hart over
1:  lr.d    t0, (s0)
    addi    t0, t0, 1
    lw      t1, 0(s2)
    sc.d    t2, t0, (s0)
    add     s3, s3, t2                # failed store-conditionals
    addi    s1, s1, -1
    bnez    s1, 1b
    ld      s4, 0(s0)
"""


def test_a_reservation_survives_a_hand_over_between_the_engines():
    precise = run_on(ENGINE_PRECISE, RESERVATION, ".balign 4096\nword: .dword 0")
    fast = run_on(ENGINE_FAST, RESERVATION, ".balign 4096\nword: .dword 0")
    assert reg(precise, "s3") == 0 and reg(precise, "s4") == 50
    assert state(fast) == state(precise)


TRAPS = """
    la      t0, handler
    csrw    mtvec, t0
    li      s1, 20
1:  mul     s2, s1, s1                # the fast engine runs the loop
    addi    s1, s1, -1
    bnez    s1, 1b
    mul     s2, s2, s2
    ecall                             # an exception in a block it charged whole
    addi    s4, s4, 1
    j       2f
    .balign 4
handler:
    csrr    t1, mepc
    addi    t1, t1, 4
    csrw    mepc, t1
    addi    s3, s3, 1
    mret
2:
"""


def test_exceptions_in_a_block_charged_whole_are_taken_where_the_precise_engine_takes_them():
    precise = run_on(ENGINE_PRECISE, TRAPS)
    fast = run_on(ENGINE_FAST, TRAPS)
    assert reg(precise, "s3") == 1 and reg(precise, "s4") == 1
    assert state(fast) == state(precise)
    assert fast.harts[0].retired_adjust == precise.harts[0].retired_adjust == 1


def _run_json(firmware, tmp_path, engine: str, *args: str) -> tuple[dict, dict]:
    out = tmp_path / engine
    result = run_emulator("run", str(firmware), "--out", str(out), "--quiet", "--engine", engine, *args)
    assert result.returncode == 0, result.stderr
    summary = json.loads((out / "run.json").read_text())
    frames = {p.name: p.read_bytes() for p in out.glob("frame_*.png")}
    return summary, frames


def _same(fast: dict, precise: dict) -> None:
    for key in ("instructions", "virtual_time_s", "console", "device_writes", "warnings"):
        assert fast.get(key) == precise.get(key), key
    host = ("host_time_s",)
    assert [{k: v for k, v in f.items() if k not in host} for f in fast["frames"]] == \
        [{k: v for k, v in f.items() if k not in host} for f in precise["frames"]]


def test_the_firmware_runs_alike_on_both_engines(firmware, card, tmp_path):
    fast, fast_frames = _run_json(firmware, tmp_path, ENGINE_FAST, "--sd", str(card), "--frames", "3")
    precise, precise_frames = _run_json(firmware, tmp_path, ENGINE_PRECISE, "--sd", str(card), "--frames", "3")
    _same(fast, precise)
    assert fast_frames == precise_frames and len(fast_frames) == 3


@pytest.mark.parametrize("name", ["blink", "lcd_demo"])
def test_sdk_style_programs_run_alike_on_both_engines(c_firmware, tmp_path, name):
    elf = c_firmware / f"{name}.elf"
    fast, fast_frames = _run_json(elf, tmp_path, ENGINE_FAST, "--until", "0.12")
    precise, precise_frames = _run_json(elf, tmp_path, ENGINE_PRECISE, "--until", "0.12")
    _same(fast, precise)
    assert fast_frames == precise_frames


def test_an_unknown_engine_is_refused(firmware):
    result = run_emulator("run", str(firmware), "--engine", "turbo")
    assert result.returncode == 2 and "--engine" in result.stderr
