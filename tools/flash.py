"""Writes build/firmware.bin to a real Sipeed Maix Dock with kflash (`make flash PORT=...`).

    python tools/flash.py --port /dev/ttyUSB0 [--baud 1500000] [build/firmware.bin]

kflash (PyPI, pinned in pyproject.toml) talks to the K210's mask ROM over the Dock's USB serial
bridge: it resets the board into the ROM's ISP mode with DTR/RTS as the Dock wires them (board
`dan`), loads its flash loader into SRAM, and writes the image to the on-board flash at address
0 as the ROM boots it: a flag byte (0x02: not encrypted, dual-I/O flash), the length as a
little-endian u32, the firmware, then the SHA-256 of those three. The ROM copies the firmware to
0x8000_0000 at the next reset and starts both harts there, as the board model does.

Exit statuses: EXIT_STATUS_DETAILS (the numbers are k210_common/exit_status.py's).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

from k210_common.exit_status import EXIT_KFLASH_FAILED, EXIT_OK, EXIT_USAGE, help_epilog

ROOT = Path(__file__).resolve().parent.parent
BOARD = "dan"                 # kflash's name for the Maix Dock (CH552 serial bridge, its reset wiring)
DEFAULT_BAUD = 1_500_000      # what the Dock's bridge takes for uploads (kflash's README for `dan`)
CONSOLE_BAUD = 115_200        # the firmware's console (firmware/include/k210.inc UARTHS_BAUD)

# When this command returns each status; --help and docs/reference/'s table are made from it
# (tests/unit/shared/test_exit_status.py)
EXIT_STATUS_DETAILS: dict[int, str] = {
    EXIT_OK: "the firmware was written to the board",
    EXIT_USAGE: "bad command line: no port, a port that does not exist, no image",
    EXIT_KFLASH_FAILED: "kflash failed (its own messages above say why: no board answering, a port in use, ...)",
}


def kflash_arguments(port: str, baud: int, image: Path) -> list[str]:
    """kflash's command line for the Dock."""
    return ["-p", port, "-B", BOARD, "-b", str(baud), "-n", str(image)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="tools/flash.py", description=__doc__.split("\n\n")[0],
                                     epilog=help_epilog(EXIT_STATUS_DETAILS),
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--port", default="", help="the Dock's serial port, e.g. /dev/ttyUSB0")
    parser.add_argument("--baud", type=int, default=DEFAULT_BAUD, help=f"upload baud rate (default {DEFAULT_BAUD})")
    parser.add_argument("image", nargs="?", type=Path, default=ROOT / "build" / "firmware.bin")
    args = parser.parse_args(argv)
    if not args.port:
        print("flash: no serial port: give the Dock's, e.g. make flash PORT=/dev/ttyUSB0", file=sys.stderr)
        return EXIT_USAGE
    if not os.path.exists(args.port):
        print(f"flash: {args.port}: no such serial port (is the Dock plugged in? ls /dev/ttyUSB*)", file=sys.stderr)
        return EXIT_USAGE
    if not args.image.is_file():
        print(f"flash: {args.image}: no such image (make firmware builds build/firmware.bin)", file=sys.stderr)
        return EXIT_USAGE
    command = [sys.executable, "-m", "kflash", *kflash_arguments(args.port, args.baud, args.image)]
    print("flash: " + " ".join(command), flush=True)
    result = subprocess.run(command)
    if result.returncode != 0:
        print(f"flash: kflash failed (exit {result.returncode}); the board was not written as asked", file=sys.stderr)
        return EXIT_KFLASH_FAILED
    print(f"flash: written; see it run with: {sys.executable} -m serial.tools.miniterm {args.port} {CONSOLE_BAUD}")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
