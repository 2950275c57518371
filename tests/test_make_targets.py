"""The Makefile's targets as a user runs them with variables of their own: `make` run in the
repository, its outputs sent to the test's temporary folder."""
from __future__ import annotations

import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


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
