"""Turning the user's input files into the files that go on the card.

Rules (what a user putting a model and its texture on a card expects):

* ``.obj``: checked (see `objcheck`), copied unchanged;
* ``.ppm``: validated (P3/P6 header and length), copied unchanged, never resized;
* other images Pillow reads (PNG, JPEG, BMP, GIF, TIFF, WebP, TGA, ...): converted to binary
  PPM (P6, maxval 255) named after the source with a ``.ppm`` extension, upright per EXIF,
  alpha dropped, optionally resized to ``--texture-size``;
* anything else: copied unchanged.
"""
from __future__ import annotations

import io
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from k210_common.firmware_errors import firmware_error
from reference.depth import depth_warning
from reference.obj import ModelError, parse_obj
from reference.scene import Scene, SceneError, parse_scene

from . import objcheck, ppm
from .errors import BadInputError, UsageError
from .fat32 import check_card_name
from .rawfat import fat_fold

if TYPE_CHECKING:
    from PIL import Image

SCENE_FILE = "scene.ini"

# Pillow formats that are not pictures a user would mean as a texture (documents, videos,
# scientific-data stubs), and extensions that commonly mean something else (.rgb raw dumps,
# .fit fitness logs, .im chat logs...): such files are copied unchanged.
_NOT_TEXTURE_FORMATS = {"EPS", "BUFR", "GRIB", "HDF5", "MPEG", "IPTC", "WMF"}
_NOT_TEXTURE_EXTS = {".ppm", ".rgb", ".rgba", ".bw", ".fit", ".im"}


def image_extensions() -> set[str]:
    """Lower-case extensions that are converted to PPM: every Pillow-readable picture format
    except PPM itself and the exclusions above."""
    from PIL import Image
    Image.init()
    return {ext for ext, fmt in Image.registered_extensions().items()
            if fmt in Image.OPEN and fmt not in _NOT_TEXTURE_FORMATS
            and ext not in _NOT_TEXTURE_EXTS}


@dataclass(frozen=True)
class PlacedFile:
    """A file as placed on the card (one line of the build report)."""

    #: Absolute card path, "/" separated ("/tex/cube.ppm").
    card_path: str
    size: int
    #: The input it came from; None for a scene.ini written from --scene.
    source: Path | None
    #: For converted files: what it was converted from ("tex/cube.png (PNG 300x200 ...)").
    converted_from: str | None = None
    #: What was checked or done ("OBJ: 8 vertices ...", "copied").
    detail: str = "copied"

    def report_line(self) -> str:
        """"/tex/cube.ppm  196623 bytes  <- converted from tex/cube.png (PNG 256x256)"."""
        if self.converted_from:
            origin = f"converted from {self.converted_from}"
        elif self.source is not None:
            origin = f"from {self.source}" + (f" ({self.detail})" if self.detail else "")
        else:
            origin = self.detail
        return f"{self.card_path}  {self.size} bytes  <- {origin}"


@dataclass
class CardPlan:
    """Everything that goes on a card: folders (parents first) and files with their bytes."""

    dirs: list[str] = field(default_factory=list)
    files: list[tuple[PlacedFile, bytes]] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)


def parse_texture_size(text: str) -> tuple[int, int]:
    """"64x32" -> (64, 32); raises `UsageError` on anything else."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not m or not (1 <= int(m.group(1)) <= 8192 and 1 <= int(m.group(2)) <= 8192):
        raise UsageError(f"--texture-size {text!r}: expected WxH with 1..8192, e.g. 128x128")
    return int(m.group(1)), int(m.group(2))


def _to_rgb8(img: "Image.Image") -> "Image.Image":
    """8-bit RGB from any Pillow mode; 16-bit and float greys are scaled, not clipped."""
    import numpy as np
    from PIL import Image
    if img.mode in ("I;16", "I;16L", "I;16B", "I;16N", "I"):
        arr = np.asarray(img, dtype=np.float64)
        top = 65535.0 if img.mode.startswith("I;16") or arr.max() > 255 else 255.0
        arr = np.clip(arr / top * 255.0 + 0.5, 0, 255).astype(np.uint8)
        return Image.fromarray(arr, "L").convert("RGB")
    if img.mode == "F":
        arr = np.asarray(img, dtype=np.float64)
        top = 1.0 if arr.max() <= 1.0 else 255.0
        arr = np.clip(arr / top * 255.0 + 0.5, 0, 255).astype(np.uint8)
        return Image.fromarray(arr, "L").convert("RGB")
    if img.mode == "P" and "transparency" in img.info:
        img = img.convert("RGBA")
    return img.convert("RGB")


def convert_image(data: bytes, path: Path | str,
                  texture_size: tuple[int, int] | None = None) -> tuple[bytes, str]:
    """A Pillow-readable image -> (P6 bytes, description such as "PNG 300x200, alpha dropped").

    Raises `BadInputError` when Pillow cannot decode the file.
    """
    from PIL import Image, ImageOps, UnidentifiedImageError
    fmt = Path(path).suffix.lstrip(".").upper() or "image"
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            img = Image.open(io.BytesIO(data))
            fmt = img.format or fmt
            frames = getattr(img, "n_frames", 1)  # the transposed copy forgets it
            img.load()
            stored = img.size
            orientation = img.getexif().get(0x0112, 1)
            img = ImageOps.exif_transpose(img)
    except UnidentifiedImageError:
        raise BadInputError(path, "not an image Pillow can read (unknown or damaged format)") \
            from None
    except (OSError, SyntaxError, ValueError, Image.DecompressionBombError,
            Image.DecompressionBombWarning) as exc:
        raise BadInputError(path, f"cannot decode {fmt} image: {exc}") from None
    notes = [f"{fmt} {stored[0]}x{stored[1]}"]
    if orientation not in (1, 0):
        notes.append("turned upright per EXIF")
    if frames > 1:
        notes.append(f"first of {frames} frames")
    if img.mode in ("RGBA", "LA", "PA") or (img.mode == "P" and "transparency" in img.info):
        notes.append("alpha dropped")
    rgb = _to_rgb8(img)
    if texture_size and rgb.size != texture_size:
        rgb = rgb.resize(texture_size, Image.Resampling.LANCZOS)
        notes.append(f"resized to {texture_size[0]}x{texture_size[1]}")
    return ppm.encode_p6(rgb.width, rgb.height, rgb.tobytes()), ", ".join(notes)


def parse_scene_args(items: list[str]) -> dict[str, str]:
    """["model=models/cube.obj", ...] -> ordered dict; raises `UsageError` on bad items."""
    scene: dict[str, str] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep:
            raise UsageError(f"--scene {item!r}: expected KEY=VALUE")
        key = key.strip(" \t")
        if key.lower() in (k.lower() for k in scene):
            raise UsageError(f"--scene {item!r}: key {key!r} given twice")
        scene[key] = value.strip(" \t")
    return scene


# scene.ini is held to the firmware's rules (firmware/scene.S), written once on the host in
# `reference.scene`, which the reference renderer reads scenes with too: every key, value and
# line the firmware would refuse with ERR_BAD_SCENE is refused here with its line and words.


def scene_ini(scene: dict[str, str]) -> tuple[bytes, Scene]:
    """The scene.ini text of --scene options (one "key = value" line per entry, in the given
    order) and the scene the firmware will read from it; raises `UsageError` naming the option."""
    lines = []
    for key, value in scene.items():
        key, value = str(key).strip(" \t"), str(value).strip(" \t")
        if "#" in value[1:]:
            # written as is, the '#' would cut the value short on the card
            raise UsageError(f"--scene {key}={value}: the value contains '#', which starts a "
                             f"comment in scene.ini")
        if "\n" in value or "\r" in value:
            raise UsageError(f"--scene {key}={value!r}: a value is one line")
        lines.append(f"{key} = {value}\n")
    text = "".join(lines).encode("utf-8")
    try:
        return text, parse_scene(text)
    except SceneError as exc:
        key, value = list(scene.items())[exc.line - 1]
        raise UsageError(f"--scene {key}={value}: {exc.what} (firmware error "
                         f"{exc.firmware_error.code})") from None


def check_scene_ini(data: bytes, path: Path | str) -> Scene:
    """Validates a scene.ini given as input by the firmware's rules; raises `BadInputError` with
    the line and the firmware's words; returns the scene it describes."""
    try:
        return parse_scene(data)
    except SceneError as exc:
        raise BadInputError(path, f"{exc.what} (firmware error {exc.firmware_error.code})",
                            exc.line) from None


def missing_scene_files(scene: Scene, card_files: dict[str, str]) -> list[tuple[str, str]]:
    """The files the scene names that the card lacks, each as (key, what to say of it): the
    model, and the texture in textured mode (flat and wireframe scenes read none). The firmware
    would stop at boot with ERR_NOT_FOUND. When the card holds a file of that name in a folder,
    says so: an input folder lands as a folder on the card. `card_files`: each file's card path
    folded as FAT compares names -> the path itself."""
    not_found = firmware_error("NOT_FOUND")
    missing = []
    wanted = [("model", scene.model)] + ([("texture", scene.texture)]
                                         if scene.mode == "textured" else [])
    for key, value in wanted:
        folded = "/" + fat_fold(value.replace("\\", "/").lstrip("/"))
        if folded in card_files:
            continue
        note = f"{key} = {value}"
        if key not in scene.lines:
            note += f" (the firmware's default: the scene names no {key})"
        note += f": no such file on the card (firmware error {not_found.code}, {not_found.words[0]})"
        elsewhere = sorted(path for key_, path in card_files.items()
                           if key_.endswith(folded) and key_ != folded)
        if elsewhere:
            note += (f"; the card has {elsewhere[0]}: a folder given as input lands on the card as "
                     f"a folder (give the path from the card's root, or the folder's contents)")
        missing.append((key, note))
    return missing


def refuse_missing_scene_files(scene: Scene, card_files: dict[str, str], origin: str | None) -> None:
    """Refuses a card whose scene names a file the card lacks (issue 32: the card was built, with
    a warning, and the firmware stopped with error 6): `UsageError` for `--scene` (origin None),
    `BadInputError` naming the scene.ini given as input, and the line of each key, otherwise."""
    missing = missing_scene_files(scene, card_files)
    if not missing:
        return
    if origin is None:
        raise UsageError("\n".join(f"--scene: {note}" for _, note in missing))
    first_key, first = missing[0]
    rest = "".join(f"\n{origin}" + (f":{scene.lines[key]}" if key in scene.lines else "") + f": {note}"
                   for key, note in missing[1:])
    raise BadInputError(origin, first + rest, scene.lines.get(first_key))


def _display(path: Path) -> str:
    return str(path)


class _Planner:
    def __init__(self, texture_size: tuple[int, int] | None) -> None:
        self.texture_size = texture_size
        self.plan = CardPlan()
        self.image_exts = image_extensions()
        # Per card folder: folded name -> (card name, input it came from)
        self.names: dict[str, dict[str, tuple[str, str]]] = {"": {}}
        #: Settings of a scene.ini given as input, and its path.
        self.scene_input: tuple[Scene, str] | None = None

    def claim(self, card_dir: str, name: str, origin: str) -> str:
        problem = check_card_name(name)
        if problem:
            raise UsageError(f"{origin}: cannot be put on the card: {problem}")
        taken = self.names.setdefault(card_dir, {})
        folded = fat_fold(name)
        if folded in taken:
            other_name, other_origin = taken[folded]
            how = "the same name" if other_name == name else "names differing only in case"
            raise UsageError(f"{origin} and {other_origin} would both be {card_dir}/"
                             f"{other_name} on the card ({how}; FAT names are "
                             f"case-insensitive)")
        taken[folded] = (name, origin)
        return f"{card_dir}/{name}"

    def add_dir(self, src: Path, card_dir: str, name: str, seen: set[Path]) -> None:
        real = src.resolve()
        if real in seen:
            raise UsageError(f"{src}: folder contains itself through a symbolic link")
        path = self.claim(card_dir, name, _display(src))
        self.plan.dirs.append(path)
        self.names.setdefault(path, {})
        for child in sorted(src.iterdir(), key=lambda p: p.name):
            self.add(child, path, seen | {real})

    def add(self, src: Path, card_dir: str, seen: set[Path] = frozenset()) -> None:
        name = src.name or src.resolve().name
        if src.is_dir():
            self.add_dir(src, card_dir, name, set(seen))
        elif src.is_file():
            self.add_file(src, card_dir, name)
        elif src.exists() or src.is_symlink():
            raise UsageError(f"{src}: not a regular file or folder")
        else:
            raise UsageError(f"{src}: no such file or folder")

    def add_file(self, src: Path, card_dir: str, name: str) -> None:
        try:
            data = src.read_bytes()
        except OSError as exc:
            raise UsageError(f"{src}: cannot read: {exc.strerror}") from None
        ext = src.suffix.lower()
        converted_from = None
        if ext == ".obj":
            stats = objcheck.check_obj(data, src)
            detail = f"OBJ checked: {stats.summary()}"
        elif ext == ".ppm":
            info = ppm.parse_ppm(data, src)
            detail = f"PPM {info.magic} {info.width}x{info.height} maxval {info.maxval}"
            if self.texture_size and (info.width, info.height) != self.texture_size:
                self.plan.warnings.append(
                    f"{src}: kept at {info.width}x{info.height}; --texture-size only applies "
                    f"to converted images")
        elif ext in self.image_exts:
            data, how = convert_image(data, src, self.texture_size)
            converted_from = f"{src} ({how})"
            detail = "converted"
            name = (src.stem or name) + ".ppm"
        else:
            detail = "copied"
        if card_dir == "" and fat_fold(name) == fat_fold(SCENE_FILE) and converted_from is None:
            self.scene_input = (check_scene_ini(data, src), str(src))
            detail = "scene description checked"
        card_path = self.claim(card_dir, name, _display(src))
        self.plan.files.append((PlacedFile(card_path=card_path, size=len(data), source=src,
                                           converted_from=converted_from, detail=detail), data))


def plan_card(inputs: list[Path], scene: dict[str, str] | None = None,
              texture_size: tuple[int, int] | None = None) -> CardPlan:
    """Checks and converts the inputs; each lands at the card root under its own name.

    Raises `UsageError` for missing inputs and colliding names, `BadInputError` for broken
    OBJ/PPM/image/scene files.
    """
    planner = _Planner(texture_size)
    for src in inputs:
        planner.add(Path(src), "")
    if scene:
        root = planner.names[""]
        if fat_fold(SCENE_FILE) in root:
            raise UsageError(f"both --scene and an input {root[fat_fold(SCENE_FILE)][1]} give "
                             f"the card's {SCENE_FILE}: use one or the other")
        data, scene_read = scene_ini(scene)
        card_path = planner.claim("", SCENE_FILE, "--scene")
        planner.plan.files.append((PlacedFile(card_path=card_path, size=len(data), source=None,
                                              detail="written from --scene"), data))
    on_card = {fat_fold(p.card_path): p.card_path for p, _ in planner.plan.files}
    settings = None
    if scene:
        settings = scene_read
        refuse_missing_scene_files(scene_read, on_card, None)
    elif planner.scene_input:
        settings, origin = planner.scene_input
        refuse_missing_scene_files(settings, on_card, origin)
    # without a scene.ini the firmware draws with every key's default, and checks depth with them
    _warn_of_depth(planner.plan, settings if settings is not None else parse_scene(b""))
    return planner.plan


def _warn_of_depth(plan: CardPlan, settings: Scene) -> None:
    """The firmware's warning at load when near and far leave the model few steps of the depth
    buffer (reference/depth.py), said when the card is built."""
    wanted = "/" + fat_fold(settings.model.replace("\\", "/").lstrip("/"))
    model = next((data for placed, data in plan.files if fat_fold(placed.card_path) == wanted), None)
    if model is None:
        return
    try:
        vertices = parse_obj(model).vertices
    except ModelError:
        return          # objcheck has said what is wrong with it, or the firmware will
    warning = depth_warning(settings, vertices)
    if warning is not None:
        plan.warnings.append(f"{settings.model}: {warning} (the firmware says so at boot)")
