"""PPM (Netpbm colour image) checking and writing.

Textures go on the card as binary PPM (P6, maxval 255): the firmware can read them with a
tiny header parser and no decompression. PPM files given as input are only validated.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from .errors import BadInputError

_WHITESPACE = b" \t\n\r\v\f"
_TOKEN = re.compile(rb"\S+")


@dataclass(frozen=True)
class PpmInfo:
    """What a valid PPM holds."""

    magic: str
    width: int
    height: int
    maxval: int
    #: Byte offset of the first sample (P6) or of the sample text (P3).
    data_offset: int


def _line_of(data: bytes, offset: int) -> int:
    return data.count(b"\n", 0, offset) + 1


def _header_tokens(data: bytes, path: Path | str, count: int) -> tuple[list[int], int]:
    """Reads `count` unsigned decimal tokens after the magic; comments run from '#' to the end
    of the line. Returns the values and the offset just past the last token."""
    values: list[int] = []
    pos = 2
    while len(values) < count:
        while pos < len(data) and (data[pos] in _WHITESPACE or data[pos] == ord("#")):
            if data[pos] == ord("#"):
                end = data.find(b"\n", pos)
                pos = len(data) if end < 0 else end
            else:
                pos += 1
        if pos >= len(data):
            names = ("width", "height", "maxval")[len(values)]
            raise BadInputError(path, f"truncated PPM header: {names} missing",
                                _line_of(data, pos))
        start = pos
        while pos < len(data) and data[pos] not in _WHITESPACE and data[pos] != ord("#"):
            pos += 1
        token = data[start:pos]
        if not token.isdigit():
            what = ("width", "height", "maxval")[len(values)]
            raise BadInputError(path, f"PPM header: {what} is {token[:20]!r}, not a number",
                                _line_of(data, start))
        values.append(int(token))
    return values, pos


def parse_ppm(data: bytes, path: Path | str = "<ppm>") -> PpmInfo:
    """Validates a P3 or P6 PPM (header, sample range, length) and returns its header.

    Raises `BadInputError` naming the file and the line of the problem.
    """
    magic = data[:2]
    if magic not in (b"P3", b"P6"):
        kind = {b"P1": "a PBM (P1)", b"P4": "a PBM (P4)", b"P2": "a PGM (P2)",
                b"P5": "a PGM (P5)", b"P7": "a PAM (P7)"}.get(magic)
        detail = f"it is {kind}, not a colour PPM" if kind else f"starts with {magic!r}"
        raise BadInputError(path, f"not a PPM (expected P3 or P6): {detail}", 1)
    (width, height, maxval), pos = _header_tokens(data, path, 3)
    line = _line_of(data, pos)
    if width == 0 or height == 0:
        raise BadInputError(path, f"PPM size is {width}x{height}: must not be empty", line)
    if not 1 <= maxval <= 65535:
        raise BadInputError(path, f"PPM maxval {maxval} is outside 1..65535", line)
    if pos >= len(data) or data[pos] not in _WHITESPACE:
        raise BadInputError(path, "PPM header does not end with a whitespace character", line)
    pos += 1  # exactly one whitespace byte separates the header from binary samples
    samples = width * height * 3
    if magic == b"P6":
        need = samples * (1 if maxval < 256 else 2)
        have = len(data) - pos
        if have < need:
            raise BadInputError(path, f"truncated P6 data: {width}x{height} at maxval {maxval} "
                                      f"needs {need} bytes after the header, file has {have}",
                                _line_of(data, len(data)))
        if maxval not in (255, 65535):
            # Sample bytes above maxval are invalid; 255/65535 can never be exceeded.
            body = data[pos:pos + need]
            if maxval < 256:
                over = max(body)
                if over > maxval:
                    raise BadInputError(path, f"P6 sample {over} exceeds maxval {maxval}", line)
    else:
        count = 0
        for match in _TOKEN.finditer(data, pos):
            tok = match.group()
            if not tok.isdigit():
                what = ("comments are only allowed in the PPM header" if tok.startswith(b"#")
                        else f"P3 sample {tok[:20]!r} is not a number")
                raise BadInputError(path, what, _line_of(data, match.start()))
            if int(tok) > maxval:
                raise BadInputError(path, f"P3 sample {int(tok)} exceeds maxval {maxval}",
                                    _line_of(data, match.start()))
            count += 1
            if count == samples:
                break
        if count < samples:
            raise BadInputError(path, f"truncated P3 data: {width}x{height} needs {samples} "
                                      f"samples, file has {count}", _line_of(data, len(data)))
    return PpmInfo(magic=magic.decode(), width=width, height=height, maxval=maxval,
                   data_offset=pos)


def encode_p6(width: int, height: int, rgb: bytes) -> bytes:
    """A binary PPM (P6, maxval 255) of `width` x `height` from packed 8-bit RGB samples."""
    if len(rgb) != width * height * 3:
        raise ValueError(f"{width}x{height} RGB needs {width * height * 3} bytes, got {len(rgb)}")
    return f"P6\n{width} {height}\n255\n".encode("ascii") + rgb
