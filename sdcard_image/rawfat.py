"""A small read-only FAT32 reader working on the raw bytes of a card image.

It does not use pyfatfs on purpose: listing and extracting must survive damaged images
(pyfatfs loops forever on a cyclic cluster chain and fails with bare tracebacks), and the
layout helpers need facts pyfatfs hides (deleted entries, the raw cluster chains).
Every inconsistency raises `CorruptImageError` with a message naming what is wrong.
"""
from __future__ import annotations

import struct
import sys
from array import array
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO, Iterator

from . import mbr
from .errors import CorruptImageError

#: FAT32 needs at least this many clusters, otherwise drivers take the volume for FAT16.
MIN_FAT32_CLUSTERS = 65525
FAT_ENTRY_MASK = 0x0FFFFFFF
END_OF_CHAIN_MIN = 0x0FFFFFF8
BAD_CLUSTER = 0x0FFFFFF7

ATTR_READ_ONLY = 0x01
ATTR_HIDDEN = 0x02
ATTR_SYSTEM = 0x04
ATTR_VOLUME_ID = 0x08
ATTR_DIRECTORY = 0x10
ATTR_ARCHIVE = 0x20
ATTR_LONG_NAME = 0x0F
DELETED_MARK = 0xE5
DIR_ENTRY_SIZE = 32
#: Characters the FAT specification allows in neither long nor 8.3 names. A name holding one
#: (or a NUL, or "." / ".." outside the dot entries) can only come from damage, and must not
#: become a path on the host (extract would write outside its folder, or fail on the NUL).
_FORBIDDEN_NAME_CHARS = frozenset('"*/:<>?\\|') | frozenset(chr(c) for c in range(0x20))


@dataclass(frozen=True)
class BootSector:
    """The fields of a FAT32 BPB this tool relies on (offsets per the FAT specification)."""

    bytes_per_sector: int
    sectors_per_cluster: int
    reserved_sectors: int
    num_fats: int
    total_sectors: int
    fat_sectors: int
    root_cluster: int
    fsinfo_sector: int
    backup_boot_sector: int
    hidden_sectors: int
    sectors_per_track: int
    num_heads: int
    volume_label: str
    fs_type: str

    @property
    def bytes_per_cluster(self) -> int:
        return self.bytes_per_sector * self.sectors_per_cluster

    @property
    def first_data_sector(self) -> int:
        return self.reserved_sectors + self.num_fats * self.fat_sectors

    @property
    def cluster_count(self) -> int:
        """Number of data clusters; valid cluster numbers are 2 .. cluster_count + 1."""
        return (self.total_sectors - self.first_data_sector) // self.sectors_per_cluster

    @classmethod
    def parse(cls, sector: bytes) -> "BootSector":
        """Parses and validates a FAT32 boot sector; raises `CorruptImageError` naming the field."""
        if len(sector) < 512:
            raise CorruptImageError("partition is too short to hold a boot sector")
        if sector[510:512] != b"\x55\xAA":
            raise CorruptImageError(f"bad BPB: no boot sector signature at partition offset "
                                    f"0x1FE (found {sector[510:512].hex(' ')}, expected 55 aa)")
        if not (sector[0] == 0xE9 or (sector[0] == 0xEB and sector[2] == 0x90)):
            raise CorruptImageError(f"bad BPB: jump instruction {sector[:3].hex(' ')} is neither "
                                    f"EB xx 90 nor E9 xx xx: not a FAT boot sector")
        (bps, spc, rsvd, nfats, root_ents, tot16, _media, fatsz16, spt, heads, hidden,
         tot32) = struct.unpack_from("<HBHBHHBHHHII", sector, 0x0B)
        fatsz32, _ext_flags, _fs_ver, root_clus, fsinfo, bkboot = struct.unpack_from(
            "<IHHIHH", sector, 0x24)
        if bps not in (512, 1024, 2048, 4096):
            raise CorruptImageError(f"bad BPB: bytes per sector (offset 0x0B) is {bps}, expected "
                                    f"512, 1024, 2048 or 4096")
        if spc == 0 or spc & (spc - 1):
            raise CorruptImageError(f"bad BPB: sectors per cluster (offset 0x0D) is {spc}, "
                                    f"expected a power of two")
        if rsvd == 0:
            raise CorruptImageError("bad BPB: reserved sector count (offset 0x0E) is 0")
        if nfats == 0:
            raise CorruptImageError("bad BPB: number of FATs (offset 0x10) is 0")
        if fatsz16 != 0 or root_ents != 0:
            raise CorruptImageError(f"not FAT32: the BPB has a FAT12/16 layout (FAT size at 0x16 "
                                    f"= {fatsz16}, root entries at 0x11 = {root_ents})")
        if fatsz32 == 0:
            raise CorruptImageError("bad BPB: FAT size (offset 0x24) is 0")
        total = tot32 if tot16 == 0 else tot16
        if total == 0:
            raise CorruptImageError("bad BPB: total sector count (offsets 0x13 and 0x20) is 0")
        label = sector[0x47:0x52].decode("ascii", "replace").rstrip()
        fs_type = sector[0x52:0x5A].decode("ascii", "replace").rstrip()
        boot = cls(bytes_per_sector=bps, sectors_per_cluster=spc, reserved_sectors=rsvd,
                   num_fats=nfats, total_sectors=total, fat_sectors=fatsz32,
                   root_cluster=root_clus, fsinfo_sector=fsinfo, backup_boot_sector=bkboot,
                   hidden_sectors=hidden, sectors_per_track=spt, num_heads=heads,
                   volume_label=label, fs_type=fs_type)
        if boot.first_data_sector >= total:
            raise CorruptImageError(f"bad BPB: reserved sectors and FATs ({boot.first_data_sector} "
                                    f"sectors) leave no data area in {total} sectors")
        if boot.cluster_count < MIN_FAT32_CLUSTERS:
            raise CorruptImageError(f"not FAT32: only {boot.cluster_count} clusters (FAT32 needs "
                                    f"at least {MIN_FAT32_CLUSTERS})")
        if fatsz32 * bps // 4 < boot.cluster_count + 2:
            raise CorruptImageError(f"bad BPB: a FAT of {fatsz32} sectors cannot map "
                                    f"{boot.cluster_count} clusters")
        if not 2 <= root_clus < boot.cluster_count + 2:
            raise CorruptImageError(f"bad BPB: root cluster (offset 0x2C) {root_clus} is outside "
                                    f"2..{boot.cluster_count + 1}")
        return boot


@dataclass(frozen=True)
class DirEntry:
    """One directory entry as stored: the 8.3 entry plus the long name of its LFN slots."""

    #: Byte offset of the 8.3 entry in the image file.
    offset: int
    short_name: bytes
    attr: int
    first_cluster: int
    size: int
    long_name: str | None
    #: Number of 32-byte LFN slots in front of the 8.3 entry.
    lfn_slots: int
    deleted: bool

    @property
    def short_name_str(self) -> str:
        """The 8.3 name as "NAME.EXT" (0x05 in the first byte stands for 0xE5)."""
        raw = bytearray(self.short_name)
        if raw[0] == 0x05:
            raw[0] = 0xE5
        base = raw[:8].decode("cp437").rstrip()
        ext = raw[8:].decode("cp437").rstrip()
        return f"{base}.{ext}" if ext else base

    @property
    def name(self) -> str:
        """The name a user sees: the long name when there is one."""
        return self.long_name if self.long_name is not None else self.short_name_str

    @property
    def is_dir(self) -> bool:
        return bool(self.attr & ATTR_DIRECTORY)

    @property
    def is_volume_label(self) -> bool:
        return bool(self.attr & ATTR_VOLUME_ID) and not self.attr & ATTR_DIRECTORY

    @property
    def is_dot(self) -> bool:
        return self.short_name in (b".          ", b"..         ")


def lfn_checksum(short_name: bytes) -> int:
    """The checksum of an 11-byte 8.3 name stored in each of its LFN slots."""
    total = 0
    for byte in short_name:
        total = (((total & 1) << 7) | (total >> 1)) + byte
        total &= 0xFF
    return total


def _lfn_chars(slot: bytes) -> bytes:
    return slot[1:11] + slot[14:26] + slot[28:32]


def _decode_lfn(slots: list[bytes]) -> str:
    """Joins LFN slots given in on-disk order (last part first)."""
    raw = b"".join(_lfn_chars(s) for s in reversed(slots))
    units = [raw[i:i + 2] for i in range(0, len(raw), 2)]
    out = bytearray()
    for unit in units:
        if unit == b"\x00\x00":
            break
        out += unit
    return out.decode("utf-16-le", "replace")


@dataclass(frozen=True)
class CardFile:
    """A file or folder found on a card by `Fat32Volume.walk`."""

    path: str
    entry: DirEntry

    @property
    def is_dir(self) -> bool:
        return self.entry.is_dir

    @property
    def size(self) -> int:
        return 0 if self.entry.is_dir else self.entry.size


class Fat32Volume:
    """Read-only view of the FAT32 partition of an MBR-partitioned image file."""

    def __init__(self, image: Path | str | BinaryIO) -> None:
        if isinstance(image, (str, Path)):
            self._fp: BinaryIO = open(image, "rb")
            self._owns_fp = True
        else:
            self._fp = image
            self._owns_fp = False
        try:
            self._load()
        except BaseException:
            self.close()
            raise

    def _load(self) -> None:
        self._fp.seek(0, 2)
        image_size = self._fp.tell()
        self._fp.seek(0)
        sector0 = self._fp.read(mbr.SECTOR_SIZE)
        self.partition_index, self.partition = mbr.find_fat32_partition(
            sector0, image_size // mbr.SECTOR_SIZE)
        self.partition_offset = self.partition.start_lba * mbr.SECTOR_SIZE
        self.boot = BootSector.parse(self._read_at(self.partition_offset, 512))
        if self.boot.bytes_per_sector != mbr.SECTOR_SIZE:
            raise CorruptImageError(f"bad BPB: {self.boot.bytes_per_sector} bytes per sector; "
                                    f"SD cards use {mbr.SECTOR_SIZE}")
        if self.partition.sector_count and self.boot.total_sectors > self.partition.sector_count:
            raise CorruptImageError(f"bad BPB: the volume has {self.boot.total_sectors} sectors "
                                    f"but its partition only {self.partition.sector_count}")
        if self.partition.start_lba + self.boot.total_sectors > image_size // mbr.SECTOR_SIZE:
            raise CorruptImageError(f"bad BPB: the volume's {self.boot.total_sectors} sectors from sector "
                                    f"{self.partition.start_lba} run past the image's "
                                    f"{image_size // mbr.SECTOR_SIZE} (truncated image?)")
        fat_bytes = self._read_at(self.partition_offset
                                  + self.boot.reserved_sectors * self.boot.bytes_per_sector,
                                  (self.boot.cluster_count + 2) * 4)
        self.fat = array("I")
        self.fat.frombytes(fat_bytes)
        if sys.byteorder != "little":
            self.fat.byteswap()

    def _read_at(self, offset: int, length: int) -> bytes:
        self._fp.seek(offset)
        data = self._fp.read(length)
        if len(data) != length:
            raise CorruptImageError(f"image ends at byte {offset + len(data)}, inside a "
                                    f"structure that needs bytes up to {offset + length}")
        return data

    def close(self) -> None:
        if self._owns_fp:
            self._fp.close()

    def __enter__(self) -> "Fat32Volume":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- clusters -------------------------------------------------------------------------

    def fat_entry(self, cluster: int) -> int:
        """The FAT entry of `cluster` (low 28 bits)."""
        return self.fat[cluster] & FAT_ENTRY_MASK

    def cluster_offset(self, cluster: int) -> int:
        """Byte offset of a data cluster in the image file."""
        sector = self.boot.first_data_sector + (cluster - 2) * self.boot.sectors_per_cluster
        return self.partition_offset + sector * self.boot.bytes_per_sector

    def cluster_chain(self, first: int, what: str = "chain") -> list[int]:
        """The clusters of a chain in order; raises on loops, free/bad entries, bad numbers."""
        last_valid = self.boot.cluster_count + 1
        chain: list[int] = []
        seen: set[int] = set()
        cluster = first
        while True:
            if not 2 <= cluster <= last_valid:
                raise CorruptImageError(f"{what}: cluster {cluster:#x} is outside the data area "
                                        f"(2..{last_valid:#x})")
            if cluster in seen:
                raise CorruptImageError(f"{what}: cluster chain loops back to cluster {cluster}")
            seen.add(cluster)
            chain.append(cluster)
            nxt = self.fat_entry(cluster)
            if nxt >= END_OF_CHAIN_MIN:
                return chain
            if nxt == 0:
                raise CorruptImageError(f"{what}: cluster {cluster} is marked free in the FAT "
                                        f"but belongs to a chain")
            if nxt == BAD_CLUSTER:
                raise CorruptImageError(f"{what}: chain runs into a bad cluster after {cluster}")
            cluster = nxt

    def read_cluster(self, cluster: int) -> bytes:
        return self._read_at(self.cluster_offset(cluster), self.boot.bytes_per_cluster)

    def free_cluster_count(self) -> int:
        """Clusters whose FAT entry is 0."""
        return sum(1 for c in range(2, self.boot.cluster_count + 2) if self.fat_entry(c) == 0)

    # --- directories ----------------------------------------------------------------------

    def dir_entries(self, cluster: int, include_deleted: bool = False,
                    what: str = "directory") -> list[DirEntry]:
        """The entries of the directory starting at `cluster`, in on-disk order.

        Stops at the 0x00 end marker. LFN slots whose checksum or sequence does not match the
        8.3 entry that follows are ignored, as every FAT driver does.
        """
        entries: list[DirEntry] = []
        pending: list[bytes] = []
        for clus in self.cluster_chain(cluster, what):
            base = self.cluster_offset(clus)
            data = self.read_cluster(clus)
            for pos in range(0, len(data), DIR_ENTRY_SIZE):
                raw = data[pos:pos + DIR_ENTRY_SIZE]
                first, attr = raw[0], raw[11]
                if first == 0x00:
                    return entries
                deleted = first == DELETED_MARK
                if attr & 0x3F == ATTR_LONG_NAME:
                    if deleted:
                        pending = []
                    else:
                        pending.append(raw)
                    continue
                long_name, slots = self._match_lfn(pending, raw[:11])
                pending = []
                if deleted and not include_deleted:
                    continue
                hi, lo = struct.unpack_from("<H", raw, 20)[0], struct.unpack_from("<H", raw, 26)[0]
                entries.append(DirEntry(offset=base + pos, short_name=raw[:11], attr=attr,
                                        first_cluster=(hi << 16) | lo,
                                        size=struct.unpack_from("<I", raw, 28)[0],
                                        long_name=long_name, lfn_slots=slots, deleted=deleted))
        return entries

    @staticmethod
    def _match_lfn(slots: list[bytes], short_name: bytes) -> tuple[str | None, int]:
        if not slots:
            return None, 0
        checksum = lfn_checksum(short_name)
        if not slots[0][0] & 0x40 or (slots[0][0] & 0x3F) != len(slots):
            return None, 0
        for i, slot in enumerate(slots):
            if slot[13] != checksum or (slot[0] & 0x3F) != len(slots) - i:
                return None, 0
        return _decode_lfn(slots), len(slots)

    def walk(self) -> Iterator[CardFile]:
        """Every file and folder on the card, depth first, folders before their content."""
        yield from self._walk(self.boot.root_cluster, "", {self.boot.root_cluster})

    def _walk(self, cluster: int, prefix: str, ancestors: set[int]) -> Iterator[CardFile]:
        for entry in self.dir_entries(cluster, what=prefix or "/"):
            if entry.is_dot or entry.is_volume_label:
                continue
            name = entry.name
            if name in ("", ".", "..") or any(c in _FORBIDDEN_NAME_CHARS for c in name):
                raise CorruptImageError(f"{prefix or '/'}: the entry at image byte "
                                        f"{entry.offset:#x} has a name FAT does not allow: "
                                        f"{name!r}")
            path = f"{prefix}/{name}"
            yield CardFile(path, entry)
            if entry.is_dir:
                if entry.first_cluster < 2:
                    raise CorruptImageError(f"{path}: directory starts at cluster "
                                            f"{entry.first_cluster}, outside the data area")
                if entry.first_cluster in ancestors:
                    raise CorruptImageError(f"{path}: directory points at cluster "
                                            f"{entry.first_cluster}, which is one of its parents")
                yield from self._walk(entry.first_cluster, path, ancestors | {entry.first_cluster})

    def lookup(self, card_path: str) -> DirEntry | None:
        """The entry for a card path ("/models/cube.obj"), matching names case-insensitively
        against long and 8.3 names as FAT drivers do; None for the root folder."""
        parts = [p for p in card_path.replace("\\", "/").split("/") if p]
        cluster = self.boot.root_cluster
        entry: DirEntry | None = None
        walked = ""
        for part in parts:
            if entry is not None and not entry.is_dir:
                raise FileNotFoundError(f"{walked} is a file, not a folder")
            wanted = fat_fold(part)
            for candidate in self.dir_entries(cluster, what=walked or "/"):
                if candidate.is_dot or candidate.is_volume_label:
                    continue
                if wanted in (fat_fold(candidate.name), fat_fold(candidate.short_name_str)):
                    entry = candidate
                    break
            else:
                raise FileNotFoundError(f"no {walked}/{part} on the card")
            walked = f"{walked}/{entry.name}"
            cluster = entry.first_cluster
        return entry

    def read(self, entry: DirEntry, what: str = "file") -> bytes:
        """The content of a file entry, checked against its cluster chain."""
        if entry.is_dir:
            raise IsADirectoryError(what)
        if entry.size == 0:
            return b""
        chain = self.cluster_chain(entry.first_cluster, what)
        per = self.boot.bytes_per_cluster
        needed = -(-entry.size // per)
        if len(chain) < needed:
            raise CorruptImageError(f"{what}: size {entry.size} needs {needed} clusters but its "
                                    f"chain has {len(chain)}")
        data = b"".join(self.read_cluster(c) for c in chain[:needed])
        return data[:entry.size]


def fat_fold(name: str) -> str:
    """Case folding for name comparison: FAT compares names upper-cased, one character for one
    (so 'ß' stays 'ß', unlike Python's str.upper)."""
    return "".join(u if len(u := c.upper()) == 1 else c for c in name)
