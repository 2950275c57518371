"""Traps, delegation and interrupt order as the K210's Rocket of early 2017 has them (privileged
spec 1.9.1; rocket-chip 1322a026 rocket/CSR.scala), where they differ from today's spec, on both
engines (cpu/privileged.py)."""
from __future__ import annotations

import pytest

from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE
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
    mret
1:  li      t0, 0x02000000
    sw      zero, 0(t0)                       # an MSIP that brought us here is done
    mret
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
    # CSR.scala: delegable_exceptions = misaligned_fetch, fault_fetch, breakpoint, fault_load,
    # fault_store, user_ecall; delegable_interrupts = SSIP, STIP, SEIP
    assert reg(board, "s1") == 0x1AB
    assert reg(board, "s6") == 0x222


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
    `pie = read_mstatus(prv)`); today's spec would save MIE, 0."""
    board = run("""
        li      t0, 0x88
        csrc    mstatus, t0                       # MIE = MPIE = 0
    """ + enter(1) + """
        csrsi   sstatus, 2                        # SIE, from S-mode
        ecall                                     # to M-mode (not delegated)
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


@pytest.mark.parametrize("engine", ENGINES)
def test_a_pending_interrupt_is_taken_at_once_below_m_mode(engine):
    """M-level interrupts are enabled below M-mode whatever MIE says: an mret to U-mode with
    MSIP pending takes it before U-mode's first instruction."""
    board = run("""
        li      t0, 1 << 3
        csrs    mie, t0
        li      t0, 0x02000000
        li      t1, 1
        sw      t1, 0(t0)                         # msip[0], MIE clear: not taken in M-mode
        li      t0, 1 << 7
        csrs    mstatus, t0                       # MPIE: an mret to U-mode leaves MIE clear all the same
        li      s1, 0
    """ + enter(0) + """
    first_user:
        addi    s1, s1, 1                         # the handler clears msip and comes back here
    """, engine)
    assert reg(board, "s8") == CAUSE_INTERRUPT | 3
    assert reg(board, "s9") == symbol(board, "first_user")
    assert reg(board, "s1") == 1


@pytest.mark.parametrize("engine", ENGINES)
def test_u_mode_with_the_fpu_off_traps_on_floating_point(engine):
    board = run("""
        li      t0, 3 << 13
        csrc    mstatus, t0                       # FS = 0
    """ + enter(0) + """
        li      t1, 1
        addi    t1, t1, 1
        addi    t1, t1, 1
        fmv.d.x f1, t1                            # illegal with the FPU off
    """, engine)
    assert reg(board, "s8") == 2 and reg(board, "s11") >= 1


def test_a_trap_delegated_to_stvec_needs_no_mtvec():
    board = run("""
        li      t0, 1 << 8
        csrw    medeleg, t0
        csrw    mtvec, zero                       # the delegated ecall never goes there
    """ + enter(0) + """
        ecall
    """, ENGINE_PRECISE)
    assert reg(board, "s5") == 1 and reg(board, "s2") == 8


def test_sret_ends_the_handled_trap():
    board = run("""
        li      t0, 1 << 3
        csrw    medeleg, t0
    """ + enter(1) + """
        .option push
        .option norvc
        ebreak                                    # to stvec; its handler returns with sret
        .option pop
    """, ENGINE_PRECISE)
    assert reg(board, "s5") == 1 and reg(board, "s2") == 3
    assert board.harts[0].open_trap is None


def test_mstatus_at_reset_and_mpp_as_rocket_keeps_it():
    """Reset: MPP = M (`reset_mstatus.mpp := PRV.M`). MPP keeps even 2 (`trimPrivilege` with VM);
    an mret then restores MIE from MPIE and enters U-mode."""
    board = run("""
        csrr    s1, mstatus
        li      t0, 3 << 11
        csrc    mstatus, t0
        li      t0, 2 << 11
        csrs    mstatus, t0
        csrr    s6, mstatus
        li      t0, 1 << 7
        csrs    mstatus, t0                       # MPIE
        la      t0, 1f
        csrw    mepc, t0
        mret
    1:  ecall                                     # from U-mode: cause 8, MPIE = UIE = 0
    """, ENGINE_PRECISE)
    assert reg(board, "s1") & (3 << 11) == 3 << 11
    assert reg(board, "s6") & (3 << 11) == 2 << 11
    assert reg(board, "s8") == 8
    assert reg(board, "s10") & 8 == 0                    # the ecall cleared MIE again


def test_the_counter_enables_gate_cycle_below_m_mode():
    board = run("""
        csrw    0x320, zero                       # mucounteren: nothing for U-mode
        csrr    s1, 0x320
        li      t0, -1
        csrw    0x321, t0                         # mscounteren: what Rocket has
        csrr    s6, 0x321
    """ + enter(0) + """
        rdcycle t1                                # illegal in U-mode now
    """, ENGINE_PRECISE)
    assert reg(board, "s1") == 0 and reg(board, "s6") == 0b101
    assert reg(board, "s8") == 2


def test_sptbr_keeps_the_root_page_number_only():
    board = run("""
        li      t0, 0x8000000000000001 | (0xFFFFF << 0)
        csrw    0x180, t0
        csrr    s1, 0x180
        la      t0, marker
        lw      s6, 0(t0)                         # still untranslated
        j       2f
        .balign 4
    marker:
        .word   0x1234
    2:
    """, ENGINE_PRECISE)
    assert reg(board, "s1") == 0xFFFFF
    assert reg(board, "s6") == 0x1234
