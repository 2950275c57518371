"""The Dock's on-board SPI NOR flash as a file (`--flash IMAGE`), and the mask ROM's boot from it.

What a file means, by its kind:
- a `.kfpkg` (a zip holding flash-list.json, as kflash and the Maix tools write them): each listed
  `bin` written at its `address`, with the boot header in front of it where `sha256Prefix` is true;
- a `.bin`: a program, written at address 0 with the boot header, as `kflash firmware.bin` (and
  `make flash`) writes it;
- anything else: the flash's content from address 0 (a dump), at most 16 MiB.
Bytes nothing was written to read as erased flash, 0xFF.

The file is read once and never written unless asked: `--flash-writable` writes the flash's 16 MiB
back to a dump when the run ends (a kfpkg or a program cannot take the flash's changes back), and
`--flash-save DUMP` writes them to another file, whatever the image was. Either goes through a
temporary file renamed over the target, so an interrupted save leaves the old file whole.

The boot header (kflash.py's flash_firmware): a flag byte (bit 0: the program is AES-128-CBC
encrypted with the key in OTP; bit 1: the ROM reads the flash in dual-I/O mode), the program's
length as 4 little-endian bytes, the program, and the SHA-256 of everything before it. The mask
ROM checks the hash and copies the program to 0x8000_0000, where both harts start.
"""
from __future__ import annotations

import functools
import hashlib
import io
import json
import mmap
import os
import re
import tempfile
import struct
import zipfile
from dataclasses import dataclass
from pathlib import Path

from ..errors import BadInput
from ..memory_map import SRAM_SIZE
from .memory_files import memory_file, private_mapping

FLASH_SIZE = 16 * 1024 * 1024        # the Dock's W25Q128 (Sipeed's schematic; MicroPython's flash layout)
ERASED = 0xFF
KFPKG_SUFFIX, PROGRAM_SUFFIX = ".kfpkg", ".bin"
KFPKG, PROGRAM, DUMP, ERASED_KIND = "kfpkg", "program", "dump", "erased"
ZIP_MAGIC = b"PK\x03\x04"
HEADER = struct.Struct("<BI")         # flag, program length
HASH_SIZE = 32
FLAG_AES, FLAG_DUAL_IO = 1, 2


@functools.lru_cache(maxsize=1)
def _erased_file() -> int | None:
    return memory_file("k210-erased-flash", lambda: bytes([ERASED]) * FLASH_SIZE)


def erased_bytes() -> bytearray | mmap.mmap:
    """FLASH_SIZE erased bytes to write into: a private mapping of one erased file a process
    (memory_files.py), so that a board whose flash is never written, most of them, fills no 16 MiB
    (a quarter of a small program's board's making); where there is none, a bytearray."""
    descriptor = _erased_file()
    if descriptor is None:
        return bytearray([ERASED]) * FLASH_SIZE
    return private_mapping(descriptor, FLASH_SIZE)


def with_boot_header(program: bytes, flag: int = FLAG_DUAL_IO) -> bytes:
    """What kflash writes at the program's address: flag (by default kflash's: not encrypted, read
    in dual I/O), length, program, SHA-256 of those."""
    data = HEADER.pack(flag, len(program)) + program
    return data + hashlib.sha256(data).digest()


@dataclass
class FlashImage:
    """The flash's 16 MiB; `path` names the file it came from in messages, `kind` what it was (KFPKG,
    PROGRAM or DUMP), `writable` whether the run's changes go back to it (a dump only)."""

    path: Path
    data: bytearray | mmap.mmap       # (erased_bytes)
    kind: str = DUMP
    writable: bool = False

    @staticmethod
    def erased() -> "FlashImage":
        """The flash of a run given no --flash: every byte erased (a Dock's flash holds what was last
        written to it; a run that needs that gives it)."""
        return FlashImage(Path("(erased flash)"), erased_bytes(), kind=ERASED_KIND)

    @staticmethod
    def open(path: str | Path, writable: bool = False) -> "FlashImage":
        """Reads a kfpkg, a program or a dump (module docstring); `writable`: the run's changes go back
        to the file (a dump only). Raises BadInput naming the file and what is wrong with it."""
        path = Path(path)
        if not path.is_file():
            raise BadInput(f"flash image {path} does not exist")
        try:
            raw = path.read_bytes()
        except OSError as error:
            raise BadInput(f"{path}: cannot read it ({error.strerror or error})") from None
        flash = FlashImage(path, erased_bytes())
        if raw.startswith(ZIP_MAGIC) or path.suffix.lower() == KFPKG_SUFFIX:
            flash.kind = KFPKG
            flash._write_package(raw)
        elif path.suffix.lower() == PROGRAM_SUFFIX:
            flash.kind = PROGRAM
            if not raw:
                raise BadInput(f"{path}: the program is empty")
            flash._place(0, with_boot_header(raw), path.name)
        else:
            if len(raw) > FLASH_SIZE:
                raise BadInput(f"{path}: {len(raw)} bytes, more than the Dock's {FLASH_SIZE}-byte flash")
            flash.data[:len(raw)] = raw
        if writable:
            if flash.kind != DUMP:
                raise BadInput(f"--flash-writable: {path} is a {flash.kind} ({'the files' if flash.kind == KFPKG else 'a program'} "
                               f"kflash would write), which cannot take the flash's changes back; keep them with "
                               f"--flash-save DUMP, and run on DUMP with --flash-writable from then on")
            if not os.access(path, os.W_OK) or not os.access(path.resolve().parent, os.W_OK):
                raise BadInput(f"--flash-writable: {path} cannot be written, or its folder cannot take the "
                               f"temporary file a save goes through (permissions)")
            flash.writable = True
        return flash

    def save(self, target: str | Path | None = None) -> Path:
        """Writes the flash's 16 MiB to `target` (else back to the dump it came from, which must be
        writable) through a temporary file in the same folder, flushed to the disk before it takes the
        target's name; a symbolic link's target is written, and an existing file keeps its
        permissions. Raises BadInput if it cannot."""
        target = (Path(target) if target is not None else self.path).resolve()
        if target == self.path.resolve() and not self.writable:
            raise BadInput(f"--flash-save {target}: that is the --flash image, opened read-only; to write the "
                           f"flash back to it, give --flash-writable (a dump only)")
        try:
            mode = target.stat().st_mode & 0o7777 if target.exists() else None
            handle, temporary = tempfile.mkstemp(prefix=f".{target.name}.", dir=target.parent)
            try:
                with os.fdopen(handle, "wb") as out:
                    out.write(self.data)
                    out.flush()
                    os.fsync(out.fileno())
                if mode is not None:
                    os.chmod(temporary, mode)
                os.replace(temporary, target)
            except BaseException:
                os.unlink(temporary)
                raise
        except OSError as error:
            raise BadInput(f"cannot save the flash to {target} ({error.strerror or error})") from None
        return target

    def _place(self, address: int, data: bytes, what: str) -> None:
        if address < 0 or address + len(data) > FLASH_SIZE:
            raise BadInput(f"{self.path}: {what} ({len(data)} bytes at 0x{address:x}) does not fit in the "
                           f"Dock's {FLASH_SIZE}-byte flash")
        self.data[address:address + len(data)] = data

    def _write_package(self, raw: bytes) -> None:
        """A kfpkg: flash-list.json's files, in its order (a later one overwrites an earlier)."""
        try:
            package = zipfile.ZipFile(io.BytesIO(raw))
            names = set(package.namelist())
            if "flash-list.json" not in names:
                raise BadInput(f"{self.path}: a kfpkg holds flash-list.json at its root; this one does not")
            listing = package.read("flash-list.json").decode("utf-8", errors="replace")
            # kflash quotes bare hexadecimal addresses ("address": 0x100000,) before parsing: so do we
            listing = re.sub(r'"address"\s*:\s*(0[xX][0-9a-fA-F]+)', r'"address": "\1"', listing)
            try:
                files = json.loads(listing)["files"]
            except (ValueError, KeyError, TypeError) as error:
                raise BadInput(f"{self.path}: flash-list.json is not a kfpkg listing ({error})") from None
            for n, entry in enumerate(files):
                try:
                    name, address, prefix = entry["bin"], entry["address"], bool(entry.get("sha256Prefix", False))
                    address = int(address, 0) if isinstance(address, str) else int(address)
                except (KeyError, TypeError, ValueError):
                    raise BadInput(f"{self.path}: flash-list.json's file {n + 1} needs a \"bin\" and an "
                                   f"\"address\" (a number)") from None
                if name not in names:
                    raise BadInput(f"{self.path}: flash-list.json names {name}, which the package does not hold")
                data = package.read(name)
                self._place(address, with_boot_header(data) if prefix else data, name)
        except zipfile.BadZipFile as error:
            raise BadInput(f"{self.path}: not a readable kfpkg (zip) file ({error})") from None

    def boot_program(self) -> bytes:
        """The program the mask ROM boots: the one behind the boot header at address 0. Raises
        BadInput where the ROM would not boot it."""
        flag, length = HEADER.unpack_from(self.data, 0)
        where = f"{self.path}: the program at flash address 0"
        if flag & ~(FLAG_AES | FLAG_DUAL_IO):
            raise BadInput(f"{where} has no boot header (its first byte is 0x{flag:02x}, not a flag 0-3: "
                           f"an erased or data-only flash; write a program with kflash or pass it as a .bin)")
        if flag & FLAG_AES:
            raise BadInput(f"{where} is AES-encrypted; the key lives in the K210's OTP, which the model "
                           f"does not have")
        if length == 0 or length > SRAM_SIZE or HEADER.size + length + HASH_SIZE > FLASH_SIZE:
            raise BadInput(f"{where}: its header gives a length of {length} bytes (the ROM copies at most "
                           f"the {SRAM_SIZE} bytes of SRAM)")
        end = HEADER.size + length
        if hashlib.sha256(self.data[:end]).digest() != bytes(self.data[end:end + HASH_SIZE]):
            raise BadInput(f"{where}: the SHA-256 after it does not match its {length} bytes (the ROM would "
                           f"refuse to boot it: a damaged or partly written flash)")
        return bytes(self.data[HEADER.size:end])
