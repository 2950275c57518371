"""FPIOA pad routing and GPIOHS lines (facts sheet sections 4, 5 and 9), and the board
wiring derived from them (LCD reset on pad 37, D/C on pad 38)."""
from __future__ import annotations

import re

import pytest

from emulator.devices import gpiohs as g
from emulator.errors import UnmodelledAccess
from emulator.devices.fpioa import FUNC_GPIOHS0, FUNC_SPI0_SS0, FUNC_UARTHS_TX, PAD_COUNT
from emulator.devices.plic import SOURCE_GPIOHS0
from emulator.vtime import PS_PER_MS, PS_PER_US
from k210_fixtures import board, idle_elf, make_board, program, run_to_done  # noqa: F401

OE_EN, IE_EN = 1 << 12, 1 << 20

US, MS = PS_PER_US, PS_PER_MS


def route(board, pad, function, now=0, extra=OE_EN):
    board.fpioa.write(4 * pad, 4, function | extra, now)


# --- FPIOA -----------------------------------------------------------------------------

def test_pads_start_unrouted(board):
    board.gpiohs.write(g.OUTPUT_EN, 4, 0xFFFF_FFFF, 0)
    for pad in range(PAD_COUNT):
        assert board.wiring.gpiohs_level_on_pad(pad) is None, pad
    assert board.fpioa.pads_with_function(FUNC_SPI0_SS0 + 3) == []
    assert board.wiring.spi0_device(3) is None                 # no LCD chip select until routed


def test_function_of_pad_is_the_low_byte(board):
    route(board, 5, FUNC_UARTHS_TX, extra=OE_EN | 0xF << 8 | 1 << 16)
    route(board, 36, FUNC_SPI0_SS0 + 3)
    assert board.fpioa.function_of_pad(5) == FUNC_UARTHS_TX
    assert board.fpioa.function_of_pad(36) == 15
    assert board.fpioa.read(4 * 5, 4, 0) == FUNC_UARTHS_TX | OE_EN | 0xF << 8 | 1 << 16
    assert board.fpioa.pads_with_function(15) == [36]
    route(board, 40, 15)
    assert board.fpioa.pads_with_function(15) == [36, 40]


def test_fpioa_register_map_ends_after_the_tie_registers(board):
    board.fpioa.write(4 * 47, 4, 24, 0)
    board.fpioa.write(0xC0, 4, 1, 0)              # tie_en[0] follows io[47]
    board.fpioa.write(0xFC, 4, 1, 0)              # tie_val[7]
    with pytest.raises(UnmodelledAccess):
        board.fpioa.write(0x100, 4, 24, 0)


# --- GPIOHS outputs ------------------------------------------------------------------------

def test_output_level_needs_output_enable_and_follows_xor(board):
    gp = board.gpiohs
    gp.write(g.OUTPUT_VAL, 4, 0b0110, 0)
    assert gp.driven_level(1) is None                  # not an output yet
    gp.write(g.OUTPUT_EN, 4, 0b1111, 0)
    assert [gp.driven_level(n) for n in range(4)] == [0, 1, 1, 0]
    gp.write(g.OUTPUT_XOR, 4, 0b0011, 0)
    assert [gp.driven_level(n) for n in range(4)] == [1, 0, 1, 0]
    gp.write(g.OUTPUT_EN, 4, 0b1011, 0)
    assert gp.driven_level(2) is None
    assert gp.read(g.OUTPUT_VAL, 4, 0) == 0b0110    # output_val reads what was written


def test_input_readback(board):
    gp = board.gpiohs
    gp.write(g.OUTPUT_EN, 4, 0b0011, 0)
    gp.write(g.OUTPUT_VAL, 4, 0b0001, 0)
    gp.write(g.PUE, 4, 0b0100, 0)                   # line 2 pulled up, line 3 floating
    assert gp.read(g.INPUT_VAL, 4, 0) == 0             # input_en off: reads 0
    gp.write(g.INPUT_EN, 4, 0b1111, 0)
    assert gp.read(g.INPUT_VAL, 4, 0) == 0b0101
    gp.write(g.OUTPUT_XOR, 4, 0b0011, 0)
    assert gp.read(g.INPUT_VAL, 4, 0) == 0b0110
    gp.write(g.PDE, 4, 0b0100, 0)                   # both pulls: not a clear high
    assert gp.read(g.INPUT_VAL, 4, 0) & 0b0100 == 0
    with pytest.raises(UnmodelledAccess, match="read-only"):
        gp.write(g.INPUT_VAL, 4, 1, 0)


def test_edge_pending_bits_and_write_one_to_clear(board):
    gp = board.gpiohs
    line = 1 << 5
    gp.write(g.INPUT_EN, 4, line, 0)
    gp.write(g.OUTPUT_EN, 4, line, 0)
    gp.write(g.RISE_IP, 4, 0xFFFF_FFFF, 0)         # start clean
    gp.write(g.FALL_IP, 4, 0xFFFF_FFFF, 0)
    assert gp.read(g.RISE_IP, 4, 0) == 0 and gp.read(g.FALL_IP, 4, 0) == 0
    gp.write(g.OUTPUT_VAL, 4, line, US)              # rise
    assert gp.read(g.RISE_IP, 4, US) == line
    assert gp.read(g.FALL_IP, 4, US) == 0
    assert gp.read(g.HIGH_IP, 4, US) == line and gp.read(g.LOW_IP, 4, US) == 0
    gp.write(g.OUTPUT_VAL, 4, 0, 2 * US)             # fall
    assert gp.read(g.FALL_IP, 4, 2 * US) == line
    assert gp.read(g.RISE_IP, 4, 2 * US) == line     # sticky until cleared
    assert gp.read(g.LOW_IP, 4, 2 * US) == line and gp.read(g.HIGH_IP, 4, 2 * US) == 0
    gp.write(g.RISE_IP, 4, 0, 3 * US)                # writing 0 clears nothing
    assert gp.read(g.RISE_IP, 4, 3 * US) == line
    gp.write(g.RISE_IP, 4, line, 3 * US)             # write 1 to clear
    assert gp.read(g.RISE_IP, 4, 3 * US) == 0
    assert gp.read(g.FALL_IP, 4, 3 * US) == line
    gp.write(g.FALL_IP, 4, line, 4 * US)
    assert gp.read(g.FALL_IP, 4, 4 * US) == 0
    # an xor flip is an edge too
    gp.write(g.OUTPUT_XOR, 4, line, 5 * US)
    assert gp.read(g.RISE_IP, 4, 5 * US) == line


def test_gpiohs_interrupt_line_needs_enable(board):
    gp = board.gpiohs
    line = 1 << 3
    gp.write(g.INPUT_EN, 4, line, 0)
    gp.write(g.OUTPUT_EN, 4, line, 0)
    gp.write(g.OUTPUT_VAL, 4, line, US)
    assert not gp.irq_line(3)
    gp.write(g.RISE_IE, 4, line, 2 * US)
    assert gp.irq_line(3) and not gp.irq_line(4)
    assert SOURCE_GPIOHS0 + 3 in board._high_sources()
    gp.write(g.RISE_IP, 4, line, 3 * US)
    assert not gp.irq_line(3)


# --- board wiring ----------------------------------------------------------------------------

def test_gpiohs_level_on_pad_follows_fpioa_routing(board):
    gp = board.gpiohs
    gp.write(g.OUTPUT_EN, 4, 0b11, 0)
    gp.write(g.OUTPUT_VAL, 4, 0b10, 0)
    assert board.wiring.gpiohs_level_on_pad(38) is None          # pad not routed to GPIOHS
    route(board, 38, FUNC_GPIOHS0 + 1)
    assert board.wiring.gpiohs_level_on_pad(38) == 1
    route(board, 38, FUNC_GPIOHS0 + 0)
    assert board.wiring.gpiohs_level_on_pad(38) == 0
    route(board, 38, FUNC_SPI0_SS0)                        # another function: no GPIOHS level
    assert board.wiring.gpiohs_level_on_pad(38) is None
    route(board, 38, FUNC_GPIOHS0 + 31)
    assert board.wiring.gpiohs_level_on_pad(38) is None           # line 31 is not an output


def test_lcd_reset_pin_follows_the_gpiohs_line_on_pad_37(board):
    calls = []
    original = board.lcd.set_reset_pin
    board.lcd.set_reset_pin = lambda level, now: (calls.append((level, now)), original(level, now))
    gp = board.gpiohs
    route(board, 37, FUNC_GPIOHS0 + 4, now=US)
    assert calls == []                                     # undriven: the LCD's pull keeps RESX high
    gp.write(g.OUTPUT_VAL, 4, 0, 2 * US)
    gp.write(g.OUTPUT_EN, 4, 1 << 4, 3 * US)
    assert calls == [(0, 3 * US)]
    gp.write(g.OUTPUT_XOR, 4, 1 << 4, 4 * MS)              # inverted: high again
    assert calls == [(0, 3 * US), (1, 4 * MS)]
    gp.write(g.OUTPUT_VAL, 4, 1 << 4, 5 * MS)              # val ^ xor = 0
    assert calls[-1] == (0, 5 * MS)
    route(board, 37, 0xFF, now=6 * MS)                     # pad released: RESX pulled high
    assert calls[-1] == (1, 6 * MS)


def test_lcd_dc_through_a_program():
    """Firmware routes pad 38 to GPIOHS1 and drives it; the board sees the level."""
    elf = program("""
        li      s0, 0x50440000
        lw      t0, 0x28(s0)
        ori     t0, t0, 1 << 3            # APB0 (FPIOA's bus)
        sw      t0, 0x28(s0)
        lw      t0, 0x2c(s0)
        li      t1, 1 << 20               # FPIOA clock
        or      t0, t0, t1
        sw      t0, 0x2c(s0)
        li      s1, 0x502B0000
        li      t0, 25 | (1 << 12)        # GPIOHS1, output enable
        sw      t0, 38 * 4(s1)
        li      s2, 0x38001000
        li      t0, 2
        sw      t0, 0x0C(s2)              # output_val bit 1
        sw      t0, 0x08(s2)              # output_en bit 1
    """)
    board = make_board(elf)
    run_to_done(board)
    assert board.fpioa.function_of_pad(38) == FUNC_GPIOHS0 + 1
    assert board.wiring.gpiohs_level_on_pad(38) == 1


@pytest.mark.parametrize("interface, lanes, routed_d0, expected", [
    ("spi", 8, True, "a 4-line serial ST7789V (--lcd-interface spi) takes one data line"),
    ("spi", 1, False, "no pad carries SPI0_D0 (FPIOA function 4), its data line"),
    ("8080", 1, True, "the Dock's LCD has an 8-bit parallel bus"),
    ("spi", 1, True, None),
])
def test_the_lcd_takes_the_frame_format_its_interface_has(idle_elf, interface, lanes, routed_d0, expected):
    import numpy as np
    from emulator.errors import HardwareMisuse
    board = make_board(idle_elf, lcd_interface=interface)
    board.sysctl.write(0x54, 4, 1 << 10, 0)                 # misc: SPI0's data lines to the connector
    route(board, 39, 17)                                     # SPI0_SCLK
    route(board, 38, FUNC_GPIOHS0 + 1)
    board.gpiohs.write(g.OUTPUT_EN, 4, 1 << 1, 0)           # D/C driven, low: a command
    if routed_d0:
        route(board, 40, 4)                                  # SPI0_D0
    if expected is None:
        board.lcd_port.spi_transfer(np.array([0x29], dtype=np.uint8), lanes, 0)      # DISPON
        assert board.lcd.display_on
        return
    with pytest.raises(HardwareMisuse, match=re.escape(expected)):
        board.lcd_port.spi_transfer(np.array([0x29], dtype=np.uint8), lanes, 0)
