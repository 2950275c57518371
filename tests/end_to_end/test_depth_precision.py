"""Issue 34, item 3: depth from the triangle's plane, not from a running sum, and (float32) reversed. Two quads
cross on the screen's middle column at a shallow slope (one faces the camera, the other turns by `slope` about
the vertical axis); the nearer wins each pixel, so the split falls where their depths cross: between columns
159 and 160 (the crossing is x = 0, the screen's centre line). A running sum of per-pixel steps loses every
step under half an ulp of the depth (at 3 units from the camera z / w is near 0.97, where an ulp is 6e-8): at
slope 1e-4 the turned quad's depth moved by 0.3 ulp a pixel and never changed along a row, so the split fell
anywhere. From the plane but in z / w it fell within 2 pixels at 1e-4 (the two depths a pixel from the
crossing differ by a quarter of that ulp). The reversed depth (1 at the near plane, 0 at the far one) is
about 0.03 there, where floats are 16 times finer: the split is exact down to a slope of 1e-5 (3e-6 too;
at 1e-6 it falls 13 pixels off)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from suite import make_card

TEXTURE = b"P6\n2 1\n255\n" + bytes([255, 0, 0, 0, 0, 255])      # red texel, blue texel
CENTRE = 160          # the first column right of the crossing
ROWS = (60, 120, 180)


def crossing_quads(slope: float) -> bytes:
    """Quad A at z = 0 (red), quad B at z = slope x (blue), both 2 units square before the scene's scale."""
    corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    lines = [f"v {x} {y} 0" for x, y in corners] + [f"v {x} {y} {slope * x:.9g}" for x, y in corners]
    lines += ["vt 0.25 0.5", "vt 0.75 0.5", "f 1/1 2/1 3/1", "f 1/1 3/1 4/1", "f 5/2 6/2 7/2", "f 5/2 7/2 8/2"]
    return ("\n".join(lines) + "\n").encode()


def first_blue_columns(firmware: Path, folder: Path, slope: float, angle: float = 0) -> list[int]:
    """The first blue column of each of ROWS, the two quads turned by `angle` degrees about the vertical
    axis (the crossing line, which stays on the screen's centre line)."""
    from emulator.board import Board
    scene = (f"mode = textured\nangle = {angle}\nstep = 0\ncull = off\ndepth = float32\nscale = 1.5\n"
             "antialias = off\n").encode()
    card = make_card(folder, {"/scene.ini": scene, "/model.obj": crossing_quads(slope), "/texture.ppm": TEXTURE})
    frames: list[np.ndarray] = []
    board = Board(str(firmware), sd_image=str(card), on_frame=lambda record, image: frames.append(image.copy()))
    try:
        board.run(1)
    finally:
        board.close()
    image = frames[-1]
    columns = []
    for row in ROWS:
        blue, red = image[row, :, 2] > 128, image[row, :, 0] > 128
        assert blue.any() and red.any(), f"row {row}: one quad hides the other wholly"
        first = int(np.argmax(blue))
        assert not red[first:].any() and not blue[:first].any(), f"row {row}: the quads interleave"
        columns.append(first)
    return columns


@pytest.mark.parametrize("slope", [1e-2, 1e-3, 1e-4, 1e-5])
def test_crossing_quads_split_where_their_depths_cross(firmware, tmp_path, slope):
    assert first_blue_columns(firmware, tmp_path, slope) == [CENTRE] * len(ROWS)


@pytest.mark.parametrize("angle", [17, -35])
@pytest.mark.parametrize("slope, tolerance", [(1e-4, 0), (1e-5, 2)])
def test_turned_crossing_quads_split_where_their_depths_cross(firmware, tmp_path, angle, slope, tolerance):
    """Turned away from the camera the quads' depth changes by 5e-5 a pixel, so a corner snapped by up to
    1/32 pixel would move its plane by 1.5e-6, a hundred times what the two differ by a pixel from the
    crossing: the plane goes through where the corners project before snapping (raster_triangle.S
    DEPTH_GRADIENT). Measured: exact at 1e-4 (2 to 3 pixels off through the snapped corners), within 2
    pixels at 1e-5."""
    columns = first_blue_columns(firmware, tmp_path, slope, angle)
    assert all(abs(column - CENTRE) <= tolerance for column in columns), columns
