"""Programs that drive SPI1 as firmware does, through its registers from a hart: for SPI's own tests
(unit/devices/test_spi.py) and for the fast engine's, which runs them on both engines
(unit/cpu/test_fast_engine.py)."""
from __future__ import annotations

# SPI1's clock gates open (APB2, SPI1); s1 = SPI1's base
SPI1_CLOCKS_ON = """
    li      s0, 0x50440000
    lw      t0, 0x28(s0)
    ori     t0, t0, 1 << 5             # APB2
    sw      t0, 0x28(s0)
    lw      t0, 0x2c(s0)
    ori     t0, t0, 1 << 7             # SPI1
    sw      t0, 0x2c(s0)
    li      s1, 0x53000000
"""

SEND_AND_WAIT = SPI1_CLOCKS_ON + """
    li      t0, (7 << 16) | (1 << 8)   # 8-bit frames, transmit only
    sw      t0, 0x00(s1)
    li      t0, 26
    sw      t0, 0x14(s1)               # baudr
    li      t0, 1
    sw      t0, 0x08(s1)               # ssienr
    sw      t0, 0x10(s1)               # ser
    csrr    s10, mcycle
    li      t0, 0xC1
    sw      t0, 0x60(s1)
    li      t0, 0xC2
    sw      t0, 0x60(s1)
    li      t0, 0xC3
    sw      t0, 0x60(s1)
    li      t0, 0xC4
    sw      t0, 0x60(s1)
1:  lw      t1, 0x28(s1)
    andi    t1, t1, 5
    li      t2, 4
    bne     t1, t2, 1b
    csrr    s11, mcycle
"""

RECEIVE_100 = SPI1_CLOCKS_ON + """
    li      t0, (7 << 16) | (2 << 8)   # 8-bit frames, receive only
    sw      t0, 0x00(s1)
    li      t0, 99
    sw      t0, 0x04(s1)               # ctrlr1: 100 frames
    li      t0, 26
    sw      t0, 0x14(s1)
    li      t0, 1
    sw      t0, 0x08(s1)
    sw      t0, 0x10(s1)
    li      t0, -1
    sw      t0, 0x60(s1)               # dummy word starts the clocks
    la      s2, buffer
    li      s3, 100
1:  lw      t1, 0x24(s1)               # rxflr
    beqz    t1, 1b
    lw      t2, 0x60(s1)
    sb      t2, 0(s2)
    addi    s2, s2, 1
    addi    s3, s3, -1
    bnez    s3, 1b
"""
