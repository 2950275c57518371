"""Running one's own firmware as a test (issue 13): --expect / --expect-re end the run with
success once the console has printed them in order, --fail-on / --fail-on-re with failure
(status 11), an expectation not met by --until's time or within --budget fails (status 12);
--uart-input feeds UARTHS's receiver; a raw firmware.bin boots as the ROM would load it.
The programs are the C test firmware's (tests/firmware/): hello prints three lines, echo
answers the lines it reads."""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

from suite import ROOT, run_emulator
from emulator.frontends.console_watch import ConsolePattern, ConsoleWatch
from emulator.errors import ConsoleExpectationsMet, ConsoleFailText
from emulator.vtime import PS_PER_US

ECHO_INPUT = b"Ada\r\nhello world\nquit\n"


def summary_of(out) -> dict:
    return json.loads((out / "run.json").read_text())


# --- the watch on its own ---------------------------------------------------------------------

def feed(watch: ConsoleWatch, text: str, stops: list) -> None:
    watch.attach(stops.append)
    for i, ch in enumerate(text.encode()):
        watch.byte(ch, i * 100 * PS_PER_US)


def test_texts_are_found_in_the_stream_in_order_and_across_lines():
    stops: list = []
    watch = ConsoleWatch([ConsolePattern.literal("b"), ConsolePattern.literal("a"),
                          ConsolePattern.literal("x\ny")], [])
    feed(watch, "ab", stops)                   # "a" before "b" does not count for the second
    assert [m.pattern.text for m in watch.matches] == ["b"] and not stops
    feed(watch, "ax\n", stops)
    assert not stops
    feed(watch, "y", stops)                    # a prompt that ends no line is found too
    assert len(stops) == 1 and isinstance(stops[0], ConsoleExpectationsMet)


def test_a_regular_expression_waits_for_the_whole_line():
    stops: list = []
    watch = ConsoleWatch([ConsolePattern.expression(r"^frame \d+$")], [])
    feed(watch, "frame 1", stops)
    assert not stops                            # "frame 1" could still become "frame 12x"
    feed(watch, "2x\r\nframe 7\r\n", stops)
    assert len(stops) == 1 and watch.matches[0].line == "frame 7"


def test_a_failure_text_counts_anywhere():
    stops: list = []
    watch = ConsoleWatch([ConsolePattern.literal("done")], [ConsolePattern.expression("err(or)? [0-9]+")])
    feed(watch, "starting\nerror 12 out of memory\ndone\n", stops)
    assert len(stops) == 1 and isinstance(stops[0], ConsoleFailText)
    assert watch.failure.line == "error 12 out of memory" and not watch.matches


def test_empty_texts_and_bad_expressions_are_refused():
    with pytest.raises(ValueError, match="empty text"):
        ConsolePattern.literal("")
    with pytest.raises(ValueError, match="not a regular expression"):
        ConsolePattern.expression("(")


# --- through the command line -----------------------------------------------------------------

def test_a_program_that_reads_its_input_passes_with_expect(c_firmware, tmp_path):
    (tmp_path / "input.txt").write_bytes(ECHO_INPUT)
    out = tmp_path / "out"
    run = run_emulator("run", str(c_firmware / "echo.elf"), "--uart-input", str(tmp_path / "input.txt"),
                       "--expect", "name? ", "--expect", "hello, Ada!",
                       "--expect-re", r"^line 1: 11 characters, reversed: dlrow olleh$",
                       "--expect", "bye", "--fail-on", "line 2", "--quiet", "--out", str(out))
    assert run.returncode == 0, run.stderr
    summary = summary_of(out)
    assert summary["exit"] == "ok" and "printed every expected text" in summary["message"]
    assert [m["pattern"] for m in summary["expect_matched"]] == summary["expect"]
    assert summary["uart_input"] == {"source": str(tmp_path / "input.txt"), "interactive": False,
                                     "bytes": len(ECHO_INPUT), "received": len(ECHO_INPUT),
                                     "received_by": {"UARTHS": len(ECHO_INPUT)}}
    assert [e["line"] for e in summary["console"]][:3] == ["name? Ada", "hello, Ada!", "> hello world"]
    # the run ends at the last expected text, not later
    times = [m["virtual_time_s"] for m in summary["expect_matched"]]
    assert times == sorted(times) and summary["virtual_time_s"] == pytest.approx(times[-1], abs=1e-3)


def test_piped_standard_input_is_sent_whole(c_firmware, tmp_path):
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, "-m", "emulator", "run", str(c_firmware / "echo.elf"),
                          "--uart-input", "-", "--expect", "bye", "--quiet", "--out", str(out)],
                         cwd=ROOT, input=ECHO_INPUT, capture_output=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert summary_of(out)["uart_input"]["received"] == len(ECHO_INPUT)


def test_a_failure_text_ends_the_run_with_status_11(c_firmware, tmp_path):
    run = run_emulator("run", str(c_firmware / "hello.elf"), "--fail-on-re", r"sqrt\(2\) = [0-9.]+",
                       "--until", "0.1", "--quiet", "--out", str(tmp_path))
    assert run.returncode == 11, run.stderr
    assert "--fail-on /sqrt\\(2\\) = [0-9.]+/: the console printed it at" in run.stderr
    assert summary_of(tmp_path)["fail_on_matched"]["line"].startswith("malloc works; sqrt(2) = 1.414214")


@pytest.mark.parametrize("limit, words", [([], "in 5 s of virtual time after the previous expected text"),
                                          (["--until", "0.05"], "by --until's 0.05 s of virtual time")])
def test_an_expected_text_never_printed_fails_with_status_12(c_firmware, tmp_path, limit, words):
    run = run_emulator("run", str(c_firmware / "hello.elf"), "--expect", "hello from C", "--expect", "goodbye",
                       *limit, "--quiet", "--out", str(tmp_path))
    assert run.returncode == 12, run.stderr
    assert f"--expect 'goodbye': {words}" in run.stderr
    assert "(1 of 2 expected texts printed before)" in run.stderr


@pytest.mark.parametrize("args, words", [
    (["--expect", "x", "--frames", "2"], "--expect and --frames exclude each other"),
    (["--expect", ""], "argument --expect: an empty text would match before anything is printed"),
    (["--fail-on-re", "a["], "argument --fail-on-re: 'a[' is not a regular expression"),
])
def test_bad_patterns_and_combinations_are_usage_errors(c_firmware, tmp_path, args, words):
    run = run_emulator("run", str(c_firmware / "hello.elf"), *args, "--out", str(tmp_path / "out"))
    assert run.returncode == 2 and words in run.stderr
    assert not (tmp_path / "out").exists()


def test_a_missing_input_file_is_bad_input(c_firmware, tmp_path):
    run = run_emulator("run", str(c_firmware / "echo.elf"), "--uart-input", str(tmp_path / "nope.txt"),
                       "--expect", "bye", "--out", str(tmp_path / "out"))
    assert run.returncode == 6 and f"--uart-input {tmp_path / 'nope.txt'}: no such file" in run.stderr


# --- raw images ---------------------------------------------------------------------------------

def test_a_raw_image_boots_as_its_elf_does(c_firmware, tmp_path):
    binary = tmp_path / "hello.bin"
    subprocess.run(["riscv64-unknown-elf-objcopy", "-O", "binary", str(c_firmware / "hello.elf"), str(binary)],
                   check=True)
    runs = {}
    for image in (c_firmware / "hello.elf", binary):
        out = tmp_path / image.suffix[1:]
        run = run_emulator("run", str(image), "--until", "0.05", "--quiet", "--out", str(out))
        assert run.returncode == 0, run.stderr
        runs[image.suffix] = summary_of(out)
    assert runs[".bin"]["console"] == runs[".elf"]["console"]
    assert runs[".bin"]["instructions"] == runs[".elf"]["instructions"]


@pytest.mark.parametrize("content, words", [(b"", "the raw image is empty"),
                                            (b"\0" * (8 * 1024 * 1024 + 1), "more than the 8388608 bytes")])
def test_raw_images_that_cannot_be_loaded_are_bad_input(tmp_path, content, words):
    image = tmp_path / "firmware.bin"
    image.write_bytes(content)
    run = run_emulator("run", str(image), "--until", "0.01", "--out", str(tmp_path / "out"))
    assert run.returncode == 6 and words in run.stderr


def test_the_readme_shows_the_minimal_program_as_it_is():
    readme = (ROOT / "docs" / "guide" / "your-own-firmware.md").read_text()
    shown = readme.split("```asm\n", 1)[1].split("```", 1)[0]
    assert shown == (ROOT / "tests" / "firmware" / "hello.S").read_text()


def test_keys_typed_on_a_terminal_reach_the_firmware(c_firmware, tmp_path):
    """`--uart-input -` from a terminal: each key goes as it is typed (a pseudo-terminal here),
    and the terminal's settings are given back afterwards."""
    import os
    import pty
    import termios
    master, terminal = pty.openpty()
    before = termios.tcgetattr(terminal)
    out = tmp_path / "out"
    process = subprocess.Popen([sys.executable, "-m", "emulator", "run", str(c_firmware / "echo.elf"),
                                "--uart-input", "-", "--expect", "hello, Ada!", "--expect", "bye", "--out", str(out)],
                               cwd=ROOT, stdin=terminal, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        os.write(master, b"Ada\rquit\r")
        _, errors = process.communicate(timeout=600)
        after = termios.tcgetattr(terminal)
    finally:
        process.kill()
        os.close(master)
        os.close(terminal)
    assert process.returncode == 0, errors.decode()
    summary = summary_of(out)
    assert summary["uart_input"]["interactive"] is True and summary["uart_input"]["received"] == 9
    assert after == before
