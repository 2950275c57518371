"""The SHA-256 accelerator (devices/sha256.py) as the Kendryte SDK's sha256.c feeds it: padded blocks
of words as little-endian loads read the message, big-endian mode, the result read back in
reverse; checked against hashlib."""
from __future__ import annotations

import hashlib
import struct

import pytest

from emulator.devices import sha256 as sh
from emulator.vtime import PS_PER_US
from k210_fixtures import idle_elf, make_board  # noqa: F401


def sdk_hash(device, message: bytes) -> bytes:
    """sha256_hard_calculate, register by register."""
    blocks = (len(message) + 64 + 8) // 64
    device.write(sh.NUM, 4, blocks, 0)
    device.write(sh.FUNCTION1, 4, 0, 0)
    device.write(sh.FUNCTION0, 4, sh.BIG_ENDIAN | sh.ENABLE, 0)
    padded = message + b"\x80" + b"\0" * ((56 - len(message) - 1) % 64) + struct.pack(">Q", 8 * len(message))
    assert len(padded) == 64 * blocks
    for (word,) in struct.iter_unpack("<I", padded):
        assert not device.read(sh.FUNCTION1, 4, 0) & sh.FIFO_FULL
        device.write(sh.DATA_IN, 4, word, 0)
    assert device.read(sh.FUNCTION0, 4, 0) & sh.ENABLE          # complete
    return b"".join(struct.pack("<I", device.read(sh.RESULT + 4 * (7 - i), 4, 0)) for i in range(8))


@pytest.mark.parametrize("message", [b"", b"abc", b"K210" * 40, bytes(range(256)) * 3])
def test_the_sdk_way_gives_the_sha256_digest(idle_elf, message):
    device = make_board(idle_elf).sha256
    assert sdk_hash(device, message) == hashlib.sha256(message).digest()


def test_not_complete_until_the_last_block_and_more_words_overflow(idle_elf):
    device = make_board(idle_elf).sha256
    device.write(sh.NUM, 4, 2, 0)
    device.write(sh.FUNCTION0, 4, sh.BIG_ENDIAN | sh.ENABLE, 0)
    for _ in range(16):
        device.write(sh.DATA_IN, 4, 0, 0)
    assert not device.read(sh.FUNCTION0, 4, 0) & sh.ENABLE
    assert device.read(sh.NUM, 4, 0) == 2 | 1 << 16
    for _ in range(17):
        device.write(sh.DATA_IN, 4, 0, 0)
    assert device.read(sh.FUNCTION0, 4, 0) & (sh.ENABLE | sh.OVERFLOW) == sh.ENABLE | sh.OVERFLOW


def test_a_dma_channel_feeds_the_message_as_the_freertos_sdk_does(idle_elf):
    """sha256.cpp's way: the channel (32-bit items to sha_data_in1, dma_sel SHA request 21) is
    started, then sha_function_reg_1's DMA bit set; the digest is hashlib's and the channel completes."""
    from emulator.devices import dmac as d
    board = make_board(idle_elf, cold=False)
    message = bytes(range(200))
    blocks = (len(message) + 64 + 8) // 64
    padded = message + b"\x80" + b"\0" * ((56 - len(message) - 1) % 64) + struct.pack(">Q", 8 * len(message))
    source = 0x8010_0000
    board.memory.load(source, padded)
    sha = board.sha256
    sha.write(sh.FUNCTION0, 4, sh.BIG_ENDIAN | sh.ENABLE, 0)      # sha256.cpp: sha_en, then the block count
    sha.write(sh.NUM, 4, blocks, 0)
    board.sysctl.write(0x64, 4, 21, 0)                          # dma_sel: channel 0 <- SHA
    channel = d.CH_BASE
    board.dmac.write(d.CFG, 8, d.CFG_ENABLE, 0)
    board.dmac.write(channel + d.SAR, 8, source, 0)
    board.dmac.write(channel + d.DAR, 8, sh.Sha256.BASE + sh.DATA_IN, 0)
    board.dmac.write(channel + d.BLOCK_TS, 8, len(padded) // 4 - 1, 0)
    board.dmac.write(channel + d.CTL, 8, 1 << 6 | 2 << 8 | 2 << 11, 0)        # fixed destination, 32-bit items
    board.dmac.write(channel + d.CH_CFG, 8, d.TT_MEM2PER << 32 | 1 << 35, 0)  # handshake 0 on the SHA side
    board.dmac.write(d.CHEN, 8, 0x0101, 0)
    assert not sha.read(sh.FUNCTION0, 4, 0) & sh.ENABLE       # nothing taken before the DMA bit
    sha.write(sh.FUNCTION1, 4, sh.DMA_ENABLE, PS_PER_US)
    assert not board.dmac.read(d.CHEN, 8, PS_PER_US) & 1               # done at once, the DMAC caught up
    assert sha.read(sh.FUNCTION0, 4, 2 * PS_PER_US) & sh.ENABLE
    digest = b"".join(struct.pack("<I", sha.read(sh.RESULT + 4 * (7 - i), 4, 2 * PS_PER_US)) for i in range(8))
    assert digest == hashlib.sha256(message).digest()


def test_dma_items_other_than_32_bits_are_unmodelled(idle_elf):
    from emulator.devices import dmac as d
    from emulator.errors import UnmodelledAccess
    board = make_board(idle_elf, cold=False)
    board.sysctl.write(0x64, 4, 21, 0)
    channel = d.CH_BASE
    board.dmac.write(d.CFG, 8, d.CFG_ENABLE, 0)
    board.dmac.write(channel + d.SAR, 8, 0x8010_0000, 0)
    board.dmac.write(channel + d.DAR, 8, sh.Sha256.BASE + sh.DATA_IN, 0)
    board.dmac.write(channel + d.BLOCK_TS, 8, 15, 0)
    board.dmac.write(channel + d.CTL, 8, 1 << 6 | 0 << 8 | 0 << 11, 0)        # 8-bit items
    board.dmac.write(channel + d.CH_CFG, 8, d.TT_MEM2PER << 32 | 1 << 35, 0)
    with pytest.raises(UnmodelledAccess, match="8-bit items"):
        board.dmac.write(d.CHEN, 8, 0x0101, 0)
