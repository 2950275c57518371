"""--check-writes: an opt-in check that the firmware stores only inside its own buffers.

This is a verification aid of the board model, like a debugger's watchpoint, and not
hardware behaviour: the K210 has no memory protection over its SRAM, so a stray store
silently corrupts whatever lies there. Without the option (the default) the board lets
every store through, as the chip does. With it, the first store outside the firmware's
buffers stops the run with StrayWrite (exit status 10), naming the hart, pc and
instruction (or the DMA channel), the address and size, and the region it hit.

The firmware's buffers, from its ELF (the symbols are k210.ld's and heap.S's):

- the writable PT_LOAD segments: .data and .bss, p_memsz bytes from p_paddr;
- the heap blocks handed out so far, [__heap_start, heap_next), where heap_next is heap.S's
  u64 variable, read live from SRAM at the time of each store (heap.S gives blocks back by
  lowering it, heap_release: a block given back is out of bounds again);
- the storing hart's own stack: hart h owns [__stack_top - (h + 1) S, __stack_top - h S),
  S = __stack_hart0_top - __stack_hart1_top (16 KiB in k210.ld); the trap save area at its top
  is part of it.

Anything else in SRAM is out of bounds; the region a stray store hit is named as:

- "code and constants": a read-only PT_LOAD segment (.text and .rodata);
- "heap not allocated": [heap_next, __heap_end);
- "hart N's stack": the other hart's stack;
- "SRAM the firmware does not own": the rest (the 2 MiB AI SRAM at 0x8060_0000..0x8080_0000
  that the firmware never uses, the padding between its segments).

Both views of SRAM count: a store through the uncached alias at 0x4000_0000 is checked at the
same offset as through 0x8000_0000 (and heap_next may hold an address in either view).

DMA writes into SRAM (the DMAC's memory side: SD card reads, memory-to-memory copies) follow
the same rules, except that no stack is a DMA target: a stack belongs to its hart, and a
transfer can outlive the frame that asked for it. A stray DMA write names the channel.

A program without the heap and stack symbols (__heap_start, __heap_end, heap_next,
__stack_top, __stack_hart0_top, __stack_hart1_top, __stack_bottom), such as the tests' small
programs, gets only its read-only segments checked; the rest of SRAM counts as writable, and
the board warns once that only code and constants are checked.

How: the harts' stores are checked in C over a table of regions that tiles SRAM
(`_write_check.h`): on the fast engine by the interpreter after each store into SRAM, on the
precise engine by a native Unicorn UC_HOOK_MEM_WRITE callback (`_write_watch.c`, one per SRAM
view per hart); a Python hook on every store would be far too slow. The stray store itself
lands (this is a watchpoint, not protection); the hart stops before its next instruction, and
the board turns the record into StrayWrite. Device (MMIO) stores are not SRAM and are not checked here.
"""
from __future__ import annotations

import ctypes
import enum
from dataclasses import dataclass

from unicorn import riscv_const as rv
from unicorn.unicorn_py3 import unicorn as _ucpy

from ..cpu import _write_watch
from .elf import LoadedImage
from ..errors import BadInput
from ..cpu.hart import Hart
from ..memory_map import SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE
from .memory import Sram

WATCH_MAX_REGIONS = 24   # _write_check.h's table size

CODE = "code and constants"
HEAP_UNALLOCATED = "heap not allocated"
UNOWNED = "SRAM the firmware does not own"
DATA = "data and bss"
HEAP = "heap"

HEAP_SYMBOLS = ("__heap_start", "__heap_end", "heap_next")
STACK_SYMBOLS = ("__stack_top", "__stack_hart0_top", "__stack_hart1_top", "__stack_bottom")


def stack_name(hart: int) -> str:
    """The region name of a hart's stack in messages."""
    return f"hart {hart}'s stack"


class Rule(enum.IntEnum):
    """What a region lets a writer do (the numbers are _write_watch.c's)."""

    ALLOW = 0
    FORBID = 1
    HEAP = 2     # allowed below the live heap_next, forbidden from there to the region's end


@dataclass(frozen=True)
class Region:
    """[lo, hi) as SRAM offsets (0 = 0x8000_0000 cached, 0x4000_0000 uncached)."""

    lo: int
    hi: int
    rule: Rule
    name: str


@dataclass(frozen=True)
class WriteLayout:
    """Who may write where: per hart and for the DMAC, regions that tile the whole SRAM in order."""

    harts: list[list[Region]]
    dma: list[Region]
    heap_next_offset: int | None     # SRAM offset of heap_next; None when only code is checked
    missing: tuple[str, ...]          # the symbols that made it code-only (empty: everything checked)


@dataclass(frozen=True)
class Stray:
    """The first store that went astray."""

    address: int        # as stored to (either view)
    size: int
    region: Region
    heap_next: int      # heap_next's value when the store happened (0 if not read)
    pc: int | None      # the store's pc (None for DMA)


def sram_offset(address: int) -> int:
    """Offset in SRAM of an address in either view."""
    for base in (SRAM_BASE, SRAM_UNCACHED_BASE):
        if base <= address < base + SRAM_SIZE:
            return address - base
    raise ValueError(f"0x{address:x} is not in SRAM")


def _offset(address: int, what: str, firmware: str) -> int:
    """SRAM offset of a segment start or a symbol (the end of SRAM allowed, for a stack top)."""
    for base in (SRAM_BASE, SRAM_UNCACHED_BASE):
        if base <= address <= base + SRAM_SIZE:
            return address - base
    raise BadInput(f"--check-writes: {firmware}'s {what} is at 0x{address:x}, outside the K210's SRAM")


def _tile(layers: list[tuple[int, int, Rule, str]]) -> list[Region]:
    """Regions tiling SRAM from (lo, hi, rule, name) layers given as SRAM offsets; later layers
    cover earlier ones; neighbours with the same rule and name merge."""
    clipped = [(max(0, lo), min(SRAM_SIZE, hi), rule, name) for lo, hi, rule, name in layers if hi > lo]
    cuts = sorted({0, SRAM_SIZE} | {x for lo, hi, _, _ in clipped for x in (lo, hi)})
    regions: list[Region] = []
    for lo, hi in zip(cuts, cuts[1:]):
        rule, name = next((r, n) for top_lo, top_hi, r, n in reversed(clipped) if top_lo <= lo and hi <= top_hi)
        if regions and (regions[-1].rule, regions[-1].name) == (rule, name):
            regions[-1] = Region(regions[-1].lo, hi, rule, name)
        else:
            regions.append(Region(lo, hi, rule, name))
    if len(regions) > WATCH_MAX_REGIONS:
        raise BadInput(f"--check-writes: the firmware's memory map has {len(regions)} regions; the checker "
                       f"takes {WATCH_MAX_REGIONS} (_write_check.h WATCH_MAX_REGIONS)")
    return regions


def plan_layout(image: LoadedImage, harts: int, firmware: str = "the firmware") -> WriteLayout:
    """The regions each hart and the DMAC may write, from the ELF's segments and symbols."""
    starts = [_offset(segment.address, "load segment", firmware) for segment in image.segments]
    read_only = [(lo, lo + s.size, Rule.FORBID, CODE) for lo, s in zip(starts, image.segments) if not s.writable]
    writable = [(lo, lo + s.size, Rule.ALLOW, DATA) for lo, s in zip(starts, image.segments) if s.writable]
    symbols = image.symbol_values
    missing = tuple(name for name in HEAP_SYMBOLS + STACK_SYMBOLS if name not in symbols)
    if missing:
        everything = [(0, SRAM_SIZE, Rule.ALLOW, UNOWNED)] + read_only + writable
        return WriteLayout([_tile(everything)] * harts, _tile(everything), None, missing)
    at = {name: _offset(symbols[name], name, firmware) for name in HEAP_SYMBOLS + STACK_SYMBOLS}
    top, hart0_top, hart1_top, bottom = (at[name] for name in STACK_SYMBOLS)
    size = hart0_top - hart1_top
    if top != hart0_top or size <= 0 or top - bottom != harts * size:
        values = ", ".join(f"{name} 0x{symbols[name]:x}" for name in STACK_SYMBOLS)
        raise BadInput(f"--check-writes: {firmware}'s stack symbols disagree: {values} (expected {harts} "
                       f"stacks of __stack_hart0_top - __stack_hart1_top bytes below __stack_top)")
    stacks = [(top - (h + 1) * size, top - h * size) for h in range(harts)]
    heap = (at["__heap_start"], at["__heap_end"])
    base = [(0, SRAM_SIZE, Rule.FORBID, UNOWNED), (*heap, Rule.HEAP, HEAP)]

    def layout(own: int | None) -> list[Region]:
        stack_layers = [(lo, hi, Rule.ALLOW if h == own else Rule.FORBID, stack_name(h))
                        for h, (lo, hi) in enumerate(stacks)]
        return _tile(base + stack_layers + read_only + writable)

    return WriteLayout([layout(h) for h in range(harts)], layout(None), at["heap_next"], ())


def allocated_end(region: Region, heap_next: int) -> int:
    """Where a heap region's allocated part ends, as an SRAM offset (as _write_watch.c does: a
    heap_next outside SRAM, e.g. before heap_init, has handed out nothing)."""
    for base in (SRAM_BASE, SRAM_UNCACHED_BASE):
        if base <= heap_next <= base + SRAM_SIZE:
            return min(max(heap_next - base, region.lo), region.hi)
    return region.lo


def first_stray(regions: list[Region], start: int, end: int, heap_next: int) -> Region | None:
    """The region of the first byte of SRAM offsets [start, end) that may not be written."""
    offset = start
    for region in regions:
        if offset >= region.hi:
            continue
        allowed = {Rule.ALLOW: region.hi, Rule.FORBID: region.lo}.get(region.rule)
        if allowed is None:
            allowed = allocated_end(region, heap_next)
        offset = max(offset, allowed)
        if offset >= end:
            return None
        if offset < region.hi:
            return region
    return None


def describe(stray: Stray) -> str:
    """'<region> [lo, hi)' in cached addresses, and the cached address of an uncached store."""
    region = stray.region
    lo, hi = region.lo, region.hi
    if region.rule is Rule.HEAP:
        lo = allocated_end(region, stray.heap_next)
        name = HEAP_UNALLOCATED
    else:
        name = region.name
    text = f"{name} [0x{SRAM_BASE + lo:08x}, 0x{SRAM_BASE + hi:08x})"
    if region.rule is Rule.HEAP:
        text += f" (heap_next = 0x{stray.heap_next:x})"
    if stray.address < SRAM_BASE:
        text += f"; 0x{stray.address:08x} is the uncached alias of 0x{SRAM_BASE + sram_offset(stray.address):08x}"
    return text


class _Region(ctypes.Structure):
    _fields_ = [("lo", ctypes.c_uint64), ("hi", ctypes.c_uint64), ("rule", ctypes.c_uint64)]


class _Watch(ctypes.Structure):
    """write_watch_t of _write_check.h, field for field."""

    _fields_ = [("cached_base", ctypes.c_uint64), ("uncached_base", ctypes.c_uint64),
                ("sram_size", ctypes.c_uint64), ("sram", ctypes.c_void_p), ("heap_next_offset", ctypes.c_uint64),
                ("counter", ctypes.c_void_p), ("reg_read", ctypes.c_void_p), ("pc_register", ctypes.c_int64),
                ("region_count", ctypes.c_uint64), ("regions", _Region * WATCH_MAX_REGIONS),
                ("stray", ctypes.c_uint64), ("address", ctypes.c_uint64), ("size", ctypes.c_uint64),
                ("pc", ctypes.c_uint64), ("region", ctypes.c_uint64), ("heap_next", ctypes.c_uint64)]


_watch_lib = ctypes.CDLL(_write_watch.__file__)
_CHECK_HOOK = ctypes.cast(_watch_lib.check_write, ctypes.c_void_p).value
_UC_REG_READ = ctypes.cast(_ucpy.uclib.uc_reg_read, ctypes.c_void_p).value


class WriteWatch:
    """The checker of one board: attach each hart, then ask after each turn."""

    def __init__(self, image: LoadedImage, memory: Sram, harts: int, firmware: str = "the firmware") -> None:
        self.layout = plan_layout(image, harts, firmware)
        self.memory = memory
        self._watches: dict[int, tuple[_Watch, list[Region]]] = {}

    @property
    def complete(self) -> bool:
        """Whether the heap and stacks are checked too (not only code and constants)."""
        return not self.layout.missing

    def attach(self, hart: Hart) -> None:
        """Installs the native check on both SRAM views of a hart's engine."""
        regions = self.layout.harts[hart.hart_id]
        watch = _Watch(cached_base=SRAM_BASE, uncached_base=SRAM_UNCACHED_BASE, sram_size=SRAM_SIZE,
                       sram=self.memory.address, heap_next_offset=self.layout.heap_next_offset or 0,
                       counter=hart.counter_address, reg_read=_UC_REG_READ, pc_register=rv.UC_RISCV_REG_PC,
                       region_count=len(regions))
        for n, region in enumerate(regions):
            watch.regions[n] = _Region(region.lo, region.hi, int(region.rule))
        hart.attach_write_watch(watch, _CHECK_HOOK, [(base, base + SRAM_SIZE - 1)
                                                     for base in (SRAM_BASE, SRAM_UNCACHED_BASE)],
                                "the store checker (--check-writes)")
        self._watches[hart.hart_id] = (watch, regions)

    def stray_store(self, hart: Hart) -> Stray | None:
        """The hart's first stray store, if it made one (the hart stopped right after it)."""
        watch, regions = self._watches[hart.hart_id]
        if not watch.stray:
            return None
        return Stray(watch.address, watch.size, regions[watch.region], watch.heap_next, watch.pc)

    def check_dma(self, address: int, length: int) -> Stray | None:
        """A DMA write of `length` bytes at `address` (either view), checked with heap_next as it
        is now; returns what it hit, or None when it stays inside the firmware's buffers."""
        heap_next = 0
        if self.layout.heap_next_offset is not None:
            at = self.layout.heap_next_offset
            heap_next = int.from_bytes(self.memory.bytes[at:at + 8].tobytes(), "little")
        offset = sram_offset(address)
        region = first_stray(self.layout.dma, offset, offset + length, heap_next)
        return None if region is None else Stray(address, length, region, heap_next, None)
