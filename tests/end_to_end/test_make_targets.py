"""The Makefile's targets as a user runs them with variables of their own: `make` run in the
repository, its outputs sent to the test's temporary folder."""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

from k210_common.exit_status import EXIT_GOLDEN_MISMATCH

from suite import ROOT


def make(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run(["make", *args], cwd=ROOT, capture_output=True, text=True, timeout=timeout)


def test_ones_own_card_is_run_and_never_rebuilt(firmware, card, assets, tmp_path):
    """Issue 32: `make flash-to-emulator CARD=my.img` rebuilt my.img with --force from the torus
    assets once a tool source (sdcard_image/*.py, tools/make_assets.py, the Makefile) was newer
    than it. Only the default card is built by make; one's own is only read."""
    from sdcard_image import build_image
    own = tmp_path / "my.img"
    build_image(own, [assets / "models"], scene={"model": "models/gem.obj", "mode": "flat"})
    before = own.read_bytes()
    os.utime(own, (0, 0))           # older than every tool source, as a card made last year is
    dry = make("-n", "flash-to-emulator", f"CARD={own}")
    assert dry.returncode == 0, dry.stderr
    assert "sdcard_image build" not in dry.stdout and f"--sd {own}" in dry.stdout, dry.stdout
    result = make("flash-to-emulator", f"CARD={own}", "FRAMES=1", f"FRAMES_DIR={tmp_path / 'frames'}")
    assert result.returncode == 0, result.stderr[-2000:]
    assert own.read_bytes() == before and own.stat().st_mtime == 0
    assert (tmp_path / "frames" / "frame_0000.png").is_file()
    debug = make("-n", "debug", f"CARD={own}")
    assert "sdcard_image build" not in debug.stdout and f"--sd {own}" in debug.stdout, debug.stdout


def test_the_default_card_is_still_made_by_make(tmp_path):
    """The default card (build/card.img) stays a target: make knows how to build it."""
    dry = make("-n", "-W", "tools/make_assets.py", "flash-to-emulator")
    assert dry.returncode == 0, dry.stderr
    assert "sdcard_image build build/card.img --force" in dry.stdout, dry.stdout


def _scene_folder(folder: Path, assets: Path, angle: int) -> Path:
    (folder / "models").mkdir(parents=True, exist_ok=True)
    (folder / "models" / "gem.obj").write_bytes((assets / "models" / "gem.obj").read_bytes())
    (folder / "scene.ini").write_text(f"model = models/gem.obj\nmode = flat\nangle = {angle}\n")
    return folder


def test_golden_check_keeps_its_diff_images_and_says_its_status(firmware, card, assets, tmp_path):
    """Issue 32: `make golden-check` printed diff images in a temporary folder it had already
    deleted, and exited 2 (make's) where the README said 9; `make goldens` named a deleted output
    folder too. The runs' output now stays in GOLDEN_CHECK_OUT/GOLDENS_OUT (build/golden-check,
    build/goldens), whose paths the messages name; the check's status 9 is make's "Error 9", and
    make returns 2 as docs/guide/running-and-testing.md says; tools/regen_goldens.py --check returns 9 itself."""
    scene = _scene_folder(tmp_path / "my-scene", assets, 30)
    made = make("goldens", f"SCENE_DIRS={scene}", "GOLDEN_FRAMES=1", f"GOLDENS_OUT={tmp_path / 'goldens'}")
    assert made.returncode == 0, made.stderr[-2000:]
    assert (scene / "golden" / "frame_0000.png").is_file()
    assert f"output in {tmp_path / 'goldens' / 'my-scene'}" in made.stderr

    _scene_folder(scene, assets, 10)            # the scene changes: its frame no longer matches
    check_out = tmp_path / "check"
    checked = make("golden-check", f"SCENE_DIRS={scene}", "GOLDEN_FRAMES=1", f"GOLDEN_CHECK_OUT={check_out}")
    assert checked.returncode == 2 and "golden-check] Error 9" in checked.stderr, checked.stderr[-2000:]
    diffs = re.findall(r"diff image (\S+\.png)", checked.stderr)
    assert diffs == [str(check_out / "my-scene" / "diff_0000.png")], checked.stderr[-2000:]
    assert Path(diffs[0]).is_file() and (check_out / "my-scene" / "frame_0000.png").is_file()
    assert f"the run's frames and diff images are in {check_out / 'my-scene'}" in checked.stderr
    direct = subprocess.run([sys.executable, "tools/regen_goldens.py", "--check", "--folder", str(scene),
                             "--frames", "1", "--out", str(tmp_path / "direct")], cwd=ROOT, capture_output=True,
                            text=True, timeout=300)
    assert direct.returncode == EXIT_GOLDEN_MISMATCH, direct.stderr[-2000:]

    remade = make("goldens", f"SCENE_DIRS={scene}", "GOLDEN_FRAMES=1", f"GOLDENS_OUT={tmp_path / 'goldens'}")
    assert remade.returncode == 0, remade.stderr[-2000:]
    changed = re.findall(r"pixels changed \(diff image (\S+\.png)\)", remade.stdout)
    assert changed == [str(tmp_path / "goldens" / "my-scene" / "diff_0000.png")] and Path(changed[0]).is_file()


def test_the_readme_says_what_make_golden_check_returns():
    text = " ".join((ROOT / "docs" / "guide" / "running-and-testing.md").read_text().split())
    assert "make golden-check SCENE_DIRS=my-scene" in text
    assert "build/golden-check/my-scene/" in text and "`Error 9`" in text and "exits 2" in text
