# sd.S: the SD card in SPI mode on SPI1: bring-up and block reads.
#
# Wiring (pins.S): SCLK pad 27, MOSI pad 28 (SPI1_D0), MISO pad 26
# (SPI1_D1), chip select pad 29 = GPIOHS7 driven here by software. SPI1 runs
# standard format, work mode 0, 8-bit frames: transmit-and-receive for
# commands, responses and tokens, receive-only with DMAC channel 1 for data
# blocks. Commands and the bytes after them go in bursts through the
# 32-entry FIFOs (sd_burst): a command's frame and the Ncr bytes its R1
# comes in are one burst, and what arrives after R1 (an R3/R7 payload, the
# busy bytes after CMD12, the gap before a data token, the token and the
# first data bytes) waits in sd_ahead for whoever reads next.
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
# Reads (sd_read_blocks): CMD17 for one block, CMD18 + CMD12 for several,
# so a run of contiguous clusters costs one command. After the command, the
# first block's data token is looked for in bursts of SD_TOKEN_BURST_BYTES;
# the data bytes after it are kept. Then each block
# comes by DMA (SPI1 receive-only, DMAC channel 1) into a staging buffer:
# its data, its CRC16 and, while more blocks follow, SD_LOOKAHEAD_BYTES of
# the stream after it. The next block's gap and token are usually there: the
# data bytes after the token are kept at the start of the other staging
# buffer and the next DMA brings the rest, so a stream of blocks runs
# without byte-by-byte polling (a longer gap is waited out byte by byte).
# While a block arrives, the CPU checks the previous block's CRC16, copies
# it to its destination and hands it to the caller's hook (fat32.S computes
# the file's CRC-32 there), then sleeps in WFI until DMAC channel 1 is done:
# the SPI clock, not the CPU, bounds the reading. After CMD12: one stuff
# byte, R1, then busy (0x00) until 0xFF.
#
# Failures end in errors.S reports (codes in errors.inc); sd_init and
# sd_read_blocks return only on success.

    .option norelax
    .include "k210.inc"
    .include "sd.inc"
    .include "errors.inc"

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
    addi    sp, sp, -48
    sd      ra, 40(sp)
    sd      s0, 32(sp)
    sd      s1, 24(sp)
    sd      s2, 16(sp)

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

    ld      s2, 16(sp)
    ld      s1, 24(sp)
    ld      s0, 32(sp)
    ld      ra, 40(sp)
    addi    sp, sp, 48
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
    addi    sp, sp, -48
    sd      ra, 40(sp)
    sd      s0, 32(sp)
    sd      s1, 24(sp)
    sd      s2, 16(sp)
    sd      s3, 8(sp)
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

9:  ld      s3, 8(sp)
    ld      s2, 16(sp)
    ld      s1, 24(sp)
    ld      s0, 32(sp)
    ld      ra, 40(sp)
    addi    sp, sp, 48
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

    .globl sd_read_blocks
# sd_read_blocks
#   What: reads a1 consecutive 512-byte blocks starting at block a0 into
#         memory at a2: CMD17 for one block, CMD18 + CMD12 for more. Each
#         block arrives by DMA in a staging buffer (two, used in turn) with
#         its CRC16 and, while more blocks follow, SD_LOOKAHEAD_BYTES more
#         bytes of the stream: the next block's token is looked for there
#         (see the file comment). A block is checked, copied to its
#         destination and handed to the hook while the next one arrives; a
#         bad block (or an error token) is read again from that block,
#         SD_READ_RETRIES times, then error 4. Each block that passed its
#         check is handed to the hook, in order, once (the hook must not
#         touch SPI1, GPIOHS7 or DMAC channel 1, and it runs with mie.MEIE
#         set: a wfi in it would wake for any external interrupt).
#   Arguments: a0 = first block number, a1 = block count (0 does nothing),
#         a2 = destination (a1 * 512 bytes; any alignment), a3 = hook or 0,
#         a4 = hook context. The hook is called as hook(a0 = the block's
#         address in memory, a1 = context) and follows the calling
#         convention.
#   Results: none (returns only when every block arrived intact).
#   Clobbers: only ABI temporaries.
sd_read_blocks:
    addi    sp, sp, -112
    sd      ra, 104(sp)
    sd      s0, 96(sp)
    sd      s1, 88(sp)
    sd      s2, 80(sp)
    sd      s3, 72(sp)
    sd      s4, 64(sp)
    sd      s5, 56(sp)
    sd      s6, 48(sp)
    sd      s7, 40(sp)
    sd      s8, 32(sp)
    sd      s9, 24(sp)
    sd      s10, 16(sp)
    sd      s11, 8(sp)
    mv      s0, a0                      # s0 = next block to receive
    mv      s1, a1                      # s1 = blocks left to receive
    mv      s2, a2                      # s2 = where block s0 goes
    mv      s6, a3                      # s6 = hook
    mv      s10, a4                     # s10 = hook context
    li      s3, 0                       # s3 = failures of block s4 so far
    li      s4, -1                      # s4 = block that failed last
    la      s8, sd_stage                # s8 = staging buffer of block s0
    beqz    s1, 91f
    li      t0, MIE_MEIE                # WFI wakes for the DMA's interrupt
    csrs    mie, t0                     # throughout (dma_sleep_channel)
    # s7 = 1 while block s0 - 1 is received but not checked: it is in the
    # other staging buffer (sd_stage_other), due at s2 - 512.
    # s9 = bytes of block s0's data already at the start of s8's buffer.

10: # One read command from block s0.
    li      s7, 0
    li      s5, SD_CMD17_READ_SINGLE    # s5 = command in use
    li      t0, 1
    beq     s1, t0, 11f
    li      s5, SD_CMD18_READ_MULTIPLE
11: call    sd_select
    mv      a1, s0
    la      t0, sd_ccs
    lw      t0, 0(t0)
    bnez    t0, 12f
    slli    a1, a1, SD_BLOCK_SHIFT      # standard capacity: byte address
12: mv      a0, s5
    call    sd_command
    bnez    a0, 14f
    call    sd_receive_setup
    j       15f
14: mv      s9, a0
    call    sd_deselect
    li      t0, SD_R1_NONE
    beq     s9, t0, 13f
    andi    t0, s9, SD_R1_CRC_ERROR
    bnez    t0, 60f                     # the card saw a bad command CRC: again
13: mv      a0, s5
    mv      a1, s9
    call    sd_fail_r1

15: # Block s0's token (SPI1 transmit-and-receive); the data bytes that
    # came after it in its burst go to the start of s8's buffer.
    call    sd_wait_token
    li      t0, SD_TOKEN_START_BLOCK
    bne     a0, t0, 40f                 # error token
    mv      a0, s8
    call    sd_take_ahead
    mv      s9, a0

20: # Block s0 by DMA (the rest of its data, its CRC16, the lookahead while
    # more blocks follow) while the previous block is checked.
    add     a0, s8, s9
    li      a1, SD_BLOCK_BYTES + SD_CRC16_BYTES
    sub     a1, a1, s9
    li      t0, 1
    beq     s1, t0, 21f
    addi    a1, a1, SD_LOOKAHEAD_BYTES
21: call    sd_receive_start
    li      s11, 0                      # s11 = the previous block failed
    beqz    s7, 22f
    mv      a0, s8
    call    sd_stage_other
    addi    a1, s2, -SD_BLOCK_BYTES
    mv      a2, s6
    mv      a3, s10
    call    sd_check_block
    seqz    s11, a0
22: li      a0, SD_DMA_CHANNEL
    call    dma_sleep_channel
    bnez    s11, 50f
    li      s7, 1
    addi    s0, s0, 1
    addi    s2, s2, SD_BLOCK_BYTES
    addi    s1, s1, -1
    beqz    s1, 30f                     # (only CMD18 goes on with blocks left)

    # The next token: the first byte of the lookahead that is not 0xFF.
    addi    s11, s8, SD_BLOCK_BYTES + SD_CRC16_BYTES    # s11 = lookahead
    mv      a0, s8
    call    sd_stage_other
    mv      s8, a0                      # block s0 goes to the other buffer
    addi    t2, s11, SD_LOOKAHEAD_BYTES # t2 = end of the lookahead
    li      t3, SD_IDLE_BYTE
23: lbu     t0, 0(s11)
    addi    s11, s11, 1
    bne     t0, t3, 24f
    bltu    s11, t2, 23b
    call    sd_transfer_mode            # not there: wait for it byte by byte
    j       15b
24: li      t3, SD_TOKEN_START_BLOCK
    bne     t0, t3, 40f                 # error token
    sub     s9, t2, s11                 # the data bytes after the token
    mv      t1, s8
25: bgeu    s11, t2, 20b
    lbu     t0, 0(s11)
    sb      t0, 0(t1)
    addi    s11, s11, 1
    addi    t1, t1, 1
    j       25b

30: # Every block received (the last in s8's buffer): end the command,
    # check the last one.
    call    sd_transfer_mode
    li      t0, SD_CMD18_READ_MULTIPLE
    bne     s5, t0, 31f
    call    sd_stop_transmission
31: call    sd_deselect
    mv      a0, s8
    addi    a1, s2, -SD_BLOCK_BYTES
    mv      a2, s6
    mv      a3, s10
    call    sd_check_block
    bnez    a0, 90f
    j       55f

40: # Block s0 came with an error token: settle the previous one first.
    call    sd_transfer_mode
    beqz    s7, 41f
    mv      a0, s8
    call    sd_stage_other
    addi    a1, s2, -SD_BLOCK_BYTES
    mv      a2, s6
    mv      a3, s10
    call    sd_check_block
    beqz    a0, 50f
41: li      t0, SD_CMD18_READ_MULTIPLE
    bne     s5, t0, 42f
    call    sd_stop_transmission
42: call    sd_deselect
    j       60f

50: # Block s0 - 1 failed its check: end the command, back up to it.
    call    sd_transfer_mode
    li      t0, SD_CMD18_READ_MULTIPLE
    bne     s5, t0, 51f
    call    sd_stop_transmission
51: call    sd_deselect
55: addi    s0, s0, -1
    addi    s2, s2, -SD_BLOCK_BYTES
    addi    s1, s1, 1

60: # Read again from block s0, unless it has failed too often.
    beq     s0, s4, 61f
    mv      s4, s0
    li      s3, 0
61: addi    s3, s3, 1
    li      t0, SD_READ_RETRIES
    bleu    s3, t0, 10b
    li      a0, ERR_CRC
    la      a1, msg_crc_block
    mv      a2, s0
    la      a3, msg_crc_block_tail
    call    error_fatal_dec

90: li      t0, MIE_MEIE
    csrc    mie, t0
91: ld      s11, 8(sp)
    ld      s10, 16(sp)
    ld      s9, 24(sp)
    ld      s8, 32(sp)
    ld      s7, 40(sp)
    ld      s6, 48(sp)
    ld      s5, 56(sp)
    ld      s4, 64(sp)
    ld      s3, 72(sp)
    ld      s2, 80(sp)
    ld      s1, 88(sp)
    ld      s0, 96(sp)
    ld      ra, 104(sp)
    addi    sp, sp, 112
    ret

# sd_stage_other (file-local)
#   What: the staging buffer that is not a0.
#   Arguments: a0 = one of the two staging buffers.
#   Results: a0 = the other one.
#   Clobbers: only ABI temporaries.
sd_stage_other:
    la      t0, sd_stage
    bne     a0, t0, 1f
    addi    a0, t0, SD_STAGE_BYTES
    ret
1:  mv      a0, t0
    ret

# sd_check_block (file-local)
#   What: checks a block in a staging buffer against the CRC16 the card sent
#         after it (big-endian, right after the data) and, if it matches,
#         copies it to its destination and hands it to the hook there.
#   Arguments: a0 = staging buffer, a1 = destination (any alignment),
#         a2 = hook or 0, a3 = hook context.
#   Results: a0 = 1 good, 0 bad.
#   Clobbers: only ABI temporaries.
sd_check_block:
    addi    sp, sp, -48
    sd      ra, 40(sp)
    sd      s0, 32(sp)
    sd      s1, 24(sp)
    sd      s2, 16(sp)
    sd      s3, 8(sp)
    mv      s0, a0
    mv      s1, a1
    mv      s2, a2
    mv      s3, a3
    li      a1, SD_BLOCK_BYTES
    call    crc16_ccitt
    lbu     t0, SD_BLOCK_BYTES(s0)
    lbu     t1, SD_BLOCK_BYTES + 1(s0)
    slli    t0, t0, SD_BYTE_BITS
    or      t0, t0, t1                  # t0 = the CRC16 the card sent
    bne     a0, t0, 2f
    mv      a0, s1
    mv      a1, s0
    call    sd_copy_block
    beqz    s2, 1f
    mv      a0, s1
    mv      a1, s3
    jalr    s2
1:  li      a0, 1
    j       3f
2:  li      a0, 0
3:  ld      s3, 8(sp)
    ld      s2, 16(sp)
    ld      s1, 24(sp)
    ld      s0, 32(sp)
    ld      ra, 40(sp)
    addi    sp, sp, 48
    ret

# sd_copy_block (file-local)
#   What: copies 512 bytes from a staging buffer to a0: doublewords when a0
#         is 8-byte aligned, bytes otherwise.
#   Arguments: a0 = destination, a1 = staging buffer (8-byte aligned).
#   Results: none.
#   Clobbers: only ABI temporaries.
sd_copy_block:
    addi    t2, a1, SD_BLOCK_BYTES      # t2 = end of the source
    andi    t0, a0, SD_DOUBLEWORD_MASK
    bnez    t0, 2f
1:  ld      t0, 0(a1)
    sd      t0, 0(a0)
    addi    a1, a1, SD_DOUBLEWORD_BYTES
    addi    a0, a0, SD_DOUBLEWORD_BYTES
    bltu    a1, t2, 1b
    ret
2:  lbu     t0, 0(a1)
    sb      t0, 0(a0)
    addi    a1, a1, 1
    addi    a0, a0, 1
    bltu    a1, t2, 2b
    ret

# sd_wait_token (file-local)
#   What: takes received bytes (sd_ahead first, then bursts of
#         SD_TOKEN_BURST_BYTES) until one is not 0xFF (the data token, or an
#         error token), at most SD_READ_TIMEOUT_US (then error 2). The bytes
#         after the token in its burst stay in sd_ahead.
#   Arguments: none.
#   Results: a0 = the token byte.
#   Clobbers: only ABI temporaries.
sd_wait_token:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    sd      s0, 0(sp)
    li      a0, SD_READ_TIMEOUT_US
    call    timer_deadline
    mv      s0, a0
1:  call    sd_ahead_left
    bnez    a0, 3f
    li      a0, SD_TOKEN_BURST_BYTES
    call    sd_fill_ahead
3:  call    sd_take_byte
    li      t0, SD_IDLE_BYTE
    bne     a0, t0, 2f
    call    sd_ahead_left
    bnez    a0, 3b
    mv      a0, s0
    call    timer_expired
    beqz    a0, 1b
    li      a0, ERR_CARD_TIMEOUT
    la      a1, msg_token_timeout
    li      a2, 0
    call    error_fatal
2:  ld      s0, 0(sp)
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

# sd_receive_setup (file-local)
#   What: DMAC channel 1 set up for receiving from SPI1 (its configuration,
#         source, control and interrupt enables, stale interrupts cleared),
#         once per read command: sd_receive_start then gives each block only
#         its destination and length. The channel is idle (dma_wait_channel
#         saw the last block done) and nothing else uses it; the DMAC keeps
#         these registers from one block to the next.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
sd_receive_setup:
    li      t0, DMAC_BASE
    li      t1, DMAC_CH_INTCLEAR_ALL
    sd      t1, SD_DMAC_CH + DMAC_CH_INTCLEAR(t0)
1:  ld      t1, DMAC_CHEN(t0)
    andi    t1, t1, SD_DMAC_CHEN
    bnez    t1, 1b
    li      t1, SD_DMAC_CFG             # cfg before sar/dar/block_ts, as the SDK notes
    sd      t1, SD_DMAC_CH + DMAC_CH_CFG(t0)
    li      t1, SPI1_DR_ADDR
    sd      t1, SD_DMAC_CH + DMAC_CH_SAR(t0)
    li      t1, SD_DMAC_CTL
    sd      t1, SD_DMAC_CH + DMAC_CH_CTL(t0)
    li      t1, DMAC_CH_INT_BLOCK_DONE
    sd      t1, SD_DMAC_CH + DMAC_CH_INTSTATUS_EN(t0)
    sd      t1, SD_DMAC_CH + DMAC_CH_INTSIGNAL_EN(t0)
    ret

# sd_receive_start (file-local)
#   What: starts receiving a1 bytes (after a data token) into memory by
#         DMA: SPI1 receive-only for a1 frames with RX DMA requests (set up
#         only when it is not so already: SPI1 starts another a1 frames at
#         each write to its data register), DMAC channel 1 (sd_receive_setup)
#         from SPI1's data register to a0, one dummy write to start the
#         clock. Returns at once; dma_sleep_channel(SD_DMA_CHANNEL) waits for
#         the end, after which SPI1 stays receive-only until sd_transfer_mode.
#   Arguments: a0 = destination, a1 = byte count (1 .. SD_STAGE_BYTES).
#   Results: none.
#   Clobbers: only ABI temporaries.
sd_receive_start:
    addi    sp, sp, -32
    sd      ra, 24(sp)
    sd      s0, 16(sp)
    sd      s1, 8(sp)
    mv      s0, a0
    mv      s1, a1
    la      t0, sd_rx_frames
    lwu     t1, 0(t0)
    beq     t1, a1, 1f
    sw      a1, 0(t0)
    li      a0, SD_CTRLR0_RX_ONLY
    addi    a1, a1, -1                  # ctrlr1 = frames - 1
    li      a2, SPI_DMACR_RDMAE
    call    sd_spi_mode

1:  li      t0, DMAC_BASE
    sd      s0, SD_DMAC_CH + DMAC_CH_DAR(t0)
    addi    t1, s1, -1                  # block_ts = items - 1
    sd      t1, SD_DMAC_CH + DMAC_CH_BLOCK_TS(t0)
    fence   rw, o                       # earlier accesses to the buffer come first
    li      t1, SD_DMAC_CHEN | SD_DMAC_CHEN_WE
    sd      t1, DMAC_CHEN(t0)

    # One dummy write clocks ctrlr1 + 1 frames in (MOSI idles high).
    li      t0, SPI1_BASE
    li      t1, SD_IDLE_BYTE
    sw      t1, SPI_DR(t0)

    ld      s1, 8(sp)
    ld      s0, 16(sp)
    ld      ra, 24(sp)
    addi    sp, sp, 32
    ret

# sd_transfer_mode (file-local)
#   What: SPI1 back in transmit-and-receive mode, DMA requests off, for
#         exchanges (sd_burst, sd_xchg) after a DMA receive.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
sd_transfer_mode:
    la      t0, sd_rx_frames
    sw      zero, 0(t0)
    li      a0, SD_CTRLR0_TX_RX
    li      a1, 0
    li      a2, 0
    j       sd_spi_mode

# sd_stop_transmission (file-local)
#   What: ends a CMD18 stream: CMD12, skip the stuff byte, R1, then wait
#         while the card holds MISO low (busy; looked at in bursts of
#         SD_BUSY_BURST_BYTES), at most SD_BUSY_TIMEOUT_US.
#         The card stays selected.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
sd_stop_transmission:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    sd      s0, 0(sp)
    li      a0, SD_CMD12_STOP
    li      a1, 0
    call    sd_command                  # skips the stuff byte for CMD12
    li      t0, SD_R1_NONE
    bne     a0, t0, 1f
    mv      a1, a0
    li      a0, SD_CMD12_STOP
    call    sd_fail_r1
1:  li      a0, SD_BUSY_TIMEOUT_US
    call    timer_deadline
    mv      s0, a0
2:  call    sd_ahead_left
    bnez    a0, 4f
    li      a0, SD_BUSY_BURST_BYTES
    call    sd_fill_ahead
4:  call    sd_take_byte
    li      t0, SD_IDLE_BYTE
    beq     a0, t0, 3f
    call    sd_ahead_left
    bnez    a0, 4b
    mv      a0, s0
    call    timer_expired
    beqz    a0, 2b
    li      a0, ERR_CARD_TIMEOUT
    la      a1, msg_busy_timeout
    li      a2, 0
    call    error_fatal
3:  ld      s0, 0(sp)
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

# sd_cmd (file-local)
#   What: one command as its own transaction: select, command, R1 and (if
#         a2) the 4 bytes of R3/R7, deselect. A response with the CRC-error
#         bit set is sent again, up to SD_CMD_CRC_TRIES sends, then error 4.
#   Arguments: a0 = command index, a1 = argument, a2 = 1 to read 4 more
#         bytes after R1, else 0.
#   Results: a0 = R1 (SD_R1_NONE when nothing answered), a1 = the 4 bytes
#         (big-endian, as sent) or 0.
#   Clobbers: only ABI temporaries.
sd_cmd:
    addi    sp, sp, -64
    sd      ra, 56(sp)
    sd      s0, 48(sp)
    sd      s1, 40(sp)
    sd      s2, 32(sp)
    sd      s3, 24(sp)
    sd      s4, 16(sp)
    sd      s5, 8(sp)
    mv      s0, a0                      # s0 = command
    mv      s1, a1                      # s1 = argument
    mv      s2, a2                      # s2 = read R3/R7 payload
    li      s4, SD_CMD_CRC_TRIES        # s4 = sends left
1:  call    sd_select
    mv      a0, s0
    mv      a1, s1
    call    sd_command
    mv      s3, a0                      # s3 = R1
    li      s5, 0                       # s5 = payload
    beqz    s2, 2f
    li      t0, SD_R1_NONE
    beq     s3, t0, 2f
    call    sd_read_u32
    mv      s5, a0
2:  call    sd_deselect
    li      t0, SD_R1_NONE
    beq     s3, t0, 3f
    andi    t0, s3, SD_R1_CRC_ERROR
    beqz    t0, 3f
    addi    s4, s4, -1
    bnez    s4, 1b
    li      a0, ERR_CRC
    la      a1, msg_crc_cmd
    mv      a2, s0
    la      a3, msg_crc_cmd_tail
    call    error_fatal_dec
3:  mv      a0, s3
    mv      a1, s5
    ld      s5, 8(sp)
    ld      s4, 16(sp)
    ld      s3, 24(sp)
    ld      s2, 32(sp)
    ld      s1, 40(sp)
    ld      s0, 48(sp)
    ld      ra, 56(sp)
    addi    sp, sp, 64
    ret

# sd_cmd_ok (file-local)
#   What: sd_cmd for a command that must answer R1 = 0 (ready, no error
#         bits); anything else ends in sd_fail_r1's report.
#   Arguments: as sd_cmd.
#   Results: a0 = the 4 bytes after R1 (when a2 = 1), else 0.
#   Clobbers: only ABI temporaries.
sd_cmd_ok:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    sd      s0, 0(sp)
    mv      s0, a0
    call    sd_cmd
    beqz    a0, 1f
    mv      a1, a0
    mv      a0, s0
    call    sd_fail_r1
1:  mv      a0, a1
    ld      s0, 0(sp)
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

# sd_fail_r1 (file-local)
#   What: reports a command whose response is unusable: no answer at all is
#         error 2 ("card timeout: no response to CMD<n>"), an answer with
#         unexpected bits is error 3 ("unsupported card: CMD<n> R1 0x<r1>").
#   Arguments: a0 = command index, a1 = R1 (SD_R1_NONE = no answer).
#   Results: never returns.
#   Clobbers: everything.
sd_fail_r1:
    mv      s0, a0
    mv      s1, a1
    li      t0, SD_R1_NONE
    bne     s1, t0, 1f
    li      a0, ERR_CARD_TIMEOUT
    call    error_begin
    la      a0, msg_no_response
    call    console_puts
    mv      a0, s0
    call    console_put_dec
    j       error_end
1:  li      a0, ERR_UNSUPPORTED
    call    error_begin
    la      a0, msg_refused
    call    console_puts
    mv      a0, s0
    call    console_put_dec
    la      a0, msg_refused_r1
    call    console_puts
    mv      a0, s1
    li      a1, SD_R1_HEX_DIGITS
    call    console_put_hex
    j       error_end

# sd_command (file-local)
#   What: sends one command (the card is selected: sd_select) in one burst
#         with what comes before and after it: the 0xFF byte that lets the
#         card drive MISO (not for CMD12, sent in the middle of a CMD18
#         stream), the frame, for CMD12 the stuff byte, and
#         SD_NCR_BURST_BYTES of 0xFF for the response. R1 is the first byte
#         after the frame (and stuff byte) with its top bit clear, looked for
#         in SD_NCR_BYTES bytes at most (those after the burst a byte at a
#         time). The bytes after R1 stay in sd_ahead.
#   Arguments: a0 = command index, a1 = 32-bit argument.
#   Results: a0 = R1, or SD_R1_NONE when no response started.
#   Clobbers: only ABI temporaries.
sd_command:
    addi    sp, sp, -32
    sd      ra, 24(sp)
    sd      s0, 16(sp)
    sd      s1, 8(sp)
    sd      s2, 0(sp)
    mv      s2, a0
    la      s1, sd_ahead
    li      t0, SD_IDLE_BYTE
    sb      t0, 0(s1)
    # the frame: start | index, argument MSB first, CRC7 | end bit
    ori     t0, a0, SD_CMD_START
    sb      t0, SD_CMD_AT(s1)
    srli    t0, a1, 3 * SD_BYTE_BITS
    sb      t0, SD_CMD_AT + 1(s1)
    srli    t0, a1, 2 * SD_BYTE_BITS
    sb      t0, SD_CMD_AT + 2(s1)
    srli    t0, a1, SD_BYTE_BITS
    sb      t0, SD_CMD_AT + 3(s1)
    sb      a1, SD_CMD_AT + 4(s1)
    addi    a0, s1, SD_CMD_AT
    li      a1, SD_CMD_CRC_BYTES
    call    crc7_sd
    sb      a0, SD_CMD_AT + SD_CMD_CRC_BYTES(s1)
    li      s0, SD_CMD_AT + SD_CMD_FRAME_BYTES    # s0 = where the response starts
    mv      a0, s1                      # a0 = where the burst starts
    li      t0, SD_CMD12_STOP
    bne     s2, t0, 1f
    addi    s0, s0, 1                   # after the stuff byte
    addi    a0, s1, SD_CMD_AT           # no byte before the frame
1:  add     t0, s1, s0                  # the response bytes: 0xFF out
    addi    t1, t0, SD_NCR_BURST_BYTES
    li      t2, SD_IDLE_BYTE
2:  sb      t2, 0(t0)
    addi    t0, t0, 1
    bltu    t0, t1, 2b
    sub     a1, t1, a0
    call    sd_burst
    la      t0, sd_ahead_next
    sw      s0, 0(t0)
    addi    t1, s0, SD_NCR_BURST_BYTES
    sw      t1, SD_AHEAD_END_AT(t0)

    li      s0, SD_NCR_BYTES
3:  call    sd_take_byte
    andi    t0, a0, SD_R1_START_MASK
    beqz    t0, 4f
    addi    s0, s0, -1
    bnez    s0, 3b
    li      a0, SD_R1_NONE
4:  ld      s2, 0(sp)
    ld      s1, 8(sp)
    ld      s0, 16(sp)
    ld      ra, 24(sp)
    addi    sp, sp, 32
    ret

# sd_read_u32 (file-local)
#   What: the next 4 received bytes (sd_receive_bytes), most significant
#         first (R3 / R7 payload).
#   Arguments: none.
#   Results: a0 = the 32-bit value.
#   Clobbers: only ABI temporaries.
sd_read_u32:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    mv      a0, sp
    li      a1, SD_R3_PAYLOAD_BYTES
    call    sd_receive_bytes
    li      a0, 0
    mv      t0, sp
    addi    t1, sp, SD_R3_PAYLOAD_BYTES
1:  lbu     t2, 0(t0)
    slli    a0, a0, SD_BYTE_BITS
    or      a0, a0, t2
    addi    t0, t0, 1
    bltu    t0, t1, 1b
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

# sd_select (file-local)
#   What: chip select low. The 0xFF byte that lets the card drive MISO
#         before a command goes out with the command (sd_command).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
sd_select:
    li      a0, GPIOHS_SD_CS_BIT
    j       gpiohs_clear

# sd_deselect (file-local)
#   What: chip select high, then one 0xFF byte (8 clocks) so the card
#         releases MISO; received bytes not taken are dropped. No byte is
#         on the wire when CS changes: sd_burst and sd_xchg return only
#         after their bytes have come back.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
sd_deselect:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    call    sd_drop_ahead
    li      a0, GPIOHS_SD_CS_BIT
    call    gpiohs_set
    li      a0, SD_IDLE_BYTE
    call    sd_xchg
    ld      ra, 8(sp)
    addi    sp, sp, 16
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

# sd_burst (file-local)
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

# sd_fill_ahead (file-local)
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

# sd_ahead_left (file-local)
#   What: how many received bytes wait in sd_ahead.
#   Arguments: none. Results: a0 = count.
#   Clobbers: only ABI temporaries.
sd_ahead_left:
    la      t0, sd_ahead_next
    lw      a0, SD_AHEAD_END_AT(t0)
    lw      t1, 0(t0)
    sub     a0, a0, t1
    ret

# sd_drop_ahead (file-local)
#   What: forgets the received bytes waiting in sd_ahead.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
sd_drop_ahead:
    la      t0, sd_ahead_next
    sw      zero, 0(t0)
    sw      zero, SD_AHEAD_END_AT(t0)
    ret

# sd_take_byte (file-local)
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

# sd_take_ahead (file-local)
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

# sd_receive_bytes (file-local)
#   What: the next a1 received bytes to a0: those waiting in sd_ahead, then
#         bursts of at most SD_AHEAD_BYTES.
#   Arguments: a0 = destination, a1 = count.
#   Results: none.
#   Clobbers: only ABI temporaries.
sd_receive_bytes:
    addi    sp, sp, -32
    sd      ra, 24(sp)
    sd      s0, 16(sp)
    sd      s1, 8(sp)
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
3:  ld      s1, 8(sp)
    ld      s0, 16(sp)
    ld      ra, 24(sp)
    addi    sp, sp, 32
    ret

# sd_spi_setup (file-local)
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

# sd_spi_mode (file-local)
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

# sd_delay_us (file-local)
#   What: delay_us at the CPU clock in force (cpu_hz).
#   Arguments: a0 = microseconds. Results: none.
#   Clobbers: only ABI temporaries.
sd_delay_us:
    la      t0, cpu_hz
    lwu     a1, 0(t0)
    j       delay_us

# ---------------------------------------------------------------------------
    .section .rodata
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
msg_token_timeout:  .asciz "card timeout: no data token"
msg_busy_timeout:   .asciz "card timeout: busy after CMD12"
msg_no_response:    .asciz "card timeout: no response to CMD"
msg_refused:        .asciz "unsupported card: CMD"
msg_refused_r1:     .asciz " answered R1 0x"
msg_crc_block:      .asciz "CRC errors: block "
msg_crc_block_tail: .asciz " stays bad after retries"
msg_crc_cmd:        .asciz "CRC errors: CMD"
msg_crc_csd:        .asciz "CRC errors: the CSD (CMD9) stays bad after retries"
msg_csd_version:    .asciz "unsupported card: CSD_STRUCTURE "
msg_csd_version_tail: .asciz " (known: 0 and 1, CSD versions 1.0 and 2.0)"
msg_crc_cmd_tail:   .asciz " response keeps reporting a CRC error"

# ---------------------------------------------------------------------------
    .bss
    .balign 4
# sd_ccs: 1 = block-addressed card (SDHC/SDXC), 0 = byte-addressed (SDSC).
sd_ccs:
    .space  4
# sd_rx_frames: the frames SPI1's receive-only mode is set up for (its
# ctrlr1 + 1), 0 when SPI1 is in transmit-and-receive mode.
sd_rx_frames:
    .space  4
# sd_ahead_next, sd_ahead_end: the received bytes not yet taken are
# sd_ahead[sd_ahead_next .. sd_ahead_end).
sd_ahead_next:
    .space  4
sd_ahead_end:
    .space  4
    .if sd_ahead_end - sd_ahead_next != SD_AHEAD_END_AT
    .error "SD_AHEAD_END_AT does not match the layout of sd_ahead_next"
    .endif
# sd_ahead: the last burst (sd_burst), command and bytes received.
sd_ahead:
    .space  SD_AHEAD_BYTES
    .balign 8
    .globl sd_capacity
# sd_capacity: the card's capacity in 512-byte blocks (its CSD), set by
# sd_init; blocks 0 .. sd_capacity - 1 exist.
sd_capacity:
    .space  8
    .balign 8
# sd_stage: two staging buffers of SD_STAGE_BYTES (sd_read_blocks): one block
# arrives in one while the other's is checked and copied out.
sd_stage:
    .space  2 * SD_STAGE_BYTES
