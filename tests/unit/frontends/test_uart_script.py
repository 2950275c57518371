"""--uart-script (frontends/uart_script.py): a conversation with the console, step by step, with
tests/firmware/echo.c at the other end; and what a script file may hold."""
from __future__ import annotations

import json

import pytest

from suite import run_emulator
from emulator.errors import BadInput
from k210_common.exit_status import EXIT_EXPECT_UNMET
from emulator.frontends.uart_script import DEFAULT_TIMEOUT_S, parse


def test_steps_escapes_and_timeouts():
    steps = parse("# a comment\n\nexpect name? \nsend Ada\\r\\n\\x41\\\\\ntimeout 2.5\nexpect-re ^hello, (\\w+)!$\n"
                  "sleep 0.01\n", "s.txt")
    assert [(s.line, s.keyword) for s in steps] == [(3, "expect"), (4, "send"), (6, "expect-re"), (7, "sleep")]
    assert steps[0].text == "name? " and steps[0].seconds == DEFAULT_TIMEOUT_S
    assert steps[1].text == "Ada\r\nA\\"
    assert steps[2].regex.pattern == "^hello, (\\w+)!$" and steps[2].seconds == 2.5
    assert steps[3].seconds == 0.01


@pytest.mark.parametrize("text, message", [
    ("wait 1\n", "s.txt:1: 'wait' is not one of"),
    ("\nsend\n", "s.txt:2: send needs a text"),
    ("sleep soon\n", "s.txt:1: sleep needs a number of seconds"),
    ("timeout -1\n", "s.txt:1: timeout needs a number of seconds"),
    ("expect-re (\n", "s.txt:1: '(' is not a regular expression"),
    ("send a\\qb\n", "s.txt:1: an escape other than"),
])
def test_what_a_script_cannot_hold_is_named_by_its_line(text, message):
    with pytest.raises(BadInput, match=message.replace("(", r"\(")):
        parse(text, "s.txt")


def script_run(c_firmware, tmp_path, script: str, *flags):
    path = tmp_path / "session.txt"
    path.write_text(script)
    out = tmp_path / "out"
    run = run_emulator("run", str(c_firmware / "echo.elf"), "--uart-script", str(path), "--quiet", "--out", str(out),
                       *flags)
    return run, json.loads((out / "run.json").read_text())


def test_a_conversation_with_the_echo_program(c_firmware, tmp_path):
    run, summary = script_run(c_firmware, tmp_path, "expect name? \nsend Ada\\r\nexpect-re ^hello, Ada!$\n"
                              "expect > \nsend level\\r\nexpect-re reversed: level$\nsleep 0.005\nsend quit\\r\n"
                              "expect bye\n")
    assert run.returncode == 0, run.stderr
    assert "ran to its end (9 steps" in summary["message"]
    lines = [entry["line"] for entry in summary["console"]]
    assert lines[:3] == ["name? Ada", "hello, Ada!", "> level"]
    done = summary["uart_script"]["done"]
    assert [step["line"] for step in done] == list(range(1, 10))
    slept = done[6]["virtual_time_s"] - done[5]["virtual_time_s"]
    assert slept == pytest.approx(0.005, abs=1e-6)
    assert summary["uart_script"]["sent"] == len("Ada\rlevel\rquit\r")


def test_an_expect_not_met_in_time_fails_naming_its_line(c_firmware, tmp_path):
    run, summary = script_run(c_firmware, tmp_path, "timeout 0.02\nexpect name? \nsend Ada\\r\nexpect goodbye\n")
    assert run.returncode == EXIT_EXPECT_UNMET
    assert "session.txt:4: expect 'goodbye': the console did not print it within 0.02 s" in run.stderr
    assert summary["uart_script"]["waiting_at"] == {"line": 4, "step": "expect 'goodbye'"}


def test_until_bounds_a_script(c_firmware, tmp_path):
    run, summary = script_run(c_firmware, tmp_path, "expect name? \nsleep 5\n", "--until", "0.05")
    assert run.returncode == EXIT_EXPECT_UNMET and "session.txt:2: sleep 5: not done by 0.05 s" in run.stderr


def test_a_script_excludes_the_options_that_would_fight_it(c_firmware, tmp_path):
    (tmp_path / "s.txt").write_text("expect x\n")
    run = run_emulator("run", str(c_firmware / "echo.elf"), "--uart-script", str(tmp_path / "s.txt"), "--expect", "x",
                       "--out", str(tmp_path / "out"))
    assert run.returncode == 2 and "--uart-script excludes" in run.stderr


def test_text_printed_during_a_sleep_counts_and_lines_start_after_the_match(c_firmware, tmp_path):
    run, summary = script_run(c_firmware, tmp_path, "sleep 0.05\nexpect name? \nsend Ada\\r\nexpect-re ^Ada$\n")
    assert run.returncode == 0, run.stderr


def test_a_script_ending_in_a_sleep_at_the_until_time_ends_cleanly(c_firmware, tmp_path):
    run, summary = script_run(c_firmware, tmp_path, "sleep 0.01\n", "--until", "0.01")
    assert run.returncode == 0 and "Traceback" not in run.stderr, run.stderr


def test_a_character_beyond_latin_1_is_bad_input_naming_its_line(c_firmware, tmp_path):
    (tmp_path / "session.txt").write_text("expect name? \nsend 5 \u20ac\\r\n", encoding="utf-8")
    run = run_emulator("run", str(c_firmware / "echo.elf"), "--uart-script", str(tmp_path / "session.txt"),
                       "--quiet", "--out", str(tmp_path / "out"))
    assert run.returncode == 6 and "session.txt:2:" in run.stderr and "beyond 0xFF" in run.stderr
