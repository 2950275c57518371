"""Shared fixtures: the firmware is built once (by `make firmware`, which `make test` runs
first) and one board-model run of it is shared by every test that looks at its output.

Under pytest-xdist each worker has its own session; what is costly and the same for all of them
(the shared run, the generated assets) is made once, by the first worker that asks, in a folder
the workers share (`shared_by_workers`). Those helpers, and everything else the tests share but
pytest's fixtures, are in tests/support (suite.py and the modules beside it)."""
from __future__ import annotations

import fcntl
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Callable

import pytest

from golden_scenes import GOLDEN
from suite import CARD, FIRMWARE, GOLDEN_FRAMES, ROOT, run_emulator, session_root, shared_by_workers, shared_value


@pytest.fixture(scope="session", autouse=True)
def build_outputs_untouched():
    """A test run leaves build/ as it found it, but for the prerequisites the Makefile builds
    there (build_outputs.py): the user's build/frames and other outputs are theirs (issue 32)."""
    from build_outputs import build_outputs, changed_outputs
    before = build_outputs()
    yield
    changed = changed_outputs(before)
    assert not changed, f"the tests wrote into build/, the user's outputs: {changed[:10]}"


@pytest.fixture(scope="session", autouse=True)
def model_cache(tmp_path_factory) -> Path:
    """The board model's cache of cycle tables (emulator/cpu/timing.py) for this session: shared by
    the workers and the commands the tests run, kept out of the user's own cache folder."""
    from emulator.cpu.timing import CACHE_ENVIRONMENT
    folder = session_root(tmp_path_factory) / "model-cache"
    os.environ[CACHE_ENVIRONMENT] = str(folder)
    return folder


def _make(tmp_path_factory, target: str) -> None:
    """`make -s target`, one worker at a time (two makes rebuilding the same files at once would
    write them over each other)."""
    with open(session_root(tmp_path_factory) / "make.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        subprocess.run(["make", "-s", target], cwd=ROOT, check=True)


@pytest.fixture(scope="session")
def firmware(tmp_path_factory) -> Path:
    _make(tmp_path_factory, "build/firmware.elf")
    return FIRMWARE


@pytest.fixture(scope="session")
def c_firmware(tmp_path_factory) -> Path:
    """The C test firmware (tests/firmware/), built by the Makefile's rule into build/cfw."""
    _make(tmp_path_factory, "c-firmware")
    return ROOT / "build" / "cfw"


@pytest.fixture(scope="session")
def card(tmp_path_factory) -> Path:
    """The default card `make flash-to-emulator` uses (generated models and textures)."""
    _make(tmp_path_factory, "build/card.img")
    return CARD


@pytest.fixture(scope="session")
def assets(tmp_path_factory) -> Path:
    """The generated models and textures (tools/make_assets.py), made once a session for the
    tests that build cards of their own from them: afresh, not build/assets, which could be older
    than the script. Read-only: a test writes its cards elsewhere."""
    def make(folder: Path) -> None:
        subprocess.run([sys.executable, str(ROOT / "tools" / "make_assets.py"), str(folder)], check=True)
    return shared_by_workers(tmp_path_factory, "assets", make)


@pytest.fixture(scope="session")
def firmware_run(firmware, card, tmp_path_factory):
    """One run of the firmware on the default card, as `make flash-to-emulator` runs it, shared
    by the end-to-end tests: GOLDEN_FRAMES frames, held against the default scene's golden frames
    (--golden only compares after the run: the run is the plain one; a mismatch is status 9).
    Returns (the command's result, its --out folder, run.json or None)."""
    def run(folder: Path):
        out = folder / "out"
        result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", str(GOLDEN_FRAMES),
                              "--out", str(out), "--quiet", "--golden", str(GOLDEN / "default"))
        summary = json.loads((out / "run.json").read_text()) if (out / "run.json").exists() else None
        return result, out, summary
    return shared_value(tmp_path_factory, "firmware_run", run)


@pytest.fixture(scope="session")
def golden_card(tmp_path_factory, assets) -> Callable[[str], Path]:
    """golden_card(name): the card of a golden scene (golden_scenes.scene_card), built once for the
    whole session (the end-to-end and the reference tests both read each one; boards open cards
    read-only)."""
    from golden_scenes import scene_card, scene_card_path

    def card(name: str) -> Path:
        folder = shared_by_workers(tmp_path_factory, f"golden-card-{name}",
                                   lambda folder: scene_card(name, folder, assets))
        return scene_card_path(name, folder)
    return card


@pytest.fixture(scope="session")
def assemble(tmp_path_factory):
    """Assembles and links a small RV64GC program for SRAM at 0x8000_0000; returns the ELF path."""
    folder = tmp_path_factory.mktemp("programs")
    cache: dict[str, Path] = {}

    def build(source: str) -> Path:
        if source in cache:
            return cache[source]
        name = f"prog{len(cache)}"
        (folder / f"{name}.S").write_text(source)
        subprocess.run(["riscv64-unknown-elf-as", "-march=rv64gc", "-mabi=lp64d", "-o", str(folder / f"{name}.o"),
                        str(folder / f"{name}.S")], check=True)
        subprocess.run(["riscv64-unknown-elf-ld", "-Ttext=0x80000000", "--no-relax", "-N", "-o",
                        str(folder / f"{name}.elf"), str(folder / f"{name}.o")], check=True)
        cache[source] = folder / f"{name}.elf"
        return cache[source]

    return build
