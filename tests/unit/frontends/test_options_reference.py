"""docs/reference/options.md names every option of each command (issue 32, item 2: the reference
tested against the code): the board model's, the card tool's and the reference renderer's parsers."""
from __future__ import annotations

import argparse

from suite import ROOT

REFERENCE = ROOT / "docs" / "reference"


def options_of(parser: argparse.ArgumentParser) -> set[str]:
    names = set()
    for action in parser._actions:
        names |= {s for s in action.option_strings if s.startswith("--") and s != "--help"}
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                names |= options_of(sub)
    return names


def test_every_board_model_option_is_in_the_reference():
    from emulator.frontends.options import build_parser
    text = (REFERENCE / "options.md").read_text()
    missing = sorted(name for name in options_of(build_parser()) if f"`{name}" not in text and f"{name} " not in text)
    assert missing == []


def test_every_reference_renderer_option_is_in_its_reference():
    from reference.cli import _parser
    text = (REFERENCE / "reference-renderer.md").read_text()
    missing = sorted(name for name in options_of(_parser()) if f"`{name}" not in text and f"{name} " not in text
                     and f"[{name}" not in text)
    assert missing == []


def test_every_card_tool_option_is_in_its_reference():
    from sdcard_image.cli import _parser
    text = (ROOT / "sdcard_image" / "README.md").read_text() + (ROOT / "docs" / "guide" / "cards-and-scenes.md").read_text()
    missing = sorted(name for name in options_of(_parser()) if f"`{name}" not in text and f"{name} " not in text
                     and f"[{name}" not in text)
    assert missing == []
