"""The hardware breakpoint (cpu/triggers.py): one address-match trigger per hart, as the K210's
Rocket of early 2017 has it (rocket-chip 1322a026: Breakpoint.scala, CSR.scala, Rocket.scala)."""
from __future__ import annotations

import pytest

from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE
from emulator.cpu.riscv import CAUSE_BREAKPOINT
from emulator.cpu.decode import memory_access_kind as access_kind
from emulator.cpu.triggers import R, W, X, Trigger
from k210_fixtures import make_board, program, reg, run_to_done, symbol

# a trap handler that records mcause, mepc and mtval and steps over the instruction (4 bytes)
HANDLER = """
    la      t0, handler
    csrw    mtvec, t0
    j       main
    .balign 4
handler:
    csrr    s8, mcause
    csrr    s9, mepc
    csrr    s10, mtval
    addi    s11, s11, 1
    addi    t0, s9, 4
    csrw    mepc, t0
    mret
main:
"""


def run(body: str, engine: str, data: str = ""):
    board = make_board(program(HANDLER + body, data), engine=engine)
    run_to_done(board)
    return board


@pytest.mark.parametrize("engine", [ENGINE_PRECISE, ENGINE_FAST])
def test_an_execute_match_traps_before_the_instruction(engine):
    board = run("""
        la      a2, target
        csrw    tdata2, a2
        li      a0, (1 << 6) | (1 << 2)       # m, x
        csrw    tdata1, a0
        li      s1, 0
        .option push
        .option norvc
    target:
        addi    s1, s1, 1                     # never runs: the handler steps over it
        .option pop
        addi    s1, s1, 10
        csrw    tdata1, zero                  # disarmed again
    """, engine)
    assert reg(board, "s1") == 10
    assert reg(board, "s11") == 1
    assert reg(board, "s8") == CAUSE_BREAKPOINT
    assert reg(board, "s9") == reg(board, "s10") == symbol(board, "target")
    assert board.harts[0]._trigger_hook is None


@pytest.mark.parametrize("engine", [ENGINE_PRECISE, ENGINE_FAST])
def test_load_and_store_matches_give_the_address(engine):
    board = run("""
        la      a2, watched
        csrw    tdata2, a2
        li      a0, (1 << 6) | 1              # m, r: loads only
        csrw    tdata1, a0
        li      t1, 7
        .option push
        .option norvc
        sw      t1, 0(a2)                     # a store: no match
        lw      s1, 0(a2)                     # trapped, never loads
        .option pop
        mv      s2, s10
        li      a0, (1 << 6) | 2              # m, w: stores only
        csrw    tdata1, a0
        li      t1, 9
        .option push
        .option norvc
        amoadd.w s3, t1, (a2)                 # an AMO writes: trapped before it adds
        .option pop
        lw      s4, 0(a2)
        csrw    tdata1, zero
    """, engine, data="watched: .word 0")
    assert reg(board, "s11") == 2
    assert reg(board, "s1") == 0
    assert reg(board, "s2") == symbol(board, "watched")
    assert reg(board, "s10") == symbol(board, "watched")
    assert reg(board, "s4") == 7


def test_the_registers_read_as_rocket_s():
    board = run("""
        li      a0, -1
        csrw    tselect, a0
        csrr    s1, tselect                   # one trigger: no bits
        xori    a0, a0, 7                     # every bit but x, w, r (those would fire everywhere)
        csrw    tdata1, a0
        csrr    s2, tdata1
        li      a0, 1 << 38
        csrw    tdata2, a0
        csrr    s3, tdata2                    # 39 bits, sign-extended
        csrw    tdata1, zero
        csrr    s4, tdata1
    """, ENGINE_PRECISE)
    assert reg(board, "s1") == 0
    # type 2, maskmax 4, and only match, m, s, u, x, w, r taken (no dmode, action, chain, h)
    assert reg(board, "s2") == (2 << 60) | (4 << 53) | (3 << 7) | (1 << 6) | (1 << 4) | (1 << 3)
    assert reg(board, "s3") == (-(1 << 38)) & (2**64 - 1)
    assert reg(board, "s4") == (2 << 60) | (4 << 53)


def test_the_trigger_registers_are_machine_mode_only():
    board = run("""
        li      t0, 3 << 11
        csrc    mstatus, t0                   # MPP = U
        la      t0, 1f
        csrw    mepc, t0
        mret
    1:  csrr    s1, tdata1                    # illegal below M-mode
        ecall
        li      s7, 77
    """, ENGINE_PRECISE)
    assert reg(board, "s7") == 77
    assert reg(board, "s11") == 2               # the illegal read, stepped over, then the ecall
    assert reg(board, "s8") == 8


@pytest.mark.parametrize("match, address, hits, misses", [
    (0, 0x1000, [0x1000], [0x1001, 0xFFF]),
    (1, 0x1003, [0x1000, 0x1003, 0x1007], [0x1008, 0xFFF]),      # NAPOT: 0x1003 + 1 ones -> 8 bytes
    (1, 0x100F, [0x1000, 0x100F], [0x1010]),                      # maskmax 4: at most 16 bytes
    (1, 0x107F, [0x1070, 0x107F], [0x106F, 0x1080]),              # more ones than maskmax: still 16
    (2, 0x1000, [0x1000, 0x5000], [0xFFF]),                       # at or above
    (3, 0x1000, [0xFFF, 0], [0x1000]),                            # below
])
def test_address_matching(match, address, hits, misses):
    trigger = Trigger(control=(match << 7) | (1 << 6) | X, address=address)
    assert all(trigger.fires(X, 3, a) for a in hits)
    assert not any(trigger.fires(X, 3, a) for a in misses)
    assert not trigger.fires(X, 0, hits[0])    # u is clear: nothing fires in U-mode


def test_access_kinds():
    assert access_kind(0x0000A503) == R            # lw a0, 0(ra)
    assert access_kind(0x00A0A023) == W            # sw a0, 0(ra)
    assert access_kind(0x1000A52F) == R            # lr.w
    assert access_kind(0x18B5252F) == R | W        # sc.w: Rocket's isRead includes M_XSC
    assert access_kind(0x00B5252F) == R | W        # amoadd.w
    assert access_kind(0x4188) == R                # c.lw
    assert access_kind(0xC188) == W                # c.sw
    assert access_kind(0x00000013) == 0            # nop


def test_a_chip_reset_disarms_it():
    board = make_board(program("""
        li      a2, 0x100                     # never executed
        csrw    tdata2, a2
        li      a0, (1 << 6) | (1 << 2)
        csrw    tdata1, a0
    """))
    hart = board.harts[0]
    for _ in range(200):
        if hart._trigger_hook is not None:
            break
        board._step()
    assert hart.triggers.armed
    hart.reset(0x8000_0000)
    assert not hart.triggers.armed and hart._trigger_hook is None


def test_sfence_vm_of_1_9_1_is_a_no_op_without_paging():
    """The K210's TLB flush instruction (1.9.1's sfence.vm, which Unicorn's 1.10 calls illegal)
    runs in M-mode; with paging off there is nothing to flush."""
    board = run("""
        .word   0x10400073                    # sfence.vm zero
        li      s1, 1
    """, ENGINE_PRECISE)
    assert reg(board, "s1") == 1
    assert reg(board, "s11") == 0
