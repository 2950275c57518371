# sd_spi.S: SPI1 as the SD card driver uses it: chip select (GPIOHS7),
# byte exchanges (sd_xchg) and bursts of up to SPI_FIFO_DEPTH bytes through
# the FIFOs (sd_burst), the received bytes not yet taken (sd.S sd_ahead,
# read with sd_take_byte, sd_take_ahead, sd_receive_bytes), SPI1's set-up
# and its switch between transmit-and-receive and receive-only (DMA,
# sd_read.S) modes; and the driver's delays.

    .option norelax
    .include "k210.inc"
    .include "sd.inc"
    .include "frame.inc"

    .text
    .globl sd_select
# sd_select
#   What: chip select low. The 0xFF byte that lets the card drive MISO
#         before a command goes out with the command (sd_command).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
sd_select:
    li      a0, GPIOHS_SD_CS_BIT
    j       gpiohs_clear

    .globl sd_deselect
# sd_deselect
#   What: chip select high, then one 0xFF byte (8 clocks) so the card
#         releases MISO; received bytes not taken are dropped. No byte is
#         on the wire when CS changes: sd_burst and sd_xchg return only
#         after their bytes have come back.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
sd_deselect:
    FRAME_SAVE 16, ra
    call    sd_drop_ahead
    li      a0, GPIOHS_SD_CS_BIT
    call    gpiohs_set
    li      a0, SD_IDLE_BYTE
    call    sd_xchg
    FRAME_RESTORE 16, ra
    ret

# sd_xchg (file-local)
#   What: sends one byte on MOSI and returns the byte clocked in on MISO
#         (SPI1 in transmit-and-receive mode, FIFOs in step: each call
#         leaves both empty).
#   Arguments: a0 = byte to send.
#   Results: a0 = byte received.
#   Clobbers: only ABI temporaries.
sd_xchg:
    li      t0, SPI1_BASE
    sw      a0, SPI_DR(t0)
1:  lw      t1, SPI_SR(t0)
    andi    t1, t1, SPI_SR_RFNE
    beqz    t1, 1b
    lw      a0, SPI_DR(t0)
    andi    a0, a0, SD_BYTE_MASK
    ret

    .globl sd_burst
# sd_burst
#   What: exchanges a1 bytes in place: sends the bytes at a0 on MOSI and
#         puts the bytes clocked in on MISO in their place. All go into the
#         transmit FIFO at once; once the wire is idle (transmit FIFO empty,
#         not busy: the wait the Kendryte SDK's SPI driver uses) every
#         received byte is in the receive FIFO. SPI1 in transmit-and-receive
#         mode with both FIFOs empty; they are empty again after.
#   Arguments: a0 = bytes, a1 = count (1 .. SPI_FIFO_DEPTH).
#   Results: none.
#   Clobbers: only ABI temporaries.
sd_burst:
    li      t0, SPI1_BASE
    mv      t2, a0
    add     t3, a0, a1                  # t3 = end
1:  lbu     t1, 0(t2)
    sw      t1, SPI_DR(t0)
    addi    t2, t2, 1
    bltu    t2, t3, 1b
    li      t2, SPI_SR_TFE
2:  lw      t1, SPI_SR(t0)
    andi    t1, t1, SPI_SR_IDLE_MASK
    bne     t1, t2, 2b
    mv      t2, a0
3:  lw      t1, SPI_DR(t0)
    sb      t1, 0(t2)
    addi    t2, t2, 1
    bltu    t2, t3, 3b
    ret

    .globl sd_fill_ahead
# sd_fill_ahead
#   What: clocks in a0 bytes (MOSI 0xFF) in one burst; they become sd_ahead,
#         which must hold nothing not yet taken.
#   Arguments: a0 = count (1 .. SD_AHEAD_BYTES).
#   Results: none.
#   Clobbers: only ABI temporaries.
sd_fill_ahead:
    la      t0, sd_ahead_next
    sw      zero, 0(t0)
    sw      a0, SD_AHEAD_END_AT(t0)
    la      t0, sd_ahead
    add     t1, t0, a0
    li      t2, SD_IDLE_BYTE
1:  sb      t2, 0(t0)
    addi    t0, t0, 1
    bltu    t0, t1, 1b
    mv      a1, a0
    la      a0, sd_ahead
    j       sd_burst

    .globl sd_ahead_left
# sd_ahead_left
#   What: how many received bytes wait in sd_ahead.
#   Arguments: none. Results: a0 = count.
#   Clobbers: only ABI temporaries.
sd_ahead_left:
    la      t0, sd_ahead_next
    lw      a0, SD_AHEAD_END_AT(t0)
    lw      t1, 0(t0)
    sub     a0, a0, t1
    ret

    .globl sd_drop_ahead
# sd_drop_ahead
#   What: forgets the received bytes waiting in sd_ahead.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
sd_drop_ahead:
    la      t0, sd_ahead_next
    sw      zero, 0(t0)
    sw      zero, SD_AHEAD_END_AT(t0)
    ret

    .globl sd_take_byte
# sd_take_byte
#   What: the next received byte: the oldest waiting in sd_ahead, or else
#         one exchanged now (MOSI 0xFF).
#   Arguments: none. Results: a0 = the byte.
#   Clobbers: only ABI temporaries.
sd_take_byte:
    la      t0, sd_ahead_next
    lw      t1, 0(t0)
    lw      t2, SD_AHEAD_END_AT(t0)
    bgeu    t1, t2, 1f
    la      t2, sd_ahead
    add     t2, t2, t1
    lbu     a0, 0(t2)
    addi    t1, t1, 1
    sw      t1, 0(t0)
    ret
1:  li      a0, SD_IDLE_BYTE
    j       sd_xchg

    .globl sd_take_ahead
# sd_take_ahead
#   What: moves the received bytes waiting in sd_ahead to a0.
#   Arguments: a0 = destination. Results: a0 = how many.
#   Clobbers: only ABI temporaries.
sd_take_ahead:
    la      t0, sd_ahead_next
    lw      t1, 0(t0)
    lw      t2, SD_AHEAD_END_AT(t0)
    sw      t2, 0(t0)
    sub     t3, t2, t1                  # t3 = count
    la      t4, sd_ahead
    add     t1, t4, t1
    add     t2, t4, t2
1:  bgeu    t1, t2, 2f
    lbu     t5, 0(t1)
    sb      t5, 0(a0)
    addi    t1, t1, 1
    addi    a0, a0, 1
    j       1b
2:  mv      a0, t3
    ret

    .globl sd_receive_bytes
# sd_receive_bytes
#   What: the next a1 received bytes to a0: those waiting in sd_ahead, then
#         bursts of at most SD_AHEAD_BYTES.
#   Arguments: a0 = destination, a1 = count.
#   Results: none.
#   Clobbers: only ABI temporaries.
sd_receive_bytes:
    FRAME_SAVE 32, ra, s0, s1
    add     s1, a0, a1                  # s1 = end
    mv      s0, a0                      # s0 = next byte out
1:  bgeu    s0, s1, 3f
    call    sd_ahead_left
    bnez    a0, 2f
    sub     a0, s1, s0
    li      t0, SD_AHEAD_BYTES
    bleu    a0, t0, 4f
    mv      a0, t0
4:  call    sd_fill_ahead
2:  call    sd_take_byte
    sb      a0, 0(s0)
    addi    s0, s0, 1
    j       1b
3:  FRAME_RESTORE 32, ra, s0, s1
    ret

    .globl sd_spi_setup
# sd_spi_setup
#   What: SPI1 disabled, programmed for the card (transmit-and-receive,
#         8-bit standard frames, the given clock divider, no interrupts, no
#         DMA requests), enabled with its transfer-enable select bit.
#   Arguments: a0 = baudr (even).
#   Results: none.
#   Clobbers: only ABI temporaries.
sd_spi_setup:
    la      t0, sd_rx_frames
    sw      zero, 0(t0)
    li      t0, SPI1_BASE
    sw      zero, SPI_SSIENR(t0)
    sw      a0, SPI_BAUDR(t0)
    li      t1, SD_CTRLR0_TX_RX
    sw      t1, SPI_CTRLR0(t0)
    sw      zero, SPI_CTRLR1(t0)
    sw      zero, SPI_SPI_CTRLR0(t0)
    sw      zero, SPI_IMR(t0)
    sw      zero, SPI_DMACR(t0)
    li      t1, SPI_DMARDLR_VALUE
    sw      t1, SPI_DMARDLR(t0)
    li      t1, SPI_SSIENR_ENABLE
    sw      t1, SPI_SSIENR(t0)
    li      t1, SD_SPI_SER
    sw      t1, SPI_SER(t0)
    ret

    .globl sd_spi_mode
# sd_spi_mode
#   What: switches SPI1 between transfer modes (disable, ctrlr0/ctrlr1,
#         enable, then the DMA request enables). Disabling empties both
#         FIFOs; no byte is in flight when this is called.
#   Arguments: a0 = ctrlr0, a1 = ctrlr1, a2 = dmacr.
#   Results: none.
#   Clobbers: only ABI temporaries.
sd_spi_mode:
    li      t0, SPI1_BASE
    sw      zero, SPI_SSIENR(t0)
    sw      a0, SPI_CTRLR0(t0)
    sw      a1, SPI_CTRLR1(t0)
    li      t1, SPI_SSIENR_ENABLE
    sw      t1, SPI_SSIENR(t0)
    sw      a2, SPI_DMACR(t0)
    ret

    .globl sd_delay_us
# sd_delay_us
#   What: delay_us at the CPU clock in force (cpu_hz).
#   Arguments: a0 = microseconds. Results: none.
#   Clobbers: only ABI temporaries.
sd_delay_us:
    la      t0, cpu_hz
    lwu     a1, 0(t0)
    j       delay_us
