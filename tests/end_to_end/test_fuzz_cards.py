"""Fuzzing of corrupt card images: bytes of the MBR, the boot sector (BPB), the FAT, directory
entries and long-name (LFN) slots of a small card are overwritten, or the image is cut short,
and the result goes through `python -m sdcard_image list` and `extract` (Hypothesis, in
process) and, for a small sample, a full firmware boot on the board model with --check-writes.

What must hold for every corrupt card:
- the host tool ends with a documented status (0, 2 for a file the damage hid, 6 corrupt) and
  no traceback, and never modifies the image it reads;
- the firmware shows a frame or reports a documented error (`error <code>` with code 1..12,
  exit 8); it never traps, hangs, touches unmodelled hardware or stores outside its buffers.

FUZZ_EXAMPLES=N runs N examples of each Hypothesis test instead of the default, and
FUZZ_BOOTS=N boots N corrupt cards (nightly use: see docs/guide/running-and-testing.md "Fuzzing").
"""
from __future__ import annotations

import json
import os
import random
import re
import shutil
from dataclasses import dataclass
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from suite import make_card, run_emulator
from k210_common.exit_status import EXIT_CORRUPT_CARD, EXIT_FIRMWARE_ERROR, EXIT_OK, EXIT_USAGE
from k210_common.firmware_errors import firmware_errors
from sdcard_image import cli as sd_cli
from sdcard_image import mbr, rawfat

EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "200"))
BOOTS = int(os.environ.get("FUZZ_BOOTS", "6"))
FUZZ_SETTINGS = settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
                         suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                HealthCheck.too_slow])
USED_BYTES = 4 << 20               # the card's structures and files lie in its first 4 MiB
HOST_STATUSES = {EXIT_OK, EXIT_USAGE, EXIT_CORRUPT_CARD}   # or the damage hid the requested file
FIRMWARE_ERROR_CODES = firmware_errors().codes

MODEL = (b"v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\n"
         b"vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n")
TEXTURE = b"P6 2 2 255\n" + bytes(range(0, 240, 20))
SCENE = (b"model = Models/A long model name.obj\ntexture = Textures/Checker texture.ppm\n"
         b"cull = off\n")


@dataclass(frozen=True)
class Region:
    """Bytes of one on-card structure: where they are in the image file."""

    name: str
    start: int
    length: int


@dataclass(frozen=True)
class Damage:
    """Bytes overwritten at image offsets, or the image cut to `truncate_at` bytes."""

    writes: tuple[tuple[int, bytes], ...] = ()
    truncate_at: int | None = None

    def apply(self, original: Path, target: Path) -> None:
        """Makes `target` the damaged copy of `original`. A target left by an earlier call is
        repaired in place (only its damaged bytes are rewritten): copying a 64 MiB image for
        every example would dominate the run. A copy takes the first USED_BYTES and leaves the
        rest a hole, which reads as the zeros the original holds there (fuzz_card checks that),
        and a cut image gets only the bytes it keeps."""
        size = original.stat().st_size
        if not target.exists() or target.stat().st_size != size:
            keep = size if self.truncate_at is None else self.truncate_at
            with open(original, "rb") as source, open(target, "wb") as image:
                image.write(source.read(min(keep, USED_BYTES)))
                image.truncate(keep)
        with open(target, "r+b") as image:
            for offset, data in self.writes:
                image.seek(offset)
                image.write(data)
            if self.truncate_at is not None:
                image.truncate(self.truncate_at)

    def repair(self, original: Path, target: Path) -> None:
        """Undoes `apply`'s overwrites (a cut image is copied again on the next `apply`)."""
        if self.truncate_at is not None:
            return
        with open(original, "rb") as source, open(target, "r+b") as image:
            for offset, data in self.writes:
                source.seek(offset)
                image.seek(offset)
                image.write(source.read(len(data)))


@pytest.fixture(scope="module")
def fuzz_card(tmp_path_factory) -> tuple[Path, list[Region]]:
    """A small card the firmware boots (a scene whose files sit in folders with long names)
    and the regions of its structures."""
    folder = tmp_path_factory.mktemp("fuzz_card")
    card = make_card(folder, {"/scene.ini": SCENE,
                              "/Models/A long model name.obj": MODEL,
                              "/Textures/Checker texture.ppm": TEXTURE})
    with open(card, "rb") as image:
        image.seek(USED_BYTES)
        assert not any(image.read()), "the card has bytes past USED_BYTES: Damage.apply copies only those"
    return card, card_regions(card)


def card_regions(card: Path) -> list[Region]:
    """The MBR's partition table, the BPB, the FAT entries in use, the directory entries and
    the LFN slots of every folder."""
    with rawfat.Fat32Volume(card) as vol:
        boot, part = vol.boot, vol.partition_offset
        fat_start = part + boot.reserved_sectors * boot.bytes_per_sector
        used = [c for c in range(2, boot.cluster_count + 2) if vol.fat_entry(c)]
        regions = [Region("mbr", mbr.PARTITION_TABLE_OFFSET, mbr.SECTOR_SIZE - mbr.PARTITION_TABLE_OFFSET),
                   Region("bpb", part, 0x5A),
                   Region("bpb-signature", part + 0x1FE, 2),
                   Region("fat", fat_start, (max(used) + 1) * 4)]
        folders = [boot.root_cluster] + [f.entry.first_cluster for f in vol.walk() if f.is_dir]
        lfn = []
        for cluster in folders:
            entries = vol.dir_entries(cluster)
            end = max(e.offset for e in entries) + rawfat.DIR_ENTRY_SIZE
            regions.append(Region(f"directory@{cluster}", vol.cluster_offset(cluster),
                                  end - vol.cluster_offset(cluster)))
            for entry in entries:
                if entry.lfn_slots:
                    lfn.append(Region(f"lfn of {entry.name}",
                                      entry.offset - entry.lfn_slots * rawfat.DIR_ENTRY_SIZE,
                                      entry.lfn_slots * rawfat.DIR_ENTRY_SIZE))
    return regions + lfn


def damage_strategy(regions: list[Region], image_size: int) -> st.SearchStrategy[Damage]:
    """Up to 6 small overwrites inside the structures (random bytes, or the values that
    break parsers most: 0, 0xFF, 0xE5, end-of-chain), or a cut anywhere in the image."""
    interesting = st.sampled_from([b"\x00", b"\xff", b"\xe5", b"\x0f", b"\x10",
                                   b"\xff\xff\xff\x0f", b"\xf7\xff\xff\x0f", b"\x00\x00\x00\x00",
                                   b"\x02\x00\x00\x00"])

    @st.composite
    def write(draw) -> tuple[int, bytes]:
        region = draw(st.sampled_from(regions))
        offset = region.start + draw(st.integers(0, region.length - 1))
        data = draw(st.one_of(interesting, st.binary(min_size=1, max_size=4)))
        return offset, data

    writes = st.lists(write(), min_size=1, max_size=6).map(lambda w: Damage(writes=tuple(w)))
    cuts = st.integers(0, image_size - 1).map(lambda n: Damage(truncate_at=n))
    return st.one_of(writes, writes, writes, cuts)


def random_damage(rng: random.Random, regions: list[Region]) -> Damage:
    """One damage for a firmware boot: 1 to 4 random bytes written in the structures."""
    writes = []
    targets = [r for r in regions if r.length > 2]     # not the 2-byte signature alone
    for _ in range(rng.randint(1, 4)):
        region = rng.choice(targets)
        writes.append((region.start + rng.randrange(region.length),
                       bytes([rng.choice([0x00, 0xFF, 0xE5, rng.randrange(256)])])))
    return Damage(writes=tuple(writes))


def digest(path: Path) -> tuple[int, int, bytes]:
    """What changes when anything writes to the image: its size and modification time, and
    the bytes of the part the small card uses (reading all 64 MiB per call would dominate;
    the bytes themselves, compared, cost less than hashing them)."""
    info = path.stat()
    with open(path, "rb") as image:
        head = image.read(USED_BYTES)
    return info.st_size, info.st_mtime_ns, head


def test_regions_cover_every_structure(fuzz_card):
    card, regions = fuzz_card
    names = {r.name.split("@")[0].split(" of ")[0] for r in regions}
    assert names == {"mbr", "bpb", "bpb-signature", "fat", "directory", "lfn"}
    assert sum(r.name.startswith("directory") for r in regions) == 3     # root and two folders
    assert sum(r.name.startswith("lfn") for r in regions) >= 4           # 2 folders, 2 files
    assert max(r.start + r.length for r in regions) <= USED_BYTES


def _check_host_tool(argv: list[str], image: Path, before: tuple[int, int, bytes], capsys) -> int:
    """Runs a read-only command on the image, whose digest was `before` when it was made."""
    status = sd_cli.main(argv)      # anything but a documented SdImageError would raise here
    err = capsys.readouterr().err
    assert status in HOST_STATUSES, (argv, status, err)
    if status:
        assert err.startswith("python -m sdcard_image ") and "error: " in err, err
    assert digest(image) == before, "a read-only command changed the image"
    return status


def test_list_and_extract_survive_corrupt_cards(fuzz_card, tmp_path_factory, capsys):
    card, regions = fuzz_card
    work = tmp_path_factory.mktemp("fuzz_list")
    size = card.stat().st_size

    @FUZZ_SETTINGS
    @given(damage_strategy(regions, size))
    def check(damage: Damage) -> None:
        image = work / "damaged.img"
        damage.apply(card, image)
        # each command is checked against the damaged image as made: unchanged after the one
        # before, it is what the next one reads
        before = digest(image)
        try:
            _check_host_tool(["list", str(image)], image, before, capsys)
            out = work / "extracted"
            shutil.rmtree(out, ignore_errors=True)
            _check_host_tool(["extract", str(image), "--all", str(out)], image, before, capsys)
            _check_host_tool(["extract", str(image), "/Models/A long model name.obj",
                              str(work / "model.obj"), "--force"], image, before, capsys)
            assert all(p.resolve().is_relative_to(out.resolve()) for p in out.rglob("*")), \
                "extract --all wrote outside its folder"
        finally:
            damage.repair(card, image)

    check()


def boot_cases() -> list[int]:
    return list(range(BOOTS))


@pytest.mark.parametrize("case", boot_cases())
def test_firmware_boots_corrupt_cards_without_trap_hang_or_stray_store(case, firmware, fuzz_card,
                                                                       tmp_path):
    card, regions = fuzz_card
    damage = random_damage(random.Random(1000 + case), regions)
    image = tmp_path / "damaged.img"
    damage.apply(card, image)
    before = digest(image)
    out = tmp_path / "out"
    result = run_emulator("run", str(firmware), "--sd", str(image), "--frames", "1", "--out",
                          str(out), "--quiet", "--check-writes", "--budget", "2")
    where = f"damage {damage}: {result.stderr[-600:]}"
    assert result.returncode in (EXIT_OK, EXIT_FIRMWARE_ERROR), where
    if result.returncode == EXIT_FIRMWARE_ERROR:
        summary = json.loads((out / "run.json").read_text())
        errors = [c["line"] for c in summary["console"] if c["line"].startswith("error ")]
        assert errors, where
        code = int(re.match(r"error (\d+) ", errors[0]).group(1))
        assert code in FIRMWARE_ERROR_CODES, where
    assert digest(image) == before


def _lfn_rewritten(slot: bytes, name: str) -> bytes:
    """An LFN slot (the only one of its entry) whose characters spell `name` instead."""
    units = name.encode("utf-16-le") + b"\x00\x00"
    units += b"\xff" * (26 - len(units))
    raw = bytearray(slot)
    raw[1:11], raw[14:26], raw[28:32] = units[0:10], units[10:22], units[22:26]
    return bytes(raw)


@pytest.mark.parametrize("damage_kind", ["nul in 8.3 name", "lfn '..'", "lfn with '/'"])
def test_names_no_fat_driver_accepts_are_corrupt_not_paths(damage_kind, tmp_path, capsys):
    """Found by the fuzz stage: a NUL in an 8.3 name made `extract --all` end in a traceback,
    and a long name '..' or one holding '/' would have become a path outside the folder."""
    card = make_card(tmp_path / "card", {"/Models/model.obj": MODEL, "/Models/tex.ppm": TEXTURE})
    with rawfat.Fat32Volume(card) as vol:
        folder = next(f.entry for f in vol.walk() if f.is_dir)
        victim = next(e for e in vol.dir_entries(folder.first_cluster) if e.name == "model.obj")
        offset = victim.offset
    with open(card, "r+b") as image:
        if damage_kind == "nul in 8.3 name":
            image.seek(offset + 2)
            image.write(b"\x00")
            expected_name = "MO\x00EL.OBJ"
        else:
            # make_card gives model.obj an LFN slot (lower case): rewrite its characters
            image.seek(offset - rawfat.DIR_ENTRY_SIZE)
            slot = image.read(rawfat.DIR_ENTRY_SIZE)
            expected_name = ".." if damage_kind == "lfn '..'" else "../../evil"
            image.seek(offset - rawfat.DIR_ENTRY_SIZE)
            image.write(_lfn_rewritten(slot, expected_name))
    for argv in (["list", str(card)], ["extract", str(card), "--all", str(tmp_path / "out")]):
        assert sd_cli.main(argv) == EXIT_CORRUPT_CARD
        err = capsys.readouterr().err
        assert (f"/Models: the entry at image byte {offset:#x} has a name FAT does not allow: "
                f"{expected_name!r}") in err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").rglob("*.obj"))
    assert not (tmp_path / "evil").exists()
