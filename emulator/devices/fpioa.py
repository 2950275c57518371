"""FPIOA (0x502B_0000): which function drives each of the 48 IO pads.

The board derives its wiring from this: the LCD's chip select, reset and D/C
lines and the SD card's signals reach their devices only through the pads the
firmware routed, as on the Maix Dock.
"""
from __future__ import annotations

from ..memory_map import K210_BLOCKS
from ..vtime import Time
from .mmio import Peripheral, Register
from .ports import Ports

PAD_COUNT = 48
FUNCTION_MASK = 0xFF

# Function numbers (K210 datasheet / SDK fpioa_function_t)
FUNC_SPI0_D0 = 4
FUNC_SPI0_SS0 = 12
FUNC_SPI0_SCLK = 17
FUNC_UARTHS_RX = 18
FUNC_UARTHS_TX = 19
FUNC_GPIOHS0 = 24
FUNC_GPIO0 = 56
FUNC_UART1_RX = 64             # UARTn_RX = 64 + 2 (n - 1), UARTn_TX = 65 + 2 (n - 1) (fpioa.h)
FUNC_UART1_TX = 65
FUNC_TIMER0_TOGGLE1 = 190      # TIMERn_TOGGLEc = 190 + 4 n + c - 1
FUNC_SPI1_D0 = 70
FUNC_SPI1_D1 = 71
FUNC_SPI1_SS0 = 78
FUNC_SPI1_SCLK = 83
FUNC_RESV0 = 0  # JTAG_TCLK is 0 in the SDK; a pad never written keeps its reset function

TIE_EN = 0xC0
TIE_VAL = 0xE0


class Fpioa(Peripheral):
    NAME = "FPIOA"
    BASE = K210_BLOCKS["FPIOA"].base
    SIZE = K210_BLOCKS["FPIOA"].size
    GATE = K210_BLOCKS["FPIOA"].gate
    REGISTERS = {
        **{4 * pad: Register(f"io{pad}") for pad in range(PAD_COUNT)},
        **{TIE_EN + 4 * i: Register(f"tie_en{i}") for i in range(8)},
        **{TIE_VAL + 4 * i: Register(f"tie_val{i}") for i in range(8)},
    }

    def __init__(self, ports: Ports) -> None:
        super().__init__(ports)
        self._pads_by_function: dict[int, tuple[int, ...]] = {}   # looked up on every GPIO read: kept
        self.routing_version = 0    # changes whenever a pad's function may have (for tables others keep)
        self._unroute_all()

    def _unroute_all(self) -> None:
        # The SDK treats pads as unassigned until fpioa_set_function; an impossible function
        # number at reset means a pad nobody routed drives nothing.
        for pad in range(PAD_COUNT):
            self.values[4 * pad] = FUNCTION_MASK
        self._pads_by_function.clear()
        self.routing_version += 1

    def reset(self, now: Time) -> None:
        super().reset(now)
        self._unroute_all()
        self.ports.wiring_changed(now)

    def function_of_pad(self, pad: int) -> int:
        return self.values[4 * pad] & FUNCTION_MASK

    def pads_with_function(self, function: int) -> list[int]:
        pads = self._pads_by_function.get(function)
        if pads is None:
            pads = self._pads_by_function[function] = tuple(pad for pad in range(PAD_COUNT)
                                                            if self.function_of_pad(pad) == function)
        return list(pads)

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        self.values[offset] = value
        self._pads_by_function.clear()
        self.routing_version += 1
        if offset < 4 * PAD_COUNT:
            self.ports.wiring_changed(now)
