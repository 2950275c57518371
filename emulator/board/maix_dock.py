"""The Sipeed Maix Dock as data: the K210 pad each part of the board is wired to. The one home of
these numbers in the model (wiring.py and the boot ROM's hand-over take them from here); the
firmware's copies (firmware/include/k210.inc, tests/firmware/k210.h) are checked against it
(tests/unit/shared/test_memory_map.py). Sources: the Dock's schematic (Sipeed, "Maix Dock" v1.1), the SDK's and
MaixPy's pin settings for it (the LCD on pads 36-39, the SD card on 26-29, the console on 4-5)."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Pad:
    number: int
    part: str          # what on the Dock the pad reaches
    signal: str        # the part's signal


DOCK_PADS: dict[str, Pad] = {
    "UARTHS_RX": Pad(4, "USB-serial bridge (CH340)", "its TX, the K210's console input"),
    "UARTHS_TX": Pad(5, "USB-serial bridge (CH340)", "its RX, the K210's console output"),
    "LED_BLUE": Pad(12, "RGB LED", "blue, lit when the pad is low"),
    "LED_GREEN": Pad(13, "RGB LED", "green, lit when the pad is low"),
    "BOOT": Pad(16, "BOOT key", "pulled up; pressed pulls it low"),
    "SD_MISO": Pad(26, "micro SD slot", "DAT0 (MISO)"),
    "SD_SCLK": Pad(27, "micro SD slot", "CLK"),
    "SD_MOSI": Pad(28, "micro SD slot", "CMD (MOSI)"),
    "SD_CS": Pad(29, "micro SD slot", "DAT3 (CS)"),
    "LCD_CS": Pad(36, "ST7789V LCD", "CSX"),
    "LCD_RST": Pad(37, "ST7789V LCD", "RESX"),
    "LCD_DC": Pad(38, "ST7789V LCD", "D/CX"),
    "LCD_WR": Pad(39, "ST7789V LCD", "WRX, SPI0's serial clock"),
}
# other names the firmware gives the same pads
PAD_ALIASES = {"LCD_SCLK": "LCD_WR"}

PAD_CONSOLE_RX, PAD_CONSOLE_TX = DOCK_PADS["UARTHS_RX"].number, DOCK_PADS["UARTHS_TX"].number
PAD_LCD_CS, PAD_LCD_RST = DOCK_PADS["LCD_CS"].number, DOCK_PADS["LCD_RST"].number
PAD_LCD_DC, PAD_LCD_SCLK = DOCK_PADS["LCD_DC"].number, DOCK_PADS["LCD_WR"].number
PAD_SD_MISO, PAD_SD_SCLK = DOCK_PADS["SD_MISO"].number, DOCK_PADS["SD_SCLK"].number
PAD_SD_MOSI, PAD_SD_CS = DOCK_PADS["SD_MOSI"].number, DOCK_PADS["SD_CS"].number
