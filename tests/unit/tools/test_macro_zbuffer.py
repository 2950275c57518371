"""tools/macro_zbuffer.py, the simulation of the Transputer seed's macro Z-buffer (issue 12, item 5):
it skips what the seed's rule says is hidden, never a triangle with a visible pixel, and nothing
that is drawn in front of what came before."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from suite import ROOT
from reference.load import load_files
from tools import macro_zbuffer

SCENE = "mode = flat\ncull = off\ntranslate = 0 0 -3\n"
# one large triangle in front (z = 0) and a small square behind its middle (z = -1), then the same
# square larger than the triangle's middle
NEAR = "v -2 -2 0\nv 2 -2 0\nv 0 2 0\n"
FAR_SMALL = "v -0.2 -0.2 -1\nv 0.2 -0.2 -1\nv 0.2 0.2 -1\nv -0.2 0.2 -1\n"
FAR_LARGE = "v -3 -3 -1\nv 3 -3 -1\nv 3 3 -1\nv -3 3 -1\n"


def simulate(first: str, second: str, near_first: bool):
    """The near triangle and a far square (two triangles), in the order asked, over one frame."""
    near_faces, far_faces = "f 1 2 3\n", "f 4 5 6\nf 4 6 7\n"
    if near_first:
        obj = first + second + near_faces + far_faces
    else:
        obj = first + second + far_faces + near_faces
    scene, mesh, _ = load_files(SCENE, obj.encode(), None)
    return macro_zbuffer.simulate(scene, mesh, 1)


def test_a_square_behind_a_triangle_drawn_before_it_is_skipped():
    counts = simulate(NEAR, FAR_SMALL, near_first=True)
    assert counts.triangles == 3 and counts.hidden_triangles == 2
    for side in (2, 4, 8):
        assert counts.by_side[side].skipped_triangles == 2, side
        assert counts.by_side[side].skipped_pixels == counts.hidden_pixels
    assert all(c.wrong_skips == 0 for c in counts.by_side.values())


def test_nothing_is_skipped_when_the_near_triangle_comes_second():
    counts = simulate(NEAR, FAR_SMALL, near_first=False)
    assert counts.hidden_triangles == 0
    assert all(c.skipped_triangles == 0 for c in counts.by_side.values())


def test_a_square_partly_in_view_is_not_skipped():
    counts = simulate(NEAR, FAR_LARGE, near_first=True)
    assert counts.hidden_triangles == 0
    assert all(c.skipped_triangles == 0 and c.wrong_skips == 0 for c in counts.by_side.values())


def test_the_bench_torus_has_hidden_triangles_and_no_skip_is_wrong():
    """The torus is the bench scene with hidden triangles (its far side behind its near one): the
    simulation finds them, and skips none that shows a pixel."""
    name, scene, mesh = next(s for s in macro_zbuffer.bench_scenes() if s[0].startswith("A torus"))
    counts = macro_zbuffer.simulate(scene, mesh, 2)
    assert counts.hidden_triangles > 0.3 * counts.triangles
    assert all(c.wrong_skips == 0 for c in counts.by_side.values())


@pytest.mark.parametrize("args, status", [(["/no/such/card.img"], 2), (["build/card.img", "0"], 2),
                                          (["build/card.img", "2", "extra"], 2)])
def test_the_command_line_refuses_what_it_cannot_use(args, status):
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "macro_zbuffer.py"), *args], cwd=ROOT,
                            capture_output=True, text=True)
    assert result.returncode == status, result.stderr
    assert result.stderr.strip() and "Traceback" not in result.stderr


def test_the_command_line_reports_a_card(card):
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "macro_zbuffer.py"), str(card), "1"], cwd=ROOT,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert str(card) in result.stdout and "skipped" in result.stdout
