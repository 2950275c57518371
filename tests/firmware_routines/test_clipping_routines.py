"""Unit tests of the clipping stage (render.S, file comment step 4): plane_distance, clip_polygon
(one Sutherland-Hodgman step), the five planes in a row as clip_and_draw runs them, and the
wireframe's clip_segment (Liang-Barsky) with segment_point. Each routine is called by its
symbol on hart 0 of the board model (firmware_calls.py) and compared with a float64 model of
the algorithm its comment documents.

The planes (render.S clip_planes, render.inc): d = a x + b y + c z + e w >= 0 inside, for the
near plane z >= 0 and the guard band's sides x >= -G w, x <= G w, y >= -G w, y <= G w, with
G = F32_GUARD_BAND (16), read from the ELF like every layout constant here.

Tolerances, with u = 2^-24 (float32's unit roundoff; the float64 model's own error, ~1e-16
relative, is negligible beside it):

- plane distances are bit-exact: the near plane's d is z itself (the other products are exact
  zeros), a guard plane's d is +-x + G w rounded once (G w is exact, a power of two times w, and
  the zero products add nothing), which is the float64 value rounded to float32 (the sum of two
  floats is exact in float64 for the values used, and a double then single rounding of +, -, *, /
  is correct anyway since 53 >= 2 * 24 + 2).
- a cut p + t (q - p), t = dp / (dp - dq): dp and dq are each rounded once (relative error u),
  dp - dq adds magnitudes (p inside, q outside: opposite signs) and rounds once, the division
  once: t is within 4u relative. Each field rounds q - p once and p + t (q - p) once (fmadd), so
  with 0 <= t <= 1 its error is at most (|p| + |q|)(5u) + u max(|p|, |q|) <= 6u (|p| + |q|);
  CUT_ULPS = 8 leaves room for the second-order terms.
- Q4 screen positions (project_clip): the firmware rounds its float32 value to a whole Q4 unit,
  so it lies within 1/2 + e of the model's exact value, e the float32 error of the point
  (the cut bound above) carried through x / w and the viewport (`q4_error_bound`).
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np
import pytest

from firmware_calls import FirmwareCaller, bits_f32, f32, f32_bits

U = 2.0 ** -24               # float32 unit roundoff
CUT_ULPS = 8                 # a cut field's error, in u (|p| + |q|) (module docstring)
PLANE_NAMES = ("near", "left", "right", "bottom", "top")
NEAR = 0
FIELDS = ("x", "y", "z", "w", "s", "t", "k", "na", "nb", "nc")    # a clip vertex (render.inc CV_*), f32 each
ATTRIBUTES = len(FIELDS) - 4      # after the position
CV_BYTES = 4 * len(FIELDS)
CANARY = bytes(range(0xA0, 0xA0 + CV_BYTES)) * 8  # written after an output: a pattern no corner here has


@pytest.fixture(scope="module")
def fw(firmware) -> FirmwareCaller:
    """One board per module: every call below sets up all the memory it reads."""
    caller = FirmwareCaller(firmware)
    # the clip vertex and clip-space position layouts the tests write (render.inc)
    for offset, name in enumerate(("CV_X", "CV_Y", "CV_Z", "CV_W", "CV_S", "CV_T", "CV_K", "CV_NA", "CV_NB",
                                    "CV_NC")):
        assert caller.symbol(name) == 4 * offset, name
    for offset, name in enumerate(("CLIP_POS_X", "CLIP_POS_Y", "CLIP_POS_Z", "CLIP_POS_W")):
        assert caller.symbol(name) == 4 * offset, name
    assert caller.symbol("CLIP_POS_BYTES") == 16
    assert caller.symbol("CV_BYTES") == CV_BYTES
    assert caller.symbol("CLIP_PLANES") == len(PLANE_NAMES)
    assert caller.symbol("PLANE_BYTES") == 16
    return caller


def guard_band(fw: FirmwareCaller) -> float:
    return float(bits_f32(fw.symbol("F32_GUARD_BAND")))


def documented_planes(fw: FirmwareCaller) -> list[tuple[float, float, float, float]]:
    """(a, b, c, e) of each plane, as render.S's file comment and render.inc describe them."""
    g = guard_band(fw)
    return [(0, 0, 1, 0), (1, 0, 0, g), (-1, 0, 0, g), (0, 1, 0, g), (0, -1, 0, g)]


# --------------------------------------------------------------------------- float64 model

def distance(plane: tuple[float, ...], corner) -> float:
    a, b, c, e = plane
    x, y, z, w = (float(v) for v in corner[:4])
    return a * x + b * y + c * z + e * w


def frustum_outcode(v: np.ndarray, g: float) -> int:
    """vertex.S's outcode (render.inc OUT_*_BIT order: left, right, bottom, top, near, far, guard)."""
    x, y, z, w = (float(c) for c in v[:4])
    outside = [x < -w, x > w, y < -w, y > w, z < 0, z > w, max(abs(x), abs(y)) > g * w]
    return sum(1 << bit for bit, out in enumerate(outside) if out)


@dataclass(frozen=True)
class ModelCorner:
    """A corner of the model's output: `copy` = the input corner it is, or `cut` = the input
    corners (inside, outside) of the edge it was cut from."""

    values: np.ndarray            # float64 x, y, z, w, s, t, k, na, nb, nc
    copy: int | None = None
    cut: tuple[int, int] | None = None


def model_clip(corners: np.ndarray, plane: tuple[float, ...]) -> list[ModelCorner]:
    """One Sutherland-Hodgman step as clip_polygon documents it, in float64: for each edge
    a -> b, a when d(a) >= 0, then the crossing when exactly one end is inside, interpolated
    from the inside end p towards the outside end q at t = d(p) / (d(p) - d(q))."""
    corners = np.asarray(corners, dtype=np.float64)
    n = len(corners)
    out = []
    for i in range(n):
        j = (i + 1) % n
        da, db = distance(plane, corners[i]), distance(plane, corners[j])
        if da >= 0:
            out.append(ModelCorner(corners[i], copy=i))
        if (da >= 0) != (db >= 0):
            p, q, dp, dq = (i, j, da, db) if da >= 0 else (j, i, db, da)
            t = dp / (dp - dq)
            out.append(ModelCorner(corners[p] + t * (corners[q] - corners[p]), cut=(p, q)))
    return out


def cut_tolerance(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Per field: how far a float32 cut between p and q may lie from the exact one."""
    return CUT_ULPS * U * (np.abs(np.asarray(p, np.float64)) + np.abs(np.asarray(q, np.float64)))


def assert_matches_model(out: np.ndarray, model: list[ModelCorner], corners: np.ndarray, plane: int,
                         what: str) -> None:
    """The firmware's output corners against the model's: same count, copies bit-exact, cuts
    within cut_tolerance, and a cut on the near plane with z = +0 exactly."""
    assert len(out) == len(model), f"{what}: {len(out)} corners, the model has {len(model)}"
    for n, (got, want) in enumerate(zip(out, model, strict=True)):
        if want.copy is not None:
            assert got.tobytes() == corners[want.copy].tobytes(), \
                f"{what}: corner {n} should be input corner {want.copy} copied bit for bit"
            continue
        p, q = corners[want.cut[0]], corners[want.cut[1]]
        error = np.abs(got.astype(np.float64) - want.values)
        tolerance = cut_tolerance(p, q)
        assert np.all(error <= tolerance), \
            f"{what}: cut corner {n} {got} vs model {want.values} (error {error}, tolerance {tolerance})"
        if plane == NEAR:
            assert f32_bits(got[2]) == 0, f"{what}: a near-plane cut has z = {got[2]!r}, not exactly +0"


# --------------------------------------------------------------------------- exact float32 emulation

def round_f32(value: Fraction) -> np.float32:
    """value rounded to the nearest single (ties to even), exactly."""
    guess = np.float32(float(value))
    candidates = [np.nextafter(guess, np.float32(-np.inf)), guess, np.nextafter(guess, np.float32(np.inf))]
    return min(candidates, key=lambda c: (abs(Fraction(float(c)) - value), f32_bits(c) & 1))


def f32_cut(p: np.ndarray, q: np.ndarray, dp: np.float32, dq: np.float32) -> np.ndarray:
    """The documented cut p + t (q - p), t = dp / (dp - dq), in float32 with fused
    multiply-adds: what a firmware cutting from p towards q computes, bit for bit."""
    t = np.float32(dp / np.float32(dp - dq))
    return np.array([round_f32(Fraction(float(np.float32(b - a))) * Fraction(float(t)) + Fraction(float(a)))
                     for a, b in zip(p, q, strict=True)], dtype=np.float32)


# --------------------------------------------------------------------------- calling the routines

def plane_address(fw: FirmwareCaller, plane: int) -> int:
    return fw.symbol("clip_planes") + plane * fw.symbol("PLANE_BYTES")


def fw_plane_distance(fw: FirmwareCaller, corner, plane: int) -> np.float32:
    """plane_distance of a clip vertex written at the scratch address."""
    fw.write_f32(fw.scratch, list(corner[:4]) + [0.0] * ATTRIBUTES)
    return fw.call("plane_distance", [fw.scratch, plane_address(fw, plane)]).fa(0)


def fw_clip_polygon(fw: FirmwareCaller, corners: np.ndarray, plane: int, source: int, output: int,
                    room: int) -> np.ndarray:
    """clip_polygon of `corners` (written at `source`) into `output`; returns the output's corners
    (asserting the count is at most `room`)."""
    corners = np.asarray(corners, dtype=np.float32)
    fw.write_f32(source, corners.ravel())
    count = fw.call("clip_polygon", [source, len(corners), output, plane_address(fw, plane)]).a[0]
    assert count <= room, f"clip_polygon returned {count} corners, room for {room}"
    return fw.read_f32(output, len(FIELDS) * count).reshape(count, len(FIELDS))


def corner(fw: FirmwareCaller, plane: int, r: float, w: float, a: float, b: float,
           s: float, t: float, k: float, n: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """A clip vertex at distance d = r * scale from `plane` (scale = w for the near plane, G w
    for the guard planes: r < 0 outside), its other two coordinates a w and b w."""
    g = guard_band(fw)
    if plane == NEAR:
        x, y, z = a * w, b * w, r * w
    else:
        sign = 1 if plane in (1, 3) else -1                 # left, bottom: +x, +y inside
        along = sign * (r - 1) * g * w                      # d = sign * along + G w = r G w
        x, y, z = (along, a * w, b * w) if plane in (1, 2) else (a * w, along, b * w)
    return np.array([x, y, z, w, s, t, k, *n], dtype=np.float32)


# Three corners' w, free coordinates (multiples of w) and attributes
CORNER_BASE = [
    dict(w=0.5, a=0.3, b=0.45, s=0.25, t=3.5, k=10.0, n=(0.25, -0.5, 0.875)),
    dict(w=4.0, a=-2.7, b=0.9, s=12.75, t=-2.0, k=64.0, n=(-0.625, 0.125, 0.75)),
    dict(w=2.25, a=1.9, b=0.15, s=5.5, t=7.125, k=33.0, n=(0.5, 0.375, -0.25)),
]
# r of the three corners, and the corners the plane leaves: one corner outside adds a corner, two
# keep three; a corner on the plane (d = 0 exactly) is inside, and the edge from it to the corner
# outside is cut at t = 0 (a repeated corner, as the documented rule gives)
ONE_OUTSIDE = (-0.45, 0.8, 1.6)
TWO_OUTSIDE = (0.7, -0.35, -1.3)
ON_THE_PLANE = (0.0, -0.45, 1.6)
TRIANGLE_CASES = {"one-outside": (ONE_OUTSIDE, 4), "two-outside": (TWO_OUTSIDE, 3),
                  "corner-on-the-plane": (ON_THE_PLANE, 4)}


def triangle(fw: FirmwareCaller, plane: int, distances: tuple[float, ...], rotation: int) -> np.ndarray:
    corners = np.array([corner(fw, plane, r, **base) for r, base in zip(distances, CORNER_BASE, strict=True)])
    return np.roll(corners, rotation, axis=0)


# --------------------------------------------------------------------------- plane_distance

# Clip-space points (x, y, z, w): ordinary ones, sums that round, points beyond the band and
# behind the eye (w < 0), and one exactly on the right and bottom guard lines.
PROBES = [
    (1.5, -2.25, 0.75, 3.0),
    (0.1, 0.2, 0.3, 0.7),
    (-40.0, 17.5, -0.125, 2.0),
    (1.0e-3, 3.0e4, 123.456, 1000.0),
    (-1.0, 2.0, -3.0, -0.5),
    (48.0, -48.0, 5.0, 3.0),
    (1.0e7, -3.3, 0.0, 1.0e-3),
]


@pytest.mark.parametrize("plane", range(len(PLANE_NAMES)), ids=PLANE_NAMES)
def test_plane_distance(fw, plane):
    """Near plane: d is z itself, bit for bit. Guard planes: +-x or +-y plus G w, rounded once
    to float32 (the model's value rounded to single): bit-exact, signs included, so that a
    corner on a guard line (d = 0) is inside."""
    planes = documented_planes(fw)
    for probe in PROBES:
        got = fw_plane_distance(fw, probe, plane)
        if plane == NEAR:
            want = f32(probe[2])
        else:
            want = f32(distance(planes[plane], [float(f32(v)) for v in probe]))
        assert f32_bits(got) == f32_bits(want), f"{PLANE_NAMES[plane]} plane, {probe}: d = {got!r}, want {want!r}"


# --------------------------------------------------------------------------- clip_polygon, one plane

@pytest.mark.parametrize("case", TRIANGLE_CASES)
@pytest.mark.parametrize("plane", range(len(PLANE_NAMES)), ids=PLANE_NAMES)
def test_clip_polygon_one_plane(fw, plane, case):
    """A triangle with one corner (-> 4 corners) or two (-> 3) outside the plane, or one on it
    (-> 4), each corner in turn first so that the wrap-around edge is cut too: Sutherland-
    Hodgman's corners in its order, inside corners copied bit for bit, cuts within the float32
    bound, near cuts with z = 0 exactly. The output buffer's first corner past the result keeps
    its canary."""
    planes = documented_planes(fw)
    distances, corners_left = TRIANGLE_CASES[case]
    source, output = fw.scratch, fw.scratch + 8 * CV_BYTES
    for rotation in range(3):
        corners = triangle(fw, plane, distances, rotation)
        model = model_clip(corners, planes[plane])
        assert len(model) == corners_left
        fw.write(output, CANARY)
        out = fw_clip_polygon(fw, corners, plane, source, output, room=4)
        assert_matches_model(out, model, corners, plane, f"{PLANE_NAMES[plane]} plane, rotation {rotation}")
        end = len(out) * CV_BYTES
        assert fw.read(output + end, CV_BYTES) == CANARY[end:end + CV_BYTES], "written past the corners"


@pytest.mark.parametrize("plane", range(len(PLANE_NAMES)), ids=PLANE_NAMES)
def test_shared_edge_is_cut_into_identical_corners(fw, plane):
    """Two triangles (A, B, C) and (B, A, D) share the edge A-B, which leaves the plane at B.
    Each meets it in its own direction, yet both cut it from the inside corner A, so the new
    corners are bit-identical (no crack between the triangles)."""
    planes = documented_planes(fw)
    a = corner(fw, plane, 0.8, 0.5, 0.3, 0.45, 0.25, 3.5, 10.0)
    b = corner(fw, plane, -0.45, 4.0, -2.7, 0.9, 12.75, -2.0, 64.0)
    c = corner(fw, plane, 1.6, 2.25, 1.9, 0.15, 5.5, 7.125, 33.0)
    d = corner(fw, plane, 1.2, 1.5, -0.6, 0.7, 9.0, 1.25, 48.0)
    # The test must be able to fail: cutting this edge from B towards A (the second triangle's
    # direction) gives other bits than cutting it from A towards B.
    da, db = fw_plane_distance(fw, a, plane), fw_plane_distance(fw, b, plane)
    assert f32_cut(a, b, da, db).tobytes() != f32_cut(b, a, db, da).tobytes(), \
        "pick corners whose cut depends on the direction"
    cuts = []
    for first in (np.array([a, b, c]), np.array([b, a, d])):
        model = model_clip(first, planes[plane])
        out = fw_clip_polygon(fw, first, plane, fw.scratch, fw.scratch + 8 * CV_BYTES, room=4)
        assert_matches_model(out, model, first, plane, f"{PLANE_NAMES[plane]} plane")
        (index,) = [n for n, m in enumerate(model) if m.cut is not None and {first[i].tobytes() for i in m.cut}
                    == {a.tobytes(), b.tobytes()}]
        cuts.append(out[index])
    assert cuts[0].tobytes() == cuts[1].tobytes(), f"the shared edge's cuts differ: {cuts[0]} vs {cuts[1]}"


# --------------------------------------------------------------------------- all five planes

def eight_corner_triangle(fw: FirmwareCaller) -> np.ndarray:
    """A triangle cut by all five planes into 8 corners, the most in exact arithmetic. In x / w,
    y / w its corners are (0, 1.5 G), (1.875 G, -0.375 G), (-3.75 G, -2.25 G): each side cuts one corner
    off the guard square (the lines x + y = 1.5 G, y - x = 1.5 G, x - 3 y = 3 G), and with
    z = x + y + 1.5 G w the near plane cuts off the fourth, (-G, -G), and the triangle's third
    corner (z = -4.5 G w). Scaled by w = 2, 1, 0.5 so that the guard planes' G w terms differ.
    The result is an octagon: with G = 16, (16, 8), (8, 16), (-8, 16), (-16, 8), (-16, -8),
    (-8, -16), (0, -16), (16, -32/3) in some rotation."""
    g = guard_band(fw)
    corners = []
    for (x, y), w, s, t, k in (((0.0, 1.5), 2.0, 0.0, 0.0, 64.0), ((1.875, -0.375), 1.0, 64.0, 0.0, 0.0),
                               ((-3.75, -2.25), 0.5, 32.0, 64.0, 32.0)):
        z = x + y + 1.5
        corners.append([x * g * w, y * g * w, z * g * w, w, s, t, k, 0.0, 0.0, 0.0])
    return np.array(corners, dtype=np.float32)


def test_five_planes_give_at_most_clip_max_out_corners(fw):
    """clip_polygon through the five planes in turn, between clip_and_draw's own buffers
    clip_polygon_a and _b as clip_and_draw ping-pongs them, on a triangle the float64 model
    cuts into 8 corners (4, 5, 6, 7, 8 after each plane): each step matches the model of that
    step (given the firmware's previous output), the end result matches the model of the whole
    chain, and the bytes after the buffers (render_rv_out's first corner) are untouched."""
    planes = documented_planes(fw)
    max_out = fw.symbol("CLIP_MAX_OUT")
    buffer_a, buffer_b = fw.symbol("clip_polygon_a"), fw.symbol("clip_polygon_b")
    after_b = fw.symbol("render_rv_out")
    assert buffer_b - buffer_a == max_out * CV_BYTES and after_b - buffer_b == max_out * CV_BYTES, \
        "clip_polygon_a, clip_polygon_b, render_rv_out are no longer CLIP_MAX_OUT clip vertices apart"
    triangle_corners = eight_corner_triangle(fw)

    # the pure float64 chain: one more corner per plane, 3 + 5 = 8 in the end, the most a
    # triangle can have in exact arithmetic
    chain = triangle_corners.astype(np.float64)
    counts = []
    for plane in planes:
        chain = np.array([m.values for m in model_clip(chain, plane)])
        counts.append(len(chain))
    assert counts == [4, 5, 6, 7, 8], counts
    assert max_out >= 8
    g = guard_band(fw)
    octagon = {(round(x / w / g * 48), round(y / w / g * 48)) for x, y, _, w in chain[:, :4]}
    assert octagon == {(48, 24), (24, 48), (-24, 48), (-48, 24), (-48, -24), (-24, -48), (0, -48), (48, -32)}

    fw.write(after_b, CANARY[:CV_BYTES])
    corners, source, output = triangle_corners, buffer_a, buffer_b
    for plane in range(len(planes)):
        out = fw_clip_polygon(fw, corners, plane, source, output, room=max_out)
        assert_matches_model(out, model_clip(corners, planes[plane]), corners, plane,
                             f"plane {PLANE_NAMES[plane]} of the chain")
        corners, source, output = out, output, source
    assert fw.read(after_b, CV_BYTES) == CANARY[:CV_BYTES], "clip_polygon wrote past clip_polygon_b"
    # End to end, only a check that the chain does not drift (the steps above are the precise
    # checks): each step adds at most CUT_ULPS u (|p| + |q|) <= 2 CUT_ULPS u M (M = the largest
    # coordinate), and the crossings here are far from parallel to their planes, so an error
    # carried into a cut moves it by about as much again; measured: 2.7e-6, the bound 4.6e-4.
    scale = np.abs(triangle_corners).max()
    error = np.abs(corners.astype(np.float64) - chain).max()
    assert error <= 5 * 2 * CUT_ULPS * U * scale, f"the chain's corners are {error} from the model's"


# A triangle for which float32 rounding makes one plane add two corners (found by a random search
# around the guard square's corners): its middle corner lies on the corner (G w, G w) of the
# guard square within an ulp, so the right plane cuts its two edges at points that lie on the top
# line within rounding, and the top plane then sees them inside and outside alternately: four
# crossings instead of two. Singles as bit patterns (x, y, z, w); the attributes 0.
NINE_CORNER_TRIANGLE = [
    (0xC229E4A3, 0x429420FF, 0x3FE673D6, 0x3FBBB76C),
    (0x4062900A, 0x40629009, 0x4021F88E, 0x3E629009),
    (0xBFE55267, 0xC23D13ED, 0xBF3C36D5, 0x3F7E1D9E),
]


def test_rounding_cannot_overflow_the_clip_buffers(fw):
    """In exact arithmetic each plane adds at most one corner (3 + 5 = 8), but not in float32:
    this triangle, run through the five planes as clip_and_draw does (its corners' outcodes have
    both OUT_NEAR and OUT_GUARD and share no frustum bit, so clip_and_draw clips it against all
    five), ends with 9 corners (4, 5, 6, 7, 9 after each plane). render.inc sizes the buffers for
    what holds whatever the rounding (n corners become at most n + n // 2: CLIP_MAX_OUT = 19);
    this case overflowed the 8-corner buffers it had before."""
    max_out = fw.symbol("CLIP_MAX_OUT")
    buffer_a, after_b = fw.symbol("clip_polygon_a"), fw.symbol("render_rv_out")
    corners = np.array([[bits_f32(v) for v in c] + [0.0] * ATTRIBUTES for c in NINE_CORNER_TRIANGLE],
                       dtype=np.float32)
    codes = [frustum_outcode(c, guard_band(fw)) for c in corners]
    assert codes[0] & codes[1] & codes[2] & fw.symbol("OUT_FRUSTUM") == 0, "render_frame would reject it"
    either = codes[0] | codes[1] | codes[2]
    assert either & fw.symbol("OUT_NEAR") and either & fw.symbol("OUT_GUARD"), "clip_and_draw would skip planes"
    fw.write(after_b, CANARY[:CV_BYTES])
    source, output, count = buffer_a, fw.symbol("clip_polygon_b"), len(corners)
    fw.write_f32(source, corners.ravel())
    for plane in range(len(PLANE_NAMES)):
        count = fw.call("clip_polygon", [source, count, output, plane_address(fw, plane)]).a[0]
        source, output = output, source
    assert count == 9 > 8, f"{count} corners: no longer the rounding case this test is about"
    assert count <= max_out and fw.read(after_b, CV_BYTES) == CANARY[:CV_BYTES], \
        f"{count} corners after the five planes; room for {max_out}"


def test_clip_max_out_is_the_bound_whatever_the_rounding(fw):
    """CLIP_MAX_OUT follows the bound: 3 corners, at most 4 after the near plane (a triangle
    cannot alternate), then n + n // 2 for each of the four guard sides."""
    n = 4
    for _ in range(4):
        n += n // 2
    assert fw.symbol("CLIP_MAX_OUT") == n == 19


# --------------------------------------------------------------------------- clip_segment, segment_point

@dataclass(frozen=True)
class Screen:
    half_w: float                # SCREEN_HALF_W_Q4
    half_h: float


def screen(fw: FirmwareCaller) -> Screen:
    return Screen(fw.symbol("SCREEN_HALF_W_Q4"), fw.symbol("SCREEN_HALF_H_Q4"))


def model_project(point: np.ndarray, scr: Screen) -> tuple[float, float]:
    """project_clip's documented viewport, unrounded: ((x / w + 1) W / 2, (1 - y / w) H / 2) in Q4."""
    x, y, _, w = (float(v) for v in point[:4])
    return (x / w + 1) * scr.half_w, (1 - y / w) * scr.half_h


def q4_error_bound(point: np.ndarray, error: np.ndarray, scr: Screen) -> tuple[float, float]:
    """How far the firmware's unrounded Q4 position of `point` may be from the model's when its
    clip coordinates carry float32 errors `error` (x, y, z, w): the errors through x / w (first
    order), then 1 / w, the product and the viewport's fmadd, each rounded once (3u relative)."""
    x, y, _, w = (float(v) for v in point[:4])
    out = []
    for coordinate, e, half in ((x, error[0], scr.half_w), (y, error[1], scr.half_h)):
        ratio = abs(coordinate / w)
        out.append(half * ((e + ratio * error[3]) / abs(w) + 3 * U * (ratio + 1)))
    return out[0], out[1]


def outcode_bits(fw: FirmwareCaller) -> dict[str, int]:
    return {bit: fw.symbol(bit) for bit in ("OUT_NEAR", "OUT_GUARD")}


def model_segment(a: np.ndarray, b: np.ndarray, outcodes: int, planes, out: dict[str, int]):
    """Liang-Barsky as clip_segment documents it, in float64: t from 0 to 1 narrowed at each
    crossing of the planes an end is outside of. Returns (t enter, t leave) or None."""
    t0, t1 = 0.0, 1.0
    for number, plane in enumerate(planes):
        if not outcodes & (out["OUT_NEAR"] if number == NEAR else out["OUT_GUARD"]):
            continue
        da, db = distance(plane, a), distance(plane, b)
        if da < 0 and db < 0:
            return None
        if da < 0 or db < 0:
            t = da / (da - db)
            t0, t1 = (max(t0, t), t1) if da < 0 else (t0, min(t1, t))
    return None if t1 < t0 else (t0, t1)


def write_position(fw: FirmwareCaller, address: int, clip: np.ndarray) -> None:
    """A clip-space position as vertex_clip writes it (render.inc CLIP_POS_*): x, y, z, w
    (clip_segment takes the outcodes in a2 and projects the position itself)."""
    fw.write_f32(address, clip[:4])


def fw_project(fw: FirmwareCaller, clip: np.ndarray) -> tuple[int, int]:
    result = fw.call("project_clip", fargs=[float(v) for v in clip[:4]])
    return result.a_signed(0, 32), result.a_signed(1, 32)


# (name, a, b) in clip space (x, y, z, w)
SEGMENTS = [
    ("b-behind-near", (0.5, -0.25, 0.75, 2.0), (-1.3, 0.7, -1.5, 0.25)),
    ("a-behind-near", (-1.25, 2.5, -0.625, 0.5), (0.375, -0.5, 1.5, 3.0)),
    ("b-beyond-right", (0.3, 0.2, 0.5, 1.5), (60.0, -5.0, 0.75, 2.0)),
    ("a-beyond-bottom", (3.0, -70.0, 1.0, 2.5), (-0.5, 0.25, 0.6, 1.25)),
    ("left-to-top", (-45.0, 3.0, 0.5, 2.0), (4.0, 52.0, 1.5, 3.0)),
    ("left-to-behind", (-9.0, 1.0, 0.4, 0.5), (2.0, -3.0, -2.0, 1.0)),
]


@pytest.mark.parametrize("name,a,b", SEGMENTS, ids=[s[0] for s in SEGMENTS])
def test_clip_segment_cuts_as_liang_barsky(fw, name, a, b):
    """Ends cut at the near plane and at the guard planes where Liang-Barsky puts them (within
    the float32 bound after rounding to Q4), and an end not cut off projected exactly as
    project_clip projects the vertex itself (segment_point's t = 0 and t = 1)."""
    out = outcode_bits(fw)
    g, planes, scr = guard_band(fw), documented_planes(fw), screen(fw)
    a, b = np.array(a, dtype=np.float32), np.array(b, dtype=np.float32)
    outcodes = frustum_outcode(a, g) | frustum_outcode(b, g)
    span = model_segment(a, b, outcodes, planes, out)
    assert span is not None and span != (0.0, 1.0), "every case here cuts something and keeps something"
    position_a, position_b = fw.scratch, fw.scratch + fw.symbol("CLIP_POS_BYTES")
    write_position(fw, position_a, a)
    write_position(fw, position_b, b)
    result = fw.call("clip_segment", [position_a, position_b, outcodes])
    assert result.a[0] == 1, "clip_segment dropped a segment that has a part left"
    ends = [(result.a_signed(1, 32), result.a_signed(2, 32)), (result.a_signed(3, 32), result.a_signed(4, 32))]
    a64, b64 = a.astype(np.float64), b.astype(np.float64)
    for end, t, vertex in zip(ends, span, (a, b), strict=True):
        if t in (0.0, 1.0):
            assert end == fw_project(fw, vertex), f"an end not cut off ({t=}) is not project_clip of the vertex"
            continue
        point = a64 + t * (b64 - a64)
        bound = q4_error_bound(point, cut_tolerance(a[:4], b[:4]), scr)
        want = model_project(point, scr)
        for got, exact, e in zip(end, want, bound, strict=True):
            assert abs(got - exact) <= 0.5 + e, f"cut end at t = {t}: Q4 {end} vs model {want} (bound 0.5 + {bound})"


def test_clip_segment_keeps_an_uncut_end_exactly(fw):
    """The end towards b is not cut off (t = 1) and comes out as project_clip of b itself,
    although b's coordinates are tiny beside a's: a + 1 (b - a) in float32 would lose b's low
    bits and, b's w being small, land several Q4 units away (checked first, so that this test
    fails for a firmware that interpolates from a at t = 1). a is cut at the near plane only
    (it is inside the guard band), at t = 1/6, far from b."""
    out, g, planes, scr = outcode_bits(fw), guard_band(fw), documented_planes(fw), screen(fw)
    a = np.array([3000.0, -150.0, -0.1, 200.0], dtype=np.float32)
    b = np.array([0.3, 0.1, 0.5, 0.03], dtype=np.float32)
    naive = np.array([np.float32(np.float32(q - p) + p) for p, q in zip(a, b, strict=True)], dtype=np.float32)
    assert fw_project(fw, naive) != fw_project(fw, b)
    outcodes = frustum_outcode(a, g) | frustum_outcode(b, g)
    assert outcodes & (out["OUT_NEAR"] | out["OUT_GUARD"]) == out["OUT_NEAR"]
    t_enter, t_leave = model_segment(a, b, outcodes, planes, out)
    assert t_leave == 1.0
    position_a, position_b = fw.scratch, fw.scratch + fw.symbol("CLIP_POS_BYTES")
    write_position(fw, position_a, a)
    write_position(fw, position_b, b)
    result = fw.call("clip_segment", [position_a, position_b, outcodes])
    assert result.a[0] == 1
    assert (result.a_signed(3, 32), result.a_signed(4, 32)) == fw_project(fw, b)
    point = a.astype(np.float64) + t_enter * (b.astype(np.float64) - a)
    bound = q4_error_bound(point, cut_tolerance(a, b), scr)
    for got, exact, e in zip((result.a_signed(1, 32), result.a_signed(2, 32)), model_project(point, scr), bound,
                             strict=True):
        assert abs(got - exact) <= 0.5 + e


DROPPED = [
    ("both-behind-near", (0.5, 0.5, -0.25, 1.0), (-3.0, 1.0, -2.0, 2.0)),
    ("both-beyond-right", (40.0, 1.0, 0.5, 2.0), (50.0, -60.0, 1.0, 3.0)),
    ("past-the-band-corner", (-20.0, 14.0, 0.5, 1.0), (-14.0, 20.0, 0.5, 1.0)),
]


@pytest.mark.parametrize("name,a,b", DROPPED, ids=[s[0] for s in DROPPED])
def test_clip_segment_drops_what_is_outside(fw, name, a, b):
    """A segment wholly outside one plane, and one that passes outside the guard square's
    corner (it leaves through the top before it enters through the left side), leave nothing:
    a0 = 0."""
    out = outcode_bits(fw)
    g, planes = guard_band(fw), documented_planes(fw)
    a, b = np.array(a, dtype=np.float32), np.array(b, dtype=np.float32)
    outcodes = frustum_outcode(a, g) | frustum_outcode(b, g)
    assert model_segment(a, b, outcodes, planes, out) is None
    position_a, position_b = fw.scratch, fw.scratch + fw.symbol("CLIP_POS_BYTES")
    write_position(fw, position_a, a)
    write_position(fw, position_b, b)
    assert fw.call("clip_segment", [position_a, position_b, outcodes]).a[0] == 0


def test_segment_point_ends_are_the_vertices(fw):
    """segment_point at t = 0 is a and at t = 1 is b, bit for bit (at t = 1 it computes
    b + 0 (a - b)); in between it is a + t (b - a) within the cut bound. The coordinates are
    chosen so that a + 1 (b - a) in float32 is not b (b - a loses b's low bits), so the t = 1
    check fails for a firmware that interpolates from a."""
    a = np.array([3000.0, -1.0, 2.5, 7.0], dtype=np.float32)
    b = np.array([0.3, 2.0 ** -30, 0.1, 0.03], dtype=np.float32)
    naive = np.array([np.float32(np.float32(q - p) + p) for p, q in zip(a, b, strict=True)], dtype=np.float32)
    assert naive.tobytes() != b.tobytes()
    position_a, position_b = fw.scratch, fw.scratch + fw.symbol("CLIP_POS_BYTES")
    write_position(fw, position_a, a)
    write_position(fw, position_b, b)
    for t in (0.0, 1.0, 0.375):
        result = fw.call("segment_point", [position_a, position_b], fargs=[t])
        got = np.array([result.fa(n) for n in range(4)], dtype=np.float32)
        if t in (0.0, 1.0):
            want = a if t == 0.0 else b
            assert got.tobytes() == want.tobytes(), f"segment_point at t = {t}: {got}, want {want}"
        else:
            exact = a.astype(np.float64) + t * (b.astype(np.float64) - a)
            # t is exact here (3/8), so only q - p and the fmadd round: 2u (|a| + |b|)
            assert np.all(np.abs(got - exact) <= 2 * U * (np.abs(a) + np.abs(b).astype(np.float64))), got
