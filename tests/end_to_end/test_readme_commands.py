"""Every command README.md and docs/**/*.md show is run here, as written (from the repository's root, `python`
being the project's virtual environment), or, where running it inside the suite is not
possible, checked as far as it can be, for a reason stated next to it:

- `make test` is what CI runs (.ci/run), so the suite cannot run itself;
- `make bench` takes minutes, `make goldens` rewrites tests/golden and `make flash-to-emulator
  VIEW=1` serves its page until Ctrl-C (tests/end_to_end/test_view_browser.py runs that command line with a
  browser): `make -n` checks that the target exists and what it would run;
- the environment variables of the long test runs must be read by the tests they name.

What the commands write goes to the test's temporary folder, never into build/, whose outputs
are the user's (`make flash-to-emulator`'s build/frames, ...): `as_run` moves every `build/NAME`
that is not a prerequisite the Makefile builds (the firmware, the C programs, the default card)
into it, and gives `make` its output folder's variable; each test checks that build/ holds,
besides those prerequisites, what it held before (`build_outputs_untouched`).

A command added to the README or docs/ without an entry here fails `test_every_command_is_known`.
"""
from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from build_outputs import PREREQUISITES, build_outputs, changed_outputs
from suite import ROOT

README = ROOT / "README.md"
#: The documents whose commands are checked: the front page and every page of docs/.
DOCUMENTS = [README, *sorted((ROOT / "docs").rglob("*.md"))]
VENV_BIN = Path(sys.executable).parent
#: The make targets the tests run that write an output, and the variable naming its folder.
MAKE_OUTPUTS = {"flash-to-emulator": ("FRAMES_DIR", "build/frames")}


def readme_commands(text: str) -> list[str]:
    """The commands of the README: each line of a ```sh block (without its # comment) and each
    inline `...` span that starts with `make `, `python -m `, `.venv/bin/python ` or an
    environment assignment followed by one of those."""
    commands: list[str] = []
    for block in re.findall(r"```sh\n(.*?)```", text, flags=re.S):
        for line in block.splitlines():
            line = line.split(" #", 1)[0].strip()
            if line:
                commands.append(line)
    starts = r"(?:[A-Z_]+=\S+ )*(?:make |python -m |\.venv/bin/python )"
    for span in re.findall(r"`([^`\n]+)`", re.sub(r"```.*?```", "", text, flags=re.S)):
        if re.match(starts, span):
            commands.append(span.strip())
    return list(dict.fromkeys(commands))


def as_run(command: str, tmp: Path) -> str:
    """The README command as the tests run it: every output it names in build/ moved into `tmp`
    (the prerequisites it reads stay), and a make target's output folder given as its variable."""
    def moved(match: re.Match) -> str:
        return match.group(0) if PREREQUISITES.match(match.group(1)) else shlex.quote(str(tmp / match.group(1)))
    command = re.sub(r"(?<![\w./-])build/([\w.-]+)", moved, command)
    words = shlex.split(command)
    if "make" in words:
        for target, (variable, folder) in MAKE_OUTPUTS.items():
            if target in words[words.index("make") + 1:]:
                command += f" {variable}={shlex.quote(str(tmp / Path(folder).name))}"
    return command


def where(folder: str, tmp: Path) -> Path:
    """Where a folder a README command names in build/ is when the test runs it (as_run)."""
    name = Path(folder).relative_to("build")
    return ROOT / folder if PREREQUISITES.match(name.parts[0]) else tmp / name


@pytest.fixture(autouse=True)
def build_outputs_untouched():
    """Issue 32: `make test` overwrote build/frames (and wrote build/hello, build/blink, ...)."""
    before = build_outputs()
    yield
    changed = changed_outputs(before)
    assert not changed, f"the test wrote into build/, the user's outputs: {changed[:10]}"


def run(command: str, timeout: float = 300) -> subprocess.CompletedProcess:
    """Runs a README command in the repository root with the venv's python first on PATH."""
    env = {**os.environ, "PATH": f"{VENV_BIN}{os.pathsep}{os.environ['PATH']}"}
    return subprocess.run(command, shell=True, cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=timeout)


def _ran_frames(folder: str, frames: int):
    def check(result: subprocess.CompletedProcess, tmp: Path) -> None:
        summary = json.loads((where(folder, tmp) / "run.json").read_text())
        assert summary["exit"] == "ok" and len(summary["frames"]) == frames, summary["message"]
    return check


def _golden_matched(result: subprocess.CompletedProcess, tmp: Path) -> None:
    assert "[golden] all 4 frames match tests/golden/default" in result.stderr


def _frames_written(folder: str, frames: int):
    def check(result: subprocess.CompletedProcess, tmp: Path) -> None:
        assert sorted(p.name for p in where(folder, tmp).glob("frame_*.png")) == \
            [f"frame_{n:04d}.png" for n in range(frames)]
    return check


def _dry_run(command: str) -> str:
    """`make X` -> `make -n X`: the target exists and its recipe expands."""
    words = shlex.split(command)
    index = words.index("make")
    return shlex.join(words[:index + 1] + ["-n"] + words[index + 1:])


def _env_read_by_tests(*names: str):
    def check(result: subprocess.CompletedProcess, tmp: Path) -> None:
        sources = "".join(p.read_text() for p in (ROOT / "tests").rglob("test_*.py"))
        for name in names:
            assert f'environ.get("{name}"' in sources, f"no test reads {name}"
    return check


def _ci_runs(command: str):
    def check(result: subprocess.CompletedProcess, tmp: Path) -> None:
        assert command in (ROOT / ".ci" / "run").read_text().splitlines()
    return check


def _lists_exit_statuses(result: subprocess.CompletedProcess, tmp: Path) -> None:
    assert "exit status:" in result.stdout


def _tables_match(result: subprocess.CompletedProcess, tmp: Path) -> None:
    assert "(differ)" not in result.stdout
    for path, key in [("docs/reference/exit-statuses.md", "all"), ("docs/reference/options.md", "emulator"),
                      ("docs/reference/reference-renderer.md", "reference")]:
        assert f"{path}: tables {key}" in result.stdout, result.stdout


def _prints_agreement(result: subprocess.CompletedProcess, tmp: Path) -> None:
    from golden_scenes import SCENES            # one line per golden scene with triangles
    assert result.stdout.count("lit per face: identical") == len(SCENES)


def _console_says(folder: str, *lines: str):
    def check(result: subprocess.CompletedProcess, tmp: Path) -> None:
        assert result.returncode == 0, result.stderr
        console = (where(folder, tmp) / "console.log").read_text()
        for line in lines:
            assert line in console, console
    return check


def _c_golden_matched(result: subprocess.CompletedProcess, tmp: Path) -> None:
    assert result.returncode == 0, result.stderr
    assert "[golden] all 4 frames match tests/golden/c-lcd-demo" in result.stderr


def _serves_the_view(result: subprocess.CompletedProcess, tmp: Path) -> None:
    run_line = next(line for line in result.stdout.splitlines() if "-m emulator run" in line)
    assert "--view 8210" in run_line and "--frames" not in run_line      # until Ctrl-C (test_view_browser.py)


#: README command -> (how it is checked: "run" or "dry-run", what must hold afterwards).
#: "dry-run" commands go through `make -n` (see the module's docstring for why).
COMMANDS = {
    "make firmware": ("run", lambda r, tmp: None),
    "make test": ("ci", _ci_runs("make test")),
    "make bench": ("dry-run", lambda r, tmp: None),
    # (CoreMark's sources are not in the repository: tests/unit/tools/test_coremark.py runs it where a
    # checkout is at hand)
    "make coremark COREMARK=DIR": ("dry-run", lambda r, tmp: None),
    # (likewise the thesis's firmware: tests/unit/tools/test_thesis_firmware.py)
    "make thesis-firmware THESIS=DIR": ("dry-run", lambda r, tmp: None),
    "make goldens": ("dry-run", lambda r, tmp: None),
    "make goldens SCENES=gem-flat": ("dry-run", lambda r, tmp: None),
    "make debug": ("dry-run", lambda r, tmp: None),
    "make flash-to-emulator VIEW=1": ("dry-run", _serves_the_view),
    "make flash-to-emulator CARD=build/my-card.img VIEW=1": ("dry-run", _serves_the_view),
    "make flash PORT=/dev/ttyUSB0": ("dry-run", lambda r, tmp: None),
    'make goldens SCENE_DIRS="my-scene other-scene"': ("dry-run", lambda r, tmp: None),
    "make golden-check SCENE_DIRS=my-scene": ("dry-run", lambda r, tmp: None),
    "EXTREMES_FULL=1 make test": ("dry-run", _env_read_by_tests("EXTREMES_FULL")),
    "FUZZ_EXAMPLES=5000 FUZZ_BOOTS=100 make test": ("dry-run",
                                                   _env_read_by_tests("FUZZ_EXAMPLES", "FUZZ_BOOTS")),
    "python -m emulator run build/firmware.elf --sd build/card.img --frames 4 --out build/golden-check "
    "--golden tests/golden/default": ("run", _golden_matched),
    "python -m reference render-card build/card.img --frames 2 --out build/reference":
        ("run", _frames_written("build/reference", 2)),
    "python -m reference render-card build/card.img --frames 2 --out build/reference-ideal --ideal":
        ("run", _frames_written("build/reference-ideal", 2)),
    "python -m emulator run --help": ("run", _lists_exit_statuses),
    "make c-firmware": ("run", lambda r, tmp: None),
    "python -m emulator run build/cfw/hello.elf --until 0.05 --out build/hello":
        ("run", _console_says("build/hello", "hello from C on the K210")),
    "python -m emulator run build/cfw/blink.elf --until 0.6 --out build/blink":
        ("run", _console_says("build/blink", "tick 10: blue off, green on", "blink: done")),
    "python -m emulator run build/cfw/lcd_demo.elf --frames 4 --out build/lcd-demo --golden tests/golden/c-lcd-demo":
        ("run", _c_golden_matched),
    "python -m emulator run build/cfw/lcd_demo_serial.elf --lcd-interface spi --frames 4 --out build/lcd-serial "
    "--golden tests/golden/c-lcd-demo": ("run", _c_golden_matched),
    "printf 'Ada\\nhello world\\nquit\\n' | python -m emulator run build/cfw/echo.elf --uart-input - "
    '--expect "hello, Ada!" --expect bye --out build/echo': ("run", _console_says("build/echo", "hello, Ada!", "bye")),
    ".venv/bin/python -m pytest tests/unit/tools/test_reference.py -k first_golden -s":
        ("run", _prints_agreement),
    "python -m tools.exit_status_tables --check": ("run", _tables_match),
    "python -m tools.memory_limits --check": ("run", lambda result, tmp: None),
    "python -m tools.bench_history --check": ("run", lambda result, tmp: None),
}
#: Each needs the one before (assemble, link, run), so they run in this order in one test.
OWN_FIRMWARE_COMMANDS = {
    "riscv64-unknown-elf-as -march=rv64gc -o build/hello-asm.o tests/firmware/hello.S": lambda r, tmp: None,
    "riscv64-unknown-elf-ld -N -Ttext=0x80000000 --no-warn-rwx-segments -o build/hello-asm.elf build/hello-asm.o":
        lambda r, tmp: None,
    'python -m emulator run build/hello-asm.elf --expect "hello from my own firmware" --fail-on "error" '
    "--out build/hello-asm": _console_says("build/hello-asm", "hello from my own firmware"),
}
#: The README's five-minute walk-through, in its order: write a model, build a card of it, run it.
WALKTHROUGH_COMMANDS = {
    "mkdir -p build/my-scene": lambda r, tmp: None,
    "printf 'v -1 -1 0\\nv 1 -1 0\\nv 0 1 0\\nf 1 2 3\\n' > build/my-scene/model.obj": lambda r, tmp: None,
    "python -m sdcard_image build build/my-card.img --scene mode=flat build/my-scene/model.obj":
        lambda r, tmp: None,
    "make flash-to-emulator CARD=build/my-card.img": _ran_frames("build/frames", 8),
}
#: Both write the same folder (build/frames as the README runs them), so they run one after the
#: other in one test.
FLASH_COMMANDS = {
    "make flash-to-emulator": _ran_frames("build/frames", 8),
    "make flash-to-emulator FRAMES=30": _ran_frames("build/frames", 30),
}


def test_every_command_is_known():
    found = [command for document in DOCUMENTS for command in readme_commands(document.read_text())]
    known = set(COMMANDS) | set(FLASH_COMMANDS) | set(OWN_FIRMWARE_COMMANDS) | set(WALKTHROUGH_COMMANDS)
    assert set(found) == known, (
        f"README commands without a check here: {sorted(set(found) - known)}; "
        f"checks of commands the README no longer shows: {sorted(known - set(found))}")


def _run_and_check(command: str, how: str, check, tmp: Path) -> None:
    if how == "ci":
        check(None, tmp)
        return
    result = run(_dry_run(command) if how == "dry-run" else as_run(command, tmp))
    assert result.returncode == 0, f"{command}: exit {result.returncode}\n{result.stderr[-2000:]}"
    check(result, tmp)


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_readme_command(command, firmware, card, request, tmp_path):
    if "build/cfw/" in command:
        request.getfixturevalue("c_firmware")     # the C programs exist before they are run
    _run_and_check(command, *COMMANDS[command], tmp_path)


def test_readme_flash_commands(firmware, card, tmp_path):
    for command, check in FLASH_COMMANDS.items():
        _run_and_check(command, "run", check, tmp_path)


def test_readme_own_firmware_commands(firmware, tmp_path):
    for command, check in OWN_FIRMWARE_COMMANDS.items():
        _run_and_check(command, "run", check, tmp_path)


def test_readme_walkthrough_commands(firmware, tmp_path):
    for command, check in WALKTHROUGH_COMMANDS.items():
        _run_and_check(command, "run", check, tmp_path)


def test_outputs_move_to_the_temporary_folder_and_prerequisites_stay(tmp_path):
    assert as_run("python -m emulator run build/cfw/hello.elf --until 0.05 --out build/hello", tmp_path) == \
        f"python -m emulator run build/cfw/hello.elf --until 0.05 --out {tmp_path}/hello"
    assert as_run("riscv64-unknown-elf-ld -o build/hello-asm.elf build/hello-asm.o", tmp_path) == \
        f"riscv64-unknown-elf-ld -o {tmp_path}/hello-asm.elf {tmp_path}/hello-asm.o"
    assert as_run("python -m reference render-card build/card.img --out build/reference", tmp_path) == \
        f"python -m reference render-card build/card.img --out {tmp_path}/reference"
    assert as_run("make flash-to-emulator FRAMES=30", tmp_path) == \
        f"make flash-to-emulator FRAMES=30 FRAMES_DIR={tmp_path}/frames"
    assert where("build/frames", tmp_path) == tmp_path / "frames"
    assert where("build/cfw", tmp_path) == ROOT / "build" / "cfw"
