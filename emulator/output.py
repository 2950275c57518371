"""What a run leaves in its output folder: frame_NNNN.png per frame, animation.png
(an animated PNG of all frames), console.log and run.json."""
from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
from PIL import Image

from .board import FrameRecord

ANIMATION_NAME = "animation.png"
FRAME_PATTERN = "frame_{:04d}.png"


class RunOutput:
    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        stale_files = list(self.folder.glob("frame_*.png")) + list(self.folder.glob("diff_*.png")) + \
            list(self.folder.glob("grab_*.png")) + [self.folder / ANIMATION_NAME]
        for stale in stale_files:
            stale.unlink(missing_ok=True)
        self.console_path = self.folder / "console.log"
        self._console = self.console_path.open("wb")
        self.frame_paths: list[Path] = []
        self.frame_times: list[float] = []
        self.grabs: list[dict] = []

    def console_byte(self, byte: int) -> None:
        self._console.write(bytes((byte,)))

    def frame(self, record: FrameRecord, image: np.ndarray) -> None:
        path = self.folder / FRAME_PATTERN.format(record.index)
        Image.fromarray(image, "RGB").save(path)
        self.frame_paths.append(path)
        self.frame_times.append(record.virtual_time_s)

    def grab(self, request, board) -> None:
        """Writes grab_<what>_<ms>ms.png for a --grab request (see grab.py)."""
        from .grab import grab
        name = f"grab_{request.what}_{request.at_s * 1e3:.3f}ms.png".replace("/", "_")
        try:
            image = grab(board, request)
        except Exception as error:   # a bad symbol or address is reported, the run goes on
            self.grabs.append({"request": request.label, "error": str(error)})
            return
        Image.fromarray(image, "RGB").save(self.folder / name)
        self.grabs.append({"request": request.label, "virtual_time_s": board.time, "file": name})

    def finish(self, summary: dict) -> None:
        self._console.close()
        if self.frame_paths:
            images = [Image.open(p) for p in self.frame_paths]
            gaps = np.diff([0.0] + self.frame_times) if len(self.frame_times) > 1 else [0.1]
            durations = [max(20, int(round(g * 1000))) for g in gaps]
            images[0].save(self.folder / ANIMATION_NAME, save_all=True, append_images=images[1:],
                           duration=durations, loop=0)
        (self.folder / "run.json").write_text(json.dumps(summary, indent=2) + "\n")


def summary_dict(exit_kind: str, message: str, frames: list[FrameRecord], virtual_time_s: float,
                 instructions: list[int], host_time_s: float, warnings: list[str], firmware: str,
                 device_writes: dict[str, list[int]], console_lines: list[tuple[float, str]]) -> dict:
    return {
        "exit": exit_kind,
        "message": message,
        "firmware": firmware,
        "virtual_time_s": virtual_time_s,
        "instructions": instructions,
        "host_time_s": host_time_s,
        "device_writes": device_writes,
        "console": [{"virtual_time_s": t, "line": line} for t, line in console_lines],
        "frames": [asdict(f) for f in frames],
        "warnings": warnings,
    }
