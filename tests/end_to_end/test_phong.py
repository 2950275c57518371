"""shading = phong: the corners' normals interpolated perspective-correctly and lit at every pixel,
I = max(ambient, N . L / |N|), as the reference renderer lights (reference/render.py Lighting).

A quad turned 50 degrees away from the camera (so 1/w varies across it, and screen-linear
interpolation of the normals would be visibly off), whose four corner normals lean different
ways, is drawn with light in 1/65536 steps and compared, pixel by pixel inside its outline, with
the reference's float64 image: Phong is the reference to within a step of a channel, where
Gouraud (the intensity interpolated, not the normal) is several steps off. The same holds where
the near plane cuts the quad (the normals interpolated along the cut, render_clip.S). A model
without normals looks as with flat shading, bit for bit. test_wide_light.py checks that every
Phong fill applies the intensity it finds exactly."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import reference
from suite import make_card, run_emulator

# A 2 x 2 quad in z = 0 whose corner normals lean out and apart (unnormalised: their lengths differ,
# which the normalisation per pixel drops)
QUAD = """v -1 -1 0
v 1 -1 0
v 1 1 0
v -1 1 0
vn -0.6 -0.3 1
vn 0.9 -0.6 1.2
vn 0.5 0.7 0.8
vn -0.4 0.8 1
f 1//1 2//2 3//3
f 1//1 3//3 4//4
"""
TURNED = {"axis": "0 1 0", "angle": "50", "step": "0", "cull": "off", "ambient": "0.05",
          "light": "0.3 0.2 1", "mode": "flat", "light_levels": "65537", "depth": "float32"}
PLACES = {
    "in-front": {"translate": "0 0 -3"},
    # near the camera, turned further: the near plane (0.1) cuts the quad's far side off
    "cut-by-the-near-plane": {"translate": "0.6 0 -0.9", "angle": "70"},
}


def _draw(firmware: Path, folder: Path, model: str, scene: dict[str, str]) -> tuple[np.ndarray, np.ndarray]:
    """The firmware's first frame and the reference's, as RGB565 channels (H, W, 3)."""
    ini = "".join(f"{key} = {value}\n" for key, value in scene.items())
    card = make_card(folder, {"/model.obj": model.encode(), "/scene.ini": ini.encode()})
    out = folder / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "1", "--out", str(out), "--quiet")
    assert result.returncode == 0, result.stderr
    shown = np.asarray(Image.open(out / "frame_0000.png").convert("RGB")).astype(np.int64)
    loaded = reference.load_card_image(card)
    expected = reference.render_image(*loaded, 0).astype(np.int64)
    return _channels(shown), _channels(expected)


def _channels(rgb: np.ndarray) -> np.ndarray:
    return np.stack([rgb[..., 0] >> 3, rgb[..., 1] >> 2, rgb[..., 2] >> 3], axis=-1)


def _inside(image: np.ndarray) -> np.ndarray:
    """Pixels of the quad whose 3 x 3 neighbourhood is all quad (away from its outline, where
    snapping to 1/16 pixel decides coverage differently from the reference's exact corners)."""
    drawn = (image != image[0, 0]).any(axis=-1)
    inside = drawn.copy()
    padded = np.pad(drawn, 1)
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            inside &= padded[dy:dy + drawn.shape[0], dx:dx + drawn.shape[1]]
    return inside


@pytest.mark.parametrize("place", PLACES)
def test_phong_lights_every_pixel_as_the_reference_does(firmware, tmp_path, place):
    scene = {**TURNED, **PLACES[place]}
    phong, expected = _draw(firmware, tmp_path / "phong", QUAD, {**scene, "shading": "phong"})
    gouraud, _ = _draw(firmware, tmp_path / "gouraud", QUAD, {**scene, "shading": "gouraud"})
    inside = _inside(expected)
    assert inside.sum() > 8000                                  # the quad covers much of the screen
    greens = np.unique(expected[..., 1][inside])
    assert len(greens) > 20                                     # the light varies across it
    error = np.abs(phong - expected).max(axis=-1)[inside]
    assert error.max() <= 1, f"{(error > 1).sum()} pixels more than a step off"
    assert (error == 0).mean() > 0.99
    # Gouraud's intensity, linear between the corners, is not the normalised normal's
    gouraud_error = np.abs(gouraud - expected).max(axis=-1)[inside]
    assert gouraud_error.max() >= 3
    assert (gouraud_error == 0).mean() < 0.6


def test_a_model_without_normals_looks_as_with_flat_shading(firmware, tmp_path):
    """Each corner then gets a vector whose intensity is the face's own (corner_phong)."""
    faceted = QUAD.replace("//1", "").replace("//2", "").replace("//3", "").replace("//4", "")
    faceted = "".join(line + "\n" for line in faceted.splitlines() if not line.startswith("vn"))
    scene = {**TURNED, **PLACES["in-front"], "light_levels": "65"}
    flat, _ = _draw(firmware, tmp_path / "flat", faceted, {**scene, "shading": "flat"})
    phong, _ = _draw(firmware, tmp_path / "phong", faceted, {**scene, "shading": "phong"})
    assert (flat != flat[0, 0]).any(axis=-1).sum() > 8000
    assert np.array_equal(phong, flat)


def test_a_zero_normal_leaves_its_corner_to_the_others(firmware, tmp_path):
    """A `vn 0 0 0` stays zero (normals_phong makes only the others unit), so the corners with a
    normal light the triangle and the zero one adds nothing, as the reference's unit_rows has it."""
    quad = QUAD.replace("vn 0.9 -0.6 1.2", "vn 0 0 0")
    phong, expected = _draw(firmware, tmp_path, quad, {**TURNED, **PLACES["in-front"], "shading": "phong"})
    inside = _inside(expected)
    error = np.abs(phong - expected).max(axis=-1)[inside]
    assert inside.sum() > 8000 and error.max() <= 1 and (error == 0).mean() > 0.99
