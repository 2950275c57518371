"""The K210's address map as every layer of the model sees it: where SRAM is, where the harts
start, and every block the model builds (K210_BLOCKS: address, interrupt sources, clock gate) or
knows by name (K210_UNMODELLED). Devices take their place from here; the board wires their
interrupt lines from it."""
from __future__ import annotations

from dataclasses import dataclass

SRAM_BASE = 0x8000_0000
SRAM_UNCACHED_BASE = 0x4000_0000      # the same bytes, not through the data cache
SRAM_SIZE = 8 * 1024 * 1024          # 6 MiB SRAM0/SRAM1 + 2 MiB AI SRAM
GENERAL_SRAM_SIZE = 6 * 1024 * 1024
RESET_PC = SRAM_BASE                 # where both harts start when the mask ROM hands over


def is_sram(address: int) -> bool:
    """Whether `address` is in SRAM, through either view."""
    return SRAM_BASE <= address < SRAM_BASE + SRAM_SIZE or SRAM_UNCACHED_BASE <= address < SRAM_UNCACHED_BASE + SRAM_SIZE


def sram_views(address: int, length: int) -> list[int]:
    """Where the `length` bytes at `address` can be reached: `address` itself and, when they lie in
    one view of SRAM, the same offset in the other (the K210 maps its SRAM at 0x8000_0000 through
    the cache and at 0x4000_0000 around it: the Kendryte SDK's lds/kendryte.ld, `ram` and
    `ram_nocache`). Code linked in one view runs in the other too: both harts start at
    0x8000_0000 whatever the link address, and a jump may cross."""
    for view, other in ((SRAM_BASE, SRAM_UNCACHED_BASE), (SRAM_UNCACHED_BASE, SRAM_BASE)):
        if view <= address and address + length <= view + SRAM_SIZE:
            return [address, address - view + other]
    return [address]


# The buses blocks' registers sit on, as the Kendryte SDK's platform.h groups them: "Under Coreplex"
# and "Under TileLink" (Rocket's own TileLink), "Under AXI 64 bit", "Under AHB 32 bit", "Under APB1/2/3
# 32 bit". SYSCTL's apb0/1/2 clock dividers clock platform.h's APB1/2/3 (its PERI_BUS: WDT on apb1,
# SPI0/SPI1 on apb2), so they are named here by their SYSCTL clock.
TILELINK, AXI, AHB, APB0, APB1, APB2 = "TileLink", "AXI", "AHB", "APB0", "APB1", "APB2"
APBS = (APB0, APB1, APB2)


@dataclass(frozen=True)
class Block:
    """One block of the K210 the model builds: where it sits, the PLIC sources its interrupt lines
    drive (line n on irqs[n]), the SYSCTL clock gate it sits behind (devices/sysctl.py
    PERI_BITS; None: always clocked), and the bus its registers are on."""
    base: int
    size: int
    irqs: tuple[int, ...] = ()
    gate: str | None = None
    bus: str = APB0


# The K210 as the model builds it, by the name each block has in messages: addresses from the
# Kendryte SDK's platform.h, interrupt sources from plic.h, gates from sysctl.h/sysctl.c.
K210_BLOCKS: dict[str, Block] = {
    "CLINT": Block(0x0200_0000, 0x1_0000, bus=TILELINK),
    "PLIC": Block(0x0C00_0000, 0x0400_0000, bus=TILELINK),
    "UARTHS": Block(0x3800_0000, 0x1000, (33,), bus=TILELINK),
    "GPIOHS": Block(0x3800_1000, 0x1000, tuple(range(34, 66)), bus=TILELINK),
    "DMAC": Block(0x5000_0000, 0x1000, tuple(range(27, 33)), "dma", bus=AHB),
    "GPIO": Block(0x5020_0000, 0x1000, (23,), "gpio"),
    **{f"UART{n}": Block(0x5020_0000 + 0x1_0000 * n, 0x1_0000, (10 + n,), f"uart{n}") for n in (1, 2, 3)},
    "FPIOA": Block(0x502B_0000, 0x1000, (), "fpioa"),
    "SHA256": Block(0x502C_0000, 0x1_0000, (), "sha"),
    **{f"TIMER{n}": Block(0x502D_0000 + 0x1_0000 * n, 0x1_0000, (14 + 2 * n, 15 + 2 * n), f"timer{n}")
       for n in (0, 1, 2)},
    **{f"WDT{n}": Block(0x5040_0000 + 0x1_0000 * n, 0x1_0000, (21 + n,), f"wdt{n}", APB1) for n in (0, 1)},
    "SYSCTL": Block(0x5044_0000, 0x1000, bus=APB1),
    "RTC": Block(0x5046_0000, 0x1_0000, (20,), "rtc", APB1),
    **{f"SPI{n}": Block(0x5200_0000 + 0x0100_0000 * n, 0x1000, (1 + n,), f"spi{n}", APB2) for n in (0, 1)},
    "SPI3": Block(0x5400_0000, 0x1000, (4,), "spi3", APB2),
    "FFT": Block(0x4200_0000, 0x1000, (26,), "fft", AXI),
    "OTP": Block(0x5042_0000, 0x1000, (), "otp", APB1),
}

# Blocks the model knows by name but does not build: an access there stops the run naming them
K210_UNMODELLED: tuple[tuple[int, int, str], ...] = (
    (0x5020_1000, 0xF000, "GPIO (past its registers)"), (0x5024_0000, 0x1_0000, "SPI slave"),
    (0x5025_0000, 0x3_0000, "I2S"), (0x5028_0000, 0x3_0000, "I2C"), (0x5042_1000, 0xF000, "OTP (past its registers)"),
    (0x5043_0000, 0x1_0000, "DVP"), (0x5045_0000, 0x1_0000, "AES"),
    (0x5400_1000, 0xFF_F000, "SPI3 (past its registers)"), (0x5000_0000 + 0x1000, 0xF000, "DMAC (past its registers)"),
    (0x5100_0000, 0x100_0000, "SPI2"), (0x4080_0000, 0x100_0000, "KPU"), (0x4200_1000, 0xFF_F000, "FFT (past its registers)"),
    (0x8800_0000, 0x2_0000, "boot ROM"),
)
