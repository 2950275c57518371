"""The tests' way of running `python -m emulator`, `python -m reference` and `python -m sdcard_image`
(tests/support/emulator_runs.py): a forked child of a process that has imported the project gives what the
command started from the shell gives."""
from __future__ import annotations

import subprocess
import sys

import pytest

from suite import ROOT, run_emulator
from emulator_runs import run_module


def _from_the_shell(*args: str, module: str = "emulator", cwd=ROOT, text: bool = True) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", module, *args], cwd=cwd, capture_output=True, text=text,
                          timeout=600)


@pytest.mark.parametrize("args", [
    ("run", "build/firmware.elf", "--sd", "build/card.img", "--frames", "1", "--out", "{tmp}"),
    ("run", "build/firmware.elf", "--frames", "0"),
    ("run", "build/no-such-firmware.elf", "--out", "{tmp}"),     # its run.json: not into build/frames
], ids=["a-run", "usage-error", "missing-firmware"])
def test_a_run_gives_what_the_shell_gives(firmware, card, args, tmp_path):
    args = tuple(arg.replace("{tmp}", str(tmp_path)) for arg in args)
    forked, spawned = run_emulator(*args), _from_the_shell(*args)
    assert (forked.returncode, forked.stdout, forked.stderr) == (spawned.returncode, spawned.stdout, spawned.stderr)
    assert forked.args == spawned.args


def test_a_run_past_its_timeout_is_killed_and_the_next_run_works(firmware, card, tmp_path):
    with pytest.raises(subprocess.TimeoutExpired):
        run_emulator("run", "build/firmware.elf", "--sd", "build/card.img", "--frames", "100000", "--out",
                     str(tmp_path), timeout=0.3)
    assert run_emulator("run", "build/firmware.elf", "--frames", "0").returncode == 2


@pytest.mark.parametrize("module, args", [
    ("sdcard_image", ("list", "build/card.img")),
    ("sdcard_image", ("extract", "build/card.img", "/scene.ini", "-")),
    ("sdcard_image", ("list", "no-such-card.img")),
    ("reference", ("render-card", "build/card.img", "--frames", "1", "--out", "{tmp}", "--quiet")),
    ("reference", ("render", "{tmp}/no-such-folder", "--out", "{tmp}/out")),
], ids=["list", "extract-to-stdout", "missing-card", "render", "missing-folder"])
def test_the_other_tools_run_as_from_the_shell(card, module, args, tmp_path):
    """Also from another working folder, and with output as bytes."""
    args = tuple(arg.replace("{tmp}", str(tmp_path)) for arg in args)
    forked, spawned = run_module(module, *args, cwd=ROOT), _from_the_shell(*args, module=module)
    assert (forked.returncode, forked.stdout, forked.stderr) == (spawned.returncode, spawned.stdout, spawned.stderr)
    assert forked.args == spawned.args
    absolute = tuple(str(ROOT / arg) if arg.startswith("build/") else arg for arg in args)
    forked = run_module(module, *absolute, cwd=tmp_path, text=False)
    spawned = _from_the_shell(*absolute, module=module, cwd=tmp_path, text=False)
    assert (forked.returncode, forked.stdout, forked.stderr) == (spawned.returncode, spawned.stdout, spawned.stderr)


def test_only_the_served_packages_run():
    with pytest.raises(ValueError, match="not one of the packages"):
        run_module("pip", "--version")
