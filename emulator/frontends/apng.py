"""animation.png written frame by frame (the APNG extension of PNG: acTL, fcTL, fdAT), so that a run's
memory does not grow with its frames: each frame is compressed as it comes and its chunks go to a
side file in the output folder; a frame waits there only until the next one tells how long it is
shown. `finish` writes the file (signature, IHDR, acTL with the frame count, the frames, IEND) and
removes the side file. Every frame is a whole 8-bit RGB image (no deltas, no merging)."""
from __future__ import annotations

import struct
import zlib
from fractions import Fraction
from pathlib import Path

import numpy as np

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def delay(ms: float) -> tuple[int, int]:
    """A frame's delay as fcTL's 16-bit fraction of a second, exact where it can be."""
    fraction = Fraction(ms / 1000).limit_denominator(65535)
    if fraction.numerator > 65535:
        return 65535, 1
    return fraction.numerator, fraction.denominator


class ApngWriter:
    def __init__(self, path: Path, compress_level: int) -> None:
        self.path = path
        self._side = path.with_name(path.name + ".frames")
        self._frames = self._side.open("wb", buffering=0)    # a failed write fails at its frame
        self._level = compress_level
        self._size: tuple[int, int] | None = None
        self._pending: bytes | None = None          # the last frame's compressed scanlines
        self.count = 0
        self._sequence = 0

    def add(self, image: np.ndarray, shown_ms_of_previous: float | None) -> None:
        """Appends a (height, width, 3) uint8 frame; the previous frame (if any) was shown for
        shown_ms_of_previous."""
        height, width, _ = image.shape
        if self._size is None:
            self._size = (width, height)
        elif self._size != (width, height):
            raise ValueError(f"a {width}x{height} frame in a {self._size[0]}x{self._size[1]} animation")
        if self._pending is not None:
            self._write_pending(shown_ms_of_previous or 0.0)
        rows = np.concatenate([np.zeros((height, 1), np.uint8), image.reshape(height, width * 3)], axis=1)
        self._pending = zlib.compress(rows.tobytes(), self._level)     # filter type 0 on every row

    def _write_pending(self, ms: float) -> None:
        """Writes the held frame's control and data chunks as one piece: a write that fails
        leaves the side file as it was (cut back) and the frame dropped, never half a frame."""
        width, height = self._size
        numerator, denominator = delay(ms)
        control = struct.pack(">IIIIIHHBB", self._sequence, width, height, 0, 0, numerator, denominator, 0, 0)
        if self.count == 0:
            data = chunk(b"IDAT", self._pending)                         # the first frame is the image itself
        else:
            data = chunk(b"fdAT", struct.pack(">I", self._sequence + 1) + self._pending)
        piece = memoryview(chunk(b"fcTL", control) + data)
        self._pending = None
        start = self._frames.tell()
        try:
            while piece:
                written = self._frames.write(piece)
                piece = piece[written:]
        except OSError:
            self._frames.truncate(start)
            self._frames.seek(start)
            raise
        self._sequence += 1 if self.count == 0 else 2
        self.count += 1

    def finish(self, last_shown_ms: float) -> None:
        """Writes animation.png from the frames so far; the last one is shown for last_shown_ms."""
        if self._pending is not None:
            self._write_pending(last_shown_ms)
        self._frames.close()
        if self.count == 0:
            self._side.unlink()
            return
        width, height = self._size
        with self.path.open("wb") as out, self._side.open("rb") as frames:
            out.write(SIGNATURE)
            out.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
            out.write(chunk(b"acTL", struct.pack(">II", self.count, 0)))     # played for ever
            while block := frames.read(1 << 20):
                out.write(block)
            out.write(chunk(b"IEND", b""))
        self._side.unlink()

    def discard(self) -> None:
        """Drops the frames (none came, or the animation cannot be written)."""
        try:
            self._frames.close()
        except OSError:
            pass                          # what could not be written is dropped with the rest
        self._side.unlink(missing_ok=True)
