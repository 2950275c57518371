"""Issue 34, item 4: near and far that leave the model few steps of the depth buffer are said, not
silent. The firmware's warning at load (firmware/depth_check.S), the same count from the card builder
(reference/depth.py, which sdcard_image calls), and the count itself against the depth mapping."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from reference.depth import DEPTH_WARN_STEPS, depth_steps, depth_warning
from reference.obj import parse_obj
from reference.scene import parse_scene
from sdcard_image import build_image
from suite import ROOT, make_card

TORUS = ROOT / "build" / "assets" / "models" / "torus.obj"
# (translate z, scale, far, depth): the default scene; a model 100 times larger, 100 times further, with
# a far plane of 1e7 (16-bit depth: a handful of steps; float32, reversed: millions), and 10,000 times
# (float32: millions still); the model at its own size a million units away (float32: its 1 / D, rounded,
# takes a few dozen values)
FAR_SCENES = {
    "default": (-3, 1, "100", "int16"),
    "far-int16": (-300, 100, "1e7", "int16"),
    "far-float32": (-300, 100, "1e7", "float32"),
    "farther-float32": (-30000, 10000, "1e7", "float32"),
    "thin-far-float32": (-1e6, 1, "1e7", "float32"),
}


def scene_text(z: float, scale: float, far: str, depth: str) -> str:
    return (f"mode = flat\ntranslate = 0 0 {z}\nscale = {scale}\nnear = 0.1\nfar = {far}\ndepth = {depth}\n"
            "step = 0\nangle = 30\naxis = 1 0.5 0\n")


def firmware_console(firmware: Path, folder: Path, scene: str) -> list[str]:
    from emulator.board import Board
    card = make_card(folder, {"/scene.ini": scene.encode(), "/model.obj": TORUS.read_bytes()})
    board = Board(str(firmware), sd_image=str(card))
    try:
        board.run(1)
    finally:
        board.close()
    return [line for _, line in board.console_lines]


@pytest.mark.parametrize("name", list(FAR_SCENES))
def test_the_firmware_warns_exactly_when_the_card_builder_does(firmware, tmp_path, name):
    text = scene_text(*FAR_SCENES[name])
    expected = depth_warning(parse_scene(text), parse_obj(TORUS.read_bytes()).vertices)
    warnings = [line for line in firmware_console(firmware, tmp_path, text) if line.startswith("warning: depth")]
    assert warnings == ([] if expected is None else [f"warning: {expected}"])
    assert (expected is not None) == (name in ("far-int16", "thin-far-float32"))


def _floats_between(a: float, b: float) -> int:
    """How many float32 values lie between a and b (both >= 0, each rounded to a float32 first)."""
    return abs(int(np.float32(a).view(np.int32)) - int(np.float32(b).view(np.int32)))


def test_the_steps_follow_the_depth_mapping():
    """The count against the mappings done in double precision: 16-bit depth cuts far / (far - near)
    near (1 / D0 - 1 / D1) into 65534ths; float32's reversed depth c1 / D - c0 has as many steps as
    there are floats between its values at D1 and D0, or between 1 / D1 and 1 / D0 where those are
    fewer (within a step or two of single-precision rounding, or a thousandth)."""
    vertices = parse_obj(TORUS.read_bytes()).vertices
    r = float(np.max(np.linalg.norm(vertices, axis=1)))
    for z, scale, far, depth in FAR_SCENES.values():
        scene = parse_scene(scene_text(z, scale, far, depth))
        near, far_ = 0.1, float(far)
        d0, d1 = max(-z - scale * r, near), -z + scale * r
        if depth == "int16":
            ideal = far_ / (far_ - near) * near * (1 / d0 - 1 / d1) * 65534
        else:
            c0 = near / (far_ - near)
            ideal = min(_floats_between(c0 * far_ / d0 - c0, c0 * far_ / d1 - c0), _floats_between(1 / d0, 1 / d1))
        assert abs(depth_steps(scene, vertices) - ideal) <= max(2, ideal * 1e-3), (z, depth)


def test_wireframe_has_no_depth_buffer_to_warn_of(firmware, tmp_path):
    text = scene_text(*FAR_SCENES["far-int16"]).replace("mode = flat", "mode = wireframe")
    assert depth_steps(parse_scene(text), parse_obj(TORUS.read_bytes()).vertices) is None
    assert not [line for line in firmware_console(firmware, tmp_path, text) if line.startswith("warning: depth")]


def test_a_card_without_a_scene_is_checked_with_the_defaults(tmp_path):
    """The firmware draws a card without scene.ini with every key's default (model.obj at 0 0 -3) and
    checks its depth so; the builder too."""
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "model.obj").write_bytes(b"v 0 0 0\nv 0.001 0 0\nv 0 0.001 0\nf 1 2 3\n")
    (tmp_path / "in" / "texture.ppm").write_bytes(b"P6\n1 1\n255\n\x80\x80\x80")
    heard: list[str] = []
    build_image(tmp_path / "card.img", [tmp_path / "in" / "model.obj", tmp_path / "in" / "texture.ppm"],
                force=True, on_warning=heard.append)
    steps = depth_steps(parse_scene(""), parse_obj((tmp_path / "in" / "model.obj").read_bytes()).vertices)
    assert steps is not None and steps < DEPTH_WARN_STEPS
    assert [message for message in heard if "depth" in message] == [
        f"model.obj: depth: near and far leave {steps} steps of the depth buffer over the model's depth (fewer than "
        f"{DEPTH_WARN_STEPS}: its surfaces may hide each other wrongly) (the firmware says so at boot)"]


def test_a_model_wholly_beyond_the_far_plane_has_no_steps_to_count():
    scene = parse_scene("translate = 0 0 -500\nfar = 100\n")
    assert depth_steps(scene, np.array([[1.0, 0.0, 0.0]])) is None


def test_the_card_builder_says_it(tmp_path):
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "model.obj").write_bytes(TORUS.read_bytes())
    heard: list[str] = []
    keys = {"mode": "flat", "model": "model.obj", "translate": "0 0 -300", "scale": "100", "far": "1e7"}
    build_image(tmp_path / "card.img", [tmp_path / "in" / "model.obj"], scene=keys, force=True,
                on_warning=heard.append)
    steps = depth_steps(parse_scene("translate = 0 0 -300\nscale = 100\nfar = 1e7\n"),
                        parse_obj(TORUS.read_bytes()).vertices)
    assert steps < DEPTH_WARN_STEPS
    assert heard == [f"model.obj: depth: near and far leave {steps} steps of the depth buffer over the model's "
                     f"depth (fewer than {DEPTH_WARN_STEPS}: its surfaces may hide each other wrongly) (the firmware "
                     "says so at boot)"]
    build_image(tmp_path / "card.img", [tmp_path / "in" / "model.obj"], scene={"mode": "flat"}, force=True,
                on_warning=heard.append)
    assert len(heard) == 1                                  # the default scene: nothing to say
