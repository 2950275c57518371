"""An SDHC card in SPI mode, backed by an image file, as the Dock's micro SD slot holds it.

The card sees bytes on MOSI and answers on MISO, byte for byte, as the SD Physical
Layer Simplified Specification describes SPI mode:

- power-up: at least 74 clocks with CS high before the first command (Physical Layer
  Simplified Specification, "Power Up": "the host shall supply at least 74 SD clocks ...
  In case of SPI mode, CS shall be held to high during 74 clock cycles"). Real cards
  evidently take CMD0 without them (issue 10: firmware that ran on Docks sends none), so
  by default CMD0 is answered, with a warning; `strict` enforces the rule: CMD0 is ignored;
- CMD0 (enter SPI mode, idle), CMD8 (interface condition, R7), CMD55 + ACMD41
  (initialisation: the card stays idle until ACMD41 comes INIT_TIME after the
  first one), CMD58 (OCR, R3: powered up, CCS = 1), CMD59 (CRC on/off), CMD9/CMD10
  (CSD/CID as 16-byte data blocks), CMD13 (R2), CMD16 (block length; fixed 512 on
  SDHC), CMD17/CMD18 (single/multiple block read, until CMD12), CMD24/CMD25
  (single/multiple block write), CMD12 (stop: a stuff byte, R1, then busy);
- Ncr: responses come NCR_BYTES bytes after the command;
- Nac: a read's first data block comes once the card has read it from its flash: the
  card answers 0xFF until `access_time` after the command's last bit (the read access
  time, READ_ACCESS_TIME by default, --sd-access-time), then NAC_BYTES more bytes of
  0xFF, a 0xFE token, 512 bytes and their CRC16. Further blocks of a CMD18 stream follow
  NAC_BYTES after the previous one (a card reads the next block while it sends one: a
  measured 4 GB card waits only before the first, cqr113.github.io 2018); the
  "varying-nac" fault varies that gap. The CSD and CID come after NAC_BYTES;
- CRC7 is checked on CMD0 and CMD8 always, and on every command after CMD59(1);
  a bad CRC answers R1 with the CRC-error bit and the command is not executed.
  CRC16 of written blocks is checked while CRC checking is on;
- any other command, or an application command without CMD55, answers R1 with
  the illegal-command bit.

Block addresses (CCS = 1). The image is opened read-only unless writes are asked
for; then writes go to the file. Read-only, the card still accepts writes (it has
no write-protect switch in SPI mode) but keeps them in memory for the run only,
so the image on disk never changes.

Capacity: the card holds exactly the image's blocks; a read or write at a block past
them answers R1 with the parameter-error bit (the argument is outside the card's
range), a CMD18 stream that runs past them ends in an out-of-range error token. The
CSD (version 2.0) states the capacity as (C_SIZE + 1) x 512 KiB, so it can only be
exact for an image of whole 512 KiB (what the card builder makes); for other sizes
it states the whole 512 KiB units the image holds, so a host that believes the CSD
never reads past the image (and one of under 512 KiB, which no CSD can state, is
stated as 512 KiB). Either is a warning, as is a partition table entry that runs
past the image's end: a card whose partition table claims more than the card holds
is the firmware's to judge (as a real card of that size would be), but on an image
it usually means a download cut short, so the user hears of it. Only an image the
card cannot hold at all is refused: empty, or not a whole number of 512-byte blocks.
"""
from __future__ import annotations

import binascii

import os
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import BadInput, write_failed
from ..vtime import PS_PER_MS, PS_PER_US, Time

BLOCK = 512
NCR_BYTES = 1            # bytes of 0xFF between a command and its response (spec: 1..8)
NAC_BYTES = 8            # bytes of 0xFF before a data token once the data are ready
# A read's access time, from the command to its first block ready to send. Real cards differ: the SD
# specification bounds it at 100 ms for SDHC (Physical Layer Simplified Specification, "Read" timeouts)
# and CSD 2.0 states 1 ms (TAAC 0x0E) whatever the card; a Toshiba 4 GB card was measured at about
# 0.6 ms (cqr113.github.io, 2018, CMD17); the card of the thesis's Dock took 0.547 ms a block for its
# 367-block texture and 0.552 ms for its 78-block model, each about 0.2 ms more than this model with
# no access time takes for the same reads (docs/measurements.md), so that card's access time was about
# 0.2 ms. That card, the only one measured on a Dock, sets the default.
READ_ACCESS_TIME: Time = 200 * PS_PER_US
VARYING_NAC_MAX = 24     # the "varying-nac" fault's longest gap: 1 .. 24 bytes, every value in 24 blocks
STOP_BUSY_BYTES = 4      # busy (0x00) bytes after CMD12
WRITE_BUSY: Time = 250 * PS_PER_US     # programming time after a written block
INIT_TIME: Time = 10 * PS_PER_MS       # initialisation time after the first ACMD41
POWER_UP_CLOCKS = 74
RULE_POWER_UP_CLOCKS = "SD card CMD0 before 74 clocks with CS high"   # the board counts it by this kind

R1_IDLE, R1_ILLEGAL, R1_CRC, R1_ADDRESS, R1_PARAMETER = 0x01, 0x04, 0x08, 0x20, 0x40
TOKEN_START, TOKEN_MULTI_WRITE, TOKEN_STOP_TRAN = 0xFE, 0xFC, 0xFD
ERROR_TOKEN_OUT_OF_RANGE = 0x08
DATA_ACCEPTED, DATA_CRC_ERROR = 0x05, 0x0B
OCR_POWERED_UP, OCR_CCS, OCR_VOLTAGE = 1 << 31, 1 << 30, 0x00FF_8000
CSD_UNIT_BLOCKS = 1024   # an SDHC CSD counts capacity in 512 KiB: (C_SIZE + 1) * 1024 blocks
CSD_C_SIZE_MAX = (1 << 22) - 1   # C_SIZE's 22 bits: 2 TiB at most
MBR_SIGNATURE = b"\x55\xaa"
MBR_TABLE, MBR_ENTRY_BYTES, MBR_ENTRIES = 446, 16, 4


def crc7(data: bytes) -> int:
    """CRC7 (x^7 + x^3 + 1) of data, as the 7-bit value."""
    crc = 0
    for byte in data:
        for bit in range(7, -1, -1):
            feedback = ((byte >> bit) & 1) ^ ((crc >> 6) & 1)
            crc = (crc << 1) & 0x7F
            if feedback:
                crc ^= 0x09
    return crc


def crc16(data: bytes) -> int:
    """CRC16-CCITT (x^16 + x^12 + x^5 + 1, initial 0) as SD data blocks carry it: the standard
    library's crc_hqx is this CRC (XMODEM's), about 20 times faster than a table loop in Python."""
    return binascii.crc_hqx(data, 0)


def crc16_bitwise(data: bytes) -> int:
    """The same CRC from its definition, bit by bit (for tests)."""
    crc = 0
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def command_frame(index: int, argument: int) -> bytes:
    """The 6-byte frame of a command, with its CRC7 (for tests and tools)."""
    body = bytes([0x40 | index]) + argument.to_bytes(4, "big")
    return body + bytes([(crc7(body) << 1) | 1])


class SdImage:
    """The card's storage: the image file, read-only unless `writable`. `warn` hears what is
    odd about the image but still usable (see the module comment)."""

    def __init__(self, path: str | Path, writable: bool = False, warn: Callable[[str], None] | None = None) -> None:
        path = Path(path)
        if not path.is_file():
            raise BadInput(f"SD card image {path} does not exist")
        size = path.stat().st_size
        if size == 0 or size % BLOCK:
            raise BadInput(f"SD card image {path}: {size} bytes is not a whole number of 512-byte blocks "
                           f"(truncated?)")
        self.path = path
        self.writable = writable
        if size // BLOCK // CSD_UNIT_BLOCKS > CSD_C_SIZE_MAX + 1:
            raise BadInput(f"SD card image {path}: {size} bytes is more than the 2 TiB a card's CSD (version 2.0, "
                           f"C_SIZE of 22 bits) can state")
        try:
            self._file = path.open("r+b" if writable else "rb", buffering=0)
        except OSError as error:
            purpose = "for writing (--sd-writable)" if writable else "for reading"
            raise BadInput(f"SD card image {path}: cannot open it {purpose} ({error.strerror or error})") from None
        self.blocks = size // BLOCK
        self.overlay: dict[int, bytes] = {}
        notes = self._capacity_notes() + self._partition_notes()
        for note in notes:
            (warn or (lambda text: None))(f"SD card image {self.path}: {note}")

    @property
    def csd_c_size(self) -> int:
        """C_SIZE of the CSD: the whole 512 KiB units the image holds, less one (at least 0)."""
        return max(0, self.blocks // CSD_UNIT_BLOCKS - 1)

    def _capacity_notes(self) -> list[str]:
        """Why the CSD cannot state the image's size exactly, if it cannot."""
        stated = (self.csd_c_size + 1) * CSD_UNIT_BLOCKS
        if stated == self.blocks:
            return []
        if stated > self.blocks:
            return [f"{self.blocks} blocks is less than 512 KiB, the smallest capacity an SDHC card's CSD can "
                    f"state: the CSD says {stated} blocks, and blocks {self.blocks} on answer out of range"]
        return [f"{self.blocks} blocks is not a whole number of 512 KiB (an SDHC card's capacity is "
                f"(C_SIZE + 1) x 512 KiB): the CSD states {stated} blocks, so the last {self.blocks - stated} "
                f"are beyond what the firmware is told"]

    def _partition_notes(self) -> list[str]:
        """Every MBR entry that runs past the image's end: the card is what it is, but an image
        whose partition table claims more than it holds was probably cut short."""
        mbr = os.pread(self._file.fileno(), BLOCK, 0)
        if mbr[BLOCK - len(MBR_SIGNATURE):] != MBR_SIGNATURE:
            return []   # no MBR: a superfloppy or a blank card; the firmware will say what it thinks
        notes = []
        for entry in range(MBR_ENTRIES):
            raw = mbr[MBR_TABLE + MBR_ENTRY_BYTES * entry: MBR_TABLE + MBR_ENTRY_BYTES * (entry + 1)]
            kind = raw[4]
            first = int.from_bytes(raw[8:12], "little")
            count = int.from_bytes(raw[12:16], "little")
            if kind and count and first + count > self.blocks:
                notes.append(f"partition {entry + 1} (type 0x{kind:02X}, blocks {first}..{first + count - 1}) "
                             f"runs past the image's last block {self.blocks - 1}: a truncated image? The card "
                             f"holds only the image's blocks")
        return notes

    def read(self, block: int) -> bytes:
        """A block as the image holds it now. The image is read (pread), not mapped: a file cut
        short while the run goes on is then a clear stop, not a SIGBUS."""
        if block in self.overlay:
            return self.overlay[block]
        data = os.pread(self._file.fileno(), BLOCK, block * BLOCK)
        if len(data) != BLOCK:
            self._gone(block)
        return data

    def write(self, block: int, data: bytes) -> None:
        if not self.writable:
            self.overlay[block] = bytes(data)
            return
        if block >= self.blocks or os.fstat(self._file.fileno()).st_size < (block + 1) * BLOCK:
            self._gone(block)
        piece, at = memoryview(bytes(data)), block * BLOCK
        try:
            while piece:
                written = os.pwrite(self._file.fileno(), piece, at)
                piece, at = piece[written:], at + written
        except OSError as error:                   # a full disk under a sparse image
            raise write_failed(self.path, error) from None

    def _gone(self, block: int) -> None:
        size = os.fstat(self._file.fileno()).st_size
        raise BadInput(f"SD card image {self.path}: block {block} is gone: the file is {size} bytes now, "
                       f"{self.blocks * BLOCK} when the run began (changed by another program during the run)")

    def close(self) -> None:
        if self.writable:
            os.fsync(self._file.fileno())
        self._file.close()


# Faults a test can inject, to drive firmware error paths a healthy card never takes.
FAULTS = {
    "no-init": "ACMD41 never completes: the card stays idle (the firmware should time out)",
    "bad-crc": "every data block (the CSD and CID registers too) is sent with a wrong CRC16",
    "flaky-crc": "the first time each block (or register) is sent its CRC16 is wrong; a retry gets it right",
    "varying-nac": f"the gap before each data block's token (Nac) varies from block to block, 1 to "
                   f"{VARYING_NAC_MAX} bytes of 0xFF, as a slower card's read access time does (else "
                   f"always {NAC_BYTES})",
}


class SdCard:
    """The card's SPI-mode state machine. `exchange` takes MOSI bytes and returns MISO bytes."""

    def __init__(self, image: SdImage, warn=None, faults: frozenset[str] = frozenset(), strict: bool = False,
                 on_rule: Callable[[str, Time, str], None] | None = None,
                 access_time: Time = READ_ACCESS_TIME) -> None:
        """warn(text) hears the card's warnings; on_rule(kind, now, text), instead, a broken timing
        rule (RULE_POWER_UP_CLOCKS), enforced when `strict` (see the module comment); `access_time`
        is the read access time (Nac) before a read's first block."""
        if access_time < 0:
            raise BadInput(f"SD card read access time {access_time} ps is negative")
        self.access_time = access_time
        unknown = set(faults) - set(FAULTS)
        if unknown:
            raise BadInput(f"unknown SD card fault(s): {', '.join(sorted(unknown))} (known: {', '.join(FAULTS)})")
        self.faults = frozenset(faults)
        self._blocks_sent: set[int | str] = set()
        self.commands: dict[int, int] = {}      # command index -> times received (whole frames)
        self.image = image
        self.warn = warn or (lambda text: None)
        self.strict = strict
        self.on_rule = on_rule or (lambda kind, now, text: self.warn(text))
        self.selected = False
        self.spi_mode = False
        self.initialised = False
        self.init_started: Time | None = None
        self.crc_checking = False
        self.app_command = False
        self.powerup_clocks = 0
        self._command = bytearray()
        self._out = bytearray()
        self._out_pos = 0
        self._reading: int | None = None      # next block of a CMD18 stream
        self._write_mode: str | None = None   # "single" or "multi" while a write command is active
        self._write_buffer: bytearray | None = None
        self._busy_until: Time = 0
        # a read's first block is held until its access time has passed: where it begins in _out, and when
        self._hold_at: int | None = None
        self._hold_until: Time = 0
        self.commands_seen: list[int] = []

    # --- chip select ---------------------------------------------------------------

    def set_selected(self, selected: bool, now: Time) -> None:
        if selected == self.selected:
            return
        self.selected = selected
        if not selected:
            # CS high: a half-received command is dropped and the card lets go of MISO
            self._command.clear()

    # --- byte exchange -------------------------------------------------------------------

    def exchange(self, mosi: np.ndarray, now: Time, clocked_at: Callable[[int], Time] | None = None) -> np.ndarray:
        """The card's answer to a run of bytes clocked while it is selected, handed over at `now`;
        clocked_at(i) says when byte i was clocked (else: all at `now`). (Worked on as bytes: most
        runs are one byte long, where numpy's per-call cost would dominate.)"""
        n = len(mosi)
        if not self.selected:
            self.powerup_clocks += 8 * n
            return np.full(n, 0xFF, dtype=np.uint8)
        data = mosi.tobytes()
        out = bytearray(b"\xff" * n)
        at = clocked_at or (lambda i: now)
        i = 0
        while i < n:
            if self._write_buffer is not None or (self._write_mode and not self._command):
                out[i] = self._write_byte(data[i], at(i))
                i += 1
                continue
            pending = len(self._out) - self._out_pos
            if self._hold_at is not None:
                pending = min(pending, self._hold_at - self._out_pos)
            if pending and not self._command:
                # bulk path: while the host only clocks 0xFF, stream what the card has to say
                run = data[i:i + pending]
                take = len(run) - len(run.lstrip(b"\xff"))
                if take:
                    out[i:i + take] = self._out[self._out_pos:self._out_pos + take]
                    self._out_pos += take
                    i += take
                    self._refill_stream()
                    continue
            out[i] = self._next_out_byte(at(i))
            self._command_byte(data[i], at(i))
            i += 1
        return np.frombuffer(out, dtype=np.uint8)

    def _next_out_byte(self, now: Time) -> int:
        if self._hold_at is not None and self._out_pos >= self._hold_at:
            if now < self._hold_until:
                return 0xFF    # still reading the block from its flash
            self._hold_at = None
        if self._out_pos < len(self._out):
            byte = self._out[self._out_pos]
            self._out_pos += 1
            self._refill_stream()
            return byte
        return 0x00 if now < self._busy_until else 0xFF   # busy while programming a block

    def _say(self, data: bytes) -> None:
        if self._out_pos >= len(self._out) and self._hold_at is None:
            self._out = bytearray()
            self._out_pos = 0
        self._out += data

    def _abandon_read(self) -> None:
        """A read ends where it is: its stream, what it queued and its hold are dropped."""
        self._reading = None
        self._out = bytearray()
        self._out_pos = 0
        self._hold_at = None

    def _hold_next(self, now: Time) -> None:
        """What is said next waits for the read access time from `now` (a read command's last bit)."""
        if self.access_time:
            self._hold_at = len(self._out)
            self._hold_until = now + self.access_time

    def _refill_stream(self) -> None:
        """A CMD18 stream keeps producing blocks as the host reads them."""
        if self._reading is not None and len(self._out) - self._out_pos < BLOCK:
            self._queue_block(self._reading)
            if self._reading is not None:
                self._reading += 1

    def _queue_block(self, block: int) -> None:
        gap = b"\xff" * self._read_gap(block)
        if block >= self.image.blocks:
            self._say(gap + bytes([ERROR_TOKEN_OUT_OF_RANGE]))
            self._reading = None
            return
        data = self.image.read(block)
        self._say(gap + bytes([TOKEN_START]) + data + self._data_crc(data, block).to_bytes(2, "big"))

    def _read_gap(self, block: int) -> int:
        """Bytes of 0xFF before block `block`'s data token (Nac): fixed, or with the "varying-nac"
        fault 1 .. VARYING_NAC_MAX, each value once in any VARYING_NAC_MAX consecutive blocks (7 and
        24 are coprime)."""
        if "varying-nac" in self.faults:
            return 1 + block * 7 % VARYING_NAC_MAX
        return NAC_BYTES

    def _data_crc(self, data: bytes, key: int | str) -> int:
        """The CRC16 sent with a data block (a block, key = its number, or a register, key = its
        name), made wrong as the faults ask: always, or the first time this key is sent."""
        crc = crc16(data)
        if "bad-crc" in self.faults or ("flaky-crc" in self.faults and key not in self._blocks_sent):
            crc ^= 0xFFFF
        self._blocks_sent.add(key)
        return crc

    # --- commands ------------------------------------------------------------------------

    def _command_byte(self, byte: int, now: Time) -> None:
        if not self._command:
            if byte & 0xC0 != 0x40:
                return   # not a command start: 0xFF while the host waits, or noise
        self._command.append(byte)
        if len(self._command) == 6:
            frame = bytes(self._command)
            self._command.clear()
            self._execute(frame, now)

    def _r1(self) -> int:
        return 0 if self.initialised else R1_IDLE

    def _execute(self, frame: bytes, now: Time) -> None:
        index = frame[0] & 0x3F
        self.commands[index] = self.commands.get(index, 0) + 1
        argument = int.from_bytes(frame[1:5], "big")
        app = self.app_command
        self.app_command = False
        self.commands_seen.append(index + (100 if app else 0))
        if not self.spi_mode and index != 0:
            return   # in SD mode the card does not answer on these lines
        if index != 12 and self._hold_at is not None:
            # a command while a read's block is still being fetched (a host that gave up waiting, or
            # resets the card): the read is abandoned, so that the answer is not queued behind it
            self._abandon_read()
        if index == 12 and self._reading is not None:
            # stop transmission: drop what was queued, one stuff byte, R1, busy
            self._abandon_read()
            self._say(b"\xff" + bytes([self._r1()]) + b"\x00" * STOP_BUSY_BYTES)
            return
        crc_ok = (crc7(frame[:5]) << 1 | 1) == frame[5]
        if not self.spi_mode and not crc_ok:
            return   # still in SD mode, where a command with a bad CRC gets no response
        if (index in (0, 8) or self.crc_checking) and not crc_ok:
            self._respond(self._r1() | R1_CRC)
            return
        if index == 0:
            if not self.spi_mode and self.powerup_clocks < POWER_UP_CLOCKS:
                text = (f"SD card: CMD0 after only {self.powerup_clocks} clocks with CS high (the SD "
                        f"specification asks for at least {POWER_UP_CLOCKS} after power-up)")
                if self.strict:
                    self.on_rule(RULE_POWER_UP_CLOCKS, now, f"{text}: ignored (--strict)")
                    return
                self.on_rule(RULE_POWER_UP_CLOCKS, now, f"{text}: answered (--strict ignores it)")
            self.spi_mode = True
            self.initialised = False
            self.init_started = None
            self._reading = None
            self._respond(R1_IDLE)
        elif index == 8:
            if argument & 0xF00 != 0x100:
                self._respond(self._r1(), (argument & 0xFF).to_bytes(4, "big"))   # voltage not accepted
            else:
                self._respond(self._r1(), (argument & 0xFFF).to_bytes(4, "big"))
        elif index == 55:
            self.app_command = True
            self._respond(self._r1())
        elif index == 41 and app:
            if self.init_started is None:
                self.init_started = now
            if not argument & (1 << 30):
                self._respond(self._r1())   # without HCS an SDHC card never leaves idle
                return
            if now - self.init_started >= INIT_TIME and "no-init" not in self.faults:
                self.initialised = True
            self._respond(self._r1())
        elif index == 58:
            ocr = OCR_VOLTAGE | (OCR_POWERED_UP | OCR_CCS if self.initialised else 0)
            self._respond(self._r1(), ocr.to_bytes(4, "big"))
        elif index == 59:
            self.crc_checking = bool(argument & 1)
            self._respond(self._r1())
        elif not self.initialised and index in (9, 10, 12, 13, 16, 17, 18, 24, 25):
            self._respond(R1_IDLE | R1_ILLEGAL)
        elif index in (9, 10):
            register = self._csd() if index == 9 else self._cid()
            crc = self._data_crc(register, "CSD" if index == 9 else "CID")
            self._respond(0)
            self._say(b"\xff" * NAC_BYTES + bytes([TOKEN_START]) + register + crc.to_bytes(2, "big"))
        elif index == 13:
            self._respond(0, b"\x00")
        elif index == 16:
            self._respond(0 if argument <= BLOCK else R1_PARAMETER)
        elif index in (17, 18):
            if argument >= self.image.blocks:
                self._respond(R1_PARAMETER)
                return
            self._respond(0)
            self._hold_next(now)
            self._queue_block(argument)
            if index == 18:
                self._reading = argument + 1
        elif index in (24, 25):
            if argument >= self.image.blocks:
                self._respond(R1_PARAMETER)
                return
            self._respond(0)
            self._write_mode = "single" if index == 24 else "multi"
            self._write_block = argument
        elif index == 12:
            self._respond(0)
        else:
            self._respond(self._r1() | R1_ILLEGAL)

    def _respond(self, r1: int, extra: bytes = b"") -> None:
        self._say(b"\xff" * NCR_BYTES + bytes([r1]) + extra)

    # --- writes ----------------------------------------------------------------------------

    def _write_byte(self, byte: int, now: Time) -> int:
        busy = now < self._busy_until
        reply = self._next_out_byte(now)
        if self._write_buffer is None:
            if busy:
                return reply   # still programming the previous block: the host must wait
            if byte == TOKEN_START and self._write_mode == "single" or byte == TOKEN_MULTI_WRITE and self._write_mode == "multi":
                self._write_buffer = bytearray()
            elif byte == TOKEN_STOP_TRAN and self._write_mode == "multi":
                self._write_mode = None
                self._busy_until = now + WRITE_BUSY
            elif byte & 0xC0 == 0x40 and self._write_mode:
                self._write_mode = None
                self._command_byte(byte, now)
            return reply
        self._write_buffer.append(byte)
        if len(self._write_buffer) < BLOCK + 2:
            return reply
        data = bytes(self._write_buffer[:BLOCK])
        crc = int.from_bytes(self._write_buffer[BLOCK:], "big")
        self._write_buffer = None
        if self.crc_checking and crc != crc16(data):
            self._say(bytes([DATA_CRC_ERROR]))
            self._write_mode = None
            return reply
        self.image.write(self._write_block, data)
        self._write_block += 1
        self._say(bytes([DATA_ACCEPTED]))
        self._busy_until = now + WRITE_BUSY
        if self._write_mode == "single":
            self._write_mode = None
        return reply

    # --- registers ---------------------------------------------------------------------------

    def _csd(self) -> bytes:
        """CSD version 2.0 (SDHC): capacity = (C_SIZE + 1) * 512 KiB (SdImage.csd_c_size)."""
        c_size = self.image.csd_c_size
        csd = bytearray(16)
        csd[0] = 0x40                      # CSD_STRUCTURE = 1
        csd[1] = 0x0E                      # TAAC
        csd[3] = 0x32                      # TRAN_SPEED: 25 MHz
        csd[4], csd[5] = 0x5B, 0x59        # CCC, READ_BL_LEN = 9
        csd[7] = (c_size >> 16) & 0x3F
        csd[8] = (c_size >> 8) & 0xFF
        csd[9] = c_size & 0xFF
        csd[10], csd[11], csd[12], csd[13] = 0x7F, 0x80, 0x0A, 0x40
        csd[15] = (crc7(bytes(csd[:15])) << 1) | 1
        return bytes(csd)

    def _cid(self) -> bytes:
        cid = bytearray(b"\x00EMK210SD\x10\x00\x00\x00\x01\x01\x6a\x00")
        cid[15] = (crc7(bytes(cid[:15])) << 1) | 1
        return bytes(cid)
