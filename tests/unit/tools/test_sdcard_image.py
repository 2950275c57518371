"""Tests of the SD card image tool (`python -m sdcard_image`, `sdcard_image` API).

Images are checked by outside tools (fsck.fat from dosfstools, mdir/mcopy from mtools) and by
a tiny raw FAT32 reader written here, independent of both pyfatfs and the package's own
reader. The images are small (the 64 MiB default is sparse) and shared per session.
"""
from __future__ import annotations

import contextlib
import hashlib
import io
import os
import random
import shutil
import struct
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from k210_common.exit_status import (EXIT_BAD_INPUT, EXIT_CARD_TOO_SMALL, EXIT_CORRUPT_CARD, EXIT_OUTPUT_EXISTS,
                                     EXIT_USAGE)
from sdcard_image import (BadInputError, CorruptImageError, ImageTooSmallError, OutputExistsError,
                          UsageError, build_image, list_image, read_file)
from sdcard_image import cli, fat32, image as image_mod, layouts
from emulator_runs import run_module
from sdcard_image.convert import CardPlan, PlacedFile
from reference.obj import parse_obj
from sdcard_image.objcheck import check_obj
from sdcard_image.ppm import parse_ppm

PART_OFFSET = 2048 * 512
MIB = 1024 * 1024

# --- outside tools ---------------------------------------------------------------------------

_TOOLS = {"fsck.fat": "dosfstools", "mdir": "mtools", "mcopy": "mtools"}


def tool(name: str) -> str:
    """Path of an outside checker; fails (never skips) naming the Debian package to install."""
    found = shutil.which(name) or next((p for d in ("/usr/sbin", "/sbin")
                                        if os.access(p := f"{d}/{name}", os.X_OK)), None)
    if not found:
        pytest.fail(f"{name} is missing: install the Debian package {_TOOLS[name]} "
                    f"(apt-get install {_TOOLS[name]})")
    return found


def mtools_env() -> dict[str, str]:
    # UTF-8 so mtools prints long names as they are; skip no checks: the images must pass them.
    return {**os.environ, "LC_ALL": "C.UTF-8"}


def sparse_copy(src: Path, dst: Path, offset: int = 0) -> None:
    """Copies `src` from `offset`, leaving holes for zero blocks (the images are sparse)."""
    zero = bytes(MIB)
    with open(src, "rb") as fin, open(dst, "wb") as fout:
        fin.seek(offset)
        while block := fin.read(MIB):
            if block == zero[:len(block)]:
                fout.seek(len(block), 1)
            else:
                fout.write(block)
        fout.truncate()


def fsck(img: Path, tmp: Path) -> subprocess.CompletedProcess:
    """fsck.fat -n on a copy of the partition bytes (fsck.fat has no offset option)."""
    part = tmp / f"{img.name}.part"
    sparse_copy(img, part, PART_OFFSET)
    result = subprocess.run([tool("fsck.fat"), "-n", "-v", str(part)], capture_output=True,
                            text=True)
    part.unlink()
    return result


def mdir_paths(img: Path) -> set[str]:
    out = subprocess.run([tool("mdir"), "-i", f"{img}@@1M", "-/", "-b", "::"], check=True,
                         capture_output=True, text=True, env=mtools_env()).stdout
    return {line[2:].rstrip("/") for line in out.splitlines() if line.startswith("::/")}


def mcopy(img: Path, card_path: str, out: Path) -> bytes:
    subprocess.run([tool("mcopy"), "-n", "-i", f"{img}@@1M", f"::{card_path}", str(out)],
                   check=True, capture_output=True, env=mtools_env())
    return out.read_bytes()


def run_process(*args: str | Path) -> subprocess.CompletedProcess:
    """`python -m sdcard_image ARGS` in a child process of its own (forked by the tests' run server,
    emulator_runs.py)."""
    return run_module("sdcard_image", *args, timeout=120)


def run_cli(*args: str | Path) -> subprocess.CompletedProcess:
    """The same command line run in this process (fast); exit status, stdout and stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            status = cli.main([str(a) for a in args])
        except SystemExit as exc:  # argparse's own usage errors
            status = exc.code
    return subprocess.CompletedProcess(list(args), status, out.getvalue(), err.getvalue())


# --- an independent raw FAT32 reader -----------------------------------------------------------

class Raw:
    """Just enough FAT32 to check layouts: BPB, FAT, chains, directory slots, long names."""

    def __init__(self, img: Path) -> None:
        self.img = img
        self.mbr = self._at(0, 512)
        self.bpb = self._at(PART_OFFSET, 512)
        b = self.bpb
        self.bps = struct.unpack_from("<H", b, 0x0B)[0]
        self.spc = b[0x0D]
        self.rsvd = struct.unpack_from("<H", b, 0x0E)[0]
        self.nfats = b[0x10]
        self.fatsz = struct.unpack_from("<I", b, 0x24)[0]
        self.root = struct.unpack_from("<I", b, 0x2C)[0]
        self.total = struct.unpack_from("<I", b, 0x20)[0]
        self.first_data = self.rsvd + self.nfats * self.fatsz
        self.clusters = (self.total - self.first_data) // self.spc
        self.fat_bytes = self._at(PART_OFFSET + self.rsvd * self.bps, self.fatsz * self.bps)

    def _at(self, offset: int, length: int) -> bytes:
        with open(self.img, "rb") as f:
            f.seek(offset)
            return f.read(length)

    def fat(self, n: int) -> int:
        return struct.unpack_from("<I", self.fat_bytes, 4 * n)[0] & 0x0FFFFFFF

    def chain(self, first: int) -> list[int]:
        out = [first]
        while (nxt := self.fat(out[-1])) < 0x0FFFFFF8:
            assert 2 <= nxt < self.clusters + 2 and nxt not in out, f"bad chain at {out[-1]}"
            out.append(nxt)
        return out

    def cluster(self, n: int) -> bytes:
        at = PART_OFFSET + (self.first_data + (n - 2) * self.spc) * self.bps
        return self._at(at, self.spc * self.bps)

    def slots(self, first: int) -> list[bytes]:
        """All 32-byte slots of a directory up to the 0x00 end marker, deleted ones included."""
        raw = b"".join(self.cluster(c) for c in self.chain(first))
        out = []
        for i in range(0, len(raw), 32):
            if raw[i] == 0:
                break
            out.append(raw[i:i + 32])
        return out

    def entries(self, first: int) -> list[tuple[str, bytes]]:
        """(long-or-short name, 8.3 slot) of live entries; LFN joined without checks beyond
        sequence order, which is all this test needs."""
        out, parts = [], []
        for s in self.slots(first):
            if s[0] == 0xE5:
                parts = []
                continue
            if s[11] == 0x0F:
                parts.insert(0, s[1:11] + s[14:26] + s[28:32])
                continue
            if parts:
                name = b"".join(parts).decode("utf-16-le").split("\x00")[0]
            else:
                base, ext = s[:8].decode("ascii").rstrip(), s[8:11].decode("ascii").rstrip()
                name = f"{base}.{ext}" if ext else base
            parts = []
            out.append((name, s))
        return out

    def find(self, path: str) -> bytes:
        cluster, slot = self.root, b""
        for part in [p for p in path.split("/") if p]:
            slot = next(s for n, s in self.entries(cluster) if n.lower() == part.lower())
            cluster = self.first_cluster(slot)
        return slot

    @staticmethod
    def first_cluster(slot: bytes) -> int:
        return (struct.unpack_from("<H", slot, 20)[0] << 16) | struct.unpack_from("<H", slot, 26)[0]

    def read(self, path: str) -> bytes:
        slot = self.find(path)
        size = struct.unpack_from("<I", slot, 28)[0]
        if size == 0:
            return b""
        return b"".join(self.cluster(c) for c in self.chain(self.first_cluster(slot)))[:size]


# --- inputs and shared images ------------------------------------------------------------------

CUBE_OBJ = b"""# a cube
mtllib cube.mtl
o Cube
v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 -1
vn 0 0 1
g sides
usemtl metal
s off
f 1/1/1 2/2/1 3/3/1 4/4/1
f 5/1/2 6/2/2 7/3/2
f -4/-4/-1 -3/-3/-1 -2/-2/-1
f 1//1 2//1 3//1
f 1/1 2/2 3/3
f 1 2 3
"""


def gradient(w: int, h: int, mode: str = "RGB") -> Image.Image:
    img = Image.new(mode, (w, h))
    img.putdata([((x * 37) % 256, (y * 53) % 256, (x * y * 7) % 256, 200)[:len(mode)]
                 for y in range(h) for x in range(w)])
    return img


@pytest.fixture(scope="session")
def inputs(tmp_path_factory) -> Path:
    """Input tree with the file kinds a card holds (sizes around the 512-byte cluster)."""
    src = tmp_path_factory.mktemp("inputs")
    rng = random.Random(1)
    (src / "models").mkdir()
    (src / "models" / "cube.obj").write_bytes(CUBE_OBJ)
    (src / "tex").mkdir()
    gradient(7, 5).save(src / "tex" / "cube.png")
    p6 = b"P6\n# made by hand\n2 2\n255\n" + bytes(range(12))
    (src / "tex" / "ready.ppm").write_bytes(p6)
    (src / "tex" / "plain.ppm").write_bytes(b"P3\n2 1\n255\n255 0 0\n0 255 0\n")
    deep = src / "Long Folder Name" / "Sub Folder"
    deep.mkdir(parents=True)
    (deep / "a file with a rather long name, more than 13 chars.txt").write_bytes(b"deep\n")
    (src / "empty.bin").write_bytes(b"")
    (src / "one.bin").write_bytes(b"\x01")
    (src / "cluster.bin").write_bytes(rng.randbytes(512))
    (src / "big.bin").write_bytes(rng.randbytes(3 * MIB + 7))
    (src / "README.TXT").write_bytes(b"upper-case 8.3 name, no long name entry\n")
    (src / "Ünïcode näme.txt").write_bytes("ü\n".encode())
    return src


def input_paths(src: Path) -> list[Path]:
    return sorted(src.iterdir())


def expected_files(src: Path) -> dict[str, bytes]:
    """Card path -> content the sample card must hold."""
    files = {}
    for p in src.rglob("*"):
        if p.is_file():
            card = "/" + p.relative_to(src).as_posix()
            files[card] = p.read_bytes()
    png = files.pop("/tex/cube.png")
    assert png
    files["/tex/cube.ppm"] = b"P6\n7 5\n255\n" + gradient(7, 5).tobytes()
    files["/scene.ini"] = b"model = models/cube.obj\ntexture = tex/cube.ppm\n"
    return files


@pytest.fixture(scope="session")
def sample(tmp_path_factory, inputs):
    """The sample card, built through the command line as a user would."""
    out = tmp_path_factory.mktemp("sample") / "card.img"
    result = run_process("build", out, *input_paths(inputs), "--scene", "model=models/cube.obj",
                     "--scene", "texture=tex/cube.ppm")
    assert result.returncode == 0, result.stderr
    return out, result


@pytest.fixture(scope="session")
def sample_img(sample) -> Path:
    return sample[0]


@pytest.fixture(scope="session")
def special(tmp_path_factory) -> layouts.SpecialCard:
    return layouts.build_special_card(tmp_path_factory.mktemp("special") / "special.img")


# --- the image format --------------------------------------------------------------------------

def test_mbr_has_one_fat32_lba_partition_at_1mib(sample_img):
    data = sample_img.read_bytes()
    assert len(data) == 64 * MIB
    assert data[510:512] == b"\x55\xAA"
    status, ptype, start, count = (data[0x1BE], data[0x1BE + 4],
                                   *struct.unpack_from("<II", data, 0x1BE + 8))
    assert (status, ptype, start, count) == (0x00, 0x0C, 2048, 64 * MIB // 512 - 2048)
    assert data[0x1CE:0x1FE] == bytes(48), "the other three entries are empty"


def test_partition_is_fat32_with_sane_bpb(sample_img):
    raw = Raw(sample_img)
    assert raw.bpb[510:512] == b"\x55\xAA"
    assert raw.bps == 512 and raw.spc == 1 and raw.nfats == 2
    assert struct.unpack_from("<H", raw.bpb, 0x16)[0] == 0, "FAT16 size field must be 0"
    assert raw.clusters >= 65525, "fewer clusters would make it FAT16 to every driver"
    assert raw.fatsz * 512 // 4 >= raw.clusters + 2
    assert raw.bpb[0x52:0x5A] == b"FAT32   "
    assert struct.unpack_from("<I", raw.bpb, 0x1C)[0] == 2048, "hidden sectors = partition start"
    assert raw.total == 64 * MIB // 512 - 2048
    backup = raw._at(PART_OFFSET + 6 * 512, 512)
    assert backup == raw.bpb


@pytest.mark.parametrize("size_mib", [34, 64, 300])
def test_pyfatfs_geometry_matches_plan_and_fsck(tmp_path, size_mib):
    img = tmp_path / "blank.img"
    fat32.CardWriter.create(img, size_mib).close()  # raises if pyfatfs deviates from the plan
    geo = fat32.image_geometry(size_mib)
    raw = Raw(img)
    assert (raw.spc, raw.fatsz, raw.clusters) == (geo.sectors_per_cluster, geo.fat_sectors,
                                                  geo.cluster_count)
    assert raw.clusters >= 65525
    result = fsck(img, tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr


def test_the_fat_is_read_and_packed_as_pyfatfs_does_it(special, tmp_path):
    """CardFat reads a FAT32 table in one go: the same entries as pyfatfs' own reading (the
    reserved top bits cleared), and the same warning when the two FATs differ; and packs it for
    writing into the bytes pyfatfs' own packing gives."""
    from pyfatfs.PyFat import PyFat
    from pyfatfs.PyFatFS import PyFatFS
    card = shutil.copy(special.image, tmp_path / "card.img")
    twin = shutil.copy(special.image, tmp_path / "twin.img")
    ours = fat32.CardFS(str(card), PART_OFFSET)
    entries = list(ours.fs.fat)
    assert bytes(ours.fs) == PyFat.__bytes__(ours.fs)
    ours.fs.close()
    theirs = PyFatFS(str(twin), offset=PART_OFFSET)
    assert entries == theirs.fs.fat
    assert any(entry not in (0, 0x0FFF_FFFF, 0x0FFF_FFF8) for entry in entries)   # chains, not only ends
    theirs.close()
    raw = Raw(card)
    with open(card, "r+b") as f:       # the first FAT's entry 3 with its reserved bits set
        f.seek(PART_OFFSET + raw.rsvd * 512 + 3 * 4)
        f.write(struct.pack("<I", 0xF000_0000 | entries[3]))
    with pytest.warns(UserWarning, match="One or more FATs differ"):
        ours = fat32.CardFS(str(card), PART_OFFSET)
    assert ours.fs.fat[:8] == entries[:8]
    ours.fs.close()


def test_fsck_finds_no_errors(sample_img, tmp_path):
    result = fsck(sample_img, tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "wrong" not in result.stdout.lower() and "differ" not in result.stdout.lower()


def test_mdir_lists_the_same_files(sample_img, inputs):
    expected = set(expected_files(inputs))
    dirs = {"/models", "/tex", "/Long Folder Name", "/Long Folder Name/Sub Folder"}
    assert mdir_paths(sample_img) == expected | dirs
    listed = {e.path for e in list_image(sample_img)}
    assert listed == expected | dirs


def test_mcopy_extracts_every_file_byte_for_byte(sample_img, inputs, tmp_path):
    for i, (card_path, content) in enumerate(sorted(expected_files(inputs).items())):
        assert mcopy(sample_img, card_path, tmp_path / f"f{i}") == content, card_path


def test_raw_reader_agrees(sample_img, inputs):
    raw = Raw(sample_img)
    for card_path, content in expected_files(inputs).items():
        assert raw.read(card_path) == content, card_path
    # An 8.3 upper-case name needs no long-name slot; a lower-case one gets one.
    root = raw.slots(raw.root)
    names = [s[:11] for s in root]
    readme = names.index(b"README  TXT")
    assert root[readme - 1][11] != 0x0F
    one = names.index(b"ONE     BIN")
    assert root[one - 1][11] == 0x0F


def test_build_report_names_every_file(sample, inputs):
    _, result = sample
    lines = result.stdout.splitlines()
    for card_path, content in expected_files(inputs).items():
        line = next(line for line in lines if line.startswith(card_path + "  "))
        assert f"  {len(content)} bytes" in line
    ppm_line = next(line for line in lines if line.startswith("/tex/cube.ppm"))
    assert "converted from" in ppm_line and "cube.png" in ppm_line and "PNG 7x5" in ppm_line


def test_reading_leaves_the_image_untouched(sample_img, tmp_path):
    before = hashlib.sha256(sample_img.read_bytes()).hexdigest()
    stat = sample_img.stat()
    assert run_cli("list", sample_img).returncode == 0
    assert run_cli("extract", sample_img, "--all", tmp_path / "all").returncode == 0
    read_file(sample_img, "/big.bin")
    assert hashlib.sha256(sample_img.read_bytes()).hexdigest() == before
    assert sample_img.stat().st_mtime_ns == stat.st_mtime_ns


# --- list / extract ----------------------------------------------------------------------------

def test_list_cli_shows_paths_sizes_and_folders(sample_img, inputs):
    result = run_cli("list", sample_img)
    assert result.returncode == 0, result.stderr
    rows = {line.split(None, 1)[1]: line.split(None, 1)[0] for line in result.stdout.splitlines()}
    assert rows["/models/"] == "<DIR>"
    for card_path, content in expected_files(inputs).items():
        assert rows[card_path] == str(len(content))


def test_extract_single_file_all_and_stdout(sample_img, inputs, tmp_path):
    expected = expected_files(inputs)
    out = tmp_path / "cube.obj"
    assert run_cli("extract", sample_img, "/models/cube.obj", out).returncode == 0
    assert out.read_bytes() == CUBE_OBJ
    again = run_cli("extract", sample_img, "/models/cube.obj", out)
    assert again.returncode == EXIT_OUTPUT_EXISTS and "--force" in again.stderr
    assert run_cli("extract", sample_img, "/models/cube.obj", out, "--force").returncode == 0
    # FAT names are case-insensitive: so is the lookup; a folder as OUT keeps the name.
    assert run_cli("extract", sample_img, "/LONG FOLDER NAME/sub folder/"
                   "A FILE WITH A RATHER LONG NAME, MORE THAN 13 CHARS.TXT", tmp_path).returncode == 0
    assert (tmp_path / "A FILE WITH A RATHER LONG NAME, MORE THAN 13 CHARS.TXT").read_bytes() \
        == b"deep\n"
    piped = run_module("sdcard_image", "extract", sample_img, "/one.bin", "-", text=False)
    assert piped.returncode == 0 and piped.stdout == b"\x01"
    dest = tmp_path / "all"
    result = run_cli("extract", sample_img, "--all", dest)
    assert result.returncode == 0, result.stderr
    got = {"/" + p.relative_to(dest).as_posix(): p.read_bytes()
           for p in dest.rglob("*") if p.is_file()}
    assert got == expected
    assert run_cli("extract", sample_img, "--all", dest).returncode == EXIT_OUTPUT_EXISTS
    missing = run_cli("extract", sample_img, "/nope.txt", tmp_path / "x")
    assert missing.returncode == EXIT_USAGE and "nope.txt" in missing.stderr


# --- API -----------------------------------------------------------------------------------------

def test_api_build_list_read(tmp_path, inputs):
    out = tmp_path / "api.img"
    placed = build_image(out, [inputs / "models", inputs / "one.bin"], size_mib=40,
                         scene={"model": "models/cube.obj", "mode": "flat"})
    assert [p.card_path for p in placed] == ["/models/cube.obj", "/one.bin", "/scene.ini"]
    assert placed[0].source == inputs / "models" / "cube.obj" and "OBJ checked" in placed[0].detail
    assert out.stat().st_size == 40 * MIB
    entries = list_image(out)
    assert [(e.path, e.size, e.is_dir) for e in entries] == [
        ("/models", 0, True), ("/models/cube.obj", len(CUBE_OBJ), False),
        ("/one.bin", 1, False), ("/scene.ini", 36, False)]
    assert read_file(out, "/Models/CUBE.OBJ") == CUBE_OBJ
    assert read_file(out, "scene.ini") == b"model = models/cube.obj\nmode = flat\n"
    with pytest.raises(UsageError):
        read_file(out, "/models/missing.obj")
    assert not list(tmp_path.glob(".*tmp"))


@pytest.mark.parametrize("layout", [fat32.LAYOUT_FATGEN103, fat32.LAYOUT_MKFS_FAT])
def test_source_date_epoch_makes_the_same_card_byte_for_byte(tmp_path, inputs, monkeypatch, layout):
    """reproducible-builds.org's SOURCE_DATE_EPOCH: two builds of the same files a few seconds
    apart give the same image (volume ID, disk signature, every entry's times); without it the
    volume ID is random. The times read back as the epoch names (UTC)."""
    if layout == fat32.LAYOUT_MKFS_FAT:
        tool("fsck.fat")                        # dosfstools, which has mkfs.fat
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")          # 2023-11-14 22:13:20 UTC
    digests = []
    for name in ("a.img", "b.img"):
        assert run_cli("build", tmp_path / name, "-q", "--layout", layout, inputs / "models").returncode == 0
        digests.append(hashlib.sha256((tmp_path / name).read_bytes()).hexdigest())
        time.sleep(1.1)
    assert digests[0] == digests[1]
    boot = (tmp_path / "a.img").read_bytes()[PART_OFFSET:PART_OFFSET + 512]
    assert struct.unpack_from("<I", boot, 67)[0] == 1700000000      # BS_VolID
    writer = fat32.CardWriter.open(tmp_path / "a.img")
    try:
        entry = writer.fs.getinfo("/models/cube.obj", namespaces=["details"])
        assert entry.modified.replace(tzinfo=None).timetuple()[:6] == (2023, 11, 14, 22, 13, 20)
    finally:
        writer.fs.close()
    monkeypatch.delenv("SOURCE_DATE_EPOCH")
    for name in ("c.img", "d.img"):
        assert run_cli("build", tmp_path / name, "-q", "--layout", layout, inputs / "models").returncode == 0
    ids = {struct.unpack_from("<I", (tmp_path / n).read_bytes(), PART_OFFSET + 67)[0] for n in ("c.img", "d.img")}
    assert len(ids) == 2


@pytest.mark.parametrize("value", ["soon", "1.5", "100", "9999999999999"])
def test_a_source_date_epoch_that_is_no_fat_time_is_a_usage_error(tmp_path, inputs, monkeypatch, value):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", value)
    result = run_cli("build", tmp_path / "x.img", "-q", inputs / "models")
    assert result.returncode == EXIT_USAGE
    assert "SOURCE_DATE_EPOCH" in result.stderr and "Traceback" not in result.stderr
    assert not (tmp_path / "x.img").exists()


def test_size_grows_in_64_mib_steps_when_content_needs_it():
    plan = CardPlan(files=[(PlacedFile("/huge.bin", 70 * MIB, None), b"")])
    assert image_mod.choose_size(plan, None) == 128
    small = CardPlan(files=[(PlacedFile("/a.bin", 10, None), b"")])
    assert image_mod.choose_size(small, None) == 64
    with pytest.raises(ImageTooSmallError, match="--size 7[0-9]"):
        image_mod.choose_size(plan, 64)


# --- conversions --------------------------------------------------------------------------------

def test_image_conversions_are_exact(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    gradient(6, 4, "RGBA").save(src / "alpha.png")
    gradient(9, 3).save(src / "photo.jpg", quality=90)
    gradient(5, 5).convert("P").save(src / "pal.gif")
    gradient(4, 2).save(src / "win.bmp")
    out = tmp_path / "c.img"
    placed = build_image(out, sorted(src.iterdir()), size_mib=34)
    by_path = {p.card_path: p for p in placed}
    assert set(by_path) == {"/alpha.ppm", "/photo.ppm", "/pal.ppm", "/win.ppm"}
    assert read_file(out, "/alpha.ppm") == b"P6\n6 4\n255\n" + gradient(6, 4).tobytes()
    assert "alpha dropped" in by_path["/alpha.ppm"].converted_from
    jpeg_pixels = Image.open(src / "photo.jpg").convert("RGB").tobytes()
    assert read_file(out, "/photo.ppm") == b"P6\n9 3\n255\n" + jpeg_pixels
    gif_pixels = Image.open(src / "pal.gif").convert("RGB").tobytes()
    assert read_file(out, "/pal.ppm") == b"P6\n5 5\n255\n" + gif_pixels
    assert read_file(out, "/win.ppm") == b"P6\n4 2\n255\n" + gradient(4, 2).tobytes()


def test_texture_size_resizes_converted_images_only(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    gradient(16, 8).save(src / "t.png")
    (src / "keep.ppm").write_bytes(b"P6\n1 1\n255\n\x01\x02\x03")
    out = tmp_path / "c.img"
    result = run_cli("build", out, src / "t.png", src / "keep.ppm", "--texture-size", "4x2",
                     "--size", "34")
    assert result.returncode == 0, result.stderr
    resized = gradient(16, 8).resize((4, 2), Image.Resampling.LANCZOS).tobytes()
    assert read_file(out, "/t.ppm") == b"P6\n4 2\n255\n" + resized
    assert read_file(out, "/keep.ppm") == b"P6\n1 1\n255\n\x01\x02\x03"
    assert "keep.ppm" in result.stderr and "kept at 1x1" in result.stderr
    assert "resized to 4x2" in result.stdout
    bad = run_cli("build", tmp_path / "d.img", src / "t.png", "--texture-size", "4by2")
    assert bad.returncode == EXIT_USAGE and "WxH" in bad.stderr


def test_obj_is_copied_unchanged_and_accepts_all_face_forms():
    stats = check_obj(CUBE_OBJ, "cube.obj")
    assert (stats.vertices, stats.texcoords, stats.normals, stats.triangles) == (8, 4, 2, 7)
    crlf = CUBE_OBJ.replace(b"\n", b"\r\n")
    assert check_obj(crlf).triangles == 7


# The firmware's words (firmware/obj.S through reference/obj.py), at the firmware's line.
BAD_OBJS = [
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", 4, "vertex index out of range"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", 4, "vertex index out of range"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 4, "index 0"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n", 4, "texture coordinate index out of range"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//2 2//2 3//2\n", 4, "normal index out of range"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", 4, "face with fewer than 3 vertices"),
    (b"v 0 0 0\nv 1 0 0.5.1\nv 0 1 0\n", 2, "malformed number"),
    (b"v 0 0 nan\n", 1, "malformed number"),
    (b"v 0 0\n", 1, "v takes 3, 4, 6 or 7 numbers"),
    (b"vt 0 x\n", 1, "malformed number"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a 2 3\n", 4, "malformed face corner"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1// 2 3\n", 4, "malformed face corner"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nf 1 2 3\n", 4, "unknown statement"),
    # issue 14: numbers beyond single precision and line ends the firmware does not take
    (b"v 1e400 0 0\n", 1, "number out of range"),
    (b"v 0 0 0\nv 3.5e38 0 0\n", 2, "number out of range"),
    (b"v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3\r", 1, "malformed number"),
    (b"v 0 0 0\r\r\nv 1 0 0\r\r\nv 0 1 0\r\r\nf 1 2 3\r\r\n", 1, "malformed number"),
    # issue 14: the old check said "the file defines 8 vertexs"
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", 4, "vertex index out of range"),
]


def test_a_model_without_faces_is_refused():
    with pytest.raises(BadInputError, match="no faces"):
        check_obj(b"v 0 0 0\nv 1 0 0\n", "m.obj")


@pytest.mark.parametrize("text,line,message", BAD_OBJS)
def test_obj_errors_name_file_and_line(text, line, message):
    with pytest.raises(BadInputError) as info:
        check_obj(text, "m.obj")
    assert info.value.line == line
    assert str(info.value).startswith(f"m.obj:{line}: {message}")
    assert str(info.value).endswith("(firmware error 10)")
    assert "vertexs" not in str(info.value)


def test_a_model_is_parsed_once_a_process_and_a_refused_one_each_time(monkeypatch):
    """Cards built one after another from the same models (the bench, the tests) parse each model
    once; a refused model is parsed and named again every time."""
    from sdcard_image import objcheck
    parsed = []
    monkeypatch.setattr(objcheck, "parse_obj", lambda data: parsed.append(data) or parse_obj(data))
    monkeypatch.setattr(objcheck, "_PASSED", {})
    model = CUBE_OBJ + b"# this test's own copy\n"
    assert check_obj(model, "a.obj") == check_obj(model, "b.obj")
    assert len(parsed) == 1
    assert check_obj(model + b"\n").triangles == 7 and len(parsed) == 2    # other bytes: parsed
    broken = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"
    for name in ("x.obj", "y.obj"):
        with pytest.raises(BadInputError, match=f"^{name}:4: vertex index out of range"):
            check_obj(broken, name)
    assert len(parsed) == 4


def test_bad_obj_on_command_line_exits_3_with_line(tmp_path):
    obj = tmp_path / "broken.obj"
    obj.write_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 9\n")
    result = run_process("build", tmp_path / "c.img", obj)
    assert result.returncode == EXIT_BAD_INPUT
    assert f"{obj}:5: vertex index out of range" in result.stderr
    assert "Traceback" not in result.stderr
    assert not (tmp_path / "c.img").exists() and not list(tmp_path.glob(".c.img*"))


@pytest.mark.parametrize("data,message", [
    (b"P6\n2 2\n255\n" + bytes(11), "truncated raster"),
    (b"P6\n2 2\n", "truncated header"),
    (b"P6\n2 x\n255\n", "bad header"),
    (b"P5\n2 2\n255\n" + bytes(4), "not a PPM"),
    (b"P3\n2 1\n255\n1 2 3 4 5\n", "truncated raster"),
    (b"P3\n1 1\n100\n1 2 300\n", "sample above maxval"),
    (b"P6\n0 2\n255\n", "width or height 0"),
    # issue 14: a two-byte P6 sample above maxval, and a magic run into the width
    (b"P6\n1 1\n1000\n" + b"\x03\xe8\x03\xe9\x00\x00", "sample above maxval"),
    (b"P68 8 255\n" + bytes(192), "bad header"),
])
def test_bad_ppm_exits_3(tmp_path, data, message):
    ppm = tmp_path / "bad.ppm"
    ppm.write_bytes(data)
    result = run_cli("build", tmp_path / "c.img", ppm)
    assert result.returncode == EXIT_BAD_INPUT, result.stderr
    assert "bad.ppm: " in result.stderr and message in result.stderr
    assert "bad texture: " in result.stderr and "(firmware error 11)" in result.stderr


def test_good_ppms_parse():
    info = parse_ppm(b"P6 # comment\n# another\n3 1 65535\n" + bytes(18))
    assert (info.magic, info.width, info.height, info.maxval) == ("P6", 3, 1, 65535)
    assert parse_ppm(b"P3\n1 1\n15\n1 2 15\n").maxval == 15


def test_undecodable_image_exits_3(tmp_path):
    png = tmp_path / "fake.png"
    png.write_bytes(b"\x89PNG\r\n\x1a\n" + b"garbage" * 10)
    result = run_cli("build", tmp_path / "c.img", png)
    assert result.returncode == EXIT_BAD_INPUT and "fake.png" in result.stderr
    assert "Traceback" not in result.stderr


# --- scene.ini ------------------------------------------------------------------------------------

def test_scene_from_options_and_from_input(tmp_path, sample_img):
    assert read_file(sample_img, "/scene.ini") == \
        b"model = models/cube.obj\ntexture = tex/cube.ppm\n"
    ini = tmp_path / "scene.ini"
    ini.write_bytes(b"# mine\nmodel = a.obj\nmode = wireframe\n")
    (tmp_path / "a.obj").write_bytes(CUBE_OBJ)
    out = tmp_path / "c.img"
    assert run_cli("build", out, ini, tmp_path / "a.obj", "--size", "34").returncode == 0
    assert read_file(out, "/scene.ini") == b"# mine\nmodel = a.obj\nmode = wireframe\n"
    both = run_cli("build", tmp_path / "d.img", ini, "--scene", "model=b.obj")
    assert both.returncode == EXIT_USAGE and "scene.ini" in both.stderr
    ini.write_bytes(b"model = a.obj\nthis line is wrong\n")
    broken = run_cli("build", tmp_path / "e.img", ini)
    assert broken.returncode == EXIT_BAD_INPUT and f"{ini}:2:" in broken.stderr
    bad_opt = run_cli("build", tmp_path / "f.img", "--scene", "novalue")
    assert bad_opt.returncode == EXIT_USAGE and "KEY=VALUE" in bad_opt.stderr


@pytest.mark.parametrize("text,line,message", [
    (b"model = a.obj\nMODEL = b.obj\n", 2, "duplicate key"),
    (b"model =\n", 1, "malformed line (no value)"),
    (b" = a.obj\n", 1, "malformed line (no key)"),
    (b"; a comment the firmware does not know\n", 1, "malformed line (no '=')"),
    (b"model = a\x01b.obj\n", 1, "malformed line (control character)"),
    (b"model = " + b"x" * 256 + b"\n", 1, "malformed line (value too long)"),
    # issue 14: what the card builder used to let through
    (b"mode = flat\nfov = 200\n", 2, "bad value (fov must be between 0 and 180 degrees)"),
    (b"mode = textures\n", 1, "bad value (expected textured, flat or wireframe)"),
    (b"# card\nspeed = 3\n", 2, "unknown key"),
    (b"near = 5\nfar = 1\n", 2, "bad value (far must be greater than near)"),
])
def test_scene_ini_follows_the_firmware_rules(tmp_path, text, line, message):
    ini = tmp_path / "scene.ini"
    ini.write_bytes(text)
    result = run_cli("build", tmp_path / "c.img", ini)
    assert result.returncode == EXIT_BAD_INPUT
    assert f"{ini}:{line}: " in result.stderr and message in result.stderr


def test_scene_ini_accepts_bom_crlf_and_comments_and_refuses_what_the_firmware_refuses(tmp_path):
    ini = tmp_path / "scene.ini"
    ini.write_bytes(b"\xef\xbb\xbf# card\r\nModel = m.obj  # the model\r\n\r\nmode = Flat\r\n"
                    b"background = #203040\r\n")
    obj = tmp_path / "m.obj"
    obj.write_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    result = run_cli("build", tmp_path / "c.img", ini, obj, "--size", "34")
    assert result.returncode == 0, result.stderr
    assert "no such file" not in result.stderr      # flat: no texture needed
    hash_in_value = run_cli("build", tmp_path / "d.img", "--scene", "model=a#b.obj")
    assert hash_in_value.returncode == EXIT_USAGE and "starts a comment" in hash_in_value.stderr
    twice = run_cli("build", tmp_path / "e.img", "--scene", "model=a", "--scene", "Model=b")
    assert twice.returncode == EXIT_USAGE and "twice" in twice.stderr
    missing = run_cli("build", tmp_path / "f.img", "--scene", "texture=t.ppm", "--size", "34")
    assert missing.returncode == EXIT_USAGE and "--scene: texture = t.ppm: no such file on the card" in missing.stderr
    assert ("--scene: model = model.obj (the firmware's default: the scene names no model): no such file on the "
            "card") in missing.stderr


@pytest.mark.parametrize("option,message", [
    ("fov=200", "--scene fov=200: bad value (fov must be between 0 and 180 degrees) (firmware "
                "error 9)"),
    ("mode=textures", "--scene mode=textures: bad value (expected textured, flat or wireframe)"),
    ("speed=3", "--scene speed=3: unknown key"),
    ("axis=0 0 0", "--scene axis=0 0 0: bad value (zero vector)"),
])
def test_scene_options_the_firmware_refuses_are_usage_errors(tmp_path, option, message):
    """Issue 14: these built with exit 0 and stopped the firmware at boot with error 9."""
    result = run_cli("build", tmp_path / "c.img", "--scene", "model=m.obj", "--scene", option)
    assert result.returncode == EXIT_USAGE, result.stderr
    assert message in result.stderr
    assert not (tmp_path / "c.img").exists()


def test_a_scene_naming_a_file_inside_an_input_folder_says_where_it_landed(tmp_path):
    card_folder = tmp_path / "card"
    card_folder.mkdir()
    (card_folder / "x.obj").write_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    result = run_cli("build", tmp_path / "c.img", card_folder, "--scene", "model=x.obj",
                     "--scene", "mode=flat", "--size", "34")
    assert result.returncode == EXIT_USAGE, result.stderr
    assert ("--scene: model = x.obj: no such file on the card (firmware error 6, file not found); the card has "
            "/card/x.obj: a folder given as input lands on the card as a folder") in result.stderr
    assert not (tmp_path / "c.img").exists()


OBJ = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


@pytest.mark.parametrize("options,message", [
    (["--scene", "model=models/gem.obj", "--scene", "mode=flat"],
     "--scene: model = models/gem.obj: no such file on the card (firmware error 6, file not found)"),
    (["--scene", "model=m.obj", "--scene", "texture=textures/t.ppm"],
     "--scene: texture = textures/t.ppm: no such file on the card (firmware error 6, file not found)"),
    (["--scene", "mode=flat"],
     "--scene: model = model.obj (the firmware's default: the scene names no model): no such file on the card"),
])
def test_a_scene_option_naming_a_file_not_on_the_card_is_refused(tmp_path, options, message):
    """Issue 32: the card was built (status 0, with a warning) and the firmware stopped at boot with
    its error 6 (file not found). The key and the file are named; status 2, as for any --scene
    value the firmware would refuse; nothing is written."""
    (tmp_path / "m.obj").write_bytes(OBJ)
    result = run_cli("build", tmp_path / "c.img", tmp_path / "m.obj", *options, "--size", "34")
    assert result.returncode == EXIT_USAGE, result.stderr
    assert message in result.stderr
    assert not (tmp_path / "c.img").exists()


def test_an_input_scene_ini_naming_a_file_not_on_the_card_is_refused(tmp_path):
    """Issue 32, as above for a scene.ini given as input: bad input (status 6), naming the file,
    the line and key of each missing file; an existing image is left as it was."""
    (tmp_path / "m.obj").write_bytes(OBJ)
    ini = tmp_path / "scene.ini"
    ini.write_text("# mine\nmodel = models/m.obj\nmode = textured\ntexture = t.ppm\n")
    out = tmp_path / "c.img"
    out.write_bytes(b"precious")
    result = run_cli("build", out, ini, tmp_path / "m.obj", "--force", "--size", "34")
    assert result.returncode == EXIT_BAD_INPUT, result.stderr
    assert f"{ini}:2: model = models/m.obj: no such file on the card (firmware error 6, file not found)" \
        in result.stderr
    assert f"{ini}:4: texture = t.ppm: no such file on the card" in result.stderr
    assert out.read_bytes() == b"precious"
    with pytest.raises(BadInputError, match="model = models/m.obj: no such file on the card"):
        build_image(tmp_path / "d.img", [ini, tmp_path / "m.obj"])
    ini.write_text("model = m.obj\nmode = flat\ntexture = t.ppm\n")      # flat: reads no texture
    assert run_cli("build", out, ini, tmp_path / "m.obj", "--force", "--size", "34").returncode == 0


# --- failures -------------------------------------------------------------------------------------

def test_refuses_to_overwrite_without_force(tmp_path, inputs):
    out = tmp_path / "c.img"
    out.write_bytes(b"precious")
    result = run_cli("build", out, inputs / "one.bin")
    assert result.returncode == EXIT_OUTPUT_EXISTS and "--force" in result.stderr
    assert out.read_bytes() == b"precious"
    result = run_cli("build", out, inputs / "one.bin", "--force", "--size", "34")
    assert result.returncode == 0, result.stderr
    assert read_file(out, "/one.bin") == b"\x01"
    with pytest.raises(OutputExistsError):
        build_image(out, [inputs / "one.bin"])


@pytest.mark.parametrize("exc", [RuntimeError("disk on fire"), KeyboardInterrupt()])
def test_temp_file_removed_when_build_fails(tmp_path, inputs, monkeypatch, exc):
    def explode(writer, plan):
        assert list(tmp_path.glob(".c.img.*.tmp")), "building happens in a temp file"
        raise exc
    monkeypatch.setattr(image_mod, "write_plan", explode)
    with pytest.raises(type(exc)):
        build_image(tmp_path / "c.img", [inputs / "one.bin"], size_mib=34)
    assert list(tmp_path.iterdir()) == []


def test_too_small_exits_5(tmp_path, inputs):
    result = run_cli("build", tmp_path / "c.img", inputs / "big.bin", "--size", "34")
    assert result.returncode == 0, result.stderr  # 3 MiB fit in 34 MiB
    blob = tmp_path / "blob.bin"
    with open(blob, "wb") as f:
        f.truncate(33 * MIB)
    result = run_cli("build", tmp_path / "d.img", blob, "--size", "34")
    assert result.returncode == EXIT_CARD_TOO_SMALL and "--size" in result.stderr
    assert not (tmp_path / "d.img").exists() and not list(tmp_path.glob(".d.img*"))
    assert run_cli("build", tmp_path / "e.img", blob, "--size", "20").returncode == EXIT_USAGE


def test_usage_errors_exit_2(tmp_path, inputs):
    assert run_process().returncode == EXIT_USAGE
    assert run_cli("build").returncode == EXIT_USAGE
    assert run_cli("frobnicate").returncode == EXIT_USAGE
    assert run_cli("build", tmp_path / "c.img", tmp_path / "missing.obj").returncode == EXIT_USAGE
    assert run_cli("build", tmp_path / "nofolder" / "c.img", inputs / "one.bin").returncode == EXIT_USAGE
    assert run_cli("extract", tmp_path / "x.img").returncode == EXIT_USAGE
    assert run_cli("list", tmp_path / "missing.img").returncode == EXIT_USAGE


def test_names_differing_only_in_case_are_refused_in_one_folder(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    triangle = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    (tmp_path / "a" / "Cube.obj").write_bytes(triangle)
    (tmp_path / "b" / "cube.OBJ").write_bytes(triangle)
    result = run_cli("build", tmp_path / "c.img", tmp_path / "a" / "Cube.obj",
                     tmp_path / "b" / "cube.OBJ")
    assert result.returncode == EXIT_USAGE and "case" in result.stderr
    # A converted image and a PPM of the same base name collide too.
    gradient(2, 2).save(tmp_path / "a" / "cube.png")
    (tmp_path / "a" / "cube.ppm").write_bytes(b"P6\n1 1\n255\n\0\0\0")
    result = run_cli("build", tmp_path / "d.img", tmp_path / "a")
    assert result.returncode == EXIT_USAGE and "/a/cube.ppm" in result.stderr


# --- corrupt images -------------------------------------------------------------------------------

@pytest.fixture(scope="session")
def small_img(tmp_path_factory, inputs) -> Path:
    """A minimal card (34 MiB) to damage in many ways."""
    folder = tmp_path_factory.mktemp("small")
    extra = folder / "big.bin"
    extra.write_bytes(bytes(range(256)) * 32)
    out = folder / "small.img"
    build_image(out, [inputs / "cluster.bin", inputs / "models", extra], size_mib=34)
    return out


def _corrupt(small_img: Path, tmp_path: Path, how: str) -> Path:
    data = bytearray(small_img.read_bytes())
    raw = Raw(small_img)
    if how == "empty":
        data = bytearray()
    elif how == "no MBR signature":
        data[510:512] = b"\0\0"
    elif how == "no FAT32 partition":
        data[0x1BE + 4] = 0x83
    elif how == "truncated":
        data = data[:20 * MIB]
    elif how == "bad BPB":
        struct.pack_into("<H", data, PART_OFFSET + 0x0B, 3)
    elif how == "FAT16 BPB":
        struct.pack_into("<H", data, PART_OFFSET + 0x16, 200)
    elif how == "bare volume":
        data = data[PART_OFFSET:]
    elif how == "cluster loop":
        first = Raw.first_cluster(raw.find("/big.bin"))
        fat_at = PART_OFFSET + raw.rsvd * 512
        struct.pack_into("<I", data, fat_at + 4 * (first + 3), first + 1)
    img = tmp_path / f"{how.replace(' ', '_')}.img"
    img.write_bytes(bytes(data))
    return img


@pytest.mark.parametrize("how,message", [
    ("empty", "too short to hold an MBR"),
    ("no MBR signature", "no MBR signature"),
    ("no FAT32 partition", "no FAT32 partition"),
    ("truncated", "truncated image"),
    ("bad BPB", "bytes per sector"),
    ("FAT16 BPB", "not FAT32"),
    ("bare volume", "bare volume without a partition table"),
    ("cluster loop", "loops back"),
])
def test_corrupt_images_exit_corrupt_card_with_reason(small_img, tmp_path, how, message):
    img = _corrupt(small_img, tmp_path, how)
    for args in (("list", img), ("extract", img, "/big.bin", tmp_path / "out.bin")):
        result = run_cli(*args)
        assert result.returncode == EXIT_CORRUPT_CARD, (args, result.stdout, result.stderr)
        assert message in result.stderr and "Traceback" not in result.stderr
    with pytest.raises(CorruptImageError):
        list_image(img)
    if how == "cluster loop":
        result = run_process("list", img)
        assert result.returncode == EXIT_CORRUPT_CARD and "Traceback" not in result.stderr


# --- special layouts ------------------------------------------------------------------------------

def test_special_card_passes_fsck_and_mtools(special, tmp_path):
    result = fsck(special.image, tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    files = special.all_files()
    listed = mdir_paths(special.image)
    assert set(files) <= listed
    for deleted in special.deleted_paths:
        assert deleted not in listed
    for i, (card_path, content) in enumerate(sorted(files.items())):
        assert mcopy(special.image, card_path, tmp_path / f"m{i}") == content, card_path


def test_fragmented_file_has_a_gapped_chain(special):
    raw = Raw(special.image)
    slot = raw.find(special.fragmented_path)
    chain = raw.chain(Raw.first_cluster(slot))
    assert chain == special.fragmented_chain
    gaps = [(a, b) for a, b in zip(chain, chain[1:]) if b != a + 1]
    assert len(gaps) >= 2
    assert raw.read(special.fragmented_path) == special.fragmented_data
    assert len(chain) == -(-len(special.fragmented_data) // 512)
    assert layouts.is_fragmented(layouts.cluster_chain(special.image, special.fragmented_path))


def test_deleted_entries_stay_as_e5_slots_before_live_ones(special):
    raw = Raw(special.image)
    folder = Raw.first_cluster(raw.find(special.deleted_dir))
    slots = raw.slots(folder)
    deleted = [i for i, s in enumerate(slots) if s[0] == 0xE5]
    deleted_short = [i for i in deleted if slots[i][11] != 0x0F]
    deleted_lfn = [i for i in deleted if slots[i][11] == 0x0F]
    assert len(deleted_short) == len(special.deleted_paths)
    assert deleted_lfn, "long names of deleted files stay as deleted LFN slots too"
    live = [i for i, s in enumerate(slots) if s[0] != 0xE5]
    assert max(live) > min(deleted), "live entries follow deleted ones"
    # The deleted files' clusters were freed: none is still owned through a deleted slot in
    # a way fsck would flag (fsck passes on this card), and later files may reuse them.
    names = {n for n, _ in raw.entries(folder)}
    assert names == {".", ".."} | {p.rsplit("/", 1)[1] for p in special.survivors}
    for path, content in special.survivors.items():
        assert raw.read(path) == content


def test_big_directory_spans_several_clusters(special):
    raw = Raw(special.image)
    chain = raw.chain(Raw.first_cluster(raw.find(special.big_dir)))
    assert len(chain) >= 3 and chain == special.big_dir_clusters
    names = [n for n, _ in raw.entries(chain[0])]
    assert len(names) == len(special.big_dir_files) + 2
    for path, content in special.big_dir_files.items():
        assert raw.read(path) == content
    assert len(list_image(special.image)) >= len(special.big_dir_files)


def test_case_variants_live_in_separate_folders(special):
    assert len(special.case_variants) == 3
    raw = Raw(special.image)
    parents = {path.rsplit("/", 1)[0] for path in special.case_variants}
    assert len(parents) == 3
    for path, content in special.case_variants.items():
        folder_entries = raw.entries(Raw.first_cluster(raw.find(path.rsplit("/", 1)[0])))
        assert [n for n, _ in folder_entries if n not in (".", "..")] == [path.rsplit("/", 1)[1]]
        assert read_file(special.image, path) == content
    assert len(set(special.case_variants.values())) == 3


def test_writer_refuses_case_twin_in_one_folder(tmp_path):
    with fat32.CardWriter.create(tmp_path / "c.img", 34) as writer:
        writer.write("/Cube.obj", b"a")
        with pytest.raises(UsageError, match="case"):
            writer.write("/cube.obj", b"b")


def test_the_fats_are_written_at_close_or_flush_and_a_raising_writer_leaves_a_sound_card(tmp_path, monkeypatch):
    """pyfatfs would write both FATs whole at every file it creates, writes or closes (1 MiB each
    time on this card): CardFat writes them once, at close, or when a reader of the raw image
    asks (CardWriter.flush). Whatever was written before a raise is on the card, FAT and all."""
    writes = []
    real_flush = fat32.PyFat.flush_fat
    monkeypatch.setattr(fat32.PyFat, "flush_fat", lambda fat: (writes.append(1), real_flush(fat))[1])
    card = tmp_path / "c.img"
    files = {f"/file{i}.bin": bytes([i]) * (700 * i + 1) for i in range(1, 6)}
    with fat32.CardWriter.create(card, 64) as writer:
        writes.clear()                                  # (the blank card's own format)
        for path, data in list(files.items())[:3]:
            writer.write(path, data)
        assert writes == []
        writer.flush()
        assert len(writes) == 1
        assert read_file(card, "/file3.bin") == files["/file3.bin"]    # the raw image is up to date
        writer.flush()
        assert len(writes) == 1                         # nothing changed since
        for path, data in list(files.items())[3:]:
            writer.write(path, data)
    assert len(writes) == 2
    assert {path: read_file(card, path) for path in files} == files
    assert fsck(card, tmp_path).returncode == 0

    broken = tmp_path / "broken.img"
    with pytest.raises(RuntimeError, match="in the middle"):
        with fat32.CardWriter.create(broken, 64) as writer:
            writer.write("/kept.bin", b"k" * 3000)
            raise RuntimeError("in the middle")
    assert read_file(broken, "/kept.bin") == b"k" * 3000
    assert fsck(broken, tmp_path).returncode == 0


def test_exif_orientation_and_16_bit_grey(tmp_path):
    photo = Image.new("RGB", (6, 3), (10, 20, 30))
    exif = photo.getexif()
    exif[0x0112] = 6  # stored sideways: viewers turn it 90 degrees
    photo.save(tmp_path / "side.jpg", exif=exif)
    grey = np.array([[0, 65535], [32768, 256]], dtype=np.uint16)
    Image.fromarray(grey).save(tmp_path / "deep.png")
    out = tmp_path / "c.img"
    placed = build_image(out, [tmp_path / "side.jpg", tmp_path / "deep.png"], size_mib=34)
    assert read_file(out, "/side.ppm").startswith(b"P6\n3 6\n255\n")
    assert "upright" in placed[1].converted_from
    # 16-bit samples are scaled to 8 bits, not clipped at 255.
    assert read_file(out, "/deep.ppm") == b"P6\n2 2\n255\n" + bytes(
        v for s in (0, 255, 128, 1) for v in (s, s, s))


# --- the mkfs.fat layout (--layout mkfs.fat) -----------------------------------------------------

FSINFO_COUNTS = range(488, 496)        # free count and next-free hint: they follow the files written


def _mkfs_fat_reference(path: Path, size_mib: int, volume_id: bytes) -> bytes:
    """What dosfstools' mkfs.fat -F 32 writes for the card's partition (its first 8 sectors)."""
    tool("fsck.fat")      # dosfstools is present
    part_sectors = size_mib * 2048 - 2048
    with open(path, "wb") as f:
        f.truncate(size_mib * MIB)
    subprocess.run([fat32.mkfs_fat_command(), "-F", "32", "--offset", "2048", "-h", "2048", "-n", "K210SD",
                    "-i", volume_id[::-1].hex(), str(path), str(part_sectors // 2)], check=True, capture_output=True)
    return _partition_head(path)


def _partition_head(image: Path) -> bytes:
    """The first 8 sectors of the card's partition (read alone: the image is up to 300 MiB)."""
    with image.open("rb") as handle:
        handle.seek(PART_OFFSET)
        return handle.read(8 * 512)


@pytest.mark.parametrize("size_mib, bytes_per_cluster", [(64, 512), (300, 4096)])
def test_a_card_laid_out_as_mkfs_fat_does(tmp_path, size_mib, bytes_per_cluster):
    src = tmp_path / "in"
    src.mkdir()
    (src / "cube.obj").write_bytes(CUBE_OBJ)
    out = tmp_path / "card.img"
    build_image(out, [src / "cube.obj"], size_mib=size_mib, layout=fat32.LAYOUT_MKFS_FAT)
    ours = _partition_head(out)
    reference = _mkfs_fat_reference(tmp_path / "ref.img", size_mib, ours[67:71])
    for sector in (0, 1, 6, 7):       # boot sector, FSInfo and their backups
        theirs, mine = (bytearray(x[sector * 512:(sector + 1) * 512]) for x in (reference, ours))
        if sector in (1, 7):
            for i in FSINFO_COUNTS:
                theirs[i] = mine[i] = 0
        assert mine == theirs, f"sector {sector} differs from mkfs.fat's"
    assert fat32.image_geometry(size_mib, fat32.LAYOUT_MKFS_FAT).bytes_per_cluster == bytes_per_cluster
    assert read_file(out, "cube.obj") == CUBE_OBJ
    # and the default layout is not mkfs.fat's (else the option would be pointless)
    assert fat32.image_geometry(64).fat_sectors != fat32.image_geometry(64, fat32.LAYOUT_MKFS_FAT).fat_sectors


def test_an_unknown_layout_is_a_usage_error(tmp_path):
    result = run_module("sdcard_image", "build", tmp_path / "c.img", "--layout", "exfat", "--scene", "model=x.obj")
    assert result.returncode == EXIT_USAGE and "invalid choice: 'exfat'" in result.stderr


def test_a_partition_entry_of_no_length_is_read_as_the_firmware_boots_it(card, firmware, tmp_path):
    """An MBR entry of type 0x0C whose sector count is 0: FatFs (the SDK's and MaixPy's FAT
    driver) and the firmware take its type and start and let the BPB give the volume's size; the
    card tool used to call it empty and refuse the card (issue 35). Both sides agree now."""
    from suite import run_emulator
    patched = tmp_path / "card.img"
    data = bytearray(card.read_bytes())
    entry = 446                                            # the first partition entry
    assert data[entry + 4] in (0x0B, 0x0C) and int.from_bytes(data[entry + 12:entry + 16], "little")
    data[entry + 12:entry + 16] = bytes(4)
    patched.write_bytes(bytes(data))
    listed = run_process("list", str(patched))
    assert listed.returncode == 0, listed.stderr
    assert "scene.ini" in listed.stdout
    run = run_emulator("run", str(firmware), "--sd", str(patched), "--frames", "1", "--out", str(tmp_path / "out"),
                       "--quiet")
    assert run.returncode == 0, run.stderr
