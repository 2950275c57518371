"""tools/make_assets.py's held-in cases for the bench (issue 34): what each is said to be."""
from __future__ import annotations

from collections import Counter

import numpy as np

from reference.obj import parse_obj
from tools import make_assets


def test_the_icosphere_has_5120_faces_on_the_unit_sphere_and_is_closed():
    mesh = parse_obj(make_assets.icosphere())
    assert len(mesh.faces) == 5120
    assert np.allclose(np.linalg.norm(mesh.vertices, axis=1), 1.0, atol=1e-5)
    edges = Counter(tuple(sorted((int(face[k][0]), int(face[(k + 1) % 3][0])))) for face in mesh.faces for k in range(3))
    assert set(edges.values()) == {2}                   # every edge between exactly two faces


def test_the_cylinder_has_32_sides_and_two_32_gon_caps():
    text = make_assets.cylinder()
    faces = [line.split()[1:] for line in text.splitlines() if line.startswith("f ")]
    assert sorted(Counter(len(face) for face in faces).items()) == [(4, 32), (32, 2)]
    assert len(parse_obj(text).faces) == 32 * 2 + 2 * 30       # fanned: quads in 2, caps in 30


def test_the_crossing_quads_cross_on_x_0_at_their_slope():
    mesh = parse_obj(make_assets.crossing(slope=1e-4))
    second = mesh.vertices[4:]
    assert np.allclose(second[:, 2], 1e-4 * second[:, 0]) and np.all(mesh.vertices[:4, 2] == 0)


def test_the_slanted_quad_turns_80_degrees_and_the_stripes_average_grey():
    mesh = parse_obj(make_assets.slant(80.0))
    a, b, d = mesh.vertices[0], mesh.vertices[1], mesh.vertices[3]
    normal = np.cross(b - a, d - a)
    assert np.isclose(np.degrees(np.arccos(normal[2] / np.linalg.norm(normal))), 80.0)
    stripes = np.asarray(make_assets.stripes())
    assert stripes.shape == (1, 4096, 3) and stripes.mean() == 127.5


def test_the_logo_is_flat_colours_at_256_by_128():
    image = np.asarray(make_assets.logo())
    assert image.shape == (128, 256, 3) and len(np.unique(image.reshape(-1, 3), axis=0)) <= 8


def test_the_monkey_head_is_seven_smooth_closed_parts_facing_outwards():
    """A Blender-like head of our own (Blender's monkey cannot be shipped): 1,832 triangles in seven
    ellipsoids (the head, two ears, the muzzle, two eyes, the brow), every normal unit length and
    every face turned outwards (its corners counter-clockwise seen from outside, as the firmware's
    culling wants), the texture wrapped once around each part."""
    mesh = parse_obj(make_assets.monkey())
    assert len(mesh.faces) == 1832 and len(make_assets.MONKEY_PARTS) == 7
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-5)
    corners = mesh.faces[..., 0]
    v = mesh.vertices
    face_normals = np.cross(v[corners[:, 1]] - v[corners[:, 0]], v[corners[:, 2]] - v[corners[:, 0]])
    real = np.linalg.norm(face_normals, axis=1) > 1e-12              # (the poles' degenerate ones aside)
    assert np.all((face_normals * mesh.normals[mesh.faces[:, 0, 2]]).sum(axis=1)[real] > 0)
    assert mesh.texcoords.min() >= 0 and mesh.texcoords.max() <= 1
