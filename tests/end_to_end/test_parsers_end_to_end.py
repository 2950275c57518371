"""The firmware's scene.ini, .obj and .ppm readers, driven through the board model: what they
accept lands in the `scene` structure exactly, and every malformed file ends in its own error
line naming what (and where) with its error screen, never a trap or a hang."""
from __future__ import annotations

import re
import struct
from pathlib import Path

import pytest

from suite import FIRMWARE, make_card, run_emulator
from emulator.board import Board
from k210_common.exit_status import EXIT_FIRMWARE_ERROR
from k210_common.firmware_errors import firmware_error

TRIANGLE = "v 0 0 -1\nv 1 0 -1\nv 0 1 -1\nf 1 2 3\n"
TEXTURE = b"P6\n1 1\n255\n\x10\x20\x30"
ERROR = re.compile(r"^error (\d+) (.*)$", re.M)

# scene structure offsets (firmware/include/scene.inc)
SCENE_MODE, SCENE_CULL, SCENE_SCALE, SCENE_AXIS, SCENE_ANGLE, SCENE_STEP = 0, 4, 8, 20, 32, 36
SCENE_TRANSLATE, SCENE_FOV, SCENE_NEAR, SCENE_FAR, SCENE_LIGHT, SCENE_AMBIENT, SCENE_BACKGROUND = \
    40, 52, 56, 60, 64, 76, 80
SCENE_INTERPOLATION, SCENE_SHADING, SCENE_LIGHT_LEVELS, SCENE_ANGLES, SCENE_DEPTH, SCENE_SNAP = \
    84, 88, 92, 96, 100, 104
SCENE_SIZE = 184
MESH_VCOUNT, MESH_TCOUNT, MESH_NCOUNT, MESH_FCOUNT = 108, 112, 116, 120
SCENE_FILTER = 124
SCENE_HARTS = 176
MESH_V, MESH_T, MESH_N, MESH_F, TEX_W, TEX_H, TEX_PIXELS = 128, 136, 144, 152, 160, 164, 168


def boot(folder: Path, files: dict[str, bytes]) -> Board:
    board = Board(str(FIRMWARE),
                  sd_image=str(make_card(folder, files)))
    board.run(1)
    board.close()
    return board


def scene_bytes(board: Board) -> bytes:
    address = next(a for a, name in board.image.symbols.items() if name == "scene")
    return board.memory.read(address, SCENE_SIZE)


def f32s(board: Board, raw: bytes, offset: int, count: int) -> list[float]:
    return list(struct.unpack_from(f"<{count}f", raw, offset))


def u32(raw: bytes, offset: int) -> int:
    return struct.unpack_from("<I", raw, offset)[0]


def array(board: Board, raw: bytes, pointer_offset: int, count: int, fmt: str) -> list:
    pointer = struct.unpack_from("<Q", raw, pointer_offset)[0]
    size = struct.calcsize(fmt)
    data = board.memory.read(pointer, size * count)
    return [struct.unpack_from(fmt, data, i * size) for i in range(count)]


INDEX_BITS = 21                    # scene.inc MESH_INDEX_BITS: a corner's v, vt, vn indices
NO_INDEX = (1 << INDEX_BITS) - 1   # MESH_NO_INDEX


def triangles(board: Board, raw: bytes, count: int) -> list[tuple[int, ...]]:
    """The triangle array as (v0, t0, n0, v1, t1, n1, v2, t2, n2), unpacked from its three
    doubleword corners (scene.inc MESH_F): v in the low 21 bits, then vt, then vn."""
    mask = (1 << INDEX_BITS) - 1
    return [tuple((corner >> shift) & mask for corner in packed for shift in (0, INDEX_BITS, 2 * INDEX_BITS))
            for packed in array(board, raw, MESH_F, count, "<3Q")]


def test_defaults_without_scene_ini(firmware, tmp_path):
    board = boot(tmp_path, {"/model.obj": TRIANGLE.encode(), "/texture.ppm": TEXTURE})
    lines = [line for _, line in board.console_lines]
    assert "scene: no scene.ini, defaults" in lines
    raw = scene_bytes(board)
    assert u32(raw, SCENE_MODE) == 0 and u32(raw, SCENE_CULL) == 1
    assert f32s(board, raw, SCENE_SCALE, 3) == [1, 1, 1] and f32s(board, raw, SCENE_AXIS, 3) == [0, 1, 0]
    assert f32s(board, raw, SCENE_TRANSLATE, 3) == [0, 0, -3]
    assert f32s(board, raw, SCENE_STEP, 1) == [4] and f32s(board, raw, SCENE_FOV, 1) == [60]
    assert u32(raw, TEX_W) == 1 and u32(raw, TEX_H) == 1
    # the precision settings: perspective, flat, 65 levels, polynomial, int16, subpixel
    assert [u32(raw, o) for o in (SCENE_INTERPOLATION, SCENE_SHADING, SCENE_ANGLES, SCENE_DEPTH, SCENE_SNAP)] \
        == [0, 0, 0, 1, 0]
    assert u32(raw, SCENE_FILTER) == 0                                # nearest
    assert f32s(board, raw, SCENE_LIGHT_LEVELS, 1) == [65]


def test_every_key_and_an_obj_using_every_feature(firmware, tmp_path):
    obj = ("# every feature\r\nmtllib x.mtl\r\no thing\r\ng group\r\ns 1\r\nusemtl m\r\n"
           "v 1 2 3\r\nv -1.5e0 +2.25 -3E-1\r\nv 0 0 -1 1.0\r\nv 4 5 6\r\nv 7 8 9\r\n"
           "vt 0.5 0.25\r\nvt 1 0 0\r\nvn 0 0 1\r\nvn 0 1 0\r\n\r\n"
           "f 1 2 3\r\nf -5/1 -4/2 -3/1 -2/2\r\nf 1//1 2//2 3//1 4//2 5//1\r\nf 1/1/1 2/2/2 3/1/1\r\n")
    scene = ("model = m/thing.obj\ntexture = t/tex.ppm\nmode = flat\ncull = off\nscale = 2\n"
             "axis = 0 0 5\nangle = -30\nstep = 2.5\ntranslate = 1 -1 -4\nfov = 45\nnear = 0.5\n"
             "far = 50\nlight = 0 3 4\nambient = 0.1\nbackground = #FF8000\n"
             "interpolation = Affine\nshading = gouraud\nlight_levels = 33\nangles = table\ndepth = float32\n"
             "snap = pixel\nfilter = MipMap\nharts = 2\n")
    board = boot(tmp_path, {"/scene.ini": scene.encode(), "/m/thing.obj": obj.encode(), "/t/tex.ppm": TEXTURE})
    raw = scene_bytes(board)
    assert u32(raw, SCENE_MODE) == 1 and u32(raw, SCENE_CULL) == 0
    assert f32s(board, raw, SCENE_SCALE, 3) == [2, 2, 2] and f32s(board, raw, SCENE_AXIS, 3) == [0, 0, 1]
    assert f32s(board, raw, SCENE_ANGLE, 2) == [-30, 2.5]
    assert f32s(board, raw, SCENE_TRANSLATE, 3) == [1, -1, -4]
    assert f32s(board, raw, SCENE_FOV, 3) == [45, 0.5, 50]
    assert f32s(board, raw, SCENE_LIGHT, 3) == pytest.approx([0, 0.6, 0.8])
    assert f32s(board, raw, SCENE_AMBIENT, 1) == pytest.approx([0.1])
    assert u32(raw, SCENE_BACKGROUND) == 0xFC00                       # #FF8000 in RGB565
    assert [u32(raw, o) for o in (SCENE_INTERPOLATION, SCENE_SHADING, SCENE_ANGLES, SCENE_DEPTH, SCENE_SNAP)] \
        == [1, 1, 1, 0, 1]
    assert u32(raw, SCENE_FILTER) == 2                                # mipmap
    assert u32(raw, SCENE_HARTS) == 2
    assert f32s(board, raw, SCENE_LIGHT_LEVELS, 1) == [33]
    assert [u32(raw, o) for o in (MESH_VCOUNT, MESH_TCOUNT, MESH_NCOUNT, MESH_FCOUNT)] == [5, 2, 2, 1 + 2 + 3 + 1]
    vertices = array(board, raw, MESH_V, 5, "<3f")
    assert vertices[1] == pytest.approx((-1.5, 2.25, -0.3)) and vertices[4] == (7, 8, 9)
    none = NO_INDEX
    faces = triangles(board, raw, 7)
    assert faces[0] == (0, none, none, 1, none, none, 2, none, none)
    # the quad with negative indices, fanned from its first corner: (1 2 3) (1 3 4)
    assert faces[1] == (0, 0, none, 1, 1, none, 2, 0, none) and faces[2] == (0, 0, none, 2, 0, none, 3, 1, none)
    # the pentagon: (1 2 3) (1 3 4) (1 4 5), normals only
    assert [f[0::3] for f in faces[3:6]] == [(0, 1, 2), (0, 2, 3), (0, 3, 4)]
    assert faces[5][2::3] == (0, 1, 0)
    assert faces[6] == (0, 0, 0, 1, 1, 1, 2, 0, 0)


def test_wireframe_reads_no_texture_and_stores_no_normals(firmware, tmp_path):
    obj = "v 0 0 -1\nv 1 0 -1\nv 0 1 -1\nvn 0 0 1\nf 1//1 2//1 3//1\n"
    board = boot(tmp_path, {"/scene.ini": b"mode = wireframe\n", "/model.obj": obj.encode()})
    lines = [line for _, line in board.console_lines]
    assert not any(line.startswith("load texture.ppm") for line in lines)   # none on the card either
    raw = scene_bytes(board)
    assert u32(raw, MESH_NCOUNT) == 0 and struct.unpack_from("<Q", raw, MESH_N)[0] == 0


@pytest.mark.parametrize("ppm, expected", [
    (b"P3\n# a comment\n2 1 # another\n65535\n0 0 0  65535 32768 65535\n", [0x0000, 0xFC1F | (32 << 5)]),
    (b"P6\n2 1\n1000\n" + bytes([0, 0, 0, 0, 0, 0, 0x03, 0xE8, 0, 0, 0, 0]), [0x0000, 0xF800]),
    (b"P6 1 1 255\n\xff\xff\xff", [0xFFFF]),
])
def test_textures_convert_to_rgb565(firmware, tmp_path, ppm, expected):
    board = boot(tmp_path, {"/model.obj": TRIANGLE.encode(), "/texture.ppm": ppm})
    raw = scene_bytes(board)
    pixels = array(board, raw, TEX_PIXELS, len(expected), "<H")
    assert [p[0] for p in pixels] == expected


# the firmware's error codes (firmware/include/errors.inc)
BAD_SCENE, BAD_MODEL, BAD_TEXTURE = (firmware_error(name).code for name in ("BAD_SCENE", "BAD_MODEL", "BAD_TEXTURE"))
BAD_FILES = {
    # name: (files, error code, words in the error line)
    "obj-index-out-of-range": ({"/model.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"}, BAD_MODEL, "line 4"),
    "obj-negative-index-before-start": ({"/model.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n"}, BAD_MODEL, "line 4"),
    "obj-index-zero": ({"/model.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"}, BAD_MODEL, "line 4"),
    "obj-face-with-two-vertices": ({"/model.obj": b"v 0 0 0\nv 1 0 0\nf 1 2\n"}, BAD_MODEL, "line 3"),
    "obj-malformed-number": ({"/model.obj": b"v 0 0 0\nv 1.2.3 0 0\n"}, BAD_MODEL, "line 2"),
    "obj-unknown-statement": ({"/model.obj": TRIANGLE.encode() + b"l 1 2\n"}, BAD_MODEL, "line 5"),
    "obj-no-faces": ({"/model.obj": b"v 0 0 0\n"}, BAD_MODEL, "no faces"),
    "ppm-truncated": ({"/texture.ppm": b"P6\n4 4\n255\n\x00\x00"}, BAD_TEXTURE, "truncated"),
    "ppm-bad-magic": ({"/texture.ppm": b"P5\n1 1\n255\n\x00"}, BAD_TEXTURE, "not a PPM"),
    "ppm-bad-maxval": ({"/texture.ppm": b"P3\n1 1\n70000\n1 2 3\n"}, BAD_TEXTURE, "maxval"),
    "ppm-sample-above-maxval": ({"/texture.ppm": b"P3\n1 1\n15\n1 2 16\n"}, BAD_TEXTURE, "above maxval"),
    "scene-unknown-key": ({"/scene.ini": b"mode = flat\nshiny = yes\n"}, BAD_SCENE, "line 2"),
    "scene-bad-mode": ({"/scene.ini": b"# modes\nmode = glossy\n"}, BAD_SCENE, "line 2"),
    "scene-vector-too-short": ({"/scene.ini": b"translate = 0 0\n"}, BAD_SCENE, "line 1"),
    "scene-zero-axis": ({"/scene.ini": b"axis = 0 0 0\n"}, BAD_SCENE, "line 1"),
    "scene-far-before-near": ({"/scene.ini": b"near = 5\nfar = 2\n"}, BAD_SCENE, "line 2"),
    "scene-bad-number": ({"/scene.ini": b"scale = 1e\n"}, BAD_SCENE, "line 1"),
    "scene-light-levels-fraction": ({"/scene.ini": b"light_levels = 3.5\n"}, BAD_SCENE, "line 1: bad value (must be a whole"),
    "scene-light-levels-too-many": ({"/scene.ini": b"\nlight_levels = 65538\n"}, BAD_SCENE, "line 2: bad value (must be a whole"),
    "scene-bad-depth": ({"/scene.ini": b"depth = 24\n"}, BAD_SCENE, "line 1: bad value (expected int16 or float32)"),
}


@pytest.mark.parametrize("name", BAD_FILES)
def test_bad_files_end_in_their_error(firmware, tmp_path, name):
    files, code, words = BAD_FILES[name]
    files = {"/model.obj": TRIANGLE.encode(), "/texture.ppm": TEXTURE, **files}
    card = make_card(tmp_path, files)
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "1", "--out", str(out), "--quiet")
    console = (out / "console.log").read_text()
    assert result.returncode == EXIT_FIRMWARE_ERROR, result.stderr + console     # a reported error: no trap, no hang
    errors = ERROR.findall(console)
    assert errors and int(errors[0][0]) == code and words in errors[0][1], console
    frames = sorted(out.glob("frame_*.png"))
    assert frames, "no error screen"


def _vertex_lines(count: int, seed: int) -> tuple[list[str], list[tuple[float, float, float]]]:
    """Vertex lines of varied lengths and number forms (signs, exponents, leading dots, CRLF,
    tabs, comments), every number with at most 15 significant digits and a decimal exponent
    within +-22, so that the firmware's value is the correctly rounded single of Python's float."""
    import numpy as np
    rng = np.random.default_rng(seed)
    lines, values = [], []
    forms = ["{:.6f}", "{:.3e}", "{:.12g}", "{:+.9f}", "{:.1E}"]
    for n in range(count):
        xyz = rng.normal(0, 10, 3) * 10.0 ** rng.integers(-6, 6, 3)
        text = [forms[(n + k) % len(forms)].format(value) for k, value in enumerate(xyz)]
        text = [t.replace("0.", ".", 1) if t.startswith("0.") and n % 3 == 0 else t for t in text]
        sep = "\t" if n % 4 == 1 else " " * (1 + n % 3)
        end = ["\n", "\r\n", " # c\n", "\t\n"][n % 4]
        lines.append("v" + sep + sep.join(text) + end)
        values.append(tuple(float(t) for t in text))
    return lines, values


def test_a_model_longer_than_the_window_from_a_fragmented_file(firmware, tmp_path):
    """obj.S reads the model from the card through a window of OBJ_WINDOW_BYTES (16 KiB), twice,
    and keeps no text: a 62 KB model in 7 fragments, whose tokens the window's edges cut wherever
    they fall, lands exactly as the text says (every vertex the correctly rounded single of its
    numbers), with its load line (size and CRC-32 of the whole file) and nothing of its text left
    in the heap (heap_next ends at the last block render_init took, as with a tiny model)."""
    import zlib

    import numpy as np

    from extremes_support import boot_allocations, heap_layout
    from sdcard_image.fat32 import CardWriter
    from sdcard_image.layouts import cluster_chain, is_fragmented, write_fragmented

    lines, values = _vertex_lines(1500, seed=15)
    faces = "f 1 2 3\nf -1 -2 -3\n"
    model = ("".join(lines) + faces).encode()
    assert 3 * 16384 < len(model) < 4 * 16384
    scene = b"model = m/model.obj\nmode = flat\n"
    card = tmp_path / "card.img"
    with CardWriter.create(card, 64) as writer:
        writer.makedirs("/m")
        write_fragmented(writer, "/m/model.obj", model, fragments=7)
        writer.write("/texture.ppm", TEXTURE)
        writer.write("/scene.ini", scene)
    assert is_fragmented(cluster_chain(card, "/m/model.obj"))
    board = Board(str(firmware), sd_image=str(card))
    board.run(1)
    board.close()
    console = [line for _, line in board.console_lines]
    assert f"load m/model.obj {len(model)} crc32={zlib.crc32(model):08x}" in console, console
    assert "model: 2 triangles, 1500 vertices, 0 uv, 0 normals (not stored: shading flat)" in console, console
    raw = scene_bytes(board)
    stored = np.array(array(board, raw, MESH_V, 1500, "<3f"), dtype=np.float32)
    assert np.array_equal(stored, np.array(values, dtype=np.float64).astype(np.float32))
    none = NO_INDEX
    assert triangles(board, raw, 2) == [(0, none, none, 1, none, none, 2, none, none),
                                                   (1499, none, none, 1498, none, none, 1497, none, none)]
    # the heap holds the arrays and render_init's blocks (a flat scene reads no texture): the
    # replay of tests/support/extremes_support.py, where the model's text takes no part
    expected = boot_allocations(heap_layout(firmware), None, 1500, 0, 0, 2, scene_ini=len(scene))[1]
    heap_next = next(a for a, name in board.image.symbols.items() if name == "heap_next")
    assert struct.unpack("<Q", board.memory.read(heap_next, 8))[0] == expected.next
