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

import numpy as np
import unicorn

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


THESIS_MODEL_BYTES = round(38.8 * 1024)      # the thesis's model A: 400 polygons, 38.8 KiB .obj
THESIS_TEXTURE_BYTES = round(183.2 * 1024)   # and its 250 x 250 texture, 183.2 KiB .ppm


def sd_figures(firmware: Path, folder: Path) -> dict:
    """Virtual times of SD bring-up and of loading files the size of the thesis's model A
    (from the console lines' timestamps; each span includes printing its console line)."""
    from sdcard_image import build_image
    sys.path.insert(0, str(ROOT / "tools"))
    from make_assets import torus

    model = torus().encode()
    model += b"#" * (THESIS_MODEL_BYTES - len(model) - 1) + b"\n"       # padded to the thesis's size
    header = b"P6\n# padded to the thesis's texture size\n250 250\n255\n"
    pixels = bytes((i * 7) & 0xFF for i in range(250 * 250 * 3))
    texture = header[:4] + b"#" * (THESIS_TEXTURE_BYTES - len(header) - len(pixels)) + header[4:] + pixels
    (folder / "a").mkdir()
    (folder / "a" / "model.obj").write_bytes(model)
    (folder / "a" / "texture.ppm").write_bytes(texture)
    card = folder / "thesis.img"
    build_image(card, [folder / "a"], scene={"model": "a/model.obj", "texture": "a/texture.ppm"})
    board = Board(str(firmware), sd_image=str(card))
    board.run(1)
    times = {}
    for t, line in board.console_lines:
        for key in ("lcd:", "fat32:", "load scene.ini", "load a/model.obj", "load a/texture.ppm"):
            if line.startswith(key):
                times[key] = t
    board.close()
    return {
        "model_bytes": len(model), "texture_bytes": len(texture),
        "card_setup_to_root_ms": (times["fat32:"] - times["lcd:"]) * 1e3,
        "model_read_ms": (times["load a/model.obj"] - times["load scene.ini"]) * 1e3,
        "texture_read_ms": (times["load a/texture.ppm"] - times["load a/model.obj"]) * 1e3,
        "thesis_ms": {"card_setup_to_root": 32.35, "texture_read": 200.75, "model_read": 43.05},
    }


# The thesis's three test models, at the two scales it measured each at (the `scale` key)
THESIS_SCENES = [
    ("A torus 400 tri, 250x250", "models/torus.obj", "textures/torus.ppm", (0.35, 0.175)),
    ("B gem 64 tri, 100x78", "models/gem.obj", "textures/gem.ppm", (0.9, 0.45)),
    ("C cube 6 faces, 8x8", "models/cube.obj", "textures/cube.ppm", (0.9, 0.45)),
]
MODES = ("textured", "flat", "wireframe")
BENCH_FRAMES = 6


def renderer_figures(firmware: Path, folder: Path) -> list[dict]:
    """Instructions per frame per hart, virtual frame time and frame rate for every thesis scene,
    scale and mode (steady state: the first frame, which includes loading, is left out)."""
    from sdcard_image import build_image
    subprocess.run([sys.executable, str(ROOT / "tools" / "make_assets.py"), str(folder / "assets")], check=True)
    records = []
    for name, model, texture, scales in THESIS_SCENES:
        for scale in scales:
            for mode in MODES:
                card = folder / "card.img"
                scene = {"model": model, "texture": texture, "mode": mode, "scale": str(scale),
                         "translate": "0 0 -3", "step": "4"}
                build_image(card, [folder / "assets" / "models", folder / "assets" / "textures"], scene=scene,
                            force=True)
                frame_images: list[np.ndarray] = []
                board = Board(str(firmware), sd_image=str(card), on_frame=lambda record, image: frame_images.append(image))
                board.run(BENCH_FRAMES)
                board.close()
                quality = compare_with_reference(card, frame_images)
                steady = board.frames[1:]
                hart0 = sum(f.instructions[0] for f in steady) / len(steady)
                hart1 = sum(f.instructions[1] for f in steady) / len(steady)
                frame_time = (steady[-1].virtual_time_s - board.frames[0].virtual_time_s) / len(steady)
                records.append({
                    "scene": name, "mode": mode, "scale": scale,
                    "instructions_hart0": round(hart0), "instructions_hart1": round(hart1),
                    "draw_time_ms": hart0 / board.cpu_hz() * 1e3,
                    "frame_time_ms": frame_time * 1e3, "fps": 1 / frame_time,
                    **quality,
                })
    return records


def compare_with_reference(card: Path, frames: list[np.ndarray]) -> dict:
    """How far the firmware's frames are from the float64 reference renderer's (reference/):
    PSNR over all frames, the largest channel error and the share of pixels that differ."""
    import reference
    scene, mesh, texture = reference.load_card_image(card)
    squared, largest, differing, pixels = 0.0, 0, 0, 0
    for n, shown in enumerate(frames):
        expected = reference.render_image(scene, mesh, texture, n).astype(np.int32)
        error = np.abs(shown.astype(np.int32) - expected)
        squared += float((error.astype(np.float64) ** 2).sum())
        largest = max(largest, int(error.max()))
        differing += int(np.any(error, axis=2).sum())
        pixels += error.shape[0] * error.shape[1]
    mse = squared / (pixels * 3)
    return {"psnr_db": float("inf") if mse == 0 else 10 * np.log10(255 ** 2 / mse),
            "max_error": largest, "pixels_differ": differing / pixels}


def write_renderer_table(records: list[dict], folder: Path) -> str:
    lines = ["| scene | scale | mode | instructions hart 0 / frame | hart 1 / frame | draw time (ms) | "
             "frame time (ms) | fps | PSNR vs reference (dB) | max error | pixels differ |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in records:
        lines.append(f"| {r['scene']} | {r['scale']:g} | {r['mode']} | {r['instructions_hart0']:,} | "
                     f"{r['instructions_hart1']:,} | {r['draw_time_ms']:.2f} | {r['frame_time_ms']:.2f} | "
                     f"{r['fps']:.1f} | {r['psnr_db']:.1f} | {r['max_error']} | {100 * r['pixels_differ']:.2f} % |")
    table = "\n".join(lines) + "\n"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "results.json").write_text(json.dumps(records, indent=2) + "\n")
    (folder / "results.md").write_text(table)
    return table


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--firmware", default=str(ROOT / "build" / "firmware.elf"))
    parser.add_argument("--card", default=str(ROOT / "build" / "card.img"))
    parser.add_argument("--frames", type=int, default=60)
    parser.add_argument("--loop-instructions", type=int, default=40_000_000)
    parser.add_argument("--no-renderer", action="store_true", help="skip the per-scene renderer table")
    args = parser.parse_args()
    iterations = args.loop_instructions // 4
    with tempfile.TemporaryDirectory() as tmp:
        code = assemble_loop(iterations, Path(tmp))
    total = 4 * iterations + 1
    raw = raw_unicorn_mips(code, total)
    counted = hart_mips(code, total, 20_000)
    board = firmware_figures(Path(args.firmware), Path(args.card), args.frames)
    with tempfile.TemporaryDirectory() as tmp:
        sd = sd_figures(Path(args.firmware), Path(tmp))
    results = {
        "raw_unicorn_mips": raw,
        "hart_with_counter_mips": counted,
        "firmware": board,
        "ratio_hart_to_raw": counted / raw,
        "ratio_board_to_raw": board["effective_mips"] / raw,
        "sd": sd,
    }
    print(f"raw Unicorn, tight loop, no limit:         {raw:8.1f} MIPS")
    print(f"board hart, same loop, exact counting:     {counted:8.1f} MIPS  ({counted / raw:.2f} x raw)")
    print(f"board model running the firmware:          {board['effective_mips']:8.1f} MIPS  "
          f"({board['effective_mips'] / raw:.3f} x raw)")
    print(f"  while harts execute (not asleep, not polling): {board['mips_while_executing']:8.1f} MIPS; "
          f"{100 * board['share_of_host_time_executing']:.0f} % of host time is spent executing")
    print(f"  {board['frames']} frames in {board['host_time_s']:.2f} s host = {board['frames_per_host_second']:.1f} frames/s; "
          f"virtual {board['virtual_fps']:.1f} frames/s; instructions per hart {board['instructions']}")
    print(f"SD (virtual time; thesis in brackets): card set-up to root directory {sd['card_setup_to_root_ms']:.2f} ms "
          f"[32.35], model {sd['model_bytes']} bytes {sd['model_read_ms']:.2f} ms [43.05], "
          f"texture {sd['texture_bytes']} bytes {sd['texture_read_ms']:.2f} ms [200.75]")
    if not args.no_renderer:
        with tempfile.TemporaryDirectory() as tmp:
            records = renderer_figures(Path(args.firmware), Path(tmp))
        print(write_renderer_table(records, ROOT / "build" / "bench"))
        print("renderer figures written to build/bench/results.json and build/bench/results.md")
    out = ROOT / "build" / "bench.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"written to {out.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
