"""End to end through the real command: build the firmware, boot it on the board model,
and hold the first frames against the golden PNGs."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from conftest import GOLDEN, GOLDEN_FRAMES, ROOT, run_emulator

from golden_scenes import SCENES, scene_card

BOOT_STAGES = ["boot: hart 0 up", "clocks:", "pins:", "lcd: ST7789V ready", "hart 1: display loop"]


def test_run_succeeds_and_writes_its_outputs(firmware_run):
    result, out, summary = firmware_run
    assert result.returncode == 0, result.stderr
    assert summary["exit"] == "ok"
    assert len(summary["frames"]) == GOLDEN_FRAMES
    for n in range(GOLDEN_FRAMES):
        assert (out / f"frame_{n:04d}.png").exists()
    animation = Image.open(out / "animation.png")
    assert getattr(animation, "n_frames", 1) == GOLDEN_FRAMES
    for frame in summary["frames"]:
        assert set(frame) >= {"index", "virtual_time_s", "instructions", "host_time_s"}
        assert len(frame["instructions"]) == 2
    times = [f["virtual_time_s"] for f in summary["frames"]]
    assert times == sorted(times) and times[0] > 0


def test_console_has_a_line_per_boot_stage(firmware_run):
    _, out, summary = firmware_run
    console = (out / "console.log").read_text()
    # run.json keeps the same lines, each with the virtual time it ended, in order
    timed = summary["console"]
    assert [entry["line"] for entry in timed] == console.splitlines()[:len(timed)]
    assert [entry["virtual_time_s"] for entry in timed] == sorted(entry["virtual_time_s"] for entry in timed)
    position = 0
    for stage in BOOT_STAGES:
        found = console.find(stage, position)
        assert found >= 0, f"missing boot stage {stage!r} in:\n{console}"
        position = found


@pytest.mark.parametrize("name", SCENES)
def test_scene_matches_its_golden_frames(name, firmware, tmp_path):
    """Every golden scene, every frame, exactly (regenerate deliberately with `make goldens`)."""
    _, frames = SCENES[name]
    card = scene_card(name, tmp_path)
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", str(frames), "--out", str(out),
                          "--quiet", "--golden", str(GOLDEN / name))
    summary = json.loads((out / "run.json").read_text())
    problems = [c for c in summary.get("golden", {}).get("frames", []) if not c["matches"]]
    assert result.returncode == 0, "\n".join(
        [result.stderr] + [f"frame {c['index']}: {c['problem'] or c['differing_pixels']} differing; diff {c['diff_image']}"
                           for c in problems])


@pytest.fixture(scope="module")
def assets(tmp_path_factory) -> Path:
    """The generated models and textures (tools/make_assets.py), once for this module."""
    folder = tmp_path_factory.mktemp("assets")
    subprocess.run([sys.executable, str(ROOT / "tools" / "make_assets.py"), str(folder)], check=True)
    return folder


@pytest.mark.parametrize("name,mode", [("gem-flat", "flat"), ("torus-wireframe", "wireframe")])
def test_flat_and_wireframe_cards_need_no_texture(name, mode, firmware, assets, tmp_path):
    """Only textured mode draws a texture, so a flat or wireframe card without any (no texture
    key, no texture.ppm) boots, says it loaded none and draws its golden frame; the reference
    renderer reads the same card."""
    scene = {key: value for key, value in SCENES[name][0].items() if key != "texture"}
    assert scene["mode"] == mode
    from sdcard_image import build_image
    card = tmp_path / "card.img"
    build_image(card, [assets / "models"], scene=scene)
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "1", "--out", str(out),
                          "--quiet", "--golden", str(GOLDEN / name))
    console = (out / "console.log").read_text()
    assert result.returncode == 0, result.stderr + console
    assert f"texture: not loaded (mode {mode})" in console.splitlines()
    assert "load models/" in console and ".ppm" not in console
    reference = subprocess.run([sys.executable, "-m", "reference", "render-card", str(card), "--frames", "1",
                                "--out", str(tmp_path / "reference"), "--quiet"], cwd=ROOT, capture_output=True,
                               text=True)
    assert reference.returncode == 0, reference.stderr
    assert (tmp_path / "reference" / "frame_0000.png").exists()


def test_both_harts_work_and_hart1_drives_the_display(firmware_run):
    _, _, summary = firmware_run
    writes = summary["device_writes"]
    # after bring-up only hart 1 talks to the DMAC: every frame is started by hart 1
    assert writes["DMAC"][1] >= GOLDEN_FRAMES
    assert writes["SPI0"][1] >= GOLDEN_FRAMES
    for frame in summary["frames"][1:]:
        hart0, hart1 = frame["instructions"]
        assert hart0 > 10_000, "hart 0 draws every frame"
        assert hart1 > 0, "hart 1 sends every frame"


def test_missing_firmware_is_bad_input(tmp_path):
    result = run_emulator("run", str(tmp_path / "nope.elf"), "--out", str(tmp_path / "out"), "--quiet")
    assert result.returncode == 6
    assert "does not exist" in result.stderr
    assert json.loads((tmp_path / "out" / "run.json").read_text())["exit"] == "bad-input"


def test_not_an_elf_is_bad_input(tmp_path):
    bogus = tmp_path / "bogus.elf"
    bogus.write_bytes(b"this is not an ELF file")
    result = run_emulator("run", str(bogus), "--out", str(tmp_path / "out"), "--quiet")
    assert result.returncode == 6
    assert "not a valid ELF" in result.stderr


def test_unmodelled_access_names_hart_pc_instruction_address(assemble, tmp_path):
    elf = assemble("""
    .globl _start
_start:
    li t0, 0x50200000      # the slow GPIO block, not modelled
    lw t1, 8(t0)
1:  j 1b
""")
    result = run_emulator("run", str(elf), "--out", str(tmp_path), "--quiet", "--budget", "0.01")
    assert result.returncode == 5, result.stderr
    message = result.stderr
    for part in ("hart 0", "pc 0x80000004", "lw", "load of 4 bytes", "0x50200008", "GPIO"):
        assert part in message, message


def test_trap_without_handler_is_a_trap(assemble, tmp_path):
    elf = assemble("""
    .globl _start
_start:
    .word 0xffffffff
""")
    result = run_emulator("run", str(elf), "--out", str(tmp_path), "--quiet")
    assert result.returncode == 3, result.stderr
    assert "illegal instruction" in result.stderr and "mtvec" in result.stderr


def test_hang_is_reported(assemble, tmp_path):
    elf = assemble("""
    .globl _start
_start:
    csrr t0, mhartid
1:  addi t1, t1, 1
    j 1b
""")
    result = run_emulator("run", str(elf), "--out", str(tmp_path), "--quiet", "--budget", "0.02")
    assert result.returncode == 4, result.stderr
    assert "no frame reached the LCD" in result.stderr
    assert "hart 0: running" in result.stderr


def test_firmware_trap_handler_runs_then_run_stops(firmware, card, tmp_path):
    """The project's firmware trap handler reports on the console before the board stops."""
    trapping = tmp_path / "trap.elf"
    # turn the first instruction of the renderer's per-frame entry into an illegal one
    from elftools.elf.elffile import ELFFile
    data = bytearray(firmware.read_bytes())
    with firmware.open("rb") as handle:
        elf = ELFFile(handle)
        symbol = elf.get_section_by_name(".symtab").get_symbol_by_name("render_frame")
        assert symbol, "render_frame symbol missing"
        address = symbol[0]["st_value"]
        offset = None
        for segment in elf.iter_segments():
            if segment["p_type"] == "PT_LOAD" and segment["p_vaddr"] <= address < segment["p_vaddr"] + segment["p_filesz"]:
                offset = segment["p_offset"] + address - segment["p_vaddr"]
    data[offset:offset + 4] = b"\xff\xff\xff\xff"
    trapping.write_bytes(bytes(data))
    result = run_emulator("run", str(trapping), "--sd", str(card), "--out", str(tmp_path / "out"), "--quiet")
    assert result.returncode == 3, result.stderr
    console = (tmp_path / "out" / "console.log").read_text()
    assert "trap: mcause=0x" in console and "mepc=0x" in console
    assert f"0x{address:x}" in result.stderr
    # the handler painted the error screen: the last frame the LCD showed is solid red
    frames = sorted((tmp_path / "out").glob("frame_*.png"))
    assert frames, "the trap handler painted no error screen"
    error_screen = np.asarray(Image.open(frames[-1]).convert("RGB"))
    assert (error_screen == (255, 0, 0)).all()


UNKNOWN_REGISTER_PROGRAM = """
    .globl _start
_start:
    li t0, 0x38000000      # UARTHS
    lw t1, 0x20(t0)        # no such register
1:  j 1b
"""


def test_unknown_register_stops_a_strict_run(assemble, tmp_path):
    result = run_emulator("run", str(assemble(UNKNOWN_REGISTER_PROGRAM)), "--out", str(tmp_path), "--quiet",
                          "--budget", "0.01")
    assert result.returncode == 5, result.stderr
    assert "UARTHS has no register at offset 0x20" in result.stderr


def test_permissive_run_warns_and_goes_on(assemble, tmp_path):
    result = run_emulator("run", str(assemble(UNKNOWN_REGISTER_PROGRAM)), "--out", str(tmp_path), "--quiet",
                          "--budget", "0.01", "--permissive")
    assert result.returncode == 4, result.stderr   # it went on, and then never drew a frame
    warnings = json.loads((tmp_path / "run.json").read_text())["warnings"]
    assert any("UARTHS has no register at offset 0x20" in w and "permissive" in w for w in warnings)
