"""GPIO (0x5020_0000): the slow GPIO block, a DesignWare APB GPIO with one port of 8 lines.

Register layout: the Kendryte SDK's gpio.h (`gpio_t`), which is the DesignWare APB GPIO's
port A map: data output (swporta_dr) 0x00, direction (swporta_ddr, 1 = output) 0x04, data
source (swporta_ctl) 0x08, interrupt enable 0x30, mask 0x34, level/edge type 0x38 (1 =
edge), polarity 0x3C (1 = high / rising), status 0x40, raw status 0x44, debounce 0x48,
clear (porta_eoi, write 1 to clear an edge) 0x4C, external port (the pads' levels) 0x50,
level-sensitive sync 0x60, ID code 0x64, both-edge 0x68. The K210 routes eight lines
through FPIOA (functions GPIO0..GPIO7, 56..63; the SDK's GPIO_MAX_PINNO is 8), so bits
above 7 read 0 and ignore writes.

A line whose direction bit is set drives its data-output bit onto whatever pad FPIOA
routes its function to; the external-port register reads the pad: what the line drives
when it is an output, else the pad's pull (FPIOA pu/pd, bits 16/17), else 0. Interrupts
(one combined line, PLIC source 23, IRQN_APB_GPIO_INTERRUPT) follow the databook: an
enabled input line raises its raw status while its level matches the polarity
(level-sensitive) or latches it on the edge the polarity names (both edges with
int_bothedge) until a 1 is written to its eoi bit; the status register and the interrupt
line are the raw status with masked lines removed. Debounce and sync only change when a
real pad's change is seen, not what: they are stored and otherwise ignored.
"""
from __future__ import annotations

from .fpioa import FUNC_GPIO0
from ..memory_map import K210_BLOCKS
from ..vtime import Time
from .mmio import Peripheral, Register
from .ports import PadInputs, Ports

DATA_OUTPUT, DIRECTION, SOURCE = 0x00, 0x04, 0x08
INT_ENABLE, INT_MASK, INT_LEVEL, INT_POLARITY = 0x30, 0x34, 0x38, 0x3C
INT_STATUS, INT_RAW_STATUS, DEBOUNCE, INT_CLEAR = 0x40, 0x44, 0x48, 0x4C
DATA_INPUT, SYNC_LEVEL, ID_CODE, INT_BOTHEDGE = 0x50, 0x60, 0x64, 0x68
LINES = 8
LINE_MASK = (1 << LINES) - 1


class Gpio(Peripheral):
    """The slow GPIO block. The board asks it for the level a line drives (driven_level) and
    tells it when pad levels may have changed (wiring_changed)."""

    NAME = "GPIO"
    BASE = K210_BLOCKS["GPIO"].base
    SIZE = K210_BLOCKS["GPIO"].size
    GATE = K210_BLOCKS["GPIO"].gate
    REGISTERS = {
        DATA_OUTPUT: Register("data_output"), DIRECTION: Register("direction"), SOURCE: Register("source"),
        INT_ENABLE: Register("interrupt_enable"), INT_MASK: Register("interrupt_mask"),
        INT_LEVEL: Register("interrupt_level"), INT_POLARITY: Register("interrupt_polarity"),
        INT_STATUS: Register("interrupt_status", writable=False),
        INT_RAW_STATUS: Register("interrupt_status_raw", writable=False),
        DEBOUNCE: Register("interrupt_debounce"), INT_CLEAR: Register("interrupt_clear", readable=False),
        DATA_INPUT: Register("data_input", writable=False), SYNC_LEVEL: Register("sync_level"),
        ID_CODE: Register("id_code", writable=False), INT_BOTHEDGE: Register("interrupt_bothedge"),
    }

    def __init__(self, ports: Ports, pad_inputs: PadInputs) -> None:
        """pad_inputs: what the lines' pads give them as inputs (the Dock's wiring)."""
        super().__init__(ports)
        self.pad_inputs = pad_inputs
        self._last_input = 0
        self._edges = 0            # latched edge interrupts, until cleared through eoi

    def reset(self, now: Time) -> None:
        super().reset(now)
        self._last_input = 0
        self._edges = 0
        self.ports.wiring_changed(now)

    # --- pins ------------------------------------------------------------------------------

    def driven_level(self, line: int) -> int | None:
        """The level line `line` drives, or None when it is an input (or not a line)."""
        if not 0 <= line < LINES or not self.values[DIRECTION] >> line & 1:
            return None
        return self.values[DATA_OUTPUT] >> line & 1

    def input_value(self) -> int:
        """The external port: each line's pad as the line sees it: its own output, else what drives
        the pad from outside, else the pad's FPIOA pull, else 0."""
        driven = self.values[DIRECTION] & LINE_MASK
        outside, levels, pad_up, pad_down = self.pad_inputs(FUNC_GPIO0, LINES)
        pulled = pad_up & ~pad_down
        return ((self.values[DATA_OUTPUT] & driven) | (levels & outside & ~driven)
                | (pulled & ~outside & ~driven)) & LINE_MASK

    # --- interrupts ---------------------------------------------------------------------

    def _raw_status(self) -> int:
        inputs = self.input_value()
        enabled = self.values[INT_ENABLE] & ~self.values[DIRECTION] & LINE_MASK
        level_lines = enabled & ~self.values[INT_LEVEL]
        matching = ~(inputs ^ self.values[INT_POLARITY]) & LINE_MASK
        return (level_lines & matching) | (self._edges & enabled & self.values[INT_LEVEL])

    def irq_line(self) -> bool:
        # Both terms of the raw status are masked by the enabled input lines: with none enabled
        # the line is low, and the pads need not be read (the PLIC samples this on every wake check)
        if not self.values[INT_ENABLE] & ~self.values[DIRECTION] & LINE_MASK:
            return False
        return bool(self._raw_status() & ~self.values[INT_MASK])

    def wiring_changed(self, now: Time) -> None:
        """Pad levels may have changed (FPIOA, this block's outputs): latch the edges the
        enabled edge-sensitive input lines saw."""
        inputs = self.input_value()
        rose, fell = inputs & ~self._last_input, self._last_input & ~inputs
        self._last_input = inputs
        polarity, both = self.values[INT_POLARITY], self.values[INT_BOTHEDGE]
        seen = (rose & (polarity | both)) | (fell & (~polarity | both))
        self._edges |= seen & self.values[INT_ENABLE] & self.values[INT_LEVEL] & LINE_MASK
        self.ports.irq_changed(now)

    # --- registers ----------------------------------------------------------------------------

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        if offset == DATA_INPUT:
            return self.input_value()
        if offset == INT_RAW_STATUS:
            return self._raw_status()
        if offset == INT_STATUS:
            return self._raw_status() & ~self.values[INT_MASK] & LINE_MASK
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        if offset == INT_CLEAR:
            self._edges &= ~value
            self.ports.irq_changed(now)
            return
        before = [self.driven_level(line) for line in range(LINES)]
        # bytes already on the SPI wire must see the pin levels of their own time
        self.ports.catch_up(now)
        self.values[offset] = value & LINE_MASK
        if before != [self.driven_level(line) for line in range(LINES)]:
            self.ports.wiring_changed(now)
        elif offset in (INT_ENABLE, INT_MASK, INT_LEVEL, INT_POLARITY, INT_BOTHEDGE):
            self.ports.irq_changed(now)
