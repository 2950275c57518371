"""The Transputer seed's macro Z-buffer ("pre-removal"), simulated on a scene's frames, to measure
what it could save before anyone writes it in assembly (issue 12, item 5).

The seed's algorithm: the screen is cut into square tiles, and each tile keeps the farthest depth
drawn in it, changed only when one triangle covers the whole tile (then to that triangle's
farthest depth over the tile, if nearer). A triangle whose nearest depth is no nearer than the
kept depth of every tile its bounding box touches is hidden: it is skipped. (The firmware's depth
test is "strictly nearer wins", so a triangle at the kept depth is hidden too.)

The simulation runs the reference renderer's triangles of each frame, in the firmware's drawing
order, keeps the tiles as the algorithm would, and counts the triangles and pixels it would skip;
it also checks each skip against the depth buffer (every pixel of a skipped triangle must fail the
depth test: a wrong skip would change the picture). What it skips bounds what the firmware could
gain; the tile test and the tile updates would cost every triangle some work on top.

    python tools/macro_zbuffer.py                 # the bench's scenes, tiles of 2, 4, 8 and 16 pixels
    python tools/macro_zbuffer.py CARD [FRAMES]   # a card image or folder's scene (wireframe: none)

Exit status 0; for a card that cannot be read, the reference renderer's (main).
"""
from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from reference import render  # noqa: E402
from reference.load import load_files  # noqa: E402
from reference.scene import Scene  # noqa: E402
from reference.obj import Mesh  # noqa: E402

TILE_SIDES = (2, 4, 8, 16)


@dataclass
class MacroCounts:
    """What the macro Z-buffer with tiles of `side` pixels would skip over some frames."""

    side: int
    skipped_triangles: int = 0
    skipped_pixels: int = 0
    wrong_skips: int = 0          # skipped triangles with a pixel that passes the depth test


@dataclass
class SceneCounts:
    """The frames' triangles that reach the rasteriser with pixels, and per tile size what the
    macro Z-buffer would skip of them."""

    frames: int = 0
    triangles: int = 0
    pixels: int = 0
    hidden_triangles: int = 0     # every pixel fails the depth test: what a perfect test could skip
    hidden_pixels: int = 0
    by_side: dict[int, MacroCounts] = field(default_factory=dict)


class MacroZBuffer:
    """The tiles of one frame: the farthest depth kept per tile (1.0, the far plane, when none)."""

    def __init__(self, side: int) -> None:
        self.side = side
        self.far = np.ones((-(-render.HEIGHT // side), -(-render.WIDTH // side)))

    def tiles(self, bounds: tuple[int, int, int, int]) -> tuple[slice, slice]:
        xmin, xmax, ymin, ymax = bounds
        return slice(ymin // self.side, ymax // self.side + 1), slice(xmin // self.side, xmax // self.side + 1)

    def hides(self, bounds: tuple[int, int, int, int], nearest: float) -> bool:
        """Whether a triangle with this pixel box and nearest depth is hidden in every tile."""
        rows, columns = self.tiles(bounds)
        return bool((self.far[rows, columns] <= nearest).all())

    def cover(self, screen: np.ndarray, area: float, zw: np.ndarray, bounds: tuple[int, int, int, int]) -> None:
        """A drawn triangle (positive order) lowers the kept depth of every whole tile it covers:
        all the tile's pixel centres inside (its corners', the triangle being convex), to its
        farthest depth there (at a corner: depth is affine in screen space)."""
        rows, columns = self.tiles(bounds)
        side = self.side
        ty, tx = np.mgrid[rows, columns]
        whole = ((tx + 1) * side <= render.WIDTH) & ((ty + 1) * side <= render.HEIGHT)
        ty, tx = ty[whole], tx[whole]          # a tile cut by the screen's edge is never whole
        if not len(ty):
            return
        # each tile's four corner pixel centres, (tiles, 4)
        px = (tx * side)[:, None] + np.array([0.5, side - 0.5, 0.5, side - 0.5])
        py = (ty * side)[:, None] + np.array([0.5, 0.5, side - 0.5, side - 0.5])
        inside, weights = render.coverage(screen, area, px, py)
        covered = inside.all(axis=1)
        farthest = (weights[0] * zw[0] + weights[1] * zw[1] + weights[2] * zw[2]).max(axis=1)
        ty, tx, farthest = ty[covered], tx[covered], farthest[covered]
        self.far[ty, tx] = np.minimum(self.far[ty, tx], farthest)


def simulate(scene: Scene, mesh: Mesh, frames: int, sides: tuple[int, ...] = TILE_SIDES) -> SceneCounts:
    """Frames 0 .. frames - 1 of a filled scene (flat or textured: only coverage and depth matter)
    drawn by the reference renderer, with a macro Z-buffer of each tile size beside them."""
    counts = SceneCounts(frames=frames, by_side={side: MacroCounts(side) for side in sides})
    for n in range(frames):
        target = render.Target(scene.background)
        buffers = [MacroZBuffer(side) for side in sides]
        for triangle in render.frame_triangles(scene, mesh, None, n):
            facing = render.front_facing(triangle.screen, scene.cull)
            if facing is None:
                continue
            order, area = facing
            screen, zw = triangle.screen[order], triangle.zw[order]
            bounds = render.pixel_bounds(screen)
            if bounds is None:
                continue
            xmin, xmax, ymin, ymax = bounds
            px, py = np.meshgrid(np.arange(xmin, xmax + 1) + 0.5, np.arange(ymin, ymax + 1) + 0.5)
            inside, weights = render.coverage(screen, area, px, py)
            covered = int(inside.sum())
            if not covered:
                continue
            depth = weights[0][inside] * zw[0] + weights[1][inside] * zw[1] + weights[2][inside] * zw[2]
            ys, xs = np.nonzero(inside)
            hidden = bool((depth >= target.depth[ys + ymin, xs + xmin]).all())
            counts.triangles += 1
            counts.pixels += covered
            if hidden:
                counts.hidden_triangles += 1
                counts.hidden_pixels += covered
            nearest = float(zw.min())
            for buffer in buffers:
                tally = counts.by_side[buffer.side]
                if buffer.hides(bounds, nearest):
                    tally.skipped_triangles += 1
                    tally.skipped_pixels += covered
                    tally.wrong_skips += not hidden
            render.raster_triangle(target, triangle.screen, triangle.zw, triangle.q, scene.cull, render.FLAT_COLOUR)
            for buffer in buffers:
                buffer.cover(screen, area, zw, bounds)
    return counts


def bench_scenes() -> list[tuple[str, Scene, Mesh]]:
    """The bench's filled scenes (tools/bench.py: every scene at each of its scales, then the
    heavy sphere of the both-harts table), each with the bench's motion."""
    sys.path.insert(0, str(ROOT / "tools"))
    import bench
    scenes = [(name, model, scale) for name, model, _, scales in bench.BENCH_SCENES for scale in scales]
    scenes += [(name, model, scale) for name, model, _, scale, keys in bench.HARTS_SCENES if not keys]
    built = []
    for name, model, scale in scenes:
        text = "\n".join(f"{key} = {value}" for key, value in
                         {"mode": "flat", "scale": str(scale), **bench.BENCH_MOTION}.items())
        scene, mesh, _ = load_files(text, (ROOT / "build" / "assets" / model).read_bytes(), None)
        built.append((f"{name}, scale {scale}", scene, mesh))
    return built


def report(frames: int = 6, scenes: list[tuple[str, Scene, Mesh]] | None = None) -> list[dict]:
    """Scenes (the bench's by default) simulated over `frames` frames: one record per scene, its
    figures per frame."""
    records = []
    for name, scene, mesh in bench_scenes() if scenes is None else scenes:
        counts = simulate(scene, mesh, frames)
        records.append({
            "scene": name, "triangles": counts.triangles / frames, "pixels": counts.pixels / frames,
            "hidden_triangles": counts.hidden_triangles / frames, "hidden_pixels": counts.hidden_pixels / frames,
            "skipped": {side: {"triangles": c.skipped_triangles / frames, "pixels": c.skipped_pixels / frames,
                               "wrong": c.wrong_skips} for side, c in counts.by_side.items()},
        })
    return records


def format_report(records: list[dict]) -> list[str]:
    lines = ["macro Z-buffer (the Transputer seed's pre-removal), simulated per frame: triangles with pixels, "
             "those wholly hidden, and what tiles of N x N pixels would skip (triangles / pixels)"]
    for r in records:
        skips = "  ".join(f"{side}: {s['triangles']:.1f} / {s['pixels']:.0f}" + (f" ({s['wrong']} WRONG)" if s["wrong"] else "")
                          for side, s in r["skipped"].items())
        lines.append(f"  {r['scene']:48s} {r['triangles']:6.0f} tri {r['pixels']:7.0f} px; hidden "
                     f"{r['hidden_triangles']:5.1f} / {r['hidden_pixels']:4.0f}; skipped {skips}")
    return lines


def main(argv: list[str]) -> int:
    """The command line; returns the exit status (the reference renderer's, for the card it reads:
    `python -m reference --help`)."""
    from k210_common.exit_status import EXIT_USAGE
    from reference.cli import load_source
    if not argv:
        print("\n".join(format_report(report())))
        return 0
    try:
        frames = int(argv[1]) if len(argv) > 1 else 6
    except ValueError:
        frames = 0
    if frames < 1 or len(argv) > 2:
        print("usage: python tools/macro_zbuffer.py [CARD [FRAMES]] (CARD an image or a folder laid out "
              "like a card; FRAMES a whole number from 1, default 6)", file=sys.stderr)
        return EXIT_USAGE
    card = Path(argv[0])
    loaded = load_source(card, folder=card.is_dir())
    if isinstance(loaded, int):
        return loaded
    scene, mesh, _ = loaded
    if scene.mode == "wireframe":
        print(f"{card}: a wireframe scene draws without a depth test: nothing to pre-remove")
        return 0
    print("\n".join(format_report(report(frames, [(str(card), scene, mesh)]))))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
