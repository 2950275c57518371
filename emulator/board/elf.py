"""Loading a firmware ELF the way the K210 boot ROM places it: every loadable
segment's bytes at its physical address in SRAM; both harts then start at
0x8000_0000 whatever the ELF's entry field says."""
from __future__ import annotations

import functools
import struct
from dataclasses import dataclass, field
from pathlib import Path

from elftools.common.exceptions import ELFError
from elftools.elf.constants import P_FLAGS, SH_FLAGS
from elftools.elf.elffile import ELFFile

from ..errors import BadInput
from ..memory_map import SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE
from .memory import Sram

EM_RISCV = "EM_RISCV"


@dataclass(frozen=True)
class Segment:
    """A PT_LOAD segment as it sits in SRAM: `size` is p_memsz (.bss included)."""
    address: int
    size: int
    writable: bool
    executable: bool


@dataclass
class LoadedImage:
    entry: int
    code_ranges: list[tuple[int, bytes]]   # executable segments (address, bytes) for CSR scanning
    symbols: dict[int, str]
    image_bytes: int
    segments: list[Segment] = field(default_factory=list)          # every PT_LOAD with p_memsz > 0
    symbol_values: dict[str, int] = field(default_factory=dict)    # every named symbol (linker ones too)


def _in_sram(address: int, length: int) -> bool:
    return any(base <= address and address + length <= base + SRAM_SIZE for base in (SRAM_BASE, SRAM_UNCACHED_BASE))


def load_elf(path: str | Path, memory: Sram) -> LoadedImage:
    """Copies the ELF's loadable segments into SRAM. Raises BadInput naming what is wrong."""
    path = Path(path)
    if not path.is_file():
        raise BadInput(f"firmware image {path} does not exist (build it with `make firmware`)")
    try:
        with path.open("rb") as handle:
            elf = ELFFile(handle)
            if elf.header["e_machine"] != EM_RISCV or elf.elfclass != 64:
                raise BadInput(f"{path}: not a 64-bit RISC-V ELF (machine {elf.header['e_machine']}, "
                               f"class {elf.elfclass})")
            size = path.stat().st_size
            code_ranges, segments, loaded, total = [], [], [], 0
            for number, segment in enumerate(elf.iter_segments()):
                if segment["p_type"] == "PT_LOAD":
                    _check_segment(path, number, segment, size)
                if segment["p_type"] == "PT_LOAD" and segment["p_memsz"] > 0:
                    segments.append(Segment(segment["p_paddr"], segment["p_memsz"],
                                            bool(segment["p_flags"] & P_FLAGS.PF_W),
                                            bool(segment["p_flags"] & P_FLAGS.PF_X)))
                if segment["p_type"] != "PT_LOAD" or segment["p_filesz"] == 0:
                    continue
                address, data = segment["p_paddr"], segment.data()
                if not _in_sram(address, len(data)):
                    raise BadInput(f"{path}: segment at 0x{address:x} ({len(data)} bytes) lies outside the "
                                   f"K210's 8 MiB SRAM at 0x{SRAM_BASE:x}")
                memory.load(address, data)
                total += len(data)
                loaded.append((address, data))
                if segment["p_flags"] & P_FLAGS.PF_X:
                    code_ranges.append((address, data))
            if not code_ranges:
                code_ranges = _code_by_sections(elf, loaded)
            if not code_ranges:
                raise BadInput(f"{path}: no executable segment to run")
            symbols, values = _symbol_tables(elf, size)
            return LoadedImage(elf.header["e_entry"], code_ranges, symbols, total, segments, values)
    except (ELFError, ValueError, OverflowError, MemoryError, struct.error) as error:
        raise BadInput(f"{path}: not a valid ELF file ({type(error).__name__}: {error})") from None
    except OSError as error:
        raise BadInput(f"{path}: cannot read it ({error.strerror or error})") from None


def _check_segment(path: Path, number: int, segment, file_size: int) -> None:
    """A PT_LOAD's fields against the file and SRAM, before any of its bytes are read: its file
    bytes inside the file, no more of them than its memory size, all of it (.bss too) in SRAM."""
    offset, filesz, memsz, address = (segment["p_offset"], segment["p_filesz"], segment["p_memsz"],
                                      segment["p_paddr"])
    where = f"{path}: program header {number} (PT_LOAD at 0x{address:x})"
    if offset + filesz > file_size:
        raise BadInput(f"{where}: p_offset 0x{offset:x} + p_filesz 0x{filesz:x} run past the file's "
                       f"{file_size} bytes (a cut or damaged ELF)")
    if filesz > memsz:
        raise BadInput(f"{where}: p_filesz 0x{filesz:x} is more than p_memsz 0x{memsz:x}")
    if memsz and not _in_sram(address, memsz):
        raise BadInput(f"{where}: its {memsz} bytes (p_memsz) do not lie in the K210's 8 MiB SRAM at "
                       f"0x{SRAM_BASE:x} (or its uncached view at 0x{SRAM_UNCACHED_BASE:x})")


def _code_by_sections(elf: ELFFile, loaded: list[tuple[int, bytes]]) -> list[tuple[int, bytes]]:
    """The loaded segments that hold an executable section, for an ELF whose program headers
    carry no execute flag (riscv-tests' linker script gives its one segment none). The boot ROM
    never looks at the flags, so such an image runs on the chip, and runs here."""
    code = [(section["sh_addr"], section["sh_size"]) for section in elf.iter_sections()
            if section["sh_flags"] & SH_FLAGS.SHF_EXECINSTR and section["sh_size"]]
    return [(address, data) for address, data in loaded
            if any(address <= start < address + len(data) for start, _ in code)]


# Elf64_Sym: st_name, st_info, st_other, st_shndx, st_value, st_size (System V ABI, "Symbol Table")
_ELF64_SYM = struct.Struct("<IBBHQQ")
_STT_NOTYPE, _STT_FUNC = 0, 2
_SHN_ABS = 0xFFF1


def _symbol_tables(elf: ELFFile, file_size: int) -> tuple[dict[int, str], dict[str, int]]:
    """(address -> name of code and label symbols, for pc reports; name -> value of every
    named symbol). The table is unpacked in one pass over its bytes: pyelftools parses each
    symbol on its own, a third of a second for our firmware, paid by every run."""
    symbols: dict[int, str] = {}
    values: dict[str, int] = {}
    symtab = elf.get_section_by_name(".symtab")
    if symtab is None:
        return symbols, values
    if symtab["sh_entsize"] != _ELF64_SYM.size:
        raise ValueError(f".symtab entries of {symtab['sh_entsize']} bytes, not {_ELF64_SYM.size}")
    strtab = elf.get_section(symtab["sh_link"])
    for section in (symtab, strtab):
        if section["sh_offset"] + section["sh_size"] > file_size:
            raise ValueError(f"section {section.name or '?'} (sh_offset 0x{section['sh_offset']:x}, sh_size "
                             f"0x{section['sh_size']:x}) runs past the file's {file_size} bytes")
    symbols, values = _symbols_of(symtab.data(), strtab.data())
    return dict(symbols), dict(values)


@functools.lru_cache(maxsize=8)
def _symbols_of(data: bytes, strtab: bytes) -> tuple[dict[int, str], dict[str, int]]:
    """_symbol_tables' work on a .symtab and its string table, once a process for the same bytes
    (every board of a firmware reads them); the callers get copies."""
    symbols: dict[int, str] = {}
    values: dict[str, int] = {}
    for st_name, st_info, _, st_shndx, st_value, _ in _ELF64_SYM.iter_unpack(data[:len(data) - len(data) % _ELF64_SYM.size]):
        if not st_name:
            continue
        end = strtab.find(b"\0", st_name)
        name = strtab[st_name:end if end >= 0 else len(strtab)].decode("utf-8", "replace")
        if not name or name.startswith("$"):
            continue
        values.setdefault(name, st_value)
        # places in the program name pcs and addresses; an absolute symbol (an .equ constant such
        # as a limit that happens to look like an address) names none
        if st_info & 0xF in (_STT_NOTYPE, _STT_FUNC) and st_value and st_shndx != _SHN_ABS:
            symbols.setdefault(st_value, name)
    return symbols, values


def read_symbol_values(path: str | Path) -> dict[str, int]:
    """Every named symbol of an ELF and its value, without loading it anywhere (for checking
    a command line before a run). Raises BadInput as load_elf does."""
    path = Path(path)
    if not path.is_file():
        raise BadInput(f"firmware image {path} does not exist (build it with `make firmware`)")
    try:
        with path.open("rb") as handle:
            return _symbol_tables(ELFFile(handle), path.stat().st_size)[1]
    except (ELFError, ValueError, OverflowError, MemoryError, struct.error) as error:
        raise BadInput(f"{path}: not a valid ELF file ({type(error).__name__}: {error})") from None
    except OSError as error:
        raise BadInput(f"{path}: cannot read it ({error.strerror or error})") from None


def symbolize(symbols: dict[int, str], address: int) -> str:
    """'name+0xoff' for the nearest symbol at or below address, or '' if none."""
    best = None
    for start in symbols:
        if start <= address and (best is None or start > best):
            best = start
    if best is None or address - best > 0x10000:
        return ""
    offset = address - best
    return symbols[best] + (f"+0x{offset:x}" if offset else "")
