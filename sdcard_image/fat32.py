"""Formatting and filling the FAT32 partition of a card image with pyfatfs.

pyfatfs 1.1.0 does the formatting and the cluster/directory bookkeeping. Where it falls short
of a volume that fsck.fat, mtools and a strict firmware reader accept, this module fills in:

* its mkfs leaves heads, sectors per track and hidden sectors at 0 (mtools refuses such a
  volume): set before closing, so pyfatfs writes them into the boot sector and its backup;
* it never updates the FSInfo free-cluster count (fsck.fat reports it wrong): rewritten
  after the last write, from the FAT;
* its in-memory FAT has entries past the last real cluster (the FAT is sized in whole
  sectors), and its allocator would hand those out and write past the partition: the list
  is cut to the real cluster count, so a full card raises ENOSPC instead;
* its file creation cannot give a long name to an upper-case 8.3-length name with spaces
  ("A B.TXT"), makes short names without a numeric tail that can collide with a later
  8.3 name, and looks names up case-sensitively, so "Cube.obj" and "cube.obj" could both be
  created in one folder. `CardFS` replaces creation with Windows-style short names and a
  case-insensitive duplicate check.

A card is reproducible when asked: its volume ID (and the MBR's disk signature) and every entry's
times are otherwise random and the current time. With SOURCE_DATE_EPOCH set (the convention of
reproducible-builds.org: seconds since 1970, UTC) or given `CardStamp` explicitly, the same files
make the same image byte for byte (`card_stamp`). Firmware that reads a table indexed by a card's
bytes (a CRC) meets the card's caches differently on different bytes, so cycle counts are only
repeatable on a repeatable card.

pyfatfs also reads the FAT one entry at a time through struct (0.15 s for the default card,
on every open) and packs it with a struct format of one letter per entry (at every file created
or closed); `CardFat` reads a FAT32 table in one go, to the same list, and packs it in one go, to
the same bytes.
"""
from __future__ import annotations

import array
import datetime
import errno
import functools
import math
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import warnings
from copy import copy
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from fs.base import FS
from fs.errors import DirectoryExists, FileExists, ResourceNotFound
from fs.path import normpath, split
from fs.subfs import SubFS
from pyfatfs import FAT_LFN_ENCODING
from pyfatfs.EightDotThree import EightDotThree
from pyfatfs.FATDirectoryEntry import FATDirectoryEntry, FATLongDirectoryEntry
from pyfatfs.PyFat import PyFat
from pyfatfs.PyFatFS import PyFatFS
from pyfatfs._exceptions import PyFATException

from . import mbr, rawfat
from .errors import ImageTooSmallError, UsageError

VOLUME_LABEL = "K210SD"
#: How the partition is laid out: as pyfatfs formats it (Microsoft's fatgen103 table; the
#: default), or exactly as dosfstools' `mkfs.fat -F 32` formats a card's first partition on
#: Linux (it runs mkfs.fat), for firmware whose FAT code expects that.
LAYOUT_FATGEN103 = "fatgen103"
LAYOUT_MKFS_FAT = "mkfs.fat"
LAYOUTS = (LAYOUT_FATGEN103, LAYOUT_MKFS_FAT)
_SBIN = ("/usr/sbin", "/sbin")
RESERVED_SECTORS = 32  # what pyfatfs (and mkfs.fat) reserve on FAT32
NUM_FATS = 2
#: pyfatfs refuses FAT32 below this many sectors (its "up to 32.5 MB: error" row).
PYFATFS_MIN_FAT32_SECTORS = 66601
#: Largest partition pyfatfs can format (its table ends at 32 GB with 16 KiB clusters).
PYFATFS_MAX_FAT32_SECTORS = 67108864
#: pyfatfs 1.1.0's choice of sectors per cluster by partition size in sectors (mkfs), the
#: table from Microsoft's fatgen103. Mirrored here so sizes can be planned before formatting.
_SECTORS_PER_CLUSTER = ((532480, 1), (16777216, 8), (33554432, 16), (67108864, 32))
#: pyfatfs short names are made from the ibm437 code page; keep to ASCII so every reader
#: (whatever its code page) sees the same name.
_SFN_CHARS = set("ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789$%'-_@~`!(){}^#&")
_INVALID_LFN_CHARS = set('"*/:<>?\\|') | {chr(c) for c in range(0x20)} | {"\x7f"}
MAX_LFN_UNITS = 255


@dataclass(frozen=True)
class Geometry:
    """The layout pyfatfs gives a FAT32 partition of a given size."""

    partition_sectors: int
    sectors_per_cluster: int
    fat_sectors: int
    reserved_sectors: int = RESERVED_SECTORS
    num_fats: int = NUM_FATS
    bytes_per_sector: int = mbr.SECTOR_SIZE

    @property
    def bytes_per_cluster(self) -> int:
        return self.sectors_per_cluster * self.bytes_per_sector

    @property
    def first_data_sector(self) -> int:
        return self.reserved_sectors + self.num_fats * self.fat_sectors

    @property
    def cluster_count(self) -> int:
        return (self.partition_sectors - self.first_data_sector) // self.sectors_per_cluster


def plan_geometry(partition_sectors: int) -> Geometry:
    """The geometry pyfatfs 1.1.0's mkfs produces for a partition of this many 512-byte
    sectors (same arithmetic, including its FAT-size formula)."""
    if partition_sectors < PYFATFS_MIN_FAT32_SECTORS:
        raise ValueError(f"FAT32 needs at least {PYFATFS_MIN_FAT32_SECTORS} sectors")
    for limit, spc in _SECTORS_PER_CLUSTER:
        if partition_sectors <= limit:
            break
    else:
        raise ValueError(f"pyfatfs formats at most {PYFATFS_MAX_FAT32_SECTORS} sectors")
    size = partition_sectors * mbr.SECTOR_SIZE
    # pyfatfs feeds the size in bytes into fatgen103's sector formula, then divides by the
    # sector size; reproduced as is so the prediction matches what it writes.
    tmp1 = size - RESERVED_SECTORS
    tmp2 = ((256 * spc) + NUM_FATS) // 2
    fat_sectors = math.ceil((tmp1 + tmp2 - 1) // tmp2 / mbr.SECTOR_SIZE)
    return Geometry(partition_sectors=partition_sectors, sectors_per_cluster=spc,
                    fat_sectors=fat_sectors)


def image_geometry(size_mib: int, layout: str = LAYOUT_FATGEN103) -> Geometry:
    """Geometry of the partition of an image of `size_mib` MiB (partition at LBA 2048)."""
    total = size_mib * 1024 * 1024 // mbr.SECTOR_SIZE
    if layout == LAYOUT_MKFS_FAT:
        return mkfs_fat_geometry(total - mbr.PARTITION_START_LBA)
    return plan_geometry(total - mbr.PARTITION_START_LBA)


def mkfs_fat_command() -> str:
    """The mkfs.fat program (dosfstools; the bootstrap installs it). Raises UsageError."""
    found = shutil.which("mkfs.fat") or shutil.which("mkfs.fat", path=os.pathsep.join(_SBIN))
    if found is None:
        raise UsageError("--layout mkfs.fat needs dosfstools' mkfs.fat (apt-get install dosfstools)")
    return found


def mkfs_fat_format(image: Path, partition: mbr.PartitionEntry, label: str, volume_id: int) -> None:
    """Formats the partition with `mkfs.fat -F 32` and its defaults, as on a card's first
    partition under Linux: hidden sectors = the partition's start (what mkfs.fat reads from a
    partition device; an image file needs -h to say it), the rest mkfs.fat's own choice
    (cluster size, reserved sectors aligned to the cluster size, FAT size, geometry fields)."""
    kib = partition.sector_count * mbr.SECTOR_SIZE // 1024
    command = [mkfs_fat_command(), "-F", "32", "--offset", str(partition.start_lba), "-h", str(partition.start_lba),
               "-n", label, "-i", f"{volume_id:08x}", str(image), str(kib)]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        why = (result.stderr or result.stdout).strip().splitlines()
        raise UsageError(f"mkfs.fat could not format a {partition.sector_count}-sector partition: "
                         f"{why[-1] if why else f'exit {result.returncode}'}")


@functools.lru_cache(maxsize=None)
def mkfs_fat_geometry(partition_sectors: int) -> Geometry:
    """The geometry mkfs.fat gives a partition of this many sectors: measured, by formatting
    a sparse scratch file and reading its boot sector (mkfs.fat's arithmetic is its own)."""
    with tempfile.TemporaryDirectory() as scratch:
        image = Path(scratch) / "geometry.img"
        part = mbr.PartitionEntry(type=mbr.TYPE_FAT32_LBA, start_lba=mbr.PARTITION_START_LBA,
                                  sector_count=partition_sectors)
        with open(image, "wb") as f:
            f.truncate((mbr.PARTITION_START_LBA + partition_sectors) * mbr.SECTOR_SIZE)
        mkfs_fat_format(image, part, VOLUME_LABEL, 0)
        with open(image, "rb") as f:
            f.seek(mbr.PARTITION_START_LBA * mbr.SECTOR_SIZE)
            boot = f.read(mbr.SECTOR_SIZE)
    spc, reserved, fats = boot[13], struct.unpack_from("<H", boot, 14)[0], boot[16]
    total, fat_sectors = struct.unpack_from("<I", boot, 32)[0], struct.unpack_from("<I", boot, 36)[0]
    return Geometry(partition_sectors=total, sectors_per_cluster=spc, fat_sectors=fat_sectors,
                    reserved_sectors=reserved, num_fats=fats)


def min_image_mib() -> int:
    """Smallest whole-MiB image whose partition pyfatfs formats as FAT32."""
    sectors = mbr.PARTITION_START_LBA + PYFATFS_MIN_FAT32_SECTORS
    return math.ceil(sectors * mbr.SECTOR_SIZE / (1024 * 1024))


def max_image_mib() -> int:
    sectors = mbr.PARTITION_START_LBA + PYFATFS_MAX_FAT32_SECTORS
    return sectors * mbr.SECTOR_SIZE // (1024 * 1024)


# --- names ---------------------------------------------------------------------------------

def check_card_name(name: str) -> str | None:
    """Why `name` cannot be a FAT long name, or None if it can."""
    if name in ("", ".", ".."):
        return f"{name!r} is not a usable name"
    bad = sorted({c for c in name if c in _INVALID_LFN_CHARS})
    if bad:
        shown = ", ".join(repr(c) for c in bad)
        return f"{name!r} contains characters FAT does not allow in names: {shown}"
    try:
        units = len(name.encode("utf-16-le")) // 2
    except UnicodeEncodeError:
        return f"{name!r} is not valid Unicode (file name bytes in an unknown encoding?)"
    if name[-1] in " .":
        return f"{name!r} ends with a space or a dot, which FAT drivers strip"
    if units > MAX_LFN_UNITS:
        return f"{name!r} is longer than FAT's {MAX_LFN_UNITS} characters"
    return None


def fits_8dot3(name: str) -> bool:
    """Whether the name, upper-cased, is a valid 8.3 name (then it is its own short name)."""
    upper = name.upper()
    base, dot, ext = upper.partition(".")
    if not 1 <= len(base) <= 8 or len(ext) > 3 or "." in ext or (dot and not ext):
        return False
    return all(c in _SFN_CHARS for c in base + ext)


def _sfn_bytes(base: str, ext: str) -> bytes:
    return (base.ljust(8) + ext.ljust(3)).encode("ascii")


def short_name_basis(name: str) -> tuple[str, str, bool]:
    """Upper-cased 8.3 basis of a long name, Windows style: spaces and leading dots dropped,
    the last dot separates the extension, other characters outside the 8.3 set become '_'.
    Returns (base, ext, lossy); lossy means a "~N" tail is needed."""
    upper = name.upper()
    stripped = upper.replace(" ", "").lstrip(".")
    lossy = stripped != upper
    if "." in stripped:
        base, ext = stripped.rsplit(".", 1)
        if "." in base:
            lossy = True
            base = base.replace(".", "")
    else:
        base, ext = stripped, ""
    mapped_base = "".join(c if c in _SFN_CHARS else "_" for c in base)
    mapped_ext = "".join(c if c in _SFN_CHARS else "_" for c in ext)
    lossy |= mapped_base != base or mapped_ext != ext or len(base) > 8 or len(ext) > 3
    return mapped_base[:8] or "_", mapped_ext[:3], lossy


def make_short_name(name: str, taken: set[bytes]) -> bytes:
    """An 11-byte short name for `name` not in `taken` (upper-case 11-byte names)."""
    if fits_8dot3(name):
        base, _, ext = name.upper().partition(".")
        sfn = _sfn_bytes(base, ext)
        if sfn in taken:
            raise PyFATException(f"short name {base}.{ext} of {name!r} is already used by "
                                 f"another entry", errno=errno.EEXIST)
        return sfn
    base, ext, _lossy = short_name_basis(name)
    # Always number the tail: an untailed basis could later collide with a real 8.3 name.
    for n in range(1, 1000000):
        tail = f"~{n}"
        sfn = _sfn_bytes(base[:8 - len(tail)] + tail, ext)
        if sfn not in taken:
            return sfn
    raise PyFATException(f"no free short name for {name!r}", errno=errno.EEXIST)


def make_lfn(name: str, sfn: EightDotThree) -> FATLongDirectoryEntry:
    """The LFN slots for `name` (UTF-16, NUL-terminated unless it fills the last slot, padded
    with 0xFFFF), each carrying the checksum of the short name."""
    encoded = name.encode(FAT_LFN_ENCODING)
    if len(encoded) % 26:
        encoded += b"\x00\x00"
    encoded += b"\xff" * (-len(encoded) % 26)
    checksum = sfn.checksum()
    lfn = FATLongDirectoryEntry()
    count = len(encoded) // 26
    for i in range(count):
        chunk = encoded[i * 26:(i + 1) * 26]
        lfn.add_lfn_entry(LDIR_Ord=(i + 1) | (0x40 if i == count - 1 else 0),
                          LDIR_Name1=chunk[0:10], LDIR_Attr=FATDirectoryEntry.ATTR_LONG_NAME,
                          LDIR_Type=0, LDIR_Chksum=checksum, LDIR_Name2=chunk[10:22],
                          LDIR_FstClusLO=0, LDIR_Name3=chunk[22:26])
    return lfn


def dir_slots(name: str) -> int:
    """32-byte directory slots an entry named `name` takes (LFN slots + the 8.3 entry)."""
    if fits_8dot3(name) and name == name.upper():
        return 1
    units = len(name.encode("utf-16-le")) // 2
    return 1 + math.ceil(units / 13)


# --- pyfatfs with proper entry creation ----------------------------------------------------

FAT32_ENTRY_MASK = 0x0FFF_FFFF    # the top 4 bits of a FAT32 entry are reserved (FAT spec)


class CardFat(PyFat):
    """pyfatfs' volume, reading a FAT32 table with one numpy conversion instead of pyfatfs'
    struct call per entry: the same entries (the reserved top 4 bits cleared), the same
    warning when the FATs differ, the same errors. The FATs are written to the image once,
    when the volume is closed, not at every file created, written or closed."""

    def __init__(self, offset: int) -> None:
        super().__init__(offset=offset, lazy_load=True)
        self._card_offset = offset
        self._card_fp = None
        self._fat_unwritten = False

    def set_fp(self, fp) -> None:
        self._card_fp = fp      # pyfatfs keeps its own reference private to PyFat
        super().set_fp(fp)

    def _parse_fat(self) -> None:
        if self.fat_type != self.FAT_TYPE_FAT32:
            super()._parse_fat()
            return
        sector = self.bpb_header["BPB_BytsPerSec"]
        fat_bytes = sector * self._fat_size
        first = self._card_offset + self.bpb_header["BPB_RsvdSecCnt"] * sector
        fats = []
        for index in range(self.bpb_header["BPB_NumFATs"]):
            self._card_fp.seek(first + index * fat_bytes)
            fats.append(self._card_fp.read(fat_bytes))
        if not fats:
            raise PyFATException("Invalid number of FATs configured, cannot continue")
        if len(set(fats)) > 1:
            warnings.warn("One or more FATs differ, filesystem most likely corrupted. Using first FAT.")
        self.bytes_per_cluster = sector * self.bpb_header["BPB_SecPerClus"]
        if len(fats[0]) != fat_bytes:
            raise PyFATException("Invalid length of FAT")
        self.fat = (np.frombuffer(fats[0], dtype="<u4") & FAT32_ENTRY_MASK).tolist()

    def flush_fat(self) -> None:
        # pyfatfs writes every FAT whole (1 MiB on a 64 MiB card) at each file it creates,
        # writes or closes, and a small card of three files costs 10 such writes. It keeps the
        # table in memory and never reads it back from the image while the volume is open, so
        # the FATs are written once, by close (_mark_clean); a writer that raises still closes
        # (CardWriter's with-block), or when a reader of the raw image asks (write_fat).
        self._fat_unwritten = True

    def write_fat(self) -> None:
        """Writes the FATs to the image now, if a change since the last write is not there yet."""
        if self._fat_unwritten:
            super().flush_fat()
            self._fat_unwritten = False

    def _mark_clean(self) -> None:
        super()._mark_clean()       # (pyfatfs' close: the clean-shutdown bit, then the boot sector)
        self.write_fat()

    def __bytes__(self) -> bytes:
        # pyfatfs packs a FAT32 table with a struct format of one letter per entry, at every
        # file it creates or closes (flush_fat); an array of 32-bit entries gives the same bytes
        table = array.array("I")
        if self.fat_type != self.FAT_TYPE_FAT32 or table.itemsize != 4:
            return super().__bytes__()
        table.extend(self.fat)
        if sys.byteorder == "big":
            table.byteswap()
        return table.tobytes()


@dataclass(frozen=True)
class CardStamp:
    """What makes a card image differ between two builds of the same files: the volume ID (also
    the MBR's disk signature) and the time its entries are created at (None: the current time)."""
    volume_id: int
    time: datetime.datetime | None = None


def _dos_date(when: datetime.datetime) -> int:
    return (when.year - 1980) << 9 | when.month << 5 | when.day


def _dos_time(when: datetime.datetime) -> int:
    return when.hour << 11 | when.minute << 5 | when.second // 2


def card_stamp() -> CardStamp:
    """SOURCE_DATE_EPOCH's stamp when it is set (the time it names, UTC, and a volume ID from it),
    otherwise a random volume ID and the current time. Raises UsageError for a value that is not
    a whole number of seconds FAT can hold (1980 to 2107)."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    if epoch is None:
        return CardStamp(volume_id=int.from_bytes(os.urandom(4), "little"))
    try:
        seconds = int(epoch)
        when = datetime.datetime.fromtimestamp(seconds, datetime.timezone.utc).replace(tzinfo=None)
    except (ValueError, OverflowError, OSError):
        raise UsageError(f"SOURCE_DATE_EPOCH={epoch!r} is not a time (whole seconds since 1970)") from None
    if not 1980 <= when.year <= 2107:
        raise UsageError(f"SOURCE_DATE_EPOCH={epoch!r} is outside the years FAT can hold (1980-2107)")
    return CardStamp(volume_id=seconds & 0xFFFFFFFF, time=when)


class CardFS(PyFatFS):
    """pyfatfs' filesystem with FAT-correct entry creation (see the module docstring), on a
    `CardFat`; new entries take `time` (None: the current time)."""

    def __init__(self, filename: str, offset: int, time: datetime.datetime | None = None) -> None:
        # PyFatFS.__init__, with CardFat for PyFat (defaults otherwise: preserve case, local time)
        FS.__init__(self)
        self.preserve_case = True
        self.fs = CardFat(offset=int(offset))
        self.fs.open(filename)
        self.tz = datetime.datetime.now(datetime.timezone.utc).astimezone().tzinfo
        self.time = time

    def _entry_names(self, base: FATDirectoryEntry) -> list[tuple[FATDirectoryEntry, str]]:
        dirs, files, _ = base.get_entries()
        return [(e, repr(e)) for e in dirs + files]

    def find_folded(self, base: FATDirectoryEntry, name: str,
                    names: list[tuple[FATDirectoryEntry, str]] | None = None
                    ) -> FATDirectoryEntry | None:
        """The entry of `base` whose long or short name equals `name` ignoring case."""
        wanted = rawfat.fat_fold(name)
        for entry, long_name in names if names is not None else self._entry_names(base):
            if wanted in (rawfat.fat_fold(long_name), rawfat.fat_fold(entry.get_short_name())):
                return entry
        return None

    def _new_entry(self, base: FATDirectoryEntry, name: str, attr: int,
                   names: list[tuple[FATDirectoryEntry, str]]) -> FATDirectoryEntry:
        problem = check_card_name(name)
        if problem:
            raise PyFATException(problem, errno=errno.EINVAL)
        taken = {bytes(e.name.name).upper() for e, _ in names}
        sfn_bytes = make_short_name(name, taken)
        sfn = EightDotThree(encoding=self.fs.encoding)
        sfn.set_byte_name(sfn_bytes)
        entry = FATDirectoryEntry.new(name=sfn, tz=self.tz, encoding=self.fs.encoding, attr=attr)
        if self.time is not None:
            date, time = _dos_date(self.time), _dos_time(self.time)
            entry.crttime = entry.wrttime = time
            entry.crtdate = entry.wrtdate = entry.lstaccessdate = date
        if sfn.get_unpadded_filename() != name:
            entry.set_lfn_entry(make_lfn(name, sfn))
        return entry

    def _parent_and_name(self, path: str) -> tuple[FATDirectoryEntry, str]:
        parent, name = split(normpath(path))
        base = self._get_dir_entry(parent or "/")
        if not base.is_directory():
            raise ResourceNotFound(path)
        return base, name

    def create(self, path: str, wipe: bool = False) -> bool:
        """Creates an empty file (see `PyFatFS.create`), refusing a name that differs only
        in case from an existing entry."""
        base, name = self._parent_and_name(path)
        names = self._entry_names(base)
        existing = self.find_folded(base, name, names)
        if existing is not None:
            if repr(existing) == name or existing.get_short_name() == name:
                return super().create(path, wipe=wipe)
            raise FileExists(f"{path} (differs only in case from {repr(existing)!r}: FAT "
                             f"names are case-insensitive)")
        entry = self._new_entry(base, name, attr=0, names=names)
        base.add_subdirectory(entry)
        self.fs.update_directory_entry(base)
        self.fs.flush_fat()
        return True

    def makedir(self, path: str, permissions=None, recreate: bool = False) -> SubFS:
        """Creates a folder with its "." and ".." entries (see `PyFatFS.makedir`)."""
        path = normpath(path)
        base, name = self._parent_and_name(path)
        names = self._entry_names(base)
        existing = self.find_folded(base, name, names)
        if existing is not None:
            if recreate and existing.is_directory() and repr(existing) == name:
                return SubFS(self, path)
            raise DirectoryExists(path)
        newdir = self._new_entry(base, name, attr=FATDirectoryEntry.ATTR_DIRECTORY,
                                 names=names)
        first_cluster = self.fs.allocate_bytes(FATDirectoryEntry.FAT_DIRECTORY_HEADER_SIZE * 2,
                                               erase=True)[0]
        newdir.set_cluster(first_cluster)
        dot = copy(newdir)
        dot.name = EightDotThree()
        dot.name.set_byte_name(b".          ")
        dot.lfn_entry = None
        dot._parent = None
        dotdot = copy(newdir)
        dotdot.name = EightDotThree()
        dotdot.name.set_byte_name(b"..         ")
        dotdot.lfn_entry = None
        dotdot._parent = None
        # ".." of a first-level folder points at cluster 0, meaning the root (FAT spec).
        dotdot.set_cluster(0 if base is self.fs.root_dir else base.get_cluster())
        newdir.add_subdirectory(dot)
        newdir.add_subdirectory(dotdot)
        self.fs.update_directory_entry(newdir)
        base.add_subdirectory(newdir)
        self.fs.update_directory_entry(base)
        self.fs.flush_fat()
        return SubFS(self, path)


# --- a card being written ------------------------------------------------------------------

class CardWriter:
    """An MBR-partitioned image whose FAT32 partition is open for writing through pyfatfs.

    Use `CardWriter.create` for a fresh card or `CardWriter.open` to change an existing one;
    `close` (or the with-block) flushes pyfatfs and fixes the FSInfo sector.
    """

    def __init__(self, image: Path, partition: mbr.PartitionEntry, stamp: CardStamp | None = None) -> None:
        self.image = Path(image)
        self.partition = partition
        self.stamp = stamp if stamp is not None else card_stamp()
        self.offset = partition.start_lba * mbr.SECTOR_SIZE
        self.fs: CardFS = self._open()

    @classmethod
    def create(cls, image: Path, size_mib: int, label: str = VOLUME_LABEL,
               layout: str = LAYOUT_FATGEN103, stamp: CardStamp | None = None) -> "CardWriter":
        """Writes a blank card: MBR with one FAT32 (0x0C) partition from LBA 2048 to the end,
        formatted by pyfatfs or (layout mkfs.fat) by mkfs.fat. The file is created or truncated.
        `stamp` (default: `card_stamp()`) gives the volume ID and the entries' time."""
        total = size_mib * 1024 * 1024 // mbr.SECTOR_SIZE
        geometry = image_geometry(size_mib, layout)
        part = mbr.PartitionEntry(type=mbr.TYPE_FAT32_LBA, start_lba=mbr.PARTITION_START_LBA,
                                  sector_count=total - mbr.PARTITION_START_LBA)
        stamp = stamp if stamp is not None else card_stamp()
        volume_id = stamp.volume_id
        with open(image, "wb") as f:
            # Sparse: the zeros pyfatfs relies on for free FAT entries cost no disk space.
            f.truncate(total * mbr.SECTOR_SIZE)
            f.write(mbr.build_mbr([part], disk_signature=volume_id))
        if layout == LAYOUT_MKFS_FAT:
            mkfs_fat_format(image, part, label, volume_id)
            writer = cls(image, part, stamp)
            writer._stamp_label()
            if writer.cluster_count != geometry.cluster_count:
                writer.fs.close()
                raise RuntimeError(f"mkfs.fat formatted {writer.cluster_count} clusters; planned {geometry}")
            return writer
        formatter = PyFat(offset=part.start_lba * mbr.SECTOR_SIZE)
        formatter.mkfs(str(image), PyFat.FAT_TYPE_FAT32,
                       size=part.sector_count * mbr.SECTOR_SIZE, label=label,
                       volume_id=volume_id)
        formatter.close()
        writer = cls(image, part, stamp)
        writer._stamp_label()
        actual = writer.fs.fs.bpb_header
        if (actual["BPB_SecPerClus"], actual["BPB_FATSz32"]) != (geometry.sectors_per_cluster,
                                                                 geometry.fat_sectors):
            writer.fs.close()
            raise RuntimeError(f"pyfatfs formatted {actual['BPB_SecPerClus']} sectors/cluster, "
                               f"{actual['BPB_FATSz32']} FAT sectors; planned {geometry}")
        return writer

    def _stamp_label(self) -> None:
        """The formatter's volume label entry in the root folder at the stamp's time (it has the
        formatting's), when the stamp has one."""
        if self.stamp.time is None:
            return
        root = self.fs.fs.root_dir
        for entry in root._get_entries_raw():
            if entry.attr == FATDirectoryEntry.ATTR_VOLUME_ID:
                entry.crttime = entry.wrttime = _dos_time(self.stamp.time)
                entry.crtdate = entry.wrtdate = entry.lstaccessdate = _dos_date(self.stamp.time)
        self.fs.fs.update_directory_entry(root)

    @classmethod
    def open(cls, image: Path) -> "CardWriter":
        """Opens an existing card image for changes."""
        with open(image, "rb") as f:
            f.seek(0, 2)
            sectors = f.tell() // mbr.SECTOR_SIZE
            f.seek(0)
            _, part = mbr.find_fat32_partition(f.read(mbr.SECTOR_SIZE), sectors)
        return cls(image, part)

    def _open(self) -> CardFS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "not cleanly unmounted" right after mkfs
            fs = CardFS(str(self.image), offset=self.offset, time=self.stamp.time)
        pf = fs.fs
        header = pf.bpb_header
        # pyfatfs's mkfs leaves these 0; a volume another formatter made keeps its own
        if header["BPB_HiddSec"] == 0:
            header["BPB_HiddSec"] = self.partition.start_lba
        if header["BPB_SecPerTrk"] == 0 or header["BPB_NumHeads"] == 0:
            header["BPB_SecPerTrk"] = mbr.SECTORS_PER_TRACK
            header["BPB_NumHeads"] = mbr.HEADS
        data_sectors = pf._get_total_sectors() - pf.first_data_sector
        self.cluster_count = data_sectors // header["BPB_SecPerClus"]
        self.bytes_per_cluster = pf.bytes_per_cluster
        # Entries past the last cluster exist only because the FAT fills whole sectors.
        del pf.fat[self.cluster_count + 2:]
        return fs

    def reopen(self) -> None:
        """Closes and re-reads the filesystem: pyfatfs keeps directories in memory, so this
        drops what it still believes about entries changed behind its back."""
        self.fs.close()
        self.fs = self._open()

    def makedirs(self, card_dir: str) -> None:
        """Creates a folder and its missing parents ("/a/b")."""
        walked = ""
        for part in [p for p in card_dir.split("/") if p]:
            walked += "/" + part
            if not self.fs.exists(walked):
                self.fs.makedir(walked)

    def write(self, card_path: str, data: bytes) -> None:
        """Writes a new file (its folder must exist). An empty file gets no cluster."""
        try:
            # create() first: pyfatfs' own "wb" would truncate an existing file, and its
            # truncation frees cluster 0 for empty files.
            if not self.fs.create(card_path):
                raise UsageError(f"{card_path} is already on the card")
            with self.fs.openbin(card_path, "r+") as f:
                f.write(data)
        except PyFATException as exc:
            if exc.errno == errno.ENOSPC:
                raise ImageTooSmallError(f"card is full while writing {card_path}") from None
            raise
        except FileExists as exc:
            raise UsageError(str(exc)) from None

    def append(self, card_path: str, data: bytes) -> None:
        """Appends to an existing file; new clusters come from the first free ones."""
        with self.fs.openbin(card_path, "ab") as f:
            f.write(data)

    def remove(self, card_path: str) -> None:
        """Deletes a file the way pyfatfs does: the folder is rewritten without the entry."""
        self.fs.remove(card_path)

    def remove_leaving_entries(self, card_paths: list[str]) -> None:
        """Deletes files as DOS and most drivers do: their 8.3 and LFN slots stay in the folder
        marked 0xE5, and their clusters are freed. (pyfatfs' own remove compacts the folder.)

        All deletions are done before any folder is rewritten: pyfatfs re-reads a folder
        without its deleted slots, so a later change to the same folder would drop them.
        """
        by_parent: dict[int, tuple[FATDirectoryEntry, list[FATDirectoryEntry]]] = {}
        for path in card_paths:
            entry = self.fs._get_dir_entry(path)
            if entry.is_directory():
                raise IsADirectoryError(path)
            parent = entry.get_parent_dir()
            by_parent.setdefault(id(parent), (parent, []))[1].append(entry)
        for parent, entries in by_parent.values():
            for entry in entries:
                cluster = entry.get_cluster()
                entry.mark_empty()
                if cluster:
                    self.fs.fs.free_cluster_chain(cluster)
            self.fs.fs.update_directory_entry(parent)
        self.fs.fs.flush_fat()
        # pyfatfs would still list the entries under their long names: forget them.
        self.reopen()

    def flush(self) -> None:
        """Brings the image up to date while the card stays open, for a reader of the raw image
        (rawfat): file data and folders are written as they change, the FATs only at close
        (CardFat) or here."""
        self.fs.fs.write_fat()

    def free_bytes(self) -> int:
        free = self.fs.fs.fat[2:].count(0)
        return free * self.bytes_per_cluster

    def close(self) -> None:
        """Flushes pyfatfs, then writes the FSInfo free count and next-free hint."""
        self.fs.close()
        fix_fsinfo(self.image)

    def __enter__(self) -> "CardWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


_FSINFO_FREE = 0x1E8


def fix_fsinfo(image: Path) -> None:
    """Rewrites free count and next-free hint of both FSInfo sectors from the FAT."""
    with rawfat.Fat32Volume(image) as vol:
        # every data cluster's entry at once (a loop over 127,000 entries of a 64 MiB card took
        # longer than writing the card's files)
        entries = np.frombuffer(vol.fat, dtype=np.uint32)[2:vol.boot.cluster_count + 2] & rawfat.FAT_ENTRY_MASK
        free_clusters = np.flatnonzero(entries == 0)
        free = int(free_clusters.size)
        first_free = int(free_clusters[0]) + 2 if free else None
        sectors = [vol.boot.fsinfo_sector]
        if vol.boot.backup_boot_sector:
            sectors.append(vol.boot.backup_boot_sector + vol.boot.fsinfo_sector)
        base = vol.partition_offset
    with open(image, "r+b") as f:
        for sector in sectors:
            f.seek(base + sector * mbr.SECTOR_SIZE + _FSINFO_FREE)
            f.write(struct.pack("<II", free, first_free if first_free is not None
                                else 0xFFFFFFFF))

