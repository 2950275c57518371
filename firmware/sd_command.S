# sd_command.S: one SD command and its response. sd_command sends a frame
# (start bit, index, argument, CRC7 from crc.S) in one burst with the bytes
# the response comes in, and finds R1 among them; sd_cmd makes a command its
# own transaction (select, command, R1, the R3 / R7 payload, deselect) and
# sends it again while the card reports a CRC error; sd_fail_r1 reports a
# response the caller cannot use. Bytes go through sd_spi.S; the messages
# and sd_ahead are sd.S's.

    .option norelax
    .include "k210.inc"
    .include "sd.inc"
    .include "errors.inc"
    .include "frame.inc"

    .text
    .globl sd_cmd
# sd_cmd
#   What: one command as its own transaction: select, command, R1 and (if
#         a2) the 4 bytes of R3/R7, deselect. A response with the CRC-error
#         bit set is sent again, up to SD_CMD_CRC_TRIES sends, then error 4.
#   Arguments: a0 = command index, a1 = argument, a2 = 1 to read 4 more
#         bytes after R1, else 0.
#   Results: a0 = R1 (SD_R1_NONE when nothing answered), a1 = the 4 bytes
#         (big-endian, as sent) or 0.
#   Clobbers: only ABI temporaries.
sd_cmd:
    FRAME_SAVE 64, ra, s0, s1, s2, s3, s4, s5
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
    FRAME_RESTORE 64, ra, s0, s1, s2, s3, s4, s5
    ret

    .globl sd_cmd_ok
# sd_cmd_ok
#   What: sd_cmd for a command that must answer R1 = 0 (ready, no error
#         bits); anything else ends in sd_fail_r1's report.
#   Arguments: as sd_cmd.
#   Results: a0 = the 4 bytes after R1 (when a2 = 1), else 0.
#   Clobbers: only ABI temporaries.
sd_cmd_ok:
    FRAME_SAVE 16, ra, s0
    mv      s0, a0
    call    sd_cmd
    beqz    a0, 1f
    mv      a1, a0
    mv      a0, s0
    call    sd_fail_r1
1:  mv      a0, a1
    FRAME_RESTORE 16, ra, s0
    ret

    .globl sd_fail_r1
# sd_fail_r1
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

    .globl sd_command
# sd_command
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
    FRAME_SAVE 32, ra, s0, s1, s2
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
4:  FRAME_RESTORE 32, ra, s0, s1, s2
    ret

# sd_read_u32 (file-local)
#   What: the next 4 received bytes (sd_receive_bytes), most significant
#         first (R3 / R7 payload).
#   Arguments: none.
#   Results: a0 = the 32-bit value.
#   Clobbers: only ABI temporaries.
sd_read_u32:
    FRAME_SAVE 16, ra
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
    FRAME_RESTORE 16, ra
    ret
