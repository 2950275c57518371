"""Shared helpers for the peripheral and hart unit tests.

Tiny RISC-V programs are assembled at test time (riscv64-unknown-elf-as/-ld,
linked at 0x8000_0000) and cached for the whole session, so each distinct
source is built once however many tests use it. Boards are built from those
images; register-level tests then poke the peripheral objects directly with
explicit virtual times, CPU-level tests step the board with `run_until`.
"""
from __future__ import annotations

import atexit
import hashlib
import shutil
import subprocess
import tempfile
import textwrap
from pathlib import Path
from typing import Callable

import numpy as np
import pytest
from unicorn import riscv_const as rv

from emulator.board import Board
from emulator.vtime import NEVER, Time, from_seconds, to_seconds

AS = "riscv64-unknown-elf-as"
LD = "riscv64-unknown-elf-ld"

# Both harts start at 0x8000_0000: hart 1 parks in wfi with every interrupt masked
# (it never wakes), hart 0 runs the body and then spins at `done`.
PROLOGUE = """
    .option norelax
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, park_hart1
"""
EPILOGUE = """
done:
    j       done
park_hart1:
    csrw    mie, zero
1:  wfi
    j       1b
"""

_CACHE: dict[str, str] = {}
_DIR: list[Path] = []


def _build_dir() -> Path:
    if not _DIR:
        _DIR.append(Path(tempfile.mkdtemp(prefix="k210-test-fw-")))
        atexit.register(shutil.rmtree, _DIR[0], True)
    return _DIR[0]


def build_elf(source: str, linker_script: Path | None = None) -> str:
    """Assembles and links a complete program (with its own _start); returns the ELF
    path. Cached by source text (and script) for the whole test session. Without a linker
    script the program is one read-write-execute segment at 0x8000_0000; with one (the
    firmware's k210.ld) it gets the firmware's segments and heap and stack symbols."""
    source = textwrap.dedent(source)
    key = hashlib.sha1(f"{source}\0{linker_script}".encode()).hexdigest()[:16]
    path = _CACHE.get(key)
    if path is not None:
        return path
    if shutil.which(AS) is None:
        pytest.skip(f"{AS} not installed")
    directory = _build_dir()
    src, obj, elf = directory / f"{key}.S", directory / f"{key}.o", directory / f"{key}.elf"
    src.write_text(source)
    subprocess.run([AS, "-march=rv64gc", "-mabi=lp64d", "-o", str(obj), str(src)],
                   check=True, capture_output=True, text=True)
    # -N: one segment starting exactly at 0x8000_0000 (no ELF header paged in below SRAM)
    layout = ["-T", str(linker_script)] if linker_script else ["-N", "-Ttext=0x80000000"]
    subprocess.run([LD, *layout, "--no-relax", "-o", str(elf), str(obj)], check=True, capture_output=True, text=True)
    _CACHE[key] = str(elf)
    return str(elf)


def program(body: str, data: str = "") -> str:
    """A program whose hart 0 runs `body` then spins; hart 1 sleeps for good."""
    text = PROLOGUE + textwrap.dedent(body) + EPILOGUE
    if data:
        text += "\n    .data\n    .balign 8\n" + textwrap.dedent(data)
    return build_elf(text)


IDLE_SOURCE = PROLOGUE + EPILOGUE


@pytest.fixture(scope="session")
def idle_elf() -> str:
    return build_elf(IDLE_SOURCE)


def make_board(elf: str | None = None, **kwargs) -> Board:
    """A board for the register-level and CPU-level tests. They test what each register does from
    its reset value, so the board starts cold (26 MHz, clocks gated) unless a test says cold=False
    (the state the mask ROM hands a program, the board model's default)."""
    kwargs.setdefault("cold", True)
    board = Board(elf or build_elf(IDLE_SOURCE), **kwargs)
    board._frames_wanted = 1 << 60   # step freely: no frame count ends a turn early
    board.hang_budget = NEVER
    return board


@pytest.fixture
def board(idle_elf) -> Board:
    """A board running the idle program; peripherals are poked directly."""
    return make_board(idle_elf)


def route_uarths_to_the_console(board: Board) -> Board:
    """Routes pad 5 to UARTHS_TX as the mask ROM leaves it (bootrom.py): a cold board's console is
    whatever FPIOA routes to the USB-serial bridge's pad, nothing until then."""
    from emulator.board import bootrom
    board.fpioa.values[4 * bootrom.PAD_UARTHS_TX] = bootrom.PAD_WORD_UARTHS_TX
    return board


def symbol(board: Board, name: str) -> int:
    for address, sym in board.image.symbols.items():
        if sym == name:
            return address
    raise KeyError(name)


def run_until(board: Board, done: Callable[[Board], bool], max_time_s: float = 0.01,
              max_steps: int = 100_000) -> None:
    """Steps the board until done(board) or max_time_s seconds of virtual time passed."""
    limit = from_seconds(max_time_s)
    for _ in range(max_steps):
        if done(board):
            return
        if board.time > limit:
            break
        board._step()
    assert done(board), f"condition not reached by t = {to_seconds(board.time):.6g} s"


def at_done(board: Board, hart: int = 0) -> bool:
    """Hart 0 has reached the `done` spin loop."""
    return board.harts[hart].uc.reg_read(rv.UC_RISCV_REG_PC) == symbol(board, "done") or \
        board.harts[hart].pc == symbol(board, "done")


def run_to_done(board: Board, max_time_s: float = 0.01) -> None:
    run_until(board, at_done, max_time_s)


def reg(board: Board, name: str, hart: int = 0) -> int:
    return board.harts[hart].uc.reg_read(getattr(rv, f"UC_RISCV_REG_{name.upper()}"))


class RecordingDevice:
    """An SPI device for tests: records selects and transfers (with their times), and
    answers each byte from `replies` (then 0xFF)."""

    def __init__(self, replies: bytes = b"") -> None:
        self.replies = bytearray(replies)
        self.received = bytearray()
        self.transfers: list[tuple[Time, bytes, int]] = []
        self.selects: list[tuple[bool, Time]] = []
        self.dummies: list[tuple[Time, int]] = []

    def spi_select(self, selected: bool, now: Time) -> None:
        self.selects.append((selected, now))

    def spi_dummy(self, clocks: int, now: Time) -> None:
        self.dummies.append((now, clocks))

    def spi_transfer(self, data: np.ndarray, lanes: int, now: Time) -> np.ndarray:
        data = bytes(np.asarray(data, dtype=np.uint8))
        self.received += data
        self.transfers.append((now, data, lanes))
        out = bytearray()
        for _ in data:
            out.append(self.replies.pop(0) if self.replies else 0xFF)
        return np.frombuffer(bytes(out), dtype=np.uint8).copy()
