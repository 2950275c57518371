"""The precision settings of scene.ini, driven through the board model: each one really changes
what is drawn, the approximations are exact where they should be (the angle table on its grid,
Gouraud on a model without normals), and 16-bit depth fights where 32-bit depth does not."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import reference
from suite import make_card, run_emulator, shared_value

from tools import make_assets, quality

FRAMES = 2


def _ppm(image: Image.Image) -> bytes:
    rgb = image.convert("RGB")
    return f"P6\n{rgb.width} {rgb.height}\n255\n".encode() + rgb.tobytes()


def _run(firmware: Path, folder: Path, model: str, texture: bytes, scene: dict[str, str],
         frames: int = FRAMES) -> tuple[list[np.ndarray], list[int], Path]:
    """Frames (RGB888 as the LCD shows them), hart 0 instructions per frame, and the card."""
    ini = "".join(f"{key} = {value}\n" for key, value in scene.items())
    card = make_card(folder, {"/model.obj": model.encode(), "/texture.ppm": texture, "/scene.ini": ini.encode()})
    out = folder / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", str(frames), "--out", str(out),
                          "--quiet")
    assert result.returncode == 0, result.stderr                 # no trap, no hang, no firmware error
    images = [np.asarray(Image.open(out / f"frame_{n:04d}.png").convert("RGB")) for n in range(frames)]
    record = json.loads((out / "run.json").read_text())
    instructions = [frame["instructions"][0] for frame in record["frames"]]
    return images, instructions, card


@pytest.fixture(scope="module")
def torus_files() -> tuple[str, bytes]:
    return make_assets.torus(), _ppm(make_assets.texture(250, 250, 1))


TORUS_SCENE = {"mode": "textured", "scale": "0.9", "translate": "0 0 -3", "axis": "1 1 0", "angle": "17",
               "step": "3"}
# the bench's one-knob settings (tools/quality.py), one per key
SINGLE_KNOBS = {name: quality.SETTINGS[name]
                for name in ("affine", "gouraud", "light-9", "angle-table", "depth-float32", "pixel-snap")}


@pytest.fixture(scope="module")
def torus_default(firmware, torus_files, tmp_path_factory):
    """The torus scene with every setting at its default (made once for all xdist workers)."""
    model, texture = torus_files
    return shared_value(tmp_path_factory, "torus_default", lambda folder: _run(firmware, folder, model, texture,
                                                                               TORUS_SCENE))


@pytest.mark.parametrize("name", SINGLE_KNOBS)
def test_every_setting_changes_the_frames_or_their_cost(firmware, torus_files, torus_default, tmp_path, name):
    """A key the firmware accepted but ignored would pass every other test: here each one must
    change the picture (all but depth) or the instructions (depth: the same picture, another clear)."""
    model, texture = torus_files
    images, instructions, _ = _run(firmware, tmp_path, model, texture, {**TORUS_SCENE, **SINGLE_KNOBS[name]})
    default_images, default_instructions, _ = torus_default
    if name == "depth-float32":
        assert all(np.array_equal(a, b) for a, b in zip(images, default_images, strict=True))
        # the 32-bit buffer is twice as large to clear: 76,800 more bytes than 153,600, 8 stores a round
        assert instructions[1] - default_instructions[1] > 20_000
    else:   # (at 20 degrees, frame 1, the angle table is exact: frame 0 is at 17)
        assert not all(np.array_equal(a, b) for a, b in zip(images, default_images, strict=True))


def test_the_angle_table_is_exact_on_its_2_degree_grid_and_rounds_between(firmware, torus_files, tmp_path):
    """The table's entries are the polynomial's values at whole degrees of the half angle, so a
    table frame at 17 degrees (rounded to 16) is the polynomial's frame at 16 degrees, bit for bit;
    so is one 90 turns later (32,417 degrees): no drift however far the angle has run."""
    model, texture = torus_files
    still = {**TORUS_SCENE, "step": "0"}
    table, _, _ = _run(firmware, tmp_path / "table", model, texture, {**still, "angles": "table"}, frames=1)
    far, _, _ = _run(firmware, tmp_path / "far", model, texture,
                     {**still, "angles": "table", "angle": str(17 + 90 * 360)}, frames=1)
    exact, _, _ = _run(firmware, tmp_path / "exact", model, texture, {**still, "angle": "16"}, frames=1)
    assert np.array_equal(table[0], exact[0]) and np.array_equal(far[0], exact[0])


def test_gouraud_on_a_model_without_normals_is_flat_shading(firmware, tmp_path):
    """Without vn every face keeps its own intensity at all three corners: the same frames."""
    lines = [line for line in make_assets.torus().splitlines() if not line.startswith("vn")]
    model = "".join(re.sub(r"(\d+)/(\d+)/\d+", r"\1/\2", line) + "\n" for line in lines)
    texture = _ppm(make_assets.texture(16, 16, 5))
    scene = {**TORUS_SCENE, "mode": "flat"}
    flat, _, _ = _run(firmware, tmp_path / "flat", model, texture, scene)
    gouraud, _, _ = _run(firmware, tmp_path / "gouraud", model, texture, {**scene, "shading": "gouraud"})
    assert all(np.array_equal(a, b) for a, b in zip(flat, gouraud, strict=True))


def test_gouraud_is_nearer_the_smooth_reference_on_a_smooth_model(firmware, torus_files, torus_default, tmp_path):
    model, texture = torus_files
    gouraud, _, card = _run(firmware, tmp_path, model, texture, {**TORUS_SCENE, "shading": "gouraud"})
    flat, _, _ = torus_default
    scene, mesh, tex = reference.load_card_image(card)
    for n in range(FRAMES):
        ideal = reference.render_image(scene, mesh, tex, n).astype(np.int64)
        error_gouraud = float(((gouraud[n] - ideal) ** 2).mean())
        error_flat = float(((flat[n] - ideal) ** 2).mean())
        assert error_gouraud < 0.5 * error_flat, (n, error_gouraud, error_flat)


def test_16_bit_depth_fights_where_32_bit_depth_separates(firmware, tmp_path):
    """A label 0.0005 in front of a wall, 3 units away: one 16-bit depth step is about 0.0014
    units there, so the two squares mostly get equal depth values and the wall, drawn first,
    stays in front (strictly nearer wins); a float z/w separates them. The wall's texels are red,
    the label's blue, so the share of red pixels inside the label says who won."""
    model, texture = make_assets.decal(), _ppm(make_assets.decal_texture())
    scene = {"mode": "textured", "translate": "0 0 -3", "angle": "17", "step": "3"}

    def red_share(image: np.ndarray) -> float:
        label = image[80:160, 120:200].astype(np.int64)               # inside both squares
        red = (label[..., 0] > 150) & (label[..., 2] < 100)
        blue = (label[..., 2] > 150) & (label[..., 0] < 100)
        return red.sum() / max(1, (red | blue).sum())

    fighting, _, _ = _run(firmware, tmp_path / "int16", model, texture, scene)
    separated, _, card = _run(firmware, tmp_path / "float32", model, texture, {**scene, "depth": "float32"})
    ref_scene, mesh, tex = reference.load_card_image(card)
    for n in range(FRAMES):
        assert red_share(fighting[n]) > 0.5, n                        # the wall shows through
        assert red_share(separated[n]) == 0.0, n                      # the label is whole
        ideal = reference.render_image(ref_scene, mesh, tex, n)
        assert red_share(ideal) == 0.0
        differ = np.any(separated[n] != ideal, axis=2).mean()
        assert differ < 0.02, (n, differ)                             # texel-edge differences only
