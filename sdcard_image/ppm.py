"""PPM (Netpbm colour image) checking and writing.

Textures go on the card as binary PPM (P6, maxval 255): the firmware can read them with a
tiny header parser and no decompression. PPM files given as input are only validated, by the
firmware's rules (firmware/ppm.S), written once on the host in `reference.ppm`, which the
reference renderer reads textures with too: the card builder refuses exactly the textures the
firmware refuses, in its words (`bad texture: <what>`, its ERR_BAD_TEXTURE).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from reference.ppm import TextureError, parse_header
from reference.ppm import parse_ppm as decode_ppm

from .errors import BadInputError


@dataclass(frozen=True)
class PpmInfo:
    """What a valid PPM holds."""

    magic: str
    width: int
    height: int
    maxval: int


def parse_ppm(data: bytes, path: Path | str = "<ppm>") -> PpmInfo:
    """Validates a P3 or P6 PPM as the firmware would (header, samples, length) and returns its
    header. Raises `BadInputError` naming the file and the firmware's words."""
    try:
        decode_ppm(data)
        header = parse_header(data)
    except TextureError as exc:
        raise BadInputError(path, f"{exc} (firmware error {exc.firmware_error.code})") from None
    return PpmInfo(magic=header.magic, width=header.width, height=header.height,
                   maxval=header.maxval)


def encode_p6(width: int, height: int, rgb: bytes) -> bytes:
    """A binary PPM (P6, maxval 255) of `width` x `height` from packed 8-bit RGB samples."""
    if len(rgb) != width * height * 3:
        raise ValueError(f"{width}x{height} RGB needs {width * height * 3} bytes, got {len(rgb)}")
    return f"P6\n{width} {height}\n255\n".encode("ascii") + rgb
