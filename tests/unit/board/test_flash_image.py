"""--flash IMAGE (board/flash_image.py): the Dock's 16 MiB SPI flash from a kfpkg, a program .bin or
a dump, and the mask ROM's boot from it: the boot header kflash writes (flag, length, program,
SHA-256; kflash.py's flash_firmware), checked as the ROM checks it, the program copied to
0x8000_0000. A run with --flash and no firmware file boots what `kflash firmware.bin` would have
written, and prints what the same program run from its ELF prints."""
from __future__ import annotations

import hashlib
import json
import mmap
import os
import shutil
import struct
import subprocess
import sys
import zipfile

import pytest

from suite import ROOT, run_emulator
from emulator.board.flash_image import ERASED, FLASH_SIZE, HEADER, FlashImage, with_boot_header
from emulator.errors import BadInput
from k210_common.exit_status import EXIT_BAD_INPUT, EXIT_USAGE

PROGRAM = bytes(range(256)) * 3


def kfpkg(path, listing: str, files: dict[str, bytes]):
    with zipfile.ZipFile(path, "w") as package:
        package.writestr("flash-list.json", listing)
        for name, data in files.items():
            package.writestr(name, data)
    return path


def test_the_boot_header_is_flag_length_program_and_its_sha256():
    image = with_boot_header(PROGRAM)
    assert image[0] == 0x02 and struct.unpack_from("<I", image, 1)[0] == len(PROGRAM)
    assert image[5:5 + len(PROGRAM)] == PROGRAM
    assert image[-32:] == hashlib.sha256(image[:-32]).digest() and len(image) == 5 + len(PROGRAM) + 32


def test_a_program_bin_is_written_at_0_with_its_header_and_boots(tmp_path):
    (tmp_path / "firmware.bin").write_bytes(PROGRAM)
    flash = FlashImage.open(tmp_path / "firmware.bin")
    assert len(flash.data) == FLASH_SIZE and flash.data[5 + len(PROGRAM) + 32] == ERASED
    assert flash.boot_program() == PROGRAM


def test_a_kfpkg_places_each_file_at_its_address(tmp_path):
    # kflash's own listings write addresses as bare hexadecimal, which is not JSON
    listing = ('{"version": "0.1.0", "files": [{"address": 0, "bin": "app.bin", "sha256Prefix": true},\n'
               '{"address": 0x300000, "bin": "data.bin", "sha256Prefix": false}]}')
    path = kfpkg(tmp_path / "app.kfpkg", listing, {"app.bin": PROGRAM, "data.bin": b"model data"})
    flash = FlashImage.open(path)
    assert flash.boot_program() == PROGRAM
    assert flash.data[0x300000:0x300000 + 10] == b"model data" and flash.data[0x300000 + 10] == ERASED
    assert flash.data[0x2FFFFF] == ERASED


def test_a_dump_is_the_flash_from_address_0(tmp_path):
    dump = with_boot_header(PROGRAM) + b"\0" * 100
    (tmp_path / "flash.img").write_bytes(dump)
    flash = FlashImage.open(tmp_path / "flash.img")
    assert flash.data[:len(dump)] == dump and flash.data[len(dump)] == ERASED
    assert flash.boot_program() == PROGRAM


@pytest.mark.parametrize("damage, message", [
    (lambda image: bytes([0xFF]) + image[1:], "no boot header"),
    (lambda image: bytes([3]) + image[1:], "AES-encrypted"),
    (lambda image: bytes([0]) + image[1:], "SHA-256 after it does not match"),
    (lambda image: image[:10] + bytes([image[10] ^ 1]) + image[11:], "SHA-256 after it does not match"),
    (lambda image: image[:1] + struct.pack("<I", 0) + image[5:], "length of 0 bytes"),
])
def test_the_rom_refuses_what_it_would_not_boot(tmp_path, damage, message):
    (tmp_path / "flash.img").write_bytes(damage(with_boot_header(PROGRAM)))
    with pytest.raises(BadInput, match=message):
        FlashImage.open(tmp_path / "flash.img").boot_program()


def test_bad_files_are_named_with_what_is_wrong(tmp_path):
    with pytest.raises(BadInput, match="does not exist"):
        FlashImage.open(tmp_path / "missing.img")
    (tmp_path / "big.img").write_bytes(b"\xff" * (FLASH_SIZE + 1))
    with pytest.raises(BadInput, match="more than the Dock's"):
        FlashImage.open(tmp_path / "big.img")
    (tmp_path / "broken.kfpkg").write_bytes(b"PK\x03\x04 not really a zip")
    with pytest.raises(BadInput, match="not a readable kfpkg"):
        FlashImage.open(tmp_path / "broken.kfpkg")
    with pytest.raises(BadInput, match="holds flash-list.json"):
        FlashImage.open(_zip_without_listing(tmp_path / "c.kfpkg"))
    with pytest.raises(BadInput, match="names app.bin, which the package does not hold"):
        FlashImage.open(kfpkg(tmp_path / "d.kfpkg", '{"files": [{"address": 0, "bin": "app.bin"}]}', {}))
    with pytest.raises(BadInput, match="does not fit"):
        FlashImage.open(kfpkg(tmp_path / "e.kfpkg", '{"files": [{"address": "0xFFFFF0", "bin": "x"}]}',
                              {"x": b"x" * 32}))
    with pytest.raises(BadInput, match="not a kfpkg listing"):
        FlashImage.open(kfpkg(tmp_path / "f.kfpkg", '{"files": ', {}))


def _zip_without_listing(path):
    with zipfile.ZipFile(path, "w") as package:
        package.writestr("app.bin", PROGRAM)
    return path


# --- booting through the command line -----------------------------------------------------------

@pytest.fixture
def hello_bin(c_firmware, tmp_path):
    objcopy = shutil.which("riscv64-unknown-elf-objcopy")
    if objcopy is None:
        pytest.skip("riscv64-unknown-elf-objcopy is not installed")
    path = tmp_path / "hello.bin"
    subprocess.run([objcopy, "-O", "binary", str(c_firmware / "hello.elf"), str(path)], check=True)
    return path


def console(out) -> list[str]:
    return [entry["line"] for entry in json.loads((out / "run.json").read_text())["console"]]


def test_booting_from_flash_runs_what_the_elf_runs(c_firmware, hello_bin, tmp_path):
    from_elf = run_emulator("run", str(c_firmware / "hello.elf"), "--until", "0.02", "--quiet",
                            "--out", str(tmp_path / "elf"))
    package = kfpkg(tmp_path / "hello.kfpkg", '{"files": [{"address": 0, "bin": "hello.bin", "sha256Prefix": true}]}',
                    {"hello.bin": hello_bin.read_bytes()})
    for image, out in ((hello_bin, "bin"), (package, "kfpkg")):
        run = run_emulator("run", "--flash", str(image), "--until", "0.02", "--quiet", "--out", str(tmp_path / out))
        assert run.returncode == 0 and from_elf.returncode == 0, run.stderr
        assert console(tmp_path / out) == console(tmp_path / "elf") and console(tmp_path / out)[0].startswith("hello")


def test_a_flash_the_rom_would_not_boot_is_bad_input(hello_bin, tmp_path):
    image = bytearray(with_boot_header(hello_bin.read_bytes()))
    image[100] ^= 0xFF
    (tmp_path / "flash.img").write_bytes(image)
    run = run_emulator("run", "--flash", str(tmp_path / "flash.img"), "--until", "0.01", "--quiet",
                       "--out", str(tmp_path / "out"))
    assert run.returncode == EXIT_BAD_INPUT and "SHA-256 after it does not match" in run.stderr
    assert "Traceback" not in run.stderr


def test_a_run_needs_a_firmware_or_a_flash(tmp_path):
    run = run_emulator("run", "--until", "0.01", "--out", str(tmp_path / "out"))
    assert run.returncode == EXIT_USAGE and "--flash IMAGE" in run.stderr


def test_the_renderer_booted_from_its_flash_image_draws_the_golden_frames(firmware, card, tmp_path):
    # build/firmware.bin is what `make flash` hands kflash; booted from the flash it draws as its ELF does
    run = run_emulator("run", "--flash", str(firmware.parent / "firmware.bin"), "--sd", str(card), "--frames", "2",
                       "--golden", str(ROOT / "tests" / "golden" / "default"), "--quiet", "--out", str(tmp_path / "out"))
    assert run.returncode == 0, run.stderr
    assert "all 2 frames match" in run.stderr


def test_a_chip_reset_boots_the_flash_again_as_the_rom_does(hello_bin):
    """After a chip reset the ROM reads the flash again: the same program comes back; one the run
    rewrote, or a flash it left unbootable, is a clear stop (booting a new program mid-run is not
    modelled)."""
    from emulator.board import Board
    from emulator.errors import UnmodelledAccess
    board = Board(None, flash=FlashImage.open(hello_bin))
    board.memory.load(0x8000_0000, b"\x00" * 16)         # the program's first bytes overwritten in SRAM
    board.reset_chip("soft", 0.001)
    assert board.memory.read(0x8000_0000, 16) == hello_bin.read_bytes()[:16]
    board.flash.data[HEADER.size + 8] ^= 0xFF              # the program in the flash changed
    with pytest.raises(UnmodelledAccess, match="the ROM would not boot the flash any more"):
        board.reset_chip("soft", 0.002)
    rewritten = with_boot_header(hello_bin.read_bytes()[:-4] + b"\x13\x00\x00\x00")
    board.flash.data[:len(rewritten)] = rewritten
    with pytest.raises(UnmodelledAccess, match="the program in the flash has changed"):
        board.reset_chip("soft", 0.003)


def test_erased_flashes_are_each_their_own():
    """FlashImage.erased maps one erased template copy-on-write (flash_image.erased_bytes): every
    byte reads erased, and what one board's flash is written never shows in another's."""
    first, second = FlashImage.erased(), FlashImage.erased()
    if hasattr(os, "memfd_create"):
        assert isinstance(first.data, mmap.mmap)          # (a bytearray each would pass the rest)
    assert len(first.data) == FLASH_SIZE and first.data[:16] == bytes([ERASED]) * 16
    assert first.data[FLASH_SIZE - 1] == ERASED
    first.data[0x1000:0x1004] = b"\x12\x34\x56\x78"
    assert second.data[0x1000:0x1004] == bytes([ERASED]) * 4 and FlashImage.erased().data[0x1000] == ERASED
    assert first.data[0x1000:0x1004] == b"\x12\x34\x56\x78"


def test_an_erased_flash_under_a_file_size_limit_is_made_in_memory():
    """A memory file counts against `ulimit -f`, and writing one past it fails (CPython ignores
    SIGXFSZ): under a limit below the flash's size the erased flash is a bytearray."""
    script = ("import resource; resource.setrlimit(resource.RLIMIT_FSIZE, (1 << 20, 1 << 20)); "
              "from emulator.board.flash_image import FlashImage, ERASED; f = FlashImage.erased(); "
              "print(type(f.data).__name__, f.data[123] == ERASED)")
    result = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert result.returncode == 0 and result.stdout.split() == ["bytearray", "True"], result.stderr
