"""make flash (tools/flash.py): the command line it gives kflash, and what kflash would write.

Flashing was not tried on a real Dock here. Instead the real kflash (the pinned PyPI version, in
the project's venv) talks to a pseudo-terminal whose other end is a responder written here that
answers as the K210's mask ROM (ISP protocol: greeting, memory writes of kflash's flash loader,
boot) and then as that loader (flash greeting, baud change, flash init, flash writes, reboot)
do, from what kflash sends and waits for (kflash.py's MAIXLoader). The responder keeps every
flash write by address; the test reassembles the flash and checks it holds kflash's image around
our firmware.bin byte for byte. A pseudo-terminal has no DTR/RTS lines (pyserial raises
"Inappropriate ioctl for device" when kflash pulses them to reset the board into ISP mode), so
kflash runs under a two-line harness that makes setting them do nothing; everything else is
kflash as installed."""
from __future__ import annotations

import binascii
import hashlib
import os
import pty
import select
import struct
import subprocess
import sys
import threading
import tty

import pytest

from suite import ROOT
from emulator.board.flash_image import FlashImage

from tools.flash import BOARD, kflash_arguments

OK = 0xE0
HARNESS = ("import runpy, sys, serial; "
           "serial.Serial._update_dtr_state = lambda self: None; "
           "serial.Serial._update_rts_state = lambda self: None; "
           "sys.argv = ['kflash'] + sys.argv[1:]; runpy.run_module('kflash', run_name='__main__')")


class FakeDock(threading.Thread):
    """The K210 on the far end of the serial line: the ROM's ISP, then kflash's flash loader."""

    def __init__(self, fd: int) -> None:
        super().__init__(daemon=True)
        self.fd = fd
        self.flash: dict[int, bytes] = {}
        self.sram: dict[int, bytes] = {}
        self.ops: list[int] = []
        self.booted = self.rebooted = False
        self.stop = False

    def _frames(self):
        buffer, frame, escape = b"", None, False
        while not self.stop:
            ready, _, _ = select.select([self.fd], [], [], 0.1)
            if not ready:
                continue
            try:
                data = os.read(self.fd, 65536)
            except OSError:
                return
            for byte in data:
                if frame is None:
                    if byte == 0xC0:
                        frame = bytearray()
                elif escape:
                    frame.append({0xDC: 0xC0, 0xDD: 0xDB}[byte])
                    escape = False
                elif byte == 0xDB:
                    escape = True
                elif byte == 0xC0:
                    if frame:
                        yield bytes(frame)
                        frame = None
                    # an empty frame: two C0 in a row, the second opens the next one
                    else:
                        frame = bytearray()
                else:
                    frame.append(byte)

    def reply(self, op: int, reason: int = OK) -> None:
        os.write(self.fd, bytes((0xC0, op, reason, 0xC0)))

    def run(self) -> None:
        for frame in self._frames():
            op = frame[0]
            self.ops.append(op)
            if op in (0xC3, 0xD4):          # memory write (ROM) / flash write (loader)
                crc, address, length = struct.unpack_from("<III", frame, 4)
                data = frame[16:16 + length]
                good = len(data) == length and binascii.crc32(frame[8:16] + data) == crc
                (self.sram if op == 0xC3 else self.flash)[address] = data
                self.reply(op, OK if good else 0xE2)
            elif op == 0xC5:                # boot the loader: from now on the flash loader answers
                self.booted = True
            elif op in (0xC2, 0xD2, 0xD7):  # greetings, flash init
                self.reply(op)
            elif op == 0xD5:
                self.rebooted = True
                self.reply(op)
            # 0xD6 (baud rate change) has no answer

    def flash_image(self) -> bytes:
        out = bytearray()
        for address in sorted(self.flash):
            assert address == len(out), "flash written with a gap"
            out += self.flash[address]
        return bytes(out)


def flash_through_kflash(image, tmp_path) -> FakeDock:
    master, slave = pty.openpty()
    tty.setraw(slave)
    dock = FakeDock(master)
    dock.start()
    try:
        run = subprocess.run([sys.executable, "-c", HARNESS, *kflash_arguments(os.ttyname(slave), 1_500_000, image)],
                             cwd=tmp_path, capture_output=True, text=True, timeout=120)
    finally:
        dock.stop = True
        dock.join(5)
        os.close(master)
        os.close(slave)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    return dock


def test_kflash_writes_our_firmware_bin_unchanged(firmware, tmp_path):
    image = ROOT / "build" / "firmware.bin"
    dock = flash_through_kflash(image, tmp_path)
    assert dock.booted and dock.rebooted and 0x80000000 in dock.sram     # its loader, into SRAM
    written = dock.flash_image()
    body = image.read_bytes()
    head = bytes((0x02,)) + struct.pack("<I", len(body))                  # not encrypted, dual I/O
    assert written == head + body + hashlib.sha256(head + body).digest()
    # and `--flash build/firmware.bin` gives the board model's flash those very bytes, then boots them
    flash = FlashImage.open(image)
    assert bytes(flash.data[:len(written)]) == written and flash.boot_program() == body


def test_a_changed_byte_shows(firmware, tmp_path):
    """The comparison above sees one byte: a copy with one byte changed flashes to another image."""
    changed = bytearray((ROOT / "build" / "firmware.bin").read_bytes())
    changed[100] ^= 0xFF
    copy = tmp_path / "changed.bin"
    copy.write_bytes(changed)
    written = flash_through_kflash(copy, tmp_path).flash_image()
    assert written[5:-32] == bytes(changed) != (ROOT / "build" / "firmware.bin").read_bytes()


def test_the_make_target_and_bad_ports(firmware):
    dry = subprocess.run(["make", "-n", "flash", "PORT=/dev/ttyUSB0"], cwd=ROOT, capture_output=True, text=True)
    assert "tools/flash.py --port \"/dev/ttyUSB0\" --baud 1500000 build/firmware.bin" in dry.stdout
    assert kflash_arguments("/dev/ttyUSB0", 1_500_000, ROOT / "x.bin")[:4] == ["-p", "/dev/ttyUSB0", "-B", BOARD]
    for args, words in ((["--port", ""], "no serial port"),
                        (["--port", "/dev/nonexistent-tty"], "/dev/nonexistent-tty: no such serial port")):
        run = subprocess.run([sys.executable, "tools/flash.py", *args], cwd=ROOT, capture_output=True, text=True)
        assert run.returncode == 2 and words in run.stderr
