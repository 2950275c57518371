"""DMAC (DesignWare AXI DMAC, facts sheet section 8): 64-bit registers, chen write
enables, memory-to-memory copies, and SPI transfers through the dma_sel handshake."""
from __future__ import annotations

import numpy as np
import pytest

from emulator.cpu.caches import ROCKET_L1
from emulator.memory_map import K210_BLOCKS
from emulator.devices import dmac as d
from emulator.devices import spi as s
from emulator.errors import HardwareMisuse, UnmodelledAccess
from emulator.devices.plic import SOURCE_DMA0
from emulator.vtime import PS_PER_MS, PS_PER_NS, PS_PER_S, PS_PER_US, cycles_time
from dmac_channels import DST, SRC, ch, chcfg, ctl, memcpy_channel, r, run_devices, setup_channel, w
from k210_fixtures import RecordingDevice, board, idle_elf, make_board, program, reg, run_to_done  # noqa: F401

CPU_HZ = 26_000_000
SPI1_DR = 0x5300_0060
SPI_BIT = cycles_time(26, 13_000_000)            # baudr 26 from the 13 MHz SPI source: 2 us


# --- 64-bit registers through real programs -------------------------------------------------

DMAC_CLOCK_ON = """
    li      s0, 0x50440000
    lw      t0, 0x2c(s0)
    ori     t0, t0, 1 << 1               # DMA clock
    sw      t0, 0x2c(s0)
    li      s1, 0x50000000
"""


def test_ld_sd_on_64_bit_registers():
    board = make_board(program(DMAC_CLOCK_ON + """
        ld      s2, 0x00(s1)                 # id
        ld      s3, 0x08(s1)                 # compver
        li      t0, 3
        sd      t0, 0x10(s1)                 # cfg: enable, int_en
        ld      s4, 0x10(s1)
        li      t0, 0x123456789abcdef0
        sd      t0, 0x100(s1)                # ch0 sar: both halves matter
        ld      s5, 0x100(s1)
        li      t0, 0x0000004000000001
        sd      t0, 0x120(s1)                # ch0 cfg with a high-half field
        ld      s6, 0x120(s1)
    """))
    run_to_done(board)
    assert reg(board, "s3") == 0x3130_302A
    assert reg(board, "s4") == 3
    assert board.dmac.values[d.CFG] == 3
    assert reg(board, "s5") == 0x1234_5678_9ABC_DEF0
    assert board.dmac.values[ch(0, d.SAR)] == 0x1234_5678_9ABC_DEF0
    assert reg(board, "s6") == 0x0000_0040_0000_0001


@pytest.mark.parametrize("insn, direction", [("lw t0, 0x10(s1)", "load"), ("sw zero, 0x10(s1)", "store"),
                                             ("lwu t0, 0x08(s1)", "load"), ("lw t0, 0x104(s1)", "load")])
def test_32_bit_access_to_a_dmac_register_stops_a_strict_run(insn, direction):
    board = make_board(program(DMAC_CLOCK_ON + f"    {insn}\n"), strict=True)
    with pytest.raises(UnmodelledAccess) as info:
        run_to_done(board)
    text = str(info.value)
    assert f"{direction} of 4 bytes" in text
    assert "hart 0" in text and insn.split()[0] in text


def test_dmac_gated_clock_is_misuse():
    board = make_board(program("""
        li      s1, 0x50000000
        ld      t0, 0x08(s1)
    """))
    with pytest.raises(HardwareMisuse, match="DMAC accessed while its clock is gated"):
        run_to_done(board)


def test_register_table(board):
    with pytest.raises(UnmodelledAccess, match="read-only"):
        w(board, d.ID, 1, 0)
    with pytest.raises(UnmodelledAccess, match="read-only"):
        w(board, ch(0, d.CH_INTSTATUS), 1, 0)
    with pytest.raises(UnmodelledAccess, match="write-only"):
        r(board, ch(0, d.INTCLEAR), 0)
    with pytest.raises(UnmodelledAccess):
        r(board, ch(6, d.SAR), 0)                    # six channels only
    with pytest.raises(UnmodelledAccess, match="32-bit access"):
        board.dmac.read(d.CFG, 4, 0)


# --- chen ---------------------------------------------------------------------------------

def test_chen_write_enable_bits(board):
    w(board, d.CFG, d.CFG_ENABLE, 0)
    memcpy_channel(board, 0, 4096)
    memcpy_channel(board, 1, 4096, src=SRC + 0x4000, dst=DST + 0x4000)
    memcpy_channel(board, 2, 4096, src=SRC + 0x8000, dst=DST + 0x8000)
    w(board, d.CHEN, 0b111, PS_PER_US)                  # no write-enable bits: nothing happens
    assert r(board, d.CHEN, PS_PER_US) & 0x3F == 0
    assert board.dmac.channels[0].transfer is None
    w(board, d.CHEN, 0x0101, 2 * PS_PER_US)             # channel 0 only
    assert r(board, d.CHEN, 2 * PS_PER_US) & 0x3F == 0b001
    w(board, d.CHEN, 0x0404 | 0b011, 2 * PS_PER_US)     # channel 2; bits 0, 1 without their enables
    assert r(board, d.CHEN, 2 * PS_PER_US) & 0x3F == 0b101
    assert board.dmac.channels[1].transfer is None
    with pytest.raises(UnmodelledAccess, match="disabling channel 0"):
        w(board, d.CHEN, 0x0100, 3 * PS_PER_US)         # write-enabled 0 on a busy channel


def test_channel_enable_while_the_dmac_is_disabled_is_ignored(board):
    memcpy_channel(board, 0, 16)
    w(board, d.CHEN, 0x0101, 0)
    assert r(board, d.CHEN, 0) & 1 == 0
    assert any("DMAC is disabled" in text for text in board.warnings)


# --- memory to memory -----------------------------------------------------------------------

def test_memory_to_memory_copy_and_completion(board):
    data = np.arange(1000, 1000 + 256, dtype="<u4").tobytes()
    board.memory.load(SRC, data)
    w(board, d.CFG, d.CFG_ENABLE, 0)
    memcpy_channel(board, 3, 256, dst=DST - 0x4000_0000)   # destination through the uncached alias
    w(board, ch(3, d.INTSTATUS_EN), d.INT_DMA_TFR_DONE, 0)
    w(board, ch(3, d.INTSIGNAL_EN), d.INT_DMA_TFR_DONE, 0)
    t0 = 5 * PS_PER_US
    w(board, d.CHEN, 0x0808, t0)
    # 1 KiB at 8 bytes a cycle of 26 MHz: 128 cycles
    done = t0 + cycles_time(256 * 4, d.MEM2MEM_BYTES_PER_CYCLE * CPU_HZ)
    assert done == t0 + cycles_time(128, CPU_HZ)
    assert board.dmac.next_event_time(t0) == done
    assert r(board, d.CHEN, done - 1) & 0x08
    assert r(board, ch(3, d.CH_INTSTATUS), done - 1) == 0
    assert r(board, d.CHEN, done) & 0x08 == 0
    assert board.memory.read(DST, len(data)) == data
    assert r(board, ch(3, d.CH_INTSTATUS), done) == d.INT_DMA_TFR_DONE   # only what intstatus_en allows
    assert r(board, d.INTSTATUS, done) == 1 << 3
    # the interrupt line needs intsignal_en and cfg.int_en
    assert not board.dmac.irq_line(3)
    w(board, d.CFG, d.CFG_ENABLE | d.CFG_INT_EN, done)
    assert board.dmac.irq_line(3) and not board.dmac.irq_line(2)
    assert SOURCE_DMA0 + 3 in board._high_sources()
    w(board, ch(3, d.INTSIGNAL_EN), 0, done)
    assert not board.dmac.irq_line(3)
    w(board, ch(3, d.INTSIGNAL_EN), d.INT_DMA_TFR_DONE, done)
    w(board, ch(3, d.INTCLEAR), d.INT_DMA_TFR_DONE, done + 1)
    assert r(board, ch(3, d.CH_INTSTATUS), done + 1) == 0
    assert not board.dmac.irq_line(3)
    assert r(board, d.INTSTATUS, done + 1) == 0


def test_both_done_bits_when_enabled(board):
    w(board, d.CFG, d.CFG_ENABLE, 0)
    memcpy_channel(board, 0, 8)
    w(board, ch(0, d.INTSTATUS_EN), 0xFFFF_FFFF, 0)
    w(board, d.CHEN, 0x0101, 0)
    assert r(board, ch(0, d.CH_INTSTATUS), PS_PER_MS) == d.INT_BLOCK_TFR_DONE | d.INT_DMA_TFR_DONE


def test_fixed_addresses_and_byte_items(board):
    board.memory.load(SRC, bytes([0xAB, 0xCD]))
    w(board, d.CFG, d.CFG_ENABLE, 0)
    setup_channel(board, 0, sar=SRC, dar=DST, items=16, ctl_value=ctl(0, 0, sinc_fixed=True),
                  cfg_value=chcfg())
    w(board, d.CHEN, 0x0101, 0)
    r(board, d.CHEN, PS_PER_MS)
    assert board.memory.read(DST, 16) == b"\xAB" * 16


def test_unmodelled_transfers(board):
    w(board, d.CFG, d.CFG_ENABLE, 0)
    memcpy_channel(board, 0, 8)
    w(board, ch(0, d.LLP), 0x8030_0000, 0)
    with pytest.raises(UnmodelledAccess, match="linked-list"):
        w(board, d.CHEN, 0x0101, 0)
    setup_channel(board, 1, sar=SRC, dar=DST, items=8, ctl_value=ctl(), cfg_value=chcfg() | 0b0101)
    with pytest.raises(UnmodelledAccess, match="multi-block"):
        w(board, d.CHEN, 0x0202, 0)


def test_dma_outside_sram_is_misuse(board):
    w(board, d.CFG, d.CFG_ENABLE, 0)
    memcpy_channel(board, 0, 8, src=0x9000_0000)
    with pytest.raises(HardwareMisuse, match="not SRAM"):
        w(board, d.CHEN, 0x0101, 0)


# --- memory to SPI and SPI to memory --------------------------------------------------------------

@pytest.fixture
def spi_bus(board):
    dev = RecordingDevice()
    board.spi1.device_for_ss = lambda ss: dev if ss == 0 else None
    return board, board.spi1, dev


def spi_setup(spi, dfs, tmod, now=0, ctrlr1=0, dmacr=0):
    spi.write(s.CTRLR0, 4, (dfs - 1) << 16 | tmod << 8, now)
    spi.write(s.BAUDR, 4, 26, now)
    spi.write(s.CTRLR1, 4, ctrlr1, now)
    spi.write(s.DMACR, 4, dmacr, now)
    spi.write(s.SSIENR, 4, 1, now)


def test_memory_to_spi_in_order_and_on_time(spi_bus):
    board, spi, dev = spi_bus
    n = 100
    words = np.array([0x1000_0000 * (i % 16) + i for i in range(n)], dtype="<u4")
    board.memory.load(SRC, words.tobytes())
    board.sysctl.write(0x64, 4, 3 << 12, 0)          # dma_sel: channel 2 <- SSI1_TX
    w(board, d.CFG, d.CFG_ENABLE | d.CFG_INT_EN, 0)
    setup_channel(board, 2, sar=SRC, dar=SPI1_DR, items=n, ctl_value=ctl(dinc_fixed=True),
                  cfg_value=chcfg(d.TT_MEM2PER, hs_dst_sw=False, dst_per=2))
    w(board, ch(2, d.INTSTATUS_EN), d.INT_DMA_TFR_DONE, 0)
    w(board, ch(2, d.INTSIGNAL_EN), d.INT_DMA_TFR_DONE, 0)
    spi_setup(spi, 32, s.TMOD_TX, dmacr=s.DMACR_TDMAE)
    spi.write(s.SER, 4, 1, 0)
    t0 = PS_PER_US
    w(board, d.CHEN, 0x0404, t0)
    period = 32 * SPI_BIT
    t_done = run_devices(board, t0, lambda t: not board.dmac.values[d.CHEN] & 0x04)
    assert abs(t_done - (t0 + n * period)) <= (s.FIFO_DEPTH + 1) * period
    assert board.dmac.irq_line(2)
    # the wire keeps going until the last frame is out
    t_end = run_devices(board, t_done, lambda t: not spi.busy(t) and len(dev.received) == 4 * n)
    assert t_end == t0 + n * period
    assert bytes(dev.received) == words.astype(">u4").tobytes()
    assert spi.read(s.SR, 4, t_end) == s.SR_TFNF | s.SR_TFE


def test_memory_to_spi_with_8_bit_frames_keeps_the_fifo_full(spi_bus):
    board, spi, dev = spi_bus
    n = 80
    board.memory.load(SRC, np.arange(n, dtype="<u4").tobytes())
    board.sysctl.write(0x64, 4, 3, 0)                # channel 0 <- SSI1_TX
    w(board, d.CFG, d.CFG_ENABLE, 0)
    setup_channel(board, 0, sar=SRC, dar=SPI1_DR, items=n, ctl_value=ctl(dinc_fixed=True),
                  cfg_value=chcfg(d.TT_MEM2PER, hs_dst_sw=False, dst_per=0))
    spi_setup(spi, 8, s.TMOD_TX, dmacr=s.DMACR_TDMAE)
    spi.write(s.SER, 4, 1, 0)
    w(board, d.CHEN, 0x0101, 0)
    period = 8 * SPI_BIT
    assert spi.read(s.TXFLR, 4, 10 * period) == s.FIFO_DEPTH         # refilled as slots free
    t_end = run_devices(board, 0, lambda t: len(dev.received) == n and not spi.busy(t))
    assert t_end == n * period                                      # one unbroken train
    assert bytes(dev.received) == bytes(range(n))


def test_memory_to_spi_waits_for_the_handshake(spi_bus):
    board, spi, dev = spi_bus
    board.memory.load(SRC, np.arange(8, dtype="<u4").tobytes())
    board.sysctl.write(0x64, 4, 3, 0)
    w(board, d.CFG, d.CFG_ENABLE, 0)
    setup_channel(board, 0, sar=SRC, dar=SPI1_DR, items=8, ctl_value=ctl(dinc_fixed=True),
                  cfg_value=chcfg(d.TT_MEM2PER, hs_dst_sw=False, dst_per=0))
    spi_setup(spi, 8, s.TMOD_TX, dmacr=0)               # tdmae off: no requests
    spi.write(s.SER, 4, 1, 0)
    w(board, d.CHEN, 0x0101, 0)
    assert r(board, d.CHEN, PS_PER_S) & 1
    assert dev.received == b""
    assert "waits for SPI1" in board.dmac.describe_wait()


def test_memory_to_spi_handshake_misuse(spi_bus):
    board, spi, dev = spi_bus
    w(board, d.CFG, d.CFG_ENABLE, 0)
    board.sysctl.write(0x64, 4, 2, 0)                 # channel 0 <- SSI1_RX: wrong direction
    setup_channel(board, 0, sar=SRC, dar=SPI1_DR, items=8, ctl_value=ctl(dinc_fixed=True),
                  cfg_value=chcfg(d.TT_MEM2PER, hs_dst_sw=False, dst_per=0))
    with pytest.raises(HardwareMisuse, match="SPI1 RX"):
        w(board, d.CHEN, 0x0101, 0)
    board.sysctl.write(0x64, 4, 3, 0)
    setup_channel(board, 1, sar=SRC, dar=0x5200_0060, items=8, ctl_value=ctl(dinc_fixed=True),
                  cfg_value=chcfg(d.TT_MEM2PER, hs_dst_sw=False, dst_per=0))
    with pytest.raises(HardwareMisuse, match="not SPI1's data register"):
        w(board, d.CHEN, 0x0202, 0)


def test_spi_receive_to_memory(spi_bus):
    board, spi, dev = spi_bus
    n = 40                                              # more than one FIFO's worth
    reply = bytes((7 * i + 3) & 0xFF for i in range(n))
    dev.replies = bytearray(reply)
    board.memory.load(DST, b"\x55" * (4 * n + 8))
    board.sysctl.write(0x64, 4, 2 << 6, 0)            # channel 1 <- SSI1_RX
    w(board, d.CFG, d.CFG_ENABLE, 0)
    setup_channel(board, 1, sar=SPI1_DR, dar=DST, items=n, ctl_value=ctl(sinc_fixed=True),
                  cfg_value=chcfg(d.TT_PER2MEM, hs_src_sw=False, src_per=1))
    w(board, ch(1, d.INTSTATUS_EN), d.INT_DMA_TFR_DONE, 0)
    spi_setup(spi, 8, s.TMOD_RX, ctrlr1=n - 1, dmacr=s.DMACR_RDMAE)
    w(board, d.CHEN, 0x0202, 0)
    t0 = 2 * PS_PER_US
    spi.write(s.DR_FIRST, 4, 0xFFFF_FFFF, t0)           # dummy word
    spi.write(s.SER, 4, 1, t0)
    period = 8 * SPI_BIT
    assert r(board, d.CHEN, t0 + n * period - 1) & 0x02
    t_done = run_devices(board, t0, lambda t: not board.dmac.values[d.CHEN] & 0x02)
    assert t_done == t0 + n * period
    got = np.frombuffer(board.memory.read(DST, 4 * n), dtype="<u4")
    assert bytes(got.astype(np.uint8)) == reply
    assert got.max() < 256
    assert board.memory.read(DST + 4 * n, 4) == b"\x55" * 4          # nothing past the block
    assert spi.read(s.RXFLR, 4, t_done) == 0                          # all went to memory
    assert r(board, ch(1, d.CH_INTSTATUS), t_done) == d.INT_DMA_TFR_DONE


def test_sdk_order_channel_enabled_before_the_slave_select(spi_bus):
    """The SDK enables the DMA channel, then writes ser: the wire starts at the ser write
    and the frames still leave in order, back to back."""
    board, spi, dev = spi_bus
    n = 50
    board.memory.load(SRC, np.arange(100, 100 + n, dtype="<u4").tobytes())
    board.sysctl.write(0x64, 4, 3, 0)
    w(board, d.CFG, d.CFG_ENABLE, 0)
    setup_channel(board, 0, sar=SRC, dar=SPI1_DR, items=n, ctl_value=ctl(dinc_fixed=True),
                  cfg_value=chcfg(d.TT_MEM2PER, hs_dst_sw=False, dst_per=0))
    spi_setup(spi, 8, s.TMOD_TX, dmacr=s.DMACR_TDMAE)
    w(board, d.CHEN, 0x0101, 0)
    t1 = PS_PER_MS
    assert spi.read(s.TXFLR, 4, t1) == s.FIFO_DEPTH        # the DMA filled the FIFO, nothing sent
    assert dev.received == b""
    spi.write(s.SER, 4, 1, t1)
    period = 8 * SPI_BIT
    t_end = run_devices(board, t1, lambda t: len(dev.received) == n and not spi.busy(t))
    assert t_end == t1 + n * period
    assert bytes(dev.received) == bytes(range(100, 100 + n))
    assert not board.dmac.values[d.CHEN] & 1


def test_dmac_reset_register(board):
    w(board, d.CFG, d.CFG_ENABLE, 0)
    memcpy_channel(board, 0, 4096)
    w(board, d.CHEN, 0x0101, 0)
    w(board, d.RESET, 1, PS_PER_NS)
    assert r(board, d.RESET, PS_PER_NS) == 0               # reset completes at once
    assert r(board, d.CFG, PS_PER_NS) == 0
    assert r(board, d.CHEN, PS_PER_NS) == 0
    assert r(board, ch(0, d.SAR), PS_PER_NS) == 0
    assert r(board, d.COMPVER, PS_PER_NS) == 0x3130_302A
    assert board.dmac.channels[0].transfer is None


def test_dma_to_spi_through_a_program():
    """Firmware: DMA 100 words to SPI1 (8-bit frames), wait for chen to drop, then for the
    wire to go idle. The whole wait is the wire time of 100 frames."""
    board = make_board(program(DMAC_CLOCK_ON + """
        lw      t0, 0x28(s0)
        ori     t0, t0, 1 << 5              # APB2
        sw      t0, 0x28(s0)
        lw      t0, 0x2c(s0)
        ori     t0, t0, 1 << 7              # SPI1 clock
        sw      t0, 0x2c(s0)
        li      t0, 3
        sw      t0, 0x64(s0)                # dma_sel0: channel 0 <- SSI1_TX
        li      s2, 0x53000000
        li      t0, (7 << 16) | (1 << 8)
        sw      t0, 0x00(s2)
        li      t0, 26
        sw      t0, 0x14(s2)
        li      t0, 2
        sw      t0, 0x4c(s2)                # dmacr: TX DMA
        li      t0, 1
        sw      t0, 0x08(s2)                # ssienr
        li      t0, 1
        sd      t0, 0x10(s1)                # DMAC cfg enable
        la      t0, words
        sd      t0, 0x100(s1)               # sar
        addi    t0, s2, 0x60
        sd      t0, 0x108(s1)               # dar
        li      t0, 99
        sd      t0, 0x110(s1)               # block_ts
        li      t0, (2 << 8) | (2 << 11) | (1 << 6)
        sd      t0, 0x118(s1)               # ctl: 32-bit, dst fixed
        li      t0, (1 << 32) | (1 << 35)   # mem-to-periph, src software handshake, dst_per 0
        sd      t0, 0x120(s1)
        li      t0, 0x0101
        csrr    s10, mcycle
        sd      t0, 0x18(s1)                # chen
        li      t0, 1
        sw      t0, 0x10(s2)                # ser: go
    1:  ld      t1, 0x18(s1)
        andi    t1, t1, 1
        bnez    t1, 1b
        csrr    s9, mcycle
    2:  lw      t1, 0x28(s2)
        andi    t1, t1, 5
        li      t2, 4
        bne     t1, t2, 2b
        csrr    s11, mcycle
    """, data="words:\n" + "".join(f"    .word {i}\n" for i in range(100))), quantum=2000)
    dev = RecordingDevice()
    board.spi1.device_for_ss = lambda ss: dev if ss == 0 else None
    run_to_done(board, max_time_s=0.01)
    assert bytes(dev.received) == bytes(range(100))
    period_cycles = 8 * 26 * 2                              # 8 bits * 2 us at 26 MHz
    dma_wait = reg(board, "s9") - reg(board, "s10")
    assert abs(dma_wait - 100 * period_cycles) <= (s.FIFO_DEPTH + 1) * period_cycles
    total = reg(board, "s11") - reg(board, "s10")
    # and the last polls' round trips to the DMAC and SPI1 (caches.py)
    last_polls = ROCKET_L1.device(K210_BLOCKS["DMAC"].bus, (1, 1, 1)) + ROCKET_L1.device(K210_BLOCKS["SPI1"].bus, (1, 1, 1))
    assert 100 * period_cycles <= total <= 100 * period_cycles + 60 + last_polls


@pytest.mark.parametrize("n", [1, 32])
def test_a_block_that_fits_in_the_fifo_is_done_before_the_slave_select(spi_bus, n):
    """The SDK's LCD command: one item by DMA, channel enabled before ser. The DMA's part is
    over once the item is in the FIFO, so chen drops at once (it never did: the SDK's
    dmac_wait_done, which comes before anything else, spun for ever); the frames go out
    when ser selects the device."""
    board, spi, dev = spi_bus
    board.memory.load(SRC, np.arange(0xA0, 0xA0 + n, dtype="<u4").tobytes())
    board.sysctl.write(0x64, 4, 3, 0)                # channel 0 <- SSI1_TX
    w(board, d.CFG, d.CFG_ENABLE | d.CFG_INT_EN, 0)
    setup_channel(board, 0, sar=SRC, dar=SPI1_DR, items=n, ctl_value=ctl(dinc_fixed=True),
                  cfg_value=chcfg(d.TT_MEM2PER, hs_dst_sw=False, dst_per=0))
    w(board, ch(0, d.INTSTATUS_EN), d.INT_DMA_TFR_DONE, 0)
    spi_setup(spi, 8, s.TMOD_TX, dmacr=s.DMACR_TDMAE)
    w(board, d.CHEN, 0x0101, PS_PER_US)
    t1 = 2 * PS_PER_US
    assert not r(board, d.CHEN, t1) & 1
    assert r(board, ch(0, d.CH_INTSTATUS), t1) == d.INT_DMA_TFR_DONE
    assert spi.read(s.TXFLR, 4, t1) == n and dev.received == b""
    spi.write(s.SER, 4, 1, t1)
    t_end = run_devices(board, t1, lambda t: len(dev.received) == n and not spi.busy(t))
    assert t_end == t1 + n * 8 * SPI_BIT
    assert bytes(dev.received) == bytes(range(0xA0, 0xA0 + n))


@pytest.mark.parametrize("width", [1, 2, 4])
def test_dma_items_of_each_width_are_fifo_entries(spi_bus, width):
    """8-, 16- and 32-bit DMA items into frames of the same size: each item one frame,
    sent most significant bit first."""
    board, spi, dev = spi_bus
    n = 40
    values = [(0x1357_9BDF * (i + 1)) & ((1 << (8 * width)) - 1) for i in range(n)]
    dtype = {1: np.uint8, 2: "<u2", 4: "<u4"}[width]
    board.memory.load(SRC, np.array(values, dtype=dtype).tobytes())
    board.sysctl.write(0x64, 4, 3, 0)
    w(board, d.CFG, d.CFG_ENABLE, 0)
    code = {1: 0, 2: 1, 4: 2}[width]
    setup_channel(board, 0, sar=SRC, dar=SPI1_DR, items=n, ctl_value=ctl(code, code, dinc_fixed=True),
                  cfg_value=chcfg(d.TT_MEM2PER, hs_dst_sw=False, dst_per=0))
    spi_setup(spi, 8 * width, s.TMOD_TX, dmacr=s.DMACR_TDMAE)
    w(board, d.CHEN, 0x0101, 0)
    spi.write(s.SER, 4, 1, PS_PER_US)
    run_devices(board, PS_PER_US, lambda t: len(dev.received) == n * width and not spi.busy(t))
    assert bytes(dev.received) == b"".join(v.to_bytes(width, "big") for v in values)
    assert not board.dmac.values[d.CHEN] & 1
    assert not any("items into" in text for text in board.warnings)


def test_dma_items_narrower_than_the_frames_warn(spi_bus):
    """8-bit items into 16-bit frames: the frame's upper byte is what AXI leaves undefined;
    the model sends 0 and says so."""
    board, spi, dev = spi_bus
    board.memory.load(SRC, bytes([0x12, 0x34]))
    board.sysctl.write(0x64, 4, 3, 0)
    w(board, d.CFG, d.CFG_ENABLE, 0)
    setup_channel(board, 0, sar=SRC, dar=SPI1_DR, items=2, ctl_value=ctl(0, 0, dinc_fixed=True),
                  cfg_value=chcfg(d.TT_MEM2PER, hs_dst_sw=False, dst_per=0))
    spi_setup(spi, 16, s.TMOD_TX, dmacr=s.DMACR_TDMAE)
    spi.write(s.SER, 4, 1, 0)
    w(board, d.CHEN, 0x0101, 0)
    run_devices(board, 0, lambda t: len(dev.received) == 4 and not spi.busy(t))
    assert bytes(dev.received) == b"\x00\x12\x00\x34"
    assert any("DMAC channel 0 writes 8-bit items into SPI1's 16-bit frames" in text for text in board.warnings)


def test_dma_items_of_different_widths_to_a_peripheral_are_unmodelled(spi_bus):
    board, spi, dev = spi_bus
    board.sysctl.write(0x64, 4, 3, 0)
    w(board, d.CFG, d.CFG_ENABLE, 0)
    setup_channel(board, 0, sar=SRC, dar=SPI1_DR, items=4, ctl_value=ctl(2, 0, dinc_fixed=True),
                  cfg_value=chcfg(d.TT_MEM2PER, hs_dst_sw=False, dst_per=0))
    spi_setup(spi, 8, s.TMOD_TX, dmacr=s.DMACR_TDMAE)
    with pytest.raises(UnmodelledAccess, match="32-bit source items into 8-bit destination items"):
        w(board, d.CHEN, 0x0101, 0)


def test_a_channels_interrupt_signal_is_enabled_at_reset(board):
    """The SDK's dmac.c enables intstatus_en only and relies on the channel's interrupt: intsignal_en
    lets every interrupt through from reset (issue 36: a model with it at 0 lost those interrupts)."""
    assert r(board, ch(0, d.INTSIGNAL_EN), 0) == d.INTSIGNAL_RESET
    board.memory.load(SRC, bytes(range(16)))
    w(board, d.CFG, d.CFG_ENABLE | d.CFG_INT_EN, 0)
    memcpy_channel(board, 0, 4)
    w(board, ch(0, d.INTSTATUS_EN), d.INT_DMA_TFR_DONE, 0)
    w(board, d.CHEN, 0x0101, 0)
    run_devices(board, 0, lambda t: not board.dmac.values[d.CHEN] & 1)
    assert board.dmac.irq_line(0)
