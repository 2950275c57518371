"""SD card images for the K210 renderer: an MBR with one FAT32 partition, filled with pyfatfs.

Command line: ``python -m sdcard_image build|list|extract`` (see `sdcard_image.cli`).
Python API for tests and tools::

    from sdcard_image import build_image, list_image, read_file
    placed = build_image(Path("card.img"), [Path("models"), Path("tex")],
                         scene={"model": "models/cube.obj"}, texture_size=(64, 64))
    data = read_file(Path("card.img"), "/models/cube.obj")

Cards with special layouts (fragmented files, deleted entries, multi-cluster folders, names
differing only in case) come from `sdcard_image.layouts`.
"""
from .convert import PlacedFile
from .errors import (BadInputError, CorruptImageError, ImageTooSmallError, OutputExistsError,
                     SdImageError, UsageError)
from .image import (DEFAULT_SIZE_MIB, CardEntry, build_image, extract_all, list_image,
                    read_file)
from .mbr import PARTITION_START_LBA, TYPE_FAT32_LBA, PartitionEntry

__all__ = ["BadInputError", "CardEntry", "CorruptImageError", "DEFAULT_SIZE_MIB",
           "ImageTooSmallError", "OutputExistsError", "PARTITION_START_LBA", "PartitionEntry",
           "PlacedFile", "SdImageError", "TYPE_FAT32_LBA", "UsageError", "build_image",
           "extract_all", "list_image", "read_file"]
