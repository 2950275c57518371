"""The tests' way of running `python -m emulator` (tests/emulator_runs.py): a forked child of a
process that has imported the board model gives what the command started from the shell gives."""
from __future__ import annotations

import subprocess
import sys

import pytest

from conftest import ROOT, run_emulator


def _from_the_shell(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "emulator", *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=600)


@pytest.mark.parametrize("args", [
    ("run", "build/firmware.elf", "--sd", "build/card.img", "--frames", "1", "--out", "{tmp}"),
    ("run", "build/firmware.elf", "--frames", "0"),
    ("run", "build/no-such-firmware.elf"),
], ids=["a-run", "usage-error", "missing-firmware"])
def test_a_run_gives_what_the_shell_gives(firmware, card, args, tmp_path):
    args = tuple(arg.replace("{tmp}", str(tmp_path)) for arg in args)
    forked, spawned = run_emulator(*args), _from_the_shell(*args)
    assert (forked.returncode, forked.stdout, forked.stderr) == (spawned.returncode, spawned.stdout, spawned.stderr)
    assert forked.args == spawned.args


def test_a_run_past_its_timeout_is_killed_and_the_next_run_works(firmware, card):
    with pytest.raises(subprocess.TimeoutExpired):
        run_emulator("run", "build/firmware.elf", "--sd", "build/card.img", "--frames", "100000", timeout=0.3)
    assert run_emulator("run", "build/firmware.elf", "--frames", "0").returncode == 2
