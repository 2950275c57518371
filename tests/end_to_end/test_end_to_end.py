"""End to end through the real command: build the firmware, boot it on the board model,
and hold the first frames against the golden PNGs."""
from __future__ import annotations

import json
import re
import os
import pty
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from suite import GOLDEN, GOLDEN_FRAMES, ROOT, run_emulator
from emulator_runs import run_module

from emulator import errors
from emulator.frontends.options import EXIT_STATUS_DETAILS
from k210_common.exit_status import BY_CODE
from golden_scenes import SCENES

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


def test_a_correct_run_has_no_warnings(firmware_run):
    """Every device's warnings reach run.json now (see the LCD test below): the firmware's own
    run must give none, or they would be noise in every run."""
    _, _, summary = firmware_run
    assert summary["warnings"] == []


def test_the_console_shows_the_last_frame_line(firmware_run):
    """Hart 1 reports "frame N" after sending frame N; the run goes on after the last frame
    until that line is out (at most a few virtual ms), without recording more frames."""
    _, out, summary = firmware_run
    lines = (out / "console.log").read_text().splitlines()
    assert lines[-1] == f"frame {GOLDEN_FRAMES - 1}"
    assert len(summary["frames"]) == GOLDEN_FRAMES
    last_frame = summary["frames"][-1]["virtual_time_s"]
    assert last_frame < summary["console"][-1]["virtual_time_s"] <= summary["virtual_time_s"] < last_frame + 5e-3


def test_animation_timing_is_in_run_json(firmware_run):
    """animation.png shows each frame for its virtual time on screen, lengthened to 20 ms when
    shorter (browsers play shorter APNG frames at 100 ms); run.json says which frames."""
    _, out, summary = firmware_run
    animation = summary["animation"]
    times = [frame["virtual_time_s"] for frame in summary["frames"]]
    on_screen = [(b - a) * 1e3 for a, b in zip(times, times[1:])]
    on_screen.append(on_screen[-1])
    assert animation["frame_durations_ms"] == pytest.approx([max(ms, 20.0) for ms in on_screen])
    assert animation["lengthened_frames"] == [i for i, ms in enumerate(on_screen) if ms < 20.0]
    written = Image.open(out / "animation.png")
    for index, duration in enumerate(animation["frame_durations_ms"]):
        written.seek(index)
        assert written.info["duration"] == pytest.approx(duration, abs=1e-3)


def test_animation_keeps_exact_frame_durations(tmp_path):
    """Each frame is shown from its own virtual time to the next frame's, to the fraction of a
    millisecond (APNG delays are fractions of a second; no rounding to whole ms)."""
    from emulator.board import FrameRecord
    from emulator.frontends.output import RunOutput
    output = RunOutput(tmp_path)
    for index, at in enumerate([0.5, 0.5505, 0.6001]):
        image = np.full((240, 320, 3), index * 60, dtype=np.uint8)   # distinct: Pillow merges equal neighbours
        output.frame(FrameRecord(index, at, [0, 0], [0, 0], 0.0), image)
    output.finish({})
    animation = Image.open(tmp_path / "animation.png")
    durations = []
    for index in range(animation.n_frames):
        animation.seek(index)
        durations.append(animation.info["duration"])
    assert durations == pytest.approx([50.5, 49.6, 49.6], abs=1e-3)


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
def test_scene_matches_its_golden_frames(name, firmware, golden_card, firmware_run, tmp_path):
    """Every golden scene, every frame, exactly (regenerate deliberately with `make goldens`).
    The default scene's run is the shared one (firmware_run: the default card with --golden)."""
    _, frames = SCENES[name]
    if SCENES[name][0] is None:
        result, out, summary = firmware_run
        assert frames == GOLDEN_FRAMES and len(summary["golden"]["frames"]) == frames
    else:
        card = golden_card(name)
        out = tmp_path / "out"
        result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", str(frames), "--out", str(out),
                              "--quiet", "--golden", str(GOLDEN / name))
        summary = json.loads((out / "run.json").read_text())
    problems = [c for c in summary.get("golden", {}).get("frames", []) if not c["matches"]]
    assert result.returncode == 0, "\n".join(
        [result.stderr] + [f"frame {c['index']}: {c['problem'] or c['differing_pixels']} differing; diff {c['diff_image']}"
                           for c in problems])


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
    reference = run_module("reference", "render-card", card, "--frames", "1", "--out", tmp_path / "reference",
                           "--quiet")
    assert reference.returncode == 0, reference.stderr
    assert (tmp_path / "reference" / "frame_0000.png").exists()


FIRST_FRAME_LIMIT_S = 0.150   # issue 11: reset to first frame on the default card, virtual time


def test_the_first_frame_comes_within_150_ms_of_reset(firmware_run):
    """Hart 1 brings the LCD up (about 125 ms, nearly all of it the ST7789V's datasheet waits)
    while hart 0 loads the default card, its console lines sent by hart 1 meanwhile, so the
    first frame is on the LCD within 150 ms of reset (528 ms when hart 0 did both in turn and
    waited 120 ms after the reset, after SWRESET and after SLPOUT). Virtual time: deterministic."""
    _, _, summary = firmware_run
    first = summary["frames"][0]["virtual_time_s"]
    assert first < FIRST_FRAME_LIMIT_S, f"first frame at {first * 1e3:.1f} ms of virtual time"


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
    li t0, 0x50280000      # I2C0, not modelled
    lw t1, 8(t0)
1:  j 1b
""")
    result = run_emulator("run", str(elf), "--out", str(tmp_path), "--quiet", "--budget", "0.01")
    assert result.returncode == 5, result.stderr
    message = result.stderr
    for part in ("hart 0", "pc 0x80000004", "lw", "load of 4 bytes", "0x50280008", "I2C"):
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


SERVED_ECALLS = """
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, 3f
    la      t0, handler
    csrw    mtvec, t0
    li      s1, 3
1:  ecall
    addi    s1, s1, -1
    bnez    s1, 1b
2:  j       2b
3:  wfi
    j       3b
    .balign 4
handler:
    csrr    t0, mepc
    addi    t0, t0, 4
    csrw    mepc, t0
    mret
"""


def test_exceptions_the_handler_serves_are_part_of_the_run(assemble, tmp_path):
    """ecalls served by the firmware's trap handler: the run goes on (run.json counts them);
    --stop-on-trap ends it at the first (status 3)."""
    elf = assemble(SERVED_ECALLS)
    result = run_emulator("run", str(elf), "--out", str(tmp_path / "a"), "--quiet", "--until", "0.01")
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "a" / "run.json").read_text())
    assert summary["exceptions"] == {"environment call from M-mode": 3} and not summary["stop_on_trap"]
    result = run_emulator("run", str(elf), "--out", str(tmp_path / "b"), "--quiet", "--until", "0.01",
                          "--stop-on-trap")
    assert result.returncode == 3, result.stderr
    assert re.search(r"environment call from M-mode at pc 0x80000016 <_start\+0x16> \(ecall\), mtval 0x0; then, "
                     r"after the trap handler returned, hart 0: environment call", result.stderr), result.stderr
    summary = json.loads((tmp_path / "b" / "run.json").read_text())
    assert summary["exceptions"] == {"environment call from M-mode": 1} and summary["stop_on_trap"]


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


def test_until_runs_to_a_virtual_time_without_a_frame_budget(assemble, tmp_path):
    """--until: a firmware that never draws runs to the time asked for and ends well."""
    elf = assemble("""
    .globl _start
_start:
    csrr t0, mhartid
1:  addi t1, t1, 1
    j 1b
""")
    result = run_emulator("run", str(elf), "--out", str(tmp_path), "--quiet", "--budget", "0.01", "--until", "0.03")
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "run.json").read_text())
    assert summary["exit"] == "ok" and summary["until_s"] == 0.03
    assert summary["message"] == "ran until 30.000 ms of virtual time; 0 frames shown"
    assert summary["virtual_time_s"] == pytest.approx(0.03, abs=1e-6)


def test_until_skips_ahead_once_every_hart_sleeps_for_good(assemble, tmp_path):
    elf = assemble("""
    .globl _start
_start:
    csrw mie, zero
1:  wfi
    j 1b
""")
    result = run_emulator("run", str(elf), "--out", str(tmp_path), "--quiet", "--until", "10")
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "run.json").read_text())
    assert summary["virtual_time_s"] == 10
    assert "from 0.000 ms every hart slept in wfi with nothing that could wake it" in summary["message"]


def test_until_and_frames_exclude_each_other(tmp_path):
    result = run_emulator("run", str(tmp_path / "any.elf"), "--out", str(tmp_path / "out"), "--quiet",
                          "--until", "1", "--frames", "2")
    assert result.returncode == 2, result.stderr
    assert "--until and --frames exclude each other" in result.stderr
    assert not (tmp_path / "out").exists()


def test_firmware_trap_handler_runs_then_run_stops(firmware, card, tmp_path):
    """The project's firmware trap handler reports on the console before the board stops."""
    trapping = tmp_path / "trap.elf"
    # turn the first instruction of the renderer's per-frame entry into an illegal one
    from elftools.elf.elffile import ELFFile
    data = bytearray(firmware.read_bytes())
    with firmware.open("rb") as handle:
        elf = ELFFile(handle)
        symbol = elf.get_section_by_name(".symtab").get_symbol_by_name("render_band")
        assert symbol, "render_band symbol missing"
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
    li t0, 0x50440000      # SYSCTL, on the APB: the model may lack a register there
    lw t1, 0x70(t0)        # no such register
1:  j 1b
"""


def test_unknown_register_stops_the_run(assemble, tmp_path):
    result = run_emulator("run", str(assemble(UNKNOWN_REGISTER_PROGRAM)), "--out", str(tmp_path), "--quiet",
                          "--budget", "0.01")
    assert result.returncode == 5, result.stderr
    assert "SYSCTL has no register at offset 0x70" in result.stderr


def test_permissive_run_warns_and_goes_on(assemble, tmp_path):
    result = run_emulator("run", str(assemble(UNKNOWN_REGISTER_PROGRAM)), "--out", str(tmp_path), "--quiet",
                          "--budget", "0.01", "--permissive")
    assert result.returncode == 4, result.stderr   # it went on, and then never drew a frame
    warnings = json.loads((tmp_path / "run.json").read_text())["warnings"]
    assert any("SYSCTL has no register at offset 0x70" in w and "permissive" in w for w in warnings)


# --- the command line refuses what it cannot do, before anything runs ---------------------

@pytest.mark.parametrize("option, value", [
    ("--quantum", "0"), ("--quantum", "-5"), ("--quantum", "1e3"), ("--quantum", "1000000001"),
    ("--budget", "0"), ("--budget", "-1"), ("--budget", "nan"), ("--budget", "inf"), ("--budget", "x"),
    ("--frames", "0"), ("--frames", "-2"), ("--until", "0"), ("--until", "nan"), ("--until", "inf"),
])
def test_nonsense_numbers_are_refused(tmp_path, option, value):
    result = run_emulator("run", str(tmp_path / "any.elf"), "--out", str(tmp_path / "out"), "--quiet",
                          f"{option}={value}")
    assert result.returncode == 2, result.stderr
    assert f"argument {option}:" in result.stderr and "Traceback" not in result.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("options, expected", [
    (["--sd", "CARD", "--sd-fault", "bogus"], "argument --sd-fault: invalid choice: 'bogus'"),
    (["--sd-fault", "no-init"], "--sd-fault needs --sd"),
    (["--sd-writable"], "--sd-writable needs --sd"),
    (["--sd-access-time", "100"], "--sd-access-time needs --sd"),
    (["--sd", "CARD", "--sd-access-time", "-1"], "argument --sd-access-time: must be 0 to 100,000 microseconds"),
    (["--sd", "CARD", "--sd-access-time", "100001"], "argument --sd-access-time: must be 0 to 100,000 microseconds"),
    (["--sd", "CARD", "--sd-access-time", "nan"], "argument --sd-access-time: must be 0 to 100,000 microseconds"),
    (["--sd", "CARD", "--sd-access-time", "fast"], "argument --sd-access-time: 'fast' is not a number of microseconds"),
])
def test_sd_options_are_checked(tmp_path, card, options, expected):
    options = [str(card) if option == "CARD" else option for option in options]
    result = run_emulator("run", str(tmp_path / "any.elf"), "--out", str(tmp_path / "out"), "--quiet", *options)
    assert result.returncode == 2, result.stderr
    assert expected in result.stderr


@pytest.mark.parametrize("where, expected", [
    ("a-file", "a file of that name exists; the output must be a folder"),
    ("a-file/below", "cannot create the output folder (Not a directory"),
])
def test_an_unusable_output_folder_is_bad_input(firmware, tmp_path, where, expected):
    (tmp_path / "a-file").write_text("keep me\n")
    result = run_emulator("run", str(firmware), "--frames", "1", "--out", str(tmp_path / where), "--quiet")
    assert result.returncode == 6, result.stderr
    assert "Traceback" not in result.stderr
    assert f"--out {tmp_path / where}: {expected}" in result.stderr
    assert (tmp_path / "a-file").read_text() == "keep me\n"


def test_help_lists_every_exit_status():
    # every status the board model returns (its EXIT_STATUS_DETAILS; the numbers are
    # k210_common/exit_status.py's) is in --help; tests/unit/shared/test_exit_status.py checks docs/reference/
    codes = sorted(EXIT_STATUS_DETAILS)
    assert codes == list(range(13)) + [16, 130, 143]    # write-failed; 128 + the signal for SIGINT, SIGTERM
    result = run_emulator("run", "--help")
    assert result.returncode == 0
    statuses = result.stdout[result.stdout.index("exit status:"):]
    assert [int(line.split()[0]) for line in statuses.splitlines() if re.match(r" {0,2}\d+  ", line)] == codes
    for status in codes:
        assert f"\n{status:>3}  {BY_CODE[status].name}: " in statuses, status
    # the refusals this command makes are among them
    for phrase in ("--tolerance without --golden", "--sd-fault", "a --grab of a symbol the firmware does not define",
                   "a --grab whose time the run ended before", "the --out folder", "not a readable PNG"):
        assert phrase in " ".join(statuses.split()), phrase
    # every BoardStop's status is among them
    stops = [value for value in vars(errors).values() if isinstance(value, type) and issubclass(value, errors.BoardStop)]
    assert {stop.exit_status for stop in stops} <= set(codes)


# --- what the devices notice reaches the user ------------------------------------------------

# Hart 0 brings up clocks, pins and SPI0 with the firmware's own routines, then pulses the
# LCD's reset for a few instructions (the datasheet asks for 10 us) and sends SLPOUT at once
# (the datasheet asks for 5 ms after a reset). By default the pulse resets the LCD and SLPOUT
# wakes it anyway, as real panels do, each with a warning; with --strict the pulse is no reset
# (so SLPOUT finds a chip with nothing to wait for). It never gets DISPON or pixels: the run hangs.
BAD_LCD_RESET = """
    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .text
    .globl main_hart0
    .globl main_hart1
main_hart0:
    call    clocks_init
    call    pins_init
    call    spi0_init
    li      a0, GPIOHS_LCD_DC_BIT
    call    gpiohs_set
    li      a0, GPIOHS_LCD_RST_BIT
    call    gpiohs_clear
    li      a0, GPIOHS_LCD_RST_BIT
    call    gpiohs_set
    li      a0, LCD_CMD_SLPOUT
    call    lcd_command
1:  wfi
    j       1b
main_hart1:
    wfi
    j       main_hart1
"""


def link_with_firmware(source: str, folder) -> str:
    """A program whose main.S is `source`, linked with the firmware's other objects and k210.ld."""
    objects = sorted(str(p) for p in (ROOT / "build" / "fw").glob("*.o") if p.name != "main.o")
    (folder / "main.S").write_text(source)
    subprocess.run(["riscv64-unknown-elf-as", "-march=rv64gc", "-mabi=lp64d", "-I", str(ROOT / "firmware" / "include"),
                    "-o", str(folder / "main.o"), str(folder / "main.S")], check=True)
    elf = folder / "program.elf"
    subprocess.run(["riscv64-unknown-elf-ld", "-T", str(ROOT / "firmware" / "k210.ld"), "--no-relax", "-o", str(elf),
                    str(folder / "main.o"), *objects], check=True)
    return str(elf)


@pytest.mark.parametrize("strict", [False, True])
def test_a_wrong_lcd_reset_is_reported_in_the_hang(firmware, tmp_path, strict):
    elf = link_with_firmware(BAD_LCD_RESET, tmp_path)
    out = tmp_path / "out"
    result = run_emulator("run", elf, "--out", str(out), "--quiet", *(["--strict"] if strict else []))
    assert result.returncode == 4, result.stderr
    summary = json.loads((out / "run.json").read_text())
    warnings = summary["warnings"]
    assert "ST7789V: RESX low pulse of" in warnings[0] and "shorter than the 10 us" in warnings[0]
    if strict:
        assert len(warnings) == 1, warnings
        assert "not taken as a reset (--strict)" in warnings[0]
        assert summary["timing_warnings"] == {"ST7789V RESX pulse shorter than 10 us": 1}
    else:
        assert len(warnings) == 2, warnings
        assert "taken as a reset (--strict would not)" in warnings[0]
        assert "ST7789V: SLPOUT (0x11) sent within 5 ms after RESX release" in warnings[1]
        assert "carried out (--strict ignores it, as the chip may)" in warnings[1]
        # each broken wait is counted per rule in run.json
        assert summary["timing_warnings"] == {"ST7789V RESX pulse shorter than 10 us": 1,
                                              "ST7789V command within 5 ms of a reset": 1}
    # the hang report says what the LCD noticed
    report = summary["message"]
    assert "LCD: 0 frames captured, display off, awake" in report
    assert all(warning in report for warning in warnings)
    assert warnings[-1] in result.stderr


# --- the terminal ---------------------------------------------------------------------------

CONSOLE_AFTER_A_WHILE = """
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, park
    li      t0, 300000              # about 23 virtual ms at 26 MHz: the progress line is up by then
1:  addi    t0, t0, -1
    bnez    t0, 1b
    li      s0, 0x38000000          # UARTHS
    li      t0, 1
    sw      t0, 0x08(s0)            # txen
    la      s1, text
2:  lbu     t1, 0(s1)
    beqz    t1, 4f
3:  lw      t2, 0(s0)
    bltz    t2, 3b
    sw      t1, 0(s0)
    addi    s1, s1, 1
    j       2b
4:  j       4b
park:
    wfi
    j       park
text:
    .asciz  "console line\\n"
"""


def test_the_progress_line_is_cleared_before_console_lines(assemble, tmp_path):
    """On a terminal the progress line (stderr) is rewritten in place; a console line (stdout)
    must not be written onto it."""
    elf = assemble(CONSOLE_AFTER_A_WHILE)
    controller, terminal = pty.openpty()
    process = subprocess.Popen([sys.executable, "-m", "emulator", "run", str(elf), "--out", str(tmp_path / "out"),
                                "--budget", "0.1"], cwd=ROOT, stdin=subprocess.DEVNULL, stdout=terminal,
                               stderr=terminal)
    os.close(terminal)
    transcript = bytearray()
    while True:
        try:
            data = os.read(controller, 4096)
        except OSError:                 # the terminal closes with the process
            break
        if not data:
            break
        transcript += data
    os.close(controller)
    assert process.wait(timeout=60) == 4
    text = transcript.decode()
    assert "[board] frame 0/8" in text, text               # the progress line was shown
    where = text.index("console line")
    on_that_line = text[text.rfind("\n", 0, where) + 1:where]
    assert on_that_line == "" or on_that_line.endswith("\r\x1b[K"), repr(on_that_line)


@pytest.mark.parametrize("where", ["golden", "inside golden", "card folder"])
def test_an_output_folder_that_would_overwrite_an_input_is_refused(firmware, card, tmp_path, where):
    """--out the --golden folder used to replace the goldens with the run's frames (issue 35)."""
    golden = tmp_path / "golden"
    golden.mkdir()
    (golden / "frame_0000.png").write_bytes(b"kept")
    placed = tmp_path / "cards" / "card.img"
    placed.parent.mkdir()
    placed.write_bytes(card.read_bytes())
    out = {"golden": golden, "inside golden": golden / "run", "card folder": placed.parent}[where]
    result = run_emulator("run", str(firmware), "--sd", str(placed), "--frames", "1", "--golden", str(golden),
                          "--out", str(out), "--quiet")
    assert result.returncode == 2, result.stderr
    assert "--out" in result.stderr
    assert (golden / "frame_0000.png").read_bytes() == b"kept"
    assert not (out / "run.json").exists()


def test_a_long_run_holds_no_frame_in_memory(tmp_path):
    """animation.png is written as the frames come (issue 35: every frame was kept for it, about
    0.6 MB a frame): 200 frames leave the process's resident memory about where 20 did (the
    pixels of 180 frames are 41 MB; Pillow's own memory is not Python's, so RSS is measured)."""
    import os

    from emulator.board import FrameRecord
    from emulator.frontends.output import RunOutput
    output = RunOutput(tmp_path)
    rng = np.random.default_rng(1)

    def frames(first: int, count: int) -> None:
        for index in range(first, first + count):
            image = rng.integers(0, 256, (240, 320, 3), dtype=np.uint8)
            output.frame(FrameRecord(index, index * 0.05, [0, 0], [0, 0], 0.0), image)
    def resident() -> int:
        return int(open("/proc/self/statm").read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    frames(0, 20)
    after_20 = resident()
    frames(20, 180)
    after_200 = resident()
    assert after_200 - after_20 < 12_000_000, (after_20, after_200)
    output.finish({})
    animation = Image.open(tmp_path / "animation.png")
    assert animation.n_frames == 200 and not (tmp_path / "animation.png.frames").exists()
    animation.seek(137)
    assert np.array_equal(np.asarray(animation.convert("RGB")), np.asarray(Image.open(tmp_path / "frame_0137.png")))


def test_a_frame_the_animation_cannot_take_leaves_it_whole(tmp_path):
    """A write that fails part-way through a frame's chunks (a full disk) leaves the animation's
    side file as it was: animation.png then holds the frames before, every one readable."""
    from emulator.frontends.apng import ApngWriter

    writer = ApngWriter(tmp_path / "animation.png", 1)
    real = writer._frames

    class FailingOnce:
        def __init__(self) -> None:
            self.calls = 0

        def write(self, data):
            self.calls += 1
            if self.calls == 3:                              # the third frame's piece
                real.write(bytes(data)[:100])                # a part of it reached the disk
                raise OSError(28, "No space left on device")
            return real.write(data)

        def __getattr__(self, name):
            return getattr(real, name)
    writer._frames = FailingOnce()
    frames = [np.full((240, 320, 3), 40 * i, dtype=np.uint8) for i in range(5)]
    for index, image in enumerate(frames):
        try:
            writer.add(image, 50.0 if index else None)
        except OSError:
            break
    writer._frames = real
    writer.finish(50.0)
    animation = Image.open(tmp_path / "animation.png")
    assert animation.n_frames == writer.count == 2
    for index in range(2):
        animation.seek(index)
        assert np.array_equal(np.asarray(animation.convert("RGB")), frames[index])
