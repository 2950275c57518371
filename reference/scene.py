"""scene.ini, read as the firmware reads it (firmware/scene.S, docs/reference/scene-keys.md).

One `key = value` per line; `#` starts a comment except as the first character of a value
(`background = #203040`); blank lines, CRLF and a UTF-8 byte-order mark are fine; keys and the
words of `mode`, `cull` and the precision keys ignore case. An unknown or repeated key, a malformed line or a bad
value raises `SceneError` naming the line (counted from 1), with the firmware's wording:
``bad scene.ini line N: <what>``.

Numbers are read as parse.S reads them (`reference.numbers`: its double, not Python's float(),
which differs beyond 19 significant digits and at the edges of single precision). Unlike the
firmware (which keeps single precision), they are kept as float64 (parse.S's doubles: the values
written in the file to a few units in the last place of double precision) and the reference
renders with them. Range checks follow the firmware, on the value it stores (a
number must be finite in single precision, fov in (0, 180), near and far > 0, far > near,
ambient in [0, 1], axis and light not zero, then normalised).

The precision keys (`interpolation`, `shading`, `light_levels`, `angles`, `depth`, `snap`) select
the firmware's approximations. They are read and checked here exactly as the firmware reads them
and kept on the `Scene`, but the reference ignores them: it renders one ideal image per scene,
the yardstick every setting is measured against.

`filter` (`nearest`, `bilinear`, `mipmap`) is not a precision key: it chooses how the texture is
sampled, so the reference's pixel-centre image follows it (reference/render.py) and the firmware
can be checked against it; the ideal image ignores it (it area-filters every texture).

`harts` (`auto`, `1`, `2`) says which of the K210's harts draw (firmware/main.S); the frames are the
same whichever do, so the reference reads and checks it and ignores it.

`antialias` (`off`, `edge`, `supersample`) chooses how the firmware approaches the ideal image at edges
(firmware/raster.S); the pixel-centre image samples pixel centres whatever it says and the ideal
image is the ideal whatever it says, so the reference reads and checks it and ignores it.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from k210_common.firmware_errors import FirmwareError, firmware_error

from .numbers import finite_single, parse_number, single
from .ppm import rgb565_from_samples

MODES = {"textured": 0, "flat": 1, "wireframe": 2}
CULL_WORDS = {"on": True, "off": False, "yes": True, "no": False, "true": True, "false": False,
              "1": True, "0": False}
# The precision keys taking one word: key -> the words allowed, the default first.
PRECISION_WORDS: dict[str, tuple[str, ...]] = {
    "interpolation": ("perspective", "affine"),
    "shading": ("flat", "gouraud", "phong"),
    "angles": ("polynomial", "table"),
    "depth": ("int16", "float32"),
    "snap": ("subpixel", "pixel"),
}
# Texture filtering (firmware/raster.S), the default first.
FILTER_WORDS: tuple[str, ...] = ("nearest", "bilinear", "mipmap", "anisotropic")
# Which harts draw (firmware/main.S), the default first: changes how fast, never what is drawn.
HARTS_WORDS: tuple[str, ...] = ("auto", "1", "2")
# Antialiasing (firmware/raster.S), the default first: the reference renders the same images whatever it is.
ANTIALIAS_WORDS: tuple[str, ...] = ("off", "edge", "supersample")
# The keys taking one word that are not precision keys -> the words allowed, the default first.
OTHER_WORDS: dict[str, tuple[str, ...]] = {"filter": FILTER_WORDS, "harts": HARTS_WORDS,
                                           "antialias": ANTIALIAS_WORDS}
# 2 .. 65 levels light in 1/64 steps, more in 1/65536 (the firmware's wide fills, render.inc)
LIGHT_LEVELS_MIN, LIGHT_LEVELS_MAX = 2, 65537
LIGHT_LEVELS_DEFAULT = 65
KEYS = ("model", "texture", "mode", "cull", "scale", "axis", "angle", "step", "translate",
        "fov", "near", "far", "light", "ambient", "background",
        "interpolation", "shading", "light_levels", "angles", "depth", "snap", "filter", "harts",
        "antialias")
VALUE_MAX = 256          # a path of this many bytes or more is too long (NUL included)


class SceneError(ValueError):
    """A bad scene.ini line (the firmware's ERR_BAD_SCENE, whose words start the message)."""

    def __init__(self, line: int, what: str):
        super().__init__(f"{self.firmware_error.words[0]} line {line}: {what}")
        self.line = line
        self.what = what

    @property
    def firmware_error(self) -> FirmwareError:
        return firmware_error("BAD_SCENE")


@dataclass
class Scene:
    model: str = "model.obj"
    texture: str = "texture.ppm"
    mode: str = "textured"                       # textured | flat | wireframe
    cull: bool = True
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    axis: tuple[float, float, float] = (0.0, 1.0, 0.0)       # unit
    angle: float = 0.0                           # degrees at frame 0
    step: float = 4.0                            # degrees per frame
    translate: tuple[float, float, float] = (0.0, 0.0, -3.0)
    fov: float = 60.0                            # vertical, degrees
    near: float = 0.1
    far: float = 100.0
    light: tuple[float, float, float] = (0.0, 0.0, 1.0)      # unit, towards the light
    ambient: float = 0.2
    background: int = 0x10A2                     # RGB565 (RGB 16, 20, 16)
    # precision keys: what the firmware approximates (the reference ignores them)
    interpolation: str = "perspective"           # perspective | affine
    shading: str = "flat"                        # flat | gouraud | phong
    light_levels: int = LIGHT_LEVELS_DEFAULT     # 2 .. 65537
    angles: str = "polynomial"                   # polynomial | table
    depth: str = "int16"                         # int16 | float32
    snap: str = "subpixel"                       # subpixel | pixel
    # how textures are sampled (the pixel-centre image follows it)
    filter: str = "nearest"                      # nearest | bilinear | mipmap
    # which harts draw (how fast only: the reference ignores it)
    harts: str = "auto"                          # auto | 1 | 2
    # how edges are antialiased (the reference ignores it: its images are the yardsticks)
    antialias: str = "off"                       # off | edge | supersample
    lines: dict[str, int] = field(default_factory=dict, repr=False)   # key -> line that set it


def _tokens(value: str) -> list[str]:
    """The value's words, separated by spaces and tabs only, as scene.S separates them (str.split
    would also split at the other bytes Unicode calls whitespace, such as 0x85 read as latin-1)."""
    return [token for token in value.replace("\t", " ").split(" ") if token]


def _numbers(line: int, value: str, most: int, too_many: str) -> list[float]:
    """The value's numbers, read in order as scene.S reads them: a token that is not a number
    stops it ("not a number"), and so does a token after the `most` numbers the key takes
    (`too_many`, whatever that token is)."""
    numbers = []
    for token in _tokens(value):
        if len(numbers) == most:
            raise SceneError(line, too_many)
        number = parse_number(token)
        if number is None:
            raise SceneError(line, "bad value (not a number)")
        numbers.append(number)
    return numbers


def _finite_single(line: int, numbers: list[float]) -> None:
    """Every number must stay finite when rounded to single precision (as the firmware stores it)."""
    for number in numbers:
        if not finite_single(number):
            raise SceneError(line, "bad value (number out of range)")


def _count(line: int, key: str, numbers: list[float], count: int, broadcast: bool = False) -> list[float]:
    if len(numbers) == count:
        return numbers
    if broadcast and len(numbers) == 1:
        return numbers * count
    if broadcast:
        raise SceneError(line, "bad value (expected 1 or 3 numbers)")
    raise SceneError(line, "bad value (expected 1 number)" if count == 1 else "bad value (expected 3 numbers)")


def _direction(line: int, numbers: list[float]) -> tuple[float, float, float]:
    length = math.sqrt(sum(c * c for c in numbers))
    if length == 0.0:
        raise SceneError(line, "bad value (zero vector)")
    return tuple(c / length for c in numbers)  # type: ignore[return-value]


def _colour(line: int, value: str) -> int:
    bad = "bad value (expected R G B with 0..255 each, or #RRGGBB)"
    if value.startswith("#"):
        if not re.fullmatch(r"#[0-9A-Fa-f]{6}", value):
            raise SceneError(line, bad)
        rgb = [int(value[i:i + 2], 16) for i in (1, 3, 5)]
    else:
        numbers = []
        for token in _tokens(value):
            number = parse_number(token)
            if number is None:
                raise SceneError(line, bad)
            numbers.append(number)
        # range first: int() of 1e400 (infinity) would raise
        if len(numbers) != 3 or any(not 0 <= n <= 255 or n != int(n) for n in numbers):
            raise SceneError(line, bad)
        rgb = [int(n) for n in numbers]
    return rgb565_from_samples(*rgb, maxval=255)


def _expected_words(words: tuple[str, ...]) -> str:
    """The error for a word that is not one of `words`: "bad value (expected a, b or c)"."""
    listed = words[0] if len(words) == 1 else ", ".join(words[:-1]) + " or " + words[-1]
    return f"bad value (expected {listed})"


def _light_levels(line: int, value: str) -> int:
    """light_levels: one number (parse.S's grammar), finite in single precision, whose single-
    precision value is a whole number from LIGHT_LEVELS_MIN to LIGHT_LEVELS_MAX (the firmware
    keeps the number in single precision, so it is checked as such: 6.5e1 is 65)."""
    numbers = _count(line, "light_levels", _numbers(line, value, 1, "bad value (expected 1 number)"), 1)
    _finite_single(line, numbers)
    level = single(numbers[0])
    if level != math.floor(level) or not LIGHT_LEVELS_MIN <= level <= LIGHT_LEVELS_MAX:
        raise SceneError(line, f"bad value (must be a whole number from {LIGHT_LEVELS_MIN} to {LIGHT_LEVELS_MAX})")
    return int(level)


def _split_line(raw: str, line: int) -> tuple[str, str] | None:
    """(key, value) of one line, None for a blank or comment-only line (scene.S's scan)."""
    scan = "key"          # key -> value_start (after the first '=') -> value
    end = len(raw)
    for i, ch in enumerate(raw):
        if ch == "#":
            if scan == "value_start":
                scan = "value"          # '#' opening the value is kept
                continue
            end = i
            break
        if ch == "\t" or ch == " ":
            continue
        if ord(ch) < 0x20 or ord(ch) == 0x7F:
            raise SceneError(line, "malformed line (control character)")
        if ch == "=" and scan == "key":
            scan = "value_start"
        elif scan != "key":
            scan = "value"
    text = raw[:end].strip(" \t")
    if not text:
        return None
    if "=" not in text:
        raise SceneError(line, "malformed line (no '=')")
    key, value = text.split("=", 1)
    key, value = key.strip(" \t"), value.strip(" \t")
    if not key:
        raise SceneError(line, "malformed line (no key)")
    return key, value


def parse_scene(text: str | bytes | None) -> Scene:
    """The scene of a scene.ini text (None: no scene.ini, every default)."""
    scene = Scene()
    if text is None:
        return scene
    if isinstance(text, bytes):
        text = text.decode("latin-1")
    if text.startswith("\ufeff"):
        text = text[1:]
    elif text.startswith("\xef\xbb\xbf"):
        text = text[3:]
    for number, raw in enumerate(text.split("\n"), start=1):
        if raw.endswith("\r"):
            raw = raw[:-1]
        split = _split_line(raw, number)
        if split is None:
            continue
        key, value = split
        key = key.lower()
        if key not in KEYS:
            raise SceneError(number, "unknown key")
        if key in scene.lines:
            raise SceneError(number, "duplicate key")
        scene.lines[key] = number
        if not value:
            raise SceneError(number, "malformed line (no value)")
        _set(scene, key, value, number)
    near_line = scene.lines.get("near", 0)
    if not np.float32(scene.far) > np.float32(scene.near):       # as stored: singles
        raise SceneError(scene.lines.get("far", near_line), "bad value (far must be greater than near)")
    return scene


def _set(scene: Scene, key: str, value: str, line: int) -> None:
    if key in ("model", "texture"):
        if len(value.encode("latin-1")) >= VALUE_MAX:
            raise SceneError(line, "malformed line (value too long)")
        setattr(scene, key, value)
    elif key == "mode":
        if value.lower() not in MODES:
            raise SceneError(line, "bad value (expected textured, flat or wireframe)")
        scene.mode = value.lower()
    elif key == "cull":
        if value.lower() not in CULL_WORDS:
            raise SceneError(line, "bad value (expected on, off, yes, no, true, false, 1 or 0)")
        scene.cull = CULL_WORDS[value.lower()]
    elif key in PRECISION_WORDS or key in OTHER_WORDS:
        words = OTHER_WORDS[key] if key in OTHER_WORDS else PRECISION_WORDS[key]
        if value.lower() not in words:
            raise SceneError(line, _expected_words(words))
        setattr(scene, key, value.lower())
    elif key == "light_levels":
        scene.light_levels = _light_levels(line, value)
    elif key == "background":
        scene.background = _colour(line, value)
    else:
        most = 3 if key in ("scale", "axis", "light", "translate") else 1
        too_many = ("bad value (expected 1 or 3 numbers)" if key == "scale" else
                    "bad value (expected 3 numbers)" if most == 3 else "bad value (expected 1 number)")
        numbers = _numbers(line, value, most, too_many)
        if key == "scale":
            numbers = _count(line, key, numbers, 3, broadcast=True)
        elif key in ("axis", "light", "translate"):
            numbers = _count(line, key, numbers, 3)
        else:
            numbers = _count(line, key, numbers, 1)
        _finite_single(line, numbers)
        if key in ("axis", "light"):
            setattr(scene, key, _direction(line, numbers))
            return
        first = numbers[0]
        stored = single(first)                   # scene.S checks the value it stores, a single
        if key == "fov" and not 0.0 < stored < 180.0:
            raise SceneError(line, "bad value (fov must be between 0 and 180 degrees)")
        if key in ("near", "far") and not stored > 0.0:
            raise SceneError(line, "bad value (must be greater than 0)")
        if key == "ambient" and not 0.0 <= stored <= 1.0:
            raise SceneError(line, "bad value (must be between 0 and 1)")
        setattr(scene, key, tuple(numbers) if len(numbers) == 3 else first)
