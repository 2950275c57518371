# clocks.S: PLL0 and the SYSCTL clock tree.
#
# PLL0 is reprogrammed the way the Kendryte SDK's sysctl_pll_set_freq does it
# (CPU parked on the oscillator while the PLL is down, power/reset sequence,
# wait for lock clearing the slip flag), asked for what the SDK asks for
# "800 MHz": clkr 0, clkf 30, clkod 0 -> 26 MHz * 31 = 806 MHz, CPU = 403 MHz.
# Every SYSCTL write is a read-modify-write of the fields named, because the
# same registers hold settings of blocks this firmware does not own.

    .option norelax
    .include "k210.inc"
    .include "frame.inc"

    .text
    .globl clocks_init
# clocks_init
#   What: PLL0 to 806 MHz, ACLK (CPU) = PLL0 / 2 = 403 MHz; clocks of the CPU,
#         SRAM banks, APB buses, DMA, GPIO, SPI0, SPI1 and FPIOA on; SPI0 and
#         SPI1 sources = PLL0 / 2; SPI0 drives the LCD data lines
#         (misc.spi0_dvp_data_en).
#         Records the CPU clock in cpu_hz for code that needs it later.
#   Arguments: none.
#   Results: a0 = CPU clock in Hz, a1 = PLL0 output in Hz (both computed back
#         from what the registers hold, not from the constants).
#   Clobbers: only ABI temporaries.
clocks_init:
    FRAME_SAVE 16, ra, s0
    li      s0, SYSCTL_BASE

    # 1. CPU onto the 26 MHz oscillator while PLL0 is down.
    lw      t0, SYSCTL_CLK_SEL0(s0)
    andi    t0, t0, ~CLK_SEL0_ACLK_SEL
    sw      t0, SYSCTL_CLK_SEL0(s0)
    la      t1, cpu_hz
    li      t2, OSC_HZ
    sw      t2, 0(t1)                   # the trap handler's baud rate follows

    # 2. PLL0 output off, 3. PLL0 powered down.
    lw      t0, SYSCTL_PLL0(s0)
    li      t1, ~PLL_OUT_EN
    and     t0, t0, t1
    sw      t0, SYSCTL_PLL0(s0)
    li      t1, ~PLL_PWRD
    and     t0, t0, t1
    sw      t0, SYSCTL_PLL0(s0)

    # 4. New divider/multiplier fields.
    li      t1, ~(PLL_CLKR_MASK | PLL_CLKF_MASK | PLL_CLKOD_MASK | PLL_BWADJ_MASK)
    and     t0, t0, t1
    li      t1, (PLL0_CLKR << PLL_CLKR_SHIFT) | (PLL0_CLKF << PLL_CLKF_SHIFT) | (PLL0_CLKOD << PLL_CLKOD_SHIFT) | (PLL0_BWADJ << PLL_BWADJ_SHIFT)
    or      t0, t0, t1
    sw      t0, SYSCTL_PLL0(s0)

    # 5. Power on, > 100 ns before the reset pulse.
    li      t1, PLL_PWRD
    or      t0, t0, t1
    sw      t0, SYSCTL_PLL0(s0)
    li      a0, 1
    li      a1, OSC_HZ
    call    delay_us

    # 6. Reset pulse (set, > 100 ns, clear).
    lw      t0, SYSCTL_PLL0(s0)
    li      t1, PLL_RESET
    or      t0, t0, t1
    sw      t0, SYSCTL_PLL0(s0)
    li      a0, 1
    li      a1, OSC_HZ
    call    delay_us
    lw      t0, SYSCTL_PLL0(s0)
    li      t1, ~PLL_RESET
    and     t0, t0, t1
    sw      t0, SYSCTL_PLL0(s0)

    # 7. Wait for lock; a slip while locking latches, so clear it each round.
    # Lock takes microseconds: polling the status register is the SDK's way.
1:  lw      t0, SYSCTL_PLL_LOCK(s0)
    andi    t1, t0, PLL_LOCK_PLL0_MASK
    li      t2, PLL_LOCK_PLL0_MASK
    beq     t1, t2, 2f
    ori     t0, t0, PLL_LOCK_PLL0_SLIP_CLR
    sw      t0, SYSCTL_PLL_LOCK(s0)
    j       1b
2:
    # 8. PLL0 output on.
    lw      t0, SYSCTL_PLL0(s0)
    li      t1, PLL_OUT_EN
    or      t0, t0, t1
    sw      t0, SYSCTL_PLL0(s0)

    # 9. ACLK = PLL0 / 2 (divider select 0), then switch the CPU over.
    lw      t0, SYSCTL_CLK_SEL0(s0)
    andi    t0, t0, ~CLK_SEL0_ACLK_DIV_MASK
    sw      t0, SYSCTL_CLK_SEL0(s0)
    ori     t0, t0, CLK_SEL0_ACLK_SEL
    sw      t0, SYSCTL_CLK_SEL0(s0)

    # Clock gates of everything the firmware touches.
    lw      t0, SYSCTL_CLK_EN_CENT(s0)
    ori     t0, t0, CLK_EN_CENT_CPU | CLK_EN_CENT_SRAM0 | CLK_EN_CENT_SRAM1 | CLK_EN_CENT_APB0 | CLK_EN_CENT_APB1 | CLK_EN_CENT_APB2
    sw      t0, SYSCTL_CLK_EN_CENT(s0)
    lw      t0, SYSCTL_CLK_EN_PERI(s0)
    li      t1, CLK_EN_PERI_DMA | CLK_EN_PERI_GPIO | CLK_EN_PERI_SPI0 | CLK_EN_PERI_SPI1 | CLK_EN_PERI_FPIOA
    or      t0, t0, t1
    sw      t0, SYSCTL_CLK_EN_PERI(s0)

    # SPI0 and SPI1 sources = PLL0 / ((0 + 1) * 2); the LCD's and the SD
    # card's serial clocks are divided from these by baudr (spi_dma.S, sd_spi.S).
    lw      t0, SYSCTL_CLK_TH1(s0)
    li      t1, ~(CLK_TH1_SPI0_MASK | CLK_TH1_SPI1_MASK)
    and     t0, t0, t1
    li      t1, (CLK_TH1_SPI0_VALUE << CLK_TH1_SPI0_SHIFT) | (CLK_TH1_SPI1_VALUE << CLK_TH1_SPI1_SHIFT)
    or      t0, t0, t1
    sw      t0, SYSCTL_CLK_TH1(s0)

    # The LCD's 8 data lines hang off SPI0's DVP data path.
    lw      t0, SYSCTL_MISC(s0)
    li      t1, MISC_SPI0_DVP_DATA_EN
    or      t0, t0, t1
    sw      t0, SYSCTL_MISC(s0)

    # Report what the hardware now holds:
    # PLL0 = 26 MHz * (clkf + 1) / ((clkr + 1) * (clkod + 1)),
    # CPU = PLL0 / (2 << aclk_divider_sel).
    lw      t0, SYSCTL_PLL0(s0)
    srli    t1, t0, PLL_CLKF_SHIFT
    andi    t1, t1, PLL_CLKF_BITS
    addi    t1, t1, 1
    li      a1, OSC_HZ
    mul     a1, a1, t1
    srli    t1, t0, PLL_CLKR_SHIFT
    andi    t1, t1, PLL_CLKR_BITS
    addi    t1, t1, 1
    srli    t2, t0, PLL_CLKOD_SHIFT
    andi    t2, t2, PLL_CLKOD_BITS
    addi    t2, t2, 1
    mul     t1, t1, t2
    divu    a1, a1, t1                  # a1 = PLL0 Hz
    lw      t0, SYSCTL_CLK_SEL0(s0)
    srli    t0, t0, CLK_SEL0_ACLK_DIV_SHIFT
    andi    t0, t0, CLK_SEL0_ACLK_DIV_BITS
    li      t1, 2
    sll     t1, t1, t0
    divu    a0, a1, t1                  # a0 = CPU Hz
    la      t1, cpu_hz
    sw      a0, 0(t1)

    FRAME_RESTORE 16, ra, s0
    ret

# ---------------------------------------------------------------------------
    .data
    .balign 4
    .globl cpu_hz
# cpu_hz: the CPU clock in force, for code that cannot be handed it (the trap
# handler). The oscillator frequency until clocks_init has run.
cpu_hz:
    .word   OSC_HZ
