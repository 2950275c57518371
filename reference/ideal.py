"""The ideal image: what a camera would see of the scene the pixel-centre reference draws.

render.py samples each pixel at its centre and each texture at its nearest texel, as the firmware
does. Here the same scene (the same triangles, lighting, clipping, culling and depth order, from
render.frame_triangles and render.frame_segments) is integrated over each pixel's area instead:

- every pixel is the average of density x density samples on a regular grid, the sample (i, j)
  of pixel (x, y) at (x + (i + 0.5) / density, y + (j + 0.5) / density), each sample with its own
  depth test (the top-left rule decides a sample exactly on a shared edge, so a closed mesh covers
  each sample once);
- a sample's colour is continuous: the texture is read (texels = "square", the default) as what
  the firmware's nearest-texel rule makes of it, a grid of constant squares (texel (c, r) fills [c, c+1) x [r, r+1) in texel units,
  t = (u W, (1 - v) H), repeating), averaged exactly over the sample's footprint: the rectangle
  centred on the sample's t whose sides are |grad t_x| / density and |grad t_y| / density (from
  the perspective-correct Jacobian at the sample): the image of the sample's cell where the
  texture's axes follow the screen's, a rectangle of the same extent where they turn. A
  footprint within 2 x 2 texels is weighted directly; a larger one sums whole texels through an
  integer summed-area table, so minification of any degree is exact, with no mip levels; or
  (texels = "smooth") as a camera sees a filtered texture, the bilinear surface through the texel
  centres, averaged over the same footprint, exactly (SmoothTexture);
- channels are the RGB565 stored values (red and blue 0-31, green 0-63) as floats, times the
  sample's light intensity (as render.py, lit per pixel where the corners have normals), not
  rounded per sample; the averaging is of stored values, the scale the renderer lights in, not
  of linear light (see docs/reference/reference-renderer.md);
- the pixel is the average of its samples, each channel rounded to nearest into RGB565: the
  closest image the LCD can show;
- wireframe: each edge is a line 1 pixel wide, the points within half a pixel of the segment (a
  capsule, so joints have no notches and ends reach half a pixel beyond the vertex as a
  Bresenham end pixel does); a pixel is the background blended with white by the share of it
  the union of the lines covers (crossings count once), computed exactly along each of
  16 x density sample rows per pixel and averaged over the rows.

Samples are processed in bands of pixel rows so that memory stays bounded whatever the density.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .obj import Mesh
from .render import (FLAT_COLOUR, HEIGHT, WIDTH, WIRE_COLOUR, FrameTriangle, edge_function, frame_segments,
                     frame_triangles, is_textured, owns_ties, rgb565_to_rgb888)
from .scene import Scene

DEFAULT_DENSITY = 8              # samples per pixel along each axis (docs/reference/reference-renderer.md: the convergence measured)
DENSITY_MAX = 64
BAND_SAMPLES = 1 << 20           # samples held at once (about 32 MB of buffers)
CHANNEL_MAX = np.array([31.0, 63.0, 31.0])
FOOTPRINT_SPAN_MAX = float(1 << 40)    # texels: wider footprints are the texture's mean to 1e-12
TEXEL_MODELS = ("square", "smooth")     # how the ideal reads a texture (BoxTexture, SmoothTexture)


def channels(colour: int | np.ndarray) -> np.ndarray:
    """RGB565 colour(s) as float channels (..., 3): red 0-31, green 0-63, blue 0-31."""
    c = np.asarray(colour, dtype=np.int64)
    return np.stack([(c >> 11) & 31, (c >> 5) & 63, c & 31], axis=-1).astype(np.float64)


def pack_rgb565(values: np.ndarray) -> np.ndarray:
    """Float channels (..., 3) in RGB565 units rounded to nearest (and into range) as RGB565."""
    rounded = np.clip(np.floor(values + 0.5), 0.0, CHANNEL_MAX).astype(np.uint16)
    return (rounded[..., 0] << 11) | (rounded[..., 1] << 5) | rounded[..., 2]


# --------------------------------------------------------------------------- texture footprints

class BoxTexture:
    """A texture read as constant texel squares, repeating, averaged over axis-aligned
    rectangles in texel units: the footprint filter of the ideal image."""

    def __init__(self, texture: np.ndarray):
        self.height, self.width = texture.shape
        self.texels = channels(texture)                                      # (H, W, 3)
        # integer summed-area table: table[r, c] = sum of texels [0, r) x [0, c), exact in int64
        table = np.zeros((self.height + 1, self.width + 1, 3), dtype=np.int64)
        table[1:, 1:] = np.cumsum(np.cumsum(channels(texture).astype(np.int64), axis=0), axis=1)
        self.table = table.astype(np.float64)     # at most 1.9e6 texels x 63: exact as floats

    def _prefix(self, columns: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """Sum of the repeating texture over texels [0, columns) x [0, rows), (P, 3); columns and
        rows whole non-negative numbers (floats, below 2^52)."""
        qc, rc = np.divmod(columns, self.width)
        qr, rr = np.divmod(rows, self.height)
        rc, rr = rc.astype(np.int64), rr.astype(np.int64)
        t = self.table
        return ((qc * qr)[:, None] * t[-1, -1] + qc[:, None] * t[rr, -1] + qr[:, None] * t[-1, rc]
                + t[rr, rc])

    def _rectangle_sum(self, c0, c1, r0, r1) -> np.ndarray:
        """Sum over texels [c0, c1) x [r0, r1) (whole numbers, 0 <= c0 <= c1, 0 <= r0 <= r1)."""
        return self._prefix(c1, r1) - self._prefix(c0, r1) - self._prefix(c1, r0) + self._prefix(c0, r0)

    def average(self, cx: np.ndarray, cy: np.ndarray, hx: np.ndarray, hy: np.ndarray) -> np.ndarray:
        """The mean channels (P, 3) over the rectangles [cx - hx, cx + hx] x [cy - hy, cy + hy]
        (texel units, hx and hy >= 0; a zero side is the mean along the other side's line)."""
        x0, x1 = _reduced(cx, hx, self.width)
        y0, y1 = _reduced(cy, hy, self.height)
        cells_x, weights_x = _axis_segments(x0, x1)
        cells_y, weights_y = _axis_segments(y0, y1)
        result = np.zeros((len(cx), 3))
        # within 2 x 2 texels (any magnification, and minification up to the sample density):
        # weight the four texels; otherwise whole texels come from the summed-area table
        small = (cells_x[2] == cells_x[1]) & (cells_y[2] == cells_y[1])
        if small.any():
            result[small] = self._small_average(cells_x[:, small], weights_x[:, small],
                                                cells_y[:, small], weights_y[:, small])
        large = ~small
        if large.any():
            result[large] = self._large_average(cells_x[:, large], weights_x[:, large],
                                                cells_y[:, large], weights_y[:, large])
        return result

    def _small_average(self, cells_x, weights_x, cells_y, weights_y) -> np.ndarray:
        """Footprints whose middle segments are empty: texels (first, last) on each axis."""
        columns = np.stack([cells_x[0], cells_x[2]]).astype(np.int64) % self.width
        rows = np.stack([cells_y[0], cells_y[2]]).astype(np.int64) % self.height
        wx = np.stack([weights_x[0], weights_x[2]])
        wy = np.stack([weights_y[0], weights_y[2]])
        out = np.zeros((columns.shape[1], 3))
        for a in range(2):
            for b in range(2):
                out += (wx[a] * wy[b])[:, None] * self.texels[rows[b], columns[a]]
        return out

    def _large_average(self, cells_x, weights_x, cells_y, weights_y) -> np.ndarray:
        """Footprints over more than 2 texels on an axis: 3 x 3 blocks (first texel, the whole
        ones between, last texel on each axis), each block's sum times its weight."""
        out = np.zeros((cells_x.shape[1], 3))
        for a in range(3):
            for b in range(3):
                weight = weights_x[a] * weights_y[b]
                used = weight > 0
                if not used.any():
                    continue
                total = self._rectangle_sum(cells_x[a][used], cells_x[a + 1][used],
                                            cells_y[b][used], cells_y[b + 1][used])
                out[used] += weight[used][:, None] * total
        return out


class SmoothTexture(BoxTexture):
    """A texture read as a camera sees a filtered one: smooth, the bilinear surface through the
    texel centres (texel (c, r)'s value at (c + 1/2, r + 1/2), linear between them, repeating),
    averaged over the same axis-aligned rectangles. Bilinear interpolation is the texel squares
    convolved with a 1 x 1 box, so the average over a rectangle is the squares' average under the
    rectangle widened by that box: a trapezoid on each axis, whose weights per texel come from its
    integral (`_trapezoid_cdf`), exact. A footprint of no size is the bilinear sample itself."""

    def average(self, cx: np.ndarray, cy: np.ndarray, hx: np.ndarray, hy: np.ndarray) -> np.ndarray:
        segments_x = _smooth_segments(cx, hx, self.width)
        segments_y = _smooth_segments(cy, hy, self.height)
        out = np.zeros((len(cx), 3))
        for first_x, end_x, weight_x in segments_x:
            for first_y, end_y, weight_y in segments_y:
                weight = weight_x * weight_y
                used = weight != 0
                if not used.any():
                    continue
                single = used & (end_x - first_x == 1) & (end_y - first_y == 1)
                if single.any():
                    columns = first_x[single].astype(np.int64) % self.width
                    rows = first_y[single].astype(np.int64) % self.height
                    out[single] += weight[single][:, None] * self.texels[rows, columns]
                block = used & ~single
                if block.any():
                    out[block] += weight[block][:, None] * self._rectangle_sum(
                        first_x[block], end_x[block], first_y[block], end_y[block])
        return out


def _trapezoid_cdf(x: np.ndarray, centre: np.ndarray, half: np.ndarray) -> np.ndarray:
    """The share of the kernel (the box [centre - half, centre + half], mean 1, convolved with the
    unit box) that lies left of x: (G(x - centre + half + 1/2) - G(x - centre - half + 1/2)) / (2
    half), G the integral of clamp(s, 0, 1); for a box of no width its limit, clamp(x - centre +
    1/2, 0, 1)."""
    def g(value):
        return np.where(value <= 0, 0.0, np.where(value >= 1, value - 0.5, 0.5 * value * value))
    wide = half > 1e-9
    safe = np.where(wide, half, 1.0)
    spread = (g(x - centre + safe + 0.5) - g(x - centre - safe + 0.5)) / (2 * safe)
    return np.where(wide, spread, np.clip(x - centre + 0.5, 0.0, 1.0))


def _smooth_segments(centre: np.ndarray, half: np.ndarray, period: int) -> list[tuple]:
    """One axis of SmoothTexture's kernel in texel segments (first, end, weight per texel), five of
    them: the two texels each ramp of the trapezoid may cross, exactly weighed, and the whole texels
    between, where the kernel is flat (1 / (2 half) a texel). Moved by whole periods so that the
    kernel starts in [0, period)."""
    low, high = _reduced(centre, half + 0.5, period)
    centre = (low + high) / 2
    half = np.maximum((high - low) / 2 - 0.5, 0.0)
    first = np.floor(low)
    last = np.maximum(first, np.ceil(high) - 1.0)

    def weight(texel):
        return _trapezoid_cdf(texel + 1.0, centre, half) - _trapezoid_cdf(texel, centre, half)

    zero = np.zeros_like(first)
    middle = last - 1.0 > first + 2.0
    segments = [(first, first + 1.0, weight(first)),
                (first + 1.0, first + 2.0, np.where(last >= first + 1.0, weight(first + 1.0), zero)),
                (first + 2.0, np.where(middle, last - 1.0, first + 3.0),
                 np.where(middle, 1.0 / (2 * np.maximum(half, 0.5)), zero)),
                (last - 1.0, last, np.where(last - 1.0 >= first + 2.0, weight(last - 1.0), zero)),
                (last, last + 1.0, np.where(last >= first + 2.0, weight(last), zero))]
    return segments


def _reduced(centre: np.ndarray, half: np.ndarray, period: int) -> tuple[np.ndarray, np.ndarray]:
    """The interval [centre - half, centre + half] moved by whole periods so that it starts in
    [0, period), its length capped at FOOTPRINT_SPAN_MAX texels."""
    half = np.minimum(half, FOOTPRINT_SPAN_MAX / 2)
    low = centre - half
    shift = np.floor(low / period) * period
    low = np.clip(low - shift, 0.0, np.nextafter(period, 0))
    return low, low + 2 * half


def _axis_segments(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One axis of a footprint [low, high] (0 <= low < period) in three segments: the texel it
    starts in, the whole texels after it, the texel it ends in. Returns the boundaries (4, P)
    (texel indices first, first + 1, last, last + 1; the middle segment may be empty) and each
    segment's weight per texel (3, P): the share of the footprint's length in it (the first
    texel 1 when the footprint has no length)."""
    first = np.floor(low)
    last = np.maximum(first, np.ceil(high) - 1.0)
    length = high - low
    positive = length > 0
    safe = np.where(positive, length, 1.0)
    w_first = np.where(positive, (np.minimum(high, first + 1.0) - low) / safe, 1.0)
    w_middle = np.where(positive & (last > first + 1.0), 1.0 / safe, 0.0)
    w_last = np.where(positive & (last > first), (high - last) / safe, 0.0)
    cells = np.stack([first, first + 1.0, np.maximum(first + 1.0, last), last + 1.0])
    return cells, np.stack([w_first, w_middle, w_last])


# --------------------------------------------------------------------------- triangles

@dataclass(frozen=True)
class Prepared:
    """A triangle ready for sampling: corners in positive order, culled and degenerate ones gone."""
    screen: np.ndarray       # (3, 2)
    zw: np.ndarray
    q: np.ndarray
    uv: np.ndarray | None
    normals: np.ndarray | None
    intensity: float
    light: tuple[float, float, float]
    ambient: float
    area: float


def prepare(tri: FrameTriangle, cull: bool) -> Prepared | None:
    """The triangle in positive order (as render.raster_triangle orders it), or None when it
    is degenerate or a back face that `cull` drops."""
    (x0, y0), (x1, y1), (x2, y2) = tri.screen
    area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
    if area == 0 or not math.isfinite(area):
        return None
    order = [0, 1, 2]
    if area > 0:
        if cull:
            return None
    else:
        order = [0, 2, 1]
        area = -area
    lighting = tri.lighting
    return Prepared(tri.screen[order], tri.zw[order], tri.q[order],
                    None if tri.uv is None else tri.uv[order],
                    None if lighting.normals is None else lighting.normals[order],
                    lighting.intensity, lighting.light, lighting.ambient, area)


class Band:
    """The samples of pixel rows [y0, y1) and columns [x0, x1): depth and colour channels."""

    def __init__(self, x0: int, x1: int, y0: int, y1: int, density: int, background: np.ndarray):
        self.x0, self.x1, self.y0, self.y1, self.density = x0, x1, y0, y1, density
        shape = ((y1 - y0) * density, (x1 - x0) * density)
        self.depth = np.ones(shape)
        self.colour = np.empty(shape + (3,))
        self.colour[...] = background

    def sample_range(self, low: float, high: float, axis: int) -> tuple[int, int]:
        """The band's sample indices (first, last + 1) whose positions lie in [low, high] on
        `axis` (0 = x, 1 = y)."""
        origin, count = (self.x0, self.x1 - self.x0) if axis == 0 else (self.y0, self.y1 - self.y0)
        n = self.density
        first = max(0, math.ceil((low - origin) * n - 0.5)) if math.isfinite(low) else 0
        last = min(count * n - 1, math.floor((high - origin) * n - 0.5)) if math.isfinite(high) else count * n - 1
        return first, max(first, last + 1)

    def positions(self, first: int, last: int, axis: int) -> np.ndarray:
        origin = self.x0 if axis == 0 else self.y0
        return origin + (np.arange(first, last) + 0.5) / self.density

    def resolve(self) -> np.ndarray:
        """The band's pixels: the mean of each pixel's samples, (rows, columns, 3) channels."""
        n = self.density
        rows, columns = self.y1 - self.y0, self.x1 - self.x0
        return self.colour.reshape(rows, n, columns, n, 3).mean(axis=(1, 3))


def sample_triangle(band: Band, tri: Prepared, colour: np.ndarray | None, texture: BoxTexture | None) -> None:
    """Draws one prepared triangle into the band's samples: the samples inside it (top-left rule)
    and nearer than what is there take its depth and colour (`colour` channels, or the texture's
    footprint average), lit by its intensity."""
    screen = tri.screen
    i0, i1 = band.sample_range(screen[:, 0].min(), screen[:, 0].max(), 0)
    j0, j1 = band.sample_range(screen[:, 1].min(), screen[:, 1].max(), 1)
    if i0 >= i1 or j0 >= j1:
        return
    px = band.positions(i0, i1, 0)[None, :]
    py = band.positions(j0, j1, 1)[:, None]
    inside = np.ones((j1 - j0, i1 - i0), dtype=bool)
    edges = []
    for i in range(3):
        a, b = screen[(i + 1) % 3], screen[(i + 2) % 3]
        e = edge_function(a, b, px, py)
        inside &= (e >= 0) if owns_ties(a, b) else (e > 0)
        edges.append(e)
    if not inside.any():
        return
    ys, xs = np.nonzero(inside)
    l0, l1, l2 = (e[ys, xs] / tri.area for e in edges)
    depth = l0 * tri.zw[0] + l1 * tri.zw[1] + l2 * tri.zw[2]
    ys, xs = ys + j0, xs + i0
    nearer = depth < band.depth[ys, xs]
    if not nearer.any():
        return
    ys, xs, depth = ys[nearer], xs[nearer], depth[nearer]
    l0, l1, l2 = l0[nearer], l1[nearer], l2[nearer]
    band.depth[ys, xs] = depth
    q = tri.q
    inv_w = l0 * q[0] + l1 * q[1] + l2 * q[2]
    weights = np.stack([l0 * q[0], l1 * q[1], l2 * q[2]]) / inv_w                 # (3, P)
    intensity = _intensity(tri, weights)
    if texture is None or tri.uv is None:
        band.colour[ys, xs] = np.asarray(intensity)[..., None] * colour
        return
    band.colour[ys, xs] = intensity[:, None] * _texture_samples(band, tri, texture, weights, inv_w)


def _intensity(tri: Prepared, weights: np.ndarray) -> np.ndarray:
    """Per sample (P,): the face's intensity, or max(ambient, N.L / |N|) with N the
    perspective-correct interpolation of the corner normals (ambient where |N| = 0)."""
    count = weights.shape[1]
    if tri.normals is None:
        return np.full(count, float(tri.intensity))
    normal = weights.T @ tri.normals
    length = np.linalg.norm(normal, axis=1)
    lit = length > 0
    intensity = np.full(count, float(tri.ambient))
    intensity[lit] = np.maximum(tri.ambient, (normal[lit] @ np.asarray(tri.light)) / length[lit])
    return intensity


def _texture_samples(band: Band, tri: Prepared, texture: BoxTexture, weights: np.ndarray,
                     inv_w: np.ndarray) -> np.ndarray:
    """The texture's average over each sample's footprint (P, 3). t = (u W, (1 - v) H) with
    (u, v) perspective-correct: u = U / Q, U = sum l_i q_i u_i, Q = sum l_i q_i, l_i affine in
    the screen position, so du/dx = (dU/dx - u dQ/dx) / Q."""
    uv, q, screen = tri.uv, tri.q, tri.screen
    u, v = weights.T @ uv[:, 0], weights.T @ uv[:, 1]
    # d l_i / dx and d l_i / dy: the edge opposite corner i, (b - a) x (p - a) / area
    dldx = np.array([screen[(i + 1) % 3][1] - screen[(i + 2) % 3][1] for i in range(3)]) / tri.area
    dldy = np.array([screen[(i + 2) % 3][0] - screen[(i + 1) % 3][0] for i in range(3)]) / tri.area
    dq = (dldx @ q, dldy @ q)
    du = [(d @ (q * uv[:, 0]) - u * dqd) / inv_w for d, dqd in zip((dldx, dldy), dq)]
    dv = [(d @ (q * uv[:, 1]) - v * dqd) / inv_w for d, dqd in zip((dldx, dldy), dq)]
    side = 1.0 / band.density
    half_x = 0.5 * side * texture.width * np.hypot(du[0], du[1])
    half_y = 0.5 * side * texture.height * np.hypot(dv[0], dv[1])
    return texture.average(u * texture.width, (1.0 - v) * texture.height, half_x, half_y)


# --------------------------------------------------------------------------- lines

LINE_HALF_WIDTH = 0.5
LINE_ROWS_PER_DENSITY = 16       # lines: this many sample rows per pixel for each unit of density


def clip_to(a, b, bounds: tuple[float, float, float, float]):
    """Liang-Barsky of the segment a -> b against [x0, x1] x [y0, y1]; None when nothing is left."""
    (xa, ya), (xb, yb) = a, b
    dx, dy = xb - xa, yb - ya
    t0, t1 = 0.0, 1.0
    x0, y0, x1, y1 = bounds
    for p, q in ((-dx, xa - x0), (dx, x1 - xa), (-dy, ya - y0), (dy, y1 - ya)):
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
    return np.array([xa + t0 * dx, ya + t0 * dy]), np.array([xa + t1 * dx, ya + t1 * dy])


def _interval(lows: list, highs: list, low, high, valid):
    """Adds the interval [low, high] (where `valid`) to a hull being built."""
    lows.append(np.where(valid, low, np.inf))
    highs.append(np.where(valid, high, -np.inf))


def capsule_rows(a: np.ndarray, b: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where each horizontal line y = ys[k] crosses the capsule of the segment a -> b (the points
    within LINE_HALF_WIDTH of it): [low, high] per line, low > high where it misses. The capsule is
    convex, so the crossing is the hull of its crossings with the two end discs and the rectangle
    swept by the segment (the points whose projection falls on the segment, within r of its line)."""
    r = LINE_HALF_WIDTH
    lows: list = []
    highs: list = []
    for centre in (a, b):
        reach2 = r * r - (ys - centre[1]) ** 2
        half = np.sqrt(np.maximum(reach2, 0.0))
        _interval(lows, highs, centre[0] - half, centre[0] + half, reach2 >= 0)
    d = b - a
    length = math.hypot(d[0], d[1])
    if length > 0:
        # the strip |s| <= r, s = ((x - ax)(-dy) + (y - ay) dx) / L, and the slab 0 <= t <= 1,
        # t = ((x - ax) dx + (y - ay) dy) / L^2: each an interval of x on the row (or all or none)
        ones = np.ones_like(ys)
        if d[1] != 0:
            base = (ys - a[1]) * d[0] / length
            e0, e1 = a[0] + (base - r) * length / d[1], a[0] + (base + r) * length / d[1]
            strip = (np.minimum(e0, e1), np.maximum(e0, e1), ones.astype(bool))
        else:
            near = np.abs(ys - a[1]) <= r
            strip = (np.full_like(ys, -np.inf), np.full_like(ys, np.inf), near)
        if d[0] != 0:
            along = (ys - a[1]) * d[1]
            e0, e1 = a[0] - along / d[0], a[0] + (length * length - along) / d[0]
            slab = (np.minimum(e0, e1), np.maximum(e0, e1), ones.astype(bool))
        else:
            t = (ys - a[1]) / d[1]
            slab = (np.full_like(ys, -np.inf), np.full_like(ys, np.inf), (t >= 0) & (t <= 1))
        low, high = np.maximum(strip[0], slab[0]), np.minimum(strip[1], slab[1])
        _interval(lows, highs, low, high, strip[2] & slab[2] & (low <= high))
    return np.min(lows, axis=0), np.max(highs, axis=0)


def line_coverage(segments, region: tuple[int, int, int, int], rows_per_pixel: int) -> np.ndarray:
    """Each pixel's share (rows, columns) covered by the union of the segments' capsules: exact
    along x on each of rows_per_pixel sample rows per pixel (at (j + 0.5) / rows_per_pixel), the
    rows averaged. On every row the crossings of all capsules are merged (so overlaps count once)
    and their lengths shared out among the pixels they cross."""
    x0, y0, x1, y1 = region
    span = (x1 - x0) + 4.0                     # row k's crossings are stored offset by k * span
    starts, ends = [], []
    for a, b in segments:
        clipped = clip_to(a, b, (x0 - 1.0, y0 - 1.0, x1 + 1.0, y1 + 1.0))
        if clipped is None:
            continue
        a, b = clipped
        top = max(y0, min(a[1], b[1]) - LINE_HALF_WIDTH)
        bottom = min(y1, max(a[1], b[1]) + LINE_HALF_WIDTH)
        first = max(0, math.ceil((top - y0) * rows_per_pixel - 0.5))
        last = min((y1 - y0) * rows_per_pixel - 1, math.floor((bottom - y0) * rows_per_pixel - 0.5))
        if first > last:
            continue
        rows = np.arange(first, last + 1)
        low, high = capsule_rows(a, b, y0 + (rows + 0.5) / rows_per_pixel)
        low, high = np.maximum(low, x0), np.minimum(high, x1)
        hit = low < high
        starts.append(rows[hit] * span + (low[hit] - x0))
        ends.append(rows[hit] * span + (high[hit] - x0))
    coverage = np.zeros((y1 - y0, x1 - x0))
    if not starts:
        return coverage
    start, end = np.concatenate(starts), np.concatenate(ends)
    order = np.argsort(start, kind="stable")
    start, end = start[order], end[order]
    reach = np.maximum.accumulate(end)
    opens = np.ones(len(start), dtype=bool)
    opens[1:] = start[1:] > reach[:-1]              # not overlapping anything before it on its row
    closes = np.append(opens[1:], True)
    start, end = start[opens], reach[closes]
    row = np.floor(start / span)
    low, high = start - row * span, end - row * span
    pixel_row = (row // rows_per_pixel).astype(np.int64)
    first = np.minimum(np.floor(low), x1 - x0 - 1).astype(np.int64)
    last = np.maximum(first, np.ceil(high).astype(np.int64) - 1)
    single = first == last
    np.add.at(coverage, (pixel_row, first), np.where(single, high - low, first + 1 - low))
    several = ~single
    np.add.at(coverage, (pixel_row[several], last[several]), high[several] - last[several])
    whole = np.zeros((y1 - y0, x1 - x0 + 1))     # the pixels strictly between: one each
    np.add.at(whole, (pixel_row[several], first[several] + 1), 1.0)
    np.add.at(whole, (pixel_row[several], last[several]), -1.0)
    coverage += np.cumsum(whole, axis=1)[:, :-1]
    return coverage / rows_per_pixel


# --------------------------------------------------------------------------- a frame

def _bands(region: tuple[int, int, int, int], density: int):
    """The bands of rows covering region (x0, y0, x1, y1), each of at most BAND_SAMPLES samples."""
    x0, y0, x1, y1 = region
    rows = max(1, BAND_SAMPLES // ((x1 - x0) * density * density))
    for top in range(y0, y1, rows):
        yield x0, x1, top, min(y1, top + rows)


def check_density(density: int) -> None:
    """Raises ValueError unless 1 <= density <= DENSITY_MAX."""
    if isinstance(density, bool) or not isinstance(density, (int, np.integer)) or not 1 <= density <= DENSITY_MAX:
        raise ValueError(f"density must be a whole number from 1 to {DENSITY_MAX}, not {density!r}")


def check_region(region) -> tuple[int, int, int, int]:
    """Region (x0, y0, x1, y1) within the screen and not empty, as ints; ValueError otherwise."""
    if region is None:
        return 0, 0, WIDTH, HEIGHT
    x0, y0, x1, y1 = (int(v) for v in region)
    if not (0 <= x0 < x1 <= WIDTH and 0 <= y0 < y1 <= HEIGHT):
        raise ValueError(f"region {tuple(region)} is not a non-empty rectangle within "
                         f"(0, 0, {WIDTH}, {HEIGHT})")
    return x0, y0, x1, y1


def ideal_channels(scene: Scene, mesh: Mesh, texture: np.ndarray | None, n: int,
                   density: int = DEFAULT_DENSITY, region=None, texels: str = "square") -> np.ndarray:
    """Frame n's ideal pixels before rounding: (rows, columns, 3) float channels in RGB565 units
    (red and blue 0-31, green 0-63), each the mean of its density x density samples. `region`
    (x0, y0, x1, y1), default the whole screen, limits the work to those pixels; `texels`, one of
    TEXEL_MODELS, how a texture is read."""
    check_density(density)
    if texels not in TEXEL_MODELS:
        raise ValueError(f"texels must be one of {', '.join(TEXEL_MODELS)}, not {texels!r}")
    region = check_region(region)
    background = channels(scene.background)
    x0, y0, x1, y1 = region
    out = np.empty((y1 - y0, x1 - x0, 3))
    if scene.mode == "wireframe":
        segments = [(np.asarray(a, float), np.asarray(b, float)) for a, b in frame_segments(scene, mesh, n)]
        coverage = line_coverage(segments, region, LINE_ROWS_PER_DENSITY * density)
        return background + coverage[..., None] * (channels(WIRE_COLOUR) - background)
    model = SmoothTexture if texels == "smooth" else BoxTexture
    box = model(texture) if is_textured(scene, texture) else None
    prepared = [p for p in (prepare(t, scene.cull) for t in frame_triangles(scene, mesh, texture, n)) if p]
    flat = channels(FLAT_COLOUR)
    tops = np.array([p.screen[:, 1].min() for p in prepared])
    bottoms = np.array([p.screen[:, 1].max() for p in prepared])
    for bx0, bx1, by0, by1 in _bands(region, density):
        band = Band(bx0, bx1, by0, by1, density, background)
        for k in np.nonzero((bottoms >= by0) & (tops <= by1))[0]:
            sample_triangle(band, prepared[k], flat, box)
        out[by0 - y0:by1 - y0] = band.resolve()
    return out


def render_ideal_frame(scene: Scene, mesh: Mesh, texture: np.ndarray | None, n: int,
                       density: int = DEFAULT_DENSITY, region=None, texels: str = "square") -> np.ndarray:
    """Frame n's ideal image as RGB565 (240, 320) uint16 (or the region's rows and columns),
    row 0 at the top: each pixel's mean rounded to nearest per channel."""
    return pack_rgb565(ideal_channels(scene, mesh, texture, n, density, region, texels))


def render_ideal_image(scene: Scene, mesh: Mesh, texture: np.ndarray | None, n: int,
                       density: int = DEFAULT_DENSITY, region=None, texels: str = "square") -> np.ndarray:
    """Frame n's ideal image as the LCD shows it: (240, 320, 3) uint8 RGB, row 0 at the top."""
    return rgb565_to_rgb888(render_ideal_frame(scene, mesh, texture, n, density, region, texels))
