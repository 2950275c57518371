"""python -m reference render FOLDER --frames N --out DIR [--first K]
   python -m reference render-card CARD.img --frames N --out DIR [--first K]

Renders frames K .. K+N-1 of the scene (scene.ini, model and texture from a folder laid out
like a card, or from a card image) and writes DIR/frame_NNNN.png as the LCD would show them.
Exit status 0, 2 for bad usage or a missing file, 3 for a bad scene.ini, model or texture."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from PIL import Image

from .load import load_card_folder, load_card_image
from .obj import ModelError
from .ppm import TextureError
from .render import render_image
from .scene import SceneError


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m reference", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    for name, what in (("render", "FOLDER"), ("render-card", "CARD")):
        sub = commands.add_parser(name)
        sub.add_argument("source", metavar=what)
        sub.add_argument("--frames", type=int, default=1)
        sub.add_argument("--first", type=int, default=0, help="number of the first frame (0)")
        sub.add_argument("--out", type=Path, required=True)
        sub.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    if args.frames < 1 or args.first < 0:
        parser.error("--frames must be at least 1 and --first not negative")
    try:
        if args.command == "render":
            scene, mesh, texture = load_card_folder(args.source)
        else:
            scene, mesh, texture = load_card_image(args.source)
    except (SceneError, ModelError, TextureError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 3
    except (OSError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    for n in range(args.first, args.first + args.frames):
        start = time.perf_counter()
        path = args.out / f"frame_{n:04d}.png"
        Image.fromarray(render_image(scene, mesh, texture, n)).save(path)
        if not args.quiet:
            print(f"{path} ({time.perf_counter() - start:.2f} s)")
    return 0
