"""An output that cannot be written ends the run as any other end does (issue 35, item 2): the run
stops there, run.json says what could not be written (`output_failed`, exit write-failed), the
status is 16, and no traceback. A file size limit (RLIMIT_FSIZE, with SIGXFSZ ignored so that a
write past it fails with EFBIG as on a full disk) makes the failures."""
from __future__ import annotations

import json
import resource
import signal
import subprocess
import sys

from suite import ROOT


def run_limited(limit_bytes: int, *args: str) -> subprocess.CompletedProcess:
    def limit() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))
    return subprocess.run([sys.executable, "-m", "emulator", "run", *args], cwd=ROOT, preexec_fn=limit,
                          capture_output=True, text=True, timeout=600)


def test_a_trace_that_cannot_grow_stops_the_run_with_run_json(firmware, card, tmp_path):
    out, trace = tmp_path / "out", tmp_path / "trace.txt"
    result = run_limited(256 << 10, str(firmware), "--sd", str(card), "--frames", "2", "--out", str(out),
                         "--trace-insn", str(trace), "--quiet")
    assert result.returncode == 16, result.stderr
    assert "Traceback" not in result.stderr
    run = json.loads((out / "run.json").read_text())
    assert run["exit"] == "write-failed" and str(trace) in run["message"] and "too large" in run["message"]


def test_frames_that_cannot_be_written_stop_the_run_with_run_json(firmware, card, tmp_path):
    """The animation's side file passes the limit after a few frames: the run stops at that frame,
    and the frames before it, console.log and run.json are there."""
    out = tmp_path / "out"
    result = run_limited(100 << 10, str(firmware), "--sd", str(card), "--frames", "50", "--out", str(out), "--quiet")
    assert result.returncode == 16, result.stderr
    assert "Traceback" not in result.stderr
    run = json.loads((out / "run.json").read_text())
    assert run["exit"] == "write-failed" and "animation.png" in run["message"]
    written = sorted(p.name for p in out.glob("frame_*.png"))
    assert 1 <= len(written) < 50 and len(run["frames"]) >= len(written)
    assert (out / "console.log").read_text().startswith("boot: hart 0 up")
