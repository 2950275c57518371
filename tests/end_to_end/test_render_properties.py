"""Properties every correct renderer has, whatever its implementation details: checked on
frames the firmware renders on the board model (independent of the golden frames)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from suite import run_emulator
from sdcard_image import build_image

WIDTH, HEIGHT = 320, 240
BACKGROUND = (0, 0, 0)
BACKGROUND_KEY = "0 0 0"


def render(firmware: Path, assets: Path, tmp_path: Path, frames: int, **scene: str) -> list[np.ndarray]:
    """Builds a card with the generated assets and `scene`, runs the firmware, returns the frames."""
    scene = {"model": "models/cube.obj", "texture": "textures/cube.ppm", "background": BACKGROUND_KEY, **scene}
    tmp_path.mkdir(parents=True, exist_ok=True)
    card = tmp_path / "card.img"
    build_image(card, [assets / "models", assets / "textures"], scene=scene, force=True)
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", str(frames), "--out", str(out),
                          "--quiet")
    assert result.returncode == 0, result.stderr + (out / "console.log").read_text()
    return [np.asarray(Image.open(out / f"frame_{n:04d}.png").convert("RGB")) for n in range(frames)]


def project(point, translate_z: float, fov_deg: float) -> tuple[float, float]:
    """Screen position (pixels, y down) of a camera-space point, as the scene conventions say:
    camera at the origin looking down -z, vertical field of view fov, aspect 320/240."""
    x, y, z = point
    t = math.tan(math.radians(fov_deg) / 2)
    ndc_x = (x / -(z + translate_z)) / (t * WIDTH / HEIGHT)
    ndc_y = (y / -(z + translate_z)) / t
    return (ndc_x + 1) / 2 * WIDTH, (1 - ndc_y) / 2 * HEIGHT


def test_cube_face_on_covers_its_projection(firmware, assets, tmp_path):
    """A unit cube seen face-on at z = -3: its front face (z = +0.5 in model space) projects to a
    square; pixel centres inside it are lit, those outside are background."""
    frame = render(firmware, assets, tmp_path, 1, mode="flat", translate="0 0 -3", step="0", angle="0",
                   fov="60", ambient="1")[0]
    (x0, y0), (x1, y1) = project((-0.5, 0.5, 0.5), -3, 60), project((0.5, -0.5, 0.5), -3, 60)
    xs, ys = np.arange(WIDTH) + 0.5, np.arange(HEIGHT) + 0.5
    inside = ((xs[None, :] > x0) & (xs[None, :] < x1)) & ((ys[:, None] > y0) & (ys[:, None] < y1))
    # pixel centres too close to an edge are left to the tie rule
    margin = 0.01
    clear_in = ((xs[None, :] > x0 + margin) & (xs[None, :] < x1 - margin)) & \
               ((ys[:, None] > y0 + margin) & (ys[:, None] < y1 - margin))
    clear_out = ~(((xs[None, :] > x0 - margin) & (xs[None, :] < x1 + margin)) &
                  ((ys[:, None] > y0 - margin) & (ys[:, None] < y1 + margin)))
    is_background = np.all(frame == BACKGROUND, axis=2)
    assert not is_background[clear_in].any(), "background inside the cube's front face"
    assert is_background[clear_out].all(), "pixels drawn outside the cube's front face"
    assert inside.sum() > 1000
    lit = frame[clear_in]
    assert (lit == lit[0]).all(), "a face-on flat face has one colour"


def _convex_hull_mask(points: np.ndarray, margin: float) -> np.ndarray:
    """Pixel centres at least `margin` pixels inside the convex hull of points (x, y)."""
    from itertools import combinations
    centre = points.mean(axis=0)
    xs, ys = np.meshgrid(np.arange(WIDTH) + 0.5, np.arange(HEIGHT) + 0.5)
    mask = np.ones((HEIGHT, WIDTH), dtype=bool)
    for a, b in combinations(range(len(points)), 2):
        p, q = points[a], points[b]
        normal = np.array([q[1] - p[1], p[0] - q[0]])
        length = np.hypot(*normal)
        if length == 0:
            continue
        normal /= length
        side = (points - p) @ normal
        if np.all(side <= 1e-9) or np.all(side >= -1e-9):      # a hull edge
            if (centre - p) @ normal < 0:
                normal = -normal
            mask &= ((xs - p[0]) * normal[0] + (ys - p[1]) * normal[1]) >= margin
    return mask


@pytest.mark.parametrize("angle", [30, 123])
def test_no_background_shows_through_a_closed_mesh(firmware, assets, tmp_path, angle):
    """A closed convex mesh covers the convex hull of its projected corners: inside it, no pixel
    may show the background (cracks between triangles would)."""
    frame = render(firmware, assets, tmp_path, 1, mode="textured", translate="0 0 -3", step="0",
                   angle=str(angle), axis="1 1 0.5")[0]
    axis = np.array([1.0, 1.0, 0.5]) / np.linalg.norm([1.0, 1.0, 0.5])
    theta = math.radians(angle)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rotation = np.eye(3) + math.sin(theta) * k + (1 - math.cos(theta)) * k @ k
    corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]) @ rotation.T
    projected = np.array([project(c, -3, 60) for c in corners])
    inside = _convex_hull_mask(projected, margin=1.0)
    assert inside.sum() > 2000
    holes = np.all(frame == BACKGROUND, axis=2) & inside
    assert not holes.any(), f"{holes.sum()} background pixels inside the cube"


def test_a_full_turn_returns_to_the_first_frame(firmware, assets, tmp_path):
    frames = render(firmware, assets, tmp_path, 9, model="models/torus.obj", texture="textures/torus.ppm",
                    translate="0 0 -3", step="45", axis="0.3 1 0.2")
    assert not np.array_equal(frames[0], frames[1])
    assert np.array_equal(frames[0], frames[8]), "after 8 steps of 45 degrees the model is back where it began"


def test_frames_are_shown_in_order(firmware, assets, tmp_path):
    """Frame k shows the model at angle + k * step: a run that starts one step later shows, as its
    first frames, what the first run showed as its second and third (no frame lost or swapped
    between the two framebuffers)."""
    scene = dict(model="models/gem.obj", texture="textures/gem.ppm", translate="0 0 -3", step="10",
                 axis="0 1 0.3")
    first = render(firmware, assets, tmp_path / "a", 3, angle="0", **scene)
    later = render(firmware, assets, tmp_path / "b", 2, angle="10", **scene)
    assert not np.array_equal(first[0], first[1])
    assert np.array_equal(later[0], first[1]) and np.array_equal(later[1], first[2])


def test_camera_inside_a_closed_mesh_sees_it_everywhere(firmware, assets, tmp_path):
    """With the camera inside the cube every triangle crosses the near plane or lies behind the
    camera; clipped correctly, the inside faces (culling off) cover every pixel."""
    frame = render(firmware, assets, tmp_path, 1, mode="flat", translate="0 0 0", step="0", angle="20",
                   axis="0.3 1 0.1", cull="off", near="0.05", ambient="1")[0]
    assert not np.all(frame == BACKGROUND, axis=2).any()


def test_a_model_behind_the_camera_draws_nothing(firmware, assets, tmp_path):
    """Nothing behind the camera may wrap around onto the screen."""
    frame = render(firmware, assets, tmp_path, 1, mode="textured", translate="0 0 3", step="0",
                   model="models/torus.obj", texture="textures/torus.ppm")[0]
    assert np.all(frame == BACKGROUND)
