"""The fast engine (hart.py, _fast_engine.c) against the precise one: what runs, every register,
count and time must be the same; only the host time may differ.

The fast engine interprets the code in SRAM itself, counting and timing each instruction as the
precise engine's counter does, and hands the hart to the precise engine (Unicorn) for device
accesses, CSRs, atomics, exceptions and floating point it leaves to QEMU's rules (NaN operands,
other rounding modes). The programs here drive those paths: multiply and divide operands from loads
and stores, compressed and 32-bit forms, division by zero and overflow, a reservation held across a
hand-over, exceptions, random integer and floating-point instructions over the values where the
arithmetic has its corner cases; then the firmware itself and two SDK-style C programs.
"""
from __future__ import annotations

import json

import pytest

from suite import GOLDEN_FRAMES, run_emulator
from both_engines import (COMPARE, DOUBLE_VALUES, FPU_ON, IMMEDIATE_OPS, INTEGER_OPS, INTEGER_VALUES, LOADS, ROUNDED,
                          ROUNDING, SHIFT_OPS, SINGLE_VALUES, STORES, THREE, TWO, fp_state, run_on, run_on_both, state)
from emulator.frontends.options import build_parser
from emulator.errors import FirmwareTrap
from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE, Hart
from emulator.cpu.timing import TIMING_IPC1, TIMING_ROCKET, TIMING_ROCKET_NOCACHE
from emulator.vtime import PS_PER_MS
from k210_fixtures import RecordingDevice, at_done, make_board, program, reg, run_until, symbol

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


@pytest.mark.parametrize("timing", [TIMING_ROCKET, TIMING_IPC1])
def test_multiply_and_divide_operands_are_worked_out_as_the_precise_engine_reads_them(timing):
    precise, fast = run_on_both(MULDIV_WALK, MULDIV_DATA, timing)
    assert state(fast) == state(precise)
    charged = fast.harts[0].fast_statistics()
    # the walk ran on the fast engine (not handed over throughout), its multiplies timed there
    assert charged["instructions"] > 0.9 * (fast.harts[0].executed - fast.harts[0].iterations_skipped)
    if timing == TIMING_ROCKET:
        assert fast.harts[0].stall_cycles > 300 * 20     # the multiplier's and divider's iterations


# Transfers, taken or not, predicted or not, whose next instruction the fast engine hands over (a CSR
# read, an AMO, a CSR at a call's target and at a return's): the fast engine resolves a transfer as soon
# as the next instruction is sure to start, and a penalty it has not charged yet goes with the hart to
# the precise engine, which must charge it at that instruction as if it had resolved the transfer itself.
TRANSFER_THEN_HAND_OVER = """
    la      s0, table
    li      s1, 400
    li      s2, 0x9E3779B97F4A7C15
    li      s3, 12345
1:  mul     s3, s3, s2
    addi    s3, s3, 7
    srli    t0, s3, 61
    andi    t1, t0, 1
    beqz    t1, 2f                    # taken half the time, at random: mispredicted often
    csrr    t2, mcycle                # not taken: the next instruction is the precise engine's
    add     s4, s4, t2
2:  amoadd.d zero, t0, (s0)           # taken: the target is
    andi    t1, t0, 2
    bnez    t1, 3f
    jal     ra, 4f                    # a call whose target is a CSR read
3:  addi    s1, s1, -1
    bnez    s1, 1b
    j       5f
4:  csrr    t3, minstret
    add     s5, s5, t3
    ret                               # and a return to a branch
5:
"""


@pytest.mark.parametrize("timing", [TIMING_ROCKET, TIMING_ROCKET_NOCACHE])
def test_a_transfer_resolved_before_a_hand_over_is_charged_as_the_precise_engine_charges_it(timing):
    precise, fast = run_on_both(TRANSFER_THEN_HAND_OVER, MULDIV_DATA, timing)
    assert state(fast) == state(precise)
    assert fast.harts[0].mispredicts > 100
    assert fast.harts[0].fast_statistics()["handoffs"] > 100


# A multiply's operand loaded from where the instruction before stored it: its latency must be
# worked out from the value the load sees.
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


def test_an_operand_stored_just_before_is_the_one_timed():
    precise, fast = run_on_both(STORE_THEN_LOAD, MULDIV_DATA)
    assert state(fast) == state(precise)
    assert fast.harts[0].fast_statistics()["instructions"] > 0.9 * (fast.harts[0].executed - fast.harts[0].iterations_skipped)


# lr.d hands the hart to the precise engine, which runs it and a few more; the fast engine runs the
# rest of the additions up to sc.d, which it hands back: the reservation is held across both
# hand-overs. (The precise engine's stretch after sc.d ends at lr.d, which the fast engine hands
# over at once, so the stretch from lr.d is twice PRECISE_STRETCH: there are more additions.)
RESERVATION = """
    la      s0, word
    li      s1, 50
1:  lr.d    t0, (s0)
    addi    t0, t0, 1
    addi    t3, t3, 1
    addi    t4, t4, 1
    addi    t5, t5, 1
    addi    t6, t6, 1
    addi    a0, a0, 1
    addi    a1, a1, 1
    addi    a2, a2, 1
    addi    a3, a3, 1
    addi    a4, a4, 1
    addi    a5, a5, 1
    addi    a6, a6, 1
store_conditional:
    sc.d    t2, t0, (s0)
    add     s3, s3, t2                # failed store-conditionals
    addi    s1, s1, -1
    bnez    s1, 1b
    ld      s4, 0(s0)
"""


def test_a_reservation_survives_a_hand_over_between_the_engines(monkeypatch):
    precise, _ = run_on_both(RESERVATION, ".balign 4096\nword: .dword 0")
    assert reg(precise, "s3") == 0 and reg(precise, "s4") == 50
    starts = []
    run_precise = Hart._run_precise

    def recording(hart, pc):
        starts.append(pc)
        run_precise(hart, pc)
    monkeypatch.setattr(Hart, "_run_precise", recording)
    fast = run_on(ENGINE_FAST, RESERVATION, ".balign 4096\nword: .dword 0")
    assert state(fast) == state(precise)
    # the fast engine ran the additions up to sc.d after lr.d's precise run, in most of the 50
    # iterations (38 seen; the first ones run while the stretch settles, some across turn ends)
    assert starts.count(symbol(fast, "store_conditional")) >= 30


# A loop around an instruction the fast engine hands over (a hart spinning on a lock's lr.w while
# the other holds it), then a loop it runs itself.
SPIN = """
    la      s0, word
    li      s1, 20000
1:  lr.w    t0, (s0)
    addi    s1, s1, -1
    bnez    s1, 1b
    li      s2, 20000
2:  addi    s3, s3, 3
    addi    s2, s2, -1
    bnez    s2, 2b
"""


def test_a_loop_handing_over_each_round_stays_on_the_precise_engine_until_it_ends():
    """The precise engine's stretch grows while the fast engine runs next to nothing between hand-
    overs (each precise run costs tens of microseconds: one every few instructions made an error
    run's spinning hart 1 take 10 s), and shrinks again once the fast engine has code to run."""
    precise = run_on(ENGINE_PRECISE, SPIN, ".balign 4096\nword: .dword 0")
    fast = run_on(ENGINE_FAST, SPIN, ".balign 4096\nword: .dword 0")
    assert reg(precise, "s3") == 60000
    assert state(fast) == state(precise)
    assert fast.harts[0].precise_runs < 100       # about 10,000 with a stretch of 4 each time
    assert fast.harts[0].fast_statistics()["instructions"] > 0.9 * 60000   # the second loop


TRAPS = """
    la      t0, handler
    csrw    mtvec, t0
    li      s1, 20
1:  mul     s2, s1, s1                # the fast engine runs the loop
    addi    s1, s1, -1
    bnez    s1, 1b
    mul     s2, s2, s2
    ecall                             # an exception right after instructions the fast engine ran
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


def test_exceptions_are_taken_where_the_precise_engine_takes_them():
    precise, fast = run_on_both(TRAPS)
    assert reg(precise, "s3") == 1 and reg(precise, "s4") == 1
    assert state(fast) == state(precise)
    assert fast.harts[0].retired_adjust == precise.harts[0].retired_adjust == 1


# Device loads and stores of every width and extension, compressed and not: the fast engine carries
# them out itself (the bus answering while it holds the registers), the narrow and 64-bit ones with
# the bus's warnings naming the instruction (its pc is the fast engine's then).
DEVICE_ACCESSES = """
    li      s0, 0x02004000            # CLINT mtimecmp0: a 64-bit register, narrow accesses allowed
    li      t0, 0x8182838485868788
    sd      t0, 0(s0)
    c.ld    a0, 0(s0)                 # compressed (2-byte): the engine goes on after it
    ld      t3, 0(s0)
    lw      a1, 4(s0)
    lwu     a2, 4(s0)
    lh      a3, 6(s0)
    lhu     a4, 2(s0)
    lb      a5, 7(s0)
    lbu     a6, 5(s0)
    li      t1, 0x7F
    sb      t1, 7(s0)                 # narrow stores covering no whole field (warnings)
    sh      t1, 0(s0)
    sw      t1, 4(s0)
    ld      a7, 0(s0)
    c.sw    a1, 0(s0)
    c.lw    s1, 0(s0)
    ld      s6, 0(s0)
    li      t4, 0x0C000008            # PLIC priorities 2 and 3: 32-bit registers
    li      t2, 0x0000000500000003
    sd      t2, 0(t4)                 # a 64-bit store: two 32-bit ones (a warning)
    ld      s2, 0(t4)                 # likewise
    lb      s3, 4(t4)                 # a narrow load of a 32-bit register (a warning)
    li      t0, -1
    sd      t0, 0(s0)                 # mtimecmp back to no interrupt
"""


@pytest.mark.parametrize("timing", [TIMING_ROCKET_NOCACHE, TIMING_ROCKET])
def test_device_accesses_are_carried_out_by_the_fast_engine_as_by_the_precise_one(timing):
    precise, fast = run_on_both(DEVICE_ACCESSES, timing=timing)
    assert reg(precise, "a0") == reg(precise, "t3") == 0x8182838485868788
    assert reg(precise, "a1") == 2**64 - 2**32 + 0x81828384 and reg(precise, "a2") == 0x81828384
    assert reg(precise, "a3") == 2**64 - 0x10000 + 0x8182 and reg(precise, "a4") == 0x8586
    assert reg(precise, "a5") == 2**64 - 0x7F and reg(precise, "a6") == 0x83
    # the byte and halfword stores cover no whole 32-bit field of mtimecmp: the router ignores them
    assert reg(precise, "a7") == 0x0000007F85868788 and reg(precise, "s1") == 2**64 - 2**32 + 0x81828384
    assert reg(precise, "s6") == 0x0000007F81828384
    assert reg(precise, "s2") == 0x0000000500000003 and reg(precise, "s3") == 5
    assert state(fast) == state(precise)
    assert fast.warnings == precise.warnings and len(precise.warnings) == 9
    assert "(lb s3, 4(t4)): load of 1 bytes at 0x0c00000c" in precise.warnings[-1]
    assert fast.harts[0].cycles == precise.harts[0].cycles
    # every access by the fast engine; with the caches and the devices' round trips, the first
    # instructions' misses make the first turns (the harts side by side from reset) long enough for
    # the precise engine's stretch after the FPU's CSR write to carry out the first one
    assert fast.harts[0].device_accesses == (20 if timing == TIMING_ROCKET_NOCACHE else 19)
    assert precise.harts[0].device_accesses == 0
    assert fast.bus.device_writes == precise.bus.device_writes


# RECEIVE_100's poll loop slowed to about a third of a frame's time an iteration: rxflr changes
# between its reads before they count as polling
SLOW_POLL = ("1:  lw      t1, 0x24(s1)", """1:  li      t3, 50
2:  addi    t3, t3, -1
    bnez    t3, 2b
    lw      t1, 0x24(s1)""")


@pytest.mark.parametrize("program_name", ["SEND_AND_WAIT", "RECEIVE_100", "SLOW_POLL"])
def test_a_polled_status_register_is_answered_by_the_fast_engine_as_by_the_bus(program_name):
    """A program polling SPI1's status while frames go out (sr) or come in (rxflr): after the first
    read the fast engine answers the same read again itself while the bus says the register cannot
    change, counting the reads as polls as the scheduler does; everything stays the precise engine's."""
    import spi_programs
    if program_name == "SLOW_POLL":
        source = spi_programs.RECEIVE_100.replace(*SLOW_POLL)
        assert source != spi_programs.RECEIVE_100
    else:
        source = getattr(spi_programs, program_name)
    results = {}
    for engine in (ENGINE_PRECISE, ENGINE_FAST):
        board = make_board(program(FPU_ON + source, data="buffer: .space 128\n"), engine=engine, quantum=2000)
        device = RecordingDevice(bytes(range(100)))
        board.spi1.device_for_ss = lambda ss, device=device: device if ss == 0 else None
        answered = []
        hart = board.harts[0]
        if hart._repeats_answered is not None:
            report = hart._repeats_answered
            hart._repeats_answered = lambda *args: (answered.append(args[4]), report(*args))
        run_until(board, at_done, max_time_s=0.002)
        results[engine] = (state(board), bytes(device.received), board.memory.read(symbol(board, "buffer"), 100),
                           board.scheduler.time)
        if engine == ENGINE_FAST:
            assert answered, "the fast engine answered no read itself"
    assert results[ENGINE_FAST] == results[ENGINE_PRECISE]


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
    host = ("host_time_s", "host_cpu_s")
    assert [{k: v for k, v in f.items() if k not in host} for f in fast["frames"]] == \
        [{k: v for k, v in f.items() if k not in host} for f in precise["frames"]]


def test_the_firmware_runs_alike_on_both_engines(firmware, card, firmware_run, tmp_path):
    """The shared run of the default card (firmware_run) is the fast engine's, the default."""
    assert build_parser().parse_args(["run", str(firmware)]).engine == ENGINE_FAST
    result, out, fast = firmware_run
    assert result.returncode == 0, result.stderr
    fast_frames = {p.name: p.read_bytes() for p in out.glob("frame_*.png")}
    precise, precise_frames = _run_json(firmware, tmp_path, ENGINE_PRECISE, "--sd", str(card),
                                        "--frames", str(GOLDEN_FRAMES))
    _same(fast, precise)
    assert fast_frames == precise_frames and len(fast_frames) == GOLDEN_FRAMES


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


# --- floating point at the extremes: the fast engine computes on the host's FPU, the precise one with
# QEMU's softfloat; every result, flag and register must be the same. The operands are the values
# where IEEE arithmetic and the RISC-V rules have their corner cases (both_engines.py).


def _fp_walk(seed: int, length: int) -> tuple[str, str]:
    """A program of `length` random floating-point instructions over both_engines.py's values, each
    result folded into a checksum (s0) and fflags read now and then (a CSR: the precise engine reads
    what the fast one left), with frm changed on the way; and its data."""
    import random
    rng = random.Random(seed)
    lines = ["    la      s1, singles", "    la      s2, doubles", "    la      s3, integers", "    li      t0, 0x6000",
             "    csrs    mstatus, t0"]
    for n in range(32):   # f0..f31: singles (NaN-boxed) and doubles
        if n % 2:
            lines.append(f"    fld     f{n}, {8 * rng.randrange(len(DOUBLE_VALUES))}(s2)")
        else:
            lines.append(f"    flw     f{n}, {4 * rng.randrange(len(SINGLE_VALUES))}(s1)")
    for step in range(length):
        fmt = rng.choice("sd")
        rd, r1, r2, r3 = (rng.randrange(32) for _ in range(4))
        kind = rng.randrange(14)
        rm = rng.choice(ROUNDING)
        if kind < 4:
            op = rng.choice(TWO)
            suffix = f", {rm}" if op in ROUNDED else ""
            lines.append(f"    {op}.{fmt} f{rd}, f{r1}, f{r2}{suffix}")
        elif kind < 6:
            lines.append(f"    {rng.choice(THREE)}.{fmt} f{rd}, f{r1}, f{r2}, f{r3}, {rm}")
        elif kind == 6:
            lines.append(f"    fsqrt.{fmt} f{rd}, f{r1}, {rm}")
        elif kind == 7:
            lines.append(f"    {rng.choice(COMPARE)}.{fmt} t1, f{r1}, f{r2}")
            lines.append("    add     s0, s0, t1")
        elif kind == 8:
            target = rng.choice(["w", "wu", "l", "lu"])
            lines.append(f"    fcvt.{target}.{fmt} t1, f{r1}, {rm}")
            lines.append("    xor     s0, s0, t1")
        elif kind == 9:
            source = rng.choice(["w", "wu", "l", "lu"])
            lines.append(f"    ld      t1, {8 * rng.randrange(len(INTEGER_VALUES))}(s3)")
            exact = fmt == "d" and source in ("w", "wu")    # exact: the assembler takes no rounding mode
            lines.append(f"    fcvt.{fmt}.{source} f{rd}, t1" + ("" if exact else f", {rm}"))
        elif kind == 10:
            lines.append(f"    fcvt.s.d f{rd}, f{r1}, {rm}" if fmt == "s" else f"    fcvt.d.s f{rd}, f{r1}")
        elif kind == 11:
            lines.append(f"    fclass.{fmt} t1, f{r1}")
            lines.append("    add     s0, s0, t1")
        elif kind == 12:
            lines.append(f"    ld      t1, {8 * rng.randrange(len(INTEGER_VALUES))}(s3)")
            lines.append(f"    fmv.{'w' if fmt == 's' else 'd'}.x f{rd}, t1")
        else:
            lines.append(f"    fsrmi   {rng.choice([0, 0, 0, 1, 2, 3, 4])}")   # the dynamic rounding mode
        lines.append(f"    fmv.x.d t2, f{rd}")
        lines.append("    slli    t3, s0, 7")
        lines.append("    srli    s0, s0, 57")
        lines.append("    or      s0, s0, t3")
        lines.append("    xor     s0, s0, t2")
        if step % 16 == 15:
            lines.append("    frflags t4")
            lines.append("    add     s4, s4, t4")
    lines.append("    frcsr   s5")
    data = ("singles: .word " + ", ".join(f"0x{v:08x}" for v in SINGLE_VALUES) + "\n    .balign 8\n"
            "doubles: .dword " + ", ".join(f"0x{v:016x}" for v in DOUBLE_VALUES) + "\n"
            "integers: .dword " + ", ".join(str(v) for v in INTEGER_VALUES) + "\n")
    return "\n".join(lines) + "\n", ".balign 4096\n" + data


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_floating_point_at_the_extremes_is_the_precise_engines(seed):
    source, data = _fp_walk(seed, 700)
    precise, fast = run_on_both(source, data)
    assert fp_state(fast) == fp_state(precise)
    # most of it ran on the fast engine: the operands are special, not mostly NaNs
    assert fast.harts[0].fast_statistics()["instructions"] > 0.5 * (fast.harts[0].executed - fast.harts[0].iterations_skipped)


def _integer_walk(seed: int, length: int) -> tuple[str, str]:
    """Random RV64I/M instructions (the assembler picks compressed forms where it can) on the integer
    values of both_engines.py, loads and stores of every width (some misaligned: they trap, as on
    Rocket, and the handler folds mcause and mtval into the checksum and skips them), branches over
    one instruction, each result folded into a checksum (s0)."""
    import random
    rng = random.Random(seed)
    pool = ["a0", "a1", "a2", "a3", "a4", "a5", "s2", "s3", "s4", "s5", "t3", "t4", "zero"]
    lines = ["    la      t5, skip_misaligned", "    csrw    mtvec, t5",
             "    la      s1, integers", "    la      s6, scratch"]
    for name in pool[:-1]:
        lines.append(f"    ld      {name}, {8 * rng.randrange(len(INTEGER_VALUES))}(s1)")
    for step in range(length):
        rd, r1, r2 = rng.choice(pool), rng.choice(pool), rng.choice(pool)
        kind = rng.randrange(8)
        if kind < 3:
            lines.append(f"    {rng.choice(INTEGER_OPS)} {rd}, {r1}, {r2}")
        elif kind == 3:
            lines.append(f"    {rng.choice(IMMEDIATE_OPS)} {rd}, {r1}, {rng.randrange(-2048, 2048)}")
        elif kind == 4:
            op, width = rng.choice(SHIFT_OPS)
            lines.append(f"    {op} {rd}, {r1}, {rng.randrange(width)}")
        elif kind == 5:
            op, width = rng.choice(LOADS)
            offset = rng.randrange(0, 56) if rng.random() < 0.1 else width * rng.randrange(0, 56 // width)
            lines.append(f"    {op} {rd}, {offset}(s6)")
        elif kind == 6:
            op, width = rng.choice(STORES)
            offset = rng.randrange(0, 56) if rng.random() < 0.1 else width * rng.randrange(0, 56 // width)
            lines.append(f"    {op} {r1}, {offset}(s6)")
        else:
            branch = rng.choice(["beq", "bne", "blt", "bge", "bltu", "bgeu"])
            lines.append(f"    {branch} {r1}, {r2}, 1f")
            lines.append(f"    xori {rd}, {r1}, 0x5a5")
            lines.append("1:")
        lines.append("    slli    t1, s0, 5")
        lines.append("    srli    s0, s0, 59")
        lines.append("    or      s0, s0, t1")
        lines.append(f"    xor     s0, s0, {rd}")
    lines.append("    j       1f")
    lines.append(SKIP_MISALIGNED)
    lines.append("1:")
    data = ("integers: .dword " + ", ".join(str(v) for v in INTEGER_VALUES) + "\n"
            "scratch: .dword 0x0123456789ABCDEF, -1, 0, 0x8000000000000000, 42, 7, 0x7FFFFFFF, 0\n")
    return "\n".join(lines) + "\n", ".balign 4096\n" + data


# The walk's trap handler: folds mcause and mtval into the checksum and returns past the access
# (2 or 4 bytes long)
SKIP_MISALIGNED = """
    .balign 4
skip_misaligned:
    csrr    t5, mcause
    add     s0, s0, t5
    csrr    t5, mtval
    xor     s0, s0, t5
    csrr    t5, mepc
    lhu     t6, 0(t5)
    andi    t6, t6, 3
    addi    t5, t5, 2
    li      t0, 3
    bne     t6, t0, 2f
    addi    t5, t5, 2
2:  csrw    mepc, t5
    mret
"""


@pytest.mark.parametrize("seed", [1, 2])
def test_integer_instructions_at_the_extremes_are_the_precise_engines(seed):
    source, data = _integer_walk(seed, 1500)
    precise, fast = run_on_both(source, data)
    assert state(fast) == state(precise)
    taken = precise.scheduler.traps.taken
    assert taken.get("load address misaligned", 0) + taken.get("store address misaligned", 0) > 10
    assert fast.scheduler.traps.taken == taken
    assert fast.harts[0].fast_statistics()["instructions"] > 0.8 * (fast.harts[0].executed - fast.harts[0].iterations_skipped)


# A routine on a page of its own, patched between calls: the first call adds 1, the patched one 5
# (an addi's immediate rewritten), as a loader or a debugger would change code.
PATCHED_CODE = """
    la      s0, patched
    li      s2, 3
1:  jal     patched
    jal     patched
    lw      t0, 0(s0)
    li      t1, 0x00400000            # the immediate field's bit for +4 more
    add     t0, t0, t1
    sw      t0, 0(s0)
    fence.i                           # (the precise engine runs it and a few more: then the fast one)
    li      t2, 50
3:  addi    t2, t2, -1
    bnez    t2, 3b
    addi    s2, s2, -1
    bnez    s2, 1b
    j       2f
    .balign 4096
    .option push
    .option norvc                     # a 32-bit addi, whose immediate is bits 31..20
patched:
    addi    s3, s3, 1
    ret
    .option pop
    .balign 4096
2:
"""


@pytest.mark.parametrize("fence", [True, False], ids=["with fence.i", "without"])
def test_code_written_after_it_ran_runs_as_written(fence):
    # without fence.i the fast engine runs it all in one call: its own store into decoded code is
    # what makes it compare the routine's code again (QEMU sees the store to a translated page)
    source = PATCHED_CODE if fence else PATCHED_CODE.replace("    fence.i ", "    # no fence.i ")
    precise, fast = run_on_both(source)
    assert reg(precise, "s3") == 2 * (1 + 5 + 9)
    assert state(fast) == state(precise)
    if not fence:
        assert fast.harts[0].fast_statistics()["handoffs"] == 2    # FPU_ON's two CSR instructions only


# A store into the code just after a branch not taken, in the same block of the fast engine (QEMU
# ends its translated block at the branch, so it runs the stored instruction): the store and the
# branch end one page, the patched instruction begins the next, untranslated yet.
PATCHED_AFTER_A_BRANCH = """
    la      s0, patched_site
    lw      t1, 0(s0)
    li      t0, 0x06300000            # the addi's immediate 1 -> 100 (0x064 - 0x001 in bits 31..20)
    add     t1, t1, t0
    li      t2, 0
    j       store
    .option push
    .option norvc
    .balign 4096
    .skip   4096 - 8
store:
    sw      t1, 0(s0)
    bnez    t2, 1f                    # not taken
patched_site:
    addi    s3, s3, 1
    .option pop
1:
"""


def test_code_stored_after_a_branch_not_taken_runs_as_stored():
    precise, fast = run_on_both(PATCHED_AFTER_A_BRANCH)
    assert reg(precise, "s3") == 100
    assert state(fast) == state(precise)



# Long enough for the scheduler's turns alone (hart 1 sleeps in wfi): their float arithmetic must not
# reach the guest's fflags
LONG_LOOP = """
    li      s1, 100000
1:  addi    s2, s2, 3
    addi    s1, s1, -1
    bnez    s1, 1b
"""


def test_the_turns_alone_leave_the_guests_flags_alone():
    boards = []
    for engine in (ENGINE_PRECISE, ENGINE_FAST):
        board = make_board(program(FPU_ON + LONG_LOOP), engine=engine)
        turns_alone = []
        run_alone = board.harts[0].run_alone
        board.harts[0].run_alone = lambda plan: (turns_alone.append(plan), run_alone(plan))
        board.run_until(20 * PS_PER_MS)      # (the scheduler's own run: stepping keeps single turns)
        boards.append(board)
    precise, fast = boards
    assert turns_alone, "no turns alone"
    assert state(fast) == state(precise) and state(fast)["fflags"] == 0


# Five bytes to the console, then a loop long enough for many turns alone while they go out at
# 115,200 baud (about 87 us each, some 20,000 cycles), then what AFTER_THE_LOOP says
PRINT_THEN_LOOP = """
    li      t0, 0x38000000          # UARTHS txdata (the mask ROM left the transmitter on)
    la      t2, text
1:  lbu     t1, 0(t2)
    beqz    t1, 2f
    sw      t1, 0(t0)
    addi    t2, t2, 1
    j       1b
2:  {before_the_loop}
    li      s1, 150000
3:  addi    s2, s2, 3
    addi    s1, s1, -1
    bnez    s1, 3b
    {after_the_loop}
"""
AFTER_THE_LOOP = {
    "a line's end": ("", "li t1, 10\n    sw t1, 0(t0)"),
    # the transmitter off: the byte on the wire ends, the others wait for it to be on again
    "the transmitter off meanwhile": ("sw zero, 8(t0)", "li t1, 1\n    sw t1, 8(t0)\n    li t1, 10\n    sw t1, 0(t0)"),
    # a trap with mtvec 0, in the turn the turns alone hand back: the board's time and the console
    # must be those of the turn's start, as between any two turns
    "a trap": ("csrw mtvec, zero", ".word 0"),
}


@pytest.mark.parametrize("case", AFTER_THE_LOOP)
def test_the_turns_alone_run_past_the_consoles_quiet_bytes_changing_nothing_else(case):
    """A byte leaving the UART is a device event that ends a turn; when nothing but the console's
    record of it depends on its moment (Uarths.quiet_byte_ends), the turns alone run on past it, each
    still ending where it did, and the UART hears it later with its own time: the hart's
    registers and counts, the board's time, the console's bytes and their times and how the run
    ends are those of a run without turns alone (every turn through the scheduler)."""
    before, after = AFTER_THE_LOOP[case]
    source = FPU_ON + PRINT_THEN_LOOP.format(before_the_loop=before, after_the_loop=after)
    runs = []
    for alone in (False, True):
        heard: list[tuple[int, float]] = []
        board = make_board(program(source, data='text: .asciz "quiet"'), cold=False,
                           console=lambda byte: heard.append((byte, board.uarths.last_byte_time)))
        quiet = []
        if alone:
            run_alone = board.harts[0].run_alone
            board.harts[0].run_alone = lambda plan: (quiet.append(plan.ticks), run_alone(plan))
        else:
            board.scheduler._go_on_alone = lambda hart, t0, outer, horizon: horizon
        try:
            board.run_until(4 * PS_PER_MS)
            ended = "ran"
        except FirmwareTrap as error:
            ended = str(error)
        runs.append((state(board), board.harts[0].time, board.time, heard, ended))
        assert not alone or any(quiet), "no turns alone ran past a quiet byte"
    assert bytes(byte for byte, _ in runs[1][3]).startswith(b"quiet")
    assert runs[1] == runs[0]


def test_the_benchs_drawing_figures_time_one_drawing_on_each_engine(firmware, card):
    """tools/bench.py times hart 0's drawing of a steady frame on each engine: the fast engine stops
    before the frame's closing wfi, the precise engine runs it, and each way draws the same
    instructions."""
    from pathlib import Path
    from tools import bench
    ways = bench.drawing_figures(Path(firmware), Path(card), rounds=1)
    fast = ways["fast engine, Rocket cycle table"]["instructions"]
    assert fast > 100_000
    assert ways["precise engine, Rocket cycle table"]["instructions"] == fast + 1
    assert ways["precise engine, one cycle each"]["instructions"] == fast + 1
