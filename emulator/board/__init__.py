"""The Maix Dock composed: the board (dock.py) builds the harts, the devices and their wiring
(wiring.py) and connects them through ports; the scheduler (scheduler.py) owns virtual time and
the harts' turns (sram_waits.py: harts waiting on SRAM; deadlines.py: grace periods and hangs),
traps.py what a hart's trap does; the bus (bus.py) decodes every access outside SRAM and applies the K210's
rules; memory.py is the SRAM, elf.py and raw_image.py load firmware, flash_image.py the on-board flash
(--flash) and the mask ROM's boot from it, bootrom.py sets the state the
mask ROM leaves, write_watch.py checks stores (--check-writes).

May import: emulator.errors, emulator.memory_map, emulator.vtime, emulator.cpu, emulator.devices, and this
package. Never the front-ends."""
from .dock import Board, FrameRecord, RunResult  # noqa: F401  (the board and its results)
