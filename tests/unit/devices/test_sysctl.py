"""SYSCTL model: PLLs and their lock, ACLK selection, SPI source clocks, clock gates,
DMA request selects, and refusal of unknown registers (facts sheet section 3; offsets
as in the Kendryte SDK's sysctl_t)."""
from __future__ import annotations

import pytest

from emulator.devices import sysctl as sc
from emulator.errors import HardwareMisuse, UnmodelledAccess
from emulator.vtime import PS_PER_MS, PS_PER_S, PS_PER_US
from k210_fixtures import board, idle_elf, make_board, program, run_to_done  # noqa: F401

MHZ = 10 ** 6
LOCK = sc.PLL_LOCK_TIME
US, MS = PS_PER_US, PS_PER_MS


def pll_value(clkr=0, clkf=0, clkod=0, *, reset=False, pwrd=True, bypass=False, out_en=True) -> int:
    return (clkr | clkf << 4 | clkod << 10 | (reset << 20) | (pwrd << 21) | (bypass << 23)
            | (out_en << 25))


def lock_bits(board, now) -> int:
    return board.sysctl.read(sc.PLL_LOCK, 4, now)


def bring_pll0_up(board, t0=US, **fields) -> int:
    """SDK sequence: ACLK on the oscillator, program PLL0 in reset, release reset.
    Returns the time PLL0 locks."""
    s = board.sysctl
    s.write(sc.PLL0, 4, pll_value(reset=True, **fields), t0)
    s.write(sc.PLL0, 4, pll_value(reset=False, **fields), t0 + US)
    return t0 + US + LOCK


# --- frequencies --------------------------------------------------------------------

def test_reset_state_runs_cpu_from_the_26_mhz_oscillator(board):
    assert board.sysctl.cpu_hz() == 26 * MHZ
    assert board.scheduler.cpu_hz() == 26 * MHZ
    assert lock_bits(board, 0) & 3 == 3            # PLL0 comes out of reset running


@pytest.mark.parametrize("clkr, clkf, clkod, hz", [
    (0, 30, 0, 806 * MHZ),         # 26 * 31
    (0, 29, 0, 780 * MHZ),
    (1, 61, 0, 806 * MHZ),         # 26 * 62 / 2
    (0, 30, 1, 403 * MHZ),         # 26 * 31 / 2
    (2, 44, 3, 97_500_000),        # 26 * 45 / 3 / 4
    (2, 30, 0, 268_666_666),       # 26 * 31 / 3, rounded down to whole hertz
])
def test_pll_output_formula(board, clkr, clkf, clkod, hz):
    board.sysctl.write(sc.PLL0, 4, pll_value(clkr, clkf, clkod), US)
    assert board.sysctl.pll_hz(sc.PLL0) == hz


def test_pll_bypass_passes_the_oscillator(board):
    board.sysctl.write(sc.PLL0, 4, pll_value(0, 30, 0, bypass=True), US)
    assert board.sysctl.pll_hz(sc.PLL0) == 26 * MHZ


# --- lock ---------------------------------------------------------------------------

def test_pll0_locks_only_after_reset_release_plus_lock_time(board):
    s = board.sysctl
    s.write(sc.PLL0, 4, pll_value(0, 30, 0, reset=True), US)
    assert lock_bits(board, US) & 3 != 3
    assert lock_bits(board, PS_PER_S) & 3 != 3       # held in reset: never locks
    t_release = 2 * MS
    s.write(sc.PLL0, 4, pll_value(0, 30, 0), t_release)
    assert lock_bits(board, t_release) & 3 != 3
    assert lock_bits(board, t_release + LOCK * 98 // 100) & 3 != 3
    assert lock_bits(board, t_release + LOCK - 1) & 3 != 3     # a picosecond before the lock
    assert lock_bits(board, t_release + LOCK) & 3 == 3
    assert lock_bits(board, t_release + PS_PER_S) & 3 == 3
    # the lock moment is a device event the board's clock stops at
    assert s.next_event_time(t_release) == t_release + LOCK


def test_powered_down_pll_never_locks(board):
    s = board.sysctl
    assert lock_bits(board, PS_PER_S) >> 8 & 1 == 0     # PLL1 is off after reset
    s.write(sc.PLL1, 4, pll_value(0, 20, 0, reset=True), US)
    s.write(sc.PLL1, 4, pll_value(0, 20, 0, pwrd=False), 2 * US)
    assert lock_bits(board, PS_PER_S) >> 8 & 1 == 0
    s.write(sc.PLL1, 4, pll_value(0, 20, 0, reset=True), 2 * MS)
    s.write(sc.PLL1, 4, pll_value(0, 20, 0), 3 * MS)
    assert lock_bits(board, 3 * MS + LOCK // 2) >> 8 & 1 == 0
    assert lock_bits(board, 3 * MS + LOCK) >> 8 & 1 == 1
    assert lock_bits(board, 3 * MS + LOCK) & 3 == 3   # PLL0 unaffected


def test_pll2_lock_bit_is_16(board):
    s = board.sysctl
    s.write(sc.PLL2, 4, pll_value(0, 20, 0, reset=True), 0)
    s.write(sc.PLL2, 4, pll_value(0, 20, 0), US)
    assert lock_bits(board, US + LOCK) >> 16 & 1 == 1


def test_aclk_switch_to_pll0_before_lock_is_misuse(board):
    t_lock = bring_pll0_up(board, clkf=30)
    with pytest.raises(HardwareMisuse, match="before PLL0 locked"):
        board.sysctl.write(sc.CLK_SEL0, 4, 1, t_lock - LOCK // 10)
    assert board.sysctl.cpu_hz() == 26 * MHZ


def test_aclk_switch_to_pll0_with_output_disabled_is_misuse(board):
    t_lock = bring_pll0_up(board, clkf=30, out_en=False)
    with pytest.raises(HardwareMisuse, match="out_en"):
        board.sysctl.write(sc.CLK_SEL0, 4, 1, t_lock)


def test_aclk_on_locked_pll0_gives_pll0_over_two_and_retimes_the_board(board):
    t_lock = bring_pll0_up(board, clkf=30)
    board.sysctl.write(sc.CLK_SEL0, 4, 1, t_lock)
    assert board.sysctl.cpu_hz() == 403 * MHZ
    assert board.scheduler.cpu_hz() == 403 * MHZ                    # the board heard about it


@pytest.mark.parametrize("divider_sel, divisor", [(0, 2), (1, 4), (2, 8), (3, 16)])
def test_cpu_hz_with_aclk_divider_sel(board, divider_sel, divisor):
    t_lock = bring_pll0_up(board, clkf=30)
    board.sysctl.write(sc.CLK_SEL0, 4, 1 | divider_sel << 1, t_lock)
    assert board.sysctl.cpu_hz() == 806 * MHZ // divisor
    # the divider without aclk_sel does nothing: ACLK is the oscillator
    board.sysctl.write(sc.CLK_SEL0, 4, divider_sel << 1, t_lock + US)
    assert board.sysctl.cpu_hz() == 26 * MHZ


def test_reprogramming_pll0_while_aclk_uses_it_is_misuse(board):
    t_lock = bring_pll0_up(board, clkf=30)
    board.sysctl.write(sc.CLK_SEL0, 4, 1, t_lock)
    board.sysctl.write(sc.PLL0, 4, pll_value(0, 30, 0), t_lock + US)     # same value: harmless
    with pytest.raises(HardwareMisuse, match="pll0 changed"):
        board.sysctl.write(sc.PLL0, 4, pll_value(0, 29, 0), t_lock + 2 * US)
    with pytest.raises(HardwareMisuse):
        board.sysctl.write(sc.PLL0, 4, pll_value(0, 30, 0, reset=True), t_lock + 3 * US)
    # back on the oscillator, PLL0 may change again
    board.sysctl.write(sc.CLK_SEL0, 4, 0, t_lock + 4 * US)
    board.sysctl.write(sc.PLL0, 4, pll_value(0, 29, 0, reset=True), t_lock + 5 * US)
    assert board.sysctl.pll_hz(sc.PLL0) == 780 * MHZ


def test_firmware_clock_switch_changes_the_cycle_time():
    """Through a real program: SDK-style PLL0 bring-up, wait for the lock, switch ACLK.
    mcycle keeps counting one per instruction, but virtual time per cycle shrinks."""
    elf = program("""
        li      s0, 0x50440000
        li      t0, (30 << 4) | (1 << 20) | (1 << 21) | (1 << 25)   # clkf 30, reset, pwrd, out_en
        sw      t0, 0x08(s0)
        li      t1, ~(1 << 20)
        and     t0, t0, t1
        sw      t0, 0x08(s0)                                          # release reset
    1:  lw      t2, 0x18(s0)
        andi    t2, t2, 3
        li      t3, 3
        bne     t2, t3, 1b
        li      t0, 1
        sw      t0, 0x20(s0)                                          # ACLK = PLL0 / 2
    """)
    board = make_board(elf)
    run_to_done(board)
    assert board.scheduler.cpu_hz() == 403 * MHZ
    assert board.time >= LOCK


# --- SPI clocks, gates, DMA selects ------------------------------------------------------

def test_spi_source_clock_from_clk_th1(board):
    s = board.sysctl
    bring_pll0_up(board, clkf=30)
    assert s.spi_source_hz(0) == 806 * MHZ // 2                     # thresholds 0
    s.write(sc.CLK_TH1, 4, 0x0000_0103, MS)                          # spi0 3, spi1 1
    assert s.spi_source_hz(0) == 806 * MHZ // 8
    assert s.spi_source_hz(1) == 806 * MHZ // 4
    s.write(sc.CLK_TH1, 4, 0xFF << 8, MS)
    assert s.spi_source_hz(0) == 806 * MHZ // 2
    assert s.spi_source_hz(1) == 1_574_218                           # 806 MHz / 512, in whole hertz


def test_clock_gates(board):
    s = board.sysctl
    for name in ("spi0", "spi1", "dma", "fpioa", "gpio"):
        assert not s.gate_open(name), name
    s.write(sc.CLK_EN_PERI, 4, 1 << 6 | 1 << 7 | 1 << 1 | 1 << 20, 0)
    assert s.gate_open("dma")                        # DMA: no APB bus gate
    assert not s.gate_open("spi0")                   # APB2 still off
    assert not s.gate_open("fpioa")                  # APB0 still off
    s.write(sc.CLK_EN_CENT, 4, s.values[sc.CLK_EN_CENT] | 1 << sc.CENT_APB2, 0)
    assert s.gate_open("spi0") and s.gate_open("spi1")
    assert not s.gate_open("fpioa")
    s.write(sc.CLK_EN_CENT, 4, s.values[sc.CLK_EN_CENT] | 1 << sc.CENT_APB0, 0)
    assert s.gate_open("fpioa")
    s.write(sc.CLK_EN_PERI, 4, 1 << 7 | 1 << 20, 0)
    assert not s.gate_open("spi0") and s.gate_open("spi1")


def test_access_to_a_gated_peripheral_stops_the_run():
    board = make_board(program("""
        li      s0, 0x52000000
        lw      t0, 0x28(s0)          # SPI0 sr with SPI0's clock gated
    """))
    with pytest.raises(HardwareMisuse, match="clock is gated") as info:
        run_to_done(board)
    assert "SPI0" in str(info.value) and "0x52000028" in str(info.value)


def test_dma_sel_decoding(board):
    s = board.sysctl
    assert s.dma_request(0) == ("spi0", "rx")         # reset value 0 = SSI0_RX
    sel0 = 1 | 3 << 6 | 2 << 12 | 0 << 18 | 40 << 24
    s.write(sc.DMA_SEL0, 4, sel0, 0)
    s.write(sc.DMA_SEL1, 4, 3, 0)
    assert s.dma_request(0) == ("spi0", "tx")
    assert s.dma_request(1) == ("spi1", "tx")
    assert s.dma_request(2) == ("spi1", "rx")
    assert s.dma_request(3) == ("spi0", "rx")
    assert s.dma_request(4) is None                  # some other peripheral's request
    assert s.dma_request(5) == ("spi1", "tx")


def test_peri_reset_returns_a_peripheral_to_reset_values(board):
    s = board.sysctl
    board.spi1.write(0x14, 4, 26, 0)                 # baudr
    old = board.spi1
    s.write(sc.PERI_RESET, 4, 1 << 7, US)            # SDK: peri_reset at 0x34, spi1 bit 7
    assert s.in_reset("spi1") and not s.in_reset("spi0")
    s.write(sc.PERI_RESET, 4, 0, 2 * US)
    assert not s.in_reset("spi1")
    assert board.spi1 is old                         # the same block, back at its reset values
    assert board.spi1.read(0x14, 4, 3 * US) == 0


# --- register table ----------------------------------------------------------------------

@pytest.mark.parametrize("offset", [0x70, 0x74, 0x100, 0xFFC])
def test_unknown_offset_is_unmodelled(board, offset):
    with pytest.raises(UnmodelledAccess, match=f"0x{offset:x}"):
        board.sysctl.read(offset, 4, 0)
    with pytest.raises(UnmodelledAccess):
        board.sysctl.write(offset, 4, 0, 0)


def test_read_only_and_wrong_width(board):
    with pytest.raises(UnmodelledAccess, match="read-only"):
        board.sysctl.write(0x00, 4, 1, 0)             # git_id
    with pytest.raises(UnmodelledAccess, match="32-bit register"):
        board.sysctl.read(sc.CLK_SEL0, 8, 0)


def test_soft_reset_asks_for_a_chip_reset(board):
    """soft_reset bit 0 resets the whole chip (tests/unit/devices/test_wdt.py runs programs through one)."""
    board.sysctl.write(sc.SOFT_RESET, 4, 1, MS)
    assert board.scheduler.reset_requested == ("soft", MS)


def test_unknown_sysctl_offset_through_a_program():
    board = make_board(program("""
        li      s0, 0x50440000
        lw      t0, 0x70(s0)
    """))
    with pytest.raises(UnmodelledAccess, match="no register at offset 0x70"):
        run_to_done(board)
