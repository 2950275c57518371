"""One set of input rules: the card builder's checks (sdcard_image, through the reference's
readers) and the firmware's readers accept and refuse the same files, at the same line. Each
input is checked on the host and booted on the board model as it is (written onto a card behind
the card builder's back); the inputs are those issue 14 found passing the card builder while
the firmware refused them, and their accepted neighbours."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from suite import FIRMWARE, make_card
from emulator.board import Board
from emulator.errors import FirmwareReportedError
from k210_common.firmware_errors import firmware_error
from sdcard_image import BadInputError
from sdcard_image.convert import check_scene_ini
from sdcard_image.objcheck import check_obj
from sdcard_image.ppm import parse_ppm

TRIANGLE = b"v 0 0 -1\nv 1 0 -1\nv 0 1 -1\nf 1 2 3\n"
TEXTURE = b"P6\n1 1\n255\n\x10\x20\x30"
ERROR = re.compile(r"^error (\d+) (.*)$")
LINE = re.compile(r"line (\d+)")
# the firmware's error codes (firmware/include/errors.inc)
BAD_SCENE, BAD_MODEL, BAD_TEXTURE = (firmware_error(name).code for name in ("BAD_SCENE", "BAD_MODEL", "BAD_TEXTURE"))

# (what, file name on the card, its bytes, the firmware's error code or None to accept)
CASES = [
    ("obj beyond double precision", "model.obj", b"v 1e400 0 -1\nv 1 0 -1\nv 0 1 -1\nf 1 2 3\n", BAD_MODEL),
    ("obj beyond single precision", "model.obj", b"v 0 0 -1\nv 3.5e38 0 -1\nv 0 1 -1\nf 1 2 3\n", BAD_MODEL),
    ("obj largest single", "model.obj", b"v 0 0 -1\nv 3.4e38 0 -1\nv 0 1 -1\nf 1 2 3\n", None),
    # float() rounds it to the largest single, parse.S (which the firmware reads with) beyond it
    ("obj 19 digits beyond single precision", "model.obj",
     b"v 0 0 -1\nv 3.402823567797336323e38 0 -1\nv 0 1 -1\nf 1 2 3\n", BAD_MODEL),
    ("obj CR line ends", "model.obj", TRIANGLE.replace(b"\n", b"\r"), BAD_MODEL),
    ("obj CR CR LF line ends", "model.obj", TRIANGLE.replace(b"\n", b"\r\r\n"), BAD_MODEL),
    ("obj CR LF line ends", "model.obj", TRIANGLE.replace(b"\n", b"\r\n"), None),
    ("ppm two-byte sample above maxval", "texture.ppm",
     b"P6\n1 1\n1000\n\x03\xe8\x03\xe9\x00\x00", BAD_TEXTURE),
    ("ppm two-byte sample at maxval", "texture.ppm", b"P6\n1 1\n1000\n\x03\xe8\x03\xe8\x00\x00", None),
    ("ppm magic run into the width", "texture.ppm", b"P68 8 255\n" + bytes(192), BAD_TEXTURE),
    ("scene fov beyond 180", "scene.ini", b"mode = textured\nfov = 200\n", BAD_SCENE),
    ("scene unknown mode", "scene.ini", b"mode = textures\n", BAD_SCENE),
    ("scene unknown key", "scene.ini", b"cull = off\nspeed = 3\n", BAD_SCENE),
    ("scene 19 digits beyond single precision", "scene.ini", b"scale = 3.402823567797336323e38\n", BAD_SCENE),
    ("scene fine", "scene.ini", b"mode = flat\nfov = 179.5\n", None),
]


def host_verdict(name: str, data: bytes) -> tuple[int | None, int | None]:
    """(the firmware error code the host check predicts, or None; its line)."""
    check, code = {"model.obj": (check_obj, BAD_MODEL), "texture.ppm": (parse_ppm, BAD_TEXTURE),
                   "scene.ini": (check_scene_ini, BAD_SCENE)}[name]
    try:
        check(data, name)
    except BadInputError as exc:
        return code, exc.line
    return None, None


def firmware_verdict(folder: Path, name: str, data: bytes) -> tuple[int | None, int | None]:
    files = {"/model.obj": TRIANGLE, "/texture.ppm": TEXTURE, f"/{name}": data}
    board = Board(str(FIRMWARE),
                  sd_image=str(make_card(folder, files)))
    try:
        board.run(1)
    except FirmwareReportedError:      # the run stops at the error report; its line says which
        pass
    finally:
        board.close()
    for _, line in board.console_lines:
        match = ERROR.match(line)
        if match:
            number = LINE.search(match.group(2))
            return int(match.group(1)), int(number.group(1)) if number else None
    assert len(board.frames) == 1, board.console_lines
    return None, None


@pytest.mark.parametrize("what,name,data,expected", CASES, ids=[c[0] for c in CASES])
def test_host_and_firmware_agree(what, name, data, expected, firmware, tmp_path):
    host = host_verdict(name, data)
    assert host[0] == expected, f"host: {host}"
    assert firmware_verdict(tmp_path, name, data) == host
