"""The scene, model and texture of a card: from a folder laid out like a card, a card image,
or the files' contents. As on the board: the texture is loaded only in textured mode (flat and
wireframe draw none, so a card for them needs no texture file), and a card without scene.ini
shows the defaults."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .obj import Mesh, parse_obj
from .ppm import parse_ppm
from .scene import Scene, parse_scene


def load_files(scene_ini_text: str | bytes | None, obj_bytes: bytes,
               ppm_bytes: bytes | None) -> tuple[Scene, Mesh, np.ndarray | None]:
    """(scene, mesh, texture) from the files' contents; scene_ini_text None = no scene.ini,
    ppm_bytes None = no texture (it is ignored unless the mode is textured)."""
    scene = parse_scene(scene_ini_text)
    mesh = parse_obj(obj_bytes)
    texture = None
    if uses_texture(scene) and ppm_bytes is not None:
        texture = parse_ppm(ppm_bytes)
    return scene, mesh, texture


def uses_texture(scene: Scene) -> bool:
    """Whether the scene draws its texture, so that its file must be on the card: only in
    textured mode (firmware/scene.S loads it then and only then)."""
    return scene.mode == "textured"


def _find(folder: Path, card_path: str) -> Path:
    """A card path under folder, each name matched case-insensitively (as on FAT)."""
    here = folder
    for part in [p for p in card_path.replace("\\", "/").split("/") if p]:
        exact = here / part
        if exact.exists():
            here = exact
            continue
        matches = [c for c in here.iterdir()] if here.is_dir() else []
        matches = [c for c in matches if c.name.lower() == part.lower()]
        if not matches:
            raise FileNotFoundError(f"{folder}: file not found: {card_path}")
        here = matches[0]
    return here


def load_card_folder(folder) -> tuple[Scene, Mesh, np.ndarray | None]:
    folder = Path(folder)
    try:
        scene_ini = _find(folder, "scene.ini").read_bytes()
    except FileNotFoundError:
        scene_ini = None
    scene = parse_scene(scene_ini)
    obj = _find(folder, scene.model).read_bytes()
    ppm = _find(folder, scene.texture).read_bytes() if uses_texture(scene) else None
    return load_files(scene_ini, obj, ppm)


def _card_scene_ini(image: Path) -> bytes | None:
    from sdcard_image import UsageError, read_file
    try:
        return read_file(image, "/scene.ini")
    except UsageError:
        return None


def load_card_scene(image) -> Scene:
    """The scene of a card image alone (the defaults without scene.ini), without its model and
    texture, which can take seconds to parse."""
    return parse_scene(_card_scene_ini(Path(image)))


def load_card_image(image) -> tuple[Scene, Mesh, np.ndarray | None]:
    from sdcard_image import read_file
    image = Path(image)
    scene_ini = _card_scene_ini(image)
    scene = parse_scene(scene_ini)
    obj = read_file(image, "/" + scene.model.lstrip("/"))
    ppm = read_file(image, "/" + scene.texture.lstrip("/")) if uses_texture(scene) else None
    return load_files(scene_ini, obj, ppm)
