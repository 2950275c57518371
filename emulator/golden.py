"""Golden-frame checks: each frame a run showed against a reference PNG of the same index.

A pixel matches when no channel differs by more than the tolerance (0: exactly). For every
frame that does not match, a diff image is written (differing pixels in magenta over a dimmed
copy of the golden frame) and the count, the largest channel error and the bounding box of the
differences are reported, so a golden-frame check is one line in anyone's CI.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from PIL import Image

DIFF_COLOUR = (255, 0, 255)


@dataclass
class FrameComparison:
    index: int
    golden: str
    matches: bool
    differing_pixels: int
    max_channel_error: int
    bounding_box: tuple[int, int, int, int] | None   # x0, y0, x1, y1 (inclusive) of the differences
    diff_image: str | None
    problem: str | None = None                       # e.g. no golden frame, or sizes differ

    def describe(self) -> str:
        if self.matches:
            return f"frame {self.index}: matches {self.golden}"
        if self.problem:
            return f"frame {self.index}: {self.problem}"
        x0, y0, x1, y1 = self.bounding_box
        return (f"frame {self.index}: {self.differing_pixels} pixels differ from {self.golden} "
                f"(largest channel error {self.max_channel_error}, within x {x0}..{x1}, y {y0}..{y1}; "
                f"{x1 - x0 + 1}x{y1 - y0 + 1}); diff image {self.diff_image}")

    def as_dict(self) -> dict:
        return asdict(self)


def load_rgb(path: Path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"))


def compare_frame(index: int, actual_path: Path, golden_path: Path, diff_path: Path,
                  tolerance: int = 0) -> FrameComparison:
    """Compares one frame; writes `diff_path` when they differ."""
    if not golden_path.exists():
        return FrameComparison(index, str(golden_path), False, 0, 0, None, None, f"no golden frame {golden_path}")
    actual, golden = load_rgb(actual_path), load_rgb(golden_path)
    if actual.shape != golden.shape:
        return FrameComparison(index, str(golden_path), False, actual.shape[0] * actual.shape[1], 255, None, None,
                               f"size {actual.shape[1]}x{actual.shape[0]} differs from the golden "
                               f"{golden.shape[1]}x{golden.shape[0]}")
    error = np.abs(actual.astype(np.int16) - golden.astype(np.int16)).max(axis=2)
    differs = error > tolerance
    count = int(differs.sum())
    if count == 0:
        return FrameComparison(index, str(golden_path), True, 0, int(error.max()), None, None)
    ys, xs = np.nonzero(differs)
    diff = (golden // 3).astype(np.uint8)
    diff[differs] = DIFF_COLOUR
    Image.fromarray(diff).save(diff_path)
    return FrameComparison(index, str(golden_path), False, count, int(error.max()),
                           (int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max())), str(diff_path))


def compare_run(frame_paths: list[Path], golden_dir: Path, out_dir: Path, tolerance: int = 0) -> list[FrameComparison]:
    """Compares every frame of a run with golden_dir/frame_NNNN.png of the same index."""
    results = []
    for index, path in enumerate(frame_paths):
        results.append(compare_frame(index, path, golden_dir / path.name, out_dir / f"diff_{index:04d}.png",
                                     tolerance))
    return results
