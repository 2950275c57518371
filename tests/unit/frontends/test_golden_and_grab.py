"""The run command's golden-frame check (--golden, --tolerance) and framebuffer grabs (--grab)."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from suite import GOLDEN, GOLDEN_FRAMES, ROOT, run_emulator, shared_value
from emulator.frontends.grab import parse_grab, rgb565_image


def _run(firmware, card, out, *extra):
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", str(GOLDEN_FRAMES),
                          "--out", str(out), "--quiet", *extra)
    return result, json.loads((out / "run.json").read_text())


@pytest.fixture
def goldens(tmp_path):
    folder = tmp_path / "golden"
    shutil.copytree(GOLDEN / "default", folder)
    return folder


def test_matching_frames_pass(firmware_run):
    """The shared run of the default card is held against the default scene's goldens."""
    result, _, summary = firmware_run
    assert summary["golden"]["folder"] == str(GOLDEN / "default")
    assert result.returncode == 0, result.stderr
    assert all(frame["matches"] for frame in summary["golden"]["frames"])
    assert len(summary["golden"]["frames"]) == GOLDEN_FRAMES


def _nudge(path, box, delta):
    image = np.asarray(Image.open(path).convert("RGB")).astype(int)
    x0, y0, x1, y1 = box
    image[y0:y1 + 1, x0:x1 + 1] = np.clip(image[y0:y1 + 1, x0:x1 + 1] + delta, 0, 255)
    Image.fromarray(image.astype(np.uint8)).save(path)


@pytest.fixture(scope="module")
def mismatch_run(firmware, card, tmp_path_factory):
    """One run against goldens with two faults: frame 2 differs in a 10 x 5 box (3 levels darker)
    and frame 3 is missing; frames 0 and 1 are the real goldens. Returns (result, run.json, out);
    made once for all xdist workers."""
    def make(folder):
        goldens = folder / "golden"
        shutil.copytree(GOLDEN / "default", goldens)
        _nudge(goldens / "frame_0002.png", (100, 50, 109, 54), -3)
        (goldens / "frame_0003.png").unlink()
        result, summary = _run(firmware, card, folder / "out", "--golden", str(goldens))
        return result, summary, folder / "out"
    return shared_value(tmp_path_factory, "mismatch_run", make)


def test_a_differing_frame_fails_with_a_diff_image(mismatch_run):
    result, summary, out = mismatch_run
    # (the region must not be black, or darker would change nothing)
    assert np.asarray(Image.open(GOLDEN / "default" / "frame_0002.png"))[50:55, 100:110].min() >= 3
    assert result.returncode == 9, result.stderr
    assert [frame["matches"] for frame in summary["golden"]["frames"][:2]] == [True, True]
    frame = summary["golden"]["frames"][2]
    assert not frame["matches"] and frame["differing_pixels"] == 50
    assert frame["bounding_box"] == [100, 50, 109, 54] and frame["max_channel_error"] == 3
    assert (out / "diff_0002.png").exists()
    assert "50 pixels differ" in result.stderr and summary["exit"] == "golden-mismatch"


@pytest.mark.parametrize("tolerance, status", [(3, 0), (2, 9)])
def test_tolerance(firmware, card, tmp_path, goldens, tolerance, status):
    _nudge(goldens / "frame_0001.png", (0, 0, 3, 3), -3)
    result, _ = _run(firmware, card, tmp_path / "out", "--golden", str(goldens), "--tolerance", str(tolerance))
    assert result.returncode == status, result.stderr


def test_a_missing_golden_frame_is_a_mismatch(mismatch_run):
    """Frame 3's golden is missing (mismatch_run): counted with frame 2's difference."""
    result, summary, _ = mismatch_run
    assert result.returncode == 9
    assert not summary["golden"]["frames"][3]["matches"]
    assert "no golden frame" in summary["golden"]["frames"][3]["problem"]
    assert summary["message"] == "2 of 4 frames differ from " + summary["golden"]["folder"]


def test_grab_reads_the_buffers_at_the_requested_time(firmware, card, tmp_path, firmware_run):
    """Just before frame 0 has been sent, framebuffer 0 still holds frame 0 (hart 0 only draws
    frame 2 into it once the transfer is done): a grab then equals the frame the LCD showed.
    Both grabs fall before frame 0 is shown: a run of one frame takes them."""
    _, first_out, first = firmware_run
    shown_at = first["frames"][0]["virtual_time_s"]
    at = f"{shown_at - 2e-6:.7f}"
    assert 0.05 < shown_at
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "1", "--out", str(out), "--quiet",
                          "--grab", f"framebuffers@{at}:pairs", "--grab", "gram@0.05")
    summary = json.loads((out / "run.json").read_text())
    assert result.returncode == 0, result.stderr
    grabs = {g["request"].split("@")[0]: g for g in summary["grabs"]}
    assert grabs["framebuffers"]["virtual_time_s"] == pytest.approx(float(at))
    picture = np.asarray(Image.open(out / grabs["framebuffers"]["file"]).convert("RGB"))
    shown = np.asarray(Image.open(first_out / "frame_0000.png").convert("RGB"))
    assert np.array_equal(picture, shown)
    assert np.asarray(Image.open(out / grabs["gram"]["file"])).shape == (240, 320, 3)


@pytest.mark.parametrize("grab, expected", [
    ("no_such_symbol@0.2", "no symbol 'no_such_symbol' in the firmware"),
    ("0x1000@0.2", "does not lie in SRAM"),                  # an address outside SRAM
    ("framebuffers@0.2:4000x4000", "does not lie in SRAM"),  # a buffer running past its end
])
def test_a_grab_of_no_buffer_is_refused_before_the_run(firmware, tmp_path, grab, expected):
    """Checked against the firmware's symbols before anything runs: status 2, no output."""
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--frames", "1", "--out", str(out), "--quiet", "--grab", grab)
    assert result.returncode == 2, result.stderr
    assert expected in result.stderr and grab.split(":")[0] in result.stderr
    assert not out.exists()


def test_a_grab_the_run_ends_before_fails_the_run(firmware, card, tmp_path):
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "1", "--out", str(out), "--quiet",
                          "--grab", "gram@30")
    assert result.returncode == 2, result.stderr
    assert "gram@30: the run ended at" in result.stderr and "before the grab's time" in result.stderr
    summary = json.loads((out / "run.json").read_text())
    assert summary["exit"] == "grab-missed" and len(summary["frames"]) == 1
    assert summary["grabs"] == [{"request": "gram@30", "error": summary["grabs"][0]["error"]}]
    assert summary["grabs"][0]["error"].startswith("not taken: the run ended at")
    assert not list(out.glob("grab_*.png"))


def test_tolerance_without_golden_is_refused(firmware, tmp_path):
    result = run_emulator("run", str(firmware), "--frames", "1", "--out", str(tmp_path / "out"), "--quiet",
                          "--tolerance", "3")
    assert result.returncode == 2
    assert "--tolerance needs --golden" in result.stderr


@pytest.mark.parametrize("tolerance", ["-1", "256", "x"])
def test_tolerance_out_of_range_is_refused(firmware, tmp_path, goldens, tolerance):
    result = run_emulator("run", str(firmware), "--frames", "1", "--out", str(tmp_path / "out"), "--quiet",
                          "--golden", str(goldens), "--tolerance", tolerance)
    assert result.returncode == 2
    assert "argument --tolerance" in result.stderr


@pytest.mark.parametrize("damage, expected", [
    ("text", "is not a PNG image"),
    ("folder", "cannot be read as a PNG image (Is a directory)"),
    ("truncated", "cannot be read as a PNG image"),
    ("jpeg", "is a JPEG image, not a PNG"),
])
def test_an_unreadable_golden_frame_is_bad_input_before_the_run(firmware, card, tmp_path, goldens, damage, expected):
    """A golden frame that is there but is no readable PNG stops everything before the run
    (status 6, naming the file), rather than a traceback after it. (A file without read
    permission fails the same way; the tests may run as root, so a folder stands in for it.)"""
    frame = goldens / "frame_0001.png"
    if damage == "text":
        frame.write_text("not a picture\n")
    elif damage == "folder":
        frame.unlink()
        frame.mkdir()
    elif damage == "truncated":
        frame.write_bytes(frame.read_bytes()[:200])
    else:
        Image.open(goldens / "frame_0000.png").convert("RGB").save(frame, format="JPEG")
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "2", "--out", str(out), "--quiet",
                          "--golden", str(goldens))
    assert result.returncode == 6, result.stderr
    assert "Traceback" not in result.stderr
    assert f"{frame}" in result.stderr and expected in result.stderr
    assert not out.exists()


def test_a_golden_path_that_is_a_file_is_bad_input(firmware, tmp_path, goldens):
    result = run_emulator("run", str(firmware), "--frames", "1", "--out", str(tmp_path / "out"), "--quiet",
                          "--golden", str(goldens / "frame_0000.png"))
    assert result.returncode == 6
    assert "frame_0000.png: not a folder" in result.stderr


def test_grab_syntax():
    request = parse_grab("0x80001000@1.5:pairs:64x32")
    assert (request.what, request.at_s, request.width, request.height, request.pairs) == ("0x80001000", 1.5, 64, 32, True)
    for bad in ("gram", "gram@x", "fb@1:wide", "gram@1:pairs",
                "gram@1e999", "gram@e", "fb@1:0x4", "fb@1:pairs:3x2", "0xzz@1"):
        with pytest.raises(ValueError):
            parse_grab(bad)


def test_rgb565_pairs_layout():
    # two pixels in one word: the first pixel of the pair sits in the upper half
    raw = (0xF800).to_bytes(2, "little") + (0x001F).to_bytes(2, "little")   # word = 0x001F_F800
    plain = rgb565_image(raw, 2, 1, pairs=False)
    paired = rgb565_image(raw, 2, 1, pairs=True)
    assert tuple(plain[0, 0]) == (255, 0, 0) and tuple(paired[0, 0]) == (0, 0, 255)


# --- goldens of one's own scene folders (make goldens / golden-check SCENE_DIRS=...) ---------------

def _regen(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(ROOT / "tools" / "regen_goldens.py"), *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=600)


def test_a_scene_folder_of_ones_own_gets_goldens_and_is_checked_against_them(firmware, card, tmp_path):
    scene = tmp_path / "my-scene"
    (scene / "models").mkdir(parents=True)
    (scene / "textures").mkdir()
    assets = ROOT / "build" / "assets"
    shutil.copy(assets / "models" / "cube.obj", scene / "models")
    shutil.copy(assets / "textures" / "cube.png", scene / "textures")
    (scene / "scene.ini").write_text("model = models/cube.obj\ntexture = textures/cube.ppm\nmode = textured\n"
                                     "translate = 0 0 -3\naxis = 1 1 0\nangle = 20\nstep = 5\n")
    out = ["--out", str(tmp_path / "out")]         # the runs' output: not build/goldens, the user's
    made = _regen("--folder", str(scene), "--frames", "2", *out)
    assert made.returncode == 0, made.stderr
    assert sorted(p.name for p in (scene / "golden").iterdir()) == ["frame_0000.png", "frame_0001.png"]
    assert f"{scene / 'golden' / 'frame_0001.png'}: new" in made.stdout
    checked = _regen("--check", "--folder", str(scene), "--frames", "2", *out)
    assert checked.returncode == 0 and "[golden] all 2 frames match" in checked.stderr
    _nudge(scene / "golden" / "frame_0001.png", (10, 10, 12, 12), 9)
    checked = _regen("--check", "--folder", str(scene), "--frames", "2", *out)
    assert checked.returncode == 9 and "frame 1" in checked.stderr
    (scene / "scene.ini").unlink()
    refused = _regen("--check", "--folder", str(scene), *out)
    assert refused.returncode == 2 and "no scene.ini in it" in refused.stderr


COMM_PROGRAM = """
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, 2f
    la      t0, shared_pixels         # a .comm buffer: 4 x 2 RGB565 pixels, all pure red
    la      t1, local_pixels          # a .lcomm buffer: 2 x 2, all pure blue
    li      t2, 0xF800
    li      t3, 8
1:  sh      t2, 0(t0)
    addi    t0, t0, 2
    addi    t3, t3, -1
    bnez    t3, 1b
    li      t2, 0x001F
    sh      t2, 0(t1)
    sh      t2, 2(t1)
    sh      t2, 4(t1)
    sh      t2, 6(t1)
2:  wfi
    j       2b
    .comm   shared_pixels, 16, 8
    .lcomm  local_pixels, 8
"""


def test_grab_finds_buffers_declared_with_comm_and_lcomm(assemble, tmp_path):
    """Issue 10: `.comm` buffers were "no symbol" when grabs looked only at code symbols."""
    elf = assemble(COMM_PROGRAM)
    run = run_emulator("run", str(elf), "--until", "0.001", "--quiet", "--out", str(tmp_path),
                       "--grab", "shared_pixels@0.0005:4x2", "--grab", "local_pixels@0.0005:2x2")
    assert run.returncode == 0, run.stderr
    red = np.asarray(Image.open(tmp_path / "grab_shared_pixels_0.500ms.png").convert("RGB"))
    blue = np.asarray(Image.open(tmp_path / "grab_local_pixels_0.500ms.png").convert("RGB"))
    assert red.shape == (2, 4, 3) and (red == [255, 0, 0]).all()
    assert blue.shape == (2, 2, 3) and (blue == [0, 0, 255]).all()
