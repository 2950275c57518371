"""How many steps of the firmware's depth buffer the model's depth spans (firmware/depth_check.S, in
the same single-precision steps): int16 depth is floor(65534 z / w), z / w = far / (far - near) (1 -
near / D) at a view distance D, so a far plane many times the near one crowds every distance past a few
near-plane lengths into the top of 0 .. 1, where few steps remain, and surfaces on one step hide each
other by their drawing order. float32 depth is reversed, c1 / D - c0 (c0 = near / (far - near), c1 = c0
far; firmware/include/render.inc), whose floats grow finer towards the far plane. The model spans at most D = -tz -+ r,
r its largest scaled vertex distance from its origin (whatever the rotation), clipped to near .. far.
Fewer than DEPTH_WARN_STEPS steps is a warning: on the firmware's console at load, and from the card
builder."""
from __future__ import annotations

import numpy as np

from .scene import Scene

DEPTH_WARN_STEPS = 256            # 8 bits (firmware/include/render.inc DEPTH_WARN_STEPS)
DEPTH16_SPAN = np.float32(65534.0)


def _fmadd(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """a b + c (single precision, elementwise) as fmadd.s gives it: the product of two singles is exact
    in a double, the sum is rounded to a double and then to a single (twice, where fmadd.s rounds
    once: they can differ only when the double lands exactly midway between two singles)."""
    return (a.astype(np.float64) * b.astype(np.float64) + c.astype(np.float64)).astype(np.float32)


def _float_steps(pair: np.ndarray) -> int:
    """How many float32 values lie from pair[1] up to pair[0] (both >= 0: they order as their bits)."""
    bits = pair.astype(np.float32).view(np.int32).astype(np.int64)
    return int(bits[0] - bits[1])


def depth_steps(scene: Scene, vertices: np.ndarray) -> int | None:
    """The steps of the depth buffer over the model's depth span; None when the span lies wholly
    outside near .. far, or has no length, or the scene is drawn in wireframe (no depth buffer): no
    warning."""
    if scene.mode == "wireframe":
        return None
    f32 = np.float32
    points = np.asarray(vertices, dtype=np.float32).reshape(-1, 3)
    with np.errstate(over="ignore"):        # a huge vertex squares to inf, as on the FPU
        scaled = points * np.asarray(scene.scale, dtype=np.float32)
        x, y, z = scaled[:, 0], scaled[:, 1], scaled[:, 2]
        squared = _fmadd(z, z, _fmadd(y, y, x * x))
    largest = f32(squared.max()) if len(squared) else f32(0.0)
    r = np.sqrt(largest, dtype=np.float32)
    centre = -f32(scene.translate[2])
    near, far = f32(scene.near), f32(scene.far)
    d0_at, d1_at = max(f32(centre - r), near), min(f32(centre + r), far)
    if not d0_at < d1_at:
        return None
    if scene.depth == "int16":
        k = f32(far / f32(far - near))
        k_near = f32(k * near)
        d0, d1 = f32(k - f32(k_near / d0_at)), f32(k - f32(k_near / d1_at))
        return int(np.floor(f32(d1 * DEPTH16_SPAN))) - int(np.floor(f32(d0 * DEPTH16_SPAN)))
    # float32: reversed depth c1 (1 / D) - c0, as raster_set_depth and raster_triangle compute it
    c0 = f32(near / f32(far - near))
    c1 = f32(c0 * far)
    # from 1 / D rounded to a float: distances whose 1 / D round alike get one depth, so the steps
    # are the fewer of the floats between the two depths and between the two 1 / D
    inverse = np.array([1.0], dtype=np.float32) / np.array([d0_at, d1_at], dtype=np.float32)
    depths = _fmadd(inverse, np.array([c1, c1]), np.array([-c0, -c0]))
    return int(min(_float_steps(depths), _float_steps(inverse)))


def depth_warning(scene: Scene, vertices: np.ndarray) -> str | None:
    """The firmware's warning, when it gives one."""
    steps = depth_steps(scene, vertices)
    if steps is None or steps >= DEPTH_WARN_STEPS:
        return None
    return (f"depth: near and far leave {steps} steps of the depth buffer over the model's depth (fewer "
            f"than {DEPTH_WARN_STEPS}: its surfaces may hide each other wrongly)")
