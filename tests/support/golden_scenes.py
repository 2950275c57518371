"""The scenes held against golden frames: the default card of `make flash-to-emulator`, and
one scene per render mode built from the generated assets. Shared by the tests and by
tools/regen_goldens.py, so goldens are always made exactly as the tests check them."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
GOLDEN = ROOT / "tests" / "golden"
DEFAULT_CARD = ROOT / "build" / "card.img"

# name -> (scene.ini keys, frames); None: the default card built by `make card`
SCENES: dict[str, tuple[dict[str, str] | None, int]] = {
    "default": (None, 4),
    "gem-flat": ({"model": "models/gem.obj", "texture": "textures/gem.ppm", "mode": "flat",
                  "translate": "0 0 -3", "axis": "0.2 1 0", "angle": "10", "step": "6", "ambient": "0.3",
                  "light": "-0.4 0.6 1"}, 3),
    "cube-textured": ({"model": "models/cube.obj", "texture": "textures/cube.ppm", "mode": "textured",
                       "translate": "0 0 -3", "axis": "1 1 0", "angle": "20", "step": "5",
                       "background": "40 40 80"}, 3),
    # texture filtering: the cube's 8 x 8 texture magnified (bilinear's blend), the torus's 250 x 250
    # one minified (the mip chain's levels)
    "cube-bilinear": ({"model": "models/cube.obj", "texture": "textures/cube.ppm", "mode": "textured",
                       "translate": "0 0 -3", "axis": "1 1 0", "angle": "20", "step": "5",
                       "background": "40 40 80", "filter": "bilinear"}, 3),
    "torus-mipmap": ({"model": "models/torus.obj", "texture": "textures/torus.ppm", "mode": "textured",
                      "scale": "0.35", "translate": "0 0 -3", "axis": "1 1 0", "angle": "17", "step": "3",
                      "shading": "gouraud", "filter": "mipmap"}, 3),
    # antialias = edge: the torus's silhouettes (outer, and inner where it folds) by coverage,
    # textured
    "torus-edge": ({"model": "models/torus.obj", "texture": "textures/torus.ppm", "mode": "textured",
                    "scale": "0.8", "translate": "0 0 -3", "axis": "1 0.6 0.2", "angle": "40", "step": "4",
                    "background": "200 220 255", "antialias": "edge"}, 3),
    # antialias = supersample: the gem's facets, four samples a pixel
    "gem-supersample": ({"model": "models/gem.obj", "texture": "textures/gem.ppm", "mode": "flat",
                         "translate": "0 0 -3", "axis": "0.2 1 0", "angle": "10", "step": "6", "ambient": "0.3",
                         "light": "-0.4 0.6 1", "antialias": "supersample"}, 3),
    "torus-wireframe": ({"model": "models/torus.obj", "texture": "textures/torus.ppm", "mode": "wireframe",
                         "translate": "0 0 -2.8", "axis": "1 0.6 0.2", "angle": "40", "step": "4"}, 3),
    # antialias = edge in wireframe: the same torus, lines by coverage
    "torus-wireframe-aa": ({"model": "models/torus.obj", "texture": "textures/torus.ppm", "mode": "wireframe",
                            "translate": "0 0 -2.8", "axis": "1 0.6 0.2", "angle": "40", "step": "4",
                            "antialias": "edge"}, 3),
    # antialias = supersample in wireframe: the union of the lines (crossings and vertices counted
    # once)
    "torus-wireframe-supersample": ({"model": "models/torus.obj", "texture": "textures/torus.ppm",
                                     "mode": "wireframe", "translate": "0 0 -2.8", "axis": "1 0.6 0.2",
                                     "angle": "40", "step": "4", "antialias": "supersample"}, 3),
}


def scene_card_path(name: str, folder: Path) -> Path:
    """Where scene_card(name, folder) puts the card."""
    return DEFAULT_CARD if SCENES[name][0] is None else folder / f"{name}.img"


def scene_card(name: str, folder: Path, assets: Path | None = None) -> Path:
    """The card for a golden scene (built in `folder` unless it is the default card), from the
    generated models and textures in `assets` (tools/make_assets.py's output), or else generated
    into folder/assets."""
    scene, _ = SCENES[name]
    if scene is None:
        subprocess.run(["make", "-s", "build/card.img"], cwd=ROOT, check=True)
        return DEFAULT_CARD
    from sdcard_image import build_image
    if assets is None:
        assets = folder / "assets"
        if not assets.exists():
            subprocess.run([sys.executable, str(ROOT / "tools" / "make_assets.py"), str(assets)], check=True)
    card = scene_card_path(name, folder)
    build_image(card, [assets / "models", assets / "textures"], scene=scene, force=True)
    return card
