"""Exact comparison of rendered frames with golden PNGs (shared by the tests and the
regeneration script)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image


def load_rgb(path: Path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"))


def compare(actual_path: Path, golden_path: Path, diff_path: Path) -> int:
    """Number of pixels that differ; writes a diff image (differing pixels in magenta
    over a dimmed copy of the golden) when any do."""
    actual, golden = load_rgb(actual_path), load_rgb(golden_path)
    if actual.shape != golden.shape:
        return max(actual.size, golden.size) // 3
    differs = np.any(actual != golden, axis=2)
    count = int(differs.sum())
    if count:
        diff = (golden // 3).astype(np.uint8)
        diff[differs] = (255, 0, 255)
        Image.fromarray(diff).save(diff_path)
    return count
