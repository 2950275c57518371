"""The DMAC's way to SRAM with the harts' data caches modelled (caches.py): through the cores' coherence
hub, which probes the caches for each DMA access (_caches.c). SRAM is one copy in the model, so the
data are SRAM's own (board/memory.py); what changes is the caches' state: a line the DMA reads that a
hart holds dirty is written back (the hart keeps it read-only), a line the DMA writes leaves every
cache. docs/design/timing.md ("DMA and the caches") says why the DMA is taken as coherent."""
from __future__ import annotations

import ctypes

import numpy as np

from ..cpu.caches import HartCaches
from ..cpu.native import L1Memory, counter_lib
from .memory import Sram


class CoherentDma:
    """The DMAC's memory (devices/ports.py's DmaMemory): SRAM, with the caches probed on the way."""

    def __init__(self, memory: Sram, caches: list[HartCaches]) -> None:
        self.memory = memory
        self.state = L1Memory()
        self.state.cached_base = caches[0].state.cached_base
        for index, hart_caches in enumerate(caches):
            self.state.harts[index] = ctypes.pointer(hart_caches.state)
        self.caches = caches

    @property
    def write_backs(self) -> int:
        """Dirty lines the DMA's reads and writes had written back first."""
        return self.state.write_backs

    @property
    def invalidations(self) -> int:
        """Cached copies the DMA's writes dropped."""
        return self.state.invalidations

    def read_items(self, address: int, width: int, count: int, fixed: bool) -> np.ndarray:
        length = width if fixed else width * count
        counter_lib.l1_dma_read(ctypes.byref(self.state), self.memory.offset_of(address, length), length)
        return self.memory.read_items(address, width, count, fixed)

    def write_items(self, address: int, width: int, values: np.ndarray, fixed: bool, writer: str = "DMA") -> None:
        self.memory.write_items(address, width, values, fixed, writer)
        if len(values):
            length = width if fixed else width * len(values)
            counter_lib.l1_dma_write(ctypes.byref(self.state), self.memory.offset_of(address, length), length)
