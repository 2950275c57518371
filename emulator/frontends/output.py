"""What a run leaves in its output folder: frame_NNNN.png per frame, animation.png
(an animated PNG of all frames, written as they come: apng.py), console.log and run.json. Nothing
of a frame stays in memory once the next has come, however long the run."""
from __future__ import annotations

import json
import tempfile
from dataclasses import asdict
from pathlib import Path

import numpy as np
from PIL import Image

from ..board import FrameRecord
from ..errors import BadInput, write_failed
from ..vtime import Time, to_seconds
from .apng import ApngWriter

ANIMATION_NAME = "animation.png"
FRAME_PATTERN = "frame_{:04d}.png"
# zlib's fastest level for the frames and the animation: half the time of Pillow's default (6)
# for files about a third larger. Writing them is a good part of a short run's host time.
PNG_COMPRESS_LEVEL = 1
# Browsers show an APNG frame shorter than about 11 ms for 100 ms (Chromium; Firefox does
# the like), which would play a fast run ten times too slowly: frames shown for less than
# this are given this long in animation.png, and run.json says which.
MIN_ANIMATION_FRAME_MS = 20.0


def prepare_output_folder(folder: Path) -> None:
    """Creates the output folder if needed and checks that files can be written in it.
    Raises BadInput naming the folder and the reason."""
    if folder.exists() and not folder.is_dir():
        raise BadInput(f"--out {folder}: a file of that name exists; the output must be a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise BadInput(f"--out {folder}: cannot create the output folder ({error.strerror or error}"
                       f"{f': {error.filename}' if error.filename and str(error.filename) != str(folder) else ''})") \
            from None
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as error:
        raise BadInput(f"--out {folder}: cannot write in the output folder ({error.strerror or error})") from None


def animation_durations(frame_times: list[float]) -> tuple[list[float], list[int]]:
    """How long animation.png shows each frame, in ms, and the indices of the frames whose
    virtual time on screen was shorter than MIN_ANIMATION_FRAME_MS and was lengthened to it.
    A frame is on screen from its own virtual time until the next frame's; the last one for
    as long as the one before it (a single frame: a still, 0)."""
    if len(frame_times) < 2:
        return [0.0] * len(frame_times), []
    shown = [(later - earlier) * 1e3 for earlier, later in zip(frame_times, frame_times[1:])]
    shown.append(shown[-1])
    lengthened = [index for index, ms in enumerate(shown) if ms < MIN_ANIMATION_FRAME_MS]
    return [max(ms, MIN_ANIMATION_FRAME_MS) for ms in shown], lengthened


class RunOutput:
    def __init__(self, folder: str | Path) -> None:
        """The folder must exist and be writable (prepare_output_folder)."""
        self.folder = Path(folder)
        stale_files = list(self.folder.glob("frame_*.png")) + list(self.folder.glob("diff_*.png")) + \
            list(self.folder.glob("grab_*.png")) + [self.folder / ANIMATION_NAME, self.folder / (ANIMATION_NAME + ".frames")]
        for stale in stale_files:
            stale.unlink(missing_ok=True)
        self.console_path = self.folder / "console.log"
        self._console = self.console_path.open("wb", buffering=0)     # current while the run goes on (tail -f)
        self.frame_paths: list[Path] = []
        self._animation = ApngWriter(self.folder / ANIMATION_NAME, PNG_COMPRESS_LEVEL)
        self.frame_times: list[float] = []
        self.grabs: list[dict] = []
        self.animation: dict | None = None

    def console_byte(self, byte: int) -> None:
        try:
            self._console.write(bytes((byte,)))
        except OSError as error:
            raise write_failed(self.console_path, error) from None

    def frame(self, record: FrameRecord, image: np.ndarray) -> None:
        path = self.folder / FRAME_PATTERN.format(record.index)
        try:
            Image.fromarray(image, "RGB").save(path, compress_level=PNG_COMPRESS_LEVEL)
        except OSError as error:
            path.unlink(missing_ok=True)                 # no half-written frame is left
            raise write_failed(path, error) from None
        previous_ms = ((record.virtual_time_s - self.frame_times[-1]) * 1e3 if self.frame_times else None)
        try:
            self._animation.add(image, None if previous_ms is None else max(previous_ms, MIN_ANIMATION_FRAME_MS))
        except OSError as error:
            path.unlink(missing_ok=True)
            raise write_failed(self._animation.path, error) from None
        self.frame_paths.append(path)
        self.frame_times.append(record.virtual_time_s)

    def grab(self, request, board) -> None:
        """Writes grab_<what>_<ms>ms.png for a --grab request (see grab.py; the request was
        checked against the firmware before the run)."""
        from .grab import grab
        name = f"grab_{request.what}_{request.at_s * 1e3:.3f}ms.png".replace("/", "_")
        try:
            Image.fromarray(grab(board, request), "RGB").save(self.folder / name)
        except OSError as error:
            (self.folder / name).unlink(missing_ok=True)
            raise write_failed(self.folder / name, error) from None
        self.grabs.append({"request": request.label, "virtual_time_s": to_seconds(board.time), "file": name})

    def missed_grab(self, request, end_s: float) -> None:
        self.grabs.append({"request": request.label,
                           "error": f"not taken: the run ended at {end_s:.6f} s of virtual time, before it"})

    def finish(self, summary: dict) -> str | None:
        """Writes console.log's end, the animation and run.json; returns what could not be written
        (the run's output is kept as far as it goes), or None."""
        problems = []
        try:
            self._console.close()
        except OSError as error:
            problems.append(f"{self.console_path}: {error.strerror or error}")
        try:
            if self.frame_times:
                durations, lengthened = animation_durations(self.frame_times)
                self._animation.finish(durations[-1])
                if self._animation.count:
                    shown = self._animation.count      # fewer than the frames when a write failed
                    self.animation = {"file": ANIMATION_NAME, "frame_durations_ms": durations[:shown],
                                      "lengthened_to_ms": MIN_ANIMATION_FRAME_MS,
                                      "lengthened_frames": [i for i in lengthened if i < shown]}
            else:
                self._animation.discard()
        except OSError as error:
            problems.append(f"{self._animation.path}: {error.strerror or error}")
            self._animation.discard()
            (self.folder / ANIMATION_NAME).unlink(missing_ok=True)
        if problems:
            summary["output_failed"] = problems
            if summary.get("exit") == "ok":
                summary["exit"], summary["message"] = "write-failed", f"cannot write {'; '.join(problems)}"
        summary["animation"] = self.animation
        try:
            (self.folder / "run.json").write_text(json.dumps(summary, indent=2) + "\n")
        except OSError as error:
            problems.append(f"{self.folder / 'run.json'}: {error.strerror or error}")
        return "; ".join(problems) or None


def summary_dict(exit_kind: str, message: str, frames: list[FrameRecord], virtual_time_s: float,
                 instructions: list[int], host_time_s: float, warnings: list[str], firmware: str,
                 device_writes: dict[str, list[int]], console_lines: list[tuple[Time, str]]) -> dict:
    return {
        "exit": exit_kind,
        "message": message,
        "firmware": firmware,
        "virtual_time_s": virtual_time_s,
        "instructions": instructions,
        "host_time_s": host_time_s,
        "device_writes": device_writes,
        "console": [{"virtual_time_s": to_seconds(t), "line": line} for t, line in console_lines],
        "frames": [asdict(f) for f in frames],
        "warnings": warnings,
    }
