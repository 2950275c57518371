"""Benchmark (not a test): how fast the board model runs compared with raw Unicorn.

Measured in one run on one host, so the ratios are meaningful even on a noisy machine:
  1. raw Unicorn on a tight 4-instruction loop, run with no instruction limit;
  2. the same loop on a board hart (native instruction counter, 20,000-instruction quanta);
  3. the board model running the project's firmware: emulated instructions per host second
     over both harts, frames per host second, and virtual frames per second.
Results are printed and written to build/bench.json.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import unicorn
from unicorn import riscv_const as rv

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from emulator.board import Board  # noqa: E402
from emulator.hart import CsrContext, Hart  # noqa: E402

LOOP_SOURCE = """
    .globl _start
_start:
    li t0, {iterations}
1:  addi t0, t0, -1
    addi t1, t1, 1
    xor t2, t2, t1
    bnez t0, 1b
    ebreak
"""


def assemble_loop(iterations: int, folder: Path) -> bytes:
    source = folder / "loop.S"
    source.write_text(LOOP_SOURCE.format(iterations=iterations))
    subprocess.run(["riscv64-unknown-elf-as", "-march=rv64gc", "-o", str(folder / "loop.o"), str(source)], check=True)
    subprocess.run(["riscv64-unknown-elf-ld", "-Ttext=0x80000000", "-N", "-o", str(folder / "loop.elf"),
                    str(folder / "loop.o")], check=True)
    subprocess.run(["riscv64-unknown-elf-objcopy", "-O", "binary", str(folder / "loop.elf"),
                    str(folder / "loop.bin")], check=True)
    return (folder / "loop.bin").read_bytes()


def raw_unicorn_mips(code: bytes, instructions: int) -> float:
    uc = unicorn.Uc(unicorn.UC_ARCH_RISCV, unicorn.UC_MODE_RISCV64)
    uc.mem_map(0x8000_0000, 0x10000)
    uc.mem_write(0x8000_0000, code)
    end = 0x8000_0000 + len(code) - 2      # stop at the ebreak
    start = time.perf_counter()
    uc.emu_start(0x8000_0000, end)
    return instructions / (time.perf_counter() - start) / 1e6


def hart_mips(code: bytes, instructions: int, quantum: int) -> float:
    hart = Hart(0, CsrContext(mcycle=lambda: 0, mip=lambda: 0))
    hart.uc.mem_map(0x8000_0000, 0x10000)
    hart.uc.mem_write(0x8000_0000, code)
    hart.pc = 0x8000_0000
    start = time.perf_counter()
    while hart.executed < instructions:
        hart.run(min(quantum, instructions - hart.executed))
    return hart.executed / (time.perf_counter() - start) / 1e6


def firmware_figures(firmware: Path, card: Path, frames: int) -> dict:
    board = Board(str(firmware), sd_image=str(card))
    start = time.perf_counter()
    board.run(frames)
    host = time.perf_counter() - start
    instructions = [h.instret for h in board.harts]
    return {
        "frames": frames,
        "host_time_s": host,
        "virtual_time_s": board.time,
        "instructions": instructions,
        "effective_mips": sum(instructions) / host / 1e6,
        "mips_while_executing": sum(instructions) / board.host_time_in_harts / 1e6,
        "share_of_host_time_executing": board.host_time_in_harts / host,
        "frames_per_host_second": frames / host,
        "virtual_fps": (frames - 1) / (board.frames[-1].virtual_time_s - board.frames[0].virtual_time_s),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--firmware", default=str(ROOT / "build" / "firmware.elf"))
    parser.add_argument("--card", default=str(ROOT / "build" / "card.img"))
    parser.add_argument("--frames", type=int, default=60)
    parser.add_argument("--loop-instructions", type=int, default=40_000_000)
    args = parser.parse_args()
    iterations = args.loop_instructions // 4
    with tempfile.TemporaryDirectory() as tmp:
        code = assemble_loop(iterations, Path(tmp))
    total = 4 * iterations + 1
    raw = raw_unicorn_mips(code, total)
    counted = hart_mips(code, total, 20_000)
    board = firmware_figures(Path(args.firmware), Path(args.card), args.frames)
    results = {
        "raw_unicorn_mips": raw,
        "hart_with_counter_mips": counted,
        "firmware": board,
        "ratio_hart_to_raw": counted / raw,
        "ratio_board_to_raw": board["effective_mips"] / raw,
    }
    print(f"raw Unicorn, tight loop, no limit:         {raw:8.1f} MIPS")
    print(f"board hart, same loop, exact counting:     {counted:8.1f} MIPS  ({counted / raw:.2f} x raw)")
    print(f"board model running the firmware:          {board['effective_mips']:8.1f} MIPS  "
          f"({board['effective_mips'] / raw:.3f} x raw)")
    print(f"  while harts execute (not asleep, not polling): {board['mips_while_executing']:8.1f} MIPS; "
          f"{100 * board['share_of_host_time_executing']:.0f} % of host time is spent executing")
    print(f"  {board['frames']} frames in {board['host_time_s']:.2f} s host = {board['frames_per_host_second']:.1f} frames/s; "
          f"virtual {board['virtual_fps']:.1f} frames/s; instructions per hart {board['instructions']}")
    out = ROOT / "build" / "bench.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"written to {out.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
