"""The firmware's fatal errors as the host tools read them (k210_common/firmware_errors.py):
every code of firmware/include/errors.inc, with its console words and screen colour, and
errors.inc's comment table agreeing with its .equ lines."""
from __future__ import annotations

import re

import pytest

from k210_common.firmware_errors import ERRORS_INC, firmware_error, firmware_errors, parse
from suite import ROOT

FIRMWARE = ROOT / "firmware"


def test_the_parser_sees_all_twelve():
    errors = firmware_errors().errors
    assert [e.code for e in errors] == list(range(1, 13))
    assert [e.name for e in errors] == ["NO_CARD", "CARD_TIMEOUT", "UNSUPPORTED", "CRC", "NO_FAT32", "NOT_FOUND",
                                        "TOO_LARGE", "BAD_CHAIN", "BAD_SCENE", "BAD_MODEL", "BAD_TEXTURE",
                                        "MODEL_TOO_LARGE"]
    assert firmware_error("NO_FAT32").words == ("no FAT32 partition", "invalid BPB")
    assert firmware_error("MODEL_TOO_LARGE").words == ("model too large for memory",)
    assert firmware_error("BAD_MODEL").console_starts == ("error 10 bad model",)
    assert firmware_error("NO_CARD").rgb565 == 0x001F and firmware_error("NO_CARD").rgb888 == (0, 0, 255)
    assert len({e.rgb565 for e in errors}) == len(errors), "each error has a colour of its own"


def test_the_table_rgb888_is_what_the_panel_shows():
    # the panel widens 5-bit red and blue to its 6-bit GRAM (the top bit repeated), then the
    # model's frames widen 6 bits to 8 as the LCD model does
    for error in firmware_errors().errors:
        c = error.rgb565
        r6, g6, b6 = (c >> 11) << 1 | c >> 15, (c >> 5) & 63, (c & 31) << 1 | (c >> 4) & 1
        assert error.rgb888 == tuple((v << 2) | (v >> 4) for v in (r6, g6, b6)), error


def test_every_console_message_of_the_firmware_starts_with_its_words():
    """The words of the table are the words the firmware prints: every message that follows an
    `li a0, ERR_<NAME>` in the sources starts with one of them (the messages are .asciz lines)."""
    words = {e.name: e.words for e in firmware_errors().errors}
    sources = "\n".join(path.read_text() for path in sorted(FIRMWARE.glob("*.S")))
    messages = dict(re.findall(r"^(msg_\w+):\s*\.asciz\s+\"([^\"]*)\"", sources, re.M))
    checked = 0
    for name, label in re.findall(r"li\s+a0,\s*ERR_(\w+)\b(?:.*\n){0,3}?.*la\s+a1,\s*(msg_\w+)", sources):
        if label in messages and name in words:
            assert messages[label].startswith(words[name]), (name, label, messages[label])
            checked += 1
    assert checked >= 10


def test_a_table_that_disagrees_with_its_equs_is_refused():
    text = ERRORS_INC.read_text()
    with pytest.raises(ValueError, match="ERR_COLOUR_BAD_MODEL"):
        parse(text.replace(".equ ERR_COLOUR_BAD_MODEL,  0x0410", ".equ ERR_COLOUR_BAD_MODEL,  0x0411"))
    with pytest.raises(ValueError, match="ERR_BAD_TEXTURE"):
        parse(text.replace("ERR_BAD_TEXTURE   bad texture", "ERR_BAD_TEXTUR    bad texture"))
    with pytest.raises(KeyError, match="no ERR_NO_SUCH"):
        firmware_error("NO_SUCH")
