"""PLIC (0x0C00_0000): the platform-level interrupt controller, an M-mode and an S-mode context per hart.

Sources 1..65 (SPI0 1, SPI1 2, GPIO 23, DMA channels 27..32, UARTHS 33, GPIOHS 34..65).
Contexts, as on the K210: 0 = hart 0's M-mode (its MEIP), 1 = hart 0's S-mode (its SEIP),
2 = hart 1's M-mode, 3 = hart 1's S-mode. Sources: the Kendryte SDK's plic.h gives each core
0x100 bytes of enables (`target_enables.target[core_id]`) and 0x2000 of threshold and
claim/complete (`targets.target[core_id]`), i.e. two SiFive contexts (0x80 and 0x1000 each),
the first of which is the core's M-mode one; Linux's K210 device tree wires the PLIC the same
way since "riscv: dts: k210: fix broken IRQs on hart1" (2022): interrupts-extended =
<cpu0 M-ext>, <cpu0 S-ext>, <cpu1 M-ext>, <cpu1 S-ext>.
Interrupts are level-triggered through a gateway: a source becomes pending when its
line is high and it is not being served; claim returns the highest-priority pending
enabled source above the threshold (ties: lowest id) and clears its pending bit;
the source can pend again only after its id is written back to complete.

Register layout as rocket-chip's PLIC had it before its privileged-spec-1.10 merge (March
2017; the K210 implements 1.9.1): priorities (source 0's included, which always reads 0),
thresholds and claim/complete are 32-bit fields, so a store narrower than 32 bits leaves them
as they are; enables are one field per bit, so any store changes the bits it covers.
"""
from __future__ import annotations

from typing import Callable, Iterable

from ..memory_map import K210_BLOCKS
from ..vtime import Time
from .mmio import BUS_TILELINK, Peripheral, Register, byte_fields
from .ports import Ports

SOURCES = 66          # 0 is "no interrupt"
CONTEXTS_PER_HART = 2  # M-mode, then S-mode
HARTS = 2
CONTEXTS = HARTS * CONTEXTS_PER_HART
PRIORITY = 0x0000
PENDING = 0x1000
ENABLE = 0x2000
ENABLE_STRIDE = 0x80
THRESHOLD = 0x20_0000
CLAIM = 0x20_0004
CONTEXT_STRIDE = 0x1000
PRIORITY_MASK = 7
WORDS = (SOURCES + 31) // 32

# the first source of some blocks (memory_map.K210_BLOCKS has them all)
SOURCE_SPI0, SOURCE_SPI1, SOURCE_GPIO, SOURCE_DMA0, SOURCE_UARTHS, SOURCE_GPIOHS0 = (
    K210_BLOCKS[name].irqs[0] for name in ("SPI0", "SPI1", "GPIO", "DMAC", "UARTHS", "GPIOHS"))
SOURCE_UART1, SOURCE_TIMER0A, SOURCE_WDT0, SOURCE_RTC = (
    K210_BLOCKS[name].irqs[0] for name in ("UART1", "TIMER0", "WDT0", "RTC"))


def m_context(hart: int) -> int:
    """The context whose interrupt is hart `hart`'s MEIP."""
    return CONTEXTS_PER_HART * hart


def s_context(hart: int) -> int:
    """The context whose interrupt is hart `hart`'s SEIP."""
    return CONTEXTS_PER_HART * hart + 1


class Plic(Peripheral):
    NAME = "PLIC"
    BASE = K210_BLOCKS["PLIC"].base
    SIZE = K210_BLOCKS["PLIC"].size
    BUS = BUS_TILELINK
    REGISTERS = {
        **{PRIORITY + 4 * s: Register(f"priority{s}") for s in range(SOURCES)},
        **{PENDING + 4 * w: Register(f"pending{w}", writable=False) for w in range(WORDS)},
        **{ENABLE + ENABLE_STRIDE * c + 4 * w: Register(f"enable{c}_{w}", fields=byte_fields(4))
           for c in range(CONTEXTS) for w in range(WORDS)},
        **{THRESHOLD + CONTEXT_STRIDE * c: Register(f"threshold{c}") for c in range(CONTEXTS)},
        **{CLAIM + CONTEXT_STRIDE * c: Register(f"claim{c}") for c in range(CONTEXTS)},
    }

    def __init__(self, ports: Ports, high_sources: Callable[[], Iterable[int]]) -> None:
        """high_sources: the sources whose interrupt line is high now (the board's wiring of the lines)."""
        super().__init__(ports)
        self.high_sources = high_sources
        self.pending: set[int] = set()
        self.in_service: set[int] = set()

    def reset(self, now: Time) -> None:
        super().reset(now)
        self.pending.clear()
        self.in_service.clear()

    def latch(self, source: int, now: Time) -> None:
        """A pulse on a source's line (a block whose interrupt is a pulse, the RTC's): the gateway
        latches it as pending, unless the source is being served."""
        if source not in self.in_service:
            self.pending.add(source)
        self.ports.irq_changed(now)

    def sample(self) -> None:
        """Gateways: latch a pending bit for each high source line not being served."""
        for source in self.high_sources():
            if source not in self.in_service:
                self.pending.add(source)

    def _enabled(self, context: int, source: int) -> bool:
        word = self.values[ENABLE + ENABLE_STRIDE * context + 4 * (source // 32)]
        return bool(word >> (source % 32) & 1)

    def _best(self, context: int) -> int:
        threshold = self.values[THRESHOLD + CONTEXT_STRIDE * context] & PRIORITY_MASK
        best, best_priority = 0, threshold
        for source in sorted(self.pending):
            priority = self.values[PRIORITY + 4 * source] & PRIORITY_MASK
            if priority > best_priority and self._enabled(context, source):
                best, best_priority = source, priority
        return best

    def external_pending(self, context: int) -> bool:
        """The context's interrupt: MEIP or SEIP of the hart it belongs to (m_context, s_context)."""
        self.sample()
        return self._best(context) != 0

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        self.ports.catch_up(now)
        self.sample()
        if PENDING <= offset < PENDING + 4 * WORDS:
            word = (offset - PENDING) // 4
            return sum(1 << (s % 32) for s in self.pending if s // 32 == word)
        if offset >= CLAIM - 4 and (offset - CLAIM) % CONTEXT_STRIDE == 0:
            context = (offset - CLAIM) // CONTEXT_STRIDE
            source = self._best(context)
            if source:
                self.pending.discard(source)
                self.in_service.add(source)
                self.took_on_read = True
            self.ports.irq_changed(now)
            return source
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        if offset >= CLAIM - 4 and (offset - CLAIM) % CONTEXT_STRIDE == 0:
            self.in_service.discard(value)   # complete
            self.sample()
        elif offset == PRIORITY:
            pass     # source 0 ("no interrupt") has a priority register that always reads 0
        elif offset < PENDING:
            self.values[offset] = value & PRIORITY_MASK
        else:
            self.values[offset] = value
        self.ports.irq_changed(now)
