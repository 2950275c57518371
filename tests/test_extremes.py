"""Numerical extremes: scenes at the edges of what the renderer handles must neither trap nor
hang, and where exact arithmetic and the firmware's agree, the frames must be identical to the
float64 reference renderer's (the first cases of the speed/accuracy work; more to come)."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import reference
from conftest import make_card, run_emulator

TEXTURE = b"P6\n1 1\n255\n\x80\x40\x20"
TRIANGLE = "v 0 0 -1\nv 1 0 -1\nv 0 1 -1\nf 1 2 3\n"
FRAMES = 3

AGREEING = {
    # name: (model, scene.ini): the firmware's frames must equal the reference's exactly
    "coordinates-around-1e6": ("v -1e6 -1e6 -2e6\nv 1e6 -1e6 -2e6\nv 0 1e6 -2e6\nf 1 2 3\n",
                               "translate = 0 0 0\nfar = 1e7\nstep = 0\nmode = flat\n"),
    "coordinates-around-1e-6": ("v 0 0 0\nv 1e-6 0 0\nv 0 1e-6 0\nf 1 2 3\n", "mode = flat\n"),
    "scale-zero": (TRIANGLE, "scale = 0\nmode = flat\n"),
    "beyond-the-far-plane": (TRIANGLE, "translate = 0 0 -1000\nmode = flat\n"),
    "repeated-vertices": ("v 0 0 -1\nv 0 0 -1\nv 0 0 -1\nv 1 1 -1\nf 1 2 3\nf 1 2 4\n", "mode = flat\n"),
    "sliver-thousands-long": ("v -100 0 -3\nv 100 0.001 -3\nv 100 0 -3\nf 1 2 3\nf 1 3 2\n", "mode = flat\n"),
}

REFUSED = {
    "nan-in-obj": ("v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "malformed number"),
    "infinity-in-obj": ("v 1e39 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "out of range"),
}


def _card(folder: Path, model: str, scene: str) -> Path:
    return make_card(folder, {"/model.obj": model.encode(), "/texture.ppm": TEXTURE, "/scene.ini": scene.encode()})


@pytest.mark.parametrize("name", AGREEING)
def test_extreme_scene_matches_the_reference(firmware, tmp_path, name):
    model, scene = AGREEING[name]
    card = _card(tmp_path, model, scene)
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", str(FRAMES), "--out", str(out),
                          "--quiet")
    assert result.returncode == 0, result.stderr            # no trap, no hang, no error
    ref_scene, mesh, texture = reference.load_card_image(card)
    for n in range(FRAMES):
        shown = np.asarray(Image.open(out / f"frame_{n:04d}.png").convert("RGB"))
        assert np.array_equal(shown, reference.render_image(ref_scene, mesh, texture, n)), f"frame {n}"
    if name == "coordinates-around-1e6":   # the huge triangle is in view: it must really be drawn
        assert np.any(shown != shown[0, 0], axis=2).sum() > 10_000


@pytest.mark.parametrize("name", REFUSED)
def test_non_finite_numbers_are_a_clear_error(firmware, tmp_path, name):
    model, words = REFUSED[name]
    card = _card(tmp_path, model, "mode = flat\n")
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "1", "--out", str(out), "--quiet")
    console = (out / "console.log").read_text()
    assert result.returncode == 8, result.stderr + console
    assert re.search(rf"^error 10 bad model line 1: .*{words}", console, re.M), console
