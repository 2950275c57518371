"""Golden-frame checks: each frame a run showed against a reference PNG of the same index.

A pixel matches when no channel differs by more than the tolerance (0: exactly). For every
frame that does not match, a diff image is written (differing pixels in magenta over a dimmed
copy of the golden frame) and the count, the largest channel error and the bounding box of the
differences are reported, so a golden-frame check is one line in anyone's CI.
"""
from __future__ import annotations

import zlib
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from ..errors import BadInput

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
                f"{x1 - x0 + 1}x{y1 - y0 + 1}); "
                + (f"diff image {self.diff_image}" if self.diff_image else "its diff image could not be written"))

    def as_dict(self) -> dict:
        return asdict(self)


FRAME_NAME = "frame_{:04d}.png"
# What Pillow raises for a file it cannot read as an image, besides OSError (which includes
# UnidentifiedImageError and "image file is truncated"): a broken PNG chunk, bad zlib data,
# a picture too large to decode safely.
IMAGE_ERRORS = (OSError, SyntaxError, ValueError, EOFError, zlib.error, Image.DecompressionBombError)


def load_rgb(path: Path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"))


def load_golden_frames(folder: Path, count: int) -> dict[int, np.ndarray]:
    """Before a run: the golden frames DIR/frame_NNNN.png for frames 0 .. count-1 that exist,
    decoded. A missing one is left for the comparison to report as a mismatch; one that is
    there but cannot be read as a PNG raises BadInput naming it (a run would be wasted)."""
    if not folder.is_dir():
        raise BadInput(f"--golden {folder}: {'not a folder' if folder.exists() else 'no such folder'}")
    frames: dict[int, np.ndarray] = {}
    for index in range(count):
        path = folder / FRAME_NAME.format(index)
        if not path.exists():
            continue
        try:
            with Image.open(path) as image:
                if image.format != "PNG":
                    raise BadInput(f"--golden: {path} is a {image.format} image, not a PNG")
                frames[index] = np.asarray(image.convert("RGB"))
        except UnidentifiedImageError:
            raise BadInput(f"--golden: {path} is not a PNG image (nor any image Pillow reads)") from None
        except IMAGE_ERRORS as error:
            reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
            raise BadInput(f"--golden: {path} cannot be read as a PNG image ({reason})") from None
    return frames


def compare_frame(index: int, actual_path: Path, golden_path: Path, diff_path: Path,
                  tolerance: int = 0, golden: np.ndarray | None = None) -> FrameComparison:
    """Compares one frame; writes `diff_path` when they differ. `golden`: the golden frame
    already decoded (load_golden_frames), else it is read from golden_path."""
    if golden is None and not golden_path.exists():
        return FrameComparison(index, str(golden_path), False, 0, 0, None, None, f"no golden frame {golden_path}")
    actual = load_rgb(actual_path)
    if golden is None:
        try:
            golden = load_rgb(golden_path)
        except IMAGE_ERRORS as error:
            return FrameComparison(index, str(golden_path), False, 0, 0, None, None,
                                   f"golden frame {golden_path} cannot be read as a PNG image ({error})")
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
    try:
        Image.fromarray(diff).save(diff_path)
    except OSError:
        diff_path.unlink(missing_ok=True)       # the comparison stands; only its picture is missing
        return FrameComparison(index, str(golden_path), False, count, int(error.max()),
                               (int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max())), None)
    return FrameComparison(index, str(golden_path), False, count, int(error.max()),
                           (int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max())), str(diff_path))


def compare_run(frame_paths: list[Path], golden_dir: Path, out_dir: Path, tolerance: int = 0,
                goldens: dict[int, np.ndarray] | None = None) -> list[FrameComparison]:
    """Compares every frame of a run with golden_dir/frame_NNNN.png of the same index, taken
    from `goldens` (load_golden_frames) when it holds that index, else read now."""
    goldens = goldens or {}
    return [compare_frame(index, path, golden_dir / FRAME_NAME.format(index), out_dir / f"diff_{index:04d}.png",
                          tolerance, goldens.get(index))
            for index, path in enumerate(frame_paths)]
