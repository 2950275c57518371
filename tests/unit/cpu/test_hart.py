"""Harts on Unicorn (facts sheet section 2): mhartid, exact minstret, mcycle, synchronous
exceptions entering mtvec as the privileged spec says, wfi, interrupts, and the report
of an access to an address nothing answers."""
from __future__ import annotations

import ctypes
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from emulator.cpu.caches import ROCKET_L1
from emulator.memory_map import K210_BLOCKS
from emulator.board.elf import load_elf
from emulator.board.memory import Sram
from emulator.cpu.decode import decode_memory_access
from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE, CsrContext, Hart, HartState, RunEnd
from emulator.cpu.native import counter_lib
from emulator.cpu.riscv import CAUSE_INTERRUPT, IRQ_MEI, IRQ_MSI, IRQ_MTI, IRQ_SEI, IRQ_SSI, IRQ_STI
from emulator.errors import BadInput, FirmwareTrap, HangDetected, UnmodelledAccess
from emulator.vtime import PS_PER_MS
from k210_fixtures import at_done, build_elf, make_board, program, reg, run_to_done, run_until, symbol

CPU_HZ = 26e6
MSTATUS_MIE, MSTATUS_MPIE, MSTATUS_MPP = 1 << 3, 1 << 7, 3 << 11

# A trap handler for hart 0 that records mcause/mepc/mtval/mstatus in s8..s11 and stops.
HANDLER = """
    j       done
    .balign 4
handler:
    csrr    s8, mcause
    csrr    s9, mepc
    csrr    s10, mtval
    csrr    s11, mstatus
    csrr    s7, mcycle
    j       done
"""
MTVAL_SENTINEL = 0x5A5A
SET_MTVEC = f"""
    la      t0, handler
    csrw    mtvec, t0
    li      t0, {MTVAL_SENTINEL}
    csrw    mtval, t0                     # what a trap that does not write mtval leaves
"""


def trap_program(body: str) -> str:
    return program(SET_MTVEC + body + HANDLER)


# --- identity and counters ---------------------------------------------------------------------

def test_mhartid_differs_per_hart():
    board = make_board(build_elf("""
        .globl _start
    _start:
        csrr    a0, mhartid
        la      t0, ids
        slli    t1, a0, 3
        add     t0, t0, t1
        addi    t2, a0, 100
        sd      t2, 0(t0)
        bnez    a0, park
    done:
        j       done
    park:
        wfi
        j       park
        .data
        .balign 8
    ids: .dword 0, 0
    """))
    run_until(board, lambda b: at_done(b) and b.harts[1].state is HartState.ASLEEP)
    assert reg(board, "a0", 0) == 0 and reg(board, "a0", 1) == 1
    ids = board.memory.read(symbol(board, "ids"), 16)
    assert int.from_bytes(ids[:8], "little") == 100
    assert int.from_bytes(ids[8:], "little") == 101


# Each hart reads mhartid in SRAM's cached view (0x8000_0000, where both start) and again in the
# uncached one (0x4000_0000: the same bytes), storing 100 + the first and 200 + the second at its
# own slots of `ids`, chosen by what it read.
BOTH_VIEWS = """
    .globl _start
_start:
    csrr    a0, mhartid
    la      t0, ids
    slli    t1, a0, 4
    add     t0, t0, t1
    addi    t2, a0, 100
    sd      t2, 0(t0)
    la      t3, uncached
    li      t4, -0x40000000
    add     t3, t3, t4
    jr      t3                        # on in the uncached view
uncached:
    csrr    a1, mhartid
    la      t0, ids
    slli    t1, a1, 4
    add     t0, t0, t1
    addi    t2, a1, 200
    sd      t2, 8(t0)
    bnez    a1, park
done:
    j       done
park:
    wfi
    j       park
    .data
    .balign 8
ids: .dword 0, 0, 0, 0
"""


@pytest.mark.parametrize("engine", [ENGINE_FAST, ENGINE_PRECISE])
@pytest.mark.parametrize("link", [0x8000_0000, 0x4000_0000])
def test_mhartid_reads_right_in_both_views_of_sram(engine, link, tmp_path):
    """issue 32, item 7: code linked at the uncached alias 0x4000_0000 runs from 0x8000_0000 first
    (the harts' reset pc) and code linked at 0x8000_0000 may jump into the alias: the CSR
    instructions the board answers are found at the link address, and are answered in both views
    of SRAM (the K210 maps the same SRAM at both: Kendryte SDK lds/kendryte.ld, `ram` at
    0x80000000 and `ram_nocache` at 0x40000000). Before, mhartid read 0 on both harts outside the
    link view (Unicorn's own answer)."""
    script = tmp_path / "link.ld"
    script.write_text(f"SECTIONS {{ . = 0x{link:x}; .text : {{ *(.text*) }} .data : {{ *(.data*) }} }}\n")
    board = make_board(build_elf(BOTH_VIEWS, script), engine=engine)
    ids = symbol(board, "ids")
    assert ids >> 28 == link >> 28
    board.run_until(PS_PER_MS)
    values = [int.from_bytes(board.memory.read(ids + 8 * n, 8), "little") for n in range(4)]
    assert values == [100, 200, 101, 201]


def test_writing_mhartid_is_an_illegal_instruction():
    board = make_board(trap_program("""
        csrw    mhartid, zero
    """))
    run_to_done(board)
    assert reg(board, "s8") == 2
    assert board.harts[0].uc.mem_read(reg(board, "s9"), 4) == (0xF1401073).to_bytes(4, "little")


COUNTERS = """
    csrr    a1, minstret                 # the very first instruction: nothing retired yet
    csrr    s5, mcycle
    csrr    s0, minstret
    li      t0, 1000
1:  addi    t0, t0, -1
    bnez    t0, 1b
    csrr    s1, minstret
    csrr    s2, instret
    csrr    s3, mcycle
    csrr    s4, cycle
    li      t1, 5000
    csrw    minstret, t1
    csrr    a2, minstret                 # reads what was written
    csrr    a3, minstret
"""


@pytest.mark.parametrize("quantum", [37, 20_000])
def test_minstret_counts_exactly(quantum):
    board = make_board(build_elf("""
        .globl _start
    _start:
    """ + COUNTERS + """
        bnez    a1, done
    done:
        j       done
    """), quantum=quantum)
    run_until(board, lambda b: at_done(b, 0) and at_done(b, 1))
    for hart in (0, 1):
        assert reg(board, "a1", hart) == 0
        # csrr s0 + li + 1000 * (addi, bnez) retire between the two reads
        assert reg(board, "s1", hart) - reg(board, "s0", hart) == 2 + 2000
        assert reg(board, "s2", hart) == reg(board, "s1", hart) + 1
        assert reg(board, "a2", hart) == 5000
        assert reg(board, "a3", hart) == 5001


@pytest.mark.parametrize("quantum", [37, 20_000])
def test_mcycle_counts_one_cycle_per_instruction_while_running(quantum):
    """Under --timing ipc1 (tests/unit/cpu/test_cycle_timing.py has the Rocket timing's cycles)."""
    board = make_board(program(COUNTERS), quantum=quantum, timing="ipc1")
    run_to_done(board)
    # from csrr s5 to csrr s3: 2005 instructions at one per cycle
    assert reg(board, "s3") - reg(board, "s5") == 2005
    assert reg(board, "s4") == reg(board, "s3") + 1


def test_mcycle_follows_virtual_time_across_sleep():
    """mcycle is the CPU clock: it keeps counting while the hart sleeps in wfi."""
    board = make_board(program("""
        li      t0, 0x0200BFF8
        ld      t1, 0(t0)
        li      t2, 5200                      # 10 ms of mtime at 26 MHz / 50
        add     t1, t1, t2
        li      t0, 0x02004000
        sd      t1, 0(t0)
        li      t0, 1 << 7                    # MTIE, interrupts globally off
        csrw    mie, t0
        csrr    s0, mcycle
        csrr    s2, minstret
        wfi
        csrr    s1, mcycle
        csrr    s3, minstret
    """))
    run_to_done(board, max_time_s=0.05)
    assert reg(board, "s1") - reg(board, "s0") >= 0.010 * CPU_HZ - 200
    assert reg(board, "s1") - reg(board, "s0") <= 0.010 * CPU_HZ + 200
    assert reg(board, "s3") - reg(board, "s2") == 3           # csrr s2, wfi, csrr s1


# --- synchronous exceptions -------------------------------------------------------------------

@pytest.mark.parametrize("layout, fault_label", [
    # a plain 32-bit illegal instruction after a 32-bit and before a compressed one
    ("""
        .option push
        .option norvc
        addi    a0, t1, 0
        .option pop
    fault:
        .word   0xffffffff
        c.nop
    """, "fault"),
    # compressed c.unimp after a 32-bit instruction whose upper half looks compressed-less
    ("""
        .option push
        .option norvc
        addi    a0, t1, 0                     # t1 = x6: bits 17:16 of the word are 11
        .option pop
    fault:
        c.unimp
        c.nop
        c.nop
    """, "fault"),
    # compressed c.unimp between compressed instructions
    ("""
        c.nop
    fault:
        c.unimp
        c.nop
        addi    a0, a0, 1
    """, "fault"),
    # compressed c.unimp followed by a 32-bit instruction
    ("""
        .option push
        .option norvc
        nop
        .option pop
    fault:
        c.unimp
        .option push
        .option norvc
        addi    a0, t1, 0
        .option pop
    """, "fault"),
    # F instruction with mstatus.FS = 0 (the K210's reset state)
    ("""
        c.nop
    fault:
        fadd.d  f0, f1, f2
        c.nop
    """, "fault"),
])
def test_illegal_instruction_enters_mtvec(layout, fault_label):
    board = make_board(trap_program(layout))
    run_to_done(board)
    fault = symbol(board, fault_label)
    assert reg(board, "s8") == 2
    assert reg(board, "s9") == fault
    # mbadaddr (mtval) is written only for breakpoints, misaligned accesses and access faults on
    # the K210's Rocket (rocket-chip CSR.scala, `write_badaddr`): here it keeps what SET_MTVEC put there
    assert reg(board, "s10") == MTVAL_SENTINEL
    status = reg(board, "s11")
    assert status & MSTATUS_MPP == MSTATUS_MPP and not status & MSTATUS_MIE
    assert "illegal instruction" in board.last_exception
    assert f"0x{fault:08x}" in board.last_exception


def test_illegal_instruction_does_not_retire():
    board = make_board(program(SET_MTVEC + """
        csrr    s0, minstret
        .word   0xffffffff
        j       done
        .balign 4
    handler:
        csrr    s1, minstret
        j       done
    """))
    run_to_done(board)
    # only csrr s0 retired between the reads: the faulting instruction did not
    assert reg(board, "s1") - reg(board, "s0") == 1


def test_ecall_gives_cause_11_at_the_ecall():
    board = make_board(trap_program("""
        c.nop
    the_ecall:
        ecall
        c.nop
    """))
    run_to_done(board)
    assert reg(board, "s8") == 11
    assert reg(board, "s9") == symbol(board, "the_ecall")
    assert reg(board, "s10") == MTVAL_SENTINEL           # an ecall does not write mbadaddr


def test_ebreak_gives_cause_3():
    board = make_board(trap_program("""
        .option push
        .option norvc
    the_ebreak:
        ebreak
        .option pop
    """))
    run_to_done(board)
    assert reg(board, "s8") == 3
    assert reg(board, "s9") == symbol(board, "the_ebreak")


def test_mret_returns_to_mepc_plus_4():
    """A handler that skips the ecall and returns: the program carries on after it."""
    board = make_board(program("""
        la      t0, handler
        csrw    mtvec, t0
        li      s1, 0
        ecall
        li      s1, 42
        j       done
        .balign 4
    handler:
        csrr    t0, mepc
        addi    t0, t0, 4
        csrw    mepc, t0
        mret
    """))
    run_to_done(board)
    assert reg(board, "s1") == 42
    assert reg(board, "priv") == 3                          # still machine mode (MPP = M)


# --- exceptions are the program's: the run goes on ------------------------------------------------

SYSCALL_HANDLER = """
    .balign 4
handler:
    csrr    t0, mcause
    li      t1, 11
    bne     t0, t1, fatal
    addi    s2, s2, 1                    # one more system call served
    add     a0, a0, a1                   # the "system call": a0 = a0 + a1
    csrr    t0, mepc
    addi    t0, t0, 4
    csrw    mepc, t0
    mret
fatal:
    csrw    mie, zero
1:  wfi
    j       1b
"""


def test_ecall_system_calls_are_served_by_the_handler_and_the_run_goes_on():
    """newlib's system calls on the Kendryte SDK are ecalls its trap handler serves: many in a row,
    each returning to the program (before 2026-11-28 the second exception ended the run)."""
    board = make_board(program("""
        la      t0, handler
        csrw    mtvec, t0
        li      s2, 0
        li      s3, 0
        li      s4, 5
    1:  mv      a0, s3
        li      a1, 7
        ecall
        mv      s3, a0
        addi    s4, s4, -1
        bnez    s4, 1b
        j       done
    """ + SYSCALL_HANDLER))
    run_to_done(board)
    assert reg(board, "s2") == 5 and reg(board, "s3") == 35
    assert board.scheduler.traps.taken == {"environment call from M-mode": 5}
    assert board.harts[0].open_trap is None                  # every handler returned


def test_a_handler_that_parks_the_harts_ends_the_run_as_a_trap():
    """An exception the handler does not return from, after which no hart can go on: the trap
    ended the program (status 3), named with its pc."""
    board = make_board(program("""
        la      t0, handler
        csrw    mtvec, t0
    the_fault:
        .word   0xffffffff
    """ + SYSCALL_HANDLER))
    with pytest.raises(FirmwareTrap, match=r"illegal instruction at pc 0x[0-9a-f]+ <the_fault>.*did not return"):
        run_until(board, lambda b: False, max_time_s=1.0)


def test_a_handler_that_returns_to_the_fault_is_a_trap_storm():
    """A handler that returns to the same faulting instruction without changing anything: the hart
    can make no progress (reported like a hang, naming the trap)."""
    board = make_board(program("""
        la      t0, handler
        csrw    mtvec, t0
    the_fault:
        .word   0xffffffff
        j       done
        .balign 4
    handler:
        mret
    """))
    with pytest.raises(HangDetected, match=r"trap storm: hart 0: illegal instruction at pc 0x[0-9a-f]+ <the_fault>"):
        run_until(board, lambda b: False, max_time_s=1.0)
    assert board.scheduler.traps.taken["illegal instruction"] == 1000


def test_stop_on_trap_ends_the_run_at_the_first_exception():
    board = make_board(program("""
        la      t0, handler
        csrw    mtvec, t0
        li      a0, 1
        li      a1, 2
        ecall
        j       done
    """ + SYSCALL_HANDLER))
    board.scheduler.traps.stop_on_trap = True
    with pytest.raises(FirmwareTrap, match="environment call from M-mode.*the firmware's trap handler has run"):
        run_until(board, lambda b: False, max_time_s=1.0)
    assert reg(board, "s2") == 1                              # the handler ran: its grace period


def test_mret_to_user_mode_and_ecall_from_user_mode():
    """mret goes to the mode in MPP (the K210 has U-mode) and sets MPP to U; an ecall there is
    cause 8, and the trap puts the hart back in M-mode with MPP = U."""
    board = make_board(program("""
        la      t0, handler
        csrw    mtvec, t0
        li      t0, 3 << 11
        csrc    mstatus, t0                  # MPP = U
        la      t0, user
        csrw    mepc, t0
        mret
    user:
        csrr    s5, mstatus                  # M-mode CSR from U-mode: illegal
        li      s6, 1
        ecall
        .balign 4
    handler:
        csrr    t0, mcause
        li      t1, 2
        bne     t0, t1, 1f
        li      s7, 1                        # the illegal CSR read, seen
        csrr    t0, mepc
        addi    t0, t0, 4
        csrw    mepc, t0
        mret
    1:  mv      s8, t0
        csrr    s9, mstatus
        j       done
    """))
    run_to_done(board)
    assert reg(board, "s7") == 1 and reg(board, "s6") == 1
    assert reg(board, "s8") == 8                               # environment call from U-mode
    assert reg(board, "s9") & MSTATUS_MPP == 0                  # MPP = U: the mode the trap came from
    assert reg(board, "priv") == 3


MISALIGNED_RECOVERY = """
    la      t0, handler
    csrw    mtvec, t0
    la      s1, bytes
    lw      s2, 1(s1)                    # misaligned: the handler puts bytes 1..4 in s2
    li      s4, 0x1234
    sh      s4, 3(s1)                    # misaligned: the handler stores it byte by byte
    lhu     s5, 3(s1)                    # again: read back through the handler
    li      s3, 1
    j       done
    .balign 4
handler:                                 # the SDK's way (syscalls.c handle_misaligned_load/store),
    csrr    t0, mcause                   # for just the three accesses above
    csrr    t1, mtval
    csrr    t2, mepc
    addi    s6, s6, 1
    li      t3, 6
    beq     t0, t3, 2f
    lbu     t4, 0(t1)                    # a load: 4 bytes for lw, 2 for lhu
    lbu     t5, 1(t1)
    slli    t5, t5, 8
    or      t4, t4, t5
    lhu     t3, 0(t2)
    andi    t3, t3, 3
    li      t5, 3
    bne     t3, t5, 1f                   # (a compressed instruction would be 2 bytes: none here)
    lhu     t3, 0(t2)                    # (the code is 2-byte aligned: halfwords, as the SDK reads it)
    srli    t3, t3, 12
    andi    t3, t3, 7
    li      t5, 2
    bne     t3, t5, 3f                   # funct3 2: lw
    lbu     t5, 2(t1)
    slli    t5, t5, 16
    or      t4, t4, t5
    lbu     t5, 3(t1)
    slli    t5, t5, 24
    or      t4, t4, t5
    mv      s2, t4
    j       1f
3:  mv      s5, t4
    j       1f
2:  sb      s4, 0(t1)                    # the store: sh s4
    srli    t5, s4, 8
    sb      t5, 1(t1)
1:  addi    t2, t2, 4
    csrw    mepc, t2
    mret
"""


@pytest.mark.parametrize("engine", [ENGINE_PRECISE, ENGINE_FAST])
def test_misaligned_accesses_trap_and_the_handler_recovers_them(engine):
    """Rocket traps on every misaligned load and store (rocket-chip DCache.scala: xcpt.ma.ld/st);
    the Kendryte SDK's trap handler emulates them. mtval is the address, mepc the access; before
    2026-11-28 the model carried them out silently."""
    board = make_board(program(MISALIGNED_RECOVERY, data="bytes: .byte 0x10, 0x11, 0x12, 0x13, 0x14, 0x15, 0x16"),
                       engine=engine, quantum=100)
    run_to_done(board)
    assert reg(board, "s3") == 1 and reg(board, "s6") == 3
    assert reg(board, "s2") == 0x14131211
    assert reg(board, "s5") == 0x1234
    assert board.memory.read(symbol(board, "bytes"), 7) == bytes([0x10, 0x11, 0x12, 0x34, 0x12, 0x15, 0x16])
    assert board.scheduler.traps.taken == {"load address misaligned": 2, "store address misaligned": 1}


@pytest.mark.parametrize("access, address, cause", [
    ("fld f1, 4(s1)", 4, 4), ("fsd f1, 12(s1)", 12, 6), ("lr.w t1, (s7)", 2, 4), ("amoadd.w t1, t2, (s7)", 2, 6),
    ("sc.w t1, t2, (s7)", 2, 6), ("c.ld a0, 0(a5)", 4, 4), ("c.sdsp a0, 0(sp)", 12, 6), ("lh t1, 1(s1)", 1, 4)])
def test_every_kind_of_access_traps_misaligned(access, address, cause):
    """Loads, stores, floating point, compressed forms, LR (a load), SC and AMOs (stores): mcause 4 or
    6 (privileged spec 1.10, table 3.6), mtval the address, mepc the access."""
    board = make_board(program(SET_MTVEC + f"""
        li      t0, 1 << 13
        csrs    mstatus, t0                  # the FPU on
        la      s1, words
        addi    s7, s1, 2
        addi    a5, s1, 4
        addi    sp, s1, 12
    the_access:
        {access}
    """ + HANDLER, data="words: .dword 0, 0, 0, 0"), quantum=100)
    run_to_done(board)
    assert reg(board, "s8") == cause
    assert reg(board, "s9") == symbol(board, "the_access")
    assert reg(board, "s10") == symbol(board, "words") + address


@settings(max_examples=3000, deadline=None)
@given(word=st.integers(0, 2**32 - 1), compressed=st.booleans())
def test_the_counters_access_decoder_agrees_with_decode_py(word, compressed):
    """The native counter's decoder of loads and stores (_counter.h memory_access_of) and
    cpu/decode.py's decode_memory_access say the same of every instruction word."""
    size = 2 if compressed else 4
    word = word & 0xFFFF if compressed else word | 3
    if compressed and word & 3 == 3:
        word &= ~1
    out = (ctypes.c_int64 * 4)()
    counter_lib.decode_access_for_tests(word, size, out)
    expected = decode_memory_access(word)
    if word & 0x7F == 0x2F and (word >> 12) & 7 not in (2, 3):
        expected = None        # a reserved AMO width: decode.py guesses, the counter leaves it alone
    assert (tuple(out[:3]) if out[0] else None) == expected


def test_exception_without_a_trap_handler_stops_the_run():
    board = make_board(program("""
        csrw    mtvec, zero
        .word   0xffffffff
    """))
    with pytest.raises(FirmwareTrap, match="illegal instruction.*points at no trap handler"):
        run_to_done(board)


# --- wfi and interrupts --------------------------------------------------------------------------

WFI_MSIP = """
    .globl _start
_start:
    csrr    a0, mhartid
    bnez    a0, hart1
    li      t0, 1 << 3                        # MSIE; mstatus.MIE stays 0: wake, no trap
    csrw    mie, t0
    csrr    s0, minstret
    wfi
    csrr    s1, minstret
    csrr    s2, mcycle
    li      t0, 0x02000000
    sw      zero, 0(t0)                       # clear msip[0]
done:
    j       done
hart1:
    li      t0, 30000
1:  addi    t0, t0, -1
    bnez    t0, 1b
    csrr    s3, mcycle
    li      t0, 0x02000000
    li      t1, 1
    sw      t1, 0(t0)                         # msip[0] = 1
park:
    csrw    mie, zero
    wfi
    j       park
"""


def test_wfi_sleeps_until_msip_wakes_the_hart():
    board = make_board(build_elf(WFI_MSIP))
    for _ in range(20):  # writing mie ends a turn (it may unmask an interrupt); wfi follows (the turns at
        # reset are a few cycles each: the harts start in lockstep)
        board._step()
        if board.harts[0].state is HartState.ASLEEP:
            break
    assert board.harts[0].state is HartState.ASLEEP
    asleep_at = board.harts[0].instret
    board._step()
    assert board.harts[0].state is HartState.ASLEEP
    assert board.harts[0].instret == asleep_at             # sleeping costs no instructions
    run_until(board, at_done)
    assert reg(board, "s1", 0) - reg(board, "s0", 0) == 2  # csrr, wfi
    assert reg(board, "s2", 0) >= reg(board, "s3", 1)      # woke after hart 1 raised msip
    assert reg(board, "mcause", 0) == 0                    # MIE = 0: no trap taken
    assert not board.clint.msip(0)


def test_wfi_with_nothing_to_wake_it_is_a_hang():
    from emulator.errors import HangDetected
    board = make_board(program("""
        csrw    mie, zero
        wfi
        li      s1, 1
    """))
    with pytest.raises(HangDetected, match="every hart sleeps in wfi"):
        run_to_done(board)


def test_wfi_with_an_interrupt_already_pending_falls_through():
    """A wfi with an enabled interrupt already pending does not sleep (the privileged spec: WFI
    resumes when an enabled interrupt is pending), even when the other hart sleeps too and no
    device will change an interrupt input again. (The model used to put the hart to sleep and
    wake it only at the next change of an input: here never, a hang; in the firmware, hart 1
    waiting for a DMA that had finished while it drew its band, with hart 0 asleep.)"""
    board = make_board(program("""
        li      t0, 0x02000000
        li      t1, 1
        sw      t1, 0(t0)                     # msip[0] = 1: pending before the wfi
        li      t0, 1 << 3                    # MSIE; mstatus.MIE stays 0: no trap
        csrw    mie, t0
        wfi
        li      s1, 1
    """))
    run_to_done(board)
    assert reg(board, "s1", 0) == 1
    assert reg(board, "mcause", 0) == 0


def load_segments(elf: str) -> bytes:
    """The first 4 KiB of SRAM as the program's image fills them."""
    sram = Sram(fill_seed=None)
    load_elf(elf, sram)
    return sram.read(0x8000_0000, 0x1000)


def test_a_wfi_that_ends_the_budget_still_sleeps():
    """A turn whose last instruction is a wfi ends with the hart asleep: a turn boundary must not
    make the hart skip its sleep (it used to report the budget used up, and the hart ran on)."""
    code = build_elf("""
        .globl _start
    _start:
        nop
        nop
        wfi
        nop
    """)
    hart = Hart(0, CsrContext(mcycle=lambda: 0, mip=lambda: 0))
    hart.uc.mem_map(0x8000_0000, 0x1000)
    hart.uc.mem_write(0x8000_0000, load_segments(code))
    hart.pc = 0x8000_0000
    assert hart.run(3) == (RunEnd.WFI, 3)
    assert hart.pc == 0x8000_0008                   # past the wfi (after two c.nop)


TIMER_IRQ = """
    la      t0, handler
    csrw    mtvec, t0
    li      t0, 0x0200BFF8
    ld      t1, 0(t0)
    addi    t1, t1, 100                       # 100 ticks = 5000 cycles from now
    li      t0, 0x02004000
    sd      t1, 0(t0)
    csrr    s6, mcycle
    li      t0, 1 << 7                        # MTIE
    csrw    mie, t0
    csrsi   mstatus, 8                        # MIE
loop:
    addi    s1, s1, 1
    j       loop
""" + HANDLER


def test_timer_interrupt_enters_mtvec_with_the_interrupt_bit():
    board = make_board(program(TIMER_IRQ), quantum=100)
    run_to_done(board)
    assert reg(board, "s8") == CAUSE_INTERRUPT | IRQ_MTI
    assert reg(board, "s9") in (symbol(board, "loop"), symbol(board, "loop") + 2)
    status = reg(board, "s11")
    assert status & MSTATUS_MPIE and not status & MSTATUS_MIE
    assert status & MSTATUS_MPP == MSTATUS_MPP
    assert reg(board, "s1") > 0                            # the loop ran before the interrupt
    # t1 = mtimecmp; mtime ticks every 50 cycles from cycle 0
    latency = reg(board, "s7") - reg(board, "t1") * 50
    assert 0 <= latency <= 150


def test_timer_interrupt_latency_with_the_default_quantum():
    board = make_board(program(TIMER_IRQ))
    run_to_done(board)
    latency = reg(board, "s7") - reg(board, "t1") * 50
    assert 0 <= latency <= 150


def test_mtvec_has_no_vectored_mode():
    """The K210's Rocket (privileged spec 1.9.1) keeps mtvec's two low bits at zero
    (`reg_mtvec := wdata >> 2 << 2`): a base written with mode 1 (vectored, spec 1.10) reads back
    without it, and an interrupt enters the base itself, not base + 4 * cause."""
    board = make_board(program("""
        la      t0, vectors
        ori     t0, t0, 1                     # vectored mode on a 1.10 hart
        csrw    mtvec, t0
        csrr    s2, mtvec
        li      t0, 0x02000000
        li      t1, 1
        sw      t1, 0(t0)                     # msip[0]
        li      t0, 1 << 3
        csrw    mie, t0
        csrsi   mstatus, 8
    1:  j       1b
        .balign 64
        .option push
        .option norvc                         # 4-byte entries
    vectors:
        j       base
        j       wrong
        j       wrong
        j       wrong                         # entry 3: where a vectored hart would go
        .option pop
    wrong:
        li      s1, -1
        j       done
    base:
        li      s1, 3
        csrr    s8, mcause
        j       done
    """), quantum=100)
    run_to_done(board)
    assert reg(board, "s2") == symbol(board, "vectors")
    assert reg(board, "s1") == 3
    assert reg(board, "s8") == CAUSE_INTERRUPT | IRQ_MSI


def test_the_1_9_1_mmu_stops_clearly():
    """mstatus.VM (1.9.1's paging switch) asks for what the model does not have: the run stops
    naming it instead of running on untranslated."""
    board = make_board(program("""
        li      t0, 9 << 24                   # VM = Sv39
        csrs    mstatus, t0
        j       done
    """))
    with pytest.raises(UnmodelledAccess, match="mstatus.VM = 9"):
        run_to_done(board)


def test_external_interrupt_through_the_plic():
    """GPIOHS line 0 rising edge -> PLIC source 34 -> MEIP -> mcause 11 with the interrupt bit;
    the handler claims 34."""
    board = make_board(program("""
        li      s0, 0x50440000
        lw      t0, 0x28(s0)
        ori     t0, t0, 1 << 3
        sw      t0, 0x28(s0)
        la      t0, handler
        csrw    mtvec, t0
        li      s1, 0x0C000000
        li      t0, 1
        sw      t0, 34 * 4(s1)               # priority[34] = 1
        li      t1, 0x0C002004
        li      t0, 1 << 2
        sw      t0, 0(t1)                    # context 0 enables source 34
        li      t1, 0x0C200000
        sw      zero, 0(t1)                  # threshold 0
        li      t0, 1 << 11
        csrw    mie, t0                      # MEIE
        csrsi   mstatus, 8
        li      s2, 0x38001000
        li      t0, 1
        sw      t0, 0x04(s2)                 # input_en
        sw      t0, 0x08(s2)                 # output_en
        sw      t0, 0x18(s2)                 # rise_ie
        sw      t0, 0x0C(s2)                 # output_val: rising edge
    1:  j       1b
        .balign 4
    handler:
        csrr    s8, mcause
        li      t1, 0x0C200004
        lw      s3, 0(t1)                    # claim
        j       done
    """), quantum=100)
    run_to_done(board)
    assert reg(board, "s8") == CAUSE_INTERRUPT | IRQ_MEI
    assert reg(board, "s3") == 34


def test_plic_contexts_as_on_the_k210():
    """Context 2 (0x0C00_2100, 0x0C20_2000) is hart 1's M-mode context: source 34 enabled there
    reaches hart 1 as MEI. Context 1 (0x0C00_2080, 0x0C20_1000) is hart 0's S-mode context: source
    35 enabled there raises hart 0's SEIP, not its MEIP, and is taken in M-mode as cause 9 (SDK
    plic.h; Linux's K210 device tree). Before 2026-11-28 the model gave context 1 to hart 1."""
    board = make_board(build_elf("""
        .globl _start
    _start:
        la      t0, handler
        csrw    mtvec, t0
        csrr    a0, mhartid
        bnez    a0, hart1
        li      s0, 0x50440000
        lw      t0, 0x28(s0)
        ori     t0, t0, 1 << 3
        sw      t0, 0x28(s0)                 # GPIOHS's clock
        li      s1, 0x0C000000
        li      t0, 1
        sw      t0, 34 * 4(s1)               # priority[34] = 1
        sw      t0, 35 * 4(s1)               # priority[35] = 1
        li      t1, 0x0C002000 + 2 * 0x80 + 4
        li      t0, 1 << (34 - 32)
        sw      t0, 0(t1)                    # context 2 enables source 34
        li      t1, 0x0C002000 + 1 * 0x80 + 4
        li      t0, 1 << (35 - 32)
        sw      t0, 0(t1)                    # context 1 enables source 35
        li      t0, (1 << 11) | (1 << 9)
        csrw    mie, t0                      # MEIE and SEIE
        csrsi   mstatus, 8
        la      t1, ready
    1:  ld      t0, 0(t1)                    # hart 1 has its interrupts on
        beqz    t0, 1b
        li      s2, 0x38001000
        li      t0, 3
        sw      t0, 0x04(s2)                 # input_en, lines 0 and 1
        sw      t0, 0x08(s2)                 # output_en
        sw      t0, 0x18(s2)                 # rise_ie
        sw      t0, 0x0C(s2)                 # output_val: both rise
    2:  j       2b
    hart1:
        li      t0, 1 << 11
        csrw    mie, t0                      # MEIE
        csrsi   mstatus, 8
        la      t1, ready
        li      t0, 1
        sd      t0, 0(t1)
    3:  j       3b
        .balign 4
    handler:
        csrr    a0, mhartid
        bnez    a0, handler1
        csrr    s8, mcause
        csrr    s5, mip
        li      t1, 0x0C200000 + 1 * 0x1000 + 4
        lw      s3, 0(t1)                    # claim, context 1
        li      t1, 0x0C200000 + 0 * 0x1000 + 4
        lw      s4, 0(t1)                    # claim, context 0: nothing
        la      t1, seen1
    4:  ld      t0, 0(t1)                    # wait for hart 1's claim
        beqz    t0, 4b
    done:
        j       done
    handler1:
        csrr    s8, mcause
        li      t1, 0x0C200000 + 2 * 0x1000 + 4
        lw      s3, 0(t1)                    # claim, context 2
        la      t1, seen1
        li      t0, 1
        sd      t0, 0(t1)
    5:  wfi
        j       5b
        .data
        .balign 8
    ready: .dword 0
    seen1: .dword 0
    """), quantum=100)
    run_to_done(board)
    assert reg(board, "s8", 1) == CAUSE_INTERRUPT | IRQ_MEI
    assert reg(board, "s3", 1) == 34
    assert reg(board, "s8", 0) == CAUSE_INTERRUPT | IRQ_SEI
    assert reg(board, "s5", 0) >> IRQ_SEI & 1 and not reg(board, "s5", 0) >> IRQ_MEI & 1
    assert reg(board, "s3", 0) == 35
    assert reg(board, "s4", 0) == 0


def test_a_delegated_seip_is_not_taken_in_m_mode():
    """mideleg.SEI hands hart 0's S-mode external interrupt to S-mode: in M-mode it is not taken,
    though mip shows it (privileged spec 1.10, 3.1.14)."""
    board = make_board(trap_program("""
        li      s0, 0x50440000
        lw      t0, 0x28(s0)
        ori     t0, t0, 1 << 3
        sw      t0, 0x28(s0)
        li      s1, 0x0C000000
        li      t0, 1
        sw      t0, 34 * 4(s1)
        li      t1, 0x0C002000 + 1 * 0x80 + 4
        li      t0, 1 << 2
        sw      t0, 0(t1)                    # context 1 (hart 0's S-mode) enables source 34
        li      t0, 1 << 9
        csrw    mideleg, t0
        csrw    mie, t0                      # SEIE
        csrsi   mstatus, 8
        li      s2, 0x38001000
        li      t0, 1
        sw      t0, 0x04(s2)
        sw      t0, 0x08(s2)
        sw      t0, 0x18(s2)
        sw      t0, 0x0C(s2)                 # rising edge
        li      t0, 2000
    1:  addi    t0, t0, -1
        bnez    t0, 1b
        csrr    s5, mip
        li      s8, 7
    """), quantum=100)
    run_to_done(board)
    assert reg(board, "s8") == 7
    assert reg(board, "s5") >> IRQ_SEI & 1


def test_masked_interrupts_are_not_taken():
    board = make_board(program("""
        la      t0, handler
        csrw    mtvec, t0
        li      t0, 0x02000000
        li      t1, 1
        sw      t1, 0(t0)                     # msip[0], but mie.MSIE = 0
        csrsi   mstatus, 8
        li      t0, 2000
    1:  addi    t0, t0, -1
        bnez    t0, 1b
        li      s1, 7
        j       done
        .balign 4
    handler:
        li      s1, -1
        j       done
    """), quantum=100)
    run_to_done(board)
    assert reg(board, "s1") == 7


# --- accesses nothing answers ------------------------------------------------------------------

def test_unmapped_load_names_hart_pc_instruction_address_size_and_direction():
    """With --strict an access nothing answers stops the run (by default it is an access fault
    into the firmware's trap handler: tests/unit/board/test_bus.py)."""
    board = make_board(program("""
        li      t0, 0x60000000
    bad:
        lw      t1, 8(t0)
    """), strict=True)
    with pytest.raises(UnmodelledAccess) as info:
        run_to_done(board)
    text = str(info.value)
    bad = symbol(board, "bad")
    assert "hart 0" in text
    assert f"pc 0x{bad:08x}" in text
    assert "lw t1, 8(t0)" in text
    assert "0x60000008" in text
    assert "load of 4 bytes" in text


def test_store_to_a_known_but_unmodelled_block_names_it():
    board = make_board(build_elf("""
        .globl _start
    _start:
        csrr    a0, mhartid
        beqz    a0, done
        li      t0, 0x50280000
    bad:
        sd      a0, 0x10(t0)
    done:
        j       done
    """))
    with pytest.raises(UnmodelledAccess) as info:
        run_until(board, lambda b: False, max_time_s=1e-3)
    text = str(info.value)
    assert "hart 1" in text
    assert f"pc 0x{symbol(board, 'bad'):08x}" in text
    assert "sd a0, 0x10(t0)" in text
    assert "store of 8 bytes at 0x50280010" in text
    assert "I2C" in text


def test_mip_reads_the_board_pending_bits():
    board = make_board(program("""
        csrr    s1, mip
        li      t0, 0x02000000
        li      t1, 1
        sw      t1, 0(t0)                     # msip[0]
        csrr    s2, mip
        li      t0, 0x02004000
        sd      zero, 0(t0)                   # mtimecmp[0] = 0: timer pending
        csrr    s3, mip
        li      t0, -1
        csrw    mip, t0                       # the machine bits of mip are read-only, SSIP and STIP not
        csrr    s4, mip
    """))
    run_to_done(board)
    assert reg(board, "s1") == 0
    assert reg(board, "s2") == 1 << IRQ_MSI
    assert reg(board, "s3") == 1 << IRQ_MSI | 1 << IRQ_MTI
    assert reg(board, "s4") == 1 << IRQ_MSI | 1 << IRQ_MTI | 1 << IRQ_SSI | 1 << IRQ_STI


def test_software_interrupt_wins_over_timer():
    """Both pending when MIE turns on: MSI is taken first (privileged spec order MEI, MSI, MTI)."""
    board = make_board(program(SET_MTVEC + """
        li      t0, 0x02000000
        li      t1, 1
        sw      t1, 0(t0)                     # msip[0]
        li      t0, 0x02004000
        sd      zero, 0(t0)                   # timer pending too
        li      t0, (1 << 3) | (1 << 7)
        csrw    mie, t0
        csrsi   mstatus, 8
    1:  j       1b
    """ + HANDLER), quantum=100)
    run_to_done(board)
    assert reg(board, "s8") == CAUSE_INTERRUPT | IRQ_MSI


# --- turns ended by devices ---------------------------------------------------------------------

STORES_WITH_MIE = """
    csrsi   mstatus, 8                        # MIE on, mie = 0: nothing can interrupt
    csrr    s0, mcycle
    csrr    s2, minstret
    li      t0, 0x02000004
    li      t1, 100
1:  sw      zero, 0(t0)                       # msip[1] = 0: the board re-checks interrupts
    addi    t1, t1, -1
    bnez    t1, 1b
    csrr    s1, mcycle
    csrr    s3, minstret
"""


def test_a_device_ending_the_turn_does_not_repeat_the_access():
    """Each store to the CLINT with mstatus.MIE set ends the hart's turn (an interrupt may
    now be pending). The store must still happen exactly once: the loop retires exactly
    3 instructions per iteration and terminates."""
    board = make_board(program(STORES_WITH_MIE), quantum=50)
    run_to_done(board, max_time_s=0.05)
    assert reg(board, "t1") == 0
    # csrr s2, li t0 (lui + addi), li t1, 100 * (sw, addi, bnez), csrr s1
    assert reg(board, "s3") - reg(board, "s2") == 1 + 2 + 1 + 300 + 1


def test_a_device_ending_the_turn_costs_no_time():
    board = make_board(program(STORES_WITH_MIE))
    run_to_done(board, max_time_s=1.0)
    cycles = reg(board, "s1") - reg(board, "s0")
    # two cycles an instruction at most, and each store's round trip to the CLINT (caches.py)
    clint = ROCKET_L1.device(K210_BLOCKS["CLINT"].bus, (1, 1, 1))
    assert cycles <= 2 * (reg(board, "s3") - reg(board, "s2")) + 100 * clint


@pytest.mark.parametrize("instruction, cause", [("lw t2, 2(t1)", 4), ("sw t2, 6(t1)", 6), ("ld t2, 4(t1)", 4)])
def test_misaligned_device_access_raises_the_misaligned_exception(instruction, cause):
    """Unicorn would split a misaligned MMIO access into aligned pieces; the K210 traps."""
    board = make_board(trap_program(f"""
        li      t1, 0x38001000                # GPIOHS, no clock gate in the way
    fault:
        {instruction}
    """))
    run_to_done(board)
    assert reg(board, "s8") == cause
    assert reg(board, "s9") == symbol(board, "fault")
    assert reg(board, "s10") == 0x38001000 + int(instruction.split(", ")[1].split("(")[0])


def test_an_elf_without_execute_flags_runs_its_code_sections(tmp_path):
    """riscv-tests' linker script leaves its one segment without flags; the boot ROM never looks
    at them, so the code is found from the sections marked executable instead."""
    elf = Path(program("    nop\n"))
    data = bytearray(elf.read_bytes())
    phoff, phentsize, phnum = (int.from_bytes(data[0x20:0x28], "little"), int.from_bytes(data[0x36:0x38], "little"),
                               int.from_bytes(data[0x38:0x3A], "little"))
    for i in range(phnum):
        flags_at = phoff + i * phentsize + 4           # Elf64_Phdr.p_flags
        data[flags_at:flags_at + 4] = bytes(4)
    bare = tmp_path / "bare.elf"
    bare.write_bytes(bytes(data))
    image = load_elf(bare, Sram())
    assert any(address <= image.entry < address + len(code) for address, code in image.code_ranges)
    board = make_board(str(bare))
    run_to_done(board)


def _phdr_field(data: bytearray, index: int, offset: int, value: int | None = None) -> int:
    """Reads (or writes) an 8-byte field of program header `index` (Elf64_Phdr: p_offset 8,
    p_vaddr 16, p_paddr 24, p_filesz 32, p_memsz 40)."""
    phoff, phentsize = int.from_bytes(data[0x20:0x28], "little"), int.from_bytes(data[0x36:0x38], "little")
    at = phoff + index * phentsize + offset
    if value is not None:
        data[at:at + 8] = value.to_bytes(8, "little")
    return int.from_bytes(data[at:at + 8], "little")


def _first_load(data: bytearray) -> int:
    phoff, phentsize, phnum = (int.from_bytes(data[0x20:0x28], "little"), int.from_bytes(data[0x36:0x38], "little"),
                               int.from_bytes(data[0x38:0x3A], "little"))
    return next(i for i in range(phnum) if int.from_bytes(data[phoff + i * phentsize:phoff + i * phentsize + 4], "little") == 1)


@pytest.mark.parametrize("damage, words", [
    ("cut", "run past the file"),
    ("huge filesz", "run past the file"),
    ("filesz over memsz", "more than p_memsz"),
    ("past SRAM", "do not lie in the K210's 8 MiB SRAM"),
    ("huge section", "runs past the file"),
])
def test_a_damaged_elf_is_bad_input_naming_the_field(tmp_path, damage, words):
    """Issue 35: a cut ELF used to load short and trap, a huge p_filesz or sh_size gave exit 1
    (OverflowError, MemoryError), a segment past SRAM was taken."""
    data = bytearray(Path(program("    nop\n")).read_bytes())
    load = _first_load(data)
    if damage == "cut":
        data = data[:_phdr_field(data, load, 8) + _phdr_field(data, load, 32) // 2]
    elif damage == "huge filesz":
        _phdr_field(data, load, 32, 2**63)
        _phdr_field(data, load, 40, 2**63)
    elif damage == "filesz over memsz":
        _phdr_field(data, load, 40, _phdr_field(data, load, 32) - 1)
    elif damage == "past SRAM":
        _phdr_field(data, load, 40, 64 << 20)
    else:
        shoff, shentsize, shnum = (int.from_bytes(data[0x28:0x30], "little"), int.from_bytes(data[0x3A:0x3C], "little"),
                                   int.from_bytes(data[0x3C:0x3E], "little"))
        for i in range(shnum):
            header = shoff + i * shentsize
            if int.from_bytes(data[header + 4:header + 8], "little") == 2:       # SHT_SYMTAB
                data[header + 32:header + 40] = (24 << 58).to_bytes(8, "little")     # sh_size, whole entries
    bad = tmp_path / "bad.elf"
    bad.write_bytes(bytes(data))
    with pytest.raises(BadInput, match=words):
        load_elf(bad, Sram())


def test_constants_name_no_address(firmware):
    """An .equ constant that looks like an address (OBJ_INDEX_LIMIT is 0x8000_0000) is an absolute
    symbol: stop reports used to name heap addresses after it (issue 35)."""
    image = load_elf(firmware, Sram())
    assert "OBJ_INDEX_LIMIT" in image.symbol_values
    assert "OBJ_INDEX_LIMIT" not in image.symbols.values()


def test_device_windows_each_reach_their_own_callbacks_and_a_failing_one_stops_the_run():
    """map_device's windows share one pair of native callbacks, told apart by index: each load and
    store reaches its own window's, and an exception in one ends the precise engine's run and is
    raised from it, as with the binding's own callbacks."""
    code = build_elf("""
        .globl _start
    _start:
        li      t0, 0x50000000
        li      t1, 0x50001000
        lw      a0, 4(t0)
        sw      a0, 8(t1)
        lw      a1, 0(t1)
        nop
    """)
    hart = Hart(0, CsrContext(mcycle=lambda: 0, mip=lambda: 0))
    hart.uc.mem_map(0x8000_0000, 0x1000)
    hart.uc.mem_write(0x8000_0000, load_segments(code))
    seen = []
    for window in range(2):
        def read(uc, offset, size, data, window=window):
            seen.append(("load", window, offset, size))
            if window == 1:
                raise ValueError("window 1 fails")
            return 0x1234
        def write(uc, offset, size, value, data, window=window):
            seen.append(("store", window, offset, value))
        hart.map_device(0x5000_0000 + 0x1000 * window, 0x1000, read, write)
    hart.pc = 0x8000_0000
    with pytest.raises(ValueError, match="window 1 fails"):
        hart.run(20)
    assert seen == [("load", 0, 4, 4), ("store", 1, 8, 0x1234), ("load", 1, 0, 4)]
