"""Loading a raw firmware image (`firmware.bin`), as kflash writes it to the flash and the
K210's ROM copies it to SRAM at 0x8000_0000: bytes only, no sections and no symbols.

The board model takes an ELF by its magic number; any other file ending in `.bin` is a raw
image. Without an ELF's segments the whole image counts as code (it is scanned for CSR
instructions and polling loops; data that is never executed costs nothing there), and
messages name addresses without symbols.
"""
from __future__ import annotations

from pathlib import Path

from .elf import LoadedImage, Segment, load_elf
from ..errors import BadInput
from ..memory_map import RESET_PC, SRAM_BASE, SRAM_SIZE
from .memory import Sram

ELF_MAGIC = b"\x7fELF"
RAW_SUFFIX = ".bin"


def load_firmware(path: str | Path, memory: Sram) -> LoadedImage:
    """An ELF (by its magic number) or a raw `.bin` image, copied into SRAM. Raises BadInput
    naming what is wrong."""
    path = Path(path)
    if not path.is_file():
        raise BadInput(f"firmware image {path} does not exist (build it with `make firmware`)")
    try:
        with path.open("rb") as handle:
            magic = handle.read(len(ELF_MAGIC))
    except OSError as error:
        raise BadInput(f"{path}: cannot read it ({error.strerror or error})") from None
    if magic == ELF_MAGIC or path.suffix.lower() != RAW_SUFFIX:
        return load_elf(path, memory)
    return load_raw(path, memory)


def load_raw(path: Path, memory: Sram) -> LoadedImage:
    """Copies a raw image to 0x8000_0000, where the ROM puts what it boots."""
    try:
        data = path.read_bytes()
    except OSError as error:
        raise BadInput(f"{path}: cannot read it ({error.strerror or error})") from None
    if not data:
        raise BadInput(f"{path}: the raw image is empty")
    if len(data) > SRAM_SIZE:
        raise BadInput(f"{path}: the raw image is {len(data)} bytes, more than the {SRAM_SIZE} bytes of SRAM "
                       f"at 0x{SRAM_BASE:x} the ROM copies it to")
    return load_program(data, memory)


def load_program(data: bytes, memory: Sram) -> LoadedImage:
    """Copies a program (at most SRAM's size) to 0x8000_0000, as the ROM does."""
    memory.load(RESET_PC, data)
    segment = Segment(RESET_PC, len(data), writable=True, executable=True)
    return LoadedImage(RESET_PC, [(RESET_PC, data)], {}, len(data), [segment], {})
