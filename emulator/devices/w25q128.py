"""The Dock's on-board SPI NOR flash: a Winbond W25Q128FV (16 MiB) on SPI3's chip select 0.

The commands below follow the W25Q128FV datasheet (Winbond, revision M, section 8: instructions,
section 9: AC characteristics). Each command byte comes on one line (the QPI mode is not
modelled); the address, dummy clocks and data follow on the lines the table gives.

| code | command                   | address            | dummy clocks | data               |
|------|---------------------------|--------------------|--------------|--------------------|
| 03   | read data                 | 3 bytes, 1 line    | 0            | out, 1 line        |
| 0B   | fast read                 | 3 bytes, 1 line    | 8            | out, 1 line        |
| 3B   | fast read dual output     | 3 bytes, 1 line    | 8            | out, 2 lines       |
| 6B   | fast read quad output     | 3 bytes, 1 line    | 8            | out, 4 lines (QE)  |
| BB   | fast read dual I/O        | 3 bytes + M, 2     | 0            | out, 2 lines       |
| EB   | fast read quad I/O        | 3 bytes + M, 4     | 4            | out, 4 lines (QE)  |
| 02   | page program              | 3 bytes, 1 line    | 0            | in, 1 line         |
| 32   | quad page program         | 3 bytes, 1 line    | 0            | in, 4 lines (QE)   |
| 20 52 D8 | erase 4 / 32 / 64 KiB | 3 bytes, 1 line    |              |                    |
| C7 60 | chip erase               |                    |              |                    |
| 06 04 50 | write enable / disable / volatile status write enable |   |   |        |
| 05 35 15 | read status register 1 / 2 / 3 |            |              | out, repeated      |
| 01 31 11 | write status register 1 (and 2) / 2 / 3 |    |              | in                 |
| 9F   | JEDEC ID                  |                    |              | EF 40 18           |
| 90   | manufacturer / device ID  | 3 bytes            |              | EF 17 (A0 = 1: 17 EF) |
| AB   | release power-down / ID   | 3 dummy bytes      |              | 17                 |
| B9   | power down                |                    |              |                    |
| 4B   | unique ID                 | 4 dummy bytes      |              | 8 bytes            |
| 66 99 | enable reset / reset     |                    |              |                    |

Program and erase happen when /CS goes high (an erase only if /CS rises right after its address,
as the datasheet requires); the chip is then busy for the typical time (tPP 0.7 ms, tSE 45 ms,
tBE1 120 ms, tBE2 150 ms, tCE 40 s, tW 10 ms) and ignores every command but the status reads,
as it does. Programming only clears bits. Without the write enable latch a program, erase or
status write does nothing, as on the chip; the model says so in the run log.

Chosen where the datasheet leaves it to the part: the status registers start with only QE set
(quad mode on) and are not kept between runs. QE is non-volatile, and every K210 flash driver
(the SDK demos', MicroPython's) sets it when it finds it clear; a Dock in use has it set. The
SDK demo flash_w25qxx even depends on it: it reads the chip's ID right after setting QE without
waiting for the status write (tW, 10 ms) to end, which works only if QE was already set and
the write skipped. The block-protect bits are stored, but a program or erase while they protect
anything stops the run (the protection map is not modelled). The continuous read mode (M5-4 = 10
after EB or BB) and SFDP are not modelled either.
"""
from __future__ import annotations

import mmap
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import UnmodelledAccess
from ..vtime import PS_PER_MS, PS_PER_S, PS_PER_US, Time

SIZE = 16 * 1024 * 1024
PAGE = 256
MANUFACTURER, DEVICE_ID, MEMORY_TYPE, CAPACITY = 0xEF, 0x17, 0x40, 0x18
# The unique ID is the part's own; this one is the model's (any 64-bit value would do)
UNIQUE_ID = bytes.fromhex("4B3231304D4F444C")
ERASED = 0xFF

# status register bits (datasheet section 7.1)
SR1_BUSY, SR1_WEL = 0x01, 0x02
SR1_PROTECT = 0x7C               # BP0-2, TB, SEC
SR2_QE, SR2_CMP = 0x02, 0x40
SR1_WRITABLE, SR2_WRITABLE, SR3_WRITABLE = 0xFC, 0x7B, 0xE4   # bits a status write changes
SR2_LOCK_BITS = 0x38             # LB1-3: one-time programmable, set and never cleared

# typical times (datasheet section 9.6)
T_PAGE_PROGRAM: Time = 700 * PS_PER_US
T_WRITE_STATUS: Time = 10 * PS_PER_MS
T_ERASE: dict[int, Time] = {0x20: 45 * PS_PER_MS, 0x52: 120 * PS_PER_MS, 0xD8: 150 * PS_PER_MS,
                            0xC7: 40 * PS_PER_S, 0x60: 40 * PS_PER_S}
ERASE_SIZE = {0x20: 4096, 0x52: 32 * 1024, 0xD8: 64 * 1024}

READ, PROGRAM, ERASE, STATUS_READ, STATUS_WRITE, ID, CONTROL = ("read", "program", "erase", "status read",
                                                             "status write", "id", "control")


@dataclass(frozen=True)
class Command:
    code: int
    name: str
    kind: str
    address_bytes: int = 0       # address (or dummy) bytes after the code
    address_lines: int = 1
    mode_byte: bool = False      # M7-0 after the address, on the address's lines (BB, EB)
    dummy_clocks: int = 0
    data_lines: int = 1
    quad: bool = False           # needs the QE bit (IO2 and IO3 are /WP and /HOLD otherwise)


COMMANDS = {c.code: c for c in (
    Command(0x03, "read data", READ, 3),
    Command(0x0B, "fast read", READ, 3, dummy_clocks=8),
    Command(0x3B, "fast read dual output", READ, 3, dummy_clocks=8, data_lines=2),
    Command(0x6B, "fast read quad output", READ, 3, dummy_clocks=8, data_lines=4, quad=True),
    Command(0xBB, "fast read dual I/O", READ, 3, address_lines=2, mode_byte=True, data_lines=2),
    Command(0xEB, "fast read quad I/O", READ, 3, address_lines=4, mode_byte=True, dummy_clocks=4,
            data_lines=4, quad=True),
    Command(0x02, "page program", PROGRAM, 3),
    Command(0x32, "quad page program", PROGRAM, 3, data_lines=4, quad=True),
    Command(0x20, "sector erase (4 KiB)", ERASE, 3),
    Command(0x52, "block erase (32 KiB)", ERASE, 3),
    Command(0xD8, "block erase (64 KiB)", ERASE, 3),
    Command(0xC7, "chip erase", ERASE),
    Command(0x60, "chip erase", ERASE),
    Command(0x06, "write enable", CONTROL),
    Command(0x04, "write disable", CONTROL),
    Command(0x50, "volatile status register write enable", CONTROL),
    Command(0x05, "read status register 1", STATUS_READ),
    Command(0x35, "read status register 2", STATUS_READ),
    Command(0x15, "read status register 3", STATUS_READ),
    Command(0x01, "write status register 1", STATUS_WRITE),
    Command(0x31, "write status register 2", STATUS_WRITE),
    Command(0x11, "write status register 3", STATUS_WRITE),
    Command(0x9F, "JEDEC ID", ID),
    Command(0x90, "manufacturer/device ID", ID, 3),
    Command(0xAB, "release power-down / device ID", ID, 3),
    Command(0x4B, "unique ID", ID, 4),
    Command(0xB9, "power down", CONTROL),
    Command(0x66, "enable reset", CONTROL),
    Command(0x99, "reset", CONTROL),
)}
# the commands a busy chip still takes (datasheet 7.1.1: status reads, and suspend, not modelled)
WHILE_BUSY = {0x05, 0x35, 0x15}

COMMAND, ADDRESS, MODE, DUMMY, DATA, DONE, IGNORE = range(7)


class W25Q128:
    """The flash's storage and its command state machine, driven by an SPI controller (devices/spi.py's
    SpiDevice). `data` is the flash's 16 MiB, writable (a FlashImage's data): programs and erases change it."""

    def __init__(self, data: bytearray | memoryview | mmap.mmap, warn: Callable[[str, Time], None]) -> None:
        if len(data) != SIZE:
            raise ValueError(f"the W25Q128 holds {SIZE} bytes, not {len(data)}")
        self.memory = np.frombuffer(data, dtype=np.uint8)
        self.warn = warn
        self.status = [0, SR2_QE, 0]     # status registers 1-3, BUSY and WEL kept apart
        self.write_enabled = False       # WEL
        self.volatile_write = False      # after 50h: the next status write is volatile
        self.busy_until: Time = 0
        self.powered_down = False
        self.reset_enabled = False
        self.changed = False             # a program or erase has happened
        self._wel_clears_at: Time | None = None   # WEL clears when the program or erase under way ends
        self._reset_armed = False        # this command is 99h right after 66h
        self._begin()

    # --- the SpiDevice port ---------------------------------------------------------------------

    def spi_select(self, selected: bool, now: Time) -> None:
        if not selected:
            self._finish(now)
        self._begin()

    def spi_transfer(self, data: np.ndarray, lanes: int, now: Time) -> np.ndarray:
        reply = np.full(len(data), ERASED, dtype=np.uint8)
        i = 0
        while i < len(data):
            if self._stage == DATA:
                reply[i:] = self._data(data[i:], lanes, now)
                break
            self._byte(int(data[i]), lanes, now)
            i += 1
        return reply

    def spi_dummy(self, clocks: int, now: Time) -> None:
        if self._stage == MODE:
            # a controller set up for the address alone clocks the mode bits as wait cycles: its lines
            # are not driven then and read high, M7-0 = FFh, which is not the continuous read mode
            mode_clocks = 8 // self._command.address_lines
            if clocks < mode_clocks:
                self._refuse(f"{clocks} clocks with no data where the mode byte goes", now)
                return
            self._stage, clocks = DUMMY, clocks - mode_clocks
        if self._stage != DUMMY:
            if self._stage != IGNORE:
                self._refuse(f"{clocks} clocks with no data", now)
            return
        self._clocks += clocks
        self._after_dummy(now)

    # --- state --------------------------------------------------------------------------------

    def busy(self, now: Time) -> bool:
        return now < self.busy_until

    def status_register(self, n: int, now: Time) -> int:
        """Status register n (1-3) as a read shows it at `now`."""
        self._settle(now)
        if n != 1:
            return self.status[n - 1]
        return self.status[0] | (SR1_BUSY if self.busy(now) else 0) | (SR1_WEL if self.write_enabled else 0)

    def _settle(self, now: Time) -> None:
        """A program, erase or status write that has ended clears the write enable latch."""
        if self._wel_clears_at is not None and now >= self._wel_clears_at:
            self.write_enabled = False
            self._wel_clears_at = None

    def _begin(self) -> None:
        """/CS fell (or rose): the next byte is a command."""
        self._stage = COMMAND
        self._command: Command | None = None
        self._address = 0
        self._address_seen = 0
        self._clocks = 0
        self._out_index = 0
        self._written: list[np.ndarray] = []

    def _refuse(self, what: str, now: Time) -> None:
        name = f"{self._command.code:02X}h ({self._command.name})" if self._command else "a command"
        self.warn(f"W25Q128: {what} during {name}, which the chip does not expect there: the rest of the "
                  f"command is ignored (on the chip its effect is undefined)", now)
        self._stage = IGNORE

    def _byte(self, value: int, lanes: int, now: Time) -> None:
        """One byte of a command, address, mode or dummy phase (lanes: the lines it came on)."""
        stage = self._stage
        if stage == COMMAND:
            self._start(value, lanes, now)
        elif stage == ADDRESS:
            if lanes != self._command.address_lines:
                self._refuse(f"an address byte on {lanes} line(s) (expected {self._command.address_lines})", now)
                return
            self._address = (self._address << 8) | value
            self._address_seen += 1
            if self._address_seen == self._command.address_bytes:
                self._after_address(now)
        elif stage == MODE:
            if lanes != self._command.address_lines:
                self._refuse(f"the mode byte on {lanes} line(s) (expected {self._command.address_lines})", now)
                return
            if value & 0x30 == 0x20:
                raise UnmodelledAccess(f"W25Q128: {self._command.code:02X}h with mode bits 0x{value:02X} asks "
                                       f"for the continuous read mode, which the model does not have")
            self._stage = DUMMY
            self._after_dummy(now)
        elif stage == DUMMY:
            self._clocks += 8 // lanes
            self._after_dummy(now)
        elif stage == DONE:
            self._refuse("a byte after the command's end", now)

    def _start(self, code: int, lanes: int, now: Time) -> None:
        self._settle(now)
        reset_enabled, self.reset_enabled = self.reset_enabled, False    # 66h arms only the next command
        command = COMMANDS.get(code)
        self._command = command
        if lanes != 1:
            self._command = None
            self.warn(f"W25Q128: command byte 0x{code:02X} came on {lanes} lines; the chip takes commands on one "
                      f"(its QPI mode is not modelled): ignored", now)
            self._stage = IGNORE
            return
        if command is None:
            self.warn(f"W25Q128: command 0x{code:02X} is not one the model knows (w25q128.py lists them): ignored",
                      now)
            self._stage = IGNORE
            return
        self._reset_armed = reset_enabled and code == 0x99
        if code == 0xAB:
            self.powered_down = False
        if self.powered_down:
            self.warn(f"W25Q128: {command.name} ({code:02X}h) while powered down (B9h): ignored, as the chip "
                      f"ignores everything but ABh then", now)
            self._stage = IGNORE
            return
        if self.busy(now) and code not in WHILE_BUSY:
            self.warn(f"W25Q128: {command.name} ({code:02X}h) while a program or erase is under way: ignored, as "
                      f"the chip ignores it (poll BUSY in status register 1 first)", now)
            self._stage = IGNORE
            return
        if command.quad and not self.status[1] & SR2_QE:
            self.warn(f"W25Q128: {command.name} ({code:02X}h) with the QE bit of status register 2 clear: IO2 "
                      f"and IO3 are /WP and /HOLD, so the command does not work (set QE first)", now)
            self._stage = IGNORE
            return
        if command.address_bytes:
            self._stage = ADDRESS
        else:
            self._after_address(now)

    def _after_address(self, now: Time) -> None:
        command = self._command
        if command.mode_byte:
            self._stage = MODE
        elif command.kind == ERASE:
            self._stage = DONE
        else:
            self._stage = DUMMY
            self._after_dummy(now)

    def _after_dummy(self, now: Time) -> None:
        needed = self._command.dummy_clocks
        if self._clocks < needed:
            return
        if self._clocks > needed:
            self._refuse(f"{self._clocks} dummy clocks (it takes {needed})", now)
            return
        if self._command.kind == CONTROL:
            self._control(now)
            self._stage = DONE
        else:
            self._stage = DATA

    def _control(self, now: Time) -> None:
        code = self._command.code
        if code == 0x06:
            self.write_enabled, self.volatile_write = True, False
        elif code == 0x04:
            self.write_enabled = False
        elif code == 0x50:
            self.volatile_write = True
        elif code == 0xB9:
            self.powered_down = True
        elif code == 0x66:
            self.reset_enabled = True
        elif code == 0x99 and self._reset_armed:
            self.write_enabled = self.volatile_write = False

    # --- data phases --------------------------------------------------------------------------

    def _data(self, data: np.ndarray, lanes: int, now: Time) -> np.ndarray:
        command = self._command
        n = len(data)
        if command.kind in (READ, PROGRAM) and lanes != command.data_lines:
            self._refuse(f"data on {lanes} line(s) (expected {command.data_lines})", now)
            return np.full(n, ERASED, dtype=np.uint8)
        if command.kind == READ:
            index = (self._address + np.arange(n)) % SIZE
            self._address = (self._address + n) % SIZE
            return self.memory[index]
        if command.kind in (PROGRAM, STATUS_WRITE):
            self._written.append(data.astype(np.uint8))
            return np.full(n, ERASED, dtype=np.uint8)
        if command.kind == STATUS_READ:
            value = self.status_register({0x05: 1, 0x35: 2, 0x15: 3}[command.code], now)
            return np.full(n, value, dtype=np.uint8)
        # ID
        pattern = self._id_bytes()
        index = (self._out_index + np.arange(n)) % len(pattern)
        self._out_index += n
        return np.frombuffer(pattern, dtype=np.uint8)[index]

    def _id_bytes(self) -> bytes:
        code = self._command.code
        if code == 0x9F:
            return bytes([MANUFACTURER, MEMORY_TYPE, CAPACITY])
        if code == 0x90:
            return bytes([DEVICE_ID, MANUFACTURER]) if self._address & 1 else bytes([MANUFACTURER, DEVICE_ID])
        if code == 0xAB:
            return bytes([DEVICE_ID])
        return UNIQUE_ID

    # --- /CS high: what the command does -------------------------------------------------------------

    def _finish(self, now: Time) -> None:
        command = self._command
        if command is None or self._stage == IGNORE:
            return
        if command.kind == PROGRAM and self._stage == DATA and self._written:
            if self._write_allowed(now):
                self._program(np.concatenate(self._written))
                self._busy_for(T_PAGE_PROGRAM, now)
        elif command.kind == ERASE and self._stage == DONE:
            if self._write_allowed(now):
                self._erase(command.code)
                self._busy_for(T_ERASE[command.code], now)
        elif command.kind == STATUS_WRITE and self._stage == DATA and self._written:
            self._write_status(np.concatenate(self._written), now)

    def _write_allowed(self, now: Time) -> bool:
        command = self._command
        if not self.write_enabled:
            self.warn(f"W25Q128: {command.name} ({command.code:02X}h) without write enable (06h) first: the chip "
                      f"ignores it", now)
            return False
        if self.status[0] & SR1_PROTECT or self.status[1] & SR2_CMP:
            raise UnmodelledAccess(f"W25Q128: {command.name} with block protection set (status register 1 = "
                                   f"0x{self.status[0]:02X}, 2 = 0x{self.status[1]:02X}): which blocks that "
                                   f"protects is not modelled")
        return True

    def _busy_for(self, duration: Time, now: Time) -> None:
        self.busy_until = now + duration
        self._wel_clears_at = self.busy_until
        self.changed = True

    def _program(self, data: np.ndarray) -> None:
        """Page program: bytes past the page's end wrap to its start; of more than a page, the last
        256 bytes count (datasheet 8.2.15). Programming only clears bits."""
        start = self._address % PAGE
        if len(data) > PAGE:
            start = (start + len(data) - PAGE) % PAGE
            data = data[-PAGE:]
        page = self._address - self._address % PAGE
        index = page + (start + np.arange(len(data))) % PAGE
        self.memory[index] &= data

    def _erase(self, code: int) -> None:
        size = ERASE_SIZE.get(code, SIZE)
        first = self._address - self._address % size
        self.memory[first:first + size] = ERASED

    def _write_status(self, data: np.ndarray, now: Time) -> None:
        code = self._command.code
        if not (self.write_enabled or self.volatile_write):
            self.warn(f"W25Q128: {self._command.name} ({code:02X}h) without write enable (06h or 50h) first: the "
                      f"chip ignores it", now)
            return
        if code == 0x01:
            self.status[0] = (self.status[0] & ~SR1_WRITABLE) | (int(data[0]) & SR1_WRITABLE)
            if len(data) > 1:
                self._write_status2(int(data[1]))
        elif code == 0x31:
            self._write_status2(int(data[0]))
        else:
            self.status[2] = (self.status[2] & ~SR3_WRITABLE) | (int(data[0]) & SR3_WRITABLE)
        if self.volatile_write:
            self.volatile_write = False
        else:
            self.busy_until = now + T_WRITE_STATUS
            self._wel_clears_at = self.busy_until

    def _write_status2(self, value: int) -> None:
        old = self.status[1]
        self.status[1] = (old & ~SR2_WRITABLE) | (value & SR2_WRITABLE) | (old & SR2_LOCK_BITS)
