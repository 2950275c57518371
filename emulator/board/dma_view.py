"""SRAM as the DMAC sees it when the harts' data caches are modelled (caches.py): the DMA is not coherent
with them. The K210's DMAC reaches SRAM over the AXI bus around the cores' L1 caches (the SDK stages
every DMA buffer through the uncached view 0x4000_0000 since its "Fix cache" change for that reason),
so a DMA read of a line a hart holds written finds SRAM's bytes from before the hart's stores, and a
DMA write to a line a hart holds leaves the hart reading its cached copy until the line leaves its
cache. The bookkeeping is _caches.h's and _caches.c's, line by line; this is the DMAC's port to it
(devices/ports.py's DmaMemory) and what a chip reset does to it."""
from __future__ import annotations

import ctypes
from typing import Callable

import numpy as np

from ..cpu.caches import LINE_BYTES, HartCaches
from ..cpu.native import L1Memory, counter_lib
from .memory import Sram

_DTYPES = {1: np.uint8, 2: "<u2", 4: "<u4", 8: "<u8"}


class SramBehindCaches:
    """The DMAC's memory: SRAM itself, beside what the harts see through their data caches."""

    def __init__(self, memory: Sram, caches: list[HartCaches], warn: Callable[[str], None] | None = None) -> None:
        """warn: told once a run for each of the two kinds of stale line (the DMA reading older bytes
        than a hart holds, or writing a line a hart holds), since on the chip either goes unseen."""
        self.memory = memory
        self.warn = warn
        self._warned: set[str] = set()
        size = len(memory.bytes)
        self.sram = np.zeros(size, dtype=np.uint8)                  # SRAM's bytes of shadowed lines
        self.shadowed = np.zeros(size // LINE_BYTES, dtype=np.uint8)
        self.state = L1Memory()
        self.state.view = memory.bytes.ctypes.data
        self.state.sram = self.sram.ctypes.data
        self.state.shadowed = self.shadowed.ctypes.data
        self.state.size = size
        self.state.cached_base = caches[0].state.cached_base
        for index, hart_caches in enumerate(caches):
            self.state.harts[index] = ctypes.pointer(hart_caches.state)
            hart_caches.state.memory = ctypes.pointer(self.state)
        self.caches = caches

    @property
    def stale_reads(self) -> int:
        """Lines a DMA read found different in SRAM from what a hart's cache holds."""
        return self.state.stale_reads

    @property
    def stale_writes(self) -> int:
        """Lines a DMA wrote while a hart's cache held other bytes for them."""
        return self.state.stale_writes

    def read_items(self, address: int, width: int, count: int, fixed: bool) -> np.ndarray:
        length = width if fixed else width * count
        offset = self.memory.offset_of(address, length)
        raw = np.empty(length, dtype=np.uint8)
        before = self.state.stale_reads
        counter_lib.l1_dma_read(ctypes.byref(self.state), offset, length, raw.ctypes.data)
        if self.state.stale_reads != before:
            self._tell("read", f"the DMA read 0x{address:08x}..0x{address + length - 1:08x}, where a hart's data "
                               f"cache holds bytes not yet written back: it read SRAM's older ones")
        items = raw.view(_DTYPES[width]).astype(np.uint64 if width == 8 else np.uint32)
        return np.full(count, items[0], dtype=items.dtype) if fixed else items

    def write_items(self, address: int, width: int, values: np.ndarray, fixed: bool, writer: str = "DMA") -> None:
        if len(values) == 0:
            return
        if fixed:
            values = values[-1:]          # only the last one stays
        length = width * len(values)
        offset = self.memory.offset_of(address, length)
        if self.memory.write_check is not None:
            self.memory.write_check(address, length, writer)
        data = np.ascontiguousarray(values.astype(_DTYPES[width]).view(np.uint8))
        before = self.state.stale_writes
        counter_lib.l1_dma_write(ctypes.byref(self.state), offset, data.ctypes.data, length)
        if self.state.stale_writes != before:
            self._tell("write", f"{writer} wrote 0x{address:08x}..0x{address + length - 1:08x}, where a hart's data "
                                f"cache holds the line: the hart goes on reading its own copy")

    def _tell(self, kind: str, what: str) -> None:
        if self.warn is not None and kind not in self._warned:
            self._warned.add(kind)
            self.warn(f"{what} (the K210's DMA is not coherent with the caches: write lines back with FENCE.I "
                      f"before a DMA reads them, read a DMA's buffer through the uncached view 0x4000_0000; "
                      f"docs/guide/your-own-firmware.md; told once a run)")

    def reset(self) -> None:
        """A chip reset: the caches lose their lines, dirty or not, so the harts see SRAM's own bytes."""
        for index in np.flatnonzero(self.shadowed):
            start = int(index) * LINE_BYTES
            self.memory.bytes[start:start + LINE_BYTES] = self.sram[start:start + LINE_BYTES]
        self.shadowed[:] = 0
