"""A run stopped by a signal ends as any other end does (issue 35): Ctrl-C's SIGINT and SIGTERM stop
it after the instruction under way, and run.json (with the reason), console.log, the frames shown
so far and the animation are all written; the exit status is 128 + the signal's number, as shells
report it. Real signals, sent to the board model's process while it draws."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import pytest

from conftest import ROOT


@pytest.mark.parametrize("number, status, kind", [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")])
def test_a_signal_ends_the_run_with_everything_written(firmware, card, tmp_path, number, status, kind):
    out = tmp_path / "out"
    process = subprocess.Popen([sys.executable, "-m", "emulator", "run", str(firmware), "--sd", str(card),
                                "--frames", "100000", "--out", str(out), "--quiet"],
                               cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not (out / "frame_0002.png").exists():
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "no third frame in 120 s"
            time.sleep(0.05)
        process.send_signal(number)
        _, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == status, stderr
    assert "Traceback" not in stderr
    run = json.loads((out / "run.json").read_text())
    assert run["exit"] == kind and signal.Signals(number).name in run["message"]
    shown = sorted(p.name for p in out.glob("frame_*.png"))
    assert len(shown) == len(run["frames"]) >= 3
    assert (out / "animation.png").exists()
    console = (out / "console.log").read_text()
    # whole lines only; the last frame's line may still have been on its way
    assert console.endswith("\n") and f"frame {len(shown) - 2}\n" in console

