"""The SHA-256 accelerator (devices/sha256.py) as the Kendryte SDK's sha256.c feeds it: padded blocks
of words as little-endian loads read the message, big-endian mode, the result read back in
reverse; checked against hashlib."""
from __future__ import annotations

import hashlib
import struct

import pytest

from emulator.devices import sha256 as sh
from k210_fixtures import idle_elf, make_board  # noqa: F401


def sdk_hash(device, message: bytes) -> bytes:
    """sha256_hard_calculate, register by register."""
    blocks = (len(message) + 64 + 8) // 64
    device.write(sh.NUM, 4, blocks, 0.0)
    device.write(sh.FUNCTION1, 4, 0, 0.0)
    device.write(sh.FUNCTION0, 4, sh.BIG_ENDIAN | sh.ENABLE, 0.0)
    padded = message + b"\x80" + b"\0" * ((56 - len(message) - 1) % 64) + struct.pack(">Q", 8 * len(message))
    assert len(padded) == 64 * blocks
    for (word,) in struct.iter_unpack("<I", padded):
        assert not device.read(sh.FUNCTION1, 4, 0.0) & sh.FIFO_FULL
        device.write(sh.DATA_IN, 4, word, 0.0)
    assert device.read(sh.FUNCTION0, 4, 0.0) & sh.ENABLE          # complete
    return b"".join(struct.pack("<I", device.read(sh.RESULT + 4 * (7 - i), 4, 0.0)) for i in range(8))


@pytest.mark.parametrize("message", [b"", b"abc", b"K210" * 40, bytes(range(256)) * 3])
def test_the_sdk_way_gives_the_sha256_digest(idle_elf, message):
    device = make_board(idle_elf).sha256
    assert sdk_hash(device, message) == hashlib.sha256(message).digest()


def test_not_complete_until_the_last_block_and_more_words_overflow(idle_elf):
    device = make_board(idle_elf).sha256
    device.write(sh.NUM, 4, 2, 0.0)
    device.write(sh.FUNCTION0, 4, sh.BIG_ENDIAN | sh.ENABLE, 0.0)
    for _ in range(16):
        device.write(sh.DATA_IN, 4, 0, 0.0)
    assert not device.read(sh.FUNCTION0, 4, 0.0) & sh.ENABLE
    assert device.read(sh.NUM, 4, 0.0) == 2 | 1 << 16
    for _ in range(17):
        device.write(sh.DATA_IN, 4, 0, 0.0)
    assert device.read(sh.FUNCTION0, 4, 0.0) & (sh.ENABLE | sh.OVERFLOW) == sh.ENABLE | sh.OVERFLOW
