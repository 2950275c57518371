"""docs/reference/scene-keys.md has a row for every scene.ini key the readers take (reference/scene.py's
KEYS, which the fuzz stage holds against the firmware's own reader), and none for a key they refuse."""
from __future__ import annotations

import re

from reference.scene import KEYS
from suite import ROOT


def test_every_scene_key_has_its_row():
    text = (ROOT / "docs" / "reference" / "scene-keys.md").read_text()
    rows = re.findall(r"^\| `([a-z_]+)` \|", text, re.MULTILINE)
    assert sorted(rows) == sorted(KEYS)
