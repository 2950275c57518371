"""--uart-input read as the firmware takes it (frontends/uart_input.py; issue 35, item 8): pipes and
FIFOs are taken (bash's <(...) too), an endless pipe does not keep the run from starting, and the
memory held is a chunk, whatever the input's length."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import threading

import pytest

from suite import ROOT
from emulator.errors import BadInput
from emulator.frontends.uart_input import CHUNK, UartInput

ECHO_INPUT = b"Ada\r\nhello world\nquit\n"


def drain(source: UartInput) -> bytes:
    taken = bytearray()
    while source.has_byte(0.0):
        taken.append(source.pop())
    return bytes(taken)


def test_a_pipe_is_read_a_chunk_at_a_time(tmp_path):
    read_end, write_end = os.pipe()
    data = bytes(range(256)) * (40 * CHUNK // 256)              # 40 chunks
    writer = threading.Thread(target=lambda: (os.write(write_end, data), os.close(write_end)))
    writer.start()
    source = UartInput(fd=read_end, owns_fd=True)
    largest = 0
    taken = bytearray()
    while source.has_byte(0.0):
        taken.append(source.pop())
        largest = max(largest, len(source._buffer))
    writer.join()
    source.close()
    assert bytes(taken) == data and source.total == len(data) and not source.may_grow
    assert largest <= CHUNK                                       # not the whole input


def test_a_byte_put_back_comes_out_again():
    source = UartInput(b"ab")
    assert source.has_byte(0.0) and source.pop() == ord("a")
    source.put_back(ord("a"))
    assert drain(source) == b"ab"


def test_a_fifo_is_taken(tmp_path):
    fifo = tmp_path / "input.fifo"
    os.mkfifo(fifo)
    writer = threading.Thread(target=lambda: fifo.write_bytes(ECHO_INPUT))
    writer.start()
    source = UartInput.open(str(fifo))                           # waits for the writer, as cat does
    assert drain(source) == ECHO_INPUT
    writer.join()
    source.close()


def test_a_folder_is_refused(tmp_path):
    with pytest.raises(BadInput, match="is a folder"):
        UartInput.open(str(tmp_path))
    with pytest.raises(BadInput, match="no such file"):
        UartInput.open(str(tmp_path / "nothing"))


def test_bash_process_substitution_and_an_endless_pipe(c_firmware, tmp_path):
    """`--uart-input <(printf ...)` names /dev/fd/N, a pipe; `yes |` never ends, and the run starts
    and ends at its time all the same."""
    out = tmp_path / "out"
    script = (f"{sys.executable} -m emulator run {c_firmware / 'echo.elf'} --uart-input <(printf 'Ada\\r\\nquit\\n') "
              f"--expect 'hello, Ada!' --quiet --out {out}")
    run = subprocess.run(["bash", "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    endless = tmp_path / "endless"
    run = subprocess.run(["bash", "-c", f"yes | {sys.executable} -m emulator run {c_firmware / 'echo.elf'} "
                                        f"--uart-input - --until 0.05 --quiet --out {endless}"],
                         cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    summary = json.loads((endless / "run.json").read_text())
    assert summary["uart_input"]["received"] > 0


def test_a_regular_file_counts_whole_and_does_not_grow(tmp_path):
    path = tmp_path / "input.bin"
    path.write_bytes(bytes(3 * CHUNK + 7))
    source = UartInput.open(str(path))
    assert source.total == 3 * CHUNK + 7 and not source.may_grow
    assert len(drain(source)) == 3 * CHUNK + 7 and source.total == 3 * CHUNK + 7
    source.close()


@pytest.mark.parametrize("end", ["the run's end", "SIGINT", "SIGTERM"])
def test_the_terminal_is_given_back_however_the_run_ends(c_firmware, tmp_path, end):
    """--uart-input - on a terminal puts it in cbreak mode with echo off while the run lasts (each
    key goes at once; the firmware echoes); however the run ends, the terminal is given back as it
    was (issue 35: a Ctrl-C used to leave it in cbreak mode, echo off). A pseudo-terminal stands
    for the user's."""
    import pty
    import signal
    import subprocess
    import sys
    import termios
    import time

    from suite import ROOT
    master, slave = pty.openpty()
    try:
        before = termios.tcgetattr(slave)
        assert before[3] & termios.ICANON and before[3] & termios.ECHO
        out = tmp_path / "out"
        until = "0.3" if end == "the run's end" else "1000"
        process = subprocess.Popen([sys.executable, "-m", "emulator", "run", str(c_firmware / "echo.elf"),
                                    "--uart-input", "-", "--until", until, "--out", str(out), "--quiet"],
                                   cwd=ROOT, stdin=slave, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if end != "the run's end":
            deadline = time.monotonic() + 60
            while termios.tcgetattr(slave)[3] & termios.ICANON:     # until the board model has it
                assert process.poll() is None and time.monotonic() < deadline, process.communicate()
                time.sleep(0.02)
            time.sleep(0.3)                                          # and the run is under way
            process.send_signal(signal.SIGINT if end == "SIGINT" else signal.SIGTERM)
        _, stderr = process.communicate(timeout=120)
        assert process.returncode == {"the run's end": 0, "SIGINT": 130, "SIGTERM": 143}[end], stderr
        assert "Traceback" not in stderr, stderr
        assert termios.tcgetattr(slave) == before
    finally:
        os.close(master)
        os.close(slave)
