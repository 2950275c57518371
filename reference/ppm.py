"""PPM textures (P6 and P3), read as firmware/ppm.S reads them, converted to RGB565.

Header: the magic, then width, height and maxval as unsigned decimal numbers separated by
whitespace (space, tab, CR, LF, VT, FF); a comment runs from '#' to the next CR or LF and may
stand anywhere in the header. Width, height >= 1, maxval 1..65535, each below 2^31. P6: exactly one
whitespace character (or one comment with its line end) after maxval, then the raster, one byte a
sample when maxval < 256, else two (most significant first); bytes after it are ignored. P3:
decimal samples separated by whitespace (comments allowed). A sample above maxval is an error.

Each sample is scaled to its RGB565 field rounded to nearest exactly as the firmware does:
``field = (sample * field_max + maxval // 2) // maxval``. Row 0 is the top row of the file.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from k210_common.firmware_errors import FirmwareError, firmware_error

WHITESPACE = b" \t\r\n\x0b\x0c"
NUMBER_LIMIT = 2 ** 31


class TextureError(ValueError):
    """A bad texture (the firmware's ERR_BAD_TEXTURE, whose words start the message)."""

    def __init__(self, what: str):
        super().__init__(f"{self.firmware_error.words[0]}: {what}")
        self.what = what

    @property
    def firmware_error(self) -> FirmwareError:
        return firmware_error("BAD_TEXTURE")


def rgb565_from_samples(r, g, b, maxval: int):
    """RGB565 of samples 0..maxval (scalars or integer arrays), each field rounded to nearest."""
    r, g, b = (np.asarray(c, dtype=np.int64) for c in (r, g, b))
    half = maxval // 2
    r5 = (r * 31 + half) // maxval
    g6 = (g * 63 + half) // maxval
    b5 = (b * 31 + half) // maxval
    value = (r5 << 11) | (g6 << 5) | b5
    return int(value) if value.ndim == 0 else value.astype(np.uint16)


class _Reader:
    def __init__(self, data: bytes):
        self.data = data
        self.pos = 0

    def skip_space(self) -> None:
        data = self.data
        while self.pos < len(data):
            byte = data[self.pos:self.pos + 1]
            if byte in WHITESPACE:
                self.pos += 1
            elif byte == b"#":
                while self.pos < len(data) and data[self.pos:self.pos + 1] not in (b"\r", b"\n"):
                    self.pos += 1
            else:
                return

    def number(self, truncated: str, bad: str) -> int:
        """A decimal number after whitespace; it must end at whitespace, '#' or the end."""
        self.skip_space()
        start = self.pos
        while self.pos < len(self.data) and self.data[self.pos:self.pos + 1].isdigit():
            self.pos += 1
        if self.pos == start:
            if self.pos >= len(self.data):
                raise TextureError(truncated)
            raise TextureError(bad)
        if self.pos < len(self.data) and self.data[self.pos:self.pos + 1] not in WHITESPACE + b"#":
            raise TextureError(bad)
        return int(self.data[start:self.pos])


@dataclass(frozen=True)
class PpmHeader:
    """A PPM's header as the firmware reads it."""

    magic: str          # "P6" or "P3"
    width: int
    height: int
    maxval: int
    end: int            # offset just past maxval's last digit


def parse_header(data: bytes) -> PpmHeader:
    """The header (magic, width, height, maxval), checked as the firmware checks it."""
    if len(data) < 2:
        raise TextureError("truncated header" if data in (b"", b"P") else "not a PPM (magic is not P6 or P3)")
    magic = data[:2]
    if magic not in (b"P6", b"P3"):
        raise TextureError("not a PPM (magic is not P6 or P3)")
    reader = _Reader(data)
    reader.pos = 2
    header = "bad header (a width, height or maxval that is not a decimal number below 2^31)"
    if reader.pos < len(data) and data[2:3] not in WHITESPACE + b"#":
        raise TextureError(header)
    width = reader.number("truncated header", header)
    height = reader.number("truncated header", header)
    maxval = reader.number("truncated header", header)
    if magic == b"P6" and reader.pos >= len(data):
        raise TextureError("truncated header")      # ppm.S wants maxval's whitespace first
    if max(width, height, maxval) >= NUMBER_LIMIT:
        raise TextureError(header)
    if width == 0 or height == 0:
        raise TextureError("bad header (width or height 0)")
    if not 1 <= maxval <= 65535:
        raise TextureError("bad maxval (not 1..65535)")
    return PpmHeader(magic.decode("ascii"), width, height, maxval, reader.pos)


def parse_ppm(data: bytes) -> np.ndarray:
    """The texture as a (height, width) uint16 RGB565 array, row 0 at the top."""
    head = parse_header(data)
    magic, width, height, maxval = head.magic.encode("ascii"), head.width, head.height, head.maxval
    reader = _Reader(data)
    reader.pos = head.end
    count = width * height * 3
    if magic == b"P6":
        # exactly one whitespace character, or one comment with its line end
        if reader.pos >= len(data):
            raise TextureError("truncated header")
        if data[reader.pos:reader.pos + 1] == b"#":
            while reader.pos < len(data) and data[reader.pos:reader.pos + 1] not in (b"\r", b"\n"):
                reader.pos += 1
            if reader.pos >= len(data):
                raise TextureError("truncated header")      # a comment without its line end
        reader.pos += 1
        wide = maxval > 255
        raster = data[reader.pos:reader.pos + count * (2 if wide else 1)]
        if len(raster) < count * (2 if wide else 1):
            raise TextureError("truncated raster (fewer samples than width x height x 3)")
        samples = np.frombuffer(raster, dtype=">u2" if wide else np.uint8).astype(np.int64)
    else:
        samples = np.empty(count, dtype=np.int64)
        for i in range(count):
            reader.skip_space()
            if reader.pos >= len(data):
                raise TextureError("truncated raster (fewer samples than width x height x 3)")
            samples[i] = reader.number("truncated raster (fewer samples than width x height x 3)",
                                       "bad sample (not a decimal number)")
            if i % 3 == 2 and samples[i - 2:i + 1].max() > maxval:
                raise TextureError("sample above maxval")   # ppm.S checks each pixel as it reads it
    if samples.size and samples.max() > maxval:
        raise TextureError("sample above maxval")
    rgb = samples.reshape(height, width, 3)
    return rgb565_from_samples(rgb[..., 0], rgb[..., 1], rgb[..., 2], maxval).reshape(height, width)
