"""The state the K210's mask ROM hands a program: what the board looks like at 0x8000_0000.

A K210 never starts a program from its reset values. Both harts begin in the mask ROM
(0x1000, then its code at 0x8800_0000), which reads the boot pin IO_16 and either talks
kflash's ISP protocol on UARTHS (pads 4 and 5, 115200 baud) or reads the program from the
on-board flash through SPI3, checks its SHA-256 (and decrypts it with the AES engine and
the OTP key when asked), copies it to SRAM at 0x8000_0000, sends hart 1 an IPI and jumps
there; hart 1, woken, jumps there too (Sean Anderson, U-Boot doc/board/sipeed/maix.rst,
"Boot Sequence"). kflash flashes a program through its own loader (ISP_PROG, run from
SRAM) and then resets the board, so a flashed program meets the ROM's state, not the
loader's; `kflash --sram` has the ROM's ISP jump to the program directly, with UARTHS as
the ISP left it.

What is documented, and what the model chose where nothing is (docs/design/board-model.md, "The state the
firmware is handed", lists the same with sources):

- CPU clock: PLL0 at 780 MHz (26 MHz x 30), ACLK = PLL0 / 2 = 390 MHz. Documented: U-Boot's
  Maix notes give the debug UART clock as 390 MHz, "the same as the CPU's default speed", and
  Linux's k210.dtsi a timebase of 7.8 MHz (= 390 MHz / 50, "true only for the default
  frequency", its reviewer noted). The divider fields that give 780 MHz are chosen
  (clkr 0, clkf 29, clkod 0, bwadj = clkf as the SDK sets it).
- PLL1 and PLL2: off (their reset values). Documented for PLL1: Linux turns it on at boot
  because the AI SRAM bank "is by default off when the board powers-up" (k210_soc_early_init).
- Clock gates: CPU, both SRAM banks and the three APB buses on; of the peripherals, those
  the ROM's own steps use (ROM, OTP, SPI3 for the flash, SHA-256, AES, FPIOA for the boot
  pin) and those firmware that ran on real Docks used without ever enabling them (DMA,
  SPI0, SPI1: issue 10). Which gates the ROM really leaves on is not documented: chosen.
  The slow GPIO's gate is chosen on too (the ROM samples a pin; through which block is not
  documented). Every other gate keeps its reset value; the model implements none of them.
- FPIOA: pads 4 and 5 routed to UARTHS RX and TX with the SDK's pad settings for those
  functions (the ROM's ISP talks on them, and kflash's terminal listens there); every other
  pad as at reset.
- UARTHS: 115200 baud from the 390 MHz clock (div = 390 MHz / 115200 - 1, the SDK's
  uarths_init), transmitter and receiver on: what the ROM's ISP leaves; whether the ROM sets
  it up when it boots from flash is not documented (chosen the same).
- Harts: both start at 0x8000_0000 at the same moment, with every CSR at its reset value and
  msip clear (whether the ROM leaves hart 1's IPI pending is not documented: cleared, as a
  wait loop that has taken its IPI leaves it). mcycle, minstret and mtime start at 0 (the
  time the ROM spent depends on the image and is not modelled).
- SPI3: left at its reset values (the registers the ROM leaves after reading the flash are not
  documented; the SDK's spi_init and the FreeRTOS SDK set every one they use).
"""
from __future__ import annotations


from ..devices.fpioa import FUNC_UARTHS_RX, FUNC_UARTHS_TX, Fpioa
from ..devices.sysctl import (CENT_APB0, CENT_APB1, CENT_APB2, CENT_CPU, CENT_SRAM0, CENT_SRAM1, CLK_EN_CENT, CLK_EN_PERI,
                     CLK_SEL0, OSC_HZ, PERI_BITS, PLL0, PLL_CLKF, PLL_CLKOD, PLL_CLKR, PLL_LOCK_TIME,
                     PLL_OUT_EN_BIT, PLL_PWRD_BIT, Sysctl)
from ..devices.uarths import DIV, RXCTRL, TXCTRL, Uarths
from .maix_dock import PAD_CONSOLE_RX, PAD_CONSOLE_TX

PLL0_CLKF = 29                     # 26 MHz x (29 + 1) = 780 MHz
PLL_BWADJ_SHIFT = 14
PLL0_HANDED_OVER = ((0 << PLL_CLKR[0]) | (PLL0_CLKF << PLL_CLKF[0]) | (0 << PLL_CLKOD[0])
                    | (PLL0_CLKF << PLL_BWADJ_SHIFT) | (1 << PLL_PWRD_BIT) | (1 << PLL_OUT_EN_BIT))
ACLK_SEL_PLL0 = 1                  # clk_sel0 bit 0; aclk_divider_sel 0: ACLK = PLL0 / 2
CPU_HZ_HANDED_OVER = OSC_HZ * (PLL0_CLKF + 1) // 2
CLK_EN_CENT_HANDED_OVER = sum(1 << bit for bit in (CENT_CPU, CENT_SRAM0, CENT_SRAM1, CENT_APB0, CENT_APB1, CENT_APB2))
PERIPHERAL_CLOCKS_ON = ("rom", "otp", "spi3", "sha", "aes", "fpioa", "dma", "spi0", "spi1", "gpio")
CLK_EN_PERI_HANDED_OVER = sum(1 << PERI_BITS[name] for name in PERIPHERAL_CLOCKS_ON)

# FPIOA pad words as the SDK's fpioa_set_function writes them (function_config[]):
# function [7:0], drive [11:8], oe_en 12, ie_en 20, schmitt trigger 23
PAD_UARTHS_RX, PAD_UARTHS_TX = PAD_CONSOLE_RX, PAD_CONSOLE_TX
PAD_WORD_UARTHS_RX = FUNC_UARTHS_RX | (1 << 20) | (1 << 23)
PAD_WORD_UARTHS_TX = FUNC_UARTHS_TX | (0xF << 8) | (1 << 12)

ISP_BAUD = 115_200
UARTHS_DIV_HANDED_OVER = CPU_HZ_HANDED_OVER // ISP_BAUD - 1
UARTHS_TXEN = UARTHS_RXEN = 1


def hand_over(sysctl: Sysctl, fpioa: Fpioa, uarths: Uarths) -> None:
    """Puts the blocks' registers in the state the mask ROM leaves when it jumps to the program
    (module comment). Written straight into the register tables, before the board's clock and
    scheduler exist, as the state the program finds, not as accesses it makes."""
    sysctl.values[PLL0] = PLL0_HANDED_OVER
    sysctl.plls[PLL0].running_since = -PLL_LOCK_TIME     # locked long before the program starts
    sysctl.values[CLK_SEL0] = ACLK_SEL_PLL0
    sysctl.values[CLK_EN_CENT] = CLK_EN_CENT_HANDED_OVER
    sysctl.values[CLK_EN_PERI] = CLK_EN_PERI_HANDED_OVER
    sysctl.refresh_usable()
    fpioa.values[4 * PAD_UARTHS_RX] = PAD_WORD_UARTHS_RX
    fpioa.values[4 * PAD_UARTHS_TX] = PAD_WORD_UARTHS_TX
    uarths.values[DIV] = UARTHS_DIV_HANDED_OVER
    uarths.values[TXCTRL] |= UARTHS_TXEN
    uarths.values[RXCTRL] |= UARTHS_RXEN
