"""Each hart's L1 caches for timing (_caches.h carries them out in both engines): their geometry, what a
miss costs and where each figure comes from.

Geometry (facts): 32 KiB instruction and 32 KiB data cache per core (the K210 datasheet's CPU table),
64-byte lines (Linux's and U-Boot's k210.dtsi: `d-cache-block-size = <64>`). Inferred: 64 sets of 8
ways. Rocket indexes its L1 within a 4 KiB page when the core has virtual memory (rocket-chip 2017,
HellaCache.scala and ICache.scala: `require(untagBits <= pgIdxBits)`), and the K210 has Sv39, so
32 KiB needs 8 ways. Replacement is random, a 16-bit LFSR advanced per miss (RandomReplacement). The
data cache is write-back and write-allocate and blocks on a miss (DCache.scala, the blocking cache
of rocket-chip's DefaultConfig). A load acquires its line read-only, so a store to a line only read
so far misses once more for write permission (TileLink's BtoT, as rocket-chip of early 2017 does
it); the coherence hub probes the other hart's cache at each acquire. docs/design/timing.md has the
table with sources.

What a miss costs is not published for the K210 (no miss latency, memory bandwidth or uncached-access
figure was found). The figures below are built from the bus's known widths and two estimated
latencies, and the calibration (issue 31) compares whole programs against measurements:

- a line is 8 beats of 8 bytes: rocket-chip's TileLink to memory is XLen/8 = 8 bytes wide
  (Configs.scala, L1toL2 beatBytes), and the SDK's platform.h puts SRAM on the 64-bit AXI;
- BUS_ROUND_TRIP, from a request leaving the cache to the first beat coming back (the TileLink to
  AXI4 bridge each way and SRAM's read): estimated at 6 cycles, SRAM's clock being the CPU's;
- REPLAY: the blocking data cache nacks the access that missed and Rocket replays it from the
  write-back stage, refetching it through the 2-cycle instruction cache: a mispredict's 3 cycles
  (redirect from memory, timing.py) and one more.

A device register access leaves the core as the uncached view's does (a TileLink Get or Put, one in
flight: HellaCache.scala's nMMIOs = 1, which DCache.scala's maxUncachedInFlight follows, a second access
nacked and replayed until the first is answered),
and costs that round trip plus the path to the bus its registers sit on (memory_map.py, from the SDK's
platform.h). No latency is published for any of them; estimated, each crossing a cycle each way:

- TileLink (CLINT, PLIC, UARTHS, GPIOHS): Rocket's own bus, without the TileLink-to-AXI crossing the
  uncached view pays: TILELINK_SAVING cycles less;
- AXI (the FFT's registers): as the uncached view;
- AHB (the DMAC): the AXI-to-AHB bridge, AHB_BRIDGE cycles more;
- APB0/1/2 (every other block): the AXI-to-APB bridge, APB_BRIDGE cycles more, and the APB transfer's
  setup and access phases, two cycles of the APB's clock (AMBA APB Protocol Specification; the
  DesignWare blocks add no wait states), so 2 x SYSCTL's divider of that APB (1 at reset).

The flat charge is what a driver's register accesses see: Rocket does not wait for a lone device
store, nor for a load until its value is used, but drivers use a status at once and make the next
access to the device at once, which waits for the one before it.
"""
from __future__ import annotations

import ctypes
from dataclasses import dataclass

from ..memory_map import AHB, APBS, AXI, SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE, TILELINK
from .native import L1_DEVICE_WINDOWS, L1_LINE_SHIFT, L1_SETS, L1_WAYS, L1Caches

LINE_BYTES = 1 << L1_LINE_SHIFT
BEAT_BYTES = 8
LINE_BEATS = LINE_BYTES // BEAT_BYTES
BUS_ROUND_TRIP = 6        # estimated: see the module's docstring
REPLAY = 4                # Rocket's replay of the access that missed
ICACHE_LATENCY = 2        # Frontend.scala: ICache(latency = 2): the fetch read again once the line is in
# FENCE.I's flush walk reads one way's metadata at most every third cycle (DCache.scala: s1_flush_valid
# only when neither s1 nor s2 holds one)
FLUSH_PER_WAY = 3
LFSR_RESET = 1            # Chisel's LFSR16 starts at 1
TILELINK_SAVING = 2       # estimated: see the module's docstring
AHB_BRIDGE = 2            # estimated
APB_BRIDGE = 2            # estimated
APB_TRANSFER = 2          # AMBA APB: setup and access phases, in the APB's clock cycles
APB_DIVIDER_MAX = 8       # SYSCTL's apbN_clk_sel is 3 bits: ACLK / 1 .. 8


@dataclass(frozen=True)
class L1Timing:
    """Cycles beyond a hit: a data miss (the line's refill, the replay), a dirty victim's write-back
    before it, an instruction miss, one access to SRAM's uncached view."""
    data_fill: int = BUS_ROUND_TRIP + LINE_BEATS + REPLAY
    write_back: int = BUS_ROUND_TRIP + LINE_BEATS
    fetch_fill: int = BUS_ROUND_TRIP + LINE_BEATS + ICACHE_LATENCY
    uncached: int = BUS_ROUND_TRIP + 1 + REPLAY
    flush_per_way: int = FLUSH_PER_WAY
    tilelink: int = BUS_ROUND_TRIP + 1 + REPLAY - TILELINK_SAVING
    axi: int = BUS_ROUND_TRIP + 1 + REPLAY
    ahb: int = BUS_ROUND_TRIP + 1 + REPLAY + AHB_BRIDGE

    def apb(self, divider: int) -> int:
        """An APB register access with the APB clocked at ACLK / divider."""
        return self.axi + APB_BRIDGE + APB_TRANSFER * divider

    def device(self, bus: str, apb_dividers: tuple[int, int, int]) -> int:
        """Cycles a register access on `bus` (memory_map's names) takes beyond a cache hit."""
        if bus in APBS:
            return self.apb(apb_dividers[APBS.index(bus)])
        return {TILELINK: self.tilelink, AXI: self.axi, AHB: self.ahb}[bus]

    @property
    def worst_instruction(self) -> int:
        """The most a load's, store's or fetch's caches can add: two fetch misses (an instruction that
        straddles two lines), and a data miss whose victim and whose copy in the other hart's cache
        are both written back first (or an uncached or device access). FENCE.I's flush is not
        counted: no poll loop holds one."""
        return 2 * self.fetch_fill + max(self.data_fill + 2 * self.write_back, self.uncached, self.ahb,
                                     self.apb(APB_DIVIDER_MAX))


ROCKET_L1 = L1Timing()


@dataclass(frozen=True)
class CacheStatistics:
    fetch_lookups: int    # fetches from a new line of the cached view
    fetch_misses: int
    data_lookups: int     # loads and stores looked up in a set (not those the engines' hot lines answer)
    data_misses: int      # a store's upgrade to write permission included
    write_backs: int      # dirty lines written back (evicted, read by the other hart, flushed)
    uncached_accesses: int
    flushes: int          # FENCE.I's walks of the data cache
    device_accesses: int  # loads and stores of device registers


class HartCaches:
    """One hart's caches: the structure both engines' counters point at."""

    def __init__(self, figures: L1Timing = ROCKET_L1) -> None:
        self.figures = figures
        self.state = L1Caches()
        state = self.state
        state.cached_base, state.cached_size = SRAM_BASE, SRAM_SIZE
        state.uncached_base, state.uncached_size = SRAM_UNCACHED_BASE, SRAM_SIZE
        state.data_fill, state.write_back = figures.data_fill, figures.write_back
        state.fetch_fill, state.uncached = figures.fetch_fill, figures.uncached
        state.flush_per_way = figures.flush_per_way
        self.reset()

    def time_devices(self, windows: list[tuple[int, int, int]]) -> None:
        """The device windows (base, size, cycles an access takes beyond a hit) accesses are charged in."""
        if len(windows) > L1_DEVICE_WINDOWS:
            raise ValueError(f"{len(windows)} device windows: the caches time at most {L1_DEVICE_WINDOWS}")
        state = self.state
        for n, (base, size, cost) in enumerate(windows):
            state.device_base[n], state.device_size[n], state.device_cost[n] = base, size, cost
        state.device_windows = len(windows)

    def pair_with(self, other: "HartCaches") -> None:
        """The other hart's caches, which this hart's stores and misses keep coherent with."""
        self.state.peer = ctypes.pointer(other.state)
        other.state.peer = ctypes.pointer(self.state)

    def reset(self) -> None:
        """Every line invalid, as Rocket's caches come out of reset (their metadata is cleared by a
        reset walk); the statistics from zero."""
        for cache in (self.state.icache, self.state.dcache):
            ctypes.memset(ctypes.addressof(cache), 0, ctypes.sizeof(cache))
            cache.lfsr = LFSR_RESET
        self.state.fetch_line = 0
        self.state.uncached_accesses = 0
        self.state.device_accesses = 0
        self.state.acquired = 0
        self.state.flushes = 0

    def statistics(self) -> CacheStatistics:
        i, d = self.state.icache, self.state.dcache
        return CacheStatistics(i.lookups, i.misses, d.lookups, d.misses, d.write_backs,
                               self.state.uncached_accesses, self.state.flushes, self.state.device_accesses)

    def _slot(self, address: int, data: bool) -> int | None:
        """The slot (set x ways + way) of the cache holding the line of `address`, or None."""
        cache = self.state.dcache if data else self.state.icache
        line = (address >> L1_LINE_SHIFT) + 1
        first = ((address >> L1_LINE_SHIFT) & (L1_SETS - 1)) * L1_WAYS
        return next((first + way for way in range(L1_WAYS) if cache.line[first + way] == line), None)

    def holds(self, address: int, data: bool = True) -> bool:
        """Whether the data (or instruction) cache holds the line of `address` (SRAM's cached view)."""
        return self._slot(address, data) is not None

    def dirty(self, address: int) -> bool:
        """Whether the data cache holds the line of `address` writable, so written and not yet written
        back (a store's grant is followed by its write at once)."""
        slot = self._slot(address, True)
        return slot is not None and bool(self.state.dcache.writable[slot])
