"""The SD card model against the SPI-mode protocol: exact bytes for each command."""
from __future__ import annotations

import os

import numpy as np
import pytest

from k210_fixtures import idle_elf, make_board  # noqa: F401

from emulator.errors import BadInput
from emulator.devices.sdcard import (BLOCK, INIT_TIME, NAC_BYTES, NCR_BYTES, READ_ACCESS_TIME, RULE_POWER_UP_CLOCKS, VARYING_NAC_MAX, SdCard,
                             SdImage, command_frame, crc7, crc16, crc16_bitwise)
from emulator.vtime import PS_PER_NS, PS_PER_S, PS_PER_US, Time

BLOCKS = 64


def _pattern(block: int) -> bytes:
    return bytes((block * 7 + i) & 0xFF for i in range(BLOCK))


@pytest.fixture
def image_path(tmp_path):
    path = tmp_path / "card.img"
    path.write_bytes(b"".join(_pattern(b) for b in range(BLOCKS)))
    return path


def clock(card: SdCard, data: bytes, now: Time = 0) -> bytes:
    return card.exchange(np.frombuffer(data, dtype=np.uint8).copy(), now).tobytes()


def command(card: SdCard, index: int, argument: int, reply_bytes: int, now: Time = 0, crc: bool = True) -> bytes:
    """Sends a command and clocks reply_bytes of 0xFF; returns what came back after the frame."""
    frame = command_frame(index, argument)
    if not crc:
        frame = frame[:5] + b"\x01"
    clock(card, frame, now)
    return clock(card, b"\xff" * reply_bytes, now)


def powered(image_path, writable=False, faults: frozenset[str] = frozenset(), access_time: Time = 0) -> SdCard:
    """A card that has had its power-up clocks and is selected; its reads' access time 0 unless given,
    so that tests of the byte protocol can clock every byte at one moment."""
    card = SdCard(SdImage(image_path, writable=writable), faults=faults, access_time=access_time)
    clock(card, b"\xff" * 10)            # 80 clocks with CS high
    card.set_selected(True, 0)
    return card


def initialised(image_path, writable=False, faults: frozenset[str] = frozenset(), access_time: Time = 0) -> SdCard:
    card = powered(image_path, writable, faults, access_time)
    command(card, 0, 0, 2)
    command(card, 8, 0x1AA, 6)
    for now in (0, INIT_TIME):
        command(card, 55, 0, 2, now)
        command(card, 41, 0x4000_0000, 2, now)
    return card


def test_crc7_matches_the_well_known_command_crcs():
    assert (crc7(bytes([0x40, 0, 0, 0, 0])) << 1 | 1) == 0x95     # CMD0
    assert (crc7(bytes([0x48, 0, 0, 1, 0xAA])) << 1 | 1) == 0x87  # CMD8(0x1AA)


def test_crc16_of_a_block_of_ff_is_the_spec_example():
    assert crc16(b"\xff" * 512) == 0x7FA1
    import random
    rng = random.Random(7)
    for length in (0, 1, 2, 511, 512, 513):
        data = bytes(rng.randrange(256) for _ in range(length))
        assert crc16(data) == crc16_bitwise(data)


def test_cmd0_without_power_up_clocks_is_answered_with_a_warning(image_path):
    """Firmware that ran on real Docks sends CMD0 without the 74 clocks (issue 10): by default the
    card answers it, and the broken rule is a warning counted under its kind."""
    broken = []
    card = SdCard(SdImage(image_path), on_rule=lambda kind, now, text: broken.append((kind, text)))
    card.set_selected(True, 0)
    assert command(card, 0, 0, 4) == b"\xff" * NCR_BYTES + b"\x01" + b"\xff" * (3 - NCR_BYTES)
    [(kind, text)] = broken
    assert kind == RULE_POWER_UP_CLOCKS
    assert text == ("SD card: CMD0 after only 0 clocks with CS high (the SD specification asks for at least 74 "
                    "after power-up): answered (--strict ignores it)")


def test_cmd0_needs_power_up_clocks_when_strict(image_path):
    warnings = []
    card = SdCard(SdImage(image_path), warn=warnings.append, strict=True)
    card.set_selected(True, 0)
    assert command(card, 0, 0, 4) == b"\xff" * 4
    assert warnings == ["SD card: CMD0 after only 0 clocks with CS high (the SD specification asks for at least "
                        "74 after power-up): ignored (--strict)"]
    card.set_selected(False, 0)
    clock(card, b"\xff" * 10)              # 80 clocks with CS high: now the card takes CMD0
    card.set_selected(True, 0)
    assert command(card, 0, 0, 3)[NCR_BYTES] == 0x01


@pytest.mark.parametrize("strict", [False, True])
def test_the_board_counts_the_broken_power_up_rule(image_path, idle_elf, strict):
    """On the board the card hears --strict, and its broken rule joins the run's warnings and is counted
    per rule (run.json's timing_warnings)."""
    board = make_board(idle_elf, sd_image=str(image_path), strict=strict)
    card = board.sd_slot.card
    card.set_selected(True, 0)
    reply = command(card, 0, 0, 3)
    assert reply[NCR_BYTES] == (0xFF if strict else 0x01)
    assert board.timing_warnings == {RULE_POWER_UP_CLOCKS: 1}
    assert "SD card: CMD0 after only 0 clocks with CS high" in board.warnings[-1]


def test_cmd0_enters_idle_with_r1_01_after_ncr(image_path):
    card = powered(image_path)
    reply = command(card, 0, 0, 3)
    assert reply == b"\xff" * NCR_BYTES + b"\x01" + b"\xff" * (2 - NCR_BYTES)


def test_cmd0_and_cmd8_need_a_good_crc(image_path):
    card = powered(image_path)
    assert command(card, 0, 0, 2, crc=False) == b"\xff\xff"   # still in SD mode: no answer at all
    command(card, 0, 0, 2)
    assert command(card, 0, 0, 2, crc=False)[NCR_BYTES] == 0x09   # idle | CRC error
    assert command(card, 8, 0x1AA, 2, crc=False)[NCR_BYTES] == 0x09


def test_cmd8_echoes_voltage_and_check_pattern(image_path):
    card = powered(image_path)
    command(card, 0, 0, 2)
    reply = command(card, 8, 0x1AA, 6)
    assert reply[NCR_BYTES:NCR_BYTES + 5] == bytes([0x01, 0x00, 0x00, 0x01, 0xAA])


def test_acmd41_keeps_idle_until_the_initialisation_time(image_path):
    card = powered(image_path)
    command(card, 0, 0, 2)
    command(card, 55, 0, 2, 0)
    assert command(card, 41, 0x4000_0000, 2, 0)[NCR_BYTES] == 0x01
    command(card, 55, 0, 2, INIT_TIME // 2)
    assert command(card, 41, 0x4000_0000, 2, INIT_TIME // 2)[NCR_BYTES] == 0x01
    command(card, 55, 0, 2, INIT_TIME)
    assert command(card, 41, 0x4000_0000, 2, INIT_TIME)[NCR_BYTES] == 0x00


def test_cmd41_without_cmd55_is_illegal(image_path):
    card = powered(image_path)
    command(card, 0, 0, 2)
    assert command(card, 41, 0x4000_0000, 2)[NCR_BYTES] == 0x05


def test_cmd58_reports_powered_up_sdhc(image_path):
    card = initialised(image_path)
    reply = command(card, 58, 0, 6)
    assert reply[NCR_BYTES:NCR_BYTES + 5] == bytes([0x00, 0xC0, 0xFF, 0x80, 0x00])


def test_reads_before_initialisation_are_illegal(image_path):
    card = powered(image_path)
    command(card, 0, 0, 2)
    assert command(card, 17, 0, 2)[NCR_BYTES] == 0x05


def test_cmd17_returns_token_block_and_crc16(image_path):
    card = initialised(image_path)
    reply = command(card, 17, 5, NCR_BYTES + 1 + NAC_BYTES + 1 + BLOCK + 2)
    assert reply[NCR_BYTES] == 0x00
    data_start = NCR_BYTES + 1 + NAC_BYTES
    assert reply[NCR_BYTES + 1:data_start] == b"\xff" * NAC_BYTES
    assert reply[data_start] == 0xFE
    block = reply[data_start + 1:data_start + 1 + BLOCK]
    assert block == _pattern(5)
    assert int.from_bytes(reply[data_start + 1 + BLOCK:data_start + 3 + BLOCK], "big") == crc16(block)


def test_cmd17_out_of_range_is_a_parameter_error(image_path):
    card = initialised(image_path)
    assert command(card, 17, BLOCKS, 2)[NCR_BYTES] == 0x40


def test_cmd18_streams_blocks_until_cmd12(image_path):
    card = initialised(image_path)
    per_block = NAC_BYTES + 1 + BLOCK + 2
    reply = command(card, 18, 10, NCR_BYTES + 1 + 3 * per_block)
    stream = reply[NCR_BYTES + 1:]
    for n in range(3):
        chunk = stream[n * per_block:(n + 1) * per_block]
        assert chunk[NAC_BYTES] == 0xFE
        assert chunk[NAC_BYTES + 1:NAC_BYTES + 1 + BLOCK] == _pattern(10 + n)
    clock(card, command_frame(12, 0))
    after = clock(card, b"\xff" * 12)
    # one stuff byte, R1, busy, then released
    assert after[0] == 0xFF and after[1] == 0x00
    assert after[2:6] == b"\x00" * 4 and after[6:] == b"\xff" * 6


BYTE = 400 * PS_PER_NS      # a byte at 20 MHz
ACCESS = 200 * PS_PER_US


def clock_from(card: SdCard, count: int, start: Time, period: Time = BYTE) -> bytes:
    """Clocks `count` bytes of 0xFF in one batch, byte i at start + i x period, handed over after the last."""
    data = np.full(count, 0xFF, dtype=np.uint8)
    return card.exchange(data, start + count * period, lambda i: start + i * period).tobytes()


def test_a_read_s_first_block_waits_for_the_access_time(image_path):
    card = initialised(image_path, access_time=ACCESS)
    clock(card, command_frame(17, 5), 0)                   # the command's last bit at 0
    reply = clock_from(card, 1200, BYTE)
    assert reply[NCR_BYTES] == 0x00                          # R1 at once
    ready = -(-ACCESS // BYTE)                               # the first byte clocked at or after 200 us
    assert reply[NCR_BYTES + 1:ready - 1] == b"\xff" * (ready - 2 - NCR_BYTES)
    token = ready - 1 + NAC_BYTES
    assert reply[ready - 1:token] == b"\xff" * NAC_BYTES
    assert reply[token] == 0xFE and reply[token + 1:token + 1 + BLOCK] == _pattern(5)


def test_a_slow_poller_gets_the_token_by_time_not_by_bytes(image_path):
    """A host that polls one byte every 50 us (the thesis's firmware calls a function per byte) sees the
    block after the access time, whatever few bytes it clocked meanwhile."""
    card = initialised(image_path, access_time=ACCESS)
    clock(card, command_frame(17, 3), 0)
    polls, now = [], 0
    while 0xFE not in polls:
        now += 50 * PS_PER_US
        polls += clock(card, b"\xff", now)
    assert now == ACCESS + NAC_BYTES * 50 * PS_PER_US      # released by the poll at 200 us, then the gap


def test_a_stream_waits_once_then_block_follows_block(image_path):
    card = initialised(image_path, access_time=ACCESS)
    clock(card, command_frame(18, 10), 0)
    per_block = NAC_BYTES + 1 + BLOCK + 2
    ready = -(-ACCESS // BYTE)
    stream = clock_from(card, ready + 3 * per_block, BYTE)[ready - 1:]
    for n in range(3):
        chunk = stream[n * per_block:(n + 1) * per_block]
        assert chunk[NAC_BYTES] == 0xFE and chunk[NAC_BYTES + 1:NAC_BYTES + 1 + BLOCK] == _pattern(10 + n)


def test_cmd12_during_the_access_time_drops_the_block(image_path):
    card = initialised(image_path, access_time=ACCESS)
    clock(card, command_frame(18, 10), 0)
    clock(card, b"\xff" * 4, 10 * PS_PER_US)
    clock(card, command_frame(12, 0), 20 * PS_PER_US)
    after = clock(card, b"\xff" * 8, 30 * PS_PER_US)
    assert after[:6] == b"\xff\x00" + b"\x00" * 4 and after[6:] == b"\xff\xff"
    assert 0xFE not in clock(card, b"\xff" * 600, ACCESS * 2)


def test_a_command_during_the_access_time_abandons_the_read(image_path):
    """A host that gives up waiting for the block and resets the card (CMD0) or reads another block
    gets its answer at once, not behind the abandoned block."""
    card = initialised(image_path, access_time=ACCESS)
    clock(card, command_frame(17, 5), 0)
    clock(card, b"\xff" * 4, 10 * PS_PER_US)
    clock(card, command_frame(13, 0), 20 * PS_PER_US)
    assert clock(card, b"\xff" * 3, 30 * PS_PER_US)[NCR_BYTES:NCR_BYTES + 2] == b"\x00\x00"   # R2 at once
    clock(card, command_frame(17, 7), 40 * PS_PER_US)
    reply = clock_from(card, 1200, 40 * PS_PER_US + BYTE)
    token = reply.index(0xFE)
    assert reply[token + 1:token + 1 + BLOCK] == _pattern(7)     # the second read's block, after its own wait
    assert token >= ACCESS // BYTE


def test_the_default_access_time_is_the_dock_card_s(image_path):
    assert SdCard(SdImage(image_path)).access_time == READ_ACCESS_TIME == 200 * PS_PER_US
    with pytest.raises(BadInput, match="negative"):
        SdCard(SdImage(image_path), access_time=-1)


def test_varying_nac_gives_every_gap_from_1_to_its_maximum_in_a_stream(image_path):
    card = initialised(image_path, faults=frozenset({"varying-nac"}))
    first = 10
    stream = command(card, 18, first, NCR_BYTES + 1 + VARYING_NAC_MAX * (VARYING_NAC_MAX + 1 + BLOCK + 2))
    stream = stream[NCR_BYTES + 1:]
    gaps = []
    for n in range(VARYING_NAC_MAX):
        gap = len(stream) - len(stream.lstrip(b"\xff"))
        gaps.append(gap)
        assert stream[gap] == 0xFE
        block = stream[gap + 1:gap + 1 + BLOCK]
        assert block == _pattern(first + n)
        assert int.from_bytes(stream[gap + 1 + BLOCK:gap + 3 + BLOCK], "big") == crc16(block)
        stream = stream[gap + 3 + BLOCK:]
    assert sorted(gaps) == list(range(1, VARYING_NAC_MAX + 1))


def test_cmd59_turns_crc_checking_on_for_every_command(image_path):
    card = initialised(image_path)
    assert command(card, 13, 0, 3, crc=False)[NCR_BYTES] == 0x00      # not checked yet
    command(card, 59, 1, 2)
    assert command(card, 13, 0, 3, crc=False)[NCR_BYTES] == 0x08
    assert command(card, 13, 0, 3)[NCR_BYTES:NCR_BYTES + 2] == b"\x00\x00"


def test_unknown_command_is_illegal(image_path):
    card = initialised(image_path)
    assert command(card, 5, 0, 2)[NCR_BYTES] == 0x04


def test_csd_reports_the_capacity(image_path):
    card = initialised(image_path)
    reply = command(card, 9, 0, NCR_BYTES + 1 + NAC_BYTES + 1 + 16 + 2)
    csd = reply[NCR_BYTES + 1 + NAC_BYTES + 1:][:16]
    assert csd[0] >> 6 == 1
    c_size = ((csd[7] & 0x3F) << 16) | (csd[8] << 8) | csd[9]
    assert c_size == max(0, BLOCKS // 1024 - 1)
    assert csd[15] == (crc7(csd[:15]) << 1) | 1


def test_crc_faults_reach_the_csd_too(image_path):
    """--sd-fault flaky-crc sends each data block's CRC16 wrong the first time: the CSD is a
    data block, so the firmware's retry of CMD9 is exercised too; bad-crc never gets it right."""
    length = NCR_BYTES + 1 + NAC_BYTES + 1 + 16 + 2
    for fault, wrong in (("flaky-crc", [True, False]), ("bad-crc", [True, True])):
        card = SdCard(SdImage(image_path), faults=frozenset({fault}))
        clock(card, b"\xff" * 10)
        card.set_selected(True, 0)
        command(card, 0, 0, 2)
        for now in (0, INIT_TIME):
            command(card, 55, 0, 2, now)
            command(card, 41, 0x4000_0000, 2, now)
        for expected in wrong:
            reply = command(card, 9, 0, length)
            csd, crc = reply[-18:-2], int.from_bytes(reply[-2:], "big")
            assert (crc != crc16(csd)) == expected, fault


def _write_block(card: SdCard, index: int, block: int, data: bytes, now: Time = PS_PER_S) -> bytes:
    assert command(card, index, block, 2, now)[NCR_BYTES] == 0x00
    clock(card, b"\xff" + (b"\xfe" if index == 24 else b"\xfc") + data + crc16(data).to_bytes(2, "big"), now)
    return clock(card, b"\xff" * 2, now)


def test_write_lands_in_memory_only_when_read_only(image_path):
    before = image_path.read_bytes()
    card = initialised(image_path)
    data = bytes(range(256)) * 2
    response = _write_block(card, 24, 3, data)
    assert response[0] & 0x1F == 0x05
    assert response[1] == 0x00                         # busy while programming
    assert clock(card, b"\xff", 2 * PS_PER_S) == b"\xff"  # ready later
    assert card.image.read(3) == data                  # the firmware reads back what it wrote
    card.image.close()
    assert image_path.read_bytes() == before           # the file is untouched


def test_write_reaches_the_file_when_writable(image_path):
    card = initialised(image_path, writable=True)
    data = b"\xa5" * BLOCK
    assert _write_block(card, 24, 7, data)[0] & 0x1F == 0x05
    card.image.close()
    assert image_path.read_bytes()[7 * BLOCK:8 * BLOCK] == data


def test_write_with_bad_crc_is_rejected_when_checking(image_path):
    card = initialised(image_path, writable=True)
    command(card, 59, 1, 2)
    assert command(card, 24, 2, 2, PS_PER_S)[NCR_BYTES] == 0x00
    clock(card, b"\xff\xfe" + b"\x11" * BLOCK + b"\x00\x00", PS_PER_S)
    assert clock(card, b"\xff", PS_PER_S)[0] & 0x1F == 0x0B
    card.image.close()
    assert image_path.read_bytes()[2 * BLOCK:3 * BLOCK] == _pattern(2)


def test_multi_block_write_with_stop_token(image_path):
    card = initialised(image_path, writable=True)
    assert command(card, 25, 20, 2, PS_PER_S)[NCR_BYTES] == 0x00
    for n in range(2):
        data = bytes([n + 1]) * BLOCK
        clock(card, b"\xff\xfc" + data + crc16(data).to_bytes(2, "big"), (1 + n) * PS_PER_S)
        assert clock(card, b"\xff", (1 + n) * PS_PER_S)[0] & 0x1F == 0x05
        clock(card, b"\xff" * 4, (2 + n) * PS_PER_S)   # well after the programming time
    clock(card, b"\xfd", 5 * PS_PER_S)
    card.image.close()
    written = image_path.read_bytes()
    assert written[20 * BLOCK:21 * BLOCK] == b"\x01" * BLOCK and written[21 * BLOCK:22 * BLOCK] == b"\x02" * BLOCK


def test_deselected_card_does_not_answer(image_path):
    card = initialised(image_path)
    card.set_selected(False, 0)
    assert command(card, 13, 0, 3) == b"\xff" * 3


def test_missing_empty_and_partial_block_images_are_bad_input(tmp_path):
    """What no card can hold: nothing, or a part of a 512-byte block."""
    with pytest.raises(BadInput, match="does not exist"):
        SdImage(tmp_path / "none.img")
    for size in (0, 1000):
        odd = tmp_path / f"odd{size}.img"
        odd.write_bytes(b"\x00" * size)
        with pytest.raises(BadInput, match="whole number"):
            SdImage(odd)


def _mbr(*entries: tuple[int, int, int]) -> bytes:
    """Block 0 with these (type, first block, block count) partition entries."""
    mbr = bytearray(BLOCK)
    for n, (kind, first, count) in enumerate(entries):
        at = 446 + 16 * n
        mbr[at + 4] = kind
        mbr[at + 8:at + 12] = first.to_bytes(4, "little")
        mbr[at + 12:at + 16] = count.to_bytes(4, "little")
    mbr[510:512] = b"\x55\xaa"
    return bytes(mbr)


def test_a_partition_past_the_end_is_a_warning_and_the_card_still_works(tmp_path):
    """A partition table that claims more than the image holds (any entry, used or not) was once
    refused as a truncated image. The card is what the image holds and the partition table is
    the firmware's to judge (it reports error 5, tests/end_to_end/test_storage_end_to_end.py); the user
    still hears that the image looks cut short."""
    image = tmp_path / "past.img"
    image.write_bytes(_mbr((0x0C, 8, 56), (0x83, 2048, 100_000)) + _pattern(1) * (BLOCKS - 1))
    heard: list[str] = []
    card = SdImage(image, warn=heard.append)
    assert card.blocks == BLOCKS
    assert [note for note in heard if "runs past" in note] == [
        f"SD card image {image}: partition 2 (type 0x83, blocks 2048..102047) runs past the image's last "
        f"block {BLOCKS - 1}: a truncated image? The card holds only the image's blocks"]
    card.close()
    card = initialised(image)
    reply = command(card, 17, BLOCKS - 1, NCR_BYTES + 1 + NAC_BYTES + 1 + BLOCK + 2)
    assert reply[NCR_BYTES] == 0x00 and reply[NCR_BYTES + 1 + NAC_BYTES + 1:][:BLOCK] == _pattern(1)
    assert command(card, 17, BLOCKS, 2)[NCR_BYTES] == 0x40   # outside the card: parameter error


@pytest.mark.parametrize("blocks,c_size,note", [
    (2048, 1, None),
    (3000, 1, "3000 blocks is not a whole number of 512 KiB (an SDHC card's capacity is (C_SIZE + 1) x 512 KiB): "
              "the CSD states 2048 blocks, so the last 952 are beyond what the firmware is told"),
    (64, 0, "64 blocks is less than 512 KiB, the smallest capacity an SDHC card's CSD can state: the CSD says "
            "1024 blocks, and blocks 64 on answer out of range"),
])
def test_the_csd_states_the_whole_512_kib_the_image_holds(tmp_path, blocks, c_size, note):
    image = tmp_path / "card.img"
    with image.open("wb") as handle:
        handle.truncate(blocks * BLOCK)
    heard: list[str] = []
    card = SdImage(image, warn=heard.append)
    assert card.csd_c_size == c_size
    assert heard == ([] if note is None else [f"SD card image {image}: {note}"])
    card.close()


def test_an_image_cut_short_during_the_run_stops_clearly(tmp_path):
    """The image is read as the run goes (not mapped): a file another program truncates
    meanwhile is a clear stop naming the block, where a mapping ended the model with SIGBUS."""
    from emulator.devices.sdcard import SdImage
    path = tmp_path / "card.img"
    path.write_bytes(bytes(range(256)) * 2 * 2048)            # 2048 blocks
    image = SdImage(path)
    assert image.read(2047)[:2] == bytes((0, 1))
    os.truncate(path, 512 * 1000)
    with pytest.raises(BadInput, match="block 2047 is gone: the file is 512000 bytes now"):
        image.read(2047)
    image.close()


def test_an_image_that_cannot_be_opened_is_bad_input(tmp_path, monkeypatch):
    from emulator.devices.sdcard import SdImage
    path = tmp_path / "card.img"
    path.write_bytes(bytes(512 * 1024))

    def refused(self, *args, **kwargs):
        raise PermissionError(13, "Permission denied")
    monkeypatch.setattr(type(path), "open", refused)
    with pytest.raises(BadInput, match="cannot open it for writing \\(--sd-writable\\) \\(Permission denied\\)"):
        SdImage(path, writable=True)


def test_an_image_over_what_a_csd_can_state_is_refused(tmp_path):
    """CSD 2.0's C_SIZE has 22 bits: 2 TiB at most, which an image one 512 KiB unit larger exceeds
    (a sparse file: no disk is used)."""
    from emulator.devices.sdcard import SdImage
    path = tmp_path / "huge.img"
    with path.open("wb") as handle:
        handle.truncate((2 << 40) + (512 << 10))
    with pytest.raises(BadInput, match="more than the 2 TiB"):
        SdImage(path)
    with path.open("r+b") as handle:
        handle.truncate(2 << 40)
    SdImage(path).close()                                      # exactly 2 TiB: stated
