# spi_dma.S: SPI0 in octal transmit-only mode (the LCD bus), DMAC channel 0
# feeding it, and the PLIC wait for a DMA channel to finish (any channel:
# sd_read.S waits on its own channel the same way).
#
# Two frame layouts, both "instruction/address as frame format" so that what
# reaches the wire is exactly each FIFO frame, most significant bit first:
#   bytes: 8-bit frames as an 8-bit instruction phase (commands, parameters)
#   words: 32-bit frames as a 32-bit address phase (pixels, two per frame)
# A transfer ends with "TX FIFO empty and not busy" before ser drops, so the
# D/C line is never changed under bytes still on the wire.
#
# DMAC registers are 64-bit and are only accessed with ld/sd.

    .option norelax
    .include "k210.inc"
    .include "frame.inc"

    .text
    .globl spi0_init
# spi0_init
#   What: puts SPI0 in a known idle state with the LCD's serial clock
#         (403 MHz / 20 = 20.15 MHz), no interrupts, no DMA, no slave selected.
#         Needs the SPI0 clock (clocks_init).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
spi0_init:
    li      t0, SPI0_BASE
    sw      zero, SPI_SSIENR(t0)        # most registers only take writes when disabled
    sw      zero, SPI_SER(t0)
    li      t1, SPI0_BAUDR_LCD
    sw      t1, SPI_BAUDR(t0)
    sw      zero, SPI_IMR(t0)
    sw      zero, SPI_DMACR(t0)
    li      t1, SPI_DMATDLR_VALUE
    sw      t1, SPI_DMATDLR(t0)
    ret

# spi0_configure (file-local)
#   What: disables SPI0, programs the frame layout and DMA request enables,
#         and enables it again (ser still 0: nothing moves yet).
#   Arguments: a0 = ctrlr0, a1 = spi_ctrlr0, a2 = dmacr.
#   Results: t0 = SPI0_BASE (callers use it straight away).
#   Clobbers: only ABI temporaries.
spi0_configure:
    li      t0, SPI0_BASE
    sw      zero, SPI_SSIENR(t0)
    sw      a0, SPI_CTRLR0(t0)
    sw      a1, SPI_SPI_CTRLR0(t0)
    sw      a2, SPI_DMACR(t0)
    li      t1, SPI_SSIENR_ENABLE
    sw      t1, SPI_SSIENR(t0)
    ret

# spi0_finish (file-local)
#   What: waits until the last frame has left the shifter ((sr & 5) == 4),
#         then deselects the LCD and disables SPI0.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
spi0_finish:
    li      t0, SPI0_BASE
    li      t2, SPI_SR_IDLE_VALUE
1:  lw      t1, SPI_SR(t0)
    andi    t1, t1, SPI_SR_IDLE_MASK
    bne     t1, t2, 1b
    sw      zero, SPI_SER(t0)
    sw      zero, SPI_SSIENR(t0)
    ret

    .globl spi0_send_bytes
# spi0_send_bytes
#   What: sends a1 bytes from a0 to the LCD as 8-bit octal frames, polled
#         (a handful of bytes at a time: commands and their parameters). The
#         caller sets D/C first.
#   Arguments: a0 = address of the bytes, a1 = count (> 0).
#   Results: none.
#   Clobbers: only ABI temporaries.
spi0_send_bytes:
    FRAME_SAVE 32, ra, s0, s1
    mv      s0, a0
    mv      s1, a1
    li      a0, SPI_CTRLR0_OCTAL_TX_8
    li      a1, SPI_XCTRL_BYTES
    li      a2, 0
    call    spi0_configure
    li      t1, SPI_SER_LCD
    sw      t1, SPI_SER(t0)
    add     s1, s1, s0                  # s1 = end
1:  lw      t1, SPI_SR(t0)
    andi    t1, t1, SPI_SR_TFNF
    beqz    t1, 1b
    lbu     t2, 0(s0)
    sw      t2, SPI_DR(t0)
    addi    s0, s0, 1
    bltu    s0, s1, 1b
    call    spi0_finish
    FRAME_RESTORE 32, ra, s0, s1
    ret

    .globl spi0_fill_words
# spi0_fill_words
#   What: sends the same 32-bit word a1 times as 32-bit octal frames, polled.
#         For the trap handler's error screen: no DMA, no interrupts, no
#         framebuffer needed. The caller sets D/C first.
#   Arguments: a0 = word (first pixel in bits 31:16), a1 = count (> 0).
#   Results: none.
#   Clobbers: only ABI temporaries.
spi0_fill_words:
    FRAME_SAVE 32, ra, s0, s1
    mv      s0, a0
    mv      s1, a1
    li      a0, SPI_CTRLR0_OCTAL_TX_32
    li      a1, SPI_XCTRL_WORDS
    li      a2, 0
    call    spi0_configure
    li      t1, SPI_SER_LCD
    sw      t1, SPI_SER(t0)
1:  lw      t1, SPI_SR(t0)
    andi    t1, t1, SPI_SR_TFNF
    beqz    t1, 1b
    sw      s0, SPI_DR(t0)
    addi    s1, s1, -1
    bnez    s1, 1b
    call    spi0_finish
    FRAME_RESTORE 32, ra, s0, s1
    ret

    .globl dma_init
# dma_init
#   What: resets the DMAC, clears its common interrupts and enables it with
#         interrupts (per-channel signals still off). Done once, by hart 0
#         before it releases hart 1: the reset would stop a channel the other
#         hart had started. Needs the DMA clock (clocks_init).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
dma_init:
    li      t0, DMAC_BASE
    ld      t1, DMAC_RESET(t0)
    ori     t1, t1, DMAC_RESET_RST
    sd      t1, DMAC_RESET(t0)
1:  ld      t1, DMAC_RESET(t0)          # the bit self-clears when reset is done
    andi    t1, t1, DMAC_RESET_RST
    bnez    t1, 1b
    li      t1, DMAC_COM_INTCLEAR_ALL
    sd      t1, DMAC_COM_INTCLEAR(t0)
    ld      t1, DMAC_CFG(t0)
    ori     t1, t1, DMAC_CFG_EN | DMAC_CFG_INT_EN
    sd      t1, DMAC_CFG(t0)
    la      t0, dma_ready
    li      t1, 1
    sw      t1, 0(t0)
    ret

    .globl dma_irq_init
# dma_irq_init
#   What: lets DMAC channel 0's interrupt (PLIC source 27) reach the calling
#         hart (dma_irq_enable for the LCD's channel).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
dma_irq_init:
    li      a0, 0
    # fall through

    .globl dma_irq_enable
# dma_irq_enable
#   What: lets DMAC channel a0's interrupt (PLIC source 27 + a0) reach the
#         calling hart's M-mode context (context 2 x hart id on the K210),
#         threshold 0. mie.MEIE is only set while waiting, and mstatus.MIE
#         never, so this wakes WFI and never takes a trap.
#   Arguments: a0 = DMAC channel (0 .. 5).
#   Results: none.
#   Clobbers: only ABI temporaries.
dma_irq_enable:
    csrr    t0, mhartid
    addi    t3, a0, PLIC_SRC_DMA0       # t3 = PLIC source
    slli    t1, t3, 2
    li      t2, PLIC_PRIORITY
    add     t1, t1, t2
    li      t2, PLIC_DMA0_PRIORITY
    sw      t2, 0(t1)
    srli    t1, t3, 5
    slli    t1, t1, 2                   # t1 = offset of the source's enable word
    li      t2, PLIC_ENABLE
    add     t1, t1, t2
    slli    t2, t0, PLIC_HART_ENABLE_SHIFT
    add     t1, t1, t2
    lw      t2, 0(t1)
    andi    t4, t3, 31
    li      t5, 1
    sll     t5, t5, t4
    or      t2, t2, t5
    sw      t2, 0(t1)
    li      t1, PLIC_THRESHOLD
    slli    t2, t0, PLIC_HART_CONTEXT_SHIFT
    add     t1, t1, t2
    sw      zero, 0(t1)
    ret

    .globl dma_wait_channel
# dma_wait_channel
#   What: sleeps in WFI until DMAC channel a0 has finished its block (its
#         chen bit drops), then claims the PLIC interrupt, clears the
#         channel's and the common interrupt status and completes the claim.
#         Only mie.MEIE is enabled while sleeping, so a software interrupt
#         from the other hart cannot turn this into a busy loop; it stays
#         pending in the CLINT for the caller's own wait. The caller enabled
#         the channel's interrupt (intstatus_en, intsignal_en, dma_irq_enable).
#   Arguments: a0 = DMAC channel (0 .. 5).
#   Results: none.
#   Clobbers: only ABI temporaries.
dma_wait_channel:
    li      t3, MIE_MEIE
    csrs    mie, t3
    li      t4, 1                       # t4 = 1: clear mie.MEIE after the wait
    j       1f

    .globl dma_sleep_channel
# dma_sleep_channel
#   What: dma_wait_channel for a caller that keeps mie.MEIE set across a
#         series of waits (sd_read_blocks, one per SD block): no write to mie
#         (each would end the hart's run in the board model, and costs a CSR
#         access on the chip). mstatus.MIE stays 0, so MEIE only wakes WFI.
#   Arguments: a0 = DMAC channel (0 .. 5).
#   Results: none.
#   Clobbers: only ABI temporaries.
dma_sleep_channel:
    li      t4, 0
1:  li      t0, DMAC_BASE
    li      t2, 1
    sll     t2, t2, a0                  # t2 = the channel's chen bit
2:  wfi
    ld      t1, DMAC_CHEN(t0)
    and     t1, t1, t2
    bnez    t1, 2b
    beqz    t4, 3f
    li      t3, MIE_MEIE
    csrc    mie, t3

3:  # Claim, quiet the source, complete: completing while the DMAC still
    # asserts the (level) interrupt would make the PLIC raise it again.
    csrr    t4, mhartid
    slli    t4, t4, PLIC_HART_CONTEXT_SHIFT
    li      t5, PLIC_THRESHOLD + PLIC_CLAIM_OFF
    add     t5, t5, t4                  # t5 = &claim[the hart's M-mode context]
    lw      t6, 0(t5)
    slli    t1, a0, DMAC_CH_STRIDE_SHIFT
    add     t1, t1, t0                  # t1 = channel a0's registers - DMAC_CH0
    li      t2, DMAC_CH_INT_BLOCK_DONE
    sd      t2, DMAC_CH0 + DMAC_CH_INTCLEAR(t1)
    li      t2, DMAC_COM_INTCLEAR_ALL
    sd      t2, DMAC_COM_INTCLEAR(t0)
    beqz    t6, 4f                      # nothing claimed: nothing to complete
    sw      t6, 0(t5)
4:  fence                               # what the DMAC wrote is read after this
    ret

    .globl spi0_dma_send_words
# spi0_dma_send_words
#   What: sends a1 32-bit words from memory at a0 to the LCD through DMAC
#         channel 0 (request line SSI0_TX), sleeping in WFI until the channel
#         finishes, then acknowledges the interrupt and waits for the last
#         frames to leave SPI0: spi0_dma_send_start, then
#         spi0_dma_send_finish. The caller sets D/C first and must have run
#         dma_init and (on this hart) dma_irq_init.
#   Arguments: a0 = word-aligned source address, a1 = word count
#         (1 .. 2^22).
#   Results: none.
#   Clobbers: only ABI temporaries.
spi0_dma_send_words:
    FRAME_SAVE 16, ra
    call    spi0_dma_send_start
    call    spi0_dma_send_finish
    FRAME_RESTORE 16, ra
    ret

    .globl spi0_dma_send_start
# spi0_dma_send_start
#   What: starts sending a1 32-bit words from memory at a0 to the LCD
#         through DMAC channel 0 and returns at once; the words must stay
#         as they are until spi0_dma_send_finish has returned, and SPI0 is
#         busy until then. The caller sets D/C first and must have run
#         dma_init and (on this hart) dma_irq_init.
#   Arguments: a0 = word-aligned source address, a1 = word count
#         (1 .. 2^22).
#   Results: none.
#   Clobbers: only ABI temporaries.
spi0_dma_send_start:
    li      a2, DMAC_CTL_MEM_TO_SPI32
    j       spi0_dma_start

    .globl spi0_dma_send_finish
# spi0_dma_send_finish
#   What: ends what spi0_dma_send_start began: sleeps in WFI until DMAC
#         channel 0 finishes (at once when it already has: its interrupt is
#         still pending), acknowledges the interrupt, waits for the last
#         frames to leave SPI0 and turns SPI0's DMA requests off.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
spi0_dma_send_finish:
    FRAME_SAVE 16, ra
    li      a0, 0
    call    dma_wait_channel
    call    spi0_finish
    li      t0, SPI0_BASE
    sw      zero, SPI_DMACR(t0)
    FRAME_RESTORE 16, ra
    ret

    .globl spi0_dma_fill_words
# spi0_dma_fill_words
#   What: sends the 32-bit word at a0, a1 times, to the LCD through DMAC
#         channel 0 with a fixed source address, polling chen (no interrupts
#         needed: the trap handler and fatal errors use it), at most
#         DMA_POLL_LIMIT polls; then waits for SPI0 to drain. The caller sets
#         D/C first and must have run dma_init.
#   Arguments: a0 = address of the word, a1 = count (1 .. 2^22).
#   Results: none.
#   Clobbers: only ABI temporaries.
spi0_dma_fill_words:
    FRAME_SAVE 16, ra
    li      a2, DMAC_CTL_FILL_SPI32
    call    spi0_dma_start
    li      t0, DMAC_BASE
    li      t2, DMA_POLL_LIMIT
1:  ld      t1, DMAC_CHEN(t0)
    andi    t1, t1, DMAC_CHEN_CH0
    beqz    t1, 2f
    addi    t2, t2, -1
    bnez    t2, 1b
2:  li      t1, DMAC_CH_INTCLEAR_ALL
    sd      t1, DMAC_CH0 + DMAC_CH_INTCLEAR(t0)
    call    spi0_finish
    li      t0, SPI0_BASE
    sw      zero, SPI_DMACR(t0)
    FRAME_RESTORE 16, ra
    ret

# spi0_dma_start (file-local)
#   What: starts DMAC channel 0 moving a1 32-bit words from a0 into SPI0's
#         FIFO (32-bit octal frames, TX DMA requests) and selects the LCD.
#         Returns at once; the caller waits for the channel.
#   Arguments: a0 = source address, a1 = word count, a2 = channel ctl
#         (DMAC_CTL_MEM_TO_SPI32 or DMAC_CTL_FILL_SPI32).
#   Results: none.
#   Clobbers: only ABI temporaries.
spi0_dma_start:
    FRAME_SAVE 32, ra, s0, s1, s2
    mv      s0, a0
    mv      s1, a1
    mv      s2, a2

    # SPI0: 32-bit frames, TX DMA requests when the FIFO is at or below dmatdlr.
    li      a0, SPI_CTRLR0_OCTAL_TX_32
    li      a1, SPI_XCTRL_WORDS
    li      a2, SPI_DMACR_TDMAE
    call    spi0_configure

    # Channel 0's handshake interface carries SSI0_TX. The other hart may be
    # setting channel 1's field of the same register (shared_io_lock).
    call    shared_io_lock
    li      t0, SYSCTL_BASE
    lw      t1, SYSCTL_DMA_SEL0(t0)
    andi    t1, t1, ~DMA_SEL_CH0_MASK
    ori     t1, t1, DMA_REQ_SSI0_TX << DMA_SEL_CH0_SHIFT
    sw      t1, SYSCTL_DMA_SEL0(t0)
    call    shared_io_unlock

    # Channel 0: stale interrupts cleared, make sure it is off before
    # reprogramming (the registers are ignored while it runs).
    li      t0, DMAC_BASE
    li      t1, DMAC_CH_INTCLEAR_ALL
    sd      t1, DMAC_CH0 + DMAC_CH_INTCLEAR(t0)
    li      t1, DMAC_CHEN_WE_CH0        # write-enabled, enable bit 0
    sd      t1, DMAC_CHEN(t0)
1:  ld      t1, DMAC_CHEN(t0)
    andi    t1, t1, DMAC_CHEN_CH0
    bnez    t1, 1b

    # cfg before sar/dar/block_ts, as the SDK notes.
    li      t1, DMAC_CFG_MEM_TO_SPI
    sd      t1, DMAC_CH0 + DMAC_CH_CFG(t0)
    sd      s0, DMAC_CH0 + DMAC_CH_SAR(t0)
    li      t1, SPI0_DR_ADDR
    sd      t1, DMAC_CH0 + DMAC_CH_DAR(t0)
    addi    t1, s1, -1
    sd      t1, DMAC_CH0 + DMAC_CH_BLOCK_TS(t0)
    sd      s2, DMAC_CH0 + DMAC_CH_CTL(t0)
    li      t1, DMAC_CH_INT_BLOCK_DONE
    sd      t1, DMAC_CH0 + DMAC_CH_INTSTATUS_EN(t0)
    sd      t1, DMAC_CH0 + DMAC_CH_INTSIGNAL_EN(t0)

    # The pixel words written by the other hart and by this one must be in
    # memory before the DMAC reads them.
    fence   rw, o
    li      t1, DMAC_CHEN_CH0 | DMAC_CHEN_WE_CH0
    sd      t1, DMAC_CHEN(t0)

    # Select the LCD: the DMAC has started filling the FIFO, SPI0 shifts out.
    li      t2, SPI0_BASE
    li      t1, SPI_SER_LCD
    sw      t1, SPI_SER(t2)

    FRAME_RESTORE 32, ra, s0, s1, s2
    ret

    .globl dma_quiesce
# dma_quiesce
#   What: brings DMAC channel 0 and SPI0 to rest wherever they are, so the
#         trap handler can take SPI0 over for a polled transfer. A block in
#         flight is let finish (it ends by itself within one frame time);
#         only if it never does is the channel switched off by force.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
    .equ DMA_QUIESCE_POLLS,     1 << 24     # far longer than one frame's DMA
dma_quiesce:
    li      t0, DMAC_BASE
    li      t2, DMA_QUIESCE_POLLS
1:  ld      t1, DMAC_CHEN(t0)
    andi    t1, t1, DMAC_CHEN_CH0
    beqz    t1, 2f
    addi    t2, t2, -1
    bnez    t2, 1b
    li      t1, DMAC_CHEN_WE_CH0
    sd      t1, DMAC_CHEN(t0)
2:  li      t0, SPI0_BASE
    sw      zero, SPI_DMACR(t0)
    sw      zero, SPI_SER(t0)
    sw      zero, SPI_SSIENR(t0)
    ret

    .data
    .balign 4
    .globl dma_ready
# dma_ready: 1 once dma_init has run (in .data: valid before .bss is cleared),
# so the error screen knows whether it can fill the screen by DMA.
dma_ready:
    .word   0
