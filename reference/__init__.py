"""A reference renderer in Python + numpy (float64): the firmware's conventions, exact arithmetic.

    from reference import load_card_folder, render_frame
    scene, mesh, texture = load_card_folder("build/assets-card")
    rgb565 = render_frame(scene, mesh, texture, 0)        # (240, 320) uint16, row 0 at the top
    rgb = rgb565_to_rgb888(rgb565)                        # as the board model's LCD shows it
    ideal = render_ideal_frame(scene, mesh, texture, 0)   # area-averaged, area-filtered (RGB565)

render_frame samples pixel centres and nearest texels, as the firmware does (reference.render);
render_ideal_frame and render_ideal_image integrate over each pixel (reference.ideal).

Command line: ``python -m reference render FOLDER --frames N --out DIR`` and
``python -m reference render-card CARD.img --frames N --out DIR``, each with ``--ideal`` for the
ideal image (see `reference.cli`).
"""
from .ideal import DEFAULT_DENSITY, ideal_channels, render_ideal_frame, render_ideal_image
from .load import load_card_folder, load_card_image, load_card_scene, load_files
from .obj import Mesh, ModelError, parse_obj
from .ppm import TextureError, parse_ppm, rgb565_from_samples
from .render import render_frame, render_image, rgb565_to_rgb888
from .scene import Scene, SceneError, parse_scene

__all__ = ["DEFAULT_DENSITY", "Mesh", "ModelError", "Scene", "SceneError", "TextureError",
           "ideal_channels", "load_card_folder", "load_card_image", "load_card_scene", "load_files", "parse_obj",
           "parse_ppm", "parse_scene", "render_frame", "render_ideal_frame", "render_ideal_image",
           "render_image", "rgb565_from_samples", "rgb565_to_rgb888"]
