"""Wavefront .obj models, the subset firmware/obj.S reads (docs/guide/cards-and-scenes.md "Models and textures").

Statements (keywords case-sensitive): ``v x y z [w] [r g b]`` (3, 4, 6 or 7 numbers, x y z
kept), ``vt u [v [w]]`` (1 to 3 numbers, u v kept, v = 0 when absent), ``vn x y z``, and
``f c1 c2 c3 ...`` with corners ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn`` (forms may mix);
polygons are fanned into triangles (c1, ci, ci+1). ``o g s mtllib usemtl`` are ignored;
``#`` starts a comment anywhere; blank lines and CRLF are fine. Indices count from 1; -k is
the k-th latest element defined before the line; a positive index may point further down the
file (checked against the file's totals after every other check, as the firmware's second
pass does); 0 is an error. Errors raise `ModelError`: ``bad model line N: <what>``, or
``bad model: no faces``.

Numbers are read as parse.S reads them (`reference.numbers`: its double, not Python's float(),
which differs beyond 19 significant digits and at the edges of single precision) and kept as
float64 (the firmware rounds them to single precision; a number it keeps that is not finite in
single precision is an error in both, found after the count of numbers).
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from k210_common.firmware_errors import FirmwareError, firmware_error

from .numbers import finite_single, parse_number

CORNER = re.compile(r"(-?\d+)(?:/(-?\d+)?(?:/(-?\d+))?)?\Z")
IGNORED = {"o", "g", "s", "mtllib", "usemtl"}
NO_INDEX = -1


class ModelError(ValueError):
    """A bad model (the firmware's ERR_BAD_MODEL, whose words start the message)."""

    def __init__(self, line: int | None, what: str):
        words = self.firmware_error.words[0]
        super().__init__(f"{words} line {line}: {what}" if line is not None else f"{words}: {what}")
        self.line = line
        self.what = what

    @property
    def firmware_error(self) -> FirmwareError:
        return firmware_error("BAD_MODEL")


@dataclass
class Mesh:
    vertices: np.ndarray      # (V, 3) float64
    texcoords: np.ndarray     # (T, 2) float64: u, v
    normals: np.ndarray       # (N, 3) float64: vn, lighting faces whose three corners have one
    faces: np.ndarray         # (F, 3, 3) int64: per corner (v, vt, vn), 0-based, NO_INDEX = -1


def _number(line: int, token: str) -> float:
    value = parse_number(token)
    if value is None:
        raise ModelError(line, "malformed number")
    return value


NUMBERS_MAX = 7          # obj.S's OBJ_NUMBERS_MAX: the most numbers any vector statement takes


def _numbers(line: int, tokens: list[str], arity: str) -> list[float]:
    """A vector statement's numbers, read in order as obj.S reads them: a malformed token stops
    it, and so does any token after NUMBERS_MAX numbers (`arity`, whatever the token is)."""
    values = []
    for token in tokens:
        if len(values) == NUMBERS_MAX:
            raise ModelError(line, arity)
        values.append(_number(line, token))
    return values


def _in_range(line: int, values: list[float]) -> list[float]:
    """obj.S checks the count of a statement's numbers before their range, and the range only of
    the numbers it keeps (x y z of a v, u v of a vt)."""
    if not all(finite_single(value) for value in values):
        raise ModelError(line, "number out of range")
    return values


def _resolve(line: int, text: str, defined: int, kind: str) -> tuple[int, int | None]:
    """(0-based index, or the 1-based index to check against the file's total later)."""
    index = int(text)
    if index == 0:
        raise ModelError(line, "index 0 (indices start at 1)")
    if index < 0:
        if -index > defined:
            raise ModelError(line, f"{kind} index out of range")
        return defined + index, None
    return index - 1, index


CORNER_MALFORMED = "malformed face corner (expected v, v/vt, v//vn or v/vt/vn)"
INDEX = re.compile(r"[+-]?\d*")


def _corner_indices(line: int, corner: str):
    """The corner's (kind, index text or None) in obj.S's order: each index is checked (by the
    caller, through _resolve) as soon as it is read, before the rest of the corner."""
    pos = 0

    def index(kind: str):
        nonlocal pos
        text = INDEX.match(corner, pos).group()
        if not text.lstrip("+-"):
            raise ModelError(line, CORNER_MALFORMED)
        pos += len(text)
        return kind, text

    yield index("vertex")
    if pos < len(corner) and corner[pos] == "/":
        pos += 1
        if pos >= len(corner):
            raise ModelError(line, CORNER_MALFORMED)
        if corner[pos] == "/":
            yield "texture coordinate", None
            pos += 1
            yield index("normal")
        else:
            yield index("texture coordinate")
            if pos < len(corner) and corner[pos] == "/":
                pos += 1
                yield index("normal")
            else:
                yield "normal", None
    else:
        yield "texture coordinate", None
        yield "normal", None
    if pos < len(corner):
        raise ModelError(line, CORNER_MALFORMED)


def parse_obj(data: bytes | str) -> Mesh:
    text = data.decode("latin-1") if isinstance(data, bytes) else data
    vertices: list[tuple[float, float, float]] = []
    texcoords: list[tuple[float, float]] = []
    normals: list[tuple[float, float, float]] = []
    faces: list[list[tuple[int, int, int]]] = []
    forward: list[tuple[int, str, int]] = []      # (line, kind, 1-based index) checked at the end
    for number, raw in enumerate(text.split("\n"), start=1):
        if raw.endswith("\r"):           # CR LF ends a line; a CR before a comment does not
            raw = raw[:-1]
        raw = raw.split("#", 1)[0]
        tokens = raw.replace("\t", " ").split(" ")
        tokens = [t for t in tokens if t]
        if not tokens:
            continue
        keyword, args = tokens[0], tokens[1:]
        if keyword in IGNORED:
            continue
        if keyword == "v":
            values = _numbers(number, args, "v takes 3, 4, 6 or 7 numbers")
            if len(values) not in (3, 4, 6, 7):
                raise ModelError(number, "v takes 3, 4, 6 or 7 numbers")
            _in_range(number, values[:3])
            vertices.append((values[0], values[1], values[2]))
        elif keyword == "vt":
            values = _numbers(number, args, "vt takes 1, 2 or 3 numbers")
            if not 1 <= len(values) <= 3:
                raise ModelError(number, "vt takes 1, 2 or 3 numbers")
            _in_range(number, values[:2])
            texcoords.append((values[0], values[1] if len(values) > 1 else 0.0))
        elif keyword == "vn":
            values = _numbers(number, args, "vn takes 3 numbers")
            if len(values) != 3:
                raise ModelError(number, "vn takes 3 numbers")
            _in_range(number, values)
            normals.append((values[0], values[1], values[2]))
        elif keyword == "f":
            corners = []
            for arg in args:
                corner = []
                for kind, text_index in _corner_indices(number, arg):
                    if text_index is None:
                        corner.append(NO_INDEX)
                        continue
                    defined = {"vertex": len(vertices), "texture coordinate": len(texcoords),
                               "normal": len(normals)}[kind]
                    index, later = _resolve(number, text_index, defined, kind)
                    if later is not None:
                        forward.append((number, kind, later))
                    corner.append(index)
                corners.append(tuple(corner))
            if len(corners) < 3:
                raise ModelError(number, "face with fewer than 3 vertices")
            for i in range(1, len(corners) - 1):
                faces.append([corners[0], corners[i], corners[i + 1]])
        else:
            raise ModelError(number, "unknown statement")
    totals = {"vertex": len(vertices), "texture coordinate": len(texcoords), "normal": len(normals)}
    for line, kind, index in forward:
        if index > totals[kind]:
            raise ModelError(line, f"{kind} index out of range")
    if not faces:
        raise ModelError(None, "no faces")
    return Mesh(np.array(vertices, dtype=np.float64).reshape(-1, 3),
                np.array(texcoords, dtype=np.float64).reshape(-1, 2),
                np.array(normals, dtype=np.float64).reshape(-1, 3),
                np.array(faces, dtype=np.int64).reshape(-1, 3, 3))
