# sd_read.S: reading blocks from the card (sd_read_blocks): CMD17 for one
# block, CMD18 + CMD12 for several, so a run of contiguous clusters costs
# one command.
#
# After the command, the CPU sleeps through most of the card's access time
# (as long as the last command's took: sd_wait_first_token), then the first
# block's data token is looked for in bursts of SD_TOKEN_BURST_BYTES; the
# data bytes after it are kept. Then each block
# comes by DMA (SPI1 receive-only, DMAC channel 1) into a staging buffer
# (sd.S sd_stage): its data, its CRC16 and, while more blocks follow,
# SD_LOOKAHEAD_BYTES of the stream after it. The next block's gap and token
# are usually there: the data bytes after the token are kept at the start of
# the other staging buffer and the next DMA brings the rest, so a stream of
# blocks runs without byte-by-byte polling (a longer gap is waited out byte
# by byte). While a block arrives, the CPU checks the previous block's
# CRC16, copies it to its destination and hands it to the caller's hook
# (fat32_read.S computes the file's CRC-32 there), then sleeps in WFI until
# DMAC channel 1 is done: the SPI clock, not the CPU, bounds the reading.
# After CMD12: one stuff byte, R1, then busy (0x00) until 0xFF.
#
# Commands go through sd_command.S, bytes through sd_spi.S; the messages
# and the staging buffers are sd.S's.

    .option norelax
    .include "k210.inc"
    .include "sd.inc"
    .include "errors.inc"
    .include "frame.inc"

# C_J target
#   A 2-byte c.j to a symbol in another file (sd_transfer_mode's tail jump to
#   sd_spi.S sd_spi_mode): the jump the assembler chose while both were in
#   one file, so every address stays where the cycle counts were measured.
#   The assembler widens a c.j or .insn to a symbol it cannot resolve into a
#   4-byte jal, so the instruction is spelled out with its relocation; the
#   linker reports a target beyond c.j's 2 KiB reach.
.macro C_J target
    .reloc  ., R_RISCV_RVC_JUMP, \target
    .2byte  SD_C_J_ZERO_OFFSET
.endm

    .text
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
    FRAME_SAVE 112, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11
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
    call    sd_wait_first_token
    j       16f
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
16: li      t0, SD_TOKEN_START_BLOCK
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
91: FRAME_RESTORE 112, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11
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
    FRAME_SAVE 48, ra, s0, s1, s2, s3
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
3:  FRAME_RESTORE 48, ra, s0, s1, s2, s3
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

    .globl sd_wait_token
# sd_wait_token
#   What: takes received bytes (sd_ahead first, then bursts of
#         SD_TOKEN_BURST_BYTES) until one is not 0xFF (the data token, or an
#         error token), at most SD_READ_TIMEOUT_US (then error 2). The bytes
#         after the token in its burst stay in sd_ahead.
#   Arguments: none.
#   Results: a0 = the token byte.
#   Clobbers: only ABI temporaries.
sd_wait_token:
    FRAME_SAVE 16, ra, s0
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
2:  FRAME_RESTORE 16, ra, s0
    ret

# sd_wait_first_token (file-local)
#   What: sd_wait_token for a read command's first block, after sleeping in
#         WFI for sd_access_ticks; then keeps the next command's sleep there
#         (see sd.inc): 3/4 of this one's access time (from the call, the
#         sleep included, to the token), or 0 when the token came within
#         SD_ACCESS_SLEEP_MIN_US of the end of a sleep at least
#         2^SD_ACCESS_RECHECK_SHIFT times that long (the card was ready
#         sooner: measure again) or 3/4 is shorter than
#         SD_ACCESS_SLEEP_MIN_US. The token's
#         timeout starts after the sleep.
#   Arguments: none.
#   Results: a0 = the token byte.
#   Clobbers: only ABI temporaries; after a sleep, this hart's mtimecmp is
#         all ones and mie.MTIE clear (delay_until).
sd_wait_first_token:
    FRAME_SAVE 32, ra, s0, s1, s2
    li      t0, CLINT_MTIME
    ld      s0, 0(t0)                   # s0 = mtime at the call
    li      s1, 0                       # s1 = mtime at the sleep's end, 0: none
    la      t0, sd_access_ticks
    ld      t1, 0(t0)
    beqz    t1, 1f
    add     a0, s0, t1
    call    delay_until
    li      t0, CLINT_MTIME
    ld      s1, 0(t0)
1:  call    sd_wait_token
    li      t0, CLINT_MTIME
    ld      t5, 0(t0)                   # t5 = mtime at the token (timer_ticks leaves it)
    mv      s2, a0                      # s2 = the token
    li      a0, SD_ACCESS_SLEEP_MIN_US
    call    timer_ticks
    mv      t2, a0                      # t2 = the shortest sleep, in ticks
    mv      a0, s2
    mv      t1, t5
    li      t4, 0                       # t4 = the next sleep
    beqz    s1, 2f
    sub     t3, s1, s0                  # t3 = the sleep
    slli    t5, t2, SD_ACCESS_RECHECK_SHIFT
    bltu    t3, t5, 2f
    sub     t3, t1, s1
    bltu    t3, t2, 3f                  # the token came at once after a long sleep
2:  sub     t3, t1, s0                  # t3 = the access time, in ticks
    li      t5, SD_ACCESS_WAIT_NUM
    mul     t3, t3, t5
    srli    t3, t3, SD_ACCESS_WAIT_SHIFT
    bltu    t3, t2, 3f
    mv      t4, t3
3:  la      t0, sd_access_ticks
    sd      t4, 0(t0)
    FRAME_RESTORE 32, ra, s0, s1, s2
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
    FRAME_SAVE 32, ra, s0, s1
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

    FRAME_RESTORE 32, ra, s0, s1
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
    C_J     sd_spi_mode                 # in sd_spi.S: 2 bytes, as ever

# sd_stop_transmission (file-local)
#   What: ends a CMD18 stream: CMD12, skip the stuff byte, R1, then wait
#         while the card holds MISO low (busy; looked at in bursts of
#         SD_BUSY_BURST_BYTES), at most SD_BUSY_TIMEOUT_US.
#         The card stays selected.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
sd_stop_transmission:
    FRAME_SAVE 16, ra, s0
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
3:  FRAME_RESTORE 16, ra, s0
    ret
