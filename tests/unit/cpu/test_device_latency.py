"""Device register accesses on small firmware: what a run of loads from one block's registers costs in
mcycle, as the firmware reads it, against what caches.py says an access on that block's bus costs (the
round trip of the uncached view, the bridges, the APB's two clocks at SYSCTL's divider). The bus of
each block is memory_map.py's, from the SDK's platform.h. Compared with --timing rocket-nocache, which
charges devices nothing (the pipeline sees the same instructions either way)."""
from __future__ import annotations

import pytest

from emulator.cpu.caches import APB_TRANSFER, ROCKET_L1
from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE
from emulator.cpu.timing import TIMING_ROCKET, TIMING_ROCKET_NOCACHE
from emulator.devices.sysctl import CLK_EN_PERI, PERI_BITS
from emulator.memory_map import AHB, APB0, APB1, APB2, AXI, K210_BLOCKS, TILELINK
from k210_fixtures import make_board, program, reg, run_to_done

# loads(a0 = first register, a1 = how many, a2 = stride): one lw each, from one pc (different
# addresses: not a poll), between two mcycle reads; the code sits in one line, fetched before.
LOADS = """
    j       start
    .balign 64
loads:
1:  lw      t0, 0(a0)
    add     a0, a0, a2
    addi    a1, a1, -1
    bnez    a1, 1b
    ret
start:
{before}
    li      a0, {first}
    li      a1, {count}
    li      a2, {stride}
    la      t1, loads
    lw      t1, 0(t1)               # the data cache holds the code's line: no miss below but the devices'
    .balign 64
    csrr    s2, mcycle
    call    loads
    csrr    s3, mcycle
"""
SYSCTL_CLK_SEL0 = K210_BLOCKS["SYSCTL"].base + 0x20
APB0_DIVIDE_BY_4 = """
    li      t0, {clk_sel0}
    lw      t1, 0(t0)
    andi    t1, t1, -57             # apb0_clk_sel [5:3] = 3: APB0 at ACLK / 4
    ori     t1, t1, 3 << 3
    sw      t1, 0(t0)
""".format(clk_sel0=SYSCTL_CLK_SEL0)


def cycles(first: int, count: int, stride: int, timing: str, engine: str = ENGINE_FAST, before: str = "") -> int:
    board = make_board(program(LOADS.format(first=first, count=count, stride=stride, before=before)),
                       timing=timing, engine=engine, cold=False)
    run_to_done(board)
    return reg(board, "s3") - reg(board, "s2")


def device_cycles(first: int, count: int, stride: int, engine: str = ENGINE_FAST, before: str = "") -> int:
    return (cycles(first, count, stride, TIMING_ROCKET, engine, before)
            - cycles(first, count, stride, TIMING_ROCKET_NOCACHE, engine, before))


FFT_CLOCK_ON = """
    li      t0, {clk_en_peri}
    lw      t1, 0(t0)
    ori     t1, t1, 1 << {fft_bit}
    sw      t1, 0(t0)
""".format(clk_en_peri=K210_BLOCKS["SYSCTL"].base + CLK_EN_PERI, fft_bit=PERI_BITS["fft"])

# (block, first register offset, loads, stride): registers every block has at those offsets
RUNS = {TILELINK: ("PLIC", 0x4, 16, 4), AHB: ("DMAC", 0x0, 2, 8), APB0: ("FPIOA", 0x0, 16, 4),
        APB1: ("SYSCTL", 0x0, 8, 4), APB2: ("SPI1", 0x0, 6, 4), AXI: ("FFT", 0x0, 4, 8)}


@pytest.mark.parametrize("bus", list(RUNS))
def test_each_bus_costs_its_round_trip_per_access(bus):
    name, offset, count, stride = RUNS[bus]
    assert K210_BLOCKS[name].bus == bus
    per_access = ROCKET_L1.device(bus, (1, 1, 1))
    before = FFT_CLOCK_ON if name == "FFT" else ""
    assert device_cycles(K210_BLOCKS[name].base + offset, count, stride, before=before) == count * per_access


def test_the_figures_come_from_the_path_to_each_bus():
    """The uncached view's round trip (caches.py: 6 + 1 + 4), less the TileLink-to-AXI crossing for
    Rocket's own devices, plus a bridge for the AHB and the APBs, plus the APB's setup and access
    clocks."""
    assert ROCKET_L1.device(AXI, (1, 1, 1)) == ROCKET_L1.uncached == 11
    assert ROCKET_L1.device(TILELINK, (1, 1, 1)) == 9
    assert ROCKET_L1.device(AHB, (1, 1, 1)) == 13
    assert [ROCKET_L1.device(bus, (1, 2, 8)) for bus in (APB0, APB1, APB2)] == [15, 17, 29]


def test_a_slower_apb_clock_makes_its_registers_slower():
    """SYSCTL's apb0_clk_sel divides APB0's clock: each FPIOA access takes two more APB clocks' worth."""
    fpioa = K210_BLOCKS["FPIOA"].base
    divided = device_cycles(fpioa, 16, 4, before=APB0_DIVIDE_BY_4)
    assert divided == 16 * ROCKET_L1.device(APB0, (4, 1, 1)) == 16 * (ROCKET_L1.device(APB0, (1, 1, 1)) + 3 * APB_TRANSFER)


def test_both_engines_charge_device_accesses_alike():
    plic = K210_BLOCKS["PLIC"].base + 4
    fpioa = K210_BLOCKS["FPIOA"].base
    for first in (plic, fpioa):
        assert cycles(first, 16, 4, TIMING_ROCKET, ENGINE_PRECISE) == cycles(first, 16, 4, TIMING_ROCKET, ENGINE_FAST)
