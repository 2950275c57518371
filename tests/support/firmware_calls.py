"""Calling one firmware routine by its symbol on the board model's CPU, for unit tests of
individual routines (tests/firmware_routines/test_clipping_routines.py).

The board is built on the firmware ELF (Board loads its segments into SRAM) but its boot is
never run: hart 0's Unicorn engine is used directly, through the hart's own `Hart.run`, so the
board's instruction budget guards every call against a routine that never returns. A call is
set up the way the lp64d calling convention says, with what boot.S would have done first:

- .bss cleared (the board fills SRAM with a power-on pattern; routines read `scene` fields in
  .bss, e.g. project_clip's SCENE_SNAP, 0 = subpixel, boot's value until the scene is loaded),
- the FPU on (mstatus.FS = Initial, boot.S; Unicorn traps F/D instructions otherwise), fcsr = 0
  (round to nearest even, no flags),
- sp inside hart 0's stack, ra at a `wfi` written into the heap, where the call ends: Hart.run
  stops after a wfi and says so (RunEnd.WFI).

After the call the lp64d callee-saved registers (sp, s0..s11, fs0..fs11) must hold what they
held before: every routine's header says "Clobbers: only ABI temporaries", and a violation
would corrupt its callers on the real board, so `call` checks that on every call.

Float registers: Unicorn 2.1.4 exposes the 64-bit f registers (UC_RISCV_REG_F0..F31), and
single-precision arguments are NaN-boxed here (upper 32 bits all ones, as the F extension
requires of a value read as single). Single results read back with a zero upper half (the
QEMU 5.0 that Unicorn 2.1.4 is built on did not NaN-box them yet), so results are read as
their low 32 bits.
"""
from __future__ import annotations

import functools
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np
from elftools.elf.elffile import ELFFile
from unicorn import riscv_const as rv

from emulator.board import Board
from emulator.board.elf import symbolize
from emulator.cpu.hart import RunEnd
from emulator.cpu.riscv import EXCEPTION_NAMES, INSN_WFI

MSTATUS_FS_INITIAL = 1 << 13          # mstatus.FS = 01 (boot.S MSTATUS_FS_INITIAL)
NAN_BOX = 0xFFFF_FFFF_0000_0000       # upper half of an f register holding a single
STACK_MARGIN = 1024                   # sp this far below __stack_hart0_top (16-aligned)
SENTINEL_OFFSET = 0                   # the wfi the routine returns to: first word of the heap
SCRATCH_OFFSET = 64                   # scratch memory for tests starts this far into the heap
DEFAULT_BUDGET = 200_000              # instructions one call may take before it counts as hung
ARGUMENT_REGISTERS = 8                # a0..a7, fa0..fa7
# the lp64d callee-saved registers: s0, s1 = x8, x9 and s2..s11 = x18..x27, the same numbers
# of the f registers for fs0..fs11
SAVED_NUMBERS = (8, 9, *range(18, 28))
POISON = 0x5A5A_5A5A_5A5A_5A5A        # argument registers a call does not set


def f32(value: float) -> np.float32:
    """value rounded to single precision (to nearest, ties to even)."""
    return np.float32(value)


def f32_bits(value: float) -> int:
    """The IEEE single bit pattern of value rounded to single precision."""
    return int(np.array([value], dtype=np.float32).view(np.uint32)[0])


def bits_f32(bits: int) -> np.float32:
    """The single whose bit pattern is the low 32 bits of `bits`."""
    return np.array([bits & 0xFFFF_FFFF], dtype=np.uint32).view(np.float32)[0]


def signed(value: int, bits: int = 64) -> int:
    """A register value read as a two's complement integer of `bits` bits."""
    value &= (1 << bits) - 1
    return value - (1 << bits) if value >> (bits - 1) else value


@dataclass(frozen=True)
class CallResult:
    """Registers after a call: a0..a7 (unsigned 64-bit) and fa0..fa7 (single bit patterns)."""

    a: tuple[int, ...]
    fa_bits: tuple[int, ...]
    instructions: int

    def fa(self, n: int) -> np.float32:
        """fa<n> as a single."""
        return bits_f32(self.fa_bits[n])

    def a_signed(self, n: int, bits: int = 64) -> int:
        """a<n> as a signed integer of `bits` bits (32: a w-instruction's result)."""
        return signed(self.a[n], bits)


ELF64_SYMBOL = struct.Struct("<IBBHQQ")     # st_name, st_info, st_other, st_shndx, st_value, st_size


def elf_symbols(path: Path) -> dict[str, set[int]]:
    """Every named symbol of the ELF (file-local labels and .equ constants too) -> its values.
    A name defined in several files with different values maps to all of them. The symbol
    table is read as the array of ELF64 entries it is (the firmware's has about 8,700: pyelftools
    takes half a second to parse them one by one), once per file version."""
    stat = Path(path).stat()
    return {name: set(found) for name, found in _elf_symbols(str(path), stat.st_mtime_ns, stat.st_size).items()}


@functools.lru_cache(maxsize=8)
def _elf_symbols(path: str, mtime_ns: int, size: int) -> dict[str, frozenset[int]]:
    values: dict[str, set[int]] = {}
    with open(path, "rb") as handle:
        elf = ELFFile(handle)
        assert elf.elfclass == 64 and elf.little_endian, f"{path}: not a little-endian ELF64"
        symtab = elf.get_section_by_name(".symtab")
        names = elf.get_section(symtab["sh_link"]).data()
        for name_offset, _, _, _, value, _ in ELF64_SYMBOL.iter_unpack(symtab.data()):
            name = names[name_offset:names.index(b"\0", name_offset)].decode()
            if name and not name.startswith("$"):
                values.setdefault(name, set()).add(value)
    return {name: frozenset(found) for name, found in values.items()}


class FirmwareCaller:
    """The firmware image on a board model whose hart 0 runs single routines on request."""

    def __init__(self, elf: Path, check_writes: bool = False) -> None:
        self.elf = Path(elf)
        self.board = Board(str(self.elf), check_writes=check_writes)
        self.hart = self.board.harts[0]
        self.uc = self.hart.uc
        self._symbols = elf_symbols(self.elf)
        bss_start, bss_end = self.symbol("__bss_start"), self.symbol("__bss_end")
        self.write(bss_start, bytes(bss_end - bss_start))
        self.uc.reg_write(rv.UC_RISCV_REG_MSTATUS, self.uc.reg_read(rv.UC_RISCV_REG_MSTATUS) | MSTATUS_FS_INITIAL)
        self.uc.reg_write(rv.UC_RISCV_REG_FCSR, 0)
        heap = self.symbol("__heap_start")
        self.return_address = heap + SENTINEL_OFFSET
        self.write(self.return_address, INSN_WFI.to_bytes(4, "little"))
        self.scratch = heap + SCRATCH_OFFSET
        self.stack_pointer = (self.symbol("__stack_hart0_top") - STACK_MARGIN) & ~15

    # --- symbols -------------------------------------------------------------------------

    def symbol(self, name: str) -> int:
        """The value of a symbol (an address, or an .equ constant); raises KeyError when the ELF
        has no such name and ValueError when it has the name with different values."""
        values = self._symbols[name]
        if len(values) != 1:
            raise ValueError(f"{name} has several values in {self.elf}: {sorted(hex(v) for v in values)}")
        return next(iter(values))

    # --- memory --------------------------------------------------------------------------

    def write(self, address: int, data: bytes) -> None:
        self.board.memory.load(address, data)

    def read(self, address: int, length: int) -> bytes:
        return self.board.memory.read(address, length)

    def write_f32(self, address: int, values: Iterable[float]) -> None:
        """Stores values as consecutive singles (each rounded to single precision)."""
        self.write(address, np.asarray(list(values), dtype="<f4").tobytes())

    def read_f32(self, address: int, count: int) -> np.ndarray:
        return np.frombuffer(self.read(address, 4 * count), dtype="<f4").astype(np.float32)

    # --- calls ---------------------------------------------------------------------------

    def call(self, routine: str | int, args: Sequence[int] = (), fargs: Sequence[float] = (),
             budget: int = DEFAULT_BUDGET) -> CallResult:
        """Runs the routine (a symbol or an address) with a0.. = args (integers, taken modulo
        2^64) and fa0.. = fargs (rounded to single, NaN-boxed) until it returns. Raises
        AssertionError when it traps, runs past `budget` instructions, returns anywhere but to
        its caller, or changes a callee-saved register."""
        assert len(args) <= ARGUMENT_REGISTERS and len(fargs) <= ARGUMENT_REGISTERS
        uc, hart = self.uc, self.hart
        address = self.symbol(routine) if isinstance(routine, str) else routine
        for n in range(ARGUMENT_REGISTERS):
            uc.reg_write(rv.UC_RISCV_REG_X10 + n, (args[n] if n < len(args) else POISON) & (2**64 - 1))
            bits = f32_bits(fargs[n]) | NAN_BOX if n < len(fargs) else POISON
            uc.reg_write(rv.UC_RISCV_REG_F10 + n, bits)
        saved = {"sp": (rv.UC_RISCV_REG_SP, self.stack_pointer)}
        for index, n in enumerate(SAVED_NUMBERS):
            saved[f"s{index}"] = (rv.UC_RISCV_REG_X0 + n, POISON ^ (n * 0x0101_0101))
            saved[f"fs{index}"] = (rv.UC_RISCV_REG_F0 + n, POISON ^ (n * 0x0303_0303_0000))
        for register, value in saved.values():
            uc.reg_write(register, value)
        uc.reg_write(rv.UC_RISCV_REG_RA, self.return_address)
        hart.pending_exception = None
        hart.pc = address
        end, ran = hart.run(budget)
        if end is RunEnd.EXCEPTION:
            trap = hart.pending_exception
            raise AssertionError(f"{routine} trapped: {EXCEPTION_NAMES.get(trap.cause, trap.cause)} at "
                                 f"{symbolize(self.board.image.symbols, trap.epc) or hex(trap.epc)} "
                                 f"(tval 0x{trap.tval:x})")
        def where() -> str:    # (named only in a failure's message: symbolize is slow for every call)
            return symbolize(self.board.image.symbols, hart.pc) or hex(hart.pc)

        assert end is RunEnd.WFI, f"{routine} did not return within {budget} instructions ({end.value}, at {where()})"
        assert hart.pc == self.return_address + 4, f"{routine} ended at {where()}, not at its return address"
        for name, (register, value) in saved.items():
            now = uc.reg_read(register)
            assert now == value, f"{routine} changed callee-saved {name}: 0x{value:x} -> 0x{now:x}"
        return CallResult(tuple(uc.reg_read(rv.UC_RISCV_REG_X10 + n) for n in range(ARGUMENT_REGISTERS)),
                          tuple(uc.reg_read(rv.UC_RISCV_REG_F10 + n) & 0xFFFF_FFFF
                                for n in range(ARGUMENT_REGISTERS)),
                          ran)
