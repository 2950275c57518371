"""Tests of the ST7789V model against the datasheet behaviour it documents."""
from __future__ import annotations

import numpy as np
import pytest

from k210_fixtures import idle_elf, make_board  # noqa: F401

from emulator.vtime import PS_PER_MS, PS_PER_US, Time

from emulator.devices.st7789v import (
    CASET, COLMOD, DISPOFF, DISPON, INVOFF, INVON, MADCTL, NOP, NORON, PTLON,
    RAMWR, RASET, RULE_AFTER_RESET, RULE_AFTER_SLEEP, RULE_RESET_PULSE, RULE_SLEEP_TOGGLE, SLPIN, SLPOUT,
    SWRESET, ST7789V,
)

RED565 = (0xF8, 0x00)
BLACK_RGB = (0, 0, 0)
RED_RGB = (255, 0, 0)


class Host:
    """Drives the controller the way firmware does; every transfer is 1 ms after
    the previous one, so no timing rule is broken unless a test says so."""

    def __init__(self, on_frame=None, strict: bool = False) -> None:
        self.lcd = ST7789V(on_frame, strict=strict)
        self.t: Time = 0

    def cmd(self, code: int, *params: int, gap: Time = PS_PER_MS) -> None:
        self.t += gap
        self.lcd.write(np.array([code], dtype=np.uint8), 0, self.t)
        if params:
            self.lcd.write(np.array(params, dtype=np.uint8), 1, self.t)

    def data(self, payload, gap: Time = PS_PER_MS) -> None:
        self.t += gap
        self.lcd.write(np.asarray(payload, dtype=np.uint8), 1, self.t)

    def window(self, xs: int, xe: int, ys: int, ye: int) -> None:
        self.cmd(CASET, xs >> 8, xs & 0xFF, xe >> 8, xe & 0xFF)
        self.cmd(RASET, ys >> 8, ys & 0xFF, ye >> 8, ye & 0xFF)

    def wake(self, madctl: int = 0xA0, colmod: int = 0x55) -> None:
        self.cmd(SLPOUT)
        self.t += 120 * PS_PER_MS
        self.cmd(NORON)
        self.cmd(MADCTL, madctl)
        self.cmd(COLMOD, colmod)
        self.cmd(DISPON)

    def clear(self) -> None:
        """Black GRAM everywhere (uses MADCTL 0x00 and restores the current one)."""
        madctl = self.lcd.madctl
        self.cmd(MADCTL, 0x00)
        self.window(0, 239, 0, 319)
        self.cmd(RAMWR)
        self.data(np.zeros(240 * 320 * 2, dtype=np.uint8))
        self.cmd(MADCTL, madctl)

    def pixel(self, x: int, y: int, rgb565: tuple[int, int] = RED565) -> None:
        self.window(x, x, y, y)
        self.cmd(RAMWR)
        self.data(rgb565)


def ready_host(madctl: int = 0xA0, colmod: int = 0x55, on_frame=None) -> Host:
    host = Host(on_frame)
    host.wake(madctl=0x00, colmod=0x55)
    host.clear()
    host.cmd(MADCTL, madctl)
    host.cmd(COLMOD, colmod)
    return host


def positions_of(image: np.ndarray, rgb: tuple[int, int, int]) -> list[tuple[int, int]]:
    """PNG (x, y) coordinates of every pixel with exactly this colour."""
    ys, xs = np.nonzero(np.all(image == np.array(rgb, dtype=np.uint8), axis=2))
    return sorted(zip(xs.tolist(), ys.tolist(), strict=True))


def expected_565(image565: np.ndarray) -> np.ndarray:
    """(h, w) RGB565 values -> (h, w, 3) RGB888 the way the model expands them."""
    r5 = (image565 >> 11) & 0x1F
    g6 = (image565 >> 5) & 0x3F
    b5 = image565 & 0x1F
    r6, b6 = (r5 << 1) | (r5 >> 4), (b5 << 1) | (b5 >> 4)
    return np.stack([(c << 2) | (c >> 4) for c in (r6, g6, b6)], axis=2).astype(np.uint8)


# --- reset and timing ------------------------------------------------------------------


def test_power_up_state_is_the_reset_state_with_noisy_gram() -> None:
    lcd = ST7789V()
    assert lcd.sleeping and not lcd.display_on and not lcd.inverted and lcd.normal_mode
    assert lcd.madctl == 0x00
    assert lcd.colmod == 0x66
    assert lcd.window == (0, 0xEF, 0, 0x13F)
    assert lcd.gram.shape == (320, 240)
    assert np.array_equal(lcd.gram, ST7789V().gram), "power-up GRAM must be deterministic"
    assert len(np.unique(lcd.gram)) > 1000, "power-up GRAM should look random"
    assert lcd.warnings == [] and lcd.frames_captured == 0


def _dirty_registers(host: Host) -> None:
    host.wake(madctl=0xA8, colmod=0x55)
    host.cmd(INVON)
    host.cmd(PTLON)
    host.window(3, 40, 5, 60)


def test_hardware_reset_restores_defaults_and_keeps_gram() -> None:
    host = ready_host()
    host.pixel(10, 20)
    _dirty_registers(host)
    gram_before = host.lcd.gram.copy()
    host.lcd.set_reset_pin(0, host.t + PS_PER_MS)
    host.lcd.set_reset_pin(1, host.t + 2 * PS_PER_MS)
    lcd = host.lcd
    assert lcd.sleeping and not lcd.display_on and not lcd.inverted and lcd.normal_mode
    assert (lcd.madctl, lcd.colmod, lcd.window) == (0x00, 0x66, (0, 0xEF, 0, 0x13F))
    assert np.array_equal(lcd.gram, gram_before)
    assert lcd.warnings == []


def test_software_reset_restores_defaults_and_keeps_gram() -> None:
    host = ready_host()
    host.pixel(10, 20)
    _dirty_registers(host)
    gram_before = host.lcd.gram.copy()
    host.cmd(SWRESET)
    lcd = host.lcd
    assert lcd.sleeping and not lcd.display_on and not lcd.inverted and lcd.normal_mode
    assert (lcd.madctl, lcd.colmod, lcd.window) == (0x00, 0x66, (0, 0xEF, 0, 0x13F))
    assert np.array_equal(lcd.gram, gram_before)


def test_command_within_5ms_of_swreset_is_carried_out_with_warning() -> None:
    """Real panels take SWRESET, SLPOUT ... DISPON sent within microseconds (issue 10): by default the
    command is carried out and the broken wait is a warning."""
    host = Host()
    host.cmd(SWRESET)
    host.cmd(MADCTL, 0xA0, gap=4_900 * PS_PER_US)
    assert host.lcd.madctl == 0xA0
    assert len(host.lcd.warnings) == 1
    assert "MADCTL (0x36) sent within 5 ms after SWRESET at t=" in host.lcd.warnings[0]
    assert "carried out" in host.lcd.warnings[0]


def test_command_within_5ms_of_swreset_is_ignored_when_strict() -> None:
    host = Host(strict=True)
    host.cmd(SWRESET)
    host.cmd(MADCTL, 0xA0, gap=4_900 * PS_PER_US)
    assert host.lcd.madctl == 0x00
    assert len(host.lcd.warnings) == 1
    assert "MADCTL (0x36) ignored: chip busy for 5 ms after SWRESET at t=" in host.lcd.warnings[0]
    host.cmd(MADCTL, 0xA0, gap=200 * PS_PER_US)   # 5.1 ms after SWRESET
    assert host.lcd.madctl == 0xA0
    assert len(host.lcd.warnings) == 1


@pytest.mark.parametrize("strict", [False, True])
def test_command_within_5ms_of_resx_release(strict: bool) -> None:
    lcd = ST7789V(strict=strict)
    lcd.set_reset_pin(0, 10 * PS_PER_MS)
    lcd.set_reset_pin(1, 11 * PS_PER_MS)
    lcd.write(np.array([INVON], dtype=np.uint8), 0, 15_900 * PS_PER_US)
    assert lcd.inverted is not strict
    assert len(lcd.warnings) == 1 and "INVON" in lcd.warnings[0] and "RESX release" in lcd.warnings[0]
    lcd.write(np.array([INVON], dtype=np.uint8), 0, 16_100 * PS_PER_US)
    assert lcd.inverted
    assert len(lcd.warnings) == 1


def test_bytes_while_reset_is_held_low_are_ignored() -> None:
    lcd = ST7789V()
    lcd.set_reset_pin(0, 0)
    lcd.write(np.array([INVON], dtype=np.uint8), 0, PS_PER_MS)
    lcd.set_reset_pin(1, 2 * PS_PER_MS)
    lcd.write(np.array([NOP], dtype=np.uint8), 0, 10 * PS_PER_MS)
    assert not lcd.inverted
    assert len(lcd.warnings) == 1 and "RESX is low" in lcd.warnings[0]


def test_short_reset_pulse_resets_with_a_warning() -> None:
    host = Host()
    host.cmd(INVON)
    host.lcd.set_reset_pin(0, 100 * PS_PER_MS)
    host.lcd.set_reset_pin(1, 100 * PS_PER_MS + 5 * PS_PER_US)
    assert not host.lcd.inverted                   # taken as a reset
    assert len(host.lcd.warnings) == 1
    assert "RESX low pulse of 5.00 us is shorter than the 10 us" in host.lcd.warnings[0]


def test_short_reset_pulse_is_no_reset_when_strict() -> None:
    host = Host(strict=True)
    host.cmd(INVON)
    host.lcd.set_reset_pin(0, 100 * PS_PER_MS)
    host.lcd.set_reset_pin(1, 100 * PS_PER_MS + 5 * PS_PER_US)
    assert host.lcd.inverted                       # the state before the pulse
    assert len(host.lcd.warnings) == 1 and "not taken as a reset (--strict)" in host.lcd.warnings[0]
    host.cmd(INVOFF, gap=PS_PER_US)                   # and no 5 ms wait follows it
    assert not host.lcd.inverted and len(host.lcd.warnings) == 1


def test_command_within_5ms_of_slpout_is_accepted_with_warning() -> None:
    host = Host()
    host.cmd(SLPOUT)
    host.cmd(DISPON, gap=2 * PS_PER_MS)
    assert not host.lcd.sleeping and host.lcd.display_on
    assert len(host.lcd.warnings) == 1
    assert "DISPON" in host.lcd.warnings[0] and "SLPOUT" in host.lcd.warnings[0]
    host.cmd(NOP, gap=4 * PS_PER_MS)
    assert len(host.lcd.warnings) == 1


def test_command_within_5ms_of_slpout_is_ignored_when_strict() -> None:
    host = Host(strict=True)
    host.cmd(SLPOUT)
    host.cmd(DISPON, gap=2 * PS_PER_MS)
    assert not host.lcd.sleeping and not host.lcd.display_on
    assert len(host.lcd.warnings) == 1
    assert "DISPON (0x29) ignored: sent within 5 ms after SLPOUT at t=" in host.lcd.warnings[0]


def test_pixels_within_5ms_of_slpout_are_accepted_without_warning() -> None:
    host = ready_host(madctl=0x00)
    host.window(0, 0, 0, 0)
    host.cmd(SLPIN)
    host.t += 200 * PS_PER_MS
    host.cmd(RAMWR)
    host.cmd(SLPOUT)
    host.cmd(RAMWR, gap=10 * PS_PER_MS)
    host.data(RED565, gap=100 * PS_PER_US)
    assert host.lcd.gram[0, 0] == (63 << 12)
    assert host.lcd.warnings == []


@pytest.mark.parametrize("strict", [False, True])
def test_slpin_too_soon_after_slpout(strict: bool) -> None:
    host = Host(strict=strict)
    host.cmd(SLPOUT)
    host.cmd(SLPIN, gap=50 * PS_PER_MS)
    assert host.lcd.sleeping is not strict
    assert len(host.lcd.warnings) == 1 and "120 ms" in host.lcd.warnings[0]
    assert ("ignored (--strict)" if strict else "carried out") in host.lcd.warnings[0]


def test_the_board_hears_every_lcd_warning_and_counts_repeats(idle_elf) -> None:
    """On the board the LCD's notes join the run's warnings (console and run.json), timed when
    the LCD noticed them; the same note again is counted, not repeated."""
    heard: list[str] = []
    board = make_board(idle_elf, on_warning=heard.append)
    lcd = board.lcd
    lcd.set_reset_pin(0, PS_PER_MS)
    lcd.set_reset_pin(1, PS_PER_MS + 2 * PS_PER_US)     # 2 us: too short
    lcd.write(bytes([SLPOUT]), 0, 2 * PS_PER_MS)        # busy for 5 ms after the release
    lcd.write(bytes([SLPOUT]), 0, 10 * PS_PER_MS)
    for n in range(10):                                 # ten commands too soon after SLPOUT
        lcd.write(bytes([NOP]), 0, 11 * PS_PER_MS + n * 100 * PS_PER_US)
    assert len(board.warnings) == 3, board.warnings
    reset, busy, soon = board.warnings
    assert reset.startswith("[     1.002 ms] ST7789V: RESX low pulse of 2.00 us")
    assert busy.startswith("[     2.000 ms] ST7789V: SLPOUT (0x11) sent within 5 ms after RESX release")
    assert soon == ("[    11.000 ms] ST7789V: NOP (0x00) sent within 5 ms after SLPOUT at t=10.000 ms: carried "
                    "out (--strict ignores it, as the chip may) (10 times in all, the last at 11.900 ms)")
    assert heard == [reset, busy, soon.split(" (10 times")[0]]   # each heard once, when first given
    assert len(lcd.warnings) == 12                      # the model itself keeps every note
    # each broken wait is counted under its rule, for run.json's timing_warnings
    assert board.timing_warnings == {RULE_RESET_PULSE: 1, RULE_AFTER_RESET: 1, RULE_AFTER_SLEEP: 10}


# --- parameters and windows ------------------------------------------------------------


def test_caset_raset_parse_big_endian_pairs() -> None:
    host = Host()
    host.cmd(CASET, 0x00, 0x12, 0x01, 0x3F)
    host.cmd(RASET, 0x00, 0x05, 0x00, 0xEF)
    assert host.lcd.window == (0x12, 0x13F, 0x05, 0xEF)


def test_parameters_may_arrive_in_several_writes() -> None:
    host = Host()
    host.cmd(CASET, 0x00, 0x01)
    host.data([0x00])
    assert host.lcd.window == (0, 0xEF, 0, 0x13F), "CASET applies only with its 4th byte"
    host.data([0x07])
    assert host.lcd.window == (1, 7, 0, 0x13F)


def test_partial_caset_followed_by_a_command_is_ignored() -> None:
    host = Host()
    host.cmd(CASET, 0x00, 0x10, 0x00)
    host.cmd(NOP)
    host.data([0x20])
    assert host.lcd.window == (0, 0xEF, 0, 0x13F)
    assert "CASET" in host.lcd.warnings[0] and "3 of 4" in host.lcd.warnings[0]
    assert "NOP" in host.lcd.warnings[1], "the stray byte after NOP is reported too"


def test_unknown_command_is_ignored_with_its_parameters() -> None:
    host = ready_host(madctl=0x00)
    state = host.lcd.registers
    gram = host.lcd.gram.copy()
    host.cmd(0xB2, 0x0C, 0x0C, 0x00, 0x33, 0x33)   # PORCTRL: not modelled
    host.cmd(0xE0, *range(14))                    # PVGAMCTRL: not modelled
    host.cmd(0x2A - 0x20)                         # 0x0A RDDPM: a read, ignored
    assert host.lcd.registers == state
    assert np.array_equal(host.lcd.gram, gram)
    assert host.lcd.warnings == []
    host.window(1, 2, 3, 4)
    assert host.lcd.window == (1, 2, 3, 4)


def test_window_wraps_back_to_its_start() -> None:
    host = ready_host(madctl=0x00)
    host.window(10, 11, 20, 21)
    host.cmd(RAMWR)
    colours = [0x0001, 0x0002, 0x0003, 0x0004, 0x0005, 0x0006]
    host.data(np.array(colours, dtype=">u2").view(np.uint8))
    gram = host.lcd.gram
    b6 = lambda v: ((v << 1) | (v >> 4))   # 5-bit blue -> 6-bit
    assert gram[20, 10] == b6(5)
    assert gram[20, 11] == b6(6)
    assert gram[21, 10] == b6(3)
    assert gram[21, 11] == b6(4)


def test_new_command_ends_ram_write() -> None:
    host = ready_host(madctl=0x00)
    host.window(0, 0, 0, 0)
    host.cmd(RAMWR)
    host.cmd(NOP)
    host.data(RED565)
    assert host.lcd.gram[0, 0] == 0
    assert host.lcd.warnings and "NOP" in host.lcd.warnings[-1]


def test_pixels_outside_the_panel_are_dropped_but_the_pointer_advances() -> None:
    host = ready_host(madctl=0x00)
    host.window(238, 241, 0, 1)        # columns 240 and 241 do not exist without MV
    host.cmd(RAMWR)
    host.data(np.array([1, 2, 3, 4, 5, 6, 7, 8], dtype=">u2").view(np.uint8))
    gram = host.lcd.gram
    b6 = lambda v: ((v << 1) | (v >> 4))
    assert (gram[0, 238], gram[0, 239]) == (b6(1), b6(2))
    assert (gram[1, 238], gram[1, 239]) == (b6(5), b6(6))
    assert np.count_nonzero(gram) == 4


def test_mv_allows_logical_columns_up_to_319() -> None:
    host = ready_host(madctl=0x20)
    host.pixel(319, 239)
    # MV: column = y, row = x
    assert host.lcd.gram[319, 239] == (63 << 12)


def test_start_after_end_gives_a_one_column_window() -> None:
    host = ready_host(madctl=0x00)
    host.window(5, 2, 0, 319)
    host.cmd(RAMWR)
    host.data(np.array([RED565] * 3, dtype=np.uint8).ravel())
    assert positions_of_gram_red(host.lcd.gram) == [(5, 0), (5, 1), (5, 2)]


def positions_of_gram_red(gram: np.ndarray) -> list[tuple[int, int]]:
    """(column, row) of every pure-red GRAM cell."""
    rows, columns = np.nonzero(gram == (63 << 12))
    return sorted(zip(columns.tolist(), rows.tolist(), strict=True))


# --- MADCTL ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("madctl", "logical", "png"),
    [
        # 0xA0 MY|MV: the Dock's upright landscape; logical == PNG
        (0xA0, (0, 0), (0, 0)),
        (0xA0, (319, 0), (319, 0)),
        (0xA0, (0, 239), (0, 239)),
        (0xA0, (100, 50), (100, 50)),
        # 0x00: portrait, shown rotated 90 degrees clockwise
        (0x00, (0, 0), (319, 0)),
        (0x00, (239, 0), (319, 239)),
        (0x00, (0, 319), (0, 0)),
        # 0x60 MX|MV: landscape rotated 180 degrees
        (0x60, (0, 0), (319, 239)),
        (0x60, (319, 0), (0, 239)),
        (0x60, (0, 239), (319, 0)),
        # 0xC0 MY|MX: portrait, rotated 90 degrees counter-clockwise
        (0xC0, (0, 0), (0, 239)),
        (0xC0, (239, 0), (0, 0)),
        (0xC0, (0, 319), (319, 239)),
        # single bits
        (0x20, (0, 0), (319, 0)),    # MV
        (0x20, (1, 0), (318, 0)),
        (0x20, (0, 1), (319, 1)),
        (0x40, (0, 0), (319, 239)),  # MX
        (0x40, (1, 0), (319, 238)),
        (0x80, (0, 0), (0, 0)),      # MY
        (0x80, (1, 0), (0, 1)),
        (0x80, (0, 1), (1, 0)),
        # ML and MH change only the refresh order
        (0xB4, (100, 50), (100, 50)),
    ],
)
def test_madctl_places_a_logical_pixel(madctl: int, logical: tuple[int, int],
                                       png: tuple[int, int]) -> None:
    host = ready_host(madctl=madctl)
    host.pixel(*logical)
    assert positions_of(host.lcd.shown_image(), RED_RGB) == [png]


def test_madctl_00_maps_logical_to_physical_directly() -> None:
    host = ready_host(madctl=0x00)
    host.pixel(5, 7)
    assert positions_of_gram_red(host.lcd.gram) == [(5, 7)]


def test_bgr_swaps_red_and_blue() -> None:
    host = ready_host(madctl=0xA8)
    host.pixel(3, 4, RED565)
    assert positions_of(host.lcd.shown_image(), (0, 0, 255)) == [(3, 4)]
    assert host.lcd.gram[319 - 3, 4] == 63


def test_full_upright_picture_with_madctl_a0() -> None:
    rng = np.random.default_rng(1)
    picture = rng.integers(0, 1 << 16, (240, 320), dtype=np.uint16)
    host = ready_host(madctl=0xA0)
    host.window(0, 319, 0, 239)
    host.cmd(RAMWR)
    host.data(picture.astype(">u2").view(np.uint8).ravel())
    assert np.array_equal(host.lcd.shown_image(), expected_565(picture.astype(np.uint32)))


def test_full_picture_with_madctl_60_is_rotated_180() -> None:
    rng = np.random.default_rng(2)
    picture = rng.integers(0, 1 << 16, (240, 320), dtype=np.uint16)
    host = ready_host(madctl=0x60)
    host.window(0, 319, 0, 239)
    host.cmd(RAMWR)
    host.data(picture.astype(">u2").view(np.uint8).ravel())
    expected = expected_565(picture.astype(np.uint32))[::-1, ::-1]
    assert np.array_equal(host.lcd.shown_image(), expected)


def test_whole_frames_follow_each_change_of_orientation() -> None:
    """Whole frames one after another, the orientation changed between them and back: each shows
    as written in its own orientation (the model keeps what a whole-panel window's cells are per
    window, and forgets it when the window changes)."""
    rng = np.random.default_rng(3)
    host = ready_host(madctl=0xA0)
    for madctl, flip in ((0xA0, False), (0x60, True), (0xA0, False)):
        picture = rng.integers(0, 1 << 16, (240, 320), dtype=np.uint16)
        host.cmd(MADCTL, madctl)
        host.window(0, 319, 0, 239)
        host.cmd(RAMWR)
        host.data(picture.astype(">u2").view(np.uint8).ravel())
        expected = expected_565(picture.astype(np.uint32))
        assert np.array_equal(host.lcd.shown_image(), expected[::-1, ::-1] if flip else expected)


# --- COLMOD ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("rgb565", "rgb"),
    [
        (0xF800, (255, 0, 0)),
        (0x07E0, (0, 255, 0)),
        (0x001F, (0, 0, 255)),
        (0x8410, (134, 130, 134)),   # R5=16 -> R6=33 -> 134; G6=32 -> 130
        (0x0841, (8, 8, 8)),         # R5=1 -> R6=2 -> 8; G6=2 -> 8
        (0x7BEF, (121, 125, 121)),   # R5=15 -> R6=30 -> 121; G6=31 -> 125
    ],
)
def test_colmod_16bit_expansion(rgb565: int, rgb: tuple[int, int, int]) -> None:
    host = ready_host(madctl=0xA0, colmod=0x55)
    host.pixel(0, 0, (rgb565 >> 8, rgb565 & 0xFF))
    assert tuple(host.lcd.shown_image()[0, 0]) == rgb


def test_colmod_18bit_uses_the_upper_six_bits() -> None:
    host = ready_host(madctl=0xA0, colmod=0x66)
    host.window(0, 0, 0, 0)
    host.cmd(RAMWR)
    host.data([0xFC, 0x87, 0x03])
    assert host.lcd.gram[319, 0] == (63 << 12) | (33 << 6) | 0
    assert tuple(host.lcd.shown_image()[0, 0]) == (255, 134, 0)


def test_colmod_12bit_packs_two_pixels_in_three_bytes() -> None:
    host = ready_host(madctl=0xA0, colmod=0x53)
    host.window(0, 1, 0, 0)
    host.cmd(RAMWR)
    host.data([0x8F, 0x1A, 0x5C])        # (R8 GF B1) (RA G5 BC)
    image = host.lcd.shown_image()
    assert host.lcd.gram[319, 0] == (34 << 12) | (63 << 6) | 4
    assert tuple(image[0, 0]) == (138, 255, 16)
    assert tuple(image[0, 1]) == (170, 85, 207)


def test_colmod_12bit_writes_the_first_pixel_of_a_pair_on_its_own() -> None:
    host = ready_host(madctl=0xA0, colmod=0x53)
    host.window(0, 1, 0, 0)
    host.cmd(RAMWR)
    host.data([0xF0, 0x0A])              # pixel 1 complete, half of pixel 2's red
    assert host.lcd.gram[319, 0] == (63 << 12)
    assert host.lcd.gram[318, 0] == 0
    host.data([0x5C])
    assert host.lcd.gram[318, 0] == (42 << 12) | (21 << 6) | 51


def test_colmod_format_is_chosen_by_the_low_three_bits() -> None:
    host = ready_host(colmod=0x66)
    host.cmd(COLMOD, 0x05)
    assert host.lcd.colmod == 0x05
    host.pixel(0, 0, RED565)             # two bytes suffice: 16-bit
    assert tuple(host.lcd.shown_image()[0, 0]) == RED_RGB


def test_unsupported_colmod_keeps_the_previous_format_with_warning() -> None:
    host = ready_host(colmod=0x55)
    host.cmd(COLMOD, 0x77)
    assert host.lcd.colmod == 0x55
    assert len(host.lcd.warnings) == 1 and "COLMOD" in host.lcd.warnings[0]


# --- what is shown -------------------------------------------------------------------------


def test_inversion_inverts_what_is_shown_not_gram() -> None:
    host = ready_host()
    host.pixel(0, 0, (0x84, 0x10))
    gram = host.lcd.gram.copy()
    host.cmd(INVON)
    image = host.lcd.shown_image()
    assert host.lcd.inverted
    assert tuple(image[0, 0]) == (255 - 134, 255 - 130, 255 - 134)
    assert tuple(image[100, 100]) == (255, 255, 255)
    assert np.array_equal(host.lcd.gram, gram)
    host.cmd(INVOFF)
    assert tuple(host.lcd.shown_image()[0, 0]) == (134, 130, 134)


def test_display_off_shows_black() -> None:
    host = ready_host()
    host.pixel(0, 0)
    host.cmd(DISPOFF)
    assert not host.lcd.shown_image().any()
    host.cmd(DISPON)
    assert tuple(host.lcd.shown_image()[0, 0]) == RED_RGB


def test_sleep_shows_black_even_with_display_on() -> None:
    host = ready_host()
    host.pixel(0, 0)
    host.cmd(SLPIN)
    assert host.lcd.display_on and host.lcd.sleeping
    assert not host.lcd.shown_image().any()


def test_image_shape_and_type() -> None:
    image = ready_host().lcd.shown_image()
    assert image.shape == (240, 320, 3) and image.dtype == np.uint8


# --- byte stream details -------------------------------------------------------------------


def test_pixel_split_across_two_writes() -> None:
    host = ready_host(madctl=0xA0, colmod=0x55)
    host.window(0, 1, 0, 0)
    host.cmd(RAMWR)
    host.data([0xF8])
    assert host.lcd.gram[319, 0] == 0
    host.data([0x00, 0x07])
    assert host.lcd.gram[319, 0] == (63 << 12)
    assert host.lcd.gram[318, 0] == 0
    host.data([0xE0])
    assert host.lcd.gram[318, 0] == (63 << 6)


def test_18bit_pixel_split_across_three_writes() -> None:
    host = ready_host(madctl=0xA0, colmod=0x66)
    host.window(0, 0, 0, 0)
    host.cmd(RAMWR)
    for byte in (0x00, 0xFC, 0x00):
        assert host.lcd.gram[319, 0] == 0
        host.data([byte])
    assert host.lcd.gram[319, 0] == (63 << 6)


def test_chip_deselect_discards_a_partial_pixel_but_keeps_ram_write() -> None:
    host = ready_host(madctl=0xA0, colmod=0x55)
    host.window(0, 2, 0, 0)
    host.cmd(RAMWR)
    host.data([0xF8, 0x00, 0x07])        # red, then half a pixel
    host.lcd.set_chip_select(False, host.t + 100 * PS_PER_US)
    host.lcd.set_chip_select(True, host.t + 200 * PS_PER_US)
    host.data([0x00, 0x1F])              # blue: a whole new pixel
    gram = host.lcd.gram
    assert gram[319, 0] == (63 << 12)
    assert gram[318, 0] == 63
    assert gram[317, 0] == 0
    assert host.lcd.warnings == []


def test_bytes_while_deselected_are_ignored() -> None:
    host = ready_host()
    host.lcd.set_chip_select(False, host.t)
    host.cmd(INVON)
    assert not host.lcd.inverted
    assert host.lcd.warnings and "CSX" in host.lcd.warnings[-1]


def test_parameters_continue_across_deselect() -> None:
    host = Host()
    host.cmd(CASET, 0x00, 0x01)
    host.lcd.set_chip_select(False, host.t)
    host.lcd.set_chip_select(True, host.t)
    host.data([0x00, 0x09])
    assert host.lcd.window[:2] == (1, 9)


def test_accepts_bytes_objects() -> None:
    host = ready_host(madctl=0xA0)
    host.window(0, 0, 0, 0)
    host.t += PS_PER_MS
    host.lcd.write(bytes([RAMWR]), 0, host.t)
    host.lcd.write(bytes(RED565), 1, host.t)
    assert tuple(host.lcd.shown_image()[0, 0]) == RED_RGB


# --- frame capture --------------------------------------------------------------------------


def full_frame(picture: np.ndarray) -> np.ndarray:
    return picture.astype(">u2").view(np.uint8).ravel()


def test_frame_is_captured_once_per_full_coverage() -> None:
    frames: list[np.ndarray] = []
    host = ready_host(madctl=0xA0, on_frame=frames.append)
    assert host.lcd.frames_captured == 1 and len(frames) == 1   # the clear in ready_host
    picture = np.random.default_rng(3).integers(0, 1 << 16, (240, 320), dtype=np.uint16)
    host.window(0, 319, 0, 239)
    host.cmd(RAMWR)
    host.data(full_frame(picture))
    assert host.lcd.frames_captured == 2 and len(frames) == 2
    assert np.array_equal(frames[-1], expected_565(picture.astype(np.uint32)))


def test_partial_window_does_not_capture() -> None:
    frames: list[np.ndarray] = []
    host = ready_host(madctl=0xA0, on_frame=frames.append)
    host.window(0, 319, 0, 238)
    host.cmd(RAMWR)
    host.data(np.zeros(320 * 239 * 2, dtype=np.uint8))
    assert len(frames) == 1 and host.lcd.frames_captured == 1
    host.window(0, 319, 0, 239)
    host.cmd(RAMWR)
    host.data(np.zeros(320 * 239 * 2, dtype=np.uint8))   # the same rows again
    assert len(frames) == 1


def test_two_half_windows_make_one_frame() -> None:
    frames: list[np.ndarray] = []
    host = ready_host(madctl=0xA0, on_frame=frames.append)
    picture = np.random.default_rng(4).integers(0, 1 << 16, (240, 320), dtype=np.uint16)
    host.window(0, 319, 0, 119)
    host.cmd(RAMWR)
    host.data(full_frame(picture[:120]))
    assert len(frames) == 1
    host.window(0, 319, 120, 239)
    host.cmd(RAMWR)
    host.data(full_frame(picture[120:]))
    assert len(frames) == 2
    assert np.array_equal(frames[-1], expected_565(picture.astype(np.uint32)))
    # coverage starts afresh after a capture: one more full window is one more frame
    host.window(0, 319, 0, 239)
    host.cmd(RAMWR)
    host.data(full_frame(picture[::-1]))
    assert len(frames) == 3
    assert np.array_equal(frames[-1], expected_565(picture[::-1].astype(np.uint32)))


def test_frame_fires_at_the_completing_pixel_and_wrap_starts_the_next() -> None:
    frames: list[np.ndarray] = []
    host = ready_host(madctl=0xA0, on_frame=frames.append)
    first = np.full((240, 320), 0xF800, dtype=np.uint16)
    second = np.full((240, 320), 0x001F, dtype=np.uint16)
    host.window(0, 319, 0, 239)
    host.cmd(RAMWR)
    # one write: a whole red frame, then the window wraps and 10 blue pixels follow
    host.data(np.concatenate((full_frame(first), full_frame(second[:1, :10]))))
    assert len(frames) == 2
    assert (frames[-1] == np.array(RED_RGB, dtype=np.uint8)).all(), \
        "the frame is captured before the pixels after the completing one"
    host.data(full_frame(second)[20:])
    assert len(frames) == 3
    assert (frames[-1] == np.array((0, 0, 255), dtype=np.uint8)).all()


def test_frame_capture_while_asleep_shows_black() -> None:
    frames: list[np.ndarray] = []
    host = ready_host(madctl=0xA0, on_frame=frames.append)
    host.cmd(SLPIN)
    host.window(0, 319, 0, 239)
    host.cmd(RAMWR, gap=10 * PS_PER_MS)
    host.data(np.full(320 * 240 * 2, 0xFF, dtype=np.uint8))
    assert len(frames) == 2 and not frames[-1].any()
    assert (host.lcd.gram == (1 << 18) - 1).all(), "GRAM is written in sleep mode"


def test_full_frame_in_one_write() -> None:
    frames: list[np.ndarray] = []
    lcd = ST7789V(on_frame=frames.append)
    t = 0
    for code, params, gap in ((SLPOUT, [], 0), (MADCTL, [0xA0], 120 * PS_PER_MS), (COLMOD, [0x55], PS_PER_MS),
                              (CASET, [0, 0, 0x01, 0x3F], PS_PER_MS), (RASET, [0, 0, 0, 0xEF], PS_PER_MS),
                              (DISPON, [], PS_PER_MS), (RAMWR, [], PS_PER_MS)):
        t += gap
        lcd.write(np.array([code], dtype=np.uint8), 0, t)
        if params:
            lcd.write(np.array(params, dtype=np.uint8), 1, t)
    y, x = np.mgrid[0:240, 0:320]
    picture = (((x * 31 // 319) << 11) | ((y * 63 // 239) << 5) | ((x + y) & 0x1F)).astype(np.uint16)
    payload = full_frame(picture)
    assert payload.size == 153_600
    lcd.write(payload, 1, t + PS_PER_MS)
    assert lcd.frames_captured == 1 and len(frames) == 1
    expected = expected_565(picture.astype(np.uint32))
    assert np.array_equal(frames[0], expected)
    assert np.array_equal(lcd.shown_image(), expected)
    assert lcd.warnings == []


@pytest.mark.parametrize("colmod, bytes_per_pixel", [(0x55, 2), (0x66, 3), (0x53, 1.5)])
def test_pixels_kept_back_still_capture_in_the_call_that_completes_the_frame(colmod, bytes_per_pixel) -> None:
    """Pixel bytes are decoded in one go when they could finish a frame: the frame is captured in
    the very write that brings its last pixel, and cells_missing never claims more cells to go
    than there are (the scheduler's turns alone rely on it as a lower bound); it counts the pixels
    the bytes kept back make in the current format, so a frame's bytes are decoded once."""
    frames: list[np.ndarray] = []
    host = ready_host(madctl=0xA0, colmod=colmod, on_frame=frames.append)
    host.window(0, 319, 0, 239)
    host.cmd(RAMWR)
    total = int(320 * 240 * bytes_per_pixel)
    payload = np.random.default_rng(7).integers(0, 256, total + 999, dtype=np.uint8)
    sent = 0
    for chunk in np.array_split(payload, 97):
        host.data(chunk)
        sent += chunk.size
        pixels_complete = int(sent / bytes_per_pixel)
        assert len(frames) == (2 if sent >= total else 1), f"after {sent} bytes"
        if sent < total:
            assert host.lcd.cells_missing() == 320 * 240 - pixels_complete


def test_a_last_byte_completing_a_carried_over_pixel_captures_the_frame_at_once() -> None:
    """The frame's last pixel begun in one write and finished by a single byte in the next: that
    byte's write captures the frame (the half pixel carried over counts towards it)."""
    frames: list[np.ndarray] = []
    host = ready_host(madctl=0xA0, colmod=0x55, on_frame=frames.append)
    host.window(0, 319, 0, 239)
    host.cmd(RAMWR)
    payload = np.random.default_rng(8).integers(0, 256, 320 * 240 * 2, dtype=np.uint8)
    host.data(payload[:-1])
    assert len(frames) == 1
    host.data(payload[-1:])
    assert len(frames) == 2
