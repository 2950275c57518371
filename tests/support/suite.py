"""What the tests share besides pytest's fixtures (those are in tests/conftest.py): the project's
paths, the board-model runs, and the folders and values made once for a whole pytest-xdist session.
Tests import it as `suite` (pyproject.toml puts tests/support on the import path)."""
from __future__ import annotations

import datetime
import fcntl
import os
import pickle
import shutil
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Callable, TypeVar

from emulator_runs import run_emulator  # noqa: F401  (re-exported for the tests)
from golden_scenes import GOLDEN  # noqa: F401  (re-exported for the tests)

ROOT = Path(__file__).resolve().parents[2]
FIRMWARE = ROOT / "build" / "firmware.elf"
CARD = ROOT / "build" / "card.img"
GOLDEN_FRAMES = 4   # frames of the default scene the shared run shows
T = TypeVar("T")
K = TypeVar("K")


def session_root(tmp_path_factory) -> Path:
    """The temporary folder of the whole session: under xdist each worker's folder, popen-gwN,
    lies in it. (The worker id alone does not say it: a pytest that a test starts inherits the
    PYTEST_XDIST_WORKER variable, but has a session and a folder of its own.)"""
    root = tmp_path_factory.getbasetemp()
    worker = os.environ.get("PYTEST_XDIST_WORKER")
    return root.parent if worker and root.name == f"popen-{worker}" else root


def shared_by_workers(tmp_path_factory, name: str, make: Callable[[Path], None]) -> Path:
    """A folder made once for the whole test session: `make` fills it, in the first pytest-xdist
    worker that asks; the others wait for it (a lock) and take it as it is. It lies beside the
    workers' own temporary folders (pytest removes it with them)."""
    root = session_root(tmp_path_factory)
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


# The test cards' volume ID and entry times: the same files make the same card, so that runs whose
# cycles depend on the card's bytes (a CRC's table lookups in the data cache) repeat exactly.
CARD_STAMP_VOLUME_ID = 0x4B323130       # "K210"
CARD_STAMP_TIME = datetime.datetime(2022, 1, 1)


def make_card(folder: Path, files: dict[str, bytes]) -> Path:
    """A card holding exactly these files (card path -> bytes), written without the card
    builder's checks, so that malformed files reach the firmware as they are; the same files
    make the same image (CARD_STAMP_*)."""
    from sdcard_image.fat32 import CardStamp, CardWriter
    folder.mkdir(parents=True, exist_ok=True)
    card = folder / "card.img"
    with CardWriter.create(card, 64, stamp=CardStamp(CARD_STAMP_VOLUME_ID, CARD_STAMP_TIME)) as writer:
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


def private_bench_history(monkeypatch, folder: Path) -> None:
    """A tool's record of its run (tools/bench_history.py) goes to a history and a page in `folder`,
    not the repository's docs (for the tests that run make coremark's and make thesis-firmware's tools)."""
    from tools import bench_history
    (folder / "page.md").write_text(f"{bench_history.BEGIN}\n{bench_history.END}\n")
    (folder / "README.md").write_text(f"{bench_history.CALIBRATION_BEGIN}\n{bench_history.CALIBRATION_END}\n")
    monkeypatch.setattr(bench_history, "HISTORY", folder / "history.jsonl")
    monkeypatch.setattr(bench_history, "PAGE", folder / "page.md")
    monkeypatch.setattr(bench_history, "README", folder / "README.md")
