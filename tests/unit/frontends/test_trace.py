"""--trace-insn: an instruction trace of a window of virtual time (emulator/frontends/trace.py)."""
from __future__ import annotations

import json

import pytest

from suite import run_emulator
from emulator.frontends.trace import HEADER, InstructionTrace
from k210_fixtures import make_board, program, run_to_done, symbol

PROGRAM = """
    li      t1, 0x2000
    csrs    mstatus, t1               # FPU on (mstatus.FS)
    li      a0, 5
    addi    a0, a0, 1
    la      t0, cell
    fcvt.d.l fa0, a0
    fsd     fa0, 0(t0)
    ld      a1, 0(t0)
"""


def test_each_instruction_with_the_registers_it_wrote(tmp_path):
    board = make_board(program(PROGRAM, data="cell: .dword 0\n"))
    path = tmp_path / "trace.txt"
    trace = InstructionTrace(board, path.open("w"))
    run_to_done(board)
    trace.close()
    lines = path.read_text().splitlines()
    assert lines[0] + "\n" == HEADER
    start = symbol(board, "_start")
    body = [line for line in lines[1:] if line.startswith("0 ")]
    # the program's lines, from `li a0, 5` on
    first = next(i for i, line in enumerate(body) if "li a0, 5" in line or "c.li a0, 5" in line)
    ours = body[first:first + 7]
    assert ours[0].endswith("; a0=0x5") and "a0=0x6" in ours[1]
    assert any("fcvt.d.l fa0, a0" in line and "fa0=0x4018000000000000" in line for line in ours)
    assert any(line.split()[3] == "ld" and "a1=0x4018000000000000" in line for line in ours)
    hart, time_s, pc = ours[0].split()[:3]
    assert int(pc, 16) > start and float(time_s) > 0
    times = [float(line.split()[1]) for line in body]
    assert times == sorted(times)


def test_tracing_changes_no_count_and_a_window_holds_its_instructions(c_firmware, tmp_path):
    def run(out, *extra):
        result = run_emulator("run", str(c_firmware / "hello.elf"), "--until", "0.02", "--quiet", "--out",
                              str(out), *extra)
        assert result.returncode == 0, result.stderr
        return json.loads((out / "run.json").read_text())
    plain = run(tmp_path / "plain")
    whole = run(tmp_path / "whole", "--trace-insn", str(tmp_path / "whole.txt"))
    assert whole["instructions"] == plain["instructions"]
    assert whole["trace_insn"]["lines"] == sum(plain["instructions"])
    window = run(tmp_path / "window", "--trace-insn", str(tmp_path / "t.txt"), "--trace-from", "0.0002",
                 "--trace-to", "0.0004")
    times = [float(line.split()[1]) for line in (tmp_path / "t.txt").read_text().splitlines()[1:]]
    assert times and 0.0002 <= min(times) and max(times) <= 0.0004 + 1e-6
    assert window["trace_insn"]["lines"] == len(times)


@pytest.mark.parametrize("args, status, words", [
    (["--trace-from", "0.1"], 2, "--trace-from and --trace-to need --trace-insn"),
    (["--trace-insn", "T", "--trace-from", "0.2", "--trace-to", "0.1"], 2, "must come after --trace-from"),
    (["--trace-insn", "T", "--trace-from", "-1"], 2, "must be a finite number of seconds, 0 or more"),
    (["--trace-insn", "/nonexistent-folder/t.txt"], 6, "--trace-insn /nonexistent-folder/t.txt: cannot write it"),
])
def test_bad_trace_options(c_firmware, tmp_path, args, status, words):
    args = [str(tmp_path / "t.txt") if a == "T" else a for a in args]
    run = run_emulator("run", str(c_firmware / "hello.elf"), "--until", "0.01", *args, "--out", str(tmp_path / "o"))
    assert run.returncode == status and words in run.stderr, run.stderr
