"""Both harts draw (issue 12, item 4; firmware/main.S, render.S render_vertex_share and
render_band, raster.S bands): a frame whose vertex stage is split in two shares and whose rows are
split in two bands between hart 0 and hart 1 is the frame hart 0 draws alone, bit for bit,
whatever the settings and wherever the split falls; `harts = auto` lets hart 1 draw only when
drawing takes longer than the LCD's transfer; the scene key is read alike by the firmware and the
host tools."""
from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np
import pytest

from suite import make_card, run_together, shared_value
from extremes_support import check_scene_key_agreement, run_scene
from tools.make_assets import cube, sphere, texture

FRAMES = 4                  # frame 0 is hart 0's alone (hart 1 brings the LCD up); 1.. are split
# hart 1's instructions in a frame when it only sends the frame and waits, against when it draws
# a band of a 1,024-triangle sphere (about 1.4 million): far apart either way
HART1_IDLE_MAX = 50_000
HART1_DRAWING_MIN = 300_000


def ppm(width: int, height: int, seed: int) -> bytes:
    """make_assets' texture as a binary PPM (the firmware's format)."""
    pixels = np.asarray(texture(width, height, seed).convert("RGB"), dtype=np.uint8)
    return f"P6\n{width} {height}\n255\n".encode() + pixels.tobytes()


MODEL = sphere(segments=32, bands=16)           # 1,024 triangles, 561 vertices (an odd count)
TEXTURE = ppm(128, 128, 5)
FINE_TEXTURE = ppm(256, 256, 5)


RACE_SIDE = 24              # the race grid's vertices a side: 576, and 576 behind the camera


def race_grid(grid_share: int) -> str:
    """A bumpy grid of RACE_SIDE x RACE_SIDE vertices filling the screen, and as many vertices
    behind the camera that no face uses, so that each hart's share of the vertex stage (render.S
    render_vertex_share: the first half of the vertices, the second) is either the whole grid
    (every vertex projected: the dearer share) or only the hidden ones (never projected: the
    cheaper share, done well before the other). The hart with the cheap share must still wait for
    the other's before drawing: the grid's last vertices lie in its band and the faces that use
    them come first, so that drawing on early would read last frame's records.
    `grid_share` 0: the grid first, hart 1 the early one (its band is the bottom: the grid's rows
    run top to bottom); 1: the grid second, hart 0 the early one (rows bottom to top)."""
    rows = range(RACE_SIDE) if grid_share == 0 else range(RACE_SIDE - 1, -1, -1)
    grid, uvs = [], []
    for j in rows:                                   # j = 0: the top row
        for i in range(RACE_SIDE):
            u, v = i / (RACE_SIDE - 1), 1 - j / (RACE_SIDE - 1)
            grid.append((2.8 * u - 1.4, 2.1 * v - 1.05, 0.08 * ((i * 7 + j * 3) % 5)))
            uvs.append((u, v))
    hidden = [(0.0, 0.0, 5.0)] * len(grid)
    vertices = grid + hidden if grid_share == 0 else hidden + grid
    base = 0 if grid_share == 0 else len(hidden)
    faces = []
    for r in range(RACE_SIDE - 2, -1, -1):           # the last rows' faces first
        for i in range(RACE_SIDE - 1):
            a, b = base + r * RACE_SIDE + i + 1, base + (r + 1) * RACE_SIDE + i + 1
            t = r * RACE_SIDE + i + 1
            faces.append([(a, t), (b, t + RACE_SIDE), (b + 1, t + RACE_SIDE + 1)])
            faces.append([(a, t), (b + 1, t + RACE_SIDE + 1), (a + 1, t + 1)])
    return "\n".join([*(f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vertices),
                      *(f"vt {u:.6f} {v:.6f}" for u, v in uvs),
                      *(f"f {p}/{q} {r}/{w} {m}/{n}" for (p, q), (r, w), (m, n) in faces)]) + "\n"


RACE_KEYS = "translate = 0 0 -2\ncull = off\n"
# Filling the screen: heavier than the LCD's transfer, so that `auto` has hart 1 draw too.
BIG = "scale = 1.4\n"
# The settings where a band could come out differently: the plain fill (nearest texel, perspective,
# 16-bit depth), and the fills that keep their row state on the stack (mipmap), interpolate a
# Gouraud intensity, keep a float depth; the close-up cuts triangles at the near plane and at the
# screen's edges (clip_and_draw, the fans drawn on both harts); the cube's faces span both bands
# with many rows above the split, where hart 1 steps the planes down to its first row (anchoring
# them there directly instead changes texels: this scene shows it within its frames).
SCENES = {
    "plain": (MODEL, TEXTURE, BIG, FRAMES),
    "close-up": (MODEL, TEXTURE, "scale = 1.4\ntranslate = 0 0 -1.45\nfilter = mipmap\nshading = gouraud\n"
                 "depth = float32\ncull = off\n", FRAMES),
    "cube": (cube(), FINE_TEXTURE, "scale = 1.3\nangle = 30\naxis = 1 1 0\n", 6),
    # antialias = edge: silhouette triangles in the coverage fills, whose grown boxes and moved-out
    # edge functions are stepped to hart 1's band like the others (the filtered one keeps the
    # pixel's coverage on the stack; Gouraud's k clamped)
    "edge": (MODEL, TEXTURE, BIG + "antialias = edge\nfilter = bilinear\nshading = gouraud\n", 3),
    # antialias = supersample: each hart draws its band once per sample, sums and resolves it
    "supersample": (MODEL, TEXTURE, "antialias = supersample\nfilter = mipmap\n", 3),
    # shading = phong: the normal's planes at hart 1's first row (each fill finds them from the rows
    # above, PHONG_ROW), in the nearest-texel fills (flat) and the filtered ones; the normals turned
    # in two shares (normals_phong)
    "phong-flat": (MODEL, TEXTURE, BIG + "mode = flat\nshading = phong\n", 3),
    "phong-filtered": (MODEL, TEXTURE, BIG + "shading = phong\nfilter = bilinear\nantialias = edge\n", 3),
    # the vertex stage in two shares of unequal cost: each hart waits for the other's share
    "race-hart1-early": (race_grid(0), TEXTURE, RACE_KEYS, 3),
    "race-hart0-early": (race_grid(1), TEXTURE, RACE_KEYS, 3),
}


def hart1_instructions(out: Path) -> list[int]:
    """Hart 1's instructions in each shown frame (run.json)."""
    summary = json.loads((out / "run.json").read_text())
    return [frame["instructions"][1] for frame in summary["frames"]]


@pytest.fixture(scope="module")
def runs(firmware, tmp_path_factory):
    """Each scene with harts = 1 and harts = 2, and the plain one with the default (auto): made
    once for all xdist workers."""
    def make(folder: Path) -> dict:
        jobs = {(name, harts): functools.partial(run_scene, firmware, folder / f"{name}-{harts}", model,
                                                 keys + f"harts = {harts}\n", texture=texels, frames=frames)
                for name, (model, texels, keys, frames) in SCENES.items() for harts in ("1", "2")}
        jobs["plain", "auto"] = functools.partial(run_scene, firmware, folder / "plain-auto", MODEL, BIG,
                                                  texture=TEXTURE, frames=FRAMES)
        return run_together(jobs)
    return shared_value(tmp_path_factory, "both_harts_runs", make)


@pytest.mark.parametrize("name", SCENES)
def test_two_harts_draw_the_frames_one_hart_draws(runs, name):
    """harts = 2 shows the frames of harts = 1 bit for bit, with hart 1 drawing a band of every
    frame after the first (and not drawing with harts = 1)."""
    one, two = runs[name, "1"], runs[name, "2"]
    assert one.returncode == 0 and two.returncode == 0, (one.stderr, two.stderr)
    for n in range(len(one.frames)):
        differ = np.any(one.frames[n] != two.frames[n], axis=2)
        assert not differ.any(), (f"{name}: frame {n} differs in {int(differ.sum())} pixels, rows "
                                  f"{sorted(set(np.nonzero(differ)[0].tolist()))[:10]}...")
    assert max(hart1_instructions(one.out)[1:]) < HART1_IDLE_MAX, "harts = 1: hart 1 drew"
    assert min(hart1_instructions(two.out)[1:]) > (HART1_DRAWING_MIN if name != "cube" else HART1_IDLE_MAX), \
        "harts = 2: hart 1 did not draw"
    # the scene is not empty: the split is tested on pixels that are drawn
    assert (one.frames[2] != one.frames[2][0, 0]).any(axis=2).mean() > 0.15


def test_auto_draws_on_both_harts_when_drawing_is_slower_than_the_lcd(runs):
    """auto, the default: on the screen-filling sphere hart 0 alone is slower than the LCD's
    transfer, so hart 1 draws from frame 2 on (frame 1 is hart 0's alone too: auto decides from
    the frame before, and frame 0 is always hart 0's), and the frames are the same."""
    auto = runs["plain", "auto"]
    assert auto.returncode == 0, auto.stderr
    assert all(np.array_equal(a, b) for a, b in zip(auto.frames, runs["plain", "1"].frames, strict=True))
    assert min(hart1_instructions(auto.out)[2:]) > HART1_DRAWING_MIN


def test_auto_leaves_the_default_card_to_hart_0(firmware_run):
    """The default card draws far faster than the LCD takes a frame: hart 1 only sends frames."""
    _, out, summary = firmware_run
    assert summary is not None
    assert max(hart1_instructions(out)[1:]) < HART1_IDLE_MAX


@pytest.mark.parametrize("value, accepted", [("auto", True), ("1", True), ("2", True), ("AUTO", True),
                                             ("3", False), ("two", False), ("0", False)])
def test_harts_key_host_and_firmware_agree(firmware, tmp_path, value, accepted):
    """The card builder's reader takes exactly the values the firmware takes, and refuses the
    others with the firmware's message (error 9)."""
    refusal = None if accepted else "bad scene.ini line 2: bad value (expected auto, 1 or 2)"
    check_scene_key_agreement(firmware, tmp_path, "harts", value, refusal)


def test_a_silhouette_fringe_below_the_split_is_drawn_by_hart_1(firmware, tmp_path):
    """antialias = edge: a quad's bottom edge 0.2 pixel below the first split row's top (row 120,
    where frame 1 splits): no pixel centre of the quad lies in hart 1's band, but row 120 is
    covered a fifth by the edge's half-pixel reach, so hart 1 must not skip the quad (render.S
    grows the band test by half a pixel as raster_triangle grows the box): frames the same."""
    # fov 90 at z = -1: 120 pixels a unit; y = -0.2 / 120 is screen row 120.2
    quad = "v -0.5 -0.0016667 -1\nv 0.5 -0.0016667 -1\nv 0.5 0.5 -1\nv -0.5 0.5 -1\nf 1 2 3 4\n"
    keys = "mode = flat\nfov = 90\ntranslate = 0 0 0\nstep = 0\nantialias = edge\n"
    one, two = (run_scene(firmware, tmp_path / harts, quad, keys + f"harts = {harts}\n", frames=2)
                for harts in ("1", "2"))
    assert one.returncode == 0 and two.returncode == 0, (one.stderr, two.stderr)
    assert np.any(one.frames[1][120] != one.frames[1][121])           # the fringe is there
    assert np.array_equal(one.frames[1], two.frames[1])


def test_both_harts_turns_run_in_c_as_the_scheduler_runs_them_one_by_one(firmware, tmp_path):
    """While both harts draw, the scheduler runs their turns in C between device events
    (Scheduler._go_on_paired): every frame's time, both harts' instructions and cycles, their
    mispredictions and stalls, and the pixels are those of the same turns run one at a time."""
    from emulator.board.dock import Board
    card = make_card(tmp_path, {"/model.obj": MODEL.encode(), "/texture.ppm": TEXTURE,
                                "/scene.ini": (BIG + "harts = 2\n").encode()})
    seen = {}
    for pairing in (False, True):
        images: list[np.ndarray] = []
        board = Board(str(firmware), sd_image=str(card), on_frame=lambda record, image: images.append(image.copy()))
        board.scheduler.pairing = pairing
        try:
            board.run(FRAMES)
        finally:
            board.close()
        seen[pairing] = ([(f.virtual_time_s, f.instructions, f.cycles) for f in board.frames], images,
                         [(h.executed, h.cycles, h.mispredicts, h.stall_cycles) for h in board.harts],
                         board.scheduler.paired_turns)
    alone, paired = seen[False], seen[True]
    assert alone[3] == 0 and paired[3] > 100                  # the turns ran in C, hundreds of them
    assert paired[0] == alone[0] and paired[2] == alone[2]
    assert len(paired[1]) == len(alone[1]) == FRAMES
    assert all(np.array_equal(a, b) for a, b in zip(alone[1], paired[1]))


def test_both_harts_turns_in_c_stop_where_run_until_and_grabs_do(firmware, tmp_path):
    """The turns run in C end where a run_until slice ends and where a grab is due, as the turns run
    one by one do: after each slice, and at each grab, both harts have run the same instructions and
    cycles either way."""
    from emulator.board.dock import Board
    from emulator.vtime import PS_PER_MS
    card = make_card(tmp_path, {"/model.obj": MODEL.encode(), "/texture.ppm": TEXTURE,
                                "/scene.ini": (BIG + "harts = 2\n").encode()})
    seen = {}
    for pairing in (False, True):
        board = Board(str(firmware), sd_image=str(card))
        board.scheduler.pairing = pairing
        counts = []
        try:
            board.run(2)
            start = board.scheduler.time
            for n in range(1, 9):    # grabs every 0.37 ms, between slices ending every 0.73 ms
                board.grab_at(start + n * 37 * PS_PER_MS // 100, lambda b: counts.append(
                    ("grab", [(h.executed, h.cycles) for h in b.harts])))
            for n in range(1, 6):
                board.run_until(start + n * 73 * PS_PER_MS // 100)
                counts.append(("slice", [(h.executed, h.cycles) for h in board.harts]))
        finally:
            board.close()
        seen[pairing] = (counts, board.scheduler.paired_turns)
    assert seen[True][1] > 0
    assert seen[True][0] == seen[False][0]
