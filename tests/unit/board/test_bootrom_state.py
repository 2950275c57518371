"""The state the mask ROM hands a program (the board model's default) against --cold, the reset
value of every register (emulator/board/bootrom.py; docs/design/board-model.md, "The state the firmware is handed")."""
from __future__ import annotations

import json

import pytest
from suite import run_emulator

from emulator.board import bootrom
from emulator.devices import sysctl as sc
from emulator.errors import HardwareMisuse
from k210_fixtures import make_board, program, reg, run_to_done, run_until

MHZ = 1e6

# What firmware written for the real Dock does at its first instructions: it reads the clock set-up
# it was handed, prints on UARTHS without setting it up, and uses SPI0 and the DMAC without enabling
# their clocks (issue 10).
USE_WHAT_WAS_HANDED_OVER = """
    li      s0, 0x50440000          # SYSCTL
    lwu     s2, 0x08(s0)            # pll0
    lwu     s3, 0x20(s0)            # clk_sel0
    lwu     s4, 0x28(s0)            # clk_en_cent
    lwu     s5, 0x2C(s0)            # clk_en_peri
    li      s1, 0x502B0000          # FPIOA
    lwu     s6, 16(s1)              # pad 4
    lwu     s7, 20(s1)              # pad 5
    li      s1, 0x38000000          # UARTHS
    lwu     s8, 0x18(s1)            # div
    li      t0, 'K'
    sw      t0, 0(s1)               # txdata, the transmitter as handed over
    li      t0, 10
    sw      t0, 0(s1)
    li      s1, 0x52000000          # SPI0
    lwu     s9, 0x28(s1)            # sr
    li      s1, 0x50000000          # DMAC
    ld      s10, 0x10(s1)           # cfg
"""


def test_the_program_finds_the_cpu_at_390_mhz_from_pll0():
    board = make_board(cold=False)
    assert board.scheduler.cpu_hz() == 390 * MHZ
    assert board.sysctl.pll_hz(sc.PLL0) == 780 * MHZ
    assert board.sysctl.read(sc.PLL_LOCK, 4, 0.0) & 3 == 3     # locked before the jump
    assert board.sysctl.read(sc.PLL_LOCK, 4, 0.0) >> 8 & 1 == 0  # PLL1 off, as the ROM leaves it


def test_firmware_uses_what_the_rom_left_without_setting_it_up():
    lines = []
    board = make_board(program(USE_WHAT_WAS_HANDED_OVER), cold=False,
                       console=lambda byte: lines.append(byte))
    run_to_done(board)
    assert reg(board, "s2") == bootrom.PLL0_HANDED_OVER
    assert reg(board, "s3") & 7 == 1                               # ACLK from PLL0, divided by 2
    assert reg(board, "s4") == 0x3F                                # CPU, SRAM0/1, APB0/1/2
    for name in ("rom", "dma", "gpio", "spi0", "spi1", "spi3", "fpioa", "aes", "sha", "otp"):
        assert reg(board, "s5") >> sc.PERI_BITS[name] & 1, name
    assert reg(board, "s6") & 0xFF == 18 and reg(board, "s7") & 0xFF == 19   # UARTHS RX / TX
    assert reg(board, "s8") == 390_000_000 // 115_200 - 1
    assert reg(board, "s9") & 4                                    # SPI0 answers: TX FIFO empty
    assert board.warnings == []
    run_until(board, lambda b: len(lines) == 2)                    # two bytes at 115200 baud
    assert bytes(lines) == b"K\n"


def test_cold_starts_from_the_reset_values():
    board = make_board(program(USE_WHAT_WAS_HANDED_OVER), cold=True)
    assert board.scheduler.cpu_hz() == 26 * MHZ
    with pytest.raises(HardwareMisuse, match="FPIOA accessed while its clock is gated"):
        run_to_done(board)
    assert reg(board, "s3") & 1 == 0                               # ACLK from the oscillator
    assert reg(board, "s4") == 0b111 and reg(board, "s5") == 1     # CPU and SRAM; the ROM's clock
    assert board.fpioa.function_of_pad(4) == board.fpioa.function_of_pad(5) == 0xFF   # unrouted


@pytest.mark.parametrize("cold", [False, True])
def test_our_firmware_draws_the_same_frames_from_either_state(firmware, card, firmware_run, tmp_path, cold):
    """The project's firmware sets up its own clocks: from the ROM's state (the default run all the
    golden-frame tests share) and from --cold it draws the golden frames with the same instructions
    (start-up's polls aside)."""
    if not cold:
        result, out, summary = firmware_run
    else:
        out = tmp_path / "cold"
        result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", "4", "--out", str(out),
                              "--quiet", "--cold", "--golden", "tests/golden/default")
        summary = json.loads((out / "run.json").read_text())
        default = firmware_run[2]
        # the drawing is the same work; start-up (frame 0) only polls the SD card a few times more or
        # less, since the cycle-timed instructions before meet its answers at other moments
        assert [f["instructions"] for f in summary["frames"][1:]] == \
            [f["instructions"] for f in default["frames"][1:4]]
        for cold_count, warm_count in zip(summary["frames"][0]["instructions"], default["frames"][0]["instructions"],
                                          strict=True):
            assert abs(cold_count - warm_count) <= warm_count // 1000
    assert result.returncode == 0, result.stderr
    assert summary["cold"] is cold and summary["warnings"] == []
    assert summary["console"][1]["line"] == "clocks: PLL0 806000000 Hz, CPU 403000000 Hz"
