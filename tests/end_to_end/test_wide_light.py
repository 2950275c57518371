"""Light without steps (light_levels above 65: the wide fills, render.inc WIDE_*): a surface lit
at I draws each RGB565 channel c as round(c I), the exact value, whatever the fill (nearest,
bilinear, mipmap, anisotropic; flat, Gouraud or Phong; perspective or affine; either depth; edge antialiasing and
supersampling inside the triangles), where 65 levels draw round(c round(64 I) / 64).

Each case draws a grid of 64 quads, each showing the inside of one uniform 8 x 8 block of a
64 x 64 texture (so every filter's taps read one colour: the blend is that colour exactly), twice:
lit head-on (I = 1: the colours as they are) and at I = 0.618..., an intensity whose products with
0..63 lie at least 0.0066 from a rounding tie, so 16 bits of light round every channel exactly,
while 1/64 steps get 18 of the 64 values of a 6-bit channel wrong. Pixel by pixel the second
frame must be the first one's channels times I, rounded."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from suite import make_card, run_emulator

INTENSITY = 0.6180339887498949       # (sqrt 5 - 1) / 2
BLOCKS = 8                           # 8 x 8 blocks of 8 x 8 texels
BLOCK = 8


def _texture() -> bytes:
    """64 x 64 texels: block b = 8 row + column has G = b, R = b >> 1, B = 31 - (b >> 1), each
    channel's bits repeated into 8 (so that the card's RGB888 -> RGB565 keeps them)."""
    rows = bytearray()
    for y in range(BLOCKS * BLOCK):
        for x in range(BLOCKS * BLOCK):
            b = (y // BLOCK) * BLOCKS + x // BLOCK
            r5, g6, b5 = b >> 1, b, 31 - (b >> 1)
            rows += bytes(((r5 << 3) | (r5 >> 2), (g6 << 2) | (g6 >> 4), (b5 << 3) | (b5 >> 2)))
    return f"P6\n{BLOCKS * BLOCK} {BLOCKS * BLOCK}\n255\n".encode() + bytes(rows)


def _model() -> str:
    """The 64 quads in the z = 0 plane facing +z, each quad's UVs inside its block (2 .. 6 of 8
    texels: a bilinear tap never reaches the next block), every vn +z (Gouraud: constant I)."""
    lines, faces = ["vn 0 0 1"], []
    side, gap, size = 0.36, 0.04, 64.0
    start = -(BLOCKS * (side + gap) - gap) / 2
    for row in range(BLOCKS):
        for col in range(BLOCKS):
            x0, y0 = start + col * (side + gap), -start - row * (side + gap) - side
            u0, v0 = (col * BLOCK + 2) / size, 1 - (row * BLOCK + 6) / size
            u1, v1 = (col * BLOCK + 6) / size, 1 - (row * BLOCK + 2) / size
            n = len(faces) * 2
            lines += [f"v {x0:.6f} {y0:.6f} 0", f"v {x0 + side:.6f} {y0:.6f} 0",
                      f"v {x0 + side:.6f} {y0 + side:.6f} 0", f"v {x0:.6f} {y0 + side:.6f} 0",
                      f"vt {u0:.6f} {v0:.6f}", f"vt {u1:.6f} {v0:.6f}", f"vt {u1:.6f} {v1:.6f}",
                      f"vt {u0:.6f} {v1:.6f}"]
            base = n + 1
            faces.append(f"f {base}/{base}/1 {base + 1}/{base + 1}/1 {base + 2}/{base + 2}/1")
            faces.append(f"f {base}/{base}/1 {base + 2}/{base + 2}/1 {base + 3}/{base + 3}/1")
    return "\n".join(lines + faces) + "\n"


def _frame(firmware: Path, folder: Path, settings: dict[str, str], intensity: float) -> np.ndarray:
    """The frame as RGB565 channels (H, W, 3), the grid lit at `intensity` (light from +z turned
    about x, ambient 0)."""
    light = f"0 {math.sqrt(1 - intensity * intensity):.9f} {intensity:.9f}"
    scene = {"mode": "textured", "cull": "off", "step": "0", "translate": "0 0 -3.3", "ambient": "0",
             "light": light, **settings}
    ini = "".join(f"{key} = {value}\n" for key, value in scene.items())
    card = make_card(folder, {"/model.obj": _model().encode(), "/texture.ppm": _texture(),
                              "/scene.ini": ini.encode()})
    out = folder / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "1", "--out", str(out), "--quiet")
    assert result.returncode == 0, result.stderr
    rgb = np.asarray(Image.open(out / "frame_0000.png").convert("RGB")).astype(np.int64)
    return np.stack([rgb[..., 0] >> 3, rgb[..., 1] >> 2, rgb[..., 2] >> 3], axis=-1)


def _lit(channels: np.ndarray, intensity: float) -> np.ndarray:
    return np.floor(channels * intensity + 0.5).astype(np.int64)


def _inside(frame: np.ndarray) -> np.ndarray:
    """Pixels whose 3 x 3 neighbourhood is one colour (away from every quad's outline)."""
    same = np.ones(frame.shape[:2], dtype=bool)
    padded = np.pad(frame, ((1, 1), (1, 1), (0, 0)), mode="edge")
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            shifted = padded[dy:dy + frame.shape[0], dx:dx + frame.shape[1]]
            same &= (shifted == frame).all(axis=-1)
    return same


CASES = {
    "nearest-flat": {"filter": "nearest", "shading": "flat"},
    "nearest-gouraud-affine-float32": {"filter": "nearest", "shading": "gouraud", "interpolation": "affine",
                                       "depth": "float32"},
    "bilinear-flat-float32": {"filter": "bilinear", "shading": "flat", "depth": "float32"},
    "bilinear-gouraud-affine": {"filter": "bilinear", "shading": "gouraud", "interpolation": "affine"},
    "mipmap-gouraud": {"filter": "mipmap", "shading": "gouraud"},
    "edge-aa-gouraud": {"filter": "nearest", "shading": "gouraud", "antialias": "edge"},
    "edge-aa-bilinear": {"filter": "bilinear", "shading": "flat", "antialias": "edge"},
    "supersample-mipmap": {"filter": "mipmap", "shading": "flat", "antialias": "supersample"},
    # Phong (shading = phong): every vn +z, so the normal found at each pixel gives I itself
    "nearest-phong": {"filter": "nearest", "shading": "phong"},
    "bilinear-phong-affine-float32": {"filter": "bilinear", "shading": "phong", "interpolation": "affine",
                                      "depth": "float32"},
    "anisotropic-phong": {"filter": "anisotropic", "shading": "phong"},
    "edge-aa-mipmap-phong-float32": {"filter": "mipmap", "shading": "phong", "antialias": "edge",
                                     "depth": "float32"},
}


@pytest.mark.parametrize("case", CASES)
def test_wide_light_rounds_every_channel_exactly(firmware, tmp_path, case):
    settings = {**CASES[case], "light_levels": "65537"}
    unlit = _frame(firmware, tmp_path / "unlit", settings, 1.0)
    lit = _frame(firmware, tmp_path / "lit", settings, INTENSITY)
    drawn = (unlit != unlit[0, 0]).any(axis=-1)                     # (the corner: the clear colour)
    assert drawn.mean() > 0.4                                       # the grid fills much of the screen
    expected = _lit(unlit, INTENSITY)
    if "antialias" in settings:     # outlines blend the lit colour over the background: inside only
        where = _inside(unlit)
        assert where[drawn].mean() > 0.6
    else:
        where = np.ones(drawn.shape, dtype=bool)
    wrong = (lit != expected).any(axis=-1) & where & drawn
    assert not wrong.any(), f"{wrong.sum()} pixels off, first at {np.argwhere(wrong)[:3].tolist()}"
    # every 6-bit green value 0 .. 63 appears (the blocks), so every product is checked
    assert len(np.unique(unlit[..., 1][drawn & where])) == 64


@pytest.mark.parametrize("shading", ["flat", "phong"])
def test_65_levels_light_in_steps_of_1_64(firmware, tmp_path, shading):
    """The narrow fills, for comparison (and so that the test above can fail): k = round(64 I),
    each channel round(c k / 64), which differs from round(c I) on some blocks; Phong's narrow
    fills quantise the intensity they find at each pixel the same way."""
    settings = {"filter": "nearest", "shading": shading, "light_levels": "65"}
    unlit = _frame(firmware, tmp_path / "unlit", settings, 1.0)
    lit = _frame(firmware, tmp_path / "lit", settings, INTENSITY)
    k = round(64 * INTENSITY)
    drawn = (unlit != unlit[0, 0]).any(axis=-1)
    assert np.array_equal(lit[drawn], (unlit[drawn] * k + 32) >> 6)
    assert (lit[drawn] != _lit(unlit[drawn], INTENSITY)).any()
