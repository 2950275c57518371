"""The firmware reads FAT32 cards through the emulated SD card: every file it loads must
match, byte for byte (size and CRC-32), what the host put on the card, and every failure
must end in its own error code, console line and error screen colour."""
from __future__ import annotations

import json
import re
import subprocess
import zlib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from k210_common.exit_status import EXIT_FIRMWARE_ERROR
from k210_common.firmware_errors import firmware_error
from suite import ROOT, copy_card, make_card, run_emulator, shared_value
from firmware_calls import FirmwareCaller
from sdcard_image.fat32 import CardWriter
from sdcard_image.layouts import (cluster_chain, delete_leaving_entries, directory_entries, fill_directory,
                                  is_fragmented, place_case_variants, write_fragmented)

LOAD = re.compile(r"^load (.+) (\d+) crc32=([0-9a-f]{8})$", re.M)
ERROR = re.compile(r"^error (\d+) (.*)$", re.M)
BIG_BYTES = 2 * 1024 * 1024 + 12345
LONG_PATH = "Long Folder Name/deeper/a file with a rather long name.obj"
SCENE_BYTES = 512   # scene.ini is written once as a one-cluster placeholder and patched per test


TRIANGLE = b"v 0 0 -1\nv 1 0 -1\nv 0 1 -1\nf 1 2 3\n"


def obj_bytes(size: int, tag: str) -> bytes:
    """A valid one-triangle .obj of exactly `size` bytes (comment lines make up the rest)."""
    head = f"# {tag}\n".encode() + TRIANGLE
    return head + _padding(size - len(head))


def ppm_bytes(size: int) -> bytes:
    """A valid 2x2 P6 texture of exactly `size` bytes (comment lines in its header)."""
    pixels = bytes([255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255])
    tail = b"2 2\n255\n" + pixels
    return b"P6\n" + _padding(size - 3 - len(tail)) + tail


def _padding(count: int) -> bytes:
    assert count >= 0
    lines = []
    while count:
        take = min(count, 80)
        lines.append(b"#" * (take - 1) + b"\n" if take > 1 else b"\n")
        count -= take
    return b"".join(lines)


@pytest.fixture(scope="session")
def loader_card(tmp_path_factory):
    """One card with every layout the loader must cope with, all files valid models or
    textures (made once for all xdist workers); returns (image, {card path: bytes})."""
    return shared_value(tmp_path_factory, "loader_card", _make_loader_card)


def _make_loader_card(folder: Path) -> tuple[Path, dict[str, bytes]]:
    image = folder / "card.img"
    files: dict[str, bytes] = {}
    with CardWriter.create(image, 64) as writer:
        cluster = writer.bytes_per_cluster
        writer.makedirs("/frag")
        files["/frag/fragmented.obj"] = obj_bytes(cluster * 9 + 123, "fragmented model")
        write_fragmented(writer, "/frag/fragmented.obj", files["/frag/fragmented.obj"], fragments=3)
        files["/frag/fragmented.ppm"] = ppm_bytes(cluster * 5 + 77)
        write_fragmented(writer, "/frag/fragmented.ppm", files["/frag/fragmented.ppm"], fragments=3)
        writer.makedirs("/deleted")
        names = ["first deleted file.obj", "KEEP1.OBJ", "second deleted.obj", "kept long name.obj", "GONE.OBJ"]
        for n, name in enumerate(names):
            files[f"/deleted/{name}"] = obj_bytes(300 + 611 * n, name)
            writer.write(f"/deleted/{name}", files[f"/deleted/{name}"])
        gone = ["/deleted/first deleted file.obj", "/deleted/second deleted.obj", "/deleted/GONE.OBJ"]
        delete_leaving_entries(writer, gone)
        for path in gone:
            del files[path]
        files.update(fill_directory(writer, "/many", min_clusters=3, name_pattern="entry number {:03d}.obj",
                                    content_for=lambda i: obj_bytes(60 + i, f"entry {i}")))
        files.update(place_case_variants(writer, "/case", ["Cube.obj", "cube.obj", "CUBE.OBJ"],
                                         [obj_bytes(100 + 10 * i, f"variant {i}") for i in range(3)]))
        writer.makedirs("/sizes")
        writer.makedirs("/Long Folder Name/deeper")
        extra = {
            "/sizes/empty.obj": b"",
            "/sizes/one.obj": b"\n",
            "/sizes/cluster.obj": obj_bytes(cluster, "exactly one cluster"),
            "/sizes/big.obj": obj_bytes(BIG_BYTES, "several MiB"),
            "/" + LONG_PATH: obj_bytes(700, "long name"),
        }
        for path, data in extra.items():
            writer.write(path, data)
        files.update(extra)
        writer.write("/scene.ini", _scene_bytes(""))
    assert len(cluster_chain(image, "/many")) >= 3
    assert is_fragmented(cluster_chain(image, "/frag/fragmented.obj"))
    return image, files


def _scene_bytes(text: str) -> bytes:
    """scene.ini text padded with comment lines to SCENE_BYTES, so it fits the placeholder."""
    data = text.encode()
    return data + _padding(SCENE_BYTES - len(data))


def _partition_geometry(image: Path) -> tuple[int, int, int, int, int]:
    """(partition start byte, reserved sectors, FAT count, sectors per FAT, sectors per cluster)."""
    with image.open("rb") as handle:
        raw = handle.read(1024 * 1024 + 512)        # the MBR and, 1 MiB in, the first partition's BPB
    start = int.from_bytes(raw[446 + 8:446 + 12], "little") * 512
    bpb = raw[start:start + 512]
    return (start, int.from_bytes(bpb[0x0E:0x10], "little"), bpb[0x10],
            int.from_bytes(bpb[0x24:0x28], "little"), bpb[0x0D])


def _cluster_offset(image: Path, cluster: int) -> int:
    start, reserved, fats, fat_sectors, per_cluster = _partition_geometry(image)
    return start + (reserved + fats * fat_sectors + (cluster - 2) * per_cluster) * 512


def run_scene(firmware: Path, image: Path, scene: str, tmp_path: Path, *extra: str):
    """Copies the card, puts `scene` into its scene.ini placeholder and boots the firmware."""
    tmp_path.mkdir(parents=True, exist_ok=True)
    card = tmp_path / "card.img"
    copy_card(image, card)
    chain = cluster_chain(card, "/scene.ini")
    with card.open("r+b") as handle:
        handle.seek(_cluster_offset(card, chain[0]))
        handle.write(_scene_bytes(scene))
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "1", "--out", str(out),
                          "--quiet", *extra)
    return result, (out / "console.log").read_text(errors="replace"), out


def _lookup(files: dict[str, bytes], path: str) -> bytes:
    """FAT names match without regard to case."""
    wanted = "/" + path.lower()
    matches = [data for name, data in files.items() if name.lower() == wanted]
    assert len(matches) == 1, path
    return matches[0]


WIREFRAME = "mode = wireframe\n"    # no texture is read: one model file per run

CASES = {
    "one-cluster": "sizes/cluster.obj",
    "fragmented": "frag/fragmented.obj",
    "several-mib": "SIZES/BIG.OBJ",
    "long-name-in-subfolders": LONG_PATH,
    "behind-deleted-entries": "deleted/kept long name.obj",
    "8.3-name-any-case": "deleted/keep1.obj",
    "case-variant-1": "case/v1/CUBE.OBJ",
    "case-variant-3": "Case/V3/cube.obj",
}


def _load_line(path: str, data: bytes) -> str:
    return f"load {path} {len(data)} crc32={zlib.crc32(data):08x}"


@pytest.mark.parametrize("model", CASES.values(), ids=CASES.keys())
def test_loaded_files_match_the_host_byte_for_byte(firmware, loader_card, tmp_path, model):
    image, files = loader_card
    result, console, _ = run_scene(firmware, image, f"# test scene\r\nmodel = {model}\r\n{WIREFRAME}", tmp_path)
    assert result.returncode == 0, result.stderr + console
    assert _load_line(model, _lookup(files, model)) in console
    assert "model: 1 triangles" in console


def test_a_fragmented_texture_loads_too(firmware, loader_card, tmp_path):
    image, files = loader_card
    result, console, _ = run_scene(firmware, image, "model=sizes/cluster.obj\ntexture=frag/fragmented.ppm\n",
                                   tmp_path)
    assert result.returncode == 0, result.stderr + console
    assert _load_line("frag/fragmented.ppm", files["/frag/fragmented.ppm"]) in console
    assert "texture: 2x2" in console


@pytest.mark.parametrize("model", ["sizes/empty.obj", "sizes/one.obj"])
def test_tiny_files_load_exactly_then_fail_as_models(firmware, loader_card, tmp_path, model):
    """0- and 1-byte files load byte for byte; as models they have no faces, which is error 10."""
    image, files = loader_card
    result, console, out = run_scene(firmware, image, f"model={model}\n{WIREFRAME}", tmp_path)
    assert _load_line(model, files["/" + model]) in console
    assert_error(result, console, out, "BAD_MODEL", "no faces")


def test_a_directory_spanning_several_clusters(firmware, loader_card, tmp_path):
    image, files = loader_card
    many = sorted(name for name in files if name.startswith("/many/"))
    last = many[-1]
    result, console, _ = run_scene(firmware, image, f"model={last[1:]}\n{WIREFRAME}", tmp_path)
    assert result.returncode == 0, result.stderr + console
    assert _load_line(last[1:], files[last]) in console


def test_a_block_with_a_bad_crc_is_read_again(firmware, loader_card, tmp_path):
    image, files = loader_card
    result, console, _ = run_scene(firmware, image, f"model=frag/fragmented.obj\n{WIREFRAME}", tmp_path,
                                   "--sd-fault", "flaky-crc")
    assert result.returncode == 0, result.stderr + console
    assert _load_line("frag/fragmented.obj", files["/frag/fragmented.obj"]) in console


def _read_commands(firmware: Path, card: Path, faults: frozenset[str]) -> tuple[dict[int, int], str]:
    """Runs the card to its first frame through the Board API; the read commands the card received
    (CMD17, CMD18) and the console."""
    from emulator.board import Board
    board = Board(str(firmware), sd_image=str(card), sd_faults=faults)
    try:
        board.run(1)
    finally:
        board.close()
    commands = board.wiring.sd_slot.card.commands
    return {17: commands.get(17, 0), 18: commands.get(18, 0)}, "".join(line + "\n" for _, line in board.console_lines)


def test_blocks_whose_token_gaps_vary_load_byte_for_byte_without_reading_any_again(firmware, tmp_path):
    """sd_read_blocks looks for each next token among the SD_LOOKAHEAD_BYTES it receives after a block
    (gaps of 1 .. 15 bytes: the token at every place there, the data after it kept) and waits for a
    later one byte by byte (16 .. 24). No block fails its check on the way: the card gets the same
    read commands as with its usual gap of 8 (a block read wrong is read again, by a new command)."""
    from sdcard_image import build_image
    model = obj_bytes(60 * 512 + 77, "sixty-one blocks")
    (tmp_path / "files").mkdir()
    (tmp_path / "files" / "model.obj").write_bytes(model)
    card = tmp_path / "card.img"
    build_image(card, [tmp_path / "files"], scene={"model": "files/model.obj", "mode": "wireframe"}, force=True)
    varying, console = _read_commands(firmware, card, frozenset({"varying-nac"}))
    assert _load_line("files/model.obj", model) in console
    usual, _ = _read_commands(firmware, card, frozenset())
    assert varying == usual
    # with a first CRC16 wrong, every block is read again: still loaded byte for byte
    _, console = _read_commands(firmware, card, frozenset({"varying-nac", "flaky-crc"}))
    assert _load_line("files/model.obj", model) in console


def _stores_per_read_command(firmware: Path, folder: Path, access_us: int,
                             faster: tuple[int, int] | None = None) -> list[tuple[int, int]]:
    """Boots a card whose model takes some 20 read commands, with the card's read access time
    `access_us`; `faster` = (n, us): once the n-th read command has reached the card, the card's
    access time is `us` (from the next command on).
    Returns hart 0's stores to SPI1 and to the CLINT from each read command to the next (SPI1: its
    token bursts, and a few for the command and the DMA; the CLINT: two for a sleep, mtimecmp set and
    put back); checks that the model loaded byte for byte."""
    from emulator.board import Board
    from emulator.vtime import PS_PER_US
    from sdcard_image import build_image
    model = obj_bytes(20 * 512 + 77, "twenty-one blocks")
    (folder / "files").mkdir()
    (folder / "files" / "model.obj").write_bytes(model)
    card = folder / "card.img"
    build_image(card, [folder / "files"], scene={"model": "files/model.obj", "mode": "wireframe"}, force=True)
    board = Board(str(firmware), sd_image=str(card), sd_access_time=access_us * PS_PER_US)
    sd = board.wiring.sd_slot.card
    reads = lambda: sd.commands.get(17, 0) + sd.commands.get(18, 0)   # noqa: E731
    marks = []        # hart 0's stores to SPI1 when each read command had reached the card
    exchange = sd.exchange

    def watched(mosi, now, clocked_at=None):
        before = reads()
        answer = exchange(mosi, now, clocked_at)
        if reads() != before:
            marks.append((board.bus.device_writes["SPI1"][0], board.bus.device_writes.get("CLINT", [0])[0]))
            if faster is not None and reads() == faster[0]:
                sd.access_time = faster[1] * PS_PER_US
        return answer
    sd.exchange = watched
    try:
        board.run(1)
    finally:
        board.close()
    assert _load_line("files/model.obj", model) in "".join(line + "\n" for _, line in board.console_lines)
    return [(after[0] - before[0], after[1] - before[1]) for before, after in zip(marks, marks[1:])]


def test_a_read_command_sleeps_through_most_of_the_cards_access_time(firmware, tmp_path):
    """sd_read.S sd_wait_first_token: a read command sleeps in WFI through 3/4 of the access time the
    last one took (Nac, from its R1 to its data token), then looks for the token in bursts. The first
    read command has nothing to go by and polls the whole access time, a 2 ms one here; each one
    after polls about a quarter of it (4,021 stores, then 1,013-1,076; polling all of it, each took
    4,021)."""
    per_command = _stores_per_read_command(firmware, tmp_path, 2000)
    (first, first_sleep), later = per_command[0], per_command[1:]
    assert len(later) >= 8 and first > 2000 and first_sleep == 0, per_command
    assert max(spi for spi, _ in later) < 0.4 * first and min(clint for _, clint in later) >= 2, per_command


def test_a_card_that_gets_faster_is_measured_again(firmware, tmp_path):
    """The card's access time drops from 2 ms to 200 us at its sixth read command: that command's
    sleep outlasts it, and its token comes in the first burst after the sleep, which says only that
    the card was ready sooner. The next command sleeps not at all and measures the new access time
    (polling all of it), and the ones after sleep through 3/4 of that: one command oversleeps, not a
    string of them each a quarter shorter (37 stores, then 437, then 117-180)."""
    spi = [stores for stores, _ in _stores_per_read_command(firmware, tmp_path, 2000, faster=(5, 200))]
    overslept, measuring, after = spi[5], spi[6], spi[7:]
    assert overslept < 100 and 200 < measuring < 1000, spi
    assert len(after) >= 4 and max(after) < 0.5 * measuring, spi


@pytest.mark.parametrize("access_us, sleeps", [(20, True), (0, False)])
def test_a_fast_card_is_slept_for_alike_every_command_or_not_at_all(firmware, tmp_path, access_us, sleeps):
    """A card of 20 us: every command after the first sleeps (its 3/4, about 14 us, leaves less than a
    burst, which must not count as the card getting faster: it would be measured again every other
    command); one that answers at once (8 bytes of 0xFF): no command sleeps, 3/4 of its access time
    being under SD_ACCESS_SLEEP_MIN_US."""
    clint = [stores for _, stores in _stores_per_read_command(firmware, tmp_path, access_us)]
    assert len(clint) >= 8 and clint[0] == 0
    assert all(stores >= 2 for stores in clint[1:]) if sleeps else not any(clint), clint


# --- failures ---------------------------------------------------------------------------------

def assert_error(result, console: str, out: Path, name: str, words: str) -> None:
    """The run ended with the firmware's error ERR_<name> (firmware/include/errors.inc): its
    console line, with `words` in it, and its screen colour."""
    error = firmware_error(name)
    assert result.returncode == EXIT_FIRMWARE_ERROR, result.stderr + console
    errors = ERROR.findall(console)
    assert errors and int(errors[0][0]) == error.code, console
    assert error.reported_by(f"error {errors[0][0]} {errors[0][1]}"), (error.words, console)
    assert words in errors[0][1], console
    frames = sorted(out.glob("frame_*.png"))
    assert frames, "no error screen was shown"
    screen = np.asarray(Image.open(frames[-1]).convert("RGB"))
    assert (screen == error.rgb888).all(), f"error screen is not the colour of ERR_{name} ({error.colour_name})"


def test_no_card(firmware, tmp_path):
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--frames", "1", "--out", str(out), "--quiet")
    assert_error(result, (out / "console.log").read_text(), out, "NO_CARD", "no card")


def test_card_that_never_initialises_times_out(firmware, loader_card, tmp_path):
    result, console, out = run_scene(firmware, loader_card[0], f"model=sizes/cluster.obj\n{WIREFRAME}", tmp_path,
                                     "--sd-fault", "no-init")
    assert_error(result, console, out, "CARD_TIMEOUT", "timeout")


def test_blocks_that_stay_bad_are_a_crc_error(firmware, loader_card, tmp_path):
    result, console, out = run_scene(firmware, loader_card[0], f"model=sizes/cluster.obj\n{WIREFRAME}", tmp_path,
                                     "--sd-fault", "bad-crc")
    assert_error(result, console, out, "CRC", "CRC")


def test_card_without_fat32_partition(firmware, tmp_path):
    blank = tmp_path / "blank.img"
    blank.write_bytes(bytes(4 * 1024 * 1024))
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(blank), "--frames", "1", "--out", str(out), "--quiet")
    assert_error(result, (out / "console.log").read_text(), out, "NO_FAT32", "FAT32")


MIB = 1024 * 1024


def _cut_card(tmp_path: Path) -> tuple[Path, int]:
    """A card whose model lies past 4 MiB, then cut to its first 4 MiB, as a download cut short
    leaves it: the partition table and the volume claim 64 MiB. Returns (image, blocks left)."""
    card = make_card(tmp_path / "card", {"/scene.ini": f"model = model.obj\n{WIREFRAME}".encode(),
                                         "/pad.bin": bytes(3 * MIB), "/model.obj": TRIANGLE})
    cut = 4 * MIB
    assert _cluster_offset(card, cluster_chain(card, "/model.obj")[0]) >= cut
    with card.open("r+b") as handle:
        handle.truncate(cut)
    return card, cut // 512


def test_a_card_cut_short_is_a_partition_error_naming_the_block(firmware, tmp_path):
    """The partition claims blocks the card does not have. The board model runs the card (it
    holds what the image holds) and warns that the image looks truncated; the firmware compares
    the partition with the card's capacity from its CSD before reading, and reports error 5
    naming the blocks (it used to read on and stop with error 3 when the card refused a block
    of the model past its end)."""
    card, blocks = _cut_card(tmp_path)
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "1", "--out", str(out), "--quiet")
    console = (out / "console.log").read_text()
    end = 64 * MIB // 512 - 1
    assert_error(result, console, out, "NO_FAT32", f"no FAT32 partition: the partition ends at block {end}, "
                                          f"past the card's last block {blocks - 1}")
    assert f"sd: card ready, SDHC (block addressing), {blocks} blocks" in console
    warnings = json.loads((out / "run.json").read_text())["warnings"]
    assert any(f"partition 1 (type 0x0C, blocks 2048..{end}) runs past the image's last block {blocks - 1}" in w
               for w in warnings), warnings


def test_a_volume_past_the_card_is_an_invalid_boot_sector(firmware, tmp_path):
    """A partition entry without a length leaves the BPB's total sectors to say where the
    volume ends: past the card's last block, that is error 5 too."""
    card, blocks = _cut_card(tmp_path)
    with card.open("r+b") as handle:
        handle.seek(446 + 12)
        handle.write(bytes(4))
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "1", "--out", str(out), "--quiet")
    assert_error(result, (out / "console.log").read_text(), out, "NO_FAT32",
                 f"invalid BPB: the volume ends at block {64 * MIB // 512 - 1}, past the card's last block "
                 f"{blocks - 1}")


@pytest.fixture(scope="module")
def caller(firmware) -> FirmwareCaller:
    """The firmware on a board model whose hart 0 runs single routines (firmware_calls.py)."""
    return FirmwareCaller(firmware)


def _csd(structure: int, **fields: tuple[int, int, int]) -> bytes:
    """A CSD register with CSD_STRUCTURE and the given fields, each (high bit, low bit, value)
    as the SD specification numbers the register's 128 bits; 16 bytes, most significant first."""
    register = structure << 126
    for high, low, value in fields.values():
        assert value < 1 << (high - low + 1)
        register |= value << low
    return register.to_bytes(16, "big")


@pytest.mark.parametrize("c_size,mult,block_len", [(0, 0, 9), (3839, 7, 10), (4095, 7, 11), (1234, 3, 9)])
def test_the_firmware_reads_an_sdsc_capacity_from_a_version_1_csd(caller, c_size, mult, block_len):
    """sd_csd_blocks on the board model's CPU: (C_SIZE + 1) x 2^(C_SIZE_MULT + 2) blocks of
    2^READ_BL_LEN bytes, counted in 512-byte blocks (the model's card only sends version 2.0)."""
    caller.write(caller.scratch, _csd(0, c_size=(73, 62, c_size), mult=(49, 47, mult),
                                      block_len=(83, 80, block_len), filler=(61, 50, 0xABC)))
    result = caller.call("sd_csd_blocks", [caller.scratch])
    assert result.a[0] == ((c_size + 1) << (mult + 2 + block_len)) // 512 and result.a[1] == 0


def test_the_firmware_reads_an_sdhc_capacity_and_refuses_unknown_csd_versions(caller):
    for c_size in (0, 15, 0x3F_FFFF):
        caller.write(caller.scratch, _csd(1, c_size=(69, 48, c_size), around=(75, 70, 0x3F), low=(47, 40, 0xFF)))
        result = caller.call("sd_csd_blocks", [caller.scratch])
        assert (result.a[0], result.a[1]) == ((c_size + 1) * 1024, 1)
    for structure in (2, 3):
        caller.write(caller.scratch, _csd(structure, c_size=(69, 48, 100)))
        assert caller.call("sd_csd_blocks", [caller.scratch]).a[:2] == (0, structure)


DIR_LIMIT = 65536          # entries a FAT directory may hold: 2 MiB of 32-byte entries
DIR_ENTRY = 32
DELETED_ENTRY = b"\xe5ELETED TXT\x20" + bytes(DIR_ENTRY - 12)
SPARE_CLUSTERS = 10_000    # where the long folder's chain continues: free on a card of a few files
EOC = 0x0FFF_FFFF


def _long_folder_card(folder: Path, entries: int) -> Path:
    """A card whose folder /big is `entries` entries long (whole clusters): its own '.' and
    '..', the model's entries (long-name slots and 8.3 entry), then deleted entries to the end
    of its chain, with no end marker. Written on the raw FAT, as a directory chain full of
    deleted entries is what a card builder never makes."""
    card = make_card(folder, {"/scene.ini": f"model = big/model.obj\n{WIREFRAME}".encode(),
                              "/big/model.obj": TRIANGLE})
    part, reserved, fats, fat_sectors, per_cluster = _partition_geometry(card)
    cluster_bytes = 512 * per_cluster
    data_at = part + (reserved + fats * fat_sectors) * 512
    assert entries * DIR_ENTRY % cluster_bytes == 0
    first = cluster_chain(card, "/big")
    assert len(first) == 1
    model = next(e for e in directory_entries(card, "/big") if e.name == "model.obj")
    start = data_at + (first[0] - 2) * cluster_bytes
    with card.open("r+b") as handle:
        handle.seek(start)
        own = handle.read(model.offset + DIR_ENTRY - start)
        content = own + DELETED_ENTRY * (entries - len(own) // DIR_ENTRY)
        chain = first + list(range(SPARE_CLUSTERS, SPARE_CLUSTERS + len(content) // cluster_bytes - 1))
        for n, cluster in enumerate(chain):
            following = chain[n + 1] if n + 1 < len(chain) else EOC
            for copy in range(fats):
                handle.seek(part + (reserved + copy * fat_sectors) * 512 + 4 * cluster)
                assert n == 0 or handle.read(4) == bytes(4), "the spare clusters are not free"
                handle.seek(part + (reserved + copy * fat_sectors) * 512 + 4 * cluster)
                handle.write(following.to_bytes(4, "little"))
            handle.seek(data_at + (cluster - 2) * cluster_bytes)
            handle.write(content[n * cluster_bytes:(n + 1) * cluster_bytes])
    # the raw FAT reader (not the firmware) sees the folder so
    listed = directory_entries(card, "/big")
    assert len(cluster_chain(card, "/big")) * cluster_bytes // DIR_ENTRY == entries
    assert [e.name for e in listed if not e.deleted] == [".", "..", "model.obj"]
    return card


def _run_long_folder(firmware: Path, folder: Path, entries: int):
    card = _long_folder_card(folder, entries)
    out = folder / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "1", "--out", str(out), "--quiet")
    console = (out / "console.log").read_text()
    timed = json.loads((out / "run.json").read_text())["console"]
    return result, console, out, timed


def test_a_folder_of_more_than_65536_entries_is_a_corrupt_directory(firmware, tmp_path):
    """The FAT limit bounds a directory: a chain of deleted entries one cluster longer than
    65,536 entries is error 8, found on the FAT before the entries are read, in milliseconds of
    virtual time (a directory used to be bounded only by the volume: 30,000 clusters of deleted
    entries took more than the 5 s budget). The model's entry comes first: the answer does not
    depend on where the wanted entry lies."""
    result, console, out, timed = _run_long_folder(firmware, tmp_path, DIR_LIMIT + 16)
    assert_error(result, console, out, "BAD_CHAIN", f"corrupt directory: /big has more than {DIR_LIMIT} entries")
    times = {entry["line"].split()[0]: entry["virtual_time_s"] for entry in timed}
    assert times["error"] - times["load"] < 0.05, times      # from scene.ini's load line


def test_a_folder_of_exactly_65536_entries_still_works(firmware, tmp_path):
    result, console, _, _ = _run_long_folder(firmware, tmp_path, DIR_LIMIT)
    assert result.returncode == 0, result.stderr + console
    assert _load_line("big/model.obj", TRIANGLE) in console


def test_missing_file(firmware, loader_card, tmp_path):
    result, console, out = run_scene(firmware, loader_card[0], f"model=sizes/none.obj\n{WIREFRAME}", tmp_path)
    assert_error(result, console, out, "NOT_FOUND", "sizes/none.obj")


@pytest.mark.parametrize("mode", ["textured", "flat"])
def test_only_textured_mode_needs_its_texture(firmware, loader_card, tmp_path, mode):
    """The texture a scene names is read only when the mode draws it: a missing one is error 6
    in textured mode, and in flat mode it is not looked for at all."""
    result, console, out = run_scene(firmware, loader_card[0], f"model=sizes/cluster.obj\ntexture=sizes/none.ppm\n"
                                                                f"mode = {mode}\n", tmp_path)
    if mode == "textured":
        assert_error(result, console, out, "NOT_FOUND", "file not found: sizes/none.ppm")
    else:
        assert result.returncode == 0, result.stderr + console
        assert "texture: not loaded (mode flat)" in console.splitlines()


def test_file_too_large_for_memory(firmware, loader_card, tmp_path):
    """A texture is loaded whole (a model is not: obj.S reads it through a window)."""
    image = tmp_path / "huge.img"
    copy_card(loader_card[0], image)
    huge = tmp_path / "huge.bin"
    huge.write_bytes(bytes(7 * 1024 * 1024))       # more than the 6 MiB of SRAM
    subprocess.run(["mcopy", "-i", f"{image}@@1M", str(huge), "::/huge.ppm"], check=True)
    result, console, out = run_scene(firmware, image, "model = sizes/cluster.obj\ntexture = huge.ppm\n",
                                     tmp_path / "run")
    assert_error(result, console, out, "TOO_LARGE", "huge.ppm")


def _fat_entry_offsets(image: Path, cluster: int) -> list[int]:
    """Byte offsets of a cluster's entry in every FAT of the card's first partition."""
    start, reserved, fats, fat_sectors, _ = _partition_geometry(image)
    return [start + (reserved + n * fat_sectors) * 512 + 4 * cluster for n in range(fats)]


@pytest.mark.parametrize("damage", ["loop", "out-of-range"])
def test_corrupt_chain(firmware, loader_card, tmp_path, damage):
    image = tmp_path / "corrupt.img"
    copy_card(loader_card[0], image)
    chain = cluster_chain(image, "/frag/fragmented.obj")
    target = chain[0] if damage == "loop" else 0x0FFF_FFF0
    with image.open("r+b") as handle:
        for offset in _fat_entry_offsets(image, chain[-1]):
            handle.seek(offset)
            handle.write(target.to_bytes(4, "little"))
    result, console, out = run_scene(firmware, image, f"model=frag/fragmented.obj\n{WIREFRAME}", tmp_path / "run")
    assert_error(result, console, out, "BAD_CHAIN", "chain")


def test_unknown_scene_key_names_its_line(firmware, loader_card, tmp_path):
    result, console, out = run_scene(firmware, loader_card[0], "model=sizes/cluster.obj\n# fine\nshiny = yes\n",
                                     tmp_path)
    assert_error(result, console, out, "BAD_SCENE", "line 3")


def test_the_firmware_reads_a_card_laid_out_as_mkfs_fat_does(firmware, card, tmp_path):
    """The default scene on a card formatted by dosfstools' mkfs.fat (--layout mkfs.fat): the
    same first frame as on the default card."""
    mkfs_card = tmp_path / "mkfs.img"
    make = subprocess.run(["make", "-s", "-n", "build/card.img"], cwd=ROOT, capture_output=True, text=True)
    scene_args = re.findall(r'--scene ("[^"]+"|\S+)', make.stdout) or re.findall(
        r'--scene ("[^"]+"|\S+)', (ROOT / "Makefile").read_text())
    from sdcard_image import build_image
    from sdcard_image.fat32 import LAYOUT_MKFS_FAT
    scene = dict(arg.strip('"').split("=", 1) for arg in scene_args)
    assets = ROOT / "build" / "assets"
    build_image(mkfs_card, [assets / "models", assets / "textures"], scene=scene, layout=LAYOUT_MKFS_FAT)
    out = tmp_path / "out"
    run = run_emulator("run", str(firmware), "--sd", str(mkfs_card), "--frames", "1", "--quiet", "--out", str(out),
                       "--golden", str(ROOT / "tests" / "golden" / "default"))
    assert run.returncode == 0, run.stderr
