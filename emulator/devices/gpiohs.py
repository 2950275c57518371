"""GPIOHS (0x3800_1000): 32 high-speed GPIO lines (SiFive GPIO layout).

Output level of line n = bit n of (output_val XOR output_xor) when output_en
bit n is set. Inputs read back the pad FPIOA routes GPIOHSn to: a line driven by the chip reads
what it drives; else what drives the pad from outside (--pin); else its pull, GPIOHS's own
(pue/pde) or the pad's (FPIOA's pu/pd bits, which the SDK's gpiohs_set_drive_mode sets), else
0. Edge and level interrupt pending bits follow the input value; writing 1 clears an edge bit.
"""
from __future__ import annotations

from ..memory_map import K210_BLOCKS
from ..vtime import Time
from .mmio import BUS_TILELINK, Peripheral, Register
from .fpioa import FUNC_GPIOHS0
from .ports import PadInputs, Ports

INPUT_VAL, INPUT_EN, OUTPUT_EN, OUTPUT_VAL, PUE, PDE = 0x00, 0x04, 0x08, 0x0C, 0x10, 0x14
RISE_IE, RISE_IP, FALL_IE, FALL_IP = 0x18, 0x1C, 0x20, 0x24
HIGH_IE, HIGH_IP, LOW_IE, LOW_IP = 0x28, 0x2C, 0x30, 0x34
IOF_EN, IOF_SEL, OUTPUT_XOR = 0x38, 0x3C, 0x40
LINES = 32
MASK = (1 << LINES) - 1     # one bit per line in every register


class Gpiohs(Peripheral):
    """sifive-blocks' GPIO on TileLink: every register is one 32-bit field (one bit per line), so
    only a store that covers all four bytes changes it."""

    NAME = "GPIOHS"
    BASE = K210_BLOCKS["GPIOHS"].base
    SIZE = K210_BLOCKS["GPIOHS"].size
    BUS = BUS_TILELINK
    REGISTERS = {
        INPUT_VAL: Register("input_val", writable=False),
        INPUT_EN: Register("input_en"), OUTPUT_EN: Register("output_en"),
        OUTPUT_VAL: Register("output_val"), PUE: Register("pue"), PDE: Register("pde"),
        RISE_IE: Register("rise_ie"), RISE_IP: Register("rise_ip"),
        FALL_IE: Register("fall_ie"), FALL_IP: Register("fall_ip"),
        HIGH_IE: Register("high_ie"), HIGH_IP: Register("high_ip", writable=True),
        LOW_IE: Register("low_ie"), LOW_IP: Register("low_ip", writable=True),
        IOF_EN: Register("iof_en"), IOF_SEL: Register("iof_sel"), OUTPUT_XOR: Register("output_xor"),
    }

    def __init__(self, ports: Ports, pad_inputs: PadInputs) -> None:
        super().__init__(ports)
        self.pad_inputs = pad_inputs
        self._last_input = 0

    def reset(self, now: Time) -> None:
        super().reset(now)
        self._last_input = 0

    def driven_level(self, line: int) -> int | None:
        """Level the chip drives on a line, or None when the line is not an output."""
        if not self.values[OUTPUT_EN] >> line & 1:
            return None
        return ((self.values[OUTPUT_VAL] ^ self.values[OUTPUT_XOR]) >> line) & 1

    def _driven(self) -> tuple[int, int]:
        """What driven_level gives for every line, in two words: the lines driven, and their levels."""
        enabled = self.values[OUTPUT_EN]
        return enabled, (self.values[OUTPUT_VAL] ^ self.values[OUTPUT_XOR]) & enabled

    def input_value(self) -> int:
        driven = self.values[OUTPUT_EN]
        out = self.values[OUTPUT_VAL] ^ self.values[OUTPUT_XOR]
        outside, levels, pad_up, pad_down = self.pad_inputs(FUNC_GPIOHS0, LINES)
        pulled = (self.values[PUE] | pad_up) & ~(self.values[PDE] | pad_down)
        value = (out & driven) | (levels & outside & ~driven) | (pulled & ~outside & ~driven)
        return value & self.values[INPUT_EN] & MASK

    def wiring_changed(self, now: Time) -> None:
        """A pad's level from outside or FPIOA's routing may have changed: edges are latched."""
        self._sample_inputs()
        self.ports.irq_changed(now)

    def irq_lines(self) -> int:
        """Bit n set: GPIOHS line n's interrupt (PLIC source 34 + n) is high."""
        return ((self.values[RISE_IP] & self.values[RISE_IE]) | (self.values[FALL_IP] & self.values[FALL_IE])
                | (self.values[HIGH_IP] & self.values[HIGH_IE]) | (self.values[LOW_IP] & self.values[LOW_IE]))

    def irq_line(self, line: int) -> bool:
        return bool(self.irq_lines() >> line & 1)

    def _sample_inputs(self) -> None:
        now_in = self.input_value()
        rose = now_in & ~self._last_input
        fell = self._last_input & ~now_in
        self.values[RISE_IP] |= rose
        self.values[FALL_IP] |= fell
        self.values[HIGH_IP] = now_in
        self.values[LOW_IP] = ~now_in & self.values[INPUT_EN] & MASK
        self._last_input = now_in

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        if offset == INPUT_VAL:
            return self.input_value()
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        if offset in (RISE_IP, FALL_IP):
            self.values[offset] &= ~value & MASK   # write 1 to clear
            return
        if offset in (HIGH_IP, LOW_IP):
            return  # level pending bits follow the input; writes have no effect
        before = self._driven()
        # bytes already on the SPI wire must see the pin levels of their own time
        self.ports.catch_up(now)
        self.values[offset] = value
        self._sample_inputs()
        if before != self._driven():
            self.ports.wiring_changed(now)
