"""A run stopped by a signal ends as any other end does (issue 35): Ctrl-C's SIGINT and SIGTERM stop
it after the instruction under way, and run.json (with the reason), console.log, the frames shown
so far and the animation are all written; the exit status is 128 + the signal's number, as shells
report it. Real signals, sent to the board model's process while it draws."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from suite import ROOT


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
    # every byte the UART sent is there: the lines run.json times, then what was on the wire
    lines = [entry["line"] for entry in run["console"]]
    assert console.splitlines()[:len(lines)] == lines and f"frame {len(shown) - 2}" in lines



def start(*args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "emulator", "run", *args], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_a_signal_while_waiting_for_gdb_ends_the_run(c_firmware, tmp_path):
    """The wait for GDB to attach used to take the signal in, and go on waiting."""
    out = tmp_path / "out"
    process = start(str(c_firmware / "hello.elf"), "--gdb", "0", "--gdb-wait", "--out", str(out))
    assert "listening on 127.0.0.1" in process.stderr.readline()
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=30)
    assert process.returncode == 130 and "Traceback" not in stderr, stderr
    assert json.loads((out / "run.json").read_text())["exit"] == "interrupted"


def test_a_signal_while_a_fifo_s_writer_is_quiet_ends_the_run(c_firmware, tmp_path):
    """The run waits for the FIFO's writer (its bytes count as there from the start); a signal
    ends that wait too."""
    fifo, out = tmp_path / "input.fifo", tmp_path / "out"
    os.mkfifo(fifo)
    process = start(str(c_firmware / "echo.elf"), "--uart-input", str(fifo), "--until", "10", "--out", str(out),
                    "--quiet")
    writer = os.open(fifo, os.O_WRONLY)              # there, and silent
    try:
        deadline = time.monotonic() + 120
        while not (out / "console.log").exists():    # the run's output is there: the board follows
            assert time.monotonic() < deadline and process.poll() is None
            time.sleep(0.05)
        sleeping_in(process, SELECT_WAITS)            # the firmware waits for a line meanwhile
        process.send_signal(signal.SIGTERM)
        _, stderr = process.communicate(timeout=30)
    finally:
        os.close(writer)
    assert process.returncode == 143 and "Traceback" not in stderr, stderr
    assert json.loads((out / "run.json").read_text())["exit"] == "terminated"


def test_a_signal_before_the_board_exists_is_no_traceback(c_firmware, tmp_path):
    """Opening a FIFO waits for a writer, before the board is built: Ctrl-C there ends the command
    with its status and words."""
    fifo = tmp_path / "input.fifo"
    os.mkfifo(fifo)
    process = start(str(c_firmware / "echo.elf"), "--uart-input", str(fifo), "--out", str(tmp_path / "out"))
    sleeping_in(process, ("wait_for_partner",))   # opening the FIFO
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=30)
    assert process.returncode == 130 and "Traceback" not in stderr and "interrupted" in stderr, stderr


# where Linux says (/proc/PID/wchan) a process sleeps in select(), by kernel version
SELECT_WAITS = ("poll_schedule_timeout", "do_select", "do_sys_poll")


def sleeping_in(process: subprocess.Popen, waits: tuple[str, ...], longest: float = 2.0) -> None:
    """Waits until the process sleeps where Linux's /proc/PID/wchan names one of `waits` (a prefix), or
    `longest` seconds where the kernel does not say."""
    deadline = time.monotonic() + longest
    while time.monotonic() < deadline and process.poll() is None:
        try:
            if Path(f"/proc/{process.pid}/wchan").read_text().strip().startswith(waits):
                return
        except OSError:
            pass
        time.sleep(0.01)


def test_signals_while_the_outputs_are_written_are_ignored():
    from emulator.frontends.cli import SignalStop
    before = signal.getsignal(signal.SIGINT)            # (a test worker's own may not be Python's default)
    stop = SignalStop()
    try:
        stop.writing = True
        os.kill(os.getpid(), signal.SIGINT)             # would raise KeyboardInterrupt or Interrupted
        time.sleep(0.05)
    finally:
        stop.restore()
    assert signal.getsignal(signal.SIGINT) is before


# the fuzz stage's signals: a few examples by default, each a run of the command line
SIGNAL_EXAMPLES = max(3, int(os.environ.get("FUZZ_EXAMPLES", "150")) // 30)


def handlers_installed(process: subprocess.Popen, timeout: float = 30.0) -> None:
    """Waits until the process catches SIGTERM (Linux's /proc/PID/status, SigCgt): emulator/__main__.py's
    first lines have run. Before them a signal is CPython's own business (its start-up, which a loaded
    machine can stretch past any fixed delay)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        try:
            status = Path(f"/proc/{process.pid}/status").read_text()
        except OSError:
            return
        caught = next((int(line.split()[1], 16) for line in status.splitlines() if line.startswith("SigCgt:")), 0)
        if caught >> (signal.SIGTERM - 1) & 1:
            return
        time.sleep(0.005)


def test_a_signal_at_any_moment_ends_the_command_with_its_status(c_firmware, tmp_path_factory):
    """Hypothesis (the fuzz stage, issue 35): SIGINT or SIGTERM at any moment of a short run, from
    the command's first line (its modules being imported, the board being built) through the run to
    the outputs being written: the command ends with 128 + the signal's number, or 0 when the run
    had ended first, never a traceback; run.json, when written, says how the run ended. (Not
    before emulator/__main__.py's first lines: until then a signal is CPython's own business.)"""
    from hypothesis import given, settings
    from hypothesis import strategies as st

    @settings(max_examples=SIGNAL_EXAMPLES, deadline=None, derandomize=True)
    @given(number=st.sampled_from([signal.SIGINT, signal.SIGTERM]), delay=st.floats(0.0, 2.3))
    def check(number, delay):
        out = tmp_path_factory.mktemp("signal") / "out"
        process = start(str(c_firmware / "hello.elf"), "--until", "0.5", "--out", str(out), "--quiet")
        handlers_installed(process)
        time.sleep(delay)
        process.send_signal(number)
        _, stderr = process.communicate(timeout=60)
        status = {signal.SIGINT: 130, signal.SIGTERM: 143}[number]
        assert "Traceback" not in stderr, stderr
        if process.returncode == -number:
            # the signal came as the interpreter exited, everything written (Python puts the default
            # handlers back then): the run's own end is what run.json says
            assert json.loads((out / "run.json").read_text())["exit"] == "ok", stderr
            return
        assert process.returncode in (0, status), stderr
        if (out / "run.json").exists():
            run = json.loads((out / "run.json").read_text())
            assert run["exit"] == ("ok" if process.returncode == 0 else
                                   {130: "interrupted", 143: "terminated"}[process.returncode])
    check()
