"""K210 SRAM: 6 MiB general SRAM + 2 MiB AI SRAM, seen cached at 0x8000_0000 and
uncached at 0x4000_0000. One host buffer backs both views and both harts' engines,
and the DMAC reads and writes the same bytes.

Real SRAM powers up with random contents; the model fills it with a fixed
pseudo-random pattern so firmware that forgets to clear .bss misbehaves here
too, yet every run is the same.
"""
from __future__ import annotations

import ctypes
import functools
from typing import Callable

import numpy as np

from ..errors import HardwareMisuse
from ..memory_map import SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE
from .memory_files import memory_file, private_mapping
POWER_ON_SEED = 0x0210


def _draw_power_on_pattern(seed: int) -> np.ndarray:
    # 8 MiB of random bytes: about 10 ms
    return np.random.default_rng(seed).integers(0, 256, SRAM_SIZE, dtype=np.uint8)


@functools.lru_cache(maxsize=2)
def power_on_pattern(seed: int) -> np.ndarray:
    """The SRAM's contents at power-on for `seed` (read-only), drawn once a process."""
    pattern = _draw_power_on_pattern(seed)
    pattern.flags.writeable = False
    return pattern


@functools.lru_cache(maxsize=2)
def _power_on_file(seed: int) -> int | None:
    """A memory-only file holding the power-on pattern of `seed` (memory_files.memory_file), made
    once a process; the file is then the pattern's only copy in the process."""
    return memory_file(f"k210-sram-power-on-{seed:#x}", lambda: _draw_power_on_pattern(seed).tobytes())


def _sram_buffer(fill_seed: int | None) -> ctypes.Array:
    """The host buffer of a new SRAM. With a seed, a private (copy-on-write) mapping of the
    power-on file: a board starts without copying 8 MiB (about 5 ms, paid again by each of a test
    suite's hundreds of boards), and only the pages the firmware writes are copied, when it writes
    them. (The mapping lives as long as the buffer made from it: ctypes keeps it referenced.)"""
    descriptor = _power_on_file(fill_seed) if fill_seed is not None else None
    if descriptor is None:
        buffer = (ctypes.c_uint8 * SRAM_SIZE)()
        if fill_seed is not None:
            np.frombuffer(buffer, dtype=np.uint8)[:] = power_on_pattern(fill_seed)
        return buffer
    return (ctypes.c_uint8 * SRAM_SIZE).from_buffer(private_mapping(descriptor, SRAM_SIZE))


class Sram:
    def __init__(self, fill_seed: int | None = POWER_ON_SEED) -> None:
        self.buffer = _sram_buffer(fill_seed)
        self.bytes = np.frombuffer(self.buffer, dtype=np.uint8)
        # --check-writes: called as write_check(address, length, writer) before a DMA write lands
        self.write_check: Callable[[int, int, str], None] | None = None

    @property
    def address(self) -> int:
        return ctypes.addressof(self.buffer)

    def offset_of(self, address: int, length: int = 1) -> int:
        """Offset in the buffer for a bus address in either view; raises if outside SRAM."""
        for base in (SRAM_BASE, SRAM_UNCACHED_BASE):
            if base <= address and address + length <= base + SRAM_SIZE:
                return address - base
        raise HardwareMisuse(f"DMA access to 0x{address:x}..0x{address + length - 1:x}, which is not SRAM")

    def load(self, address: int, data: bytes) -> None:
        offset = self.offset_of(address, max(1, len(data)))
        self.bytes[offset:offset + len(data)] = np.frombuffer(data, dtype=np.uint8)

    def read(self, address: int, length: int) -> bytes:
        offset = self.offset_of(address, length)
        return self.bytes[offset:offset + length].tobytes()

    def read_items(self, address: int, width: int, count: int, fixed: bool) -> np.ndarray:
        """count little-endian items of `width` bytes (as uint32/uint64), from consecutive
        addresses, or all from one address when `fixed`."""
        dtype = {1: np.uint8, 2: "<u2", 4: "<u4", 8: "<u8"}[width]
        if fixed:
            offset = self.offset_of(address, width)
            item = self.bytes[offset:offset + width].view(dtype)[0]
            return np.full(count, item, dtype=np.uint64 if width == 8 else np.uint32)
        offset = self.offset_of(address, width * count)
        raw = self.bytes[offset:offset + width * count].view(dtype)
        return raw.astype(np.uint64 if width == 8 else np.uint32)

    def write_items(self, address: int, width: int, values: np.ndarray, fixed: bool, writer: str = "DMA") -> None:
        """Writes items of `width` bytes to consecutive addresses, or all to one when `fixed`
        (only the last one stays). `writer` names who writes, for the write checker."""
        dtype = {1: np.uint8, 2: "<u2", 4: "<u4", 8: "<u8"}[width]
        if len(values) == 0:
            return
        if self.write_check is not None:
            length = width if fixed else width * len(values)
            self.offset_of(address, length)          # not SRAM at all: that error comes first
            self.write_check(address, length, writer)
        if fixed:
            offset = self.offset_of(address, width)
            self.bytes[offset:offset + width] = np.array([values[-1]], dtype=dtype).view(np.uint8)
            return
        offset = self.offset_of(address, width * len(values))
        self.bytes[offset:offset + width * len(values)] = values.astype(dtype).view(np.uint8)
