"""The slow GPIO block (0x5020_0000, DesignWare APB GPIO as the SDK's gpio.h lays it out):
registers, pads through FPIOA, the LCD's reset and D/C on GPIO lines, interrupts."""
from __future__ import annotations

import pytest

from emulator.devices import gpio as g
from emulator.errors import HardwareMisuse
from emulator.devices.plic import SOURCE_GPIO
from emulator.vtime import PS_PER_MS, PS_PER_US
from k210_fixtures import board, idle_elf, make_board, program, reg, run_to_done  # noqa: F401

FUNC_GPIO0 = 56
OE_EN, PU, PD = 1 << 12, 1 << 16, 1 << 17

US, MS = PS_PER_US, PS_PER_MS


def route(board, pad, function, now=0, extra=OE_EN):
    board.fpioa.write(4 * pad, 4, function | extra, now)


def test_outputs_drive_their_pads_through_fpioa(board):
    gp = board.gpio
    gp.write(g.DATA_OUTPUT, 4, 0b0101, 0)
    assert gp.driven_level(0) is None                      # an input until its direction says so
    gp.write(g.DIRECTION, 4, 0b0011, 0)
    assert [gp.driven_level(n) for n in range(3)] == [1, 0, None]
    assert board.wiring.pad_level(12) is None                     # not routed yet
    route(board, 12, FUNC_GPIO0 + 0)
    route(board, 13, FUNC_GPIO0 + 1)
    assert (board.wiring.pad_level(12), board.wiring.pad_level(13)) == (1, 0)
    gp.write(g.DATA_OUTPUT, 4, 0b0010, MS)
    assert (board.wiring.pad_level(12), board.wiring.pad_level(13)) == (0, 1)
    assert board.pad_changes[-2:] == [(MS, 12, 0), (MS, 13, 1)]


def test_eight_lines_only(board):
    gp = board.gpio
    gp.write(g.DIRECTION, 4, 0xFFFF_FFFF, 0)
    gp.write(g.DATA_OUTPUT, 4, 0xFFFF_FFFF, 0)
    assert gp.read(g.DIRECTION, 4, 0) == 0xFF
    assert gp.read(g.DATA_OUTPUT, 4, 0) == 0xFF
    assert gp.driven_level(8) is None


def test_external_port_reads_outputs_and_the_pads_pulls(board):
    gp = board.gpio
    route(board, 20, FUNC_GPIO0 + 2, extra=PU)
    route(board, 21, FUNC_GPIO0 + 3, extra=PD)
    route(board, 22, FUNC_GPIO0 + 4, extra=PU | PD)        # both: the pull-down wins, as the pad is 0
    gp.write(g.DIRECTION, 4, 0b1, 0)
    gp.write(g.DATA_OUTPUT, 4, 0b1, 0)
    assert gp.read(g.DATA_INPUT, 4, 0) == 0b0000_0101     # line 0 driven high, line 2 pulled up


def test_level_and_edge_interrupts_reach_plic_source_23(board):
    gp = board.gpio
    route(board, 20, FUNC_GPIO0 + 2)                        # no pull: reads 0
    gp.write(g.INT_POLARITY, 4, 0, 0)                       # active low
    gp.write(g.INT_ENABLE, 4, 1 << 2, 0)                    # level-sensitive
    assert gp.read(g.INT_RAW_STATUS, 4, 0) == 1 << 2
    assert gp.irq_line() and SOURCE_GPIO in board._high_sources()
    gp.write(g.INT_MASK, 4, 1 << 2, 0)
    assert gp.read(g.INT_STATUS, 4, 0) == 0 and not gp.irq_line()
    # edge-sensitive, rising: latched when the pad's pull-up comes on, until eoi
    gp.write(g.INT_MASK, 4, 0, 0)
    gp.write(g.INT_LEVEL, 4, 1 << 2, 0)
    gp.write(g.INT_POLARITY, 4, 1 << 2, 0)
    assert gp.read(g.INT_STATUS, 4, 0) == 0
    route(board, 20, FUNC_GPIO0 + 2, now=MS, extra=PU)
    assert gp.read(g.INT_STATUS, 4, MS) == 1 << 2
    route(board, 20, FUNC_GPIO0 + 2, now=2 * MS)            # falling: not this polarity
    assert gp.read(g.INT_STATUS, 4, 2 * MS) == 1 << 2     # still latched
    gp.write(g.INT_CLEAR, 4, 1 << 2, 3 * MS)
    assert gp.read(g.INT_STATUS, 4, 3 * MS) == 0 and not gp.irq_line()
    gp.write(g.INT_BOTHEDGE, 4, 1 << 2, 3 * MS)
    route(board, 20, FUNC_GPIO0 + 2, now=4 * MS, extra=PU)
    route(board, 20, FUNC_GPIO0 + 2, now=5 * MS)
    gp.write(g.INT_CLEAR, 4, 1 << 2, 5 * MS)
    route(board, 20, FUNC_GPIO0 + 2, now=6 * MS, extra=PU)
    assert gp.read(g.INT_STATUS, 4, 6 * MS) == 1 << 2


def test_an_output_line_raises_no_interrupt(board):
    gp = board.gpio
    gp.write(g.DIRECTION, 4, 1, 0)
    gp.write(g.INT_ENABLE, 4, 1, 0)                         # level, active low; the line drives 0
    assert gp.read(g.INT_RAW_STATUS, 4, 0) == 0


def test_lcd_reset_and_dc_on_gpio_lines(board):
    """The LCD's RESX (pad 37) and D/C (pad 38) may be slow-GPIO lines as well as GPIOHS ones."""
    calls = []
    original = board.lcd.set_reset_pin
    board.lcd.set_reset_pin = lambda level, now: (calls.append((level, now)), original(level, now))
    gp = board.gpio
    route(board, 37, FUNC_GPIO0 + 0, now=US)
    route(board, 38, FUNC_GPIO0 + 1, now=US)
    gp.write(g.DIRECTION, 4, 0b11, 2 * US)                  # both low: RESX asserted
    assert calls == [(0, 2 * US)]
    gp.write(g.DATA_OUTPUT, 4, 0b01, MS)
    assert calls == [(0, 2 * US), (1, MS)]
    assert board.wiring.pad_level(38) == 0
    gp.write(g.DATA_OUTPUT, 4, 0b11, 2 * MS)
    assert board.wiring.pad_level(38) == 1


def test_dc_that_nothing_drives_is_misuse(board):
    board.sysctl.write(0x54, 4, 1 << 10, 0)                 # misc: SPI0's data lines to the LCD
    board.fpioa.write(4 * 39, 4, 17 | OE_EN, 0)             # SPI0_SCLK
    route(board, 38, FUNC_GPIO0 + 1)                        # a GPIO line, but an input
    with pytest.raises(HardwareMisuse, match="D/C line \\(pad 38\\) is not a driven GPIOHS or GPIO output"):
        board.lcd_port.spi_transfer(__import__("numpy").zeros(1, dtype="uint8"), 8, 0)


def test_gpio_through_a_program():
    """Firmware enables the GPIO clock (APB0 and clk_en_peri bit 5), routes GPIO3 to pad 12
    and drives it low, reading the pad back: before the block was modelled this stopped
    the run ("GPIO (the slow GPIO block), which the board model does not implement")."""
    board = make_board(program("""
        li      s0, 0x50440000
        lw      t0, 0x28(s0)
        ori     t0, t0, 1 << 3            # APB0
        sw      t0, 0x28(s0)
        lw      t0, 0x2c(s0)
        li      t1, (1 << 20) | (1 << 5)  # FPIOA and GPIO clocks
        or      t0, t0, t1
        sw      t0, 0x2c(s0)
        li      s1, 0x502B0000
        li      t0, 59 | (1 << 12) | (1 << 16)   # GPIO3, output enable, pull-up
        sw      t0, 12 * 4(s1)
        li      s2, 0x50200000
        lw      s3, 0x50(s2)              # input: the pull-up
        li      t0, 1 << 3
        sw      t0, 0x04(s2)              # direction: output, driving 0
        lw      s4, 0x50(s2)
    """))
    run_to_done(board)
    assert reg(board, "s3") == 1 << 3 and reg(board, "s4") == 0
    assert board.wiring.pad_level(12) == 0


def test_gpio_needs_its_clock():
    board = make_board(program("""
        li      s2, 0x50200000
        lw      s3, 0x50(s2)
    """))
    with pytest.raises(HardwareMisuse, match="GPIO accessed while its clock is gated"):
        run_to_done(board)
