"""Benchmark (not a test): how fast the board model runs, and what each frame costs and how good it is.

Measured in one run on one host, so the ratios are meaningful even on a noisy machine:
  1. raw Unicorn on a tight 4-instruction loop, run with no instruction limit;
  2. the same loop on a board hart (native instruction counter, 20,000-instruction quanta);
  3. the board model running the project's firmware: emulated instructions per host second
     over both harts, frames per host second, and virtual frames per second; instructions and
     CPU cycles per frame, reset to the first frame in virtual ms, under the Rocket cycle timing
     (the default) and under --timing ipc1, and the host cost of the cycle model (runs of both
     alternate, the fastest of each counts); hart 0's drawing of a frame alone (no scheduler, no
     devices) on the fast engine, on the precise one and on Unicorn with no hook;
  4. the same with --check-writes (the native store checker), as a ratio to 3 (runs of both
     alternate, and the fastest of each counts, so that a busy moment of the host does not
     decide the ratio).
Those are printed and written to build/bench.json. Then, per thesis scene and mode, runs of the
firmware measured against the float64 reference renderer's two images, the pixel-centre one (the
firmware's sampling, exact arithmetic) and the ideal one (area-averaged pixels, area-filtered
textures) (instructions per frame, PSNR, largest channel error, share of pixels that differ, against
each), written to build/bench/:
  - the renderer table: every scene, scale and mode with the default settings;
  - the precision sweep: every scene at its first scale, every mode, every precision setting of
    tools/quality.py's SETTINGS, with the Pareto front of instructions against PSNR:
    quality.csv, quality.md and quality.svg;
  - the ideal image's own figures per scene and mode: its host time per frame and its convergence
    (frame 0 at the default density against twice it);
  - results.json holds every record (each names its `setting`), results.md the tables;
  - both harts drawing (issue 12): heavy scenes with `harts = 1` and `harts = 2`, cycles per
    frame on each hart, the frame period and the speed-up, and that both show the same frames:
    harts.json, and a table in results.md;
  - macro pre-removal (issue 12): the Transputer seed's macro Z-buffer simulated on the scenes
    (tools/macro_zbuffer.py): what it would skip per tile size: macro_zbuffer.json, and results.md.

    python tools/bench.py                        (what `make bench` runs: everything)
    python tools/bench.py --quality-only --scenes cube --modes flat --settings default,gouraud
"""
from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import math
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import unicorn

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from emulator.board import Board  # noqa: E402
from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE, INSN_WFI, CsrContext, Hart, HartState  # noqa: E402
from emulator.memory_map import SRAM_BASE  # noqa: E402
from emulator.vtime import to_seconds  # noqa: E402
from emulator.cpu.timing import TIMING_IPC1, TIMING_ROCKET, TIMING_ROCKET_NOCACHE  # noqa: E402
from tools import quality  # noqa: E402

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


def firmware_figures(firmware: Path, card: Path, frames: int, check_writes: bool = False,
                     timing: str = TIMING_ROCKET, engine: str = ENGINE_FAST) -> dict:
    board = Board(str(firmware), sd_image=str(card), check_writes=check_writes, timing=timing, engine=engine)
    start = time.perf_counter()
    board.run(frames)
    host = time.perf_counter() - start
    instructions = [h.instret for h in board.harts]
    steady = board.frames[1:]
    return {
        "timing": timing,
        "frames": frames,
        "reset_to_first_frame_ms": board.frames[0].virtual_time_s * 1e3,
        "instructions_per_frame": [round(sum(f.instructions[h] for f in steady) / len(steady)) for h in (0, 1)],
        "cycles_per_frame": [round(sum(f.cycles[h] for f in steady) / len(steady)) for h in (0, 1)],
        "cycles": [h.cycles for h in board.harts],
        "mispredicts": [h.mispredicts for h in board.harts],
        "stall_cycles": [h.stall_cycles for h in board.harts],
        "host_time_s": host,
        "virtual_time_s": to_seconds(board.time),
        "instructions": instructions,
        "effective_mips": sum(instructions) / host / 1e6,
        "mips_while_executing": sum(instructions) / board.host_time_in_harts / 1e6,
        "share_of_host_time_executing": board.host_time_in_harts / host,
        "frames_per_host_second": frames / host,
        "virtual_fps": (frames - 1) / (board.frames[-1].virtual_time_s - board.frames[0].virtual_time_s),
        **real_time_figures(board.frames),
        "engine": engine,
        "fast_share": board.harts[0].fast_statistics().get("instructions", 0) / board.harts[0].executed,
    }


def real_time_figures(frames: list) -> dict:
    """After loading (from the first frame on): virtual seconds per host second (the real-time
    factor; 1.0 runs as fast as a Dock), in wall time and in the process's CPU time, and host
    milliseconds per frame against virtual ones."""
    first, last = frames[0], frames[-1]
    host = last.host_time_s - first.host_time_s
    cpu = last.host_cpu_s - first.host_cpu_s
    virtual = last.virtual_time_s - first.virtual_time_s
    count = len(frames) - 1
    return {"real_time_factor": virtual / host, "real_time_factor_cpu": virtual / cpu,
            "host_ms_per_frame": host / count * 1e3, "host_cpu_ms_per_frame": cpu / count * 1e3,
            "virtual_ms_per_frame": virtual / count * 1e3}


def fastest(runs: list[dict]) -> dict:
    """The real-time factors of the fastest of several runs of one configuration: in wall time the
    fastest run by wall time, in CPU time the fastest by CPU time (which may be another run: the host's
    busy moments only ever slow a run down, in either clock)."""
    return {"real_time_factor": max(r["real_time_factor"] for r in runs),
            "real_time_factor_cpu": max(r["real_time_factor_cpu"] for r in runs),
            "host_ms_per_frame": min(r["host_ms_per_frame"] for r in runs),
            "host_cpu_ms_per_frame": min(r["host_cpu_ms_per_frame"] for r in runs),
            "virtual_ms_per_frame": runs[0]["virtual_ms_per_frame"], "runs": len(runs)}


def _steady_drawing(firmware: Path, card: Path, engine: str) -> tuple[Board, Hart, Callable[[], int]]:
    """A board of the default card stopped at a steady frame's start (hart 0 asleep), and a function
    that puts hart 0 back there with both framebuffers marked free (so that it draws on) and returns
    the pc to run it from."""
    board = Board(str(firmware), sd_image=str(card), engine=engine)
    board.run(3)
    scheduler = board.scheduler
    while scheduler.harts[0].state is not HartState.ASLEEP:
        scheduler.step()
    hart = scheduler.harts[0]
    memory = board.memory.bytes
    snapshot = np.array(memory, copy=True)
    context, pc = hart.uc.context_save(), hart.pc
    fb_state = board.image.symbol_values["fb_state"] - SRAM_BASE

    def restore() -> int:
        memory[:] = snapshot
        memory[fb_state:fb_state + 8] = 0          # both buffers free: hart 0 draws on
        hart.uc.context_restore(context)
        hart.lift_limits()
        return pc
    return board, hart, restore


def drawing_figures(firmware: Path, card: Path, rounds: int = 3) -> dict:
    """What hart 0's drawing costs the host per instruction with no scheduler and no devices, from a
    steady frame's start to its next wfi: on the fast engine (the few instructions it hands over
    run on the precise one), and on the precise engine, Unicorn with the counting hook, with the
    Rocket cycle table and with one cycle each, and Unicorn with no hook at all. Decoded blocks and
    translations are dropped before each run, so that each way runs code decoded or translated for
    it; the fastest of `rounds` counts."""
    ways = {}
    board, hart, restore = _steady_drawing(firmware, card, ENGINE_FAST)

    def draw_fast() -> tuple[float, int]:
        pc = restore()
        hart.forget_decodings()
        executed = hart.executed
        start = time.perf_counter()
        while True:
            pc = hart.run_fast_stretch(pc)
            if hart.read_u32(pc) == INSN_WFI:
                break
            hart.uc.emu_start(pc, 0, count=1)      # an instruction the fast engine hands over
            pc = hart.reg(unicorn.riscv_const.UC_RISCV_REG_PC)
        return time.perf_counter() - start, hart.executed - executed

    seconds, instructions = min(draw_fast() for _ in range(rounds))
    ways["fast engine, Rocket cycle table"] = {"seconds": seconds, "instructions": instructions,
                                               "ns_per_instruction": seconds / instructions * 1e9,
                                               "mips": instructions / seconds / 1e6}
    board.close()
    board, hart, restore = _steady_drawing(firmware, card, ENGINE_PRECISE)

    def draw() -> tuple[float, int]:
        pc = restore()
        hart.uc.ctl_flush_tb()
        executed = hart.executed
        start = time.perf_counter()
        hart.uc.emu_start(pc, 0)
        return time.perf_counter() - start, hart.executed - executed

    for way in ("precise engine, Rocket cycle table", "precise engine, one cycle each", "no hook"):
        if way == "precise engine, one cycle each":
            hart.install_cycle_table(None)
        elif way == "no hook":
            hart.remove_counter()
        seconds, instructions = min(draw() for _ in range(rounds))
        if way == "no hook":
            instructions = ways["precise engine, one cycle each"]["instructions"]
        ways[way] = {"seconds": seconds, "instructions": instructions,
                     "ns_per_instruction": seconds / instructions * 1e9, "mips": instructions / seconds / 1e6}
    board.close()
    return ways


PROFILE_FRAMES = 12
PROFILE_TOP = 12


def profile_figures(firmware: Path, card: Path, frames: int = PROFILE_FRAMES) -> dict:
    """The default scene under --profile: hart 0's functions per steady frame (frames 1.. of
    `frames`), by cycles, and the host time per frame with and without the profiler."""
    from emulator.frontends.profile import Profiler
    timings = {}
    for profiled in (False, True):
        board = Board(str(firmware), sd_image=str(card))
        profiler = Profiler(board, firmware) if profiled else None
        if profiler is not None:
            board.on_frame = lambda record, image: profiler.frame(record)
        board.run(frames)
        steady = board.frames[-1].host_time_s - board.frames[0].host_time_s
        timings[profiled] = steady / (frames - 1)
    first, last = profiler._frame_marks[0][0], profiler._frame_marks[-1][0]
    per_frame = sorted(((cycles - first.get(name, (0, 0))[1], instructions - first.get(name, (0, 0))[0], name)
                        for name, (instructions, cycles) in last.items()), reverse=True)
    total = sum(c for c, _, _ in per_frame)
    rows = [{"function": name, "cycles_per_frame": round(c / (frames - 1)),
             "instructions_per_frame": round(i / (frames - 1)), "share": c / total}
            for c, i, name in per_frame[:PROFILE_TOP] if c]
    return {"frames": frames, "hart0_per_frame": rows, "host_s_per_frame": timings[False],
            "host_s_per_frame_profiled": timings[True], "cost": timings[True] / timings[False]}


THESIS_MODEL_BYTES = round(38.8 * 1024)      # the thesis's model A: 400 polygons, 38.8 KiB .obj
THESIS_TEXTURE_BYTES = round(183.2 * 1024)   # and its 250 x 250 texture, 183.2 KiB .ppm


def sd_figures(firmware: Path, folder: Path, timing: str = TIMING_ROCKET) -> dict:
    """Virtual times of SD bring-up and of loading files the size of the thesis's model A
    (from the console lines' timestamps: when each line's last byte left the UART). Card set-up
    runs from the "pins:" line, hart 0's last before it turns to the card (hart 1 brings the LCD
    up meanwhile), to the "fat32:" line. Hart 0's lines wait in the console's relay until hart 1
    sends them (main.S), so a span can be off by the UART's backlog at either end (the boot
    lines' 8 ms at the first). The texture is loaded whole first; the model is then read through
    obj.S's window twice: its load line ends the first pass (read and checked), its "model:" line
    the second (read again and stored). Also the first frame's virtual time."""
    from sdcard_image import build_image
    sys.path.insert(0, str(ROOT / "tools"))
    from make_assets import torus

    model = torus().encode()
    model += b"#" * (THESIS_MODEL_BYTES - len(model) - 1) + b"\n"       # padded to the thesis's size
    header = b"P6\n# padded to the thesis's texture size\n250 250\n255\n"
    pixels = bytes((i * 7) & 0xFF for i in range(250 * 250 * 3))
    texture = header[:4] + b"#" * (THESIS_TEXTURE_BYTES - len(header) - len(pixels)) + header[4:] + pixels
    (folder / "a").mkdir(exist_ok=True)
    (folder / "a" / "model.obj").write_bytes(model)
    (folder / "a" / "texture.ppm").write_bytes(texture)
    card = folder / "thesis.img"
    if not card.exists():
        build_image(card, [folder / "a"], scene={"model": "a/model.obj", "texture": "a/texture.ppm"})
    board = Board(str(firmware), sd_image=str(card), timing=timing)
    board.run(2)     # (hart 1 relays hart 0's last load lines after the first frame when loading ends late)
    times = {}
    for t, line in board.console_lines:
        for key in ("pins:", "fat32:", "load scene.ini", "load a/texture.ppm", "load a/model.obj", "model:"):
            if line.startswith(key):
                times[key] = to_seconds(t)
    board.close()
    return {
        "timing": timing, "reset_to_first_frame_ms": board.frames[0].virtual_time_s * 1e3,
        "model_bytes": len(model), "texture_bytes": len(texture),
        "card_setup_to_root_ms": (times["fat32:"] - times["pins:"]) * 1e3,
        "texture_read_ms": (times["load a/texture.ppm"] - times["load scene.ini"]) * 1e3,
        "model_read_ms": (times["load a/model.obj"] - times["load a/texture.ppm"]) * 1e3,
        "model_second_pass_ms": (times["model:"] - times["load a/model.obj"]) * 1e3,
        "thesis_ms": {"card_setup_to_root": 32.35, "texture_read": 200.75, "model_read": 43.05,
                      "start_up_model_a": 344.3},
    }


# The bench's scenes; the renderer table has every scale, the precision sweep each first scale.
LOAD_SIZES = {"64 KiB": 64 * 1024, "512 KiB": 512 * 1024, "2 MiB": 2 * 1024 * 1024, "5 MiB": 5 * 1024 * 1024}
LOAD_MODEL = "models/cube.obj"     # the smallest model: the texture is what is measured


def texture_of_size(size: int) -> bytes:
    """A binary PPM of exactly `size` bytes: the largest square that fits, its header padded with
    a comment (the firmware reads every byte of the file either way)."""
    side = 1
    while len(f"P6\n{side + 1} {side + 1}\n255\n") + 3 * (side + 1) ** 2 <= size:
        side += 1
    header = f"P6\n{side} {side}\n255\n".encode()
    pixels = (bytes(range(256)) * (3 * side * side // 256 + 1))[:3 * side * side]
    padding = size - len(header) - len(pixels)
    comment = b"#" + b"-" * max(0, padding - 2) + b"\n" if padding >= 2 else b"\n" * padding
    return header[:3] + comment + header[3:] + pixels


def load_figures(firmware: Path, folder: Path) -> dict:
    """Host seconds to load textures of LOAD_SIZES through the firmware: from the console's
    "load scene.ini" line to its "load <texture>" line (fat32_read.S reading the file by SD block with
    its CRC16 and CRC-32 checks, sd_read.S), each line's time taken when its newline reaches the console
    (hart 1 relays hart 0's lines, so both ends lag the event by the relay's backlog, alike). The
    run stops at the texture's line (the texture's conversion and the first frame are not in it).
    Also the virtual time of the same span."""
    from emulator.errors import ConsoleExpectationsMet
    from sdcard_image import build_image

    figures = {}
    for label, size in LOAD_SIZES.items():
        name = f"load{size}"
        (folder / name).mkdir(exist_ok=True)
        (folder / name / "texture.ppm").write_bytes(texture_of_size(size))
        (folder / name / "model.obj").write_bytes((ROOT / "build" / "assets" / LOAD_MODEL).read_bytes())
        card = folder / f"{name}.img"
        build_image(card, [folder / name], scene={"model": f"{name}/model.obj", "texture": f"{name}/texture.ppm"},
                    force=True)
        marks: dict[str, tuple[float, float]] = {}
        line = bytearray()
        board: Board | None = None

        def console(byte: int) -> None:
            if byte != 10:
                line.append(byte)
                return
            text = line.decode("ascii", "replace")
            line.clear()
            for key in ("load scene.ini", f"load {name}/texture.ppm"):
                if text.startswith(key):
                    marks[key] = (time.perf_counter(), board.uarths.last_byte_time)
            if text.startswith(f"load {name}/texture.ppm"):
                board.stop_run(ConsoleExpectationsMet("texture loaded"))

        board = Board(str(firmware), sd_image=str(card), console=console)
        try:
            board.run(1)
        except ConsoleExpectationsMet:
            pass
        finally:
            board.close()
        (host0, virtual0), (host1, virtual1) = marks["load scene.ini"], marks[f"load {name}/texture.ppm"]
        figures[label] = {"bytes": size, "host_s": host1 - host0, "virtual_ms": to_seconds(virtual1 - virtual0) * 1e3,
                          "host_s_per_mib": (host1 - host0) / (size / 2**20)}
    return figures


BENCH_SCENES = [
    # the thesis's three test models, at the two scales it measured each at (the `scale` key)
    ("A torus 400 tri, 250x250", "models/torus.obj", "textures/torus.ppm", (0.35, 0.175)),
    ("B gem 64 tri, 100x78", "models/gem.obj", "textures/gem.ppm", (0.9, 0.45)),
    ("C cube 6 faces, 8x8", "models/cube.obj", "textures/cube.ppm", (0.9, 0.45)),
    # where depth precision shows: a label 0.0005 in front of a wall, 3 units from the camera
    ("D decal 2 quads 0.0005 apart, 64x64", "models/decal.obj", "textures/decal.ppm", (1.0,)),
    # held in (issue 34): models and textures of the kinds users bring, none tuned for
    ("E icosphere 5120 tri, 128x128", "held-in/icosphere.obj", "held-in/icosphere.ppm", (0.9,)),
    ("F cylinder 32-gon caps, 64x64", "held-in/cylinder.obj", "held-in/cylinder.ppm", (0.9,)),
    ("G 2 quads crossing at slope 1e-4", "held-in/crossing.obj", "held-in/crossing.ppm", (1.0,)),
    ("H 4096x1 stripes on a quad at 80 degrees", "held-in/slant.obj", "held-in/stripes.ppm", (1.0,)),
    ("I sphere 5,120 tri with a logo, 256x128", "models/sphere.obj", "held-in/logo.ppm", (0.9,)),
    ("J monkey-like head 1,832 tri, 128x128", "held-in/monkey.obj", "held-in/monkey.ppm", (0.9,)),
]
# The motion of every bench scene: angles that are not multiples of 2 degrees, so that the angle
# table's rounding shows as it would in a user's scene (with 2-degree multiples it is exact).
BENCH_MOTION = {"translate": "0 0 -3", "angle": "17", "step": "3"}
MODES = ("textured", "flat", "wireframe")
BENCH_FRAMES = 6


def scene_id(model: str) -> str:
    """The short name --scenes takes: the model's file name without extension (torus, gem, cube)."""
    return Path(model).stem


def planned_runs(scenes: list[str], modes: list[str], settings: list[str] | None,
                 renderer: bool, sweep: bool) -> list[tuple]:
    """(scene name, model, texture, scale, mode, setting) of every run, once each, in table order:
    the renderer table is every scale and mode with the default setting; the precision sweep is
    each scene's first scale, every mode, every setting of that mode (limited to `settings`)."""
    runs = []
    for name, model, texture, scales in BENCH_SCENES:
        if scene_id(model) not in scenes:
            continue
        for scale in scales:
            for mode in modes:
                wanted = []
                if renderer:
                    wanted.append(quality.DEFAULT_SETTING)
                if sweep and scale == scales[0]:
                    wanted += quality.settings_for_mode(mode, settings)
                for setting in quality.settings_for_mode(mode, set(wanted)):
                    runs.append((name, model, texture, scale, mode, setting))
    return runs


def in_sweep(record: dict) -> bool:
    """Whether a record is at its scene's sweep scale (so belongs in the precision tables)."""
    return any(record["scene"] == name and record["scale"] == scales[0] for name, _, _, scales in BENCH_SCENES)


_warned: set[str] = set()


def _warn_once(message: str) -> None:
    """The card builder's notes (such as a scene key it does not know yet), each printed once."""
    if message not in _warned:
        _warned.add(message)
        print(f"bench: card: {message}", file=sys.stderr, flush=True)


def make_bench_assets(folder: Path) -> None:
    """The bench's models and textures (tools/make_assets.py) under folder/assets."""
    subprocess.run([sys.executable, str(ROOT / "tools" / "make_assets.py"), str(folder / "assets")], check=True,
                   capture_output=True)


def build_bench_card(folder: Path, card: Path, scene: dict) -> None:
    """`card` from the bench's assets in `folder` (make_bench_assets) with `scene`'s keys."""
    from sdcard_image import build_image
    build_image(card, [folder / "assets" / "models", folder / "assets" / "textures", folder / "assets" / "held-in"],
                scene=scene, force=True, on_warning=_warn_once)


def run_bench_card(firmware: Path, folder: Path, card: Path, scene: dict) -> tuple[Board, list[np.ndarray]]:
    """Builds `card` (build_bench_card) and runs the firmware on it for BENCH_FRAMES frames; returns the
    (closed) board and the frames shown."""
    build_bench_card(folder, card, scene)
    images: list[np.ndarray] = []
    board = Board(str(firmware), sd_image=str(card), on_frame=lambda record, image: images.append(image))
    try:
        board.run(BENCH_FRAMES)
    finally:
        board.close()
    return board, images


def measure(firmware: Path, folder: Path, name: str, model: str, texture: str, scale: float, mode: str,
            setting: str) -> dict:
    """One scene, mode and precision setting on the board model for BENCH_FRAMES frames: instructions
    per frame per hart, virtual frame time and frame rate (steady state: the first frame, which
    includes loading, is left out) and the distance of all frames from the reference renderer's
    pixel-centre and ideal images."""
    started = time.perf_counter()
    keys = quality.SETTINGS[setting]
    card = folder / "card.img"
    scene = {"model": model, "texture": texture, "mode": mode, "scale": str(scale), **BENCH_MOTION, **keys}
    board, frame_images = run_bench_card(firmware, folder, card, scene)
    compared = compare_with_reference(card, frame_images)
    steady = board.frames[1:]
    hart0 = sum(f.instructions[0] for f in steady) / len(steady)
    hart1 = sum(f.instructions[1] for f in steady) / len(steady)
    cycles0 = sum(f.cycles[0] for f in steady) / len(steady)
    cycles1 = sum(f.cycles[1] for f in steady) / len(steady)
    frame_time = (steady[-1].virtual_time_s - board.frames[0].virtual_time_s) / len(steady)
    return {
        "scene": name, "mode": mode, "scale": scale, "setting": setting, "setting_keys": dict(keys),
        "instructions_hart0": round(hart0), "instructions_hart1": round(hart1),
        "cycles_hart0": round(cycles0), "cycles_hart1": round(cycles1),
        "draw_time_ms": cycles0 / board.scheduler.cpu_hz() * 1e3,
        "frame_time_ms": frame_time * 1e3, "fps": 1 / frame_time,
        **compared,
        "host_time_s": time.perf_counter() - started,
    }


# Scenes heavy enough that hart 0 alone draws slower than the LCD takes a frame: the 5,120-triangle
# sphere textured (256 x 256) filling most of the screen, and larger; and with filter = mipmap.
HARTS_SCENES = [
    ("E sphere 5,120 tri, 256x256", "models/sphere.obj", "textures/sphere.ppm", 1.2, {}),
    ("E sphere 5,120 tri, 256x256", "models/sphere.obj", "textures/sphere.ppm", 1.5, {}),
    ("E sphere 5,120 tri, 256x256, mipmap", "models/sphere.obj", "textures/sphere.ppm", 1.5, {"filter": "mipmap"}),
]


def harts_run(firmware: Path, folder: Path, model: str, texture: str, scale: float, keys: dict,
              harts: str) -> tuple[dict, list[np.ndarray]]:
    """One heavy scene with `harts`: steady-state cycles and instructions per frame per hart (frames
    2.. of BENCH_FRAMES: frame 0 includes loading, and frame 1 is hart 0's alone with auto) and
    the frame period; and the frames."""
    scene = {"model": model, "texture": texture, "mode": "textured", "scale": str(scale), **BENCH_MOTION, **keys,
             "harts": harts}
    board, images = run_bench_card(firmware, folder, folder / "harts.img", scene)
    steady = board.frames[2:]
    period = (steady[-1].virtual_time_s - board.frames[1].virtual_time_s) / len(steady)
    return {"harts": harts, **real_time_figures(board.frames[1:]),
            "cycles": [round(sum(f.cycles[h] for f in steady) / len(steady)) for h in (0, 1)],
            "instructions": [round(sum(f.instructions[h] for f in steady) / len(steady)) for h in (0, 1)],
            "frame_period_ms": period * 1e3, "frame_period_cycles": round(period * board.scheduler.cpu_hz())}, images


def harts_figures(firmware: Path, folder: Path) -> list[dict]:
    """Every HARTS_SCENES scene with one hart drawing and with both: the speed-up of the frame
    period (both are drawing-bound: the LCD takes LCD_FRAME_CYCLES, 3,072,000 cycles, a frame)."""
    records = []
    for name, model, texture, scale, keys in HARTS_SCENES:
        one, one_images = harts_run(firmware, folder, model, texture, scale, keys, "1")
        two, two_images = harts_run(firmware, folder, model, texture, scale, keys, "2")
        same = len(one_images) == len(two_images) and all(np.array_equal(a, b) for a, b in zip(one_images, two_images))
        records.append({"scene": name, "scale": scale, "one": one, "two": two, "same_frames": same,
                        "speed_up": one["frame_period_ms"] / two["frame_period_ms"]})
        print(f"[harts] {name}, scale {scale:g}: one hart {one['frame_period_ms']:.2f} ms, both "
              f"{two['frame_period_ms']:.2f} ms, {records[-1]['speed_up']:.2f} x, frames "
              f"{'identical' if same else 'DIFFERENT'}", file=sys.stderr, flush=True)
    return records


def harts_table(records: list[dict]) -> str:
    """The table of harts_figures."""
    lines = ["| scene | scale | one hart: cycles / frame (hart 0) | frame period (ms) | both: cycles / frame hart 0, "
             "hart 1 | frame period (ms) | speed-up | frames | real-time factor one, both (CPU time) |",
             "|---|---|---:|---:|---:|---:|---:|---|---:|"]
    for r in records:
        one, two = r["one"], r["two"]
        lines.append(f"| {r['scene']} | {r['scale']:g} | {one['cycles'][0]:,} | {one['frame_period_ms']:.2f} | "
                     f"{two['cycles'][0]:,}, {two['cycles'][1]:,} | {two['frame_period_ms']:.2f} | "
                     f"{r['speed_up']:.2f} x | {'identical' if r['same_frames'] else 'DIFFERENT'} | "
                     f"{one['real_time_factor_cpu']:.2f}, {two['real_time_factor_cpu']:.2f} |")
    return "\n".join(lines) + "\n"


def scene_figures(firmware: Path, folder: Path, runs: list[tuple]) -> tuple[list[dict], list[str]]:
    """Every planned run (see planned_runs); returns the records and, for the runs that failed
    (a firmware that rejects a setting, a reference that cannot render it), what went wrong."""
    make_bench_assets(folder)
    records, failures = [], []
    for n, (name, model, texture, scale, mode, setting) in enumerate(runs, 1):
        what = f"{name}, scale {scale:g}, {mode}, {setting}"
        try:
            records.append(measure(firmware, folder, name, model, texture, scale, mode, setting))
        except Exception as error:     # noqa: BLE001  (reported, and the bench exits with status 1)
            failures.append(f"{what}: {type(error).__name__}: {error}")
            print(f"[{n}/{len(runs)}] {what}: FAILED: {type(error).__name__}: {error}", file=sys.stderr, flush=True)
            continue
        print(f"[{n}/{len(runs)}] {what}: {records[-1]['instructions_hart0']:,} instructions/frame, "
              f"{records[-1]['cycles_hart0']:,} cycles/frame, "
              f"PSNR {records[-1]['psnr_db']:.2f} dB, against the ideal {records[-1]['psnr_ideal_db']:.2f} dB, "
              f"{records[-1]['host_time_s']:.1f} s",
              file=sys.stderr, flush=True)
    return records, failures


@dataclass
class ReferenceFrames:
    """The reference renderer's frames of one scene (RGB as the LCD shows them): the pixel-centre
    image, the ideal image (a camera's: textures read smooth, as filtered; reference/ideal.py) and
    the ideal with square texels (as nearest-texel sampling draws a magnified texture); and the
    ideal's own figures: host seconds per frame, and frame 0 at the default density against twice
    the density (PSNR, dB)."""
    pixel_centre: list[np.ndarray]
    ideal: list[np.ndarray]
    square: list[np.ndarray]
    ideal_seconds_per_frame: float
    ideal_convergence_db: float


# The reference ignores the precision keys, so every setting of a scene shares its frames: rendered
# once per scene, mode and scale (the ideal takes about a second a frame); the pixel-centre image
# follows `filter`, so once per filter too.
_reference_cache: dict[tuple, ReferenceFrames] = {}
# The ideal image ignores `filter` too: shared by the filter settings of a scene.
_ideal_cache: dict[tuple, tuple[list[np.ndarray], list[np.ndarray], float, float]] = {}


def _reference_key(scene, mesh, texture, count: int, ideal: bool = False) -> tuple:
    """What the reference's frames depend on: the scene without its precision keys (and, for the
    ideal image, which area-filters every texture, without `filter`), the model's arrays, the
    texture's texels and the number of frames."""
    from reference.scene import PRECISION_WORDS
    ignored = set(PRECISION_WORDS) | {"light_levels", "lines"} | ({"filter"} if ideal else set())
    fields = tuple((f.name, repr(getattr(scene, f.name))) for f in dataclasses.fields(scene) if f.name not in ignored)
    digest = hashlib.sha256()
    for array in (mesh.vertices, mesh.texcoords, mesh.normals, mesh.faces,
                  np.zeros(0) if texture is None else texture):
        digest.update(repr(array.shape).encode() + np.ascontiguousarray(array).tobytes())
    return fields, digest.hexdigest(), count


def reference_frames(card: Path, count: int) -> ReferenceFrames:
    """Frames 0 .. count-1 of the card's scene from the reference renderer, both images."""
    import reference
    from reference.ideal import DEFAULT_DENSITY
    scene, mesh, texture = reference.load_card_image(card)
    key = _reference_key(scene, mesh, texture, count)
    if key not in _reference_cache:
        pixel_centre = [reference.render_image(scene, mesh, texture, n) for n in range(count)]
        ideal_key = _reference_key(scene, mesh, texture, count, ideal=True)
        if ideal_key not in _ideal_cache:
            started = time.perf_counter()
            ideal = [reference.render_ideal_image(scene, mesh, texture, n, texels="smooth") for n in range(count)]
            seconds = (time.perf_counter() - started) / count
            square = [reference.render_ideal_image(scene, mesh, texture, n, texels="square") for n in range(count)]
            denser = reference.render_ideal_image(scene, mesh, texture, 0, density=2 * DEFAULT_DENSITY,
                                                  texels="smooth")
            _ideal_cache[ideal_key] = (ideal, square, seconds, distance(ideal[:1], [denser])["psnr_db"])
        _reference_cache[key] = ReferenceFrames(pixel_centre, *_ideal_cache[ideal_key])
    return _reference_cache[key]


def distance(shown: list[np.ndarray], expected: list[np.ndarray]) -> dict:
    """PSNR over all frames (infinite when equal), the largest channel error and the share of
    pixels that differ, of RGB frames against the expected ones."""
    squared, largest, differing, pixels = 0.0, 0, 0, 0
    for image, wanted in zip(shown, expected):
        error = np.abs(image.astype(np.int32) - wanted.astype(np.int32))
        squared += float((error.astype(np.float64) ** 2).sum())
        largest = max(largest, int(error.max()))
        differing += int(np.any(error, axis=2).sum())
        pixels += error.shape[0] * error.shape[1]
    mse = squared / (pixels * 3)
    return {"psnr_db": float("inf") if mse == 0 else float(10 * np.log10(255 ** 2 / mse)),
            "max_error": largest, "pixels_differ": differing / pixels}


def compare_with_reference(card: Path, frames: list[np.ndarray]) -> dict:
    """How far the firmware's frames are from the float64 reference renderer's (reference/): PSNR
    over all frames, the largest channel error and the share of pixels that differ, against its
    pixel-centre image (psnr_db, max_error, pixels_differ), its ideal image (the same names
    ending in _ideal) and the ideal with square texels (psnr_square_db, max_error_square,
    pixels_differ_square), with the ideal's density,
    host time per frame and convergence."""
    from reference.ideal import DEFAULT_DENSITY
    expected = reference_frames(card, len(frames))
    ideal, square = distance(frames, expected.ideal), distance(frames, expected.square)
    return {**distance(frames, expected.pixel_centre),
            "psnr_ideal_db": ideal["psnr_db"], "max_error_ideal": ideal["max_error"],
            "pixels_differ_ideal": ideal["pixels_differ"],
            "psnr_square_db": square["psnr_db"], "max_error_square": square["max_error"],
            "pixels_differ_square": square["pixels_differ"],
            "ideal_density": DEFAULT_DENSITY, "ideal_seconds_per_frame": expected.ideal_seconds_per_frame,
            "ideal_convergence_db": expected.ideal_convergence_db}


def _db(value: float | None) -> str:
    return "" if value is None else f"{value:.1f}"


def renderer_table(records: list[dict]) -> str:
    """The renderer table: the default setting at every scene, scale and mode."""
    lines = ["| scene | scale | mode | instructions hart 0 / frame | cycles hart 0 / frame | hart 1 instructions / "
             "frame | draw time (ms) | frame time (ms) | fps | PSNR vs reference (dB) | max error | pixels differ | "
             "PSNR vs ideal (dB) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in records:
        if r["setting"] != quality.DEFAULT_SETTING:
            continue
        lines.append(f"| {r['scene']} | {r['scale']:g} | {r['mode']} | {r['instructions_hart0']:,} | "
                     f"{r['cycles_hart0']:,} | {r['instructions_hart1']:,} | {r['draw_time_ms']:.2f} | "
                     f"{r['frame_time_ms']:.2f} | "
                     f"{r['fps']:.1f} | {r['psnr_db']:.1f} | {r['max_error']} | {100 * r['pixels_differ']:.2f} % | "
                     f"{_db(r.get('psnr_ideal_db'))} |")
    return "\n".join(lines) + "\n"


def ideal_table(records: list[dict]) -> str:
    """The ideal image's own figures, once per scene, scale and mode (from the first record that
    carries them): density, host time per frame, and frame 0 against twice the density."""
    lines = ["| scene | scale | mode | density | host time per ideal frame (s) | "
             "PSNR against twice the density, frame 0 (dB) |",
             "|---|---|---|---:|---:|---:|"]
    seen = set()
    for r in records:
        key = (r["scene"], r["scale"], r["mode"])
        if key in seen or r.get("ideal_density") is None:
            continue
        seen.add(key)
        convergence = r["ideal_convergence_db"]
        lines.append(f"| {r['scene']} | {r['scale']:g} | {r['mode']} | {r['ideal_density']} | "
                     f"{r['ideal_seconds_per_frame']:.2f} | "
                     f"{'exact' if convergence is None or math.isinf(convergence) else f'{convergence:.1f}'} |")
    return "\n".join(lines) + "\n" if seen else ""


# the record's figures that are infinite for frames equal to what they are compared with
INFINITE_WHEN_EQUAL = ("psnr_db", "psnr_ideal_db", "psnr_square_db", "ideal_convergence_db")


def strict_json_record(record: dict) -> dict:
    """The record as strict JSON holds it: an infinite PSNR (frames equal to the reference's) is
    written as null, since JSON has no Infinity and strict readers reject Python's extension."""
    return {**record, **{key: None for key in INFINITE_WHEN_EQUAL
                         if record.get(key) is not None and math.isinf(record[key])}}


def write_results(records: list[dict], folder: Path, renderer: bool, sweep: bool) -> str:
    """results.json (every record, each with its `setting`), results.md (the renderer table and the
    precision table), and quality.csv, quality.md, quality.svg; returns what to print."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "results.json").write_text(json.dumps([strict_json_record(r) for r in records], indent=2,
                                                    allow_nan=False) + "\n")
    printed, md = "", ""
    if renderer:
        table = renderer_table(records)
        md += "## Renderer: every thesis scene, scale and mode, default settings\n\n" + table
        printed += table
    ideal = ideal_table(records)
    if ideal:
        md += (("\n" if md else "") + "## The ideal image: host time per frame and convergence (reference/ideal.py)\n\n"
               + ideal)
        printed += ("\n" if printed else "") + ideal
    if sweep:
        swept = [r for r in records if in_sweep(r)]
        report = quality.write_quality(swept, folder)
        md += (("\n" if md else "") + "## Precision settings: instructions against error "
               "(also quality.csv, quality.md, quality.svg)\n\n" + report)
        printed += ("\n" if printed else "") + report
    (folder / "results.md").write_text(md)
    return printed


def _names(text: str | None, allowed: list[str], what: str) -> list[str] | None:
    if text is None:
        return None
    names = [n.strip() for n in text.split(",") if n.strip()]
    unknown = [n for n in names if n not in allowed]
    if unknown:
        raise SystemExit(f"bench: unknown {what} {', '.join(unknown)} (known: {', '.join(allowed)})")
    return names


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--firmware", default=str(ROOT / "build" / "firmware.elf"))
    parser.add_argument("--card", default=str(ROOT / "build" / "card.img"))
    parser.add_argument("--frames", type=int, default=60)
    parser.add_argument("--loop-instructions", type=int, default=40_000_000)
    parser.add_argument("--out", default=str(ROOT / "build" / "bench"),
                        help="folder for results.json, results.md, quality.csv/.md/.svg (default build/bench)")
    parser.add_argument("--no-speed", action="store_true",
                        help="skip the speed figures (raw Unicorn, board hart, firmware, SD) and build/bench.json")
    parser.add_argument("--no-renderer", action="store_true",
                        help="no per-scene runs at all (neither the renderer table nor the precision sweep)")
    parser.add_argument("--no-quality", action="store_true", help="skip the precision sweep")
    parser.add_argument("--load-only", action="store_true",
                        help="only the host time of loading textures through the firmware (printed)")
    parser.add_argument("--quality-only", action="store_true",
                        help="only the precision sweep: no speed figures, no renderer table")
    parser.add_argument("--settings", help="comma-separated settings for the sweep (default: all): "
                        + ", ".join(quality.SETTINGS))
    parser.add_argument("--scenes", help="comma-separated scenes (default: all): "
                        + ", ".join(scene_id(model) for _, model, _, _ in BENCH_SCENES))
    parser.add_argument("--modes", help="comma-separated modes (default: all): " + ", ".join(MODES))
    parser.add_argument("--harts-only", action="store_true",
                        help="only the heavy scenes with one and with both harts drawing (harts.json)")
    args = parser.parse_args()
    settings = _names(args.settings, list(quality.SETTINGS), "setting")
    scenes = _names(args.scenes, [scene_id(model) for _, model, _, _ in BENCH_SCENES], "scene") \
        or [scene_id(model) for _, model, _, _ in BENCH_SCENES]
    modes = _names(args.modes, list(MODES), "mode") or list(MODES)
    if args.load_only:
        with tempfile.TemporaryDirectory() as tmp:
            print_load_figures(load_figures(Path(args.firmware), Path(tmp)))
        return 0
    renderer = not args.no_renderer and not args.quality_only
    sweep = not args.no_renderer and not args.no_quality
    if args.harts_only:
        return harts_main(Path(args.firmware), Path(args.out))
    speed = None
    if not args.quality_only and not args.no_speed:
        speed = speed_figures(args)
    failures: list[str] = []
    swept: list[dict] = []
    if renderer or sweep:
        runs = planned_runs(scenes, modes, settings, renderer, sweep)
        with tempfile.TemporaryDirectory() as tmp:
            records, failures = scene_figures(Path(args.firmware), Path(tmp), runs)
        out = Path(args.out)
        printed = write_results(records, out, renderer, sweep)
        if sweep and not failures and settings is None and scenes == [scene_id(m) for _, m, _, _ in BENCH_SCENES] \
                and modes == list(MODES):
            swept = [strict_json_record(r) for r in records if in_sweep(r)]
        if renderer:
            harts_main(Path(args.firmware), out)
            macro_zbuffer_main(out)
        print(printed)
        print(f"{len(records)} runs of {len(runs)} written to {out}: results.json, results.md"
              + (", quality.csv, quality.md, quality.svg" if sweep else ""))
    for failure in failures:
        print(f"FAILED: {failure}")
    if speed is not None or swept:
        # a partial sweep (--settings, --scenes, --modes) is not recorded: the page's table compares
        # every setting on every scene, from one run
        from tools import bench_history
        bench_history.append(speed, swept)
        print(f"recorded in {bench_history.HISTORY.relative_to(ROOT)}; the tables in "
              f"{bench_history.PAGE.relative_to(ROOT)}")
    return 1 if failures else 0


def append_to_results(out: Path, heading: str, text: str) -> None:
    """A section (`## heading`, then text) added at the end of OUT/results.md."""
    results = out / "results.md"
    previous = results.read_text() if results.exists() else ""
    results.write_text(previous + ("\n" if previous else "") + f"## {heading}\n\n" + text)


def macro_zbuffer_main(out: Path) -> None:
    """Issue 12's macro pre-removal, simulated on the bench's scenes (tools/macro_zbuffer.py: what the
    Transputer seed's macro Z-buffer would skip, per tile size): printed, written to
    OUT/macro_zbuffer.json and appended to OUT/results.md."""
    import macro_zbuffer
    records = macro_zbuffer.report()
    out.mkdir(parents=True, exist_ok=True)
    (out / "macro_zbuffer.json").write_text(json.dumps(records, indent=2) + "\n")
    lines = macro_zbuffer.format_report(records)
    append_to_results(out, "Macro Z-buffer, simulated", "```\n" + "\n".join(lines) + "\n```\n")
    print("\n".join(lines))


def harts_main(firmware: Path, out: Path) -> int:
    """The heavy scenes with one and both harts: printed, written to OUT/harts.json and appended to
    OUT/results.md; status 1 when two harts showed other frames than one."""
    with tempfile.TemporaryDirectory() as tmp:
        make_bench_assets(Path(tmp))
        records = harts_figures(firmware, Path(tmp))
    out.mkdir(parents=True, exist_ok=True)
    (out / "harts.json").write_text(json.dumps(records, indent=2) + "\n")
    table = harts_table(records)
    append_to_results(out, "Both harts drawing (harts = 1 against 2)", table)
    print(table)
    return 0 if all(r["same_frames"] for r in records) else 1


def write_check_figures(firmware: Path, card: Path, frames: int, unchecked: dict, rounds: int = 2) -> dict:
    """The board with --check-writes against the board without: `rounds` runs of each, alternating
    (the first unchecked one is `unchecked`), compared fastest to fastest."""
    plain, checked = [unchecked], []
    for n in range(rounds):
        checked.append(firmware_figures(firmware, card, frames, check_writes=True))
        if n + 1 < rounds:
            plain.append(firmware_figures(firmware, card, frames))
    best_plain = max(plain, key=lambda figures: figures["effective_mips"])
    best = max(checked, key=lambda figures: figures["effective_mips"])
    if best["instructions"] != best_plain["instructions"]:
        raise SystemExit(f"bench: --check-writes changed the firmware's run: {best['instructions']} instructions "
                         f"against {best_plain['instructions']}")
    return {**best, "rounds": rounds,
            "ratio_to_unchecked": best["effective_mips"] / best_plain["effective_mips"],
            "ratio_while_executing": best["mips_while_executing"] / max(p["mips_while_executing"] for p in plain)}


def timing_figures(firmware: Path, card: Path, frames: int, rocket: dict, rounds: int = 2,
                   other: str = TIMING_IPC1) -> dict:
    """The firmware under --timing `other` (ipc1, or rocket-nocache) against the default timing: `rounds`
    runs of each, alternating (the first default one is `rocket`), compared fastest to fastest by host
    time a frame after loading. The frames are the same instructions either way and come at the LCD's
    pace, so this is what the timing costs the host a frame; the whole run's host time would mix in
    the loading, whose virtual length the timing changes (it counted 0.996 x for ipc1 where the frames
    cost 1.2 x)."""
    timed, flat = [rocket], []
    for n in range(rounds):
        flat.append(firmware_figures(firmware, card, frames, timing=other))
        if n + 1 < rounds:
            timed.append(firmware_figures(firmware, card, frames))
    best_timed = min(timed, key=lambda figures: figures["host_ms_per_frame"])
    best_flat = min(flat, key=lambda figures: figures["host_ms_per_frame"])
    return {**best_flat, "rounds": rounds, "rocket_runs": timed[1:],
            "host_cost_of_cycle_model": best_timed["host_ms_per_frame"] / best_flat["host_ms_per_frame"]}


# The both-harts workload of the speed figures: the heaviest of HARTS_SCENES, both harts drawing
HEAVY_BOTH_HARTS = {"model": "models/sphere.obj", "texture": "textures/sphere.ppm", "mode": "textured", "scale": "1.5",
                    **BENCH_MOTION, "harts": "2"}


def both_harts_figures(firmware: Path, rounds: int = 2, frames: int = 24) -> dict:
    """The real-time factor after loading with both harts drawing the heavy sphere (HEAVY_BOTH_HARTS),
    fastest of `rounds` runs (issue 31 asks 1.0 of it)."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        make_bench_assets(folder)
        card = folder / "heavy.img"
        build_bench_card(folder, card, HEAVY_BOTH_HARTS)
        runs = []
        for _ in range(rounds):
            board = Board(str(firmware), sd_image=str(card))
            try:
                board.run(frames)
            finally:
                board.close()
            # from frame 1 on: frame 0 includes loading (and hart 1 splits the frames from frame 1)
            runs.append(real_time_figures(board.frames[1:]))
    return fastest(runs)


def print_load_figures(loads: dict) -> None:
    print("loading a texture through the firmware (console's \"load scene.ini\" to \"load <texture>\" lines):")
    for label, figures in loads.items():
        print(f"  {label:>8}: {figures['host_s']:6.2f} s host ({figures['host_s_per_mib']:.2f} s per MiB), "
              f"{figures['virtual_ms']:8.1f} ms virtual")


THESIS_START_UP_MS = {"A": 344.3, "B": 122.2, "C": 87.8}   # power-up to its main loop, measured on a Dock


def output_memory_figures(counts: tuple[int, ...] = (1_000, 10_000)) -> dict:
    """The run output's memory against its length (issue 35): the process's resident memory after
    `counts` frames written through RunOutput (frame_NNNN.png and the animation as they come), in a
    child process each, so that one count's memory does not carry into the next. Frames are
    noise, the worst case for compression."""
    figures = {}
    for count in counts:
        code = (
            "import os, sys, tempfile, numpy as np\n"
            "from emulator.board import FrameRecord\n"
            "from emulator.frontends.output import RunOutput\n"
            "def rss(): return int(open('/proc/self/statm').read().split()[1]) * os.sysconf('SC_PAGE_SIZE')\n"
            "rng = np.random.default_rng(1)\n"
            "with tempfile.TemporaryDirectory() as folder:\n"
            "    output = RunOutput(folder)\n"
            "    start = rss()\n"
            f"    for index in range({count}):\n"
            "        output.frame(FrameRecord(index, index * 0.05, [0, 0], [0, 0], 0.0),\n"
            "                     rng.integers(0, 256, (240, 320, 3), dtype=np.uint8))\n"
            "    end = rss()\n"
            "    output.finish({})\n"
            "print(start, end)\n")
        started = time.perf_counter()
        result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
        start, end = (int(x) for x in result.stdout.split())
        figures[str(count)] = {"rss_before_mb": start / 1e6, "rss_after_mb": end / 1e6,
                               "host_s": time.perf_counter() - started}
    return figures


# A firmware feeding SPI0's transmit FIFO from the CPU, a byte a store, waiting on TXFLR for room: each
# store and each poll is a device access the board carries out in Python (issue 32, item 9).
CPU_FED_SPI_SOURCE = """
    .option norelax
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, park
    li      s0, 0x52000000              # SPI0
    sw      zero, 0x08(s0)              # ssienr = 0
    li      t0, (7 << 16) | (1 << 8)    # 8-bit frames, transmit only
    sw      t0, 0x00(s0)
    li      t0, 4
    sw      t0, 0x14(s0)                # baudr
    li      t0, 1
    sw      t0, 0x10(s0)                # ser
    sw      t0, 0x08(s0)                # ssienr = 1
    li      s1, {stores}
1:  lw      t1, 0x20(s0)                # txflr
    li      t2, 32
    bgeu    t1, t2, 1b
    sw      s1, 0x60(s0)                # dr0
    addi    s1, s1, -1
    bnez    s1, 1b
done:
    j       done
park:
    csrw    mie, zero
2:  wfi
    j       2b
"""


def cpu_fed_spi_figures(stores: int = 20_000, rounds: int = 3) -> dict:
    """Host time of a firmware that feeds SPI0 from the CPU (CPU_FED_SPI_SOURCE): per FIFO store and
    per device access (the stores and the TXFLR polls the bus carried out), best of `rounds`."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "feed.S").write_text(CPU_FED_SPI_SOURCE.format(stores=stores))
        subprocess.run(["riscv64-unknown-elf-as", "-march=rv64gc", "-o", str(folder / "feed.o"),
                        str(folder / "feed.S")], check=True)
        subprocess.run(["riscv64-unknown-elf-ld", "-N", "--no-warn-rwx-segments", "-Ttext=0x80000000", "-o", str(folder / "feed.elf"),
                        str(folder / "feed.o")], check=True)
        best_cpu = best_wall = math.inf
        for _ in range(rounds):
            board = Board(str(folder / "feed.elf"))
            done = next(address for address, name in board.image.symbols.items() if name == "done")
            cpu, wall = time.process_time(), time.perf_counter()
            while board.harts[0].pc != done:
                board.scheduler.step()
            best_cpu = min(best_cpu, time.process_time() - cpu)
            best_wall = min(best_wall, time.perf_counter() - wall)
            accesses = board.harts[0].device_accesses
            virtual_ms = board.harts[0].time / 1e9      # (picoseconds to ms)
    return {"stores": stores, "device_accesses": accesses, "virtual_ms": virtual_ms,
            "host_cpu_us_per_store": best_cpu / stores * 1e6, "host_wall_us_per_store": best_wall / stores * 1e6,
            "rounds": rounds}


def speed_figures(args: argparse.Namespace) -> dict:
    """Raw Unicorn, a board hart and the board model running the firmware; SD timings. Printed,
    written to build/bench.json and returned."""
    iterations = args.loop_instructions // 4
    with tempfile.TemporaryDirectory() as tmp:
        code = assemble_loop(iterations, Path(tmp))
    total = 4 * iterations + 1
    raw = raw_unicorn_mips(code, total)
    counted = hart_mips(code, total, 20_000)
    board = firmware_figures(Path(args.firmware), Path(args.card), args.frames)
    precise = firmware_figures(Path(args.firmware), Path(args.card), args.frames, engine=ENGINE_PRECISE)
    checked = write_check_figures(Path(args.firmware), Path(args.card), args.frames, board)
    ipc1 = timing_figures(Path(args.firmware), Path(args.card), args.frames, board)
    nocache = timing_figures(Path(args.firmware), Path(args.card), args.frames, board, other=TIMING_ROCKET_NOCACHE)
    # the default card's real-time factor: the fastest of the runs of the default timing above
    best = fastest([board] + ipc1["rocket_runs"] + nocache["rocket_runs"])
    both_harts = both_harts_figures(Path(args.firmware))
    profile = profile_figures(Path(args.firmware), Path(args.card))
    drawing = drawing_figures(Path(args.firmware), Path(args.card))
    with tempfile.TemporaryDirectory() as tmp:
        sd = sd_figures(Path(args.firmware), Path(tmp))
        sd_ipc1 = sd_figures(Path(args.firmware), Path(tmp), timing=TIMING_IPC1)
        loads = load_figures(Path(args.firmware), Path(tmp))
    output_memory = output_memory_figures()
    cpu_fed_spi = cpu_fed_spi_figures()
    results = {
        "raw_unicorn_mips": raw,
        "hart_with_counter_mips": counted,
        "firmware": board,
        "firmware_fastest": best,
        "both_harts_heavy": both_harts,
        "ratio_hart_to_raw": counted / raw,
        "ratio_board_to_raw": board["effective_mips"] / raw,
        "firmware_check_writes": checked,
        "firmware_ipc1": ipc1,
        "firmware_nocache": nocache,
        "sd": sd,
        "sd_ipc1": sd_ipc1,
        "texture_loads": loads,
        "thesis_start_up_ms": THESIS_START_UP_MS,
        "profile": profile,
        "drawing": drawing,
        "firmware_precise_engine": precise,
        "output_memory": output_memory,
        "cpu_fed_spi": cpu_fed_spi,
    }
    print(f"SPI0 fed by the CPU, {cpu_fed_spi['stores']:,} FIFO stores ({cpu_fed_spi['device_accesses']:,} device "
          f"accesses, {cpu_fed_spi['virtual_ms']:.2f} ms virtual): {cpu_fed_spi['host_cpu_us_per_store']:.1f} us of host "
          f"CPU time a store (best of {cpu_fed_spi['rounds']})")
    for count, figure in output_memory.items():
        print(f"run output, {int(count):6,} frames: resident memory {figure['rss_before_mb']:.0f} -> "
              f"{figure['rss_after_mb']:.0f} MB ({figure['host_s']:.0f} s)")
    print(f"raw Unicorn, tight loop, no limit:         {raw:8.1f} MIPS")
    print(f"board hart, same loop, exact counting:     {counted:8.1f} MIPS  ({counted / raw:.2f} x raw)")
    print(f"board model running the firmware:          {board['effective_mips']:8.1f} MIPS  "
          f"({board['effective_mips'] / raw:.3f} x raw)")
    print(f"  while harts execute (not asleep, not polling): {board['mips_while_executing']:8.1f} MIPS; "
          f"{100 * board['share_of_host_time_executing']:.0f} % of host time is spent executing")
    print(f"  {board['frames']} frames in {board['host_time_s']:.2f} s host = {board['frames_per_host_second']:.1f} frames/s; "
          f"virtual {board['virtual_fps']:.1f} frames/s; instructions per hart {board['instructions']}")
    print(f"  after loading: {board['host_ms_per_frame']:.1f} ms host per {board['virtual_ms_per_frame']:.2f} ms "
          f"virtual frame, real-time factor {board['real_time_factor']:.3f} (virtual seconds per host second; "
          f"1.0 runs as fast as a Dock); the fastest of {best['runs']} runs: {best['real_time_factor']:.3f} wall, "
          f"{best['real_time_factor_cpu']:.3f} CPU time")
    print(f"  both harts drawing the heavy sphere (scale {HEAVY_BOTH_HARTS['scale']}), after loading: real-time factor "
          f"{both_harts['real_time_factor']:.3f} wall, {both_harts['real_time_factor_cpu']:.3f} CPU time (fastest of "
          f"{both_harts['runs']}; {both_harts['host_cpu_ms_per_frame']:.1f} ms host CPU per "
          f"{both_harts['virtual_ms_per_frame']:.2f} ms virtual frame)")
    per_frame = board["instructions_per_frame"][0]
    print(f"  hart 0's drawing alone on each engine (no scheduler, no devices), host time per instruction and for "
          f"a frame's {per_frame:,}:")
    for way, figures in drawing.items():
        print(f"    {way:36} {figures['ns_per_instruction']:6.2f} ns  {figures['ns_per_instruction'] * per_frame / 1e6:7.2f} ms"
              f"  {figures['mips']:7.1f} MIPS  ({figures['instructions']:,} instructions)")
    print(f"  the precise engine throughout (--engine precise): {precise['host_ms_per_frame']:.1f} ms host per "
          f"frame, real-time factor {precise['real_time_factor']:.3f}, {precise['effective_mips']:.1f} MIPS; "
          f"the fast engine ran {board['fast_share']:.1%} of hart 0's instructions")
    print(f"board with --check-writes:                 {checked['effective_mips']:8.1f} MIPS  "
          f"({checked['ratio_to_unchecked']:.3f} x the board without; fastest of {checked['rounds']} alternating "
          f"runs each; {checked['ratio_while_executing']:.3f} x while harts execute)")
    print("cycle timing (Rocket) against --timing ipc1, default card, steady-state frames of hart 0:")
    print(f"  instructions/frame {board['instructions_per_frame'][0]:,} (ipc1 {ipc1['instructions_per_frame'][0]:,}); "
          f"cycles/frame {board['cycles_per_frame'][0]:,} (ipc1 {ipc1['cycles_per_frame'][0]:,}), "
          f"{board['cycles_per_frame'][0] / board['instructions_per_frame'][0]:.2f} cycles per instruction")
    print(f"  reset to first frame {board['reset_to_first_frame_ms']:.1f} ms virtual (ipc1 "
          f"{ipc1['reset_to_first_frame_ms']:.1f} ms; the thesis's start-up, models A/B/C: "
          f"{' / '.join(f'{v:g}' for v in THESIS_START_UP_MS.values())} ms)")
    print(f"  host time a frame after loading: {ipc1['host_cost_of_cycle_model']:.3f} x ipc1's "
          f"(fastest of {ipc1['rounds']} alternating runs each, {args.frames} frames)")
    print(f"  the L1 caches: {board['cycles_per_frame'][0]:,} cycles a frame against {nocache['cycles_per_frame'][0]:,} "
          f"without (--timing rocket-nocache); host time a frame {nocache['host_cost_of_cycle_model']:.3f} x")
    for label, figures in (("Rocket", sd), ("ipc1", sd_ipc1)):
        print(f"SD, {label} timing (virtual time; thesis in brackets): card set-up to root directory "
              f"{figures['card_setup_to_root_ms']:.2f} ms [32.35], model {figures['model_bytes']} bytes "
              f"{figures['model_read_ms']:.2f} ms read and checked [43.05 read], "
              f"{figures['model_second_pass_ms']:.2f} ms read again and stored, texture {figures['texture_bytes']} "
              f"bytes {figures['texture_read_ms']:.2f} ms [200.75]; reset to first frame "
              f"{figures['reset_to_first_frame_ms']:.1f} ms [344.3]")
    print_load_figures(loads)
    print(f"profile of the default scene, hart 0, per steady frame (frames 1-{profile['frames'] - 1}), by cycles; "
          f"--profile costs {profile['cost']:.1f} x the host time per frame:")
    for row in profile["hart0_per_frame"]:
        print(f"  {row['function']:28} {row['cycles_per_frame']:>11,} cycles {100 * row['share']:5.1f} %  "
              f"{row['instructions_per_frame']:>11,} instructions")
    out = ROOT / "build" / "bench.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"written to {out.relative_to(ROOT)}")
    return results


if __name__ == "__main__":
    sys.exit(main())
