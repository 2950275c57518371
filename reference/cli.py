"""python -m reference render FOLDER --out DIR [--frames N] [--first K] [--ideal [--density D] [--texels T]] [--quiet]
   python -m reference render-card CARD.img --out DIR [--frames N] [--first K] [--ideal [--density D] [--texels T]]
       [--quiet]

Renders frames K .. K+N-1 of the scene (scene.ini, model and texture from a folder laid out
like a card, or from a card image) and writes DIR/frame_NNNN.png as the LCD would show them:
the pixel-centre image (the firmware's conventions, exactly), or with --ideal the ideal image
(area-averaged pixels, area-filtered textures: reference/ideal.py).
Exit statuses: see EXIT_STATUS_HELP."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image

from k210_common.exit_status import (EXIT_BAD_INPUT, EXIT_CORRUPT_CARD, EXIT_INTERNAL, EXIT_OK, EXIT_USAGE, EXIT_WRITE_FAILED,
                                     help_epilog)
from k210_common.firmware_errors import firmware_error

from .ideal import DEFAULT_DENSITY, DENSITY_MAX, LINE_ROWS_PER_DENSITY, TEXEL_MODELS, render_ideal_image
from .load import load_card_folder, load_card_image
from .obj import Mesh, ModelError
from .ppm import TextureError
from .render import render_image
from .scene import Scene, SceneError

# When this command returns each status (k210_common/exit_status.py holds the numbers and
# names); --help and docs/reference/reference-renderer.md's table are made from it (tests/unit/shared/test_exit_status.py)
EXIT_STATUS_DETAILS: dict[int, str] = {
    EXIT_OK: "the frames were written",
    EXIT_INTERNAL: "an internal error of the reference renderer (a bug: please report it with the command line)",
    EXIT_USAGE: f"bad command line (a `--density` outside 1 to {DENSITY_MAX}, `--density` or `--texels` "
                "without `--ideal`), or a missing input: FOLDER, CARD, or a file the scene names",
    EXIT_BAD_INPUT: "a bad scene.ini, model or texture, with the firmware's error text (its errors "
                    f"{firmware_error('BAD_SCENE').code}, {firmware_error('BAD_MODEL').code} and "
                    f"{firmware_error('BAD_TEXTURE').code})",
    EXIT_CORRUPT_CARD: "render-card: the card image is not an MBR-partitioned FAT32 card, or is damaged (the "
                       "message names the broken structure)",
    EXIT_WRITE_FAILED: "the output folder or a frame could not be written (not a folder, permissions, disk full)",
}

EXIT_STATUS_HELP = help_epilog(EXIT_STATUS_DETAILS)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m reference",
        description="The float64 reference renderer: renders a card's scene as the firmware "
                    "should, without its approximations, to PNG frames.",
        epilog=EXIT_STATUS_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, source, what in (
            ("render", "FOLDER", "a folder laid out like a card (scene.ini, the model and the "
                                 "texture it names; names match case-insensitively, as on FAT)"),
            ("render-card", "CARD", "an SD card image built by python -m sdcard_image")):
        sub = commands.add_parser(name, help=f"render the scene of {what.split(' (')[0]}",
                                  description=f"Renders the scene of {what}.",
                                  epilog=EXIT_STATUS_HELP,
                                  formatter_class=argparse.RawDescriptionHelpFormatter)
        sub.add_argument("source", metavar=source, help=what)
        sub.add_argument("--out", type=Path, required=True, metavar="DIR",
                         help="folder for frame_NNNN.png (created if needed)")
        sub.add_argument("--frames", type=int, default=1, metavar="N",
                         help="how many frames to render (default 1)")
        sub.add_argument("--first", type=int, default=0, metavar="K",
                         help="number of the first frame: the model turns K * step degrees "
                              "before it (default 0)")
        sub.add_argument("--ideal", action="store_true",
                         help="render the ideal image instead of the pixel-centre one: each pixel "
                              "the average of density x density samples, textures averaged over "
                              "each sample's footprint, wireframe lines 1 pixel wide by coverage")
        sub.add_argument("--density", type=int, default=None, metavar="D",
                         help=f"with --ideal: the sampling density, 1 to {DENSITY_MAX}: D x D samples "
                              f"per pixel for triangles, {LINE_ROWS_PER_DENSITY} D sample rows per "
                              f"pixel for wireframe lines (exact along each row); default "
                              f"{DEFAULT_DENSITY}, where the bench scenes have converged")
        sub.add_argument("--texels", choices=TEXEL_MODELS, default=None,
                         help="with --ideal: how a texture is read: square (default: constant texel "
                              "squares, as nearest-texel sampling draws them) or smooth (the bilinear "
                              "surface through the texel centres, as a camera sees a filtered texture)")
        sub.add_argument("--quiet", action="store_true",
                         help="do not print each frame's path and render time")
    return parser


def _prepare_output(folder: Path) -> str | None:
    """Creates the output folder; returns why it cannot be used, or None."""
    if folder.exists() and not folder.is_dir():
        return f"--out {folder}: exists and is not a folder"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        return f"--out {folder}: cannot create the folder: {exc.strerror}"
    return None


def load_source(source: Path, folder: bool) -> tuple[Scene, Mesh, np.ndarray | None] | int:
    """The scene, model and texture of a folder laid out like a card (folder) or of a card image;
    or, when they cannot be read, the exit status after the message on stderr (EXIT_STATUS_HELP)."""
    from sdcard_image import SdImageError, UsageError
    try:
        if folder:
            if not source.is_dir():
                print(f"error: {source}: no such folder", file=sys.stderr)
                return EXIT_USAGE
            return load_card_folder(source)
        if not source.is_file():
            print(f"error: {source}: no such image file", file=sys.stderr)
            return EXIT_USAGE
        return load_card_image(source)
    except (SceneError, ModelError, TextureError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except UsageError as exc:          # a file the scene names is not on the card
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except SdImageError as exc:
        print(f"error: {source}: not a readable card image: {exc}", file=sys.stderr)
        return EXIT_CORRUPT_CARD
    except FileNotFoundError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except OSError as exc:
        print(f"error: {source}: cannot read: {exc.strerror}", file=sys.stderr)
        return EXIT_USAGE


def main(argv: list[str] | None = None) -> int:
    """Runs the command line; returns the exit status."""
    parser = _parser()
    args = parser.parse_args(argv)
    if args.frames < 1 or args.first < 0:
        parser.error("--frames must be at least 1 and --first not negative")
    if args.density is not None and not args.ideal:
        parser.error("--density applies only with --ideal")
    if args.texels is not None and not args.ideal:
        parser.error("--texels applies only with --ideal")
    density = DEFAULT_DENSITY if args.density is None else args.density
    if not 1 <= density <= DENSITY_MAX:
        parser.error(f"--density must be from 1 to {DENSITY_MAX}")
    loaded = load_source(Path(args.source), folder=args.command == "render")
    if isinstance(loaded, int):
        return loaded
    scene, mesh, texture = loaded
    problem = _prepare_output(args.out)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return EXIT_WRITE_FAILED
    for n in range(args.first, args.first + args.frames):
        start = time.perf_counter()
        path = args.out / f"frame_{n:04d}.png"
        try:
            if args.ideal:
                image = render_ideal_image(scene, mesh, texture, n, density=density,
                                           texels=args.texels or TEXEL_MODELS[0])
            else:
                image = render_image(scene, mesh, texture, n)
            Image.fromarray(image).save(path)
        except OSError as exc:
            print(f"error: cannot write {path}: {exc.strerror or exc}", file=sys.stderr)
            return EXIT_WRITE_FAILED
        if not args.quiet:
            print(f"{path} ({time.perf_counter() - start:.2f} s)")
    return EXIT_OK
