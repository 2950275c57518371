"""--profile (emulator/frontends/profile.py): instructions and cycles per function, exclusive and
inclusive, with calls, and the folded call stacks."""
from __future__ import annotations

import json

from suite import run_emulator
from emulator.frontends.profile import Profiler, decode_call, function_starts
from k210_fixtures import make_board, program, run_to_done, symbol

CALLS = """
    j       main_code
outer:                                # 9 instructions a call, and inner twice
    addi    sp, sp, -16
    sd      ra, 0(sp)
    call    inner
    call    inner
    ld      ra, 0(sp)
    addi    sp, sp, 16
    ret
inner:                                # li + 3 x (addi, bnez) + ret = 8 instructions a call
    li      t1, 3
1:  addi    t1, t1, -1
    bnez    t1, 1b
    ret
    .globl  main_code                 # a global label: a function of its own (the spin at done too)
main_code:
    li      sp, 0x80100000
    call    outer
    call    outer
"""


def test_exclusive_inclusive_and_calls_are_exact():
    elf = program(CALLS)
    board = make_board(elf)
    profiler = Profiler(board, elf)
    run_to_done(board)
    profiler._account(board.harts[0])
    figures = profiler.figures[0]
    # inner: li + 3 x (addi, bnez) + ret = 8 instructions a call, 4 calls
    assert (figures["inner"].instructions, figures["inner"].calls) == (32, 4)
    # outer: addi, sd, 2 x (auipc, jalr), ld, addi, ret = 9 a call, 2 calls
    assert (figures["outer"].instructions, figures["outer"].calls) == (18, 2)
    assert figures["outer"].inclusive_instructions == 18 + 32
    assert figures["outer"].cycles > figures["outer"].instructions      # the Rocket timing: loads, calls cost more
    stacks = profiler.folded[0]
    assert any(path.endswith(";outer;inner") for path in stacks)


def test_calls_through_auipc_and_jalr_name_their_targets():
    elf = program(CALLS)
    names = [name for _, name in function_starts(elf)]
    assert "outer" in names and "inner" in names and "done" not in names   # a loop label is no function
    assert decode_call(0x000080E7)[0] and not decode_call(0x00008067)[0]   # jalr ra, 0(ra) / ret


def test_the_command_writes_the_table_and_the_folded_stacks(c_firmware, tmp_path):
    run = run_emulator("run", str(c_firmware / "hello.elf"), "--until", "0.02", "--quiet", "--profile",
                       "--out", str(tmp_path))
    assert run.returncode == 0, run.stderr
    table = (tmp_path / "profile.txt").read_text()
    assert "hart 0" in table and "printf" in table
    folded = (tmp_path / "profile.folded").read_text().splitlines()
    assert folded and all(line.startswith(("hart0;", "hart1;")) and line.rsplit(" ", 1)[1].isdigit()
                          for line in folded)
    summary = json.loads((tmp_path / "run.json").read_text())
    total = sum(f["instructions"] for f in summary["profile"]["functions"]["hart0"].values())
    assert total == summary["instructions"][0]
