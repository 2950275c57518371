"""Framebuffer grabs: a picture of a buffer at a chosen virtual time of a run, whether or
not a frame is complete then: the LCD's GRAM, or an RGB565 buffer in SRAM named by a
firmware symbol or an address."""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..board.memory import SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE

if TYPE_CHECKING:
    from ..board import Board

GRAB_SYNTAX = re.compile(r"^(?P<what>[^@]+)@(?P<at>[0-9.eE+-]+)(?P<options>(:[A-Za-z0-9x]+)*)$")
DEFAULT_WIDTH, DEFAULT_HEIGHT = 320, 240


@dataclass(frozen=True)
class GrabRequest:
    what: str            # "gram", a symbol, or a 0x address
    at_s: float
    width: int = DEFAULT_WIDTH
    height: int = DEFAULT_HEIGHT
    pairs: bool = False  # pixels stored in swapped pairs (first pixel in the upper half of a word)

    @property
    def label(self) -> str:
        return f"{self.what}@{self.at_s:g}"


def parse_grab(text: str) -> GrabRequest:
    """Parses WHAT@SECONDS[:pairs][:WxH]; raises ValueError with what is wrong."""
    match = GRAB_SYNTAX.match(text)
    if not match:
        raise ValueError(f"{text!r}: expected WHAT@SECONDS[:pairs][:WxH], e.g. gram@0.5 or framebuffers@0.5:pairs")
    try:
        at_s = float(match.group("at"))
    except ValueError:
        raise ValueError(f"{text!r}: {match.group('at')!r} is not a number of seconds") from None
    if not math.isfinite(at_s) or at_s < 0:
        raise ValueError(f"{text!r}: the time must be a finite number of seconds, 0 or more")
    width, height, pairs = DEFAULT_WIDTH, DEFAULT_HEIGHT, False
    for option in filter(None, match.group("options").split(":")):
        if option == "pairs":
            pairs = True
        elif re.fullmatch(r"\d+x\d+", option):
            width, height = map(int, option.split("x"))
            if width < 1 or height < 1:
                raise ValueError(f"{text!r}: a size must be at least 1x1")
        else:
            raise ValueError(f"{text!r}: unknown option {option!r} (pairs, or a size like 320x240)")
    what = match.group("what")
    if what == "gram" and (pairs or (width, height) != (DEFAULT_WIDTH, DEFAULT_HEIGHT)):
        raise ValueError(f"{text!r}: gram takes no options")
    if pairs and width % 2:
        raise ValueError(f"{text!r}: :pairs needs an even width (pixels come in pairs), not {width}")
    if what.lower().startswith("0x"):
        try:
            int(what, 16)
        except ValueError:
            raise ValueError(f"{text!r}: {what!r} is not a hexadecimal address") from None
    return GrabRequest(what, at_s, width, height, pairs)


def check_grab_buffer(request: GrabRequest, symbol_values: dict[str, int]) -> None:
    """Before a run: the buffer a request names must be a symbol of the firmware (or an
    address) and lie in SRAM whole. Raises ValueError with what is wrong."""
    if request.what == "gram":
        return
    try:
        address = buffer_address(symbol_values, request.what)
    except ValueError as error:
        raise ValueError(f"{request.label}: {error}") from None
    length = request.width * request.height * 2
    if not any(base <= address and address + length <= base + SRAM_SIZE for base in (SRAM_BASE, SRAM_UNCACHED_BASE)):
        raise ValueError(f"{request.label}: a {request.width}x{request.height} RGB565 buffer at 0x{address:x} "
                         f"(..0x{address + length - 1:x}) does not lie in SRAM "
                         f"(0x{SRAM_BASE:x}..0x{SRAM_BASE + SRAM_SIZE - 1:x}, or its uncached alias at "
                         f"0x{SRAM_UNCACHED_BASE:x})")


def gram_image(board: "Board") -> np.ndarray:
    """The LCD's GRAM as the Dock shows it upright (regardless of sleep, display or inversion)."""
    upright = np.asarray(board.lcd.gram)[::-1, :].T
    image = np.empty(upright.shape + (3,), dtype=np.uint8)
    for channel, shift in enumerate((12, 6, 0)):
        six = ((upright >> shift) & 0x3F).astype(np.uint8)
        image[:, :, channel] = (six << 2) | (six >> 4)
    return image


def buffer_address(symbol_values: dict[str, int], what: str) -> int:
    """The address WHAT names: a 0x number, or the value of a firmware symbol."""
    if what.lower().startswith("0x"):
        return int(what, 16)
    if what not in symbol_values:
        raise ValueError(f"no symbol {what!r} in the firmware")
    return symbol_values[what]


def rgb565_image(raw: bytes, width: int, height: int, pairs: bool) -> np.ndarray:
    pixels = np.frombuffer(raw, dtype="<u2").reshape(height, width)
    if pairs:
        pixels = pixels.reshape(height, width // 2, 2)[:, :, ::-1].reshape(height, width)
    # widened as the ST7789V widens 16-bit colour into its 6-bit GRAM and the panel shows it,
    # so a grab of a framebuffer compares exactly with the frames the LCD captured
    r5, g6, b5 = (pixels >> 11) & 31, (pixels >> 5) & 63, pixels & 31
    image = np.empty((height, width, 3), dtype=np.uint8)
    for channel, six in enumerate(((r5 << 1) | (r5 >> 4), g6, (b5 << 1) | (b5 >> 4))):
        image[..., channel] = ((six << 2) | (six >> 4)).astype(np.uint8)
    return image


def grab(board: "Board", request: GrabRequest) -> np.ndarray:
    """The requested buffer as an RGB image, read now."""
    if request.what == "gram":
        return gram_image(board)
    address = buffer_address(board.image.symbol_values, request.what)
    raw = board.memory.read(address, request.width * request.height * 2)
    return rgb565_image(raw, request.width, request.height, request.pairs)
