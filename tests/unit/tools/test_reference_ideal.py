"""The ideal image (reference/ideal.py): analytic cases of area averaging and texture filtering,
its agreement with the pixel-centre renderer where the two must agree, and its convergence on a
bench scene. Small regions and single frames keep it to a few seconds."""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from emulator_runs import run_module
from reference import Mesh, Scene, load_card_image, render_frame, render_image
from reference.ideal import (BoxTexture, SmoothTexture, channels, ideal_channels, line_coverage,
                             render_ideal_frame, render_ideal_image)
from reference.obj import parse_obj
from reference.render import bilinear
from reference.scene import parse_scene

BG = 0x0000
GREY = np.array([24.0, 48.0, 24.0])          # 0xC618, the flat colour, lit by 1


def _scene(**keys) -> Scene:
    base = dict(mode="flat", cull=False, step=0.0, translate=(0.0, 0.0, 0.0), ambient=1.0, background=BG)
    base.update(keys)
    return Scene(**base)


def _mesh(vertices, faces, texcoords=None) -> Mesh:
    """A mesh whose corners use the vt of their vertex's own index (when given), no normals."""
    faces = np.array([[[v, -1 if texcoords is None else v, -1] for v in f] for f in faces],
                     dtype=np.int64).reshape(-1, 3, 3)
    return Mesh(np.array(vertices, float), np.array(texcoords if texcoords is not None else [], float).reshape(-1, 2),
                np.zeros((0, 3)), faces)


def _to_world(sx, sy, z, fov=60.0):
    """The world point at depth z (< 0) that projects to screen (sx, sy)."""
    f = 1.0 / math.tan(math.radians(fov) / 2)
    w = -z
    return ((sx / 160.0 - 1.0) * w * (4 / 3) / f, (1.0 - sy / 120.0) * w / f, z)


def _screen_triangles(triangles, z=-2.0):
    """A mesh of face-on triangles given by their screen corners (all at depth z, so that the
    projection is a scale and the corners land where given, to rounding)."""
    vertices, faces = [], []
    for tri in triangles:
        faces.append(tuple(range(len(vertices), len(vertices) + 3)))
        vertices += [_to_world(x, y, z) for x, y in tri]
    return _mesh(vertices, faces)


def _clipped_area(square, a, b) -> float:
    """Area of the unit square at `square` (x, y) on the left of the directed line a -> b
    (y down: (b - a) x (p - a) >= 0), by Sutherland-Hodgman and the shoelace formula."""
    x, y = square
    polygon = [(x, y), (x + 1, y), (x + 1, y + 1), (x, y + 1)]

    def side(p):
        return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])

    out = []
    for i, p in enumerate(polygon):
        q = polygon[(i + 1) % len(polygon)]
        if side(p) >= 0:
            out.append(p)
        if (side(p) >= 0) != (side(q) >= 0):
            t = side(p) / (side(p) - side(q))
            out.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    return 0.5 * abs(sum(p[0] * q[1] - q[0] * p[1] for p, q in zip(out, out[1:] + out[:1], strict=True)))


# --------------------------------------------------------------------------- edges

@pytest.mark.parametrize("density", [2, 8, 16])
def test_a_pixel_half_covered_by_an_edge_through_its_centre_is_exactly_half_blended(density):
    """The sample grid is symmetric about the pixel's centre, so a line through the centre (with
    a slope no sample lies on) leaves exactly half of the samples on each side."""
    centre = (160.5, 120.5)
    slope = math.sqrt(2) / 4.5
    a = (centre[0] - 100, centre[1] - 100 * slope)
    b = (centre[0] + 100, centre[1] + 100 * slope)
    mesh = _screen_triangles([(a, b, (60.0, 230.0))])
    pixels = ideal_channels(_scene(), mesh, None, 0, density=density, region=(158, 118, 163, 123))
    assert np.array_equal(pixels[2, 2], GREY / 2)
    frame = render_ideal_frame(_scene(), mesh, None, 0, density=density, region=(158, 118, 163, 123))
    assert frame[2, 2] == (12 << 11) | (24 << 5) | 12
    assert np.array_equal(pixels[4, 0], GREY) and np.array_equal(pixels[0, 4], [0, 0, 0])


@pytest.mark.parametrize("density", [8, 32])
def test_pixels_crossed_by_an_edge_are_blended_by_their_covered_area(density):
    """Each pixel crossed by a straight edge is blended by the area of it the triangle covers,
    within 1 / density: in each of the density columns of samples the covered samples stand for
    the covered height to half a sample (1 / (2 density)), and where the edge leaves the pixel
    through its top or bottom inside a column the column's midpoint misjudges at most another
    half sample."""
    rng = np.random.default_rng(12)
    for _ in range(6):
        a = (float(rng.uniform(20, 60)), float(rng.uniform(20, 220)))
        b = (float(rng.uniform(260, 300)), float(rng.uniform(20, 220)))
        c = (160.0, 239.9) if rng.uniform() < 0.5 else (160.0, 0.1)
        if (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0:
            a, b = b, a                        # c on the left of a -> b: the triangle's side
        mesh = _screen_triangles([(a, b, c)])
        x = 160
        y = int((a[1] + (x + 0.5 - a[0]) * (b[1] - a[1]) / (b[0] - a[0])))
        pixels = ideal_channels(_scene(), mesh, None, 0, density=density, region=(x - 3, y - 3, x + 4, y + 4))
        for dy in range(-3, 4):
            for dx in range(-3, 4):
                area = _clipped_area((x + dx, y + dy), a, b)
                coverage = pixels[dy + 3, dx + 3] / GREY
                assert np.allclose(coverage, coverage[0])
                assert abs(coverage[0] - area) <= 1.0 / density, (dx, dy, area, coverage[0])


def test_a_sliver_and_sub_pixel_triangles_contribute_their_area():
    """A triangle seen nearly edge-on (200 pixels long, at most 0.3 wide) and sub-pixel triangles
    scattered over the screen: the pixel-centre image shows them as dashes and specks of whole
    pixels, the ideal one spreads each over the pixels it touches, its total the triangle's area:
    within 2 % for the sliver at the default density; the specks (0.04 pixels each on average,
    a few samples) within 1 % in total at 32 x 32 samples (one run: 8 x 8 -3.5 %, 16 x 16
    +2.5 %, 32 x 32 -0.02 %). A triangle exactly edge-on (collinear corners) draws nothing."""
    sliver = ((40.2, 100.3), (240.7, 131.9), (40.2, 100.6))
    area = 0.5 * 0.3 * (240.7 - 40.2)
    mesh = _screen_triangles([sliver])
    ideal = ideal_channels(_scene(), mesh, None, 0, region=(30, 90, 250, 140))
    assert ideal[..., 1].sum() / 48.0 == pytest.approx(area, rel=0.02)
    assert ideal[..., 1].max() < 48.0 * 0.5                       # nowhere a whole pixel
    assert (ideal[..., 1] > 0).sum() > 4 * area
    dashes = render_frame(_scene(), mesh, None, 0)                # whole pixels, one in seven or so
    assert 0 < (dashes != BG).sum() < 2 * area and set(np.unique(dashes)) == {BG, 0xC618}
    rng = np.random.default_rng(4)
    specks = []
    for k in range(40):
        x, y = 20 + 7 * k + 0.1, 60.1 + 3 * (k % 9)
        specks.append(tuple((x + float(u), y + float(v)) for u, v in rng.uniform(0, 0.8, (3, 2))))
    areas = sum(0.5 * abs((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])) for a, b, c in specks)
    ideal = ideal_channels(_scene(), _screen_triangles(specks), None, 0, density=32, region=(0, 55, 320, 90))
    assert ideal[..., 1].sum() / 48.0 == pytest.approx(areas, rel=0.01)
    edge_on = _screen_triangles([((50.0, 50.0), (150.0, 100.0), (250.0, 150.0))])
    assert np.all(render_ideal_frame(_scene(), edge_on, None, 0) == BG)


def test_closed_meshes_and_shared_edges_leave_no_seam():
    """Two triangles sharing an edge, the same colour: every sample is covered once (top-left
    rule per sample), so the pixels along the shared diagonal are whole, not blended twice or
    left short."""
    square = ((50.3, 40.7), (150.9, 40.7), (150.9, 140.2), (50.3, 140.2))
    a, b, c, d = square
    mesh = _screen_triangles([(a, b, c), (a, c, d)])
    pixels = ideal_channels(_scene(), mesh, None, 0, region=(40, 30, 160, 150))
    assert np.array_equal(pixels[12:109, 12:109], np.broadcast_to(GREY, (97, 97, 3)))


# --------------------------------------------------------------------------- textures

CHECKER = np.array([[0x0000, 0xFFFF], [0xFFFF, 0x0000]], dtype=np.uint16)
MEAN = np.array([15.5, 31.5, 15.5])


def _textured_quad(corners, uv, z=-2.0) -> Mesh:
    return _mesh([_to_world(x, y, z) for x, y in corners], [(0, 1, 2), (0, 2, 3)], texcoords=uv)


def test_a_minified_checkerboard_averages_to_its_mean_grey():
    """A face-on square of 64 x 64 pixels, turned 30 degrees in texture space and minified to 37.3
    texels a pixel: each pixel's footprint is a square of 37.3 texels a side, whose texels cancel
    in pairs but for those its edges cut, at most 4 x 37.3 + 4 of 37.3^2: each channel within
    (4 / 37.3 + 4 / 37.3^2) of the black-to-white amplitude from the mean grey. The pixel-centre
    image there is black and white only."""
    rate = 37.3 / 2                          # checker periods (2 texels) per pixel
    turn = math.radians(30)
    corners = [(100.0, 164.0), (164.0, 164.0), (164.0, 100.0), (100.0, 100.0)]

    def uv(x, y):
        dx, dy = (x - 100.0) * rate, (164.0 - y) * rate
        return (math.cos(turn) * dx - math.sin(turn) * dy, math.sin(turn) * dx + math.cos(turn) * dy)

    mesh = _textured_quad(corners, [uv(x, y) for x, y in corners])
    scene = _scene(mode="textured")
    ideal = ideal_channels(scene, mesh, CHECKER, 0, region=(101, 101, 163, 163))
    bound = (4 / 37.3 + 4 / 37.3 ** 2) * MEAN
    assert np.all(np.abs(ideal - MEAN) <= bound)
    assert np.abs(ideal.mean(axis=(0, 1)) - MEAN).max() < 0.1
    centres = render_frame(scene, mesh, CHECKER, 0)[101:163, 101:163]
    assert set(np.unique(centres)) == {0x0000, 0xFFFF}


def test_a_checkerboard_floor_turns_grey_towards_the_horizon():
    """A floor 1 unit below the camera reaching 200 units away, 4000 checker texels a side over
    200 units: rows near the horizon see tens to hundreds of texels a pixel, and the ideal image
    is within 1 level (of 31 and 63) of the mean grey there, where the pixel-centre image is
    black and white noise."""
    floor = [(-100.0, -1.0, -1.0), (100.0, -1.0, -1.0), (100.0, -1.0, -200.0), (-100.0, -1.0, -200.0)]
    repeats = 2000.0
    mesh = _mesh(floor, [(0, 1, 2), (0, 2, 3)], texcoords=[(0, 0), (repeats, 0), (repeats, repeats), (0, repeats)])
    scene = _scene(mode="textured", far=1000.0)
    rows = (122, 127)                         # the horizon (200 units away) is at row 121.04
    ideal = ideal_channels(scene, mesh, CHECKER, 0, region=(0, rows[0], 320, rows[1]))
    assert np.all(np.abs(ideal - MEAN) <= [1.0, 2.0, 1.0])
    centres = render_frame(scene, mesh, CHECKER, 0)[rows[0]:rows[1]]
    assert set(np.unique(centres)) == {0x0000, 0xFFFF}


def test_a_texture_mapped_one_to_one_comes_back_unchanged():
    """Texels on pixels: every sample's footprint lies in its pixel's texel, so the ideal image is
    the texture itself, as the pixel-centre image is."""
    rng = np.random.default_rng(1)
    tw, th, x0, y0 = 37, 23, 101, 57
    texture = rng.integers(0, 65536, (th, tw)).astype(np.uint16)
    corners = [(x0, y0 + th), (x0 + tw, y0 + th), (x0 + tw, y0), (x0, y0)]
    mesh = _textured_quad(corners, [(0, 0), (1, 0), (1, 1), (0, 1)], z=-1.7)
    frame = render_ideal_frame(_scene(mode="textured", cull=True), mesh, texture, 0)
    assert np.array_equal(frame[y0:y0 + th, x0:x0 + tw], texture)
    mask = np.ones(frame.shape, bool)
    mask[y0:y0 + th, x0:x0 + tw] = False
    assert np.all(frame[mask] == BG)


def test_a_magnified_texture_equals_the_nearest_texel_inside_texels_and_blends_across_them():
    """4.37 pixels a texel: a pixel inside one texel is that texel, as in the pixel-centre image;
    a pixel across a texel boundary lies between the texels on either side of it, in proportion
    to the areas (within the sample grid's 1 / density)."""
    rng = np.random.default_rng(7)
    texture = rng.integers(0, 65536, (6, 9)).astype(np.uint16)
    scale = 4.37
    x0, y0 = 70.0, 60.0
    corners = [(x0, y0 + 6 * scale), (x0 + 9 * scale, y0 + 6 * scale), (x0 + 9 * scale, y0), (x0, y0)]
    mesh = _textured_quad(corners, [(0, 0), (1, 0), (1, 1), (0, 1)])
    scene = _scene(mode="textured")
    ideal = ideal_channels(scene, mesh, texture, 0, region=(70, 60, 110, 87))
    centres = render_frame(scene, mesh, texture, 0)
    texels = channels(texture)
    inside = across = 0
    for py in range(60, 86):
        for px in range(70, 109):
            left, right = (px - x0) / scale, (px + 1 - x0) / scale
            top, bottom = (py - y0) / scale, (py + 1 - y0) / scale
            if not (0 <= left and right <= 9 and 0 <= top and bottom <= 6):
                continue
            value = ideal[py - 60, px - 70]
            if math.floor(left) == math.floor(right - 1e-9) and math.floor(top) == math.floor(bottom - 1e-9):
                assert np.allclose(value, channels(int(centres[py, px])), rtol=0, atol=1e-9)
                inside += 1
            elif math.floor(top) == math.floor(bottom - 1e-9):
                column, row = math.floor(left), math.floor(top)
                share = (column + 1 - left) / (right - left)
                expected = share * texels[row, column] + (1 - share) * texels[row, column + 1]
                assert np.all(np.abs(value - expected) <= np.abs(texels[row, column] - texels[row, column + 1]) / 8 + 1e-9)
                across += 1
    assert inside > 300 and across > 50


def test_box_filter_matches_a_texel_by_texel_sum():
    """BoxTexture.average against the overlap of the rectangle with each texel, summed one by one:
    footprints within 2 x 2 texels, wider ones (summed-area table), zero and tiny sides, negative
    and repeated coordinates; and far beyond the texture's size, its mean."""
    rng = np.random.default_rng(0)
    texture = rng.integers(0, 65536, (5, 7)).astype(np.uint16)
    box = BoxTexture(texture)
    texels = channels(texture)

    def weights(low, high):
        if high == low:
            return {math.floor(low): 1.0}
        return {c: (min(high, c + 1) - max(low, c)) / (high - low)
                for c in range(math.floor(low), math.ceil(high)) if min(high, c + 1) > max(low, c)}

    def by_texels(cx, cy, hx, hy):
        total = np.zeros(3)
        for c, wx in weights(cx - hx, cx + hx).items():
            for r, wy in weights(cy - hy, cy + hy).items():
                total += wx * wy * texels[r % 5, c % 7]
        return total

    sides = [0.0, 1e-9, 0.2, 0.5, 0.9, 1.3, 4.7, 20.3]
    cx, cy = rng.uniform(-50, 50, 300), rng.uniform(-50, 50, 300)
    hx, hy = rng.choice(sides, 300), rng.choice(sides, 300)
    expected = np.array([by_texels(*args) for args in zip(cx, cy, hx, hy, strict=True)])
    assert np.abs(box.average(cx, cy, hx, hy) - expected).max() < 1e-9
    far = box.average(np.array([1e30, -1e20]), np.array([5.0, 2e15]), np.array([1e25, 1e18]), np.array([1e25, 1e18]))
    assert np.allclose(far, texels.mean(axis=(0, 1)), atol=1e-6)


def test_smooth_texels_are_the_bilinear_surface_averaged_over_the_footprint():
    """SmoothTexture.average (texels = "smooth", a camera's view of a filtered texture) against the
    bilinear surface through the texel centres (render.bilinear) averaged numerically over each
    rectangle (a 600 x 600 midpoint grid: within 5e-4 of a channel step); a footprint of no size is
    the bilinear sample itself, exactly; and far beyond the texture's size, its mean."""
    rng = np.random.default_rng(4)
    texture = rng.integers(0, 65536, (5, 7)).astype(np.uint16)
    smooth = SmoothTexture(texture)

    def numerically(cx, cy, hx, hy, n=600):
        xs = cx + ((np.arange(n) + 0.5) / n * 2 - 1) * hx if hx > 0 else np.array([cx])
        ys = cy + ((np.arange(n) + 0.5) / n * 2 - 1) * hy if hy > 0 else np.array([cy])
        grid_x, grid_y = np.meshgrid(xs, ys)
        return bilinear(texture, grid_x.ravel(), grid_y.ravel()).mean(axis=0)

    sides = [0.0, 0.2, 0.5, 0.9, 1.3, 4.7, 11.5]
    for _ in range(60):
        cx, cy = rng.uniform(-30, 30, 2)
        hx, hy = rng.choice(sides, 2)
        got = smooth.average(np.array([cx]), np.array([cy]), np.array([hx]), np.array([hy]))[0]
        assert np.abs(got - numerically(cx, cy, hx, hy)).max() < 5e-4, (cx, cy, hx, hy)
    cx, cy = rng.uniform(-30, 30, 200), rng.uniform(-30, 30, 200)
    zero = np.zeros(200)
    assert np.abs(smooth.average(cx, cy, zero, zero) - bilinear(texture, cx, cy)).max() < 1e-9
    far = smooth.average(np.array([1e30, -1e20]), np.array([5.0, 2e15]), np.array([1e25, 1e18]), np.array([1e25, 1e18]))
    assert np.allclose(far, channels(texture).mean(axis=(0, 1)), atol=1e-6)


def test_the_smooth_ideal_of_a_magnified_texture_is_bilinear_and_of_a_minified_one_the_square_ideal():
    """Near, each of 256 x 256 texels about a pixel wide, the smooth ideal shows the texture blended
    between texel centres where the square one shows hard texel edges (they differ); far away, a
    sample's footprint covers a dozen texels and the two ideals agree within a channel step."""
    texture = np.random.default_rng(9).integers(0, 65536, (256, 256)).astype(np.uint16)
    mesh = parse_obj(b"v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\n"
                     b"vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
    for translate, expect_equal in (("0 0 -0.8", False), ("0 0 -40", True)):
        scene = parse_scene(f"mode = textured\ncull = off\nambient = 1\nstep = 0\nangle = 20\naxis = 1 0 0\n"
                            f"translate = {translate}\n")
        square = ideal_channels(scene, mesh, texture, 0, density=4)
        smooth = ideal_channels(scene, mesh, texture, 0, density=4, texels="smooth")
        difference = np.abs(square - smooth).max()
        assert (difference < 1.0) == expect_equal, (translate, difference)
    with pytest.raises(ValueError, match="texels must be one of square, smooth"):
        ideal_channels(scene, mesh, texture, 0, density=1, texels="round")


# --------------------------------------------------------------------------- lines

def test_a_line_is_one_pixel_wide_with_round_ends():
    """A horizontal segment on a row's centre line covers that row fully between its ends and
    nothing of the rows beside; on a pixel boundary it covers half of each row; its total is
    length x 1 + the two half discs (pi / 4). A white line blends with the background by it."""
    a, b = np.array([50.5, 100.5]), np.array([150.5, 100.5])
    coverage = line_coverage([(a, b)], (40, 90, 170, 110), 128)
    assert np.allclose(coverage[10, 11:110], 1.0) and np.allclose(coverage[9, 11:110], 0.0)
    assert coverage.sum() == pytest.approx(100 + math.pi / 4, abs=2e-3)
    coverage = line_coverage([(a - [0, 0.5], b - [0, 0.5])], (40, 90, 170, 110), 128)
    assert np.allclose(coverage[9:11, 11:110], 0.5)
    crossing = line_coverage([(a, b), (np.array([100.5, 60.5]), np.array([100.5, 140.5]))], (40, 50, 170, 150), 128)
    assert crossing.max() <= 1.0 + 1e-12 and crossing[50, 60] == pytest.approx(1.0)
    assert crossing.sum() == pytest.approx(100 + 80 - 1 + 2 * math.pi / 4, abs=5e-3)   # the cross counted once
    scene = _scene(mode="wireframe", background=0x0000)
    mesh = _screen_triangles([((50.5, 100.5), (150.5, 100.5), (100.5, 30.5))])
    frame = render_ideal_frame(scene, mesh, None, 0)
    assert frame[100, 100] == 0xFFFF and frame[102, 100] == BG


def test_line_coverage_matches_dense_sampling():
    """Segments at random angles, some overlapping, some leaving the region: the coverage exact
    along 128 rows a pixel against 128 x 128 samples a pixel on the same rows, which misplace
    each end of a row's crossing by at most half a sample: within 1 / 128 a pixel."""
    rng = np.random.default_rng(3)
    size = 12
    segments = [(rng.uniform(-3, size + 3, 2), rng.uniform(-3, size + 3, 2)) for _ in range(5)]
    segments.append((np.array([3.3, 3.3]), np.array([3.3, 3.3])))          # a dot: a disc
    region = (0, 0, size, size)
    fine = 128
    ys, xs = (np.mgrid[0:size * fine, 0:size * fine] + 0.5) / fine
    inside = np.zeros(xs.shape, bool)
    for a, b in segments:
        d = b - a
        t = np.clip(((xs - a[0]) * d[0] + (ys - a[1]) * d[1]) / max(d @ d, 1e-300), 0, 1)
        inside |= (xs - a[0] - t * d[0]) ** 2 + (ys - a[1] - t * d[1]) ** 2 <= 0.25
    dense = inside.reshape(size, fine, size, fine).mean(axis=(1, 3))
    assert np.abs(line_coverage(segments, region, 128) - dense).max() < 1 / 128


# --------------------------------------------------------------------------- whole scenes

@pytest.fixture(scope="module")
def cards(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("ideal-cards")


def _card(assets: Path, cards: Path, **keys) -> tuple:
    from sdcard_image import build_image
    card = cards / "card.img"
    build_image(card, [assets / "models", assets / "textures"], scene=keys, force=True, on_warning=lambda _: None)
    return load_card_image(card)


def test_at_one_sample_a_pixel_flat_mode_is_the_pixel_centre_image(assets, cards):
    """With one sample at each pixel's centre the ideal image is the pixel-centre image wherever
    textures are not involved: the same triangles, near-plane cut, culling, depth order, Phong
    lighting (the torus has smooth normals) and rounding."""
    scene, mesh, texture = _card(assets, cards, model="models/torus.obj", texture="textures/torus.ppm", mode="flat",
                                 translate="0 0.1 -0.75", near="0.5", axis="1 0.6 0.2", angle="40",
                                 light="0.3 0.5 1", ambient="0.2")
    frame = render_frame(scene, mesh, texture, 0)
    assert (frame != scene.background).mean() > 0.3
    assert np.array_equal(render_ideal_frame(scene, mesh, texture, 0, density=1), frame)
    assert not np.array_equal(render_ideal_frame(replace(scene, cull=False), mesh, texture, 0, density=1),
                              frame)


def _psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = float(((a.astype(float) - b.astype(float)) ** 2).mean())
    return math.inf if mse == 0 else 10 * math.log10(255 ** 2 / mse)


def test_the_ideal_image_has_converged_at_the_default_density(assets, cards):
    """The bench's gem (tools/bench.py: scale 0.9, translate 0 0 -3, angle 17, step 3), textured,
    frame 0, over the gem's bounding box: 8 x 8 samples against 16 x 16 differ by an RMS below
    1 / 316 of full scale (PSNR above 50 dB; over the whole frame one run measured 60.3 dB,
    docs/reference/reference-renderer.md), at least 10 dB closer than the pixel-centre image is to either."""
    scene, mesh, texture = _card(assets, cards, model="models/gem.obj", texture="textures/gem.ppm", mode="textured",
                                 scale="0.9", translate="0 0 -3", angle="17", step="3")
    box = (100, 62, 219, 178)                  # the gem's pixels in frame 0, and a pixel more
    eight = render_ideal_image(scene, mesh, texture, 0, density=8, region=box)
    sixteen = render_ideal_image(scene, mesh, texture, 0, density=16, region=box)
    centres = render_image(scene, mesh, texture, 0)[box[1]:box[3], box[0]:box[2]]
    assert np.all(centres[0] == centres[0, 0]) and np.all(centres[:, -1] == centres[0, 0])
    converged = _psnr(eight, sixteen)
    assert converged > 50
    assert converged > _psnr(eight, centres) + 10


def test_cli_renders_the_ideal_and_refuses_a_bad_density(tmp_path):
    folder = tmp_path / "card"
    folder.mkdir()
    (folder / "scene.ini").write_text("mode = flat\ncull = off\n")
    (folder / "model.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n")
    for extra, out in (([], "centres"), (["--ideal", "--density", "4"], "ideal")):
        result = run_module("reference", "render", folder, "--out", tmp_path / out, "--quiet", *extra)
        assert result.returncode == 0, result.stderr
    centres, ideal = (np.asarray(Image.open(tmp_path / out / "frame_0000.png")) for out in ("centres", "ideal"))
    assert 0 < np.any(centres != ideal, axis=2).mean() < 0.05            # the triangle's edges
    for extra, message in ((["--ideal", "--density", "65"], "--density must be from 1 to 64"),
                           (["--density", "4"], "--density applies only with --ideal"),
                           (["--texels", "smooth"], "--texels applies only with --ideal")):
        result = run_module("reference", "render", folder, "--out", tmp_path / "bad", *extra)
        assert result.returncode == 2 and message in result.stderr and "Traceback" not in result.stderr
