# sd.S: the SD card in SPI mode on SPI1: bring-up (sd_init) and the card's
# capacity from its CSD; the driver's messages and state.
#
# Wiring (pins.S): SCLK pad 27, MOSI pad 28 (SPI1_D0), MISO pad 26
# (SPI1_D1), chip select pad 29 = GPIOHS7 driven here by software. SPI1 runs
# standard format, work mode 0, 8-bit frames: transmit-and-receive for
# commands, responses and tokens, receive-only with DMAC channel 1 for data
# blocks (sd_read.S). Commands and the bytes after them go in bursts through
# the 32-entry FIFOs (sd_spi.S sd_burst): a command's frame and the Ncr
# bytes its R1 comes in are one burst, and what arrives after R1 (an R3/R7
# payload, the busy bytes after CMD12, the gap before a data token, the
# token and the first data bytes) waits in sd_ahead for whoever reads next.
#
# Every command carries its CRC7 (crc.S), so CMD59 can turn the card's CRC
# checking on; every data block's CRC16 is checked and a bad block is read
# again from that block (SD_READ_RETRIES times) before error 4.
#
# Bring-up (sd_init), at <= 400 kHz:
#   >= 74 clocks with CS high; CMD0 -> R1 idle (SD_CMD0_TRIES tries, no
#   answer at all = no card); CMD8(0x1AA) -> R7 echo; CMD55 + ACMD41(HCS)
#   until R1 = 0 (1 s limit on the CLINT timer, delay_us between tries);
#   CMD58 -> OCR (power-up bit, CCS); CMD59(1) CRC on; CMD16(512) for a
#   byte-addressed card; CMD9 -> CSD: the card's capacity in blocks
#   (sd_capacity; fat32.S refuses a volume that does not fit in it, so no
#   read ever asks for a block the card does not have); then SCLK to
#   403 MHz / 18 = 22.4 MHz.
#
# Failures end in errors.S reports (codes in errors.inc); sd_init and
# sd_read_blocks return only on success.
#
# The driver's messages and variables (.rodata, .bss, below) live here for
# all the sd*.S files, in the order the image has always had them (the
# Makefile's FW_ORDER keeps code and data where the cycle counts were
# measured); each says who uses it.
#
# The driver's files, in link order:
#   sd.S           sd_init (bring-up), the CSD (capacity); messages, state
#   sd_read.S      block reads: CMD17 / CMD18 + CMD12, data tokens, DMA into
#                  the staging buffers, each block's CRC16 checked
#   sd_command.S   one command and its response: the frame with its CRC7,
#                  R1 (and R3 / R7), resent on a CRC error; failure reports
#   sd_spi.S       SPI1 for the card: chip select, byte exchanges and bursts,
#                  the received bytes waiting (sd_ahead), SPI1's modes

    .option norelax
    .include "k210.inc"
    .include "sd.inc"
    .include "errors.inc"
    .include "frame.inc"

    .if SD_DMA_CHANNEL != 1
    .error "SD_DMA_SEL_SHIFT / SD_DMA_SEL_MASK assume DMAC channel 1"
    .endif
    .if SD_BAUDR_FAST < 2 || SD_BAUDR_INIT > SD_BAUDR_MAX
    .error "SD clock dividers out of range"
    .endif

    .text
    .globl sd_init
# sd_init
#   What: SPI1 and DMAC channel 1 set up for the card, then the card's SPI
#         mode bring-up (see the file comment), its capacity from the CSD
#         (sd_capacity) and the fast clock. Prints one console line on
#         success. Needs clocks_init, pins_init,
#         console_init, crc_init, dma_init; the LCD should be up so that
#         errors can be shown.
#   Arguments: none. Results: none (returns only with a ready card).
#   Clobbers: only ABI temporaries.
sd_init:
    FRAME_SAVE 48, ra, s0, s1, s2

    li      a0, SD_BAUDR_INIT
    call    sd_spi_setup

    # DMAC channel 1's handshake interface carries SSI1_RX; its interrupt
    # reaches this hart for the WFI waits. The other hart may be setting
    # channel 0's field of the same register (shared_io_lock).
    call    shared_io_lock
    li      t0, SYSCTL_BASE
    lw      t1, SYSCTL_DMA_SEL0(t0)
    li      t2, ~SD_DMA_SEL_MASK
    and     t1, t1, t2
    ori     t1, t1, DMA_REQ_SSI1_RX << SD_DMA_SEL_SHIFT
    sw      t1, SYSCTL_DMA_SEL0(t0)
    call    shared_io_unlock
    li      a0, SD_DMA_CHANNEL
    call    dma_irq_enable

    # Supply ramp, then >= 74 clocks with CS high (pins_init left it high).
    li      a0, SD_POWER_UP_US
    call    sd_delay_us
    li      a0, SD_INIT_CLOCK_BYTES
    call    sd_fill_ahead
    call    sd_drop_ahead

    # CMD0: software reset into SPI mode; the card answers "idle".
    li      s0, SD_CMD0_TRIES
2:  li      a0, SD_CMD0_GO_IDLE
    li      a1, 0
    li      a2, 0
    call    sd_cmd
    mv      s1, a0                      # s1 = last R1
    li      t0, SD_R1_IDLE
    beq     a0, t0, 3f
    li      a0, SD_CMD0_RETRY_US
    call    sd_delay_us
    addi    s0, s0, -1
    bnez    s0, 2b
    li      t0, SD_R1_NONE
    bne     s1, t0, 4f
    li      a0, ERR_NO_CARD
    la      a1, msg_no_card
    li      a2, 0
    call    error_fatal
4:  li      a0, SD_CMD0_GO_IDLE
    mv      a1, s1
    call    sd_fail_r1

    # CMD8: a version 2 card echoes the voltage range and check pattern.
3:  li      a0, SD_CMD8_SEND_IF_COND
    li      a1, SD_CMD8_ARG
    li      a2, 1
    call    sd_cmd
    mv      s1, a1                      # s1 = R7 payload
    li      t0, SD_R1_NONE
    beq     a0, t0, 5f
    andi    t0, a0, SD_R1_ILLEGAL_COMMAND
    beqz    t0, 6f
    li      a0, ERR_UNSUPPORTED
    la      a1, msg_sd_v1
    li      a2, 0
    call    error_fatal
6:  li      t0, SD_R1_IDLE
    bne     a0, t0, 5f
    li      t0, SD_CMD8_ECHO_MASK
    and     t0, s1, t0
    li      t1, SD_CMD8_ARG
    beq     t0, t1, 7f
    li      a0, ERR_UNSUPPORTED
    la      a1, msg_cmd8_echo
    mv      a2, s1
    li      a3, SD_WORD_HEX_DIGITS
    call    error_fatal_hex
5:  mv      a1, a0
    li      a0, SD_CMD8_SEND_IF_COND
    call    sd_fail_r1

    # CMD55 + ACMD41 until the card leaves the idle state (1 s at most).
7:  li      a0, SD_ACMD41_TIMEOUT_US
    call    timer_deadline
    mv      s2, a0                      # s2 = deadline
8:  li      a0, SD_CMD55_APP_CMD
    li      a1, 0
    li      a2, 0
    call    sd_cmd
    andi    t0, a0, ~SD_R1_IDLE
    beqz    t0, 9f
    mv      a1, a0
    li      a0, SD_CMD55_APP_CMD
    call    sd_fail_r1
9:  li      a0, SD_ACMD41_SEND_OP_COND
    li      a1, SD_ACMD41_HCS
    li      a2, 0
    call    sd_cmd
    beqz    a0, 11f                     # ready
    li      t0, SD_R1_IDLE
    beq     a0, t0, 10f
    mv      a1, a0
    li      a0, SD_ACMD41_SEND_OP_COND
    call    sd_fail_r1
10: mv      a0, s2
    call    timer_expired
    beqz    a0, 12f
    li      a0, ERR_CARD_TIMEOUT
    la      a1, msg_acmd41_timeout
    li      a2, 0
    call    error_fatal
12: li      a0, SD_ACMD41_POLL_US
    call    sd_delay_us
    j       8b

    # CMD58: OCR. Powered up; CCS tells block from byte addressing.
11: li      a0, SD_CMD58_READ_OCR
    li      a1, 0
    li      a2, 1
    call    sd_cmd_ok
    mv      s1, a0                      # s1 = OCR
    li      t0, SD_OCR_POWERED_UP
    and     t0, s1, t0
    bnez    t0, 13f
    li      a0, ERR_UNSUPPORTED
    la      a1, msg_ocr_power
    mv      a2, s1
    li      a3, SD_WORD_HEX_DIGITS
    call    error_fatal_hex
13: srli    s1, s1, SD_OCR_CCS_SHIFT
    andi    s1, s1, 1                   # s1 = CCS
    la      t0, sd_ccs
    sw      s1, 0(t0)

    # CMD59(1): the card checks the CRC7 of every command from now on.
    li      a0, SD_CMD59_CRC_ON_OFF
    li      a1, SD_CMD59_CRC_ON
    li      a2, 0
    call    sd_cmd_ok

    # A byte-addressed (standard capacity) card: make sure blocks are 512.
    bnez    s1, 14f
    li      a0, SD_CMD16_SET_BLOCKLEN
    li      a1, SD_BLOCK_BYTES
    li      a2, 0
    call    sd_cmd_ok

    # CMD9: the CSD, for the card's capacity (at the identification clock,
    # which any card takes).
14: mv      a0, sp
    call    sd_read_csd
    mv      a0, sp
    call    sd_csd_blocks
    bnez    a0, 16f
    mv      a2, a1
    li      a0, ERR_UNSUPPORTED
    la      a1, msg_csd_version
    la      a3, msg_csd_version_tail
    call    error_fatal_dec
16: mv      s2, a0                      # s2 = capacity in blocks
    la      t0, sd_capacity
    sd      s2, 0(t0)

    # Identification done: up to the default-speed clock.
    li      a0, SD_BAUDR_FAST
    call    sd_spi_setup

    call    console_lock
    la      a0, msg_sd_ready
    call    console_puts
    la      a0, msg_sdhc
    bnez    s1, 15f
    la      a0, msg_sdsc
15: call    console_puts
    la      a0, msg_sd_capacity
    call    console_puts
    mv      a0, s2
    call    console_put_dec
    la      a0, msg_sd_clock
    call    console_puts
    li      a0, SD_FAST_ACTUAL_HZ
    call    console_put_dec
    la      a0, msg_hz_nl
    call    console_puts
    call    console_unlock

    FRAME_RESTORE 48, ra, s0, s1, s2
    ret

# sd_read_csd (file-local)
#   What: CMD9: the CSD register, a 16-byte data block after R1 (read by
#         the CPU, it is short), its CRC16 checked. A bad CRC16, an error
#         token or an R1 reporting a command CRC error is read again, up to
#         SD_READ_RETRIES times, then error 4.
#   Arguments: a0 = where the SD_CSD_BYTES bytes go.
#   Results: none (returns only with an intact CSD).
#   Clobbers: only ABI temporaries.
sd_read_csd:
    FRAME_SAVE 48, ra, s0, s1, s2, s3
    mv      s0, a0                      # s0 = destination
    li      s1, SD_READ_RETRIES + 1     # s1 = tries left
1:  call    sd_select
    li      a0, SD_CMD9_SEND_CSD
    li      a1, 0
    call    sd_command
    beqz    a0, 3f
    mv      s2, a0                      # s2 = R1
    call    sd_deselect
    li      t0, SD_R1_NONE
    beq     s2, t0, 2f
    andi    t0, s2, SD_R1_CRC_ERROR
    bnez    t0, 7f                      # the card saw a bad command CRC: again
2:  li      a0, SD_CMD9_SEND_CSD
    mv      a1, s2
    call    sd_fail_r1

3:  call    sd_wait_token
    li      t0, SD_TOKEN_START_BLOCK
    bne     a0, t0, 6f                  # error token
    mv      a0, s0
    li      a1, SD_CSD_BYTES
    call    sd_receive_bytes
    mv      a0, sp
    li      a1, SD_CRC16_BYTES
    call    sd_receive_bytes
    lbu     s3, 0(sp)
    slli    s3, s3, SD_BYTE_BITS
    lbu     t0, 1(sp)
    or      s3, s3, t0                  # s3 = CRC16 the card sent
    call    sd_deselect
    mv      a0, s0
    li      a1, SD_CSD_BYTES
    call    crc16_ccitt
    beq     a0, s3, 9f
    j       7f
6:  call    sd_deselect
7:  addi    s1, s1, -1
    bnez    s1, 1b
    li      a0, ERR_CRC
    la      a1, msg_crc_csd
    li      a2, 0
    call    error_fatal

9:  FRAME_RESTORE 48, ra, s0, s1, s2, s3
    ret

    .globl sd_csd_blocks
# sd_csd_blocks
#   What: a card's capacity in 512-byte blocks from its CSD register (the
#         field layouts are in sd.inc): version 2.0 (SDHC, SDXC)
#         (C_SIZE + 1) << 10; version 1.0 (SDSC) (C_SIZE + 1) <<
#         (C_SIZE_MULT + 2) blocks of 2^READ_BL_LEN bytes, counted in 512s.
#   Arguments: a0 = the SD_CSD_BYTES bytes, as the card sent them.
#   Results: a0 = capacity in blocks, or 0 for a CSD_STRUCTURE this
#         firmware does not know (version 3.0, reserved); a1 = CSD_STRUCTURE.
#   Clobbers: only ABI temporaries.
sd_csd_blocks:
    lbu     a1, SD_CSD_STRUCTURE_BYTE(a0)
    srli    a1, a1, SD_CSD_STRUCTURE_SHIFT
    li      t0, SD_CSD_VERSION_2
    beq     a1, t0, 2f
    li      t0, SD_CSD_VERSION_1
    beq     a1, t0, 1f
    li      a0, 0
    ret
1:  lbu     t0, SD_CSD1_C_SIZE_HI(a0)
    andi    t0, t0, SD_CSD1_C_SIZE_HI_MASK
    slli    t0, t0, SD_CSD1_C_SIZE_HI_SHIFT
    lbu     t1, SD_CSD1_C_SIZE_MID(a0)
    slli    t1, t1, SD_CSD1_C_SIZE_MID_SHIFT
    or      t0, t0, t1
    lbu     t1, SD_CSD1_C_SIZE_LO(a0)
    srli    t1, t1, SD_CSD1_C_SIZE_LO_SHIFT
    or      t0, t0, t1
    addi    t0, t0, 1                   # t0 = C_SIZE + 1
    lbu     t1, SD_CSD1_MULT_HI(a0)
    andi    t1, t1, SD_CSD1_MULT_HI_MASK
    slli    t1, t1, 1
    lbu     t2, SD_CSD1_MULT_LO(a0)
    srli    t2, t2, SD_CSD1_MULT_LO_SHIFT
    or      t1, t1, t2
    addi    t1, t1, SD_CSD1_MULT_BIAS   # t1 = C_SIZE_MULT + 2
    lbu     t2, SD_CSD1_READ_BL_LEN(a0)
    andi    t2, t2, SD_CSD1_READ_BL_LEN_MASK
    add     t1, t1, t2
    sll     t0, t0, t1                  # bytes (below 2^37 whatever the fields)
    srli    a0, t0, SD_BLOCK_SHIFT
    ret
2:  lbu     t0, SD_CSD2_C_SIZE_HI(a0)
    andi    t0, t0, SD_CSD2_C_SIZE_HI_MASK
    lbu     t1, SD_CSD2_C_SIZE_MID(a0)
    slli    t0, t0, SD_BYTE_BITS
    or      t0, t0, t1
    lbu     t1, SD_CSD2_C_SIZE_LO(a0)
    slli    t0, t0, SD_BYTE_BITS
    or      t0, t0, t1
    addi    t0, t0, 1
    slli    a0, t0, SD_CSD2_UNIT_SHIFT
    ret

# ---------------------------------------------------------------------------
    .section .rodata
# The reports' words: sd_init's and the CSD's, sd_read.S's (no data token,
# busy after CMD12, a block that stays bad) and sd_command.S's (no response,
# an R1 refused, a command's CRC), in the order the image has them.
msg_sd_ready:       .asciz "sd: card ready, "
msg_sdhc:           .asciz "SDHC (block addressing)"
msg_sdsc:           .asciz "SDSC (byte addressing)"
msg_sd_capacity:    .asciz ", "
msg_sd_clock:       .asciz " blocks, SPI1 "
msg_hz_nl:          .asciz " Hz\n"
msg_no_card:        .asciz "no card: no response to CMD0"
msg_sd_v1:          .asciz "unsupported card: CMD8 illegal (SD 1.x card)"
msg_cmd8_echo:      .asciz "unsupported card: CMD8 echo "
msg_ocr_power:      .asciz "unsupported card: OCR not powered up "
msg_acmd41_timeout: .asciz "card timeout: still initialising after ACMD41 for 1 s"
    .globl msg_token_timeout
msg_token_timeout:  .asciz "card timeout: no data token"
    .globl msg_busy_timeout
msg_busy_timeout:   .asciz "card timeout: busy after CMD12"
    .globl msg_no_response
msg_no_response:    .asciz "card timeout: no response to CMD"
    .globl msg_refused
msg_refused:        .asciz "unsupported card: CMD"
    .globl msg_refused_r1
msg_refused_r1:     .asciz " answered R1 0x"
    .globl msg_crc_block
msg_crc_block:      .asciz "CRC errors: block "
    .globl msg_crc_block_tail
msg_crc_block_tail: .asciz " stays bad after retries"
    .globl msg_crc_cmd
msg_crc_cmd:        .asciz "CRC errors: CMD"
msg_crc_csd:        .asciz "CRC errors: the CSD (CMD9) stays bad after retries"
msg_csd_version:    .asciz "unsupported card: CSD_STRUCTURE "
msg_csd_version_tail: .asciz " (known: 0 and 1, CSD versions 1.0 and 2.0)"
    .globl msg_crc_cmd_tail
msg_crc_cmd_tail:   .asciz " response keeps reporting a CRC error"

# ---------------------------------------------------------------------------
    .bss
    .balign 4
    .globl sd_ccs
# sd_ccs: 1 = block-addressed card (SDHC/SDXC), 0 = byte-addressed (SDSC);
# set by sd_init, read by sd_read.S to address a block.
sd_ccs:
    .space  4
    .globl sd_rx_frames
# sd_rx_frames: the frames SPI1's receive-only mode is set up for (its
# ctrlr1 + 1), 0 when SPI1 is in transmit-and-receive mode (sd_read.S,
# sd_spi.S).
sd_rx_frames:
    .space  4
    .globl sd_ahead_next
# sd_ahead_next, sd_ahead_end: the received bytes not yet taken are
# sd_ahead[sd_ahead_next .. sd_ahead_end).
sd_ahead_next:
    .space  4
sd_ahead_end:
    .space  4
    .if sd_ahead_end - sd_ahead_next != SD_AHEAD_END_AT
    .error "SD_AHEAD_END_AT does not match the layout of sd_ahead_next"
    .endif
    .globl sd_ahead
# sd_ahead: the last burst (sd_spi.S sd_burst), command and bytes received
# (sd_command.S builds the command there).
sd_ahead:
    .space  SD_AHEAD_BYTES
    .balign 8
    .globl sd_access_ticks
# sd_access_ticks: how long (mtime ticks) a read command sleeps before it
# looks for its first data token, from the last command's access time; 0:
# no sleep (sd_read.S sd_wait_first_token).
sd_access_ticks:
    .space  8
    .globl sd_capacity
# sd_capacity: the card's capacity in 512-byte blocks (its CSD), set by
# sd_init; blocks 0 .. sd_capacity - 1 exist.
sd_capacity:
    .space  8
    .balign 8
    .globl sd_stage
# sd_stage: two staging buffers of SD_STAGE_BYTES (sd_read.S): one block
# arrives in one while the other's is checked and copied out.
sd_stage:
    .space  2 * SD_STAGE_BYTES
