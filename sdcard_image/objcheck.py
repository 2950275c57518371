"""Checking Wavefront .obj files before they go on the card.

The rules are the firmware's (firmware/obj.S), written once on the host in `reference.obj`,
which the reference renderer reads models with too: a model the card builder accepts is a model
the firmware accepts, and a refusal names the line the firmware would name, in its words
(`bad model line N: <what>`, its ERR_BAD_MODEL). The file is then copied unchanged.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

from reference.obj import ModelError, parse_obj

from .errors import BadInputError


@dataclass(frozen=True)
class ObjStats:
    """What a valid OBJ holds, counted as the firmware reports it (`model: ...`)."""

    vertices: int
    texcoords: int
    normals: int
    #: Triangles after polygons are fanned.
    triangles: int

    def summary(self) -> str:
        return (f"{self.triangles} triangles, {self.vertices} vertices, {self.texcoords} uv, "
                f"{self.normals} normals")


# Models that passed, by a digest of their bytes: a process that builds many cards from the same
# models (make bench, the test suite) parses each one once (a 5,000-triangle model takes a
# tenth of a second in Python). A refused model is parsed again, to name its line each time.
_PASSED: dict[bytes, ObjStats] = {}
_PASSED_KEPT = 64


def check_obj(data: bytes, path: Path | str = "<obj>") -> ObjStats:
    """Parses an OBJ by the firmware's rules; raises `BadInputError` (file, the firmware's line
    and words) on the first problem, as the firmware's ERR_BAD_MODEL would."""
    digest = hashlib.sha256(data).digest()
    stats = _PASSED.get(digest)
    if stats is not None:
        return stats
    try:
        mesh = parse_obj(data)
    except ModelError as exc:
        raise BadInputError(path, f"{exc.what} (firmware error {exc.firmware_error.code})", exc.line) \
            from None
    stats = ObjStats(vertices=len(mesh.vertices), texcoords=len(mesh.texcoords),
                     normals=len(mesh.normals), triangles=len(mesh.faces))
    if len(_PASSED) >= _PASSED_KEPT:
        _PASSED.pop(next(iter(_PASSED)))
    _PASSED[digest] = stats
    return stats
