"""Traps, delegation and interrupt order as the K210's Rocket of early 2017 has them (privileged
spec 1.9.1; rocket-chip 1322a026 rocket/CSR.scala), where they differ from today's spec, on both
engines (cpu/privileged.py)."""
from __future__ import annotations

import pytest

from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE
from emulator.cpu.privileged import DELEGABLE_EXCEPTIONS, DELEGABLE_INTERRUPTS
from emulator.cpu.riscv import CAUSE_INTERRUPT, IRQ_SSI, MSTATUS_MPIE, MSTATUS_SPIE, MSTATUS_SPP
from k210_fixtures import make_board, program, reg, run_to_done, symbol

ENGINES = [ENGINE_PRECISE, ENGINE_FAST]

# M-mode and S-mode handlers that record the cause, epc and status and step over the instruction
HANDLERS = """
    la      t0, m_handler
    csrw    mtvec, t0
    la      t0, s_handler
    csrw    stvec, t0
    j       main
    .balign 4
m_handler:
    csrr    s8, mcause
    csrr    s9, mepc
    csrr    s10, mstatus
    addi    s11, s11, 1
    bltz    s8, 1f                            # an interrupt: mepc is where to go on
    addi    t0, s9, 4
    csrw    mepc, t0
1:  mret
    .balign 4
s_handler:
    csrr    s2, scause
    csrr    s3, sepc
    csrr    s4, sstatus
    addi    s5, s5, 1
    li      t0, 2
    csrc    sip, t0                           # an SSIP that brought us here is done
    bltz    s2, 1f
    addi    t0, s3, 4
    csrw    sepc, t0
1:  sret
main:
"""


def enter(mode: int) -> str:
    """Drops from M-mode to `mode` (0 U, 1 S) at the next line."""
    return f"""
        li      t0, 3 << 11
        csrc    mstatus, t0
        li      t0, {mode} << 11
        csrs    mstatus, t0
        la      t0, 1f
        csrw    mepc, t0
        mret
    1:
    """


def run(body: str, engine: str):
    board = make_board(program(HANDLERS + body + "\n    li s7, 77\n"), engine=engine)
    run_to_done(board)
    assert reg(board, "s7") == 77
    return board


@pytest.mark.parametrize("engine", ENGINES)
def test_a_delegated_u_mode_ecall_enters_s_mode_and_sret_returns(engine):
    board = run("""
        li      t0, 1 << 8
        csrw    medeleg, t0
    """ + enter(0) + """
    call_site:
        ecall
    """, engine)
    assert reg(board, "s5") == 1 and reg(board, "s11") == 0
    assert reg(board, "s2") == 8
    assert reg(board, "s3") == symbol(board, "call_site")
    assert not reg(board, "s4") & MSTATUS_SPP                 # came from U-mode
    assert not reg(board, "s4") & MSTATUS_SPIE                # U-mode's interrupt enable: none
    assert board.harts[0].privilege == 0


def test_only_rocket_s_delegable_bits_are_kept():
    board = run("""
        li      t0, -1
        csrw    medeleg, t0
        csrr    s1, medeleg
        csrw    mideleg, t0
        csrr    s6, mideleg
        csrw    mideleg, zero
        csrw    medeleg, zero
    """, ENGINE_PRECISE)
    assert reg(board, "s1") == DELEGABLE_EXCEPTIONS            # not misaligned accesses, not illegal
    assert reg(board, "s6") == DELEGABLE_INTERRUPTS            # SSIP, STIP, SEIP


@pytest.mark.parametrize("engine", ENGINES)
def test_a_delegated_software_interrupt_waits_for_s_mode_with_sie(engine):
    board = run("""
        li      t0, 1 << 1
        csrw    mideleg, t0
        csrs    mie, t0
        csrsi   mstatus, 8                        # MIE: still not taken in M-mode (delegated)
        csrs    mip, t0                           # SSIP, written by software
        nop
        mv      s1, s5                            # nothing taken yet
        csrci   mstatus, 8
        li      t0, 1 << 7
        csrs    mstatus, t0                       # MPIE: mret into S-mode sets SIE from it
    """ + enter(1) + """
        nop
    """, engine)
    assert reg(board, "s1") == 0
    assert reg(board, "s5") == 1
    assert reg(board, "s2") == CAUSE_INTERRUPT | IRQ_SSI
    assert reg(board, "s11") == 0
    assert board.harts[0].privilege == 1                      # sret went back to S-mode


@pytest.mark.parametrize("engine", ENGINES)
def test_the_lowest_numbered_interrupt_is_taken_first(engine):
    """Rocket's PriorityEncoder: an SSIP (1) left in M-mode goes before the CLINT's MSIP (3);
    today's spec would take MSIP first."""
    board = run("""
        li      t0, 0x02000000
        li      t1, 1
        sw      t1, 0(t0)                         # msip[0]
        li      t0, (1 << 1) | (1 << 3)
        csrs    mie, t0
        li      t0, 1 << 1
        csrs    mip, t0                           # SSIP, not delegated
        la      t0, first
        csrw    mtvec, t0
        csrsi   mstatus, 8
        nop
        j       after
        .balign 4
    first:
        csrr    s1, mcause
        li      t0, 0x02000000
        sw      zero, 0(t0)
        li      t0, 2
        csrc    mip, t0
        la      t0, after
        csrw    mepc, t0
        mret
    after:
    """, engine)
    assert reg(board, "s1") == CAUSE_INTERRUPT | IRQ_SSI


@pytest.mark.parametrize("engine", ENGINES)
def test_mpie_keeps_the_interrupt_enable_of_the_mode_trapped_from(engine):
    """A trap from S-mode with SIE set and MIE clear saves SIE in MPIE (Rocket's
    `pie = read_mstatus(prv)`), not MIE as today's spec does."""
    board = run("""
        csrci   mstatus, 8
        li      t0, 1 << 7
        csrs    mstatus, t0                       # MPIE: mret into S-mode sets SIE from it
    """ + enter(1) + """
        ecall                                     # to M-mode (not delegated), SIE set, MIE clear
    """, engine)
    assert reg(board, "s8") == 9
    assert reg(board, "s10") & MSTATUS_MPIE


@pytest.mark.parametrize("engine", ENGINES)
def test_mret_to_u_mode_leaves_mie_alone(engine):
    board = run("""
        csrsi   mstatus, 8                        # MIE
        li      t0, 1 << 7
        csrs    mstatus, t0                       # MPIE
    """ + enter(0) + """
        ecall                                     # back in M: mstatus as mret left it
    """, engine)
    assert reg(board, "s8") == 8
    # mret to U-mode: MIE stays as it was (set), MPIE = 1; then the trap: MPIE = UIE = 0, MIE = 0
    assert not reg(board, "s10") & MSTATUS_MPIE
