"""The K210's memory-mapped blocks and the Dock's parts on their pins, one module per block
(clint.py, plic.py, uarths.py, ...; st7789v.py, sdcard.py), each written as its datasheet's
register table (mmio.py). A device is given ports (ports.py: its clock, interrupt notice,
warnings, memory, the peers it talks to), never the board.

May import: emulator.errors, emulator.memory_map, emulator.vtime, and this package."""
