"""Shared fixtures: the firmware is built once (by `make firmware`, which `make test` runs
first) and one board-model run of it is shared by every test that looks at its output.

Under pytest-xdist each worker has its own session; what is costly and the same for all of them
(the shared run, the generated assets) is made once, by the first worker that asks, in a folder
the workers share (`shared_by_workers`)."""
from __future__ import annotations

import fcntl
import json
import os
import pickle
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Callable, TypeVar

import pytest

from emulator_runs import run_emulator  # noqa: F401  (re-exported for the tests)
from golden_scenes import GOLDEN  # noqa: F401  (re-exported for the tests)

ROOT = Path(__file__).resolve().parent.parent
FIRMWARE = ROOT / "build" / "firmware.elf"
CARD = ROOT / "build" / "card.img"
GOLDEN_FRAMES = 4   # frames of the default scene the shared run shows
T = TypeVar("T")
K = TypeVar("K")




def _session_root(tmp_path_factory) -> Path:
    """The temporary folder of the whole session: under xdist each worker's folder, popen-gwN,
    lies in it. (The worker id alone does not say it: a pytest that a test starts inherits the
    PYTEST_XDIST_WORKER variable, but has a session and a folder of its own.)"""
    root = tmp_path_factory.getbasetemp()
    worker = os.environ.get("PYTEST_XDIST_WORKER")
    return root.parent if worker and root.name == f"popen-{worker}" else root


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
    folder = _session_root(tmp_path_factory) / "model-cache"
    os.environ[CACHE_ENVIRONMENT] = str(folder)
    return folder


def _make(tmp_path_factory, target: str) -> None:
    """`make -s target`, one worker at a time (two makes rebuilding the same files at once would
    write them over each other)."""
    with open(_session_root(tmp_path_factory) / "make.lock", "w") as lock:
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


def shared_by_workers(tmp_path_factory, name: str, make: Callable[[Path], None]) -> Path:
    """A folder made once for the whole test session: `make` fills it, in the first pytest-xdist
    worker that asks; the others wait for it (a lock) and take it as it is. It lies beside the
    workers' own temporary folders (pytest removes it with them)."""
    root = _session_root(tmp_path_factory)
    folder = root / f"shared-{name}"
    with open(root / f"shared-{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (folder / ".made").exists():
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            make(folder)
            (folder / ".made").touch()
    return folder


def shared_value(tmp_path_factory, name: str, compute: Callable[[Path], T]) -> T:
    """compute(folder), computed once for the whole test session (shared_by_workers) and handed
    to every worker that asks as it was returned (pickled beside what compute wrote in `folder`):
    for the module fixtures whose tests pytest-xdist may share out between its workers."""
    def make(folder: Path) -> None:
        (folder / "value.pickle").write_bytes(pickle.dumps(compute(folder)))
    folder = shared_by_workers(tmp_path_factory, name, make)
    return pickle.loads((folder / "value.pickle").read_bytes())


def run_together(jobs: dict[K, Callable[[], T]]) -> dict[K, T]:
    """Each job's result, the jobs run two at a time: they are board-model runs, each a process
    of its own that the test only waits for, so a fixture that makes several keeps both cores
    busy while the other xdist worker waits for it (shared_value)."""
    with ThreadPoolExecutor(max_workers=2) as pool:
        futures = {key: pool.submit(job) for key, job in jobs.items()}
        return {key: future.result() for key, future in futures.items()}


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


def make_card(folder: Path, files: dict[str, bytes]) -> Path:
    """A card holding exactly these files (card path -> bytes), written without the card
    builder's checks, so that malformed files reach the firmware as they are."""
    from sdcard_image.fat32 import CardWriter
    folder.mkdir(parents=True, exist_ok=True)
    card = folder / "card.img"
    with CardWriter.create(card, 64) as writer:
        for path, data in files.items():
            parent = path.rpartition("/")[0]
            if parent:
                writer.makedirs(parent)
            writer.write(path, data)
    return card


def copy_card(source: Path, target: Path) -> Path:
    """A copy of a card image that keeps its holes: only the parts holding data are copied
    (shutil.copyfile would write all 64 MiB of a card that holds a few). The copy reads back
    byte for byte as the source."""
    with open(source, "rb") as src, open(target, "wb") as dst:
        size = os.fstat(src.fileno()).st_size
        offset = 0
        while offset < size:
            try:
                start = os.lseek(src.fileno(), offset, os.SEEK_DATA)
            except OSError:             # ENXIO: nothing but a hole up to the end
                break
            end = os.lseek(src.fileno(), start, os.SEEK_HOLE)
            src.seek(start)
            dst.seek(start)
            dst.write(src.read(end - start))
            offset = end
        dst.truncate(size)
    return target


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
