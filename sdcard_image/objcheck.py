"""Checking Wavefront .obj files before they go on the card.

The firmware parses OBJ with a small assembly reader that trusts its input, so every problem
it could trip over is caught here, on the host, with the file name and line. The file is
then copied unchanged.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from .errors import BadInputError

# Plain decimal numbers only: Python's float() would also take "nan", "inf" and "1_0",
# which no OBJ reader (and not the firmware's) accepts.
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?\Z")
_INDEX = re.compile(r"[+-]?\d+\Z")

#: Statements accepted without comment (grouping, smoothing and materials do not change the
#: geometry the renderer draws).
_ACCEPTED = {"o", "g", "s", "mtllib", "usemtl"}
#: How many numbers each vertex statement takes.
_ARITY = {"v": (3, 4, 6, 7), "vt": (1, 2, 3), "vn": (3,)}


@dataclass
class ObjStats:
    """What a valid OBJ contains."""

    vertices: int = 0
    texcoords: int = 0
    normals: int = 0
    faces: int = 0
    #: Statements that are valid OBJ but ignored by the renderer (keyword -> first line).
    ignored: dict[str, int] = field(default_factory=dict)

    def summary(self) -> str:
        return (f"{self.vertices} vertices, {self.texcoords} texcoords, {self.normals} normals, "
                f"{self.faces} faces")


def _check_number(tok: str, path: Path | str, lineno: int, what: str) -> None:
    if not _NUMBER.match(tok):
        raise BadInputError(path, f"malformed number {tok!r} in {what}", lineno)


def _resolve(tok: str, count: int, kind: str, path: Path | str, lineno: int,
             forward: list[tuple[int, int, str]]) -> None:
    """Checks one index: positive indices count from 1, negative ones back from the latest
    element defined so far (that is the OBJ rule, so they are checked here, at their line)."""
    if not _INDEX.match(tok):
        raise BadInputError(path, f"malformed {kind} index {tok!r} in face", lineno)
    idx = int(tok)
    if idx == 0:
        raise BadInputError(path, f"{kind} index 0 in face (OBJ indices start at 1)", lineno)
    if idx < 0:
        if -idx > count:
            raise BadInputError(path, f"{kind} index {idx} out of range: only {count} "
                                      f"{kind}s defined before this line", lineno)
    elif idx > count:
        # A positive index may name an element defined further down; decide at the end.
        forward.append((idx, lineno, kind))


def check_obj(data: bytes, path: Path | str = "<obj>") -> ObjStats:
    """Parses an OBJ and raises `BadInputError` (file and line) on the first problem.

    Accepted: v/vt/vn/f with v, v/vt, v//vn and v/vt/vn corners, negative (relative) indices,
    o/g/s/mtllib/usemtl, comments and blank lines. Anything else, and a model without faces,
    is refused here as the firmware's parser refuses it (error 10), so a card never carries a
    model the board would stop on.
    """
    stats = ObjStats()
    forward: list[tuple[int, int, str]] = []
    text = data.decode("latin-1")  # never fails; names in comments may be in any encoding
    for lineno, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        keyword, *args = line.split()
        if keyword in _ARITY:
            arity = _ARITY[keyword]
            if len(args) not in arity:
                expected = " or ".join(str(n) for n in arity)
                raise BadInputError(path, f"'{keyword}' needs {expected} numbers, got "
                                          f"{len(args)}", lineno)
            for tok in args:
                _check_number(tok, path, lineno, f"'{keyword}'")
            if keyword == "v":
                stats.vertices += 1
            elif keyword == "vt":
                stats.texcoords += 1
            else:
                stats.normals += 1
        elif keyword == "f":
            if len(args) < 3:
                raise BadInputError(path, f"face with {len(args)} vertices (at least 3 needed)",
                                    lineno)
            for corner in args:
                parts = corner.split("/")
                if len(parts) > 3 or parts[0] == "" or (len(parts) == 3 and parts[1] == ""
                                                        and parts[2] == ""):
                    raise BadInputError(path, f"malformed face corner {corner!r} (expected v, "
                                              f"v/vt, v//vn or v/vt/vn)", lineno)
                _resolve(parts[0], stats.vertices, "vertex", path, lineno, forward)
                if len(parts) >= 2 and parts[1] != "":
                    _resolve(parts[1], stats.texcoords, "texcoord", path, lineno, forward)
                if len(parts) == 2 and parts[1] == "":
                    raise BadInputError(path, f"malformed face corner {corner!r} (empty "
                                              f"texcoord index)", lineno)
                if len(parts) == 3 and parts[2] != "":
                    _resolve(parts[2], stats.normals, "normal", path, lineno, forward)
                elif len(parts) == 3:
                    raise BadInputError(path, f"malformed face corner {corner!r} (empty normal "
                                              f"index)", lineno)
            stats.faces += 1
        elif keyword in _ACCEPTED:
            if keyword in ("mtllib", "usemtl") and not args:
                raise BadInputError(path, f"'{keyword}' needs a name", lineno)
        else:
            raise BadInputError(path, f"unknown statement '{keyword}' (the renderer reads v, vt, vn and f, "
                                      f"and accepts o, g, s, mtllib and usemtl)", lineno)
    if stats.faces == 0:
        raise BadInputError(path, "no faces: the model has nothing to draw")
    totals = {"vertex": stats.vertices, "texcoord": stats.texcoords, "normal": stats.normals}
    for idx, lineno, kind in forward:
        if idx > totals[kind]:
            raise BadInputError(path, f"{kind} index {idx} out of range: the file defines "
                                      f"{totals[kind]} {kind}s", lineno)
    return stats
