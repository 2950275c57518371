"""The master boot record: sector 0 of the card, holding the partition table.

The firmware (and every SD-card reader) finds the FAT32 volume through this table, so the
layout is the classic one: four 16-byte entries at 0x1BE and the 0x55 0xAA signature.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass

from .errors import CorruptImageError

SECTOR_SIZE = 512
#: First partition sector. 1 MiB alignment is what SD cards are formatted with (the SD
#: Association's formatter and every OS partitioner do it) and keeps clusters aligned to
#: the card's erase blocks.
PARTITION_START_LBA = 2048
PARTITION_TABLE_OFFSET = 0x1BE
DISK_SIGNATURE_OFFSET = 0x1B8
SIGNATURE_OFFSET = 0x1FE
SIGNATURE = b"\x55\xAA"
#: FAT32 addressed by LBA. 0x0B (FAT32 with CHS) is also accepted when reading.
TYPE_FAT32_LBA = 0x0C
TYPE_FAT32_CHS = 0x0B
FAT32_TYPES = (TYPE_FAT32_CHS, TYPE_FAT32_LBA)

# A made-up but conventional geometry: CHS values only matter to BIOS-era software, yet some
# tools reject zeros, so the MBR and the BPB agree on 255 heads x 63 sectors.
HEADS = 255
SECTORS_PER_TRACK = 63

_ENTRY = struct.Struct("<B3sB3sII")


def lba_to_chs(lba: int) -> bytes:
    """Encodes an LBA as the 3-byte CHS of a partition entry (saturating past cylinder 1023)."""
    cylinder, rest = divmod(lba, HEADS * SECTORS_PER_TRACK)
    head, sector = divmod(rest, SECTORS_PER_TRACK)
    if cylinder > 1023:
        # The conventional "use LBA" marker: the largest CHS value.
        return bytes((0xFE, 0xFF, 0xFF))
    sector += 1
    return bytes((head, ((cylinder >> 2) & 0xC0) | sector, cylinder & 0xFF))


@dataclass(frozen=True)
class PartitionEntry:
    """One 16-byte entry of the MBR partition table."""

    type: int
    start_lba: int
    sector_count: int
    bootable: bool = False

    @property
    def end_lba(self) -> int:
        """First sector after the partition."""
        return self.start_lba + self.sector_count

    @property
    def is_empty(self) -> bool:
        return self.type == 0 or self.sector_count == 0

    def pack(self) -> bytes:
        """The entry's 16 on-disk bytes."""
        last = self.start_lba + max(self.sector_count, 1) - 1
        return _ENTRY.pack(0x80 if self.bootable else 0x00, lba_to_chs(self.start_lba), self.type,
                           lba_to_chs(last), self.start_lba, self.sector_count)

    @classmethod
    def unpack(cls, data: bytes) -> "PartitionEntry":
        """Parses 16 on-disk bytes (CHS fields are ignored: LBA is authoritative)."""
        status, _chs_first, ptype, _chs_last, start, count = _ENTRY.unpack(data)
        return cls(type=ptype, start_lba=start, sector_count=count, bootable=status == 0x80)


def build_mbr(partitions: list[PartitionEntry], disk_signature: int = 0) -> bytes:
    """A 512-byte MBR with up to four partitions, no boot code, and the 0x55AA signature."""
    if len(partitions) > 4:
        raise ValueError("an MBR holds at most four partitions")
    sector = bytearray(SECTOR_SIZE)
    struct.pack_into("<I", sector, DISK_SIGNATURE_OFFSET, disk_signature & 0xFFFFFFFF)
    for i, part in enumerate(partitions):
        off = PARTITION_TABLE_OFFSET + 16 * i
        sector[off:off + 16] = part.pack()
    sector[SIGNATURE_OFFSET:SIGNATURE_OFFSET + 2] = SIGNATURE
    return bytes(sector)


def parse_mbr(sector0: bytes) -> list[PartitionEntry]:
    """The four partition entries of an MBR; raises `CorruptImageError` without a signature."""
    if len(sector0) < SECTOR_SIZE:
        raise CorruptImageError(f"image is only {len(sector0)} bytes: too short to hold an MBR "
                                f"({SECTOR_SIZE} bytes)")
    sig = sector0[SIGNATURE_OFFSET:SIGNATURE_OFFSET + 2]
    if sig != SIGNATURE:
        raise CorruptImageError(f"no MBR signature: bytes 0x1FE-0x1FF are {sig.hex(' ')}, "
                                f"expected 55 aa")
    return [PartitionEntry.unpack(sector0[PARTITION_TABLE_OFFSET + 16 * i:
                                          PARTITION_TABLE_OFFSET + 16 * (i + 1)])
            for i in range(4)]


def _looks_like_bare_fat(sector0: bytes) -> bool:
    return sector0[0] in (0xEB, 0xE9) and sector0[0x52:0x5A] == b"FAT32   "


def find_fat32_partition(sector0: bytes, image_sectors: int) -> tuple[int, PartitionEntry]:
    """The first FAT32 partition (index 0..3 and entry), checked to lie inside the image. An
    entry's type and start decide, as for FatFs (the Kendryte SDK's and MaixPy's FAT driver reads
    no more of it) and the firmware (fat32.S): one whose length is 0 is taken, the volume's BPB
    then giving its size."""
    entries = parse_mbr(sector0)
    for index, entry in enumerate(entries):
        if entry.type in FAT32_TYPES:
            if entry.start_lba == 0:
                raise CorruptImageError(f"partition {index + 1} starts at sector 0, on top of "
                                        f"the MBR")
            if entry.start_lba >= image_sectors:
                raise CorruptImageError(f"partition {index + 1} starts at sector {entry.start_lba} but the "
                                        f"image has only {image_sectors} sectors (truncated image?)")
            if entry.end_lba > image_sectors:
                raise CorruptImageError(
                    f"partition {index + 1} ends at sector {entry.end_lba} but the image has "
                    f"only {image_sectors} sectors (truncated image?)")
            return index, entry
    types = ", ".join(f"{e.type:#04x}" for e in entries if not e.is_empty) or "none"
    hint = (" (sector 0 is a FAT32 boot sector: a bare volume without a partition table)"
            if _looks_like_bare_fat(sector0) else "")
    raise CorruptImageError(f"no FAT32 partition (type 0x0b/0x0c) in the MBR; partition types "
                            f"found: {types}{hint}")
