"""Memory-mapped peripherals: the common register-table machinery.

A peripheral declares its registers as a table (offset -> Register) the way a
datasheet lists them. The bus routes loads and stores to `read`/`write`, which
take exactly the accesses the table describes; an offset that is not in the
table, a write to a read-only register, a read of a write-only one or an access
of another width raises `RegisterRuleViolation`. What happens then is the bus's
business (bus.py): the K210's buses answer such accesses in ways of their own,
which the bus models by default, or the run stops (--strict), so firmware never
silently talks to hardware the model does not implement.

Each peripheral says which bus it sits on (`BUS`), since that decides what a
narrow store does to a register; a register of a TileLink device lists its
fields (`fields`), since the TileLink register router writes a field only when
a store covers all of its bytes.
"""
from __future__ import annotations

from dataclasses import dataclass
from ..errors import RegisterRuleViolation
from ..vtime import NEVER, Time
from .ports import Ports


@dataclass(frozen=True)
class Register:
    """One register of a peripheral's register table."""

    name: str
    width: int = 4          # bytes: 4 for 32-bit registers, 8 for the DMAC's 64-bit ones
    readable: bool = True
    writable: bool = True
    reset: int = 0
    narrow_ok: bool = False  # a 64-bit register that may also be accessed as two 32-bit halves
    # TileLink devices only: the register's writable fields as (lowest bit, width in bits), as the
    # RTL's register map declares them; None: one field spanning the whole register
    fields: tuple[tuple[int, int], ...] | None = None
    # a status register whose reading changes nothing and whose value changes only at the device's
    # own events (next_event_time) or through an access to the device: a read of it may be answered
    # again from the last one until the next event (Peripheral.stable_until). A read that takes
    # something after all (a latched error it clears) says so with took_on_read.
    steady: bool = False


# The buses a peripheral can sit on (see bus.py for what each does with a narrow store)
BUS_TILELINK = "TileLink"   # Rocket's register router: CLINT, PLIC, UARTHS, GPIOHS
BUS_APB = "APB"             # 32-bit APB behind the AXI-to-APB bridges: SYSCTL, FPIOA, SPI0, SPI1
BUS_AHB = "AHB"             # the DMAC's 32-bit AHB port


def byte_fields(width: int) -> tuple[tuple[int, int], ...]:
    """The fields of a register the RTL declares byte by byte (RegField.bytes)."""
    return tuple((8 * n, 8) for n in range(width))


class Peripheral:
    """Base class of every memory-mapped block. Subclasses fill `REGISTERS` and
    override `read_register`/`write_register` for registers with side effects."""

    NAME = "peripheral"
    BASE = 0
    SIZE = 0x1000
    BUS = BUS_APB
    REGISTERS: dict[int, Register] = {}
    # set by read_register when the read took something from the device (a FIFO's oldest entry,
    # a claimed interrupt), cleared by the bus: such reads are not a poll, however alike their values
    took_on_read = False

    def __init__(self, ports: Ports) -> None:
        self.ports = ports
        self.values: dict[int, int] = {off: reg.reset for off, reg in self.REGISTERS.items()}
        # lookup's answers by (offset, size, is_write): the table is fixed, and the firmware polls
        self._found: dict[tuple[int, int, bool], tuple[int, Register]] = {}

    def reset(self, now: Time) -> None:
        """A reset of this block (SYSCTL peri_reset): registers return to their reset values."""
        self.values = {off: reg.reset for off, reg in self.REGISTERS.items()}

    # --- routing, called by the board -------------------------------------------------

    def lookup(self, offset: int, size: int, is_write: bool) -> tuple[int, Register]:
        """Finds the register an access hits; raises RegisterRuleViolation if none can take it."""
        found = self._found.get((offset, size, is_write))
        if found is None:
            found = self._found[(offset, size, is_write)] = self._find(offset, size, is_write)
        return found

    def _find(self, offset: int, size: int, is_write: bool) -> tuple[int, Register]:
        reg = self.REGISTERS.get(offset)
        base = offset
        if reg is None and size == 4 and (offset - 4) in self.REGISTERS:
            wide = self.REGISTERS[offset - 4]
            if wide.width == 8 and wide.narrow_ok:
                reg, base = wide, offset - 4
        if reg is None:
            raise RegisterRuleViolation(f"{self.NAME} has no register at offset 0x{offset:x}")
        if size != reg.width and not (reg.width == 8 and reg.narrow_ok and size == 4):
            raise RegisterRuleViolation(
                f"{self.NAME}.{reg.name} is a {reg.width * 8}-bit register; "
                f"a {size * 8}-bit access is not supported by the model"
            )
        if is_write and not reg.writable:
            raise RegisterRuleViolation(f"{self.NAME}.{reg.name} is read-only")
        if not is_write and not reg.readable:
            raise RegisterRuleViolation(f"{self.NAME}.{reg.name} is write-only")
        return base, reg

    def register_containing(self, offset: int) -> tuple[int, Register] | None:
        """(offset of the register, register) for the register whose bytes include `offset`."""
        word = offset & ~3
        reg = self.REGISTERS.get(word)
        if reg is not None:
            return word, reg
        double = offset & ~7
        reg = self.REGISTERS.get(double)
        if reg is not None and reg.width == 8:
            return double, reg
        return None

    def merge_base(self, offset: int, reg: Register, now: Time) -> int:
        """What a store that changes only some bytes of a register leaves in the others."""
        return self.values[offset]

    def read(self, offset: int, size: int, now: Time) -> int:
        base, reg = self.lookup(offset, size, False)
        value = self.read_register(base, reg, now)
        if base != offset:
            return (value >> 32) & 0xFFFF_FFFF
        if size == 4:
            return value & 0xFFFF_FFFF
        return value

    def write(self, offset: int, size: int, value: int, now: Time) -> None:
        base, reg = self.lookup(offset, size, True)
        if reg.width == 8 and size == 4:
            old = self.values.get(base, 0)
            if base == offset:
                value = (old & ~0xFFFF_FFFF) | (value & 0xFFFF_FFFF)
            else:
                value = (old & 0xFFFF_FFFF) | ((value & 0xFFFF_FFFF) << 32)
        self.write_register(base, reg, value & ((1 << (reg.width * 8)) - 1), now)

    # --- behaviour, overridden by subclasses ------------------------------------------

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        self.values[offset] = value

    def irq_line(self) -> bool:
        """Whether the block's (only) interrupt line is high now."""
        return False

    def irq_lines(self) -> int:
        """The block's interrupt lines now, line n in bit n (memory_map.K210_BLOCKS gives each line's
        PLIC source); a block with more than one line overrides this."""
        return 1 if self.irq_line() else 0

    def next_event_time(self, now: Time) -> Time | None:
        """The next virtual time at which this device changes state by itself (None: never)."""
        return None

    def stable_until(self, offset: int, now: Time) -> Time:
        """Right after a read of the register at `offset` at `now`: the virtual time before which
        reading it again would return the same value and change nothing, in the device or
        elsewhere (advancing the device to then included), provided no other access reaches the
        device meanwhile; `now` or earlier: no such promise. The bus answers a hart polling the
        register from this (bus.py). A register declared `steady` is stable until the device's next
        event; a device whose registers change between its events (SPI's FIFO levels, at every
        frame edge) works the bound out itself."""
        reg = self.REGISTERS.get(offset)
        if reg is None or not reg.steady:
            return now
        event = self.next_event_time(now)
        return NEVER if event is None else max(now, event)

    def advance(self, now: Time) -> None:
        """Brings the device's time-driven state up to `now`."""

    def describe_wait(self) -> str | None:
        """If the device is stuck waiting for something, a sentence saying what (for hang reports)."""
        return None


def field(value: int, low: int, width: int) -> int:
    """Extracts bits [low + width - 1 : low] of value."""
    return (value >> low) & ((1 << width) - 1)
