"""A reference renderer in Python + numpy (float64): the firmware's conventions, exact arithmetic.

    from reference import load_card_folder, render_frame
    scene, mesh, texture = load_card_folder("build/assets-card")
    rgb565 = render_frame(scene, mesh, texture, 0)        # (240, 320) uint16, row 0 at the top
    rgb = rgb565_to_rgb888(rgb565)                        # as the board model's LCD shows it

Command line: ``python -m reference render FOLDER --frames N --out DIR`` and
``python -m reference render-card CARD.img --frames N --out DIR`` (see `reference.cli`).
"""
from .load import load_card_folder, load_card_image, load_files
from .obj import Mesh, ModelError, parse_obj
from .ppm import TextureError, parse_ppm, rgb565_from_samples
from .render import render_frame, render_image, rgb565_to_rgb888
from .scene import Scene, SceneError, parse_scene

__all__ = ["Mesh", "ModelError", "Scene", "SceneError", "TextureError", "load_card_folder",
           "load_card_image", "load_files", "parse_obj", "parse_ppm", "parse_scene",
           "render_frame", "render_image", "rgb565_from_samples", "rgb565_to_rgb888"]
