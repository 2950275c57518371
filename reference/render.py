"""One frame, rendered exactly (float64) with the firmware's documented conventions.

Written for clarity, not speed: it is the yardstick for the firmware's trade-offs.

Conventions (docs/design/firmware.md "Rendering", firmware/vertex.S, render.S, raster.S, maths.S):
- right-handed; the camera at the origin looking down -z; no view matrix (world = eye space);
- model matrix M = T R S, R the rotation by the unit quaternion about the (normalised) axis by
  angle + n * step degrees (right-hand rule);
- projection (D3D-style depth, 0 at near, 1 at far), f = cot(fov / 2), aspect 320 / 240:
  [[f/aspect, 0, 0, 0], [0, f, 0, 0], [0, 0, far/(near-far), near far/(near-far)], [0, 0, -1, 0]];
- screen x = (x/w + 1) * 160, y = (1 - y/w) * 120 (y down); pixel (x, y) covers
  [x, x+1) x [y, y+1) and is sampled at its centre (x + 0.5, y + 0.5);
- trivial rejection by outcodes; triangles cut at the near plane (clip z >= 0) in homogeneous
  clip space, attributes interpolated linearly in clip space;
- signed area (x1-x0)(y2-y0) - (x2-x0)(y1-y0) < 0 (y down) = counter-clockwise as seen = front;
  0 = degenerate (nothing drawn); > 0 = back, dropped when cull is on;
- inside: every edge function (b - a) x (p - a) >= 0 once the corners are in positive order,
  and a centre exactly on an edge belongs to the triangle only for a top edge (dy = 0, dx > 0)
  or a left edge (dy < 0) -- the top-left rule;
- depth z/w (affine in screen space), cleared to 1.0 (the far plane), nearer strictly wins;
- lighting, I = max(ambient, N.L / |N|) with L = `light` (ambient where |N| = 0):
  - a face whose three corners have a normal (vn): per pixel (Phong), N the perspective-correct
    interpolation (as u, v) of the corners' world normals R C n / |R C n|, R the frame's
    rotation and C = diag(sy sz, sx sz, sx sy) the cofactor matrix of the scale (det(S) S^-T,
    finite at scale 0; a corner whose normal comes out zero contributes nothing);
  - any other face: per face from its geometric normal N = (w1 - w0) x (w2 - w0), the
    world-space corners (so a model without vn is lit per face throughout);
- flat mode: 0xC618 lit; textured: perspective-correct (u, v), texel column floor(u W) mod W,
  row floor((1 - v) H) mod H (v = 0 is the bottom of the image), lit; a corner without vt
  takes (0, 0); each pixel's channels are multiplied by that pixel's I;
- texture filtering (`filter`, firmware/raster.S): `nearest` as above; `bilinear` samples at
  (s - 1/2, t - 1/2) with s = u W, t = (1 - v) H, the four texels around it (repeating) weighed
  by the fractions, channels blended as stored (RGB565, not linear light), then lit;
  `mipmap`: the chain `mip_chain` builds (each level a box average of the one above), the level
  the footprint chooses per pixel (`mip_level`: round(log2 rho), rho^2 = |det J| the area of the
  pixel's footprint in texels, J the exact Jacobian of (s, t) over screen (x, y) at the
  centre), bilinear within it at s W_l / W - 1/2, t H_l / H - 1/2; `anisotropic`: the same
  chain, taps along the footprint's longer axis in the level of its length over the taps
  (`anisotropic`);
- wireframe: the unique (min, max) vertex index edges, white, no depth test or culling,
  rejected by outcodes, cut at the near plane, clipped to the screen rectangle [0, 320] x [0, 240]
  (Liang-Barsky), each end in the pixel it lies in (floor, clamped), Bresenham from the smaller
  index (or from the end in front of the near plane when one end is cut).

Where the reference is exact and the firmware is not (these are what the comparison measures):
- float64 throughout, numbers as written in the files (the firmware: single precision, its own
  sin/cos polynomials);
- screen positions are not snapped to 1/16 pixel;
- lighting from the vertex normals per pixel, which describe the surface the model's author
  meant (the firmware's Phong shading lights this way too, in single precision): the firmware's
  flat shading (one I per face, from the geometric normal) and Gouraud
  shading (I per corner, interpolated) both approximate it; the two agree with the reference
  only on faces whose corner normals equal the face normal, or without vn;
- each RGB565 channel times I rounded to nearest (the firmware quantises I to
  k = round(64 I), or to its `light_levels`, and rounds channel * k / 64; above 65 levels k / 65536);
- texture coordinates: exact perspective-correct interpolation (the firmware interpolates
  u/w, v/w, 1/w incrementally in single precision and divides once per pixel);
- bilinear weights: exact fractions (the firmware's are in 1/32 texel, truncated) and one
  rounding of the lit blend (the firmware's is the same, with k / 64 or k / 65536 for I); the mip level
  from the exact Jacobian (the firmware's from its float32 planes, |det H| w^3);
- wireframe end points: exact projections (the firmware converts its Q4 positions to pixels).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .obj import Mesh
from .scene import Scene

WIDTH, HEIGHT = 320, 240
FLAT_COLOUR = 0xC618
WIRE_COLOUR = 0xFFFF

# outcode bits (render.inc)
OUT_LEFT, OUT_RIGHT, OUT_BOTTOM, OUT_TOP, OUT_NEAR, OUT_FAR = (1 << i for i in range(6))


# --------------------------------------------------------------------------- matrices

def rotation_matrix(axis, degrees: float) -> np.ndarray:
    """The 3x3 rotation of the unit quaternion (cos(a/2), sin(a/2) axis)."""
    axis = np.asarray(axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    half = math.radians(degrees) / 2.0
    w = math.cos(half)
    x, y, z = math.sin(half) * axis
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def model_matrix(scene: Scene, n: int) -> np.ndarray:
    """T R S for frame n."""
    m = np.eye(4)
    m[:3, :3] = rotation_matrix(scene.axis, scene.angle + n * scene.step) @ np.diag(scene.scale)
    m[:3, 3] = scene.translate
    return m


def projection_matrix(scene: Scene) -> np.ndarray:
    f = 1.0 / math.tan(math.radians(scene.fov) / 2.0)
    aspect = WIDTH / HEIGHT
    near, far = scene.near, scene.far
    return np.array([
        [f / aspect, 0, 0, 0],
        [0, f, 0, 0],
        [0, 0, far / (near - far), near * far / (near - far)],
        [0, 0, -1, 0],
    ], dtype=np.float64)


def outcodes(clip: np.ndarray) -> np.ndarray:
    x, y, z, w = clip.T
    return ((x < -w) * OUT_LEFT | (x > w) * OUT_RIGHT | (y < -w) * OUT_BOTTOM | (y > w) * OUT_TOP
            | (z < 0) * OUT_NEAR | (z > w) * OUT_FAR).astype(np.int64)


def to_screen(clip: np.ndarray) -> np.ndarray:
    """Screen positions in pixels (x right, y down) of clip-space points with w > 0."""
    x, y, w = clip[..., 0], clip[..., 1], clip[..., 3]
    return np.stack([(x / w + 1.0) * (WIDTH / 2), (1.0 - y / w) * (HEIGHT / 2)], axis=-1)


# --------------------------------------------------------------------------- colours

def rgb565_channels(colour: int) -> tuple[int, int, int]:
    return (colour >> 11) & 31, (colour >> 5) & 63, colour & 31


def shade(colours, intensity: float):
    """RGB565 colour(s) with each channel times the intensity, rounded to nearest."""
    c = np.asarray(colours, dtype=np.int64)
    r = np.floor(((c >> 11) & 31) * intensity + 0.5).astype(np.int64)
    g = np.floor(((c >> 5) & 63) * intensity + 0.5).astype(np.int64)
    b = np.floor((c & 31) * intensity + 0.5).astype(np.int64)
    out = (np.minimum(r, 31) << 11) | (np.minimum(g, 63) << 5) | np.minimum(b, 31)
    return out.astype(np.uint16)


def rgb565_to_rgb888(pixels: np.ndarray) -> np.ndarray:
    """As the board model's LCD shows RGB565 (emulator/grab.py rgb565_image): 5 -> 6 bits by
    r << 1 | r >> 4, then 6 -> 8 bits by c << 2 | c >> 4."""
    pixels = np.asarray(pixels, dtype=np.uint16)
    r5, g6, b5 = (pixels >> 11) & 31, (pixels >> 5) & 63, pixels & 31
    image = np.empty(pixels.shape + (3,), dtype=np.uint8)
    for channel, six in enumerate(((r5 << 1) | (r5 >> 4), g6, (b5 << 1) | (b5 >> 4))):
        image[..., channel] = ((six << 2) | (six >> 4)).astype(np.uint8)
    return image


def normal_matrix(scene: Scene, n: int) -> np.ndarray:
    """R C for frame n: R the rotation, C = diag(sy sz, sx sz, sx sy) the cofactor matrix of the
    scale S (det(S) S^-T: normals transform by it, and it stays finite when a scale is 0). A
    mirroring scale (det(S) < 0) turns the normals round, as it does the face normal
    (w1 - w0) x (w2 - w0) of the mirrored corners, so the two keep agreeing."""
    sx, sy, sz = scene.scale
    cofactor = np.diag([sy * sz, sx * sz, sx * sy])
    return rotation_matrix(scene.axis, scene.angle + n * scene.step) @ cofactor


def unit_rows(vectors: np.ndarray) -> np.ndarray:
    """Each row divided by its length; a row of length 0 stays zero."""
    vectors = np.asarray(vectors, dtype=np.float64)
    length = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return np.divide(vectors, length, out=np.zeros_like(vectors), where=length > 0)


def world_normals(mesh: Mesh, scene: Scene, n: int) -> np.ndarray:
    """The mesh's normals (vn) in world space for frame n, unit length (zero rows where the
    transformed normal is zero: a zero vn, or a scale of 0 on two axes)."""
    return unit_rows(mesh.normals @ normal_matrix(scene, n).T)


def corner_normals(face: np.ndarray, normals: np.ndarray) -> np.ndarray | None:
    """The world normals (3, 3) of a face's corners, or None when a corner has no normal
    (no vn index, or one out of range): such a face is lit per face."""
    indices = face[:, 2]
    if not np.all((indices >= 0) & (indices < len(normals))):
        return None
    return normals[indices]


def face_intensity(world: np.ndarray, scene: Scene) -> float:
    """max(ambient, N.L / |N|), N = (w1 - w0) x (w2 - w0); ambient for a degenerate face."""
    normal = np.cross(world[1] - world[0], world[2] - world[0])
    length = np.linalg.norm(normal)
    if length == 0.0:
        return scene.ambient
    return max(scene.ambient, float(np.dot(normal, scene.light)) / length)


# --------------------------------------------------------------------------- triangles

def clip_near(corners: np.ndarray) -> np.ndarray:
    """Sutherland-Hodgman against z >= 0 of rows (x, y, z, w, attributes...): 0, 3 or 4 rows.
    An edge is cut from its corner in front towards the one behind, z set to exactly 0."""
    out = []
    for i in range(len(corners)):
        a, b = corners[i], corners[(i + 1) % len(corners)]
        a_in, b_in = a[2] >= 0, b[2] >= 0
        if a_in:
            out.append(a)
        if a_in != b_in:
            p, q = (a, b) if a_in else (b, a)
            t = p[2] / (p[2] - q[2])
            cut = p + t * (q - p)
            cut[2] = 0.0
            out.append(cut)
    return np.array(out)


def edge_function(a: np.ndarray, b: np.ndarray, px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """(b - a) x (p - a), computed with the end points in a canonical order and negated when
    swapped, so that the two triangles sharing an edge get exactly opposite values (no crack,
    no pixel drawn twice even where rounding would otherwise disagree)."""
    if (a[0], a[1]) > (b[0], b[1]):
        return -edge_function(b, a, px, py)
    return (b[0] - a[0]) * (py - a[1]) - (b[1] - a[1]) * (px - a[0])


def owns_ties(a: np.ndarray, b: np.ndarray) -> bool:
    """Top-left rule for the edge a -> b of a triangle in positive order (y down)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    return dy < 0 or (dy == 0 and dx > 0)


@dataclass(frozen=True)
class Lighting:
    """How a triangle is lit: with `normals` None, by `intensity` at every pixel (face
    lighting); otherwise per pixel, I = max(ambient, N.L / |N|) with N the perspective-correct
    interpolation of the corners' world normals `normals` (3, 3), and ambient where |N| = 0."""
    intensity: float = 1.0
    normals: np.ndarray | None = None
    light: tuple[float, float, float] = (0.0, 0.0, 1.0)     # unit, towards the light
    ambient: float = 0.0

    def at(self, weights: np.ndarray) -> float | np.ndarray:
        """The intensity at pixels whose perspective-correct corner weights are `weights`
        (3, P), each column summing to 1: a number (face lighting) or one per pixel (P,)."""
        if self.normals is None:
            return self.intensity
        normal = weights.T @ self.normals                       # (P, 3)
        length = np.linalg.norm(normal, axis=1)
        lit = length > 0
        intensity = np.full(len(length), float(self.ambient))
        cosine = (normal[lit] @ np.asarray(self.light, dtype=np.float64)) / length[lit]
        intensity[lit] = np.maximum(self.ambient, cosine)
        return intensity


UNLIT = Lighting()                 # intensity 1: the colour as given


class Target:
    """The colour and depth buffers of one frame."""

    def __init__(self, background: int):
        self.colour = np.full((HEIGHT, WIDTH), background, dtype=np.uint16)
        self.depth = np.ones((HEIGHT, WIDTH), dtype=np.float64)


def front_facing(screen: np.ndarray, cull: bool) -> tuple[list[int], float] | None:
    """The corner order that puts a triangle's screen corners (3, 2) in positive order, and its
    area then (twice the triangle's), or None: degenerate, or a back face culled."""
    (x0, y0), (x1, y1), (x2, y2) = screen
    area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
    if area == 0 or not math.isfinite(area):
        return None
    if area > 0:
        return None if cull else ([0, 1, 2], area)      # a back face
    return [0, 2, 1], -area                             # a front face: into positive order


def pixel_bounds(screen: np.ndarray) -> tuple[int, int, int, int] | None:
    """(xmin, xmax, ymin, ymax): the pixels whose centres the corners' box holds, on the screen;
    None when there are none."""
    xmin = max(0, math.ceil(screen[:, 0].min() - 0.5))
    xmax = min(WIDTH - 1, math.floor(screen[:, 0].max() - 0.5))
    ymin = max(0, math.ceil(screen[:, 1].min() - 0.5))
    ymax = min(HEIGHT - 1, math.floor(screen[:, 1].max() - 0.5))
    if xmin > xmax or ymin > ymax:
        return None
    return xmin, xmax, ymin, ymax


def coverage(screen: np.ndarray, area: float, px: np.ndarray, py: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
    """Which of the points (px, py) a triangle in positive order (front_facing) covers, by the
    edge functions and the top-left rule, and each corner's barycentric weight there (the edge
    opposite it over `area`)."""
    inside = np.ones(np.shape(px), dtype=bool)
    weights = []
    for i in range(3):
        a, b = screen[(i + 1) % 3], screen[(i + 2) % 3]
        e = edge_function(a, b, px, py)
        inside &= (e >= 0) if owns_ties(a, b) else (e > 0)
        weights.append(e / area)
    return inside, weights


def raster_triangle(target: Target, screen: np.ndarray, zw: np.ndarray, q: np.ndarray,
                    cull: bool, colour: int | None, uv: np.ndarray | None = None,
                    texture: np.ndarray | None = None, lighting: Lighting = UNLIT,
                    filter: str = "nearest") -> None:
    """One triangle given by its screen corners (3, 2), z/w (3,), 1/w (3,): `colour`, or
    textured (uv (3, 2) per corner, perspective-correct, sampled as `filter` says), each pixel
    lit by `lighting`."""
    facing = front_facing(screen, cull)
    if facing is None:
        return
    order, area = facing
    screen, zw, q = screen[order], zw[order], q[order]
    if uv is not None:
        uv = uv[order]
    if lighting.normals is not None:
        lighting = replace(lighting, normals=lighting.normals[order])
    bounds = pixel_bounds(screen)
    if bounds is None:
        return
    xmin, xmax, ymin, ymax = bounds
    px, py = np.meshgrid(np.arange(xmin, xmax + 1) + 0.5, np.arange(ymin, ymax + 1) + 0.5)
    inside, weights = coverage(screen, area, px, py)
    if not inside.any():
        return
    l0, l1, l2 = (w[inside] for w in weights)
    depth = l0 * zw[0] + l1 * zw[1] + l2 * zw[2]
    ys, xs = np.nonzero(inside)
    ys, xs = ys + ymin, xs + xmin
    nearer = depth < target.depth[ys, xs]
    if not nearer.any():
        return
    ys, xs, depth = ys[nearer], xs[nearer], depth[nearer]
    l0, l1, l2 = l0[nearer], l1[nearer], l2[nearer]
    target.depth[ys, xs] = depth
    # perspective-correct weights: attribute = sum(l_i a_i / w_i) / sum(l_i / w_i)
    inv_w = l0 * q[0] + l1 * q[1] + l2 * q[2]
    weights = np.stack([l0 * q[0], l1 * q[1], l2 * q[2]]) / inv_w          # (3, P)
    intensity = lighting.at(weights)
    if texture is None or uv is None:
        target.colour[ys, xs] = shade(colour, intensity)
        return
    u = (l0 * uv[0, 0] * q[0] + l1 * uv[1, 0] * q[1] + l2 * uv[2, 0] * q[2]) / inv_w
    v = (l0 * uv[0, 1] * q[0] + l1 * uv[1, 1] * q[1] + l2 * uv[2, 1] * q[2]) / inv_w
    height, width = texture.shape
    if filter == "nearest":
        column = np.floor(u * width).astype(np.int64) % width
        row = np.floor((1.0 - v) * height).astype(np.int64) % height
        target.colour[ys, xs] = shade(texture[row, column], intensity)
        return
    s_texel, t_texel = u * width, (1.0 - v) * height
    if filter == "bilinear":
        channels = bilinear(texture, s_texel, t_texel)
    else:
        chain = mip_chain(texture)
        # the footprint: d(s, t) / d(x, y) from the planes U = s q, V = t q, q, each affine in
        # screen space (the barycentric weights' gradients are the edges' over the area)
        grad_l = []
        for i in range(3):
            a, b = screen[(i + 1) % 3], screen[(i + 2) % 3]
            grad_l.append((-(b[1] - a[1]) / area, (b[0] - a[0]) / area))
        ucol = np.array([uv[i, 0] * q[i] * width for i in range(3)])
        vcol = np.array([(1.0 - uv[i, 1]) * q[i] * height for i in range(3)])
        gx, gy = np.array([g[0] for g in grad_l]), np.array([g[1] for g in grad_l])
        jac = np.array([[(ucol @ gx - s_texel * (q @ gx)) / inv_w, (ucol @ gy - s_texel * (q @ gy)) / inv_w],
                        [(vcol @ gx - t_texel * (q @ gx)) / inv_w, (vcol @ gy - t_texel * (q @ gy)) / inv_w]])
        if filter == "anisotropic":
            channels = anisotropic(chain, jac, s_texel, t_texel)
        else:
            rho2 = np.abs(jac[0, 0] * jac[1, 1] - jac[0, 1] * jac[1, 0])
            level = mip_level(rho2, len(chain))
            channels = np.zeros((len(s_texel), 3))
            for number in np.unique(level):
                pick = level == number
                mip = chain[number]
                channels[pick] = bilinear(mip, s_texel[pick] * (mip.shape[1] / width),
                                          t_texel[pick] * (mip.shape[0] / height))
    target.colour[ys, xs] = shade_channels(channels, intensity)


ANISO_MAX_TAPS_LOG2 = 3         # at most 8 taps (firmware/include/render.inc ANISO_MAX_TAPS_LOG2)


def anisotropic(chain: list[np.ndarray], jac: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(P, 3) float channels: `filter = anisotropic` at texel coordinates (s, t) of the base level
    with Jacobian `jac` (2, 2, P) (rows s, t; columns x, y). The footprint's axes are taken as the
    Jacobian's columns: the longer one, `major`, is walked by N = 2^k taps (k = round(log2(major /
    minor)), the halves rounded up as (e + 1) >> 1 of major^2 / minor^2's exponent e, at most
    2^ANISO_MAX_TAPS_LOG2), each bilinear in the level of major / N (mip_level of major^2 / 4^k),
    evenly spaced about the centre: (i - (N - 1) / 2) / N of the major axis, i = 0 .. N - 1; the
    taps' channels averaged."""
    width = chain[0].shape[1]
    height = chain[0].shape[0]
    lx2 = jac[0, 0] ** 2 + jac[1, 0] ** 2
    ly2 = jac[0, 1] ** 2 + jac[1, 1] ** 2
    x_major = lx2 >= ly2
    major2, minor2 = np.where(x_major, lx2, ly2), np.where(x_major, ly2, lx2)
    axis_s = np.where(x_major, jac[0, 0], jac[0, 1])
    axis_t = np.where(x_major, jac[1, 0], jac[1, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio2 = major2 / minor2
    finite = np.isfinite(ratio2) & (ratio2 > 0)
    _, exponent = np.frexp(np.where(finite, ratio2, 1.0))           # ratio^2 = m 2^exponent, m in [1/2, 1)
    k = np.where(finite, np.clip((exponent - 1 + 1) >> 1, 0, ANISO_MAX_TAPS_LOG2), ANISO_MAX_TAPS_LOG2)
    level = mip_level(major2 / 4.0 ** k, len(chain))
    channels = np.zeros((len(s), 3))
    for taps_log2 in np.unique(k):
        for number in np.unique(level[k == taps_log2]):
            pick = (k == taps_log2) & (level == number)
            mip = chain[number]
            taps = 1 << int(taps_log2)
            for i in range(taps):
                along = (i - (taps - 1) / 2) / taps
                channels[pick] += bilinear(mip, (s[pick] + along * axis_s[pick]) * (mip.shape[1] / width),
                                           (t[pick] + along * axis_t[pick]) * (mip.shape[0] / height))
            channels[pick] /= taps
    return channels


def bilinear(texture: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(P, 3) float RGB565 channels: the texture at texel coordinates (s, t) (texel (i, j) covers
    [i, i + 1) x [j, j + 1), its centre at + 1/2), the four nearest texel centres weighed by
    the fractions, repeating."""
    height, width = texture.shape
    s, t = np.asarray(s, dtype=np.float64) - 0.5, np.asarray(t, dtype=np.float64) - 0.5
    i0, j0 = np.floor(s), np.floor(t)
    fx, fy = s - i0, t - j0
    i0, j0 = i0.astype(np.int64) % width, j0.astype(np.int64) % height
    i1, j1 = (i0 + 1) % width, (j0 + 1) % height
    out = np.zeros((len(s), 3))
    for rows, cols, weight in ((j0, i0, (1 - fx) * (1 - fy)), (j0, i1, fx * (1 - fy)),
                               (j1, i0, (1 - fx) * fy), (j1, i1, fx * fy)):
        c = texture[rows, cols].astype(np.int64)
        out += weight[:, None] * np.stack([(c >> 11) & 31, (c >> 5) & 63, c & 31], axis=-1)
    return out


def shade_channels(channels: np.ndarray, intensity) -> np.ndarray:
    """RGB565 from (P, 3) float channels, each times the intensity and rounded to nearest."""
    lit = np.floor(np.asarray(channels) * np.asarray(intensity, dtype=np.float64).reshape(-1, 1) + 0.5)
    r, g, b = (np.minimum(lit[:, i], top).astype(np.int64) for i, top in ((0, 31), (1, 63), (2, 31)))
    return ((r << 11) | (g << 5) | b).astype(np.uint16)


def mip_size(width: int, height: int, level: int) -> tuple[int, int]:
    """The size of mip level `level`: each side halved (rounded down) per level, at least 1."""
    return max(1, width >> level), max(1, height >> level)


def mip_levels(width: int, height: int) -> int:
    """How many levels the chain has: down to 1 x 1, the base texture included."""
    return max(width, height).bit_length()


def mip_chain(texture: np.ndarray) -> list[np.ndarray]:
    """The mip chain the firmware builds at load time (render.S mip_build): level 0 is the
    texture; texel (i, j) of level l + 1 is the mean of texels 2i, 2i + 1 by 2j, 2j + 1 of level
    l, each RGB565 channel rounded to nearest (half up); where level l's side is odd the last
    texel of level l + 1 takes the three last columns (rows) of level l, so every texel
    contributes; a side of 1 stays 1 (the texel itself). Kept for the last few textures (a
    frame asks for it once per triangle)."""
    key = id(texture)
    cached = _MIP_CACHE.get(key)
    if cached is not None and cached[0] is texture:
        return cached[1]
    chain = [np.asarray(texture, dtype=np.uint16)]
    height, width = texture.shape
    for level in range(1, mip_levels(width, height)):
        above = chain[-1].astype(np.int64)
        channels = np.stack([(above >> 11) & 31, (above >> 5) & 63, above & 31], axis=-1)
        new_w, new_h = mip_size(width, height, level)
        sums, counts = _halve(channels, new_h, axis=0)
        sums, col_counts = _halve(sums, new_w, axis=1)
        count = counts[:, None, None] * col_counts[None, :, None]
        mean = (sums + count // 2) // count
        chain.append(((mean[..., 0] << 11) | (mean[..., 1] << 5) | mean[..., 2]).astype(np.uint16))
    if len(_MIP_CACHE) >= 4:
        _MIP_CACHE.clear()
    _MIP_CACHE[key] = (texture, chain)
    return chain


_MIP_CACHE: dict[int, tuple[np.ndarray, list[np.ndarray]]] = {}


def _halve(values: np.ndarray, new: int, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Sums of pairs along `axis` (2k, 2k + 1), the last pair taking the odd one left over; a side
    of 1 stays as it is. Returns (sums, how many each sum took)."""
    old = values.shape[axis]
    if old == 1:
        return values, np.ones(1, dtype=np.int64)
    take = np.take(values, np.arange(0, 2 * new, 2), axis=axis) + np.take(values, np.arange(1, 2 * new, 2), axis=axis)
    counts = np.full(new, 2, dtype=np.int64)
    if old % 2:
        last = [slice(None)] * values.ndim
        last[axis] = slice(new - 1, new)
        extra = [slice(None)] * values.ndim
        extra[axis] = slice(old - 1, old)
        take[tuple(last)] += values[tuple(extra)]
        counts[-1] = 3
    return take, counts


def mip_level(rho2: np.ndarray, levels: int) -> np.ndarray:
    """The level each pixel samples: round(log2 rho) (halves up) with rho^2 the footprint's area
    in texels, clamped to 0 .. levels - 1. With e = floor(log2 rho^2), that is (e + 1) >> 1, which
    the firmware takes from rho^2's float exponent."""
    rho2 = np.asarray(rho2, dtype=np.float64)
    positive = rho2 > 0
    _, exponent = np.frexp(np.where(positive, rho2, 1.0))      # rho^2 = m 2^exponent, m in [1/2, 1)
    level = np.where(positive, (exponent - 1 + 1) >> 1, 0)
    return np.clip(level, 0, levels - 1)


# --------------------------------------------------------------------------- lines

def bresenham(x0: int, y0: int, x1: int, y1: int):
    """raster_line's pixels, both ends included (the error-term form of all octants)."""
    dx, sx = abs(x1 - x0), (1 if x1 >= x0 else -1)
    dy, sy = -abs(y1 - y0), (1 if y1 >= y0 else -1)
    error = dx + dy
    while True:
        yield x0, y0
        if x0 == x1 and y0 == y1:
            return
        e2 = 2 * error
        if e2 >= dy:
            error += dy
            x0 += sx
        if e2 <= dx:
            error += dx
            y0 += sy


def clip_segment(a, b):
    """Liang-Barsky against [0, W] x [0, H]; None when nothing is left."""
    (x0, y0), (x1, y1) = a, b
    dx, dy = x1 - x0, y1 - y0
    t0, t1 = 0.0, 1.0
    for p, q in ((-dx, x0), (dx, WIDTH - x0), (-dy, y0), (dy, HEIGHT - y0)):
        if p == 0:
            if q < 0:
                return None
            continue
        r = q / p
        if p < 0:
            t0 = max(t0, r)
        else:
            t1 = min(t1, r)
        if t1 < t0:
            return None
    return (x0 + t0 * dx, y0 + t0 * dy), (x0 + t1 * dx, y0 + t1 * dy)


def draw_segment(target: Target, a, b, colour: int) -> None:
    clipped = clip_segment(a, b)
    if clipped is None:
        return
    (xa, ya), (xb, yb) = clipped
    ends = [min(max(math.floor(c), 0), limit - 1)
            for c, limit in ((xa, WIDTH), (ya, HEIGHT), (xb, WIDTH), (yb, HEIGHT))]
    for x, y in bresenham(*ends):
        target.colour[y, x] = colour


def unique_edges(faces: np.ndarray) -> np.ndarray:
    v = faces[:, :, 0]
    pairs = np.concatenate([v[:, [0, 1]], v[:, [1, 2]], v[:, [2, 0]]])
    pairs.sort(axis=1)
    return np.unique(pairs, axis=0)


# --------------------------------------------------------------------------- a frame

@dataclass(frozen=True)
class FrameTriangle:
    """One triangle of a frame as the rasteriser receives it, after the vertex stage and the
    near-plane cut: screen corners (3, 2), z/w (3,), 1/w (3,), texture coordinates (3, 2) when
    the frame is textured (None otherwise) and its lighting. Corners in the model's order (not
    yet culled or put in positive order: that is the rasteriser's business)."""
    screen: np.ndarray
    zw: np.ndarray
    q: np.ndarray
    uv: np.ndarray | None
    lighting: Lighting


def is_textured(scene: Scene, texture: np.ndarray | None) -> bool:
    """Whether the frame is drawn with its texture (textured mode and a texture with texels)."""
    return scene.mode == "textured" and texture is not None and texture.size > 0


def frame_triangles(scene: Scene, mesh: Mesh, texture: np.ndarray | None, n: int):
    """The triangles of frame n in drawing order (faces in file order, each face's near-plane
    pieces as a fan), skipping faces whose corners are all outside one frustum plane. Not for
    wireframe mode (see frame_segments)."""
    points = np.hstack([mesh.vertices, np.ones((len(mesh.vertices), 1))])
    model = model_matrix(scene, n)
    world = (points @ model.T)[:, :3]
    clip = points @ (projection_matrix(scene) @ model).T
    codes = outcodes(clip)
    textured = is_textured(scene, texture)
    normals = world_normals(mesh, scene, n)
    for face in mesh.faces:
        corners = face[:, 0]
        if np.bitwise_and.reduce(codes[corners]):
            continue                                  # all outside one plane
        uv = np.zeros((3, 2))
        if textured:
            for k, t in enumerate(face[:, 1]):
                if 0 <= t < len(mesh.texcoords):
                    uv[k] = mesh.texcoords[t]
        smooth = corner_normals(face, normals)       # None: lit per face
        face_lighting = Lighting(intensity=face_intensity(world[corners], scene)) if smooth is None else None
        # rows x y z w | u v | nx ny nz: the near-plane cut interpolates every column linearly
        # in clip space (the cut corners' normals are not renormalised, so that interpolating
        # over the pieces equals interpolating over the whole triangle)
        attributes = np.hstack([clip[corners], uv, np.zeros((3, 3)) if smooth is None else smooth])
        pieces = clip_near(attributes)
        if len(pieces) < 3:
            continue
        screen = to_screen(pieces)
        zw = pieces[:, 2] / pieces[:, 3]
        q = 1.0 / pieces[:, 3]
        for tri in ([0, 1, 2], [0, 2, 3])[:len(pieces) - 2]:
            if face_lighting is not None:
                lighting = face_lighting
            else:
                lighting = Lighting(normals=pieces[tri, 6:9], light=scene.light, ambient=scene.ambient)
            yield FrameTriangle(screen[tri], zw[tri], q[tri], pieces[tri, 4:6] if textured else None, lighting)


def frame_segments(scene: Scene, mesh: Mesh, n: int):
    """The wireframe edges of frame n as screen end points (a, b), in drawing order: each unique
    edge not outside one frustum plane, cut at the near plane (b then the cut end)."""
    points = np.hstack([mesh.vertices, np.ones((len(mesh.vertices), 1))])
    clip = points @ (projection_matrix(scene) @ model_matrix(scene, n)).T
    codes = outcodes(clip)
    for i, j in unique_edges(mesh.faces):
        if codes[i] & codes[j]:
            continue
        a, b = clip[i], clip[j]
        if (codes[i] | codes[j]) & OUT_NEAR:
            if codes[i] & OUT_NEAR:
                a, b = b, a                      # a = the end in front
            t = a[2] / (a[2] - b[2])
            b = a + t * (b - a)
            b[2] = 0.0
        yield to_screen(a), to_screen(b)


def render_frame(scene: Scene, mesh: Mesh, texture: np.ndarray | None, n: int) -> np.ndarray:
    """Frame n as a (240, 320) uint16 RGB565 array, row 0 at the top."""
    target = Target(scene.background)
    if scene.mode == "wireframe":
        for a, b in frame_segments(scene, mesh, n):
            draw_segment(target, a, b, WIRE_COLOUR)
        return target.colour
    for tri in frame_triangles(scene, mesh, texture, n):
        if tri.uv is not None:
            raster_triangle(target, tri.screen, tri.zw, tri.q, scene.cull, None,
                            uv=tri.uv, texture=texture, lighting=tri.lighting, filter=scene.filter)
        else:
            raster_triangle(target, tri.screen, tri.zw, tri.q, scene.cull, FLAT_COLOUR,
                            lighting=tri.lighting)
    return target.colour


def render_image(scene: Scene, mesh: Mesh, texture: np.ndarray | None, n: int) -> np.ndarray:
    """Frame n as the LCD shows it: (240, 320, 3) uint8 RGB, row 0 at the top."""
    return rgb565_to_rgb888(render_frame(scene, mesh, texture, n))
