"""The reference renderer (reference/): analytic cases that must hold exactly, its parsers'
errors, and a loose agreement with the firmware's golden frames (a convention check)."""
from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest
from PIL import Image

from k210_common.exit_status import EXIT_BAD_INPUT

from golden_scenes import DEFAULT_CARD, GOLDEN, SCENES
from emulator_runs import run_module
from reference import (Mesh, ModelError, Scene, SceneError, TextureError, load_card_image,
                       load_files, parse_obj, parse_ppm, parse_scene, render_frame, render_ideal_frame,
                       render_image)
from reference.render import FLAT_COLOUR, Target, model_matrix, raster_triangle, shade

W, H = 320, 240
BG = 0x0000


def _scene(**keys) -> Scene:
    base = dict(mode="flat", cull=False, step=0.0, translate=(0.0, 0.0, 0.0), ambient=1.0, background=BG)
    base.update(keys)
    return Scene(**base)


def _mesh(vertices, faces, texcoords=None, normals=None) -> Mesh:
    """A mesh whose corners use the vt and vn of their vertex's own index (when given)."""
    faces = np.array([[[v, -1 if texcoords is None else v, -1 if normals is None else v] for v in f]
                      for f in faces], dtype=np.int64).reshape(-1, 3, 3)
    return Mesh(np.array(vertices, float), np.array(texcoords if texcoords is not None else [], float).reshape(-1, 2),
                np.array(normals if normals is not None else [], float).reshape(-1, 3), faces)


def _to_world(sx, sy, z, fov=60.0):
    """The world point at depth z (< 0) that projects to screen (sx, sy)."""
    f = 1.0 / math.tan(math.radians(fov) / 2)
    w = -z
    return ((sx / 160.0 - 1.0) * w * (4 / 3) / f, (1.0 - sy / 120.0) * w / f, z)


def _project(point, fov=60.0):
    f = 1.0 / math.tan(math.radians(fov) / 2)
    x, y, z = point
    return ((f / (4 / 3) * x / -z + 1) * 160.0, (1 - f * y / -z) * 120.0)


def _centres():
    return np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)


# --------------------------------------------------------------------------- coverage

def test_a_face_on_quad_covers_exactly_the_centres_inside_it():
    z = -2.0
    corners = [(-0.7, -0.3), (0.45, -0.3), (0.45, 0.55), (-0.7, 0.55)]
    mesh = _mesh([(x, y, z) for x, y in corners], [(0, 1, 2), (0, 2, 3)])
    frame = render_frame(_scene(), mesh, None, 0)
    left, bottom = _project((-0.7, -0.3, z))
    right, top = _project((0.45, 0.55, z))
    cx, cy = _centres()
    expected = (cx > left) & (cx < right) & (cy > top) & (cy < bottom)
    assert expected.sum() > 1000
    assert np.array_equal(frame != BG, expected)
    assert set(np.unique(frame[expected])) == {0xC618}


def _coverage(triangles):
    count = np.zeros((H, W), int)
    for tri in triangles:
        target = Target(BG)
        raster_triangle(target, np.array(tri, float), np.full(3, 0.5), np.ones(3), False, 0xFFFF)
        count += target.colour != BG
    return count


@pytest.mark.parametrize("left, top, right, bottom", [(10.5, 20.5, 90.5, 70.5),      # corners on centres
                                                       (30.0, 40.0, 130.0, 100.0),     # on pixel edges
                                                       (12.37, 8.91, 211.13, 199.71)])  # generic
def test_two_triangles_sharing_an_edge_cover_their_union_exactly_once(left, top, right, bottom):
    a, b, c, d = (left, top), (right, top), (right, bottom), (left, bottom)
    cx, cy = _centres()
    # the top-left rule on an axis-aligned rectangle: left and top edges in, right and bottom out
    expected = (cx >= left) & (cx < right) & (cy >= top) & (cy < bottom)
    for pair in ([(a, b, c), (a, c, d)], [(a, b, d), (b, c, d)], [(a, c, b), (c, a, d)]):
        count = _coverage(pair)
        assert count.max() == 1
        assert np.array_equal(count == 1, expected)


def test_a_fan_of_triangles_around_a_point_has_no_cracks_or_overlaps():
    rng = np.random.default_rng(5)
    centre = (160.5, 120.5)                               # on a pixel centre, shared by every triangle
    angles = np.sort(rng.uniform(0, 2 * np.pi, 11))
    rim = [(160.5 + 100 * np.cos(t), 120.5 + 100 * np.sin(t)) for t in angles]
    count = _coverage([(centre, rim[i], rim[(i + 1) % len(rim)]) for i in range(len(rim))])
    assert count.max() == 1
    # the union is the convex rim polygon: every centre strictly inside it is covered once
    cx, cy = _centres()
    inside = np.ones((H, W), bool)
    for i in range(len(rim)):
        (x0, y0), (x1, y1) = rim[i], rim[(i + 1) % len(rim)]
        inside &= (x1 - x0) * (cy - y0) - (y1 - y0) * (cx - x0) > 1e-9
    assert np.all(count[inside] == 1)


def test_back_faces_are_culled_and_front_faces_are_counter_clockwise():
    z = -2.0
    ccw = _mesh([(-0.5, -0.5, z), (0.5, -0.5, z), (0.0, 0.5, z)], [(0, 1, 2)])
    cw = _mesh([(-0.5, -0.5, z), (0.0, 0.5, z), (0.5, -0.5, z)], [(0, 1, 2)])
    assert (render_frame(_scene(cull=True), ccw, None, 0) != BG).sum() > 1000
    assert (render_frame(_scene(cull=True), cw, None, 0) != BG).sum() == 0
    assert np.array_equal(render_frame(_scene(cull=False), cw, None, 0),
                          render_frame(_scene(cull=False), ccw, None, 0))


def test_the_nearer_triangle_wins():
    far = [(-0.8, -0.8, -3.0), (0.8, -0.8, -3.0), (0.0, 0.8, -3.0)]
    near = [(-0.3, -0.3, -2.0), (0.3, -0.3, -2.0), (0.0, 0.3, -2.0)]
    for order in ([(0, 1, 2), (3, 4, 5)], [(3, 4, 5), (0, 1, 2)]):
        scene = _scene(light=(0.0, 0.6, 0.8), ambient=0.0)
        mesh = _mesh(far + near, order)
        frame = render_frame(scene, mesh, None, 0)
        # both faces lit the same; tell them apart by rendering the near one alone
        alone = render_frame(scene, _mesh(near, [(0, 1, 2)]), None, 0) != BG
        assert np.all(frame[alone] != BG)
        assert (frame != BG).sum() > alone.sum()


# --------------------------------------------------------------------------- texture and light

def test_a_texture_mapped_one_to_one_comes_back_unchanged():
    rng = np.random.default_rng(1)
    tw, th, x0, y0 = 37, 23, 101, 57
    texture = rng.integers(0, 65536, (th, tw)).astype(np.uint16)
    z = -1.7
    corners = [(x0, y0 + th), (x0 + tw, y0 + th), (x0 + tw, y0), (x0, y0)]   # screen: bottom-left first
    vertices = [_to_world(sx, sy, z) for sx, sy in corners]
    uv = [(0, 0), (1, 0), (1, 1), (0, 1)]
    mesh = _mesh(vertices, [(0, 1, 2), (0, 2, 3)], texcoords=uv)
    frame = render_frame(_scene(mode="textured", cull=True), mesh, texture, 0)
    assert np.array_equal(frame[y0:y0 + th, x0:x0 + tw], texture)
    mask = np.ones((H, W), bool)
    mask[y0:y0 + th, x0:x0 + tw] = False
    assert np.all(frame[mask] == BG)


def test_texture_coordinates_repeat():
    texture = np.arange(4 * 4, dtype=np.uint16).reshape(4, 4) + 1
    z = -1.0
    corners = [(40, 120), (120, 120), (120, 40), (40, 40)]
    vertices = [_to_world(sx, sy, z) for sx, sy in corners]
    once = _mesh(vertices, [(0, 1, 2), (0, 2, 3)], texcoords=[(0, 0), (1, 0), (1, 1), (0, 1)])
    twice = _mesh(vertices, [(0, 1, 2), (0, 2, 3)], texcoords=[(-1, 3), (1, 3), (1, 5), (-1, 5)])
    a = render_frame(_scene(mode="textured"), once, texture, 0)[40:120, 40:120]
    b = render_frame(_scene(mode="textured"), twice, texture, 0)[40:120, 40:120]
    assert np.array_equal(a.reshape(4, 20, 4, 20)[:, 0, :, 0], texture)     # 20 x 20 pixels a texel
    for y in (0, 40):
        for x in (0, 40):
            assert np.array_equal(b[y:y + 40, x:x + 40], a[::2, ::2])


@pytest.mark.parametrize("light, ambient", [((0.0, 0.0, 1.0), 0.2), ((0.0, 0.6, 0.8), 0.2),
                                            ((0.36, 0.48, 0.8), 0.9), ((0.0, 1.0, 0.0), 0.3),
                                            ((0.0, 0.0, -1.0), 0.25)])
def test_lighting_of_a_face_on_quad_is_max_of_ambient_and_n_dot_l(light, ambient):
    z = -2.0
    mesh = _mesh([(-0.5, -0.5, z), (0.5, -0.5, z), (0.5, 0.5, z), (-0.5, 0.5, z)], [(0, 1, 2), (0, 2, 3)])
    frame = render_frame(_scene(light=light, ambient=ambient), mesh, None, 0)
    intensity = max(ambient, light[2])                    # the face normal is +z
    expected = (int(math.floor(24 * intensity + 0.5)) << 11) | (int(math.floor(48 * intensity + 0.5)) << 5) \
        | int(math.floor(24 * intensity + 0.5))
    assert set(np.unique(frame[frame != BG])) == {expected}


def _unit(vector) -> np.ndarray:
    vector = np.asarray(vector, float)
    return vector / np.linalg.norm(vector)


def _dot3(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Dot products of 3-vectors along the last axis, summed x + y + z."""
    return u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1] + u[..., 2] * v[..., 2]


def _phong_lit(scene: Scene, world_corners, world_normals, sx: np.ndarray, sy: np.ndarray) -> np.ndarray:
    """0xC618 lit as the ideal does at screen points (sx, sy) of a triangle seen with the default
    camera: the ray through the point meets the triangle's plane at p; N = sum b_i n_i with b the
    barycentric coordinates of p in 3D (what perspective-correct interpolation computes), unit.
    One point per element of sx, sy (the same arithmetic as point by point, done at once)."""
    a, b, c = (np.asarray(p, float) for p in world_corners)
    sx, sy = np.asarray(sx, float), np.asarray(sy, float)
    ray = np.stack(np.broadcast_arrays(*_to_world(sx, sy, -1.0)), axis=-1)
    plane = np.cross(b - a, c - a)
    p = ray * ((plane @ a) / _dot3(ray, plane))[..., None]
    total = plane @ plane
    weights = [_dot3(np.cross(c - b, p - b), plane) / total, _dot3(np.cross(a - c, p - c), plane) / total,
               _dot3(np.cross(b - a, p - a), plane) / total]
    normal = sum(w[..., None] * np.asarray(n, float) for w, n in zip(weights, world_normals, strict=True))
    length = np.linalg.norm(normal, axis=-1)
    lit = _dot3(normal, np.array(scene.light)) / np.where(length == 0, 1.0, length)
    intensity = np.where(length == 0, scene.ambient, np.maximum(scene.ambient, lit))
    return shade(FLAT_COLOUR, intensity).astype(np.int64)


def test_a_model_without_normals_is_lit_per_face():
    """No vn: every face keeps its geometric normal's intensity (as before per-pixel lighting),
    here under a rotation and a non-uniform scale, in flat and textured mode."""
    roof = [(-0.6, -0.4, 0.3), (0.6, -0.4, 0.3), (0.6, 0.1, -0.2), (-0.6, 0.1, -0.2), (-0.6, 0.5, 0.35), (0.6, 0.5, 0.35)]
    faces = [(0, 1, 2), (0, 2, 3), (3, 2, 5), (3, 5, 4)]
    scene = _scene(translate=(0.0, 0.0, -2.5), axis=tuple(_unit((1, 0.5, 0.2))), angle=25.0, scale=(1.3, 0.8, 1.7),
                   light=tuple(_unit((-0.3, 0.5, 1.0))), ambient=0.15)
    world = (np.hstack([np.array(roof), np.ones((6, 1))]) @ model_matrix(scene, 0).T)[:, :3]
    uv = [(0.2, 0.2)] * 6
    texel = np.full((1, 1), 0x7BEF, dtype=np.uint16)
    flat = render_frame(scene, _mesh(roof, faces), None, 0)
    textured = render_frame(replace(scene, mode="textured"), _mesh(roof, faces, texcoords=uv), texel, 0)
    seen = 0
    for face in faces:
        alone = render_frame(scene, _mesh(roof, [face]), None, 0) != BG
        normal = _unit(np.cross(world[face[1]] - world[face[0]], world[face[2]] - world[face[0]]))
        intensity = max(scene.ambient, float(normal @ np.array(scene.light)))
        assert np.all(flat[alone] == int(shade(FLAT_COLOUR, intensity)))
        assert np.all(textured[alone] == int(shade(0x7BEF, intensity)))
        seen += alone.sum()
    assert seen == (flat != BG).sum() > 5000
    assert len(np.unique(flat[flat != BG])) == 2          # the two slopes of the roof


@pytest.mark.parametrize("mode", ["flat", "textured"])
def test_corner_normals_equal_to_the_face_normal_change_nothing(mode):
    """A flat (tilted) quad whose four vn all equal its face normal in model space renders as
    without vn: the normals go through R C (C the scale's cofactor matrix), which keeps them
    perpendicular to the scaled surface, so they stay equal to the world face normal."""
    quad = [(-0.5, -0.5, -0.15), (0.5, -0.5, -0.15), (0.5, 0.5, 0.15), (-0.5, 0.5, 0.15)]
    faces = [(0, 1, 2), (0, 2, 3)]
    normal = _unit(np.cross(np.subtract(quad[1], quad[0]), np.subtract(quad[2], quad[0])))
    uv = [(0, 0), (1, 0), (1, 1), (0, 1)]
    texture = np.random.default_rng(3).integers(0, 65536, (5, 7)).astype(np.uint16)
    scene = _scene(mode=mode, translate=(0.1, 0.0, -2.2), axis=tuple(_unit((1, 1, 0.3))), angle=-35.0,
                   scale=(1.5, 0.7, 2.0), light=tuple(_unit((-0.4, 0.6, 1.0))), ambient=0.1)
    without = render_frame(scene, _mesh(quad, faces, texcoords=uv), texture, 0)
    with_normals = render_frame(scene, _mesh(quad, faces, texcoords=uv, normals=[normal] * 4), texture, 0)
    assert (without != BG).sum() > 3000
    if mode == "flat":                                     # lit above ambient, not clamped
        assert set(np.unique(without[without != BG])) - {int(shade(FLAT_COLOUR, scene.ambient))}
    assert np.array_equal(with_normals, without)


def test_tilted_corner_normals_give_a_smooth_gradient():
    """A face-on quad whose left corners' normals lean left and right corners' lean right, lit
    from the right: the intensity rises steadily from left to right, every pixel as the
    interpolated, renormalised normal gives, and the corner pixels as their corners' normals."""
    z, left, right, top, bottom = -2.0, 60.0, 260.0, 50.0, 190.0
    corners = [(left, bottom), (right, bottom), (right, top), (left, top)]
    tilt = math.radians(40)
    lean_left, lean_right = (-math.sin(tilt), 0.0, math.cos(tilt)), (math.sin(tilt), 0.0, math.cos(tilt))
    normals = [lean_left, lean_right, lean_right, lean_left]
    scene = _scene(light=(math.sin(tilt), 0.0, math.cos(tilt)), ambient=0.1)
    vertices = [_to_world(sx, sy, z) for sx, sy in corners]
    frame = render_frame(scene, _mesh(vertices, [(0, 1, 2), (0, 2, 3)], normals=normals), None, 0)
    ys, xs = np.nonzero(frame != BG)
    assert (ys.min(), ys.max(), xs.min(), xs.max()) == (top, bottom - 1, left, right - 1)
    green = (frame[int(top):int(bottom), int(left):int(right)].astype(int) >> 5) & 63
    assert np.all(np.diff(green, axis=1) >= 0) and np.all(green == green[0])   # rises along x only
    assert green[0, 0] < 15 and green[0, -1] == 48                            # cos 80 and cos 0 of 48
    light = np.array(scene.light)
    for x in range(int(left), int(right)):                 # face-on: the interpolation is linear in x
        t = (x + 0.5 - left) / (right - left)
        normal = _unit((1 - t) * np.array(lean_left) + t * np.array(lean_right))
        expected = int(shade(FLAT_COLOUR, max(scene.ambient, float(normal @ light))))
        assert np.all(frame[int(top):int(bottom), x] == expected), x
    for x, corner_normal in ((int(left), lean_left), (int(right) - 1, lean_right)):
        for y in (int(top), int(bottom) - 1):
            exact = int(shade(FLAT_COLOUR, max(scene.ambient, float(np.dot(corner_normal, light)))))
            assert abs(((int(frame[y, x]) >> 5) & 63) - ((exact >> 5) & 63)) <= 1


@pytest.mark.parametrize("near", [0.1, 0.9])
def test_normals_are_interpolated_perspective_correctly_and_through_the_near_cut(near):
    """A triangle receding in depth with three different corner normals: every pixel is lit
    with the normal at the 3D point it sees (barycentric in 3D, as u and v are). With near =
    0.9 its nearest corner is behind the near plane: the cut carries the normals along."""
    a, b, c = (-0.6, -0.5, -0.7), (0.9, -0.4, -3.0), (-0.2, 0.7, -2.0)
    normals = [_unit((-0.5, -0.3, 1.0)), _unit((0.8, 0.1, 0.6)), _unit((0.0, 0.9, 0.4))]
    scene = _scene(near=near, light=tuple(_unit((0.3, 0.4, 1.0))), ambient=0.05)
    frame = render_frame(scene, _mesh([a, b, c], [(0, 1, 2)], normals=normals), None, 0)
    ys, xs = np.nonzero(frame != BG)
    assert len(ys) > 3000
    expected = _phong_lit(scene, (a, b, c), normals, xs + 0.5, ys + 0.5)
    assert np.array_equal(frame[ys, xs], expected)
    assert len(np.unique(frame[ys, xs])) > 20


def test_a_zero_normal_or_scale_gives_ambient_and_never_fails():
    """Scale 0 on every axis: no triangle to draw and no numerical warning. Scale 0 on z keeps a
    quad in the xy plane; its cofactor matrix diag(0, 0, sx sy) keeps vn (0 0 1) but maps vn
    (1 0 0) to zero: lit by ambient. A vn of 0 0 0 is ambient too."""
    quad = [(-0.5, -0.5, 0.0), (0.5, -0.5, 0.0), (0.5, 0.5, 0.0), (-0.5, 0.5, 0.0)]
    faces = [(0, 1, 2), (0, 2, 3)]
    light = tuple(_unit((0.2, 0.3, 1.0)))
    ambient_colour = int(shade(FLAT_COLOUR, 0.25))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for mode in ("flat", "textured"):
            scene = _scene(mode=mode, translate=(0.0, 0.0, -2.0), scale=(0.0, 0.0, 0.0), light=light, ambient=0.25)
            mesh = _mesh(quad, faces, texcoords=[(0, 0)] * 4, normals=[(0, 0, 1)] * 4)
            assert np.all(render_frame(scene, mesh, np.ones((2, 2), np.uint16), 0) == BG)
        scene = _scene(translate=(0.0, 0.0, -2.0), scale=(1.0, 1.0, 0.0), light=light, ambient=0.25)
        facing = render_frame(scene, _mesh(quad, faces, normals=[(0, 0, 1)] * 4), None, 0)
        assert set(np.unique(facing[facing != BG])) == {int(shade(FLAT_COLOUR, light[2]))}
        for normals in ([(1, 0, 0)] * 4, [(0, 0, 0)] * 4):
            frame = render_frame(scene, _mesh(quad, faces, normals=normals), None, 0)
            assert np.array_equal(frame != BG, facing != BG)
            assert set(np.unique(frame[frame != BG])) == {ambient_colour}


# --------------------------------------------------------------------------- near plane

def test_near_plane_clipping_matches_the_analytic_intersection():
    near = 0.5
    a, b, c = (-0.05, -0.03, -0.3), (0.4, -0.3, -1.5), (-0.3, 0.35, -1.2)   # a is behind the near plane
    mesh = _mesh([a, b, c], [(0, 1, 2)])
    frame = render_frame(_scene(near=near), mesh, None, 0)

    def cut(p, q):      # where p -> q crosses z = -near
        t = (-near - p[2]) / (q[2] - p[2])
        return tuple(p[i] + t * (q[i] - p[i]) for i in range(3))

    polygon = [_project(p) for p in (cut(a, b), b, c, cut(a, c))]
    cx, cy = _centres()
    signs = []
    for i in range(4):
        (x0, y0), (x1, y1) = polygon[i], polygon[(i + 1) % 4]
        signs.append((x1 - x0) * (cy - y0) - (y1 - y0) * (cx - x0))
    expected = np.all(np.array(signs) > 0, axis=0) | np.all(np.array(signs) < 0, axis=0)
    assert expected.sum() > 1000
    assert np.array_equal(frame != BG, expected)
    # and the cut is on screen: without it the corner behind would land elsewhere
    assert (render_frame(_scene(near=0.1), mesh, None, 0) != BG).sum() != expected.sum()


def test_a_triangle_behind_the_camera_draws_nothing():
    for z in (0.5, 2.0):
        mesh = _mesh([(-0.5, -0.5, z), (0.5, -0.5, z), (0.0, 0.5, z)], [(0, 1, 2)])
        for mode in ("flat", "wireframe"):
            assert np.all(render_frame(_scene(mode=mode), mesh, None, 0) == BG)


def test_wireframe_draws_each_edge_once_in_white():
    z = -2.0
    mesh = _mesh([(-0.5, -0.5, z), (0.5, -0.5, z), (0.5, 0.5, z), (-0.5, 0.5, z)], [(0, 1, 2), (0, 2, 3)])
    frame = render_frame(_scene(mode="wireframe"), mesh, None, 0)
    assert set(np.unique(frame)) == {BG, 0xFFFF}
    left, bottom = _project((-0.5, -0.5, z))
    right, top = _project((0.5, 0.5, z))
    x0, x1, y0, y1 = math.floor(left), math.floor(right), math.floor(top), math.floor(bottom)
    assert np.all(frame[y0, x0:x1 + 1] == 0xFFFF) and np.all(frame[y0:y1 + 1, x1] == 0xFFFF)
    lit = (frame == 0xFFFF).sum()
    perimeter = 2 * (x1 - x0) + 2 * (y1 - y0)
    assert lit == perimeter + max(x1 - x0, y1 - y0) - 1    # the diagonal shares its two end pixels


# --------------------------------------------------------------------------- parsers

@pytest.mark.parametrize("text, line, what", [
    ("mode = flat\nbogus = 1\n", 2, "unknown key"),
    ("fov = 60\n\n# c\nFOV = 70\n", 4, "duplicate key"),
    ("scale 2\n", 1, "malformed line (no '=')"),
    ("a=1\n", 1, "unknown key"),
    (" = 3\n", 1, "malformed line (no key)"),
    ("angle =  \t\n", 1, "malformed line (no value)"),
    ("angle = # a '#' opening a value is kept\n", 1, "bad value (not a number)"),
    ("mode = shaded\n", 1, "bad value (expected textured, flat or wireframe)"),
    ("cull = maybe\n", 1, "bad value (expected on, off, yes, no, true, false, 1 or 0)"),
    ("\n\nangle = ten\n", 3, "bad value (not a number)"),
    ("scale = 1 2\n", 1, "bad value (expected 1 or 3 numbers)"),
    ("translate = 1 2\n", 1, "bad value (expected 3 numbers)"),
    ("step = 1 2\n", 1, "bad value (expected 1 number)"),
    ("axis = 0 0 0\n", 1, "bad value (zero vector)"),
    ("fov = 180\n", 1, "bad value (fov must be between 0 and 180 degrees)"),
    ("near = 0\n", 1, "bad value (must be greater than 0)"),
    ("ambient = 1.5\n", 1, "bad value (must be between 0 and 1)"),
    ("background = 1 2 256\n", 1, "bad value (expected R G B with 0..255 each, or #RRGGBB)"),
    ("background = #12345\n", 1, "bad value (expected R G B with 0..255 each, or #RRGGBB)"),
    ("angle = 1e39\n", 1, "bad value (number out of range)"),
    ("far = 5\nnear = 6\n", 1, "bad value (far must be greater than near)"),
    ("near = 200\n", 1, "bad value (far must be greater than near)"),
    ("mode = flat\x01\n", 1, "malformed line (control character)"),
    # the precision keys
    ("interpolation = linear\n", 1, "bad value (expected perspective or affine)"),
    ("mode = flat\nshading = smooth\n", 2, "bad value (expected flat, gouraud or phong)"),
    ("angles = lookup\n", 1, "bad value (expected polynomial or table)"),
    ("depth = float16\n", 1, "bad value (expected int16 or float32)"),
    ("snap = none\n", 1, "bad value (expected subpixel or pixel)"),
    ("snap = pixel\n# again\nSNAP = subpixel\n", 3, "duplicate key"),
    # texture filtering
    ("filter = trilinear\n", 1, "bad value (expected nearest, bilinear, mipmap or anisotropic)"),
    ("filter = mipmap\nFilter = Nearest\n", 2, "duplicate key"),
    ("filter = bilinear mipmap\n", 1, "bad value (expected nearest, bilinear, mipmap or anisotropic)"),
    ("shading =\n", 1, "malformed line (no value)"),
    ("\nlight_levels = 3.5\n", 2, "bad value (must be a whole number from 2 to 65537)"),
    ("light_levels = 1\n", 1, "bad value (must be a whole number from 2 to 65537)"),
    ("light_levels = 65538\n", 1, "bad value (must be a whole number from 2 to 65537)"),
    ("light_levels = -8\n", 1, "bad value (must be a whole number from 2 to 65537)"),
    ("light_levels = 8 8\n", 1, "bad value (expected 1 number)"),
    ("light_levels = eight\n", 1, "bad value (not a number)"),
    ("light_levels = 0x10\n", 1, "bad value (not a number)"),
    ("light_levels = 1e39\n", 1, "bad value (number out of range)"),
])
def test_scene_errors_name_the_line(text, line, what):
    with pytest.raises(SceneError) as error:
        parse_scene(text)
    assert (error.value.line, error.value.what) == (line, what)
    assert str(error.value) == f"bad scene.ini line {line}: {what}"


def test_scene_values_and_defaults():
    scene = parse_scene("\ufeff# comment\r\nMODE = Wireframe\r\nscale = 2\r\naxis = 0 0 2  # z\r\n"
                        "background = #203040\r\ncull = No\r\nmodel = Models/A.obj\r\n")
    assert scene.mode == "wireframe" and scene.cull is False and scene.scale == (2.0, 2.0, 2.0)
    assert scene.axis == (0.0, 0.0, 1.0) and scene.model == "Models/A.obj"
    assert scene.background == ((0x20 * 31 + 127) // 255) << 11 | ((0x30 * 63 + 127) // 255) << 5 | (0x40 * 31 + 127) // 255
    default = parse_scene(None)
    assert (default.background, default.fov, default.translate, default.step) == (0x10A2, 60.0, (0, 0, -3), 4.0)
    assert parse_scene("background = 16 20 16\n").background == 0x10A2


def test_precision_keys_parse_with_defaults_and_change_neither_image():
    default = parse_scene(None)
    assert (default.interpolation, default.shading, default.light_levels, default.angles, default.depth,
            default.snap) == ("perspective", "flat", 65, "polynomial", "int16", "subpixel")
    assert parse_scene("mode = flat\n").light_levels == 65
    text = "Interpolation = AFFINE\nshading = Gouraud\nLIGHT_LEVELS = 2\nangles = Table\ndepth = FLOAT32\nsnap = Pixel\n"
    scene = parse_scene(text)
    assert (scene.interpolation, scene.shading, scene.light_levels, scene.angles, scene.depth, scene.snap) == \
        ("affine", "gouraud", 2, "table", "float32", "pixel")
    assert scene.lines["light_levels"] == 3 and scene.lines["snap"] == 6
    for written, levels in (("65", 65), ("+17", 17), ("6.5e1", 65), ("2.0", 2), ("  33\t# comment", 33)):
        assert parse_scene(f"light_levels = {written}\n").light_levels == levels, written
    z = -2.0
    vertices = [(-0.5, -0.5, z), (0.5, -0.5, z), (0.5, 0.5, z)]
    mesh = _mesh(vertices, [(0, 1, 2)], normals=[(-0.3, 0, 1), (0.3, 0, 1), (0, 0.3, 1)])
    plain = _scene(ambient=0.1)
    precise = replace(plain, interpolation="affine", shading="gouraud", light_levels=2, angles="table",
                      depth="float32", snap="pixel")
    assert np.array_equal(render_frame(precise, mesh, None, 0), render_frame(plain, mesh, None, 0))
    # the ideal image ignores them too (the bench renders it once for all settings of a scene)
    assert np.array_equal(render_ideal_frame(precise, mesh, None, 0, density=2),
                          render_ideal_frame(plain, mesh, None, 0, density=2))


@pytest.mark.parametrize("text, line, what", [
    ("v 0 0 0\nvx 1\n", 2, "unknown statement"),
    ("v 0 0 zero\n", 1, "malformed number"),
    ("v 0 0\n", 1, "v takes 3, 4, 6 or 7 numbers"),
    ("v 1 2 3 4 5\n", 1, "v takes 3, 4, 6 or 7 numbers"),
    ("vt\n", 1, "vt takes 1, 2 or 3 numbers"),
    ("vn 1 2\n", 1, "vn takes 3 numbers"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2/\n", 4, "malformed face corner (expected v, v/vt, v//vn or v/vt/vn)"),
    ("v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "face with fewer than 3 vertices"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 4, "index 0 (indices start at 1)"),
    ("v 0 0 0\nv 1 0 0\nf -3 -2 -1\nv 0 1 0\n", 3, "vertex index out of range"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n", 4, "texture coordinate index out of range"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//2 2//1 3//1\nvn 0 0 1\n", 4, "normal index out of range"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", 4, "vertex index out of range"),
    ("v 1e39 0 0\n", 1, "number out of range"),
])
def test_model_errors_name_the_line(text, line, what):
    with pytest.raises(ModelError) as error:
        parse_obj(text.encode())
    assert (error.value.line, error.value.what) == (line, what)
    assert str(error.value) == f"bad model line {line}: {what}"


def test_model_forms_negative_indices_and_fans():
    mesh = parse_obj(b"# a quad\r\no q\nv 0 0 0\nv 1 0 0 1\nv 1 1 0 1 0.5 0.5\nv 0 1 0\nvt 0.5\nvt 0 1 0\n"
                     b"vn 0 0 1\nf 1/1 2//1 -2/-1/-1 4\ns off\nf 3 2 1 # forward and back\n")
    assert mesh.faces.shape == (3, 3, 3)
    assert mesh.faces[0].tolist() == [[0, 0, -1], [1, -1, 0], [2, 1, 0]]
    assert mesh.faces[1].tolist() == [[0, 0, -1], [2, 1, 0], [3, -1, -1]]
    assert mesh.texcoords.tolist() == [[0.5, 0.0], [0.0, 1.0]]
    with pytest.raises(ModelError, match="bad model: no faces"):
        parse_obj(b"v 0 0 0\n")


def test_ppm_reading_and_rounding():
    p6 = b"P6\n# c\n2 1\n65535\n" + bytes([0xFF, 0xFF, 0x80, 0x00, 0x00, 0x00, 0x7F, 0xFF, 0x00, 0x01, 0x00, 0x00])
    texture = parse_ppm(p6)
    expected = [((65535 * 31 + 32767) // 65535) << 11 | ((0x8000 * 63 + 32767) // 65535) << 5,
                ((0x7FFF * 31 + 32767) // 65535) << 11 | ((1 * 63 + 32767) // 65535) << 5]
    assert texture.tolist() == [expected]
    assert parse_ppm(b"P3 1 1 1 1 0 1").tolist() == [[0xF81F]]
    assert parse_ppm(b"P3 1 2 255 16 20 16 #x\n 255 255 255").tolist() == [[0x10A2], [0xFFFF]]
    for data, what in [(b"P5 1 1 255 \0", "not a PPM (magic is not P6 or P3)"),
                       (b"P6 1 1", "truncated header"),
                       (b"P6 1 0 255 ", "bad header (width or height 0)"),
                       (b"P6 1 1 65536 ", "bad maxval (not 1..65535)"),
                       (b"P6 1 1 255 \0\0", "truncated raster (fewer samples than width x height x 3)"),
                       (b"P3 1 1 255 1 x 3", "bad sample (not a decimal number)"),
                       (b"P3 1 1 7 1 8 3", "sample above maxval")]:
        with pytest.raises(TextureError) as error:
            parse_ppm(data)
        assert error.value.what == what, data


@pytest.mark.parametrize("mode", ["flat", "wireframe"])
def test_load_files_skips_the_texture_unless_textured(mode):
    """Only textured mode draws the texture, so only it reads one (as the firmware)."""
    obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    scene, mesh, texture = load_files(f"mode = {mode}\n", obj, b"not a ppm")
    assert texture is None and len(mesh.faces) == 1
    with pytest.raises(TextureError):
        load_files(None, obj, b"not a ppm")


# --------------------------------------------------------------------------- the firmware's goldens

def _agreement(mine: np.ndarray, theirs: np.ndarray) -> tuple[float, float, float]:
    """(share of identical pixels, share within 8 levels per channel, PSNR in dB) of two RGB images."""
    mine, theirs = mine.astype(int), theirs.astype(int)
    difference = np.abs(mine - theirs).max(axis=2)
    mse = float(((mine - theirs) ** 2).mean())
    psnr = 10 * math.log10(255 ** 2 / mse) if mse else math.inf
    return float((difference == 0).mean()), float((difference <= 8).mean()), psnr


def _without_normals(mesh: Mesh) -> Mesh:
    """The mesh with its vn dropped: the reference then lights every face from its geometric
    normal, as the firmware's (default) flat shading does."""
    return Mesh(mesh.vertices, mesh.texcoords, np.zeros((0, 3)), mesh.faces)


@pytest.mark.parametrize("name", sorted(SCENES))
def test_first_golden_frame_agrees_loosely_with_the_firmware(name, golden_card):
    """A convention check (projection, coverage, texel addressing, lighting formula), so the
    reference is compared lit per face, like the firmware's flat shading: its ideal lights per
    pixel from the vertex normals, which on the torus's smooth normals is a real difference in
    the picture (measured by the bench), not a convention mismatch. The ideal frame is printed
    too; for the cube and the gem, whose vn are their facets' normals, it must equal the per-face
    frame but for rounding (the gem's vn are written with 6 decimals)."""
    if SCENES[name][0] is None:
        if not DEFAULT_CARD.exists():
            pytest.skip("no build/card.img (make card)")
        card = DEFAULT_CARD
    else:
        card = golden_card(name)
    scene, mesh, texture = load_card_image(card)
    golden = np.asarray(Image.open(GOLDEN / name / "frame_0000.png").convert("RGB"))
    per_face = render_image(scene, _without_normals(mesh), texture, 0)
    identical, close, psnr = _agreement(per_face, golden)
    ideal = render_image(scene, mesh, texture, 0)
    ideal_identical, ideal_close, ideal_psnr = _agreement(ideal, golden)
    print(f"\n{name} ({scene.mode}), lit per face: identical {identical:.2%}, within 8 levels {close:.2%}, "
          f"PSNR {psnr:.1f} dB; ideal: identical {ideal_identical:.2%}, within 8 levels {ideal_close:.2%}, "
          f"PSNR {ideal_psnr:.1f} dB")
    if scene.mode == "wireframe" and scene.antialias != "off":
        # coverage lines (up to three pixels across) around the reference's one-pixel lines
        from extremes_support import within_one_pixel
        background = golden[0, 0]
        shown, ref = (np.any(f != background, axis=-1) for f in (golden, per_face))
        assert within_one_pixel(shown, ref) and within_one_pixel(ref, shown)
    elif scene.mode == "wireframe":
        assert identical >= 0.98
        assert np.array_equal(ideal, per_face)          # nothing is lit
    else:
        assert close >= 0.97 and identical >= 0.80 and psnr >= 35
    if name in ("cube-textured", "gem-flat"):
        assert np.any(ideal != per_face, axis=2).mean() < 0.001


# --------------------------------------------------------------------------- command line

def test_cli_renders_a_folder_and_a_card(tmp_path):
    folder = tmp_path / "card"
    (folder / "Models").mkdir(parents=True)
    (folder / "scene.ini").write_text("model = models/tri.OBJ\nmode = flat\ncull = off\n")
    (folder / "Models" / "tri.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n")
    (folder / "texture.ppm").write_bytes(b"P3 1 1 1 1 1 1")
    out = tmp_path / "out"
    result = run_module("reference", "render", folder, "--frames", "2", "--out", out, "--quiet")
    assert result.returncode == 0, result.stderr
    frames = sorted(p.name for p in out.iterdir())
    assert frames == ["frame_0000.png", "frame_0001.png"]
    image = np.asarray(Image.open(out / "frame_0000.png"))
    assert image.shape == (240, 320, 3) and (image != image[0, 0]).any()
    (folder / "scene.ini").write_text("mode = flat\nnear = -1\n")
    result = run_module("reference", "render", folder, "--out", out)
    assert result.returncode == EXIT_BAD_INPUT and "bad scene.ini line 2: bad value (must be greater than 0)" in result.stderr
    if DEFAULT_CARD.exists():
        result = run_module("reference", "render-card", DEFAULT_CARD, "--out", tmp_path / "card-out", "--quiet")
        assert result.returncode == 0, result.stderr
        assert (tmp_path / "card-out" / "frame_0000.png").exists()
