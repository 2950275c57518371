"""The thesis's own firmware on the board model (issue 31, item 3: calibration against the thesis's
measurements on a Dock), from a checkout of github.com/luczis/Renderizacao-3D-RISC-V-Assembly (not
part of this repository): built with Debian's riscv64-unknown-elf-gcc as its CMake files build it
(every `src/*.S` and `lib/crt.S`, linked with its `lds/kendryte.ld`), run on cards holding files of
the sizes the thesis gives for its models A, B and C, and timed from reset to its main loop, the span
the thesis measured (344.3, 122.2 and 87.8 ms on a Dock), and through its three SD phases, which it
measured on model A from the card's chip select (32.35, 200.75 and 43.05 ms): the card's set-up to the
root directory (sdInitialize and openFAT), the texture's read and the model's read (each a readFile).

    make thesis-firmware THESIS=DIR
    python tools/thesis_firmware.py DIR [--timing rocket,rocket-nocache,ipc1] [--out DIR]

The cards are made as the thesis's FAT32 code needs them: it puts the root directory at partition
start + FATs + 2 clusters (so reserved sectors must be twice the sectors per cluster: mkfs.fat -s 16
-R 32) and finds files by their long-name entries only (written with sdcard_image's CardWriter). The
files: our generated torus, gem and cube (tools/make_assets.py) and textures of the thesis's sizes,
padded with comment lines to the thesis's byte counts. Exit status 0 when every run reached the main
loop, 1 when one did not, 2 for bad arguments.
"""
from __future__ import annotations

import argparse
import json
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

# (model, its triangles, texture side, the thesis's model and texture bytes, its start-up on a Dock in ms):
# the thesis's table of its three test models and its measured start-up (section 5, "Resultados")
MODELS = {
    "A": ("torus", 250, 250, 39731, 187597, 344.3),
    "B": ("gem", 100, 78, 7373, 23450, 122.2),
    "C": ("cube", 8, 8, 466, 249, 87.8),
}
# the SD phases the thesis measured on model A from the card's chip select (section 5, Figure 39): the card's
# set-up to the root directory and the FAT, the texture's read, the model's read, in ms
THESIS_SD_PHASES_MS = {"A": {"set_up": 32.35, "texture": 200.75, "model": 43.05}}
TIMINGS = ("rocket", "rocket-nocache", "ipc1")
MAIN_LOOP = "loop0"          # hart 0's main loop (src/main.S), which the thesis timed start-up to
# where each phase begins and ends in src/main.S: (symbol, its n-th entry) -- the card's set-up begins at
# sdInitialize and ends where the first readFile (the texture's) begins; the texture's read ends at
# openPPMTex, which parses it; the model's read is the second readFile, ending at openOBJModel
PHASE_MARKS = {"set_up": (("sdInitialize", 1), ("readFile", 1)),
               "texture": (("readFile", 1), ("openPPMTex", 1)),
               "model": (("readFile", 2), ("openOBJModel", 1))}
CARD_MIB = 600               # FAT32 needs 65,525 clusters: at 8 KiB clusters, over 512 MiB
PARTITION_START = 2048


def build(checkout: Path, out: Path) -> Path:
    sources = sorted((checkout / "src").glob("*.S")) if (checkout / "src").is_dir() else []
    if not sources or not (checkout / "lds" / "kendryte.ld").is_file() or not (checkout / "lib" / "crt.S").is_file():
        raise SystemExit(f"thesis-firmware: {checkout} is not a checkout of the thesis's firmware "
                         f"(no src/*.S, lib/crt.S, lds/kendryte.ld)")
    out.mkdir(parents=True, exist_ok=True)
    elf = out / "thesis.elf"
    command = ["riscv64-unknown-elf-gcc", "-march=rv64imafdc", "-mabi=lp64d", "-mcmodel=medany", "-nostdlib",
               "-nostartfiles", "-Wl,--no-relax", "-Wl,--no-warn-rwx-segments", "-T", str(checkout / "lds" / "kendryte.ld"),
               f"-I{checkout / 'src'}", "-o", str(elf), str(checkout / "lib" / "crt.S"), *map(str, sources)]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise SystemExit(f"thesis-firmware: the build failed:\n{result.stderr}")
    return elf


def files(model: str) -> tuple[bytes, bytes]:
    """The model and its texture, padded to the thesis's byte counts."""
    from tools import make_assets
    name, width, height, model_bytes, texture_bytes, _ = MODELS[model]
    obj = getattr(make_assets, name)().encode()
    if len(obj) < model_bytes:
        obj += b"#" * (model_bytes - len(obj) - 1) + b"\n"
    header = f"P6\n{width} {height}\n255\n".encode()
    pixels = bytes((i * 7) & 0xFF for i in range(width * height * 3))
    padding = texture_bytes - len(header) - len(pixels) - 1          # a comment line: '#'s and its newline
    texture = header[:3] + (b"#" * padding + b"\n" if padding > 0 else b"") + header[3:] + pixels
    return obj, texture


def card(folder: Path, obj: bytes, texture: bytes) -> Path:
    from sdcard_image.fat32 import CardWriter
    image = folder / "card.img"
    image.unlink(missing_ok=True)
    with open(image, "wb") as handle:
        handle.truncate(CARD_MIB << 20)
        entry = struct.pack("<B3sB3sII", 0, b"\x00\x02\x00", 0x0C, b"\xff\xff\xff", PARTITION_START,
                            (CARD_MIB << 11) - PARTITION_START)
        handle.write(bytes(446) + entry + bytes(48) + b"\x55\xaa")
    sectors = (CARD_MIB << 11) - PARTITION_START
    subprocess.run(["mkfs.fat", "-F", "32", "-s", "16", "-R", "32", "--offset", str(PARTITION_START), "-h",
                    str(PARTITION_START), str(image), str(sectors // 2)], check=True, capture_output=True)
    with CardWriter.open(image) as writer:
        writer.write("/bitboy.ppm", texture)          # the names src/inc/files.inc gives
        writer.write("/bitboy.obj", obj)
    return image


def start_up(elf: Path, image: Path, timing: str, budget_ms: float = 2000.0) -> dict:
    """Reset to hart 0's first instruction of its main loop, in virtual time, the SD phases on the way
    (PHASE_MARKS), and host time."""
    import unicorn
    from emulator.board import Board
    from emulator.vtime import PS_PER_MS, to_seconds
    board = Board(str(elf), sd_image=str(image), timing=timing)
    hart = board.harts[0]
    wanted = {MAIN_LOOP} | {name for marks in PHASE_MARKS.values() for name, _ in marks}
    entries: dict[str, list[float]] = {name: [] for name in wanted}

    def at_symbol(uc, address, size, name) -> None:
        entries[name].append(to_seconds(board.scheduler.time_at_cycles(hart, hart.cycles)) * 1e3)
    for address, name in board.image.symbols.items():
        if name in wanted:
            hart.add_hook(unicorn.UC_HOOK_CODE, at_symbol, name, address, address)
    started = time.process_time()
    try:
        while not entries[MAIN_LOOP] and board.time < budget_ms * PS_PER_MS:
            board._step()
    finally:
        board.close()
    phases = {}
    for phase, ((first, nth), (last, mth)) in PHASE_MARKS.items():
        if len(entries[first]) >= nth and len(entries[last]) >= mth:
            phases[phase] = entries[last][mth - 1] - entries[first][nth - 1]
    return {"timing": timing, "start_up_ms": entries[MAIN_LOOP][0] if entries[MAIN_LOOP] else None,
            "sd_phases_ms": phases, "host_cpu_s": time.process_time() - started}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="tools/thesis_firmware.py", description=__doc__.splitlines()[0])
    parser.add_argument("checkout", help="a checkout of github.com/luczis/Renderizacao-3D-RISC-V-Assembly")
    parser.add_argument("--timing", default=",".join(TIMINGS), help="comma-separated timing models")
    parser.add_argument("--out", default=str(ROOT / "build" / "thesis-firmware"))
    args = parser.parse_args(argv)
    timings = [name.strip() for name in args.timing.split(",") if name.strip()]
    unknown = [name for name in timings if name not in TIMINGS]
    if unknown:
        parser.error(f"unknown timing {', '.join(unknown)}")
    out = Path(args.out)
    elf = build(Path(args.checkout), out)
    records = []
    with tempfile.TemporaryDirectory() as tmp:
        for model, (_, _, _, _, _, thesis_ms) in MODELS.items():
            image = card(Path(tmp), *files(model))
            for timing in timings:
                record = {"model": model, "thesis_ms": thesis_ms, **start_up(elf, image, timing)}
                records.append(record)
                ours = record["start_up_ms"]
                print(f"model {model}, {timing:15} start-up to the main loop "
                      + (f"{ours:8.2f} ms against {thesis_ms} ms on a Dock ({ours / thesis_ms:.2f} x)"
                         if ours is not None else "NOT REACHED"))
                dock_phases = THESIS_SD_PHASES_MS.get(model, {})
                record["thesis_sd_phases_ms"] = dock_phases
                print("    SD phases: " + ", ".join(
                    f"{phase} {ms:.2f} ms" + (f" against {dock_phases[phase]} ({ms / dock_phases[phase]:.2f} x)"
                                              if phase in dock_phases else "")
                    for phase, ms in record["sd_phases_ms"].items()))
    (out / "thesis-firmware.json").write_text(json.dumps(records, indent=2) + "\n")
    if all(record["start_up_ms"] is not None for record in records):
        from tools import bench_history
        bench_history.append(None, thesis_firmware=records)
        print(f"recorded in {bench_history.HISTORY}; the table in "
              f"{bench_history.PAGE}")
        return 0
    return 1


if __name__ == "__main__":
    sys.exit(main())
