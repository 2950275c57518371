# errors.S: fatal error reports (codes, words and colours in errors.inc).
#
# A report is one console line, "error <code> <words>[<detail>]\n", taken
# as one locked line; then the screen is filled with the code's colour and
# the hart parks for good. The board model treats a line starting with
# "error <code> " as the firmware's fatal error report.
#
# Fatal errors are raised on hart 0 during the boot-time loading, after
# hart 1 was released to bring the LCD up and own SPI0 (main.S): the colour is
# stored for lcd_error_screen and hart 1 is asked to paint it, as trap.S does
# for a trap; hart 1 does so once lcd_init has finished. Before the release
# (no error is raised there today) hart 0 would paint the screen itself.
#
# Callers build a report with error_begin, console_puts / console_put_dec /
# console_put_hex, and error_end; error_fatal, error_fatal_dec and
# error_fatal_hex do that for the common shapes. None of them return.

    .option norelax
    .include "k210.inc"
    .include "errors.inc"
    .include "frame.inc"

    .section .rodata
    .balign 2
# error_colours: RGB565 screen colour per code (index 0 unused).
error_colours:
    .hword  0
    .hword  ERR_COLOUR_NO_CARD, ERR_COLOUR_CARD_TIMEOUT, ERR_COLOUR_UNSUPPORTED
    .hword  ERR_COLOUR_CRC, ERR_COLOUR_NO_FAT32, ERR_COLOUR_NOT_FOUND
    .hword  ERR_COLOUR_TOO_LARGE, ERR_COLOUR_BAD_CHAIN, ERR_COLOUR_BAD_SCENE
    .hword  ERR_COLOUR_BAD_MODEL, ERR_COLOUR_BAD_TEXTURE, ERR_COLOUR_MODEL_TOO_LARGE
error_colours_end:
    .if (error_colours_end - error_colours) != 2 * ERR_CODE_COUNT
    .error "error_colours needs one colour per code"
    .endif

msg_error:      .asciz "error "
msg_hex_prefix: .asciz "0x"

    .text
    .globl error_begin
# error_begin
#   What: starts a fatal error report: takes the console (ending a line this
#         hart had left half-printed) and prints "error <code> ". The caller
#         prints the words and detail, then calls error_end.
#   Arguments: a0 = error code (1 .. ERR_CODE_COUNT - 1).
#   Results: none.
#   Clobbers: only ABI temporaries.
error_begin:
    FRAME_SAVE 16, ra, s0
    mv      s0, a0
    la      t0, error_code
    sw      a0, 0(t0)
    csrr    t1, mhartid
    addi    t1, t1, 1
    la      t0, console_owner
    lw      t0, 0(t0)
    bne     t0, t1, 1f
    li      a0, '\n'                    # this hart holds the console mid-line
    call    console_putc
    j       2f
1:  call    console_lock
2:  la      a0, msg_error
    call    console_puts
    mv      a0, s0
    call    console_put_dec
    li      a0, ' '
    call    console_putc
    FRAME_RESTORE 16, ra, s0
    ret

    .globl error_end
# error_end
#   What: ends the report error_begin started: newline, console released,
#         the screen filled with the code's colour (by this hart before
#         hart 1's release, else by hart 1 on request), then parks.
#   Arguments: none. Results: never returns.
#   Clobbers: everything (the hart stops).
error_end:
    li      a0, '\n'
    call    console_putc
    call    console_relay_stop          # the report is out before this hart parks
    call    console_unlock

    la      t0, error_code
    lwu     t0, 0(t0)
    li      t1, ERR_CODE_COUNT
    bltu    t0, t1, 1f
    li      t0, 0                       # out of range: index 0, black
1:  slli    t0, t0, 1
    la      t1, error_colours
    add     t1, t1, t0
    lhu     t1, 0(t1)
    la      t0, lcd_error_colour
    sw      t1, 0(t0)
    fence   rw, w

    la      t0, boot_release
    lw      t0, 0(t0)
    li      t1, BOOT_RELEASE_MAGIC
    beq     t0, t1, 2f
    call    lcd_error_screen
    j       trap_park

    # Hart 1 owns SPI0: stop both loops; hart 1 paints on its way out.
2:  la      t0, halt_request
    li      t1, 1
    amoswap.w.rl zero, t1, (t0)
    fence
    csrr    t0, mhartid
    xori    t0, t0, OTHER_HART_XOR
    slli    t0, t0, CLINT_MSIP_SHIFT
    li      t1, CLINT_MSIP
    add     t0, t0, t1
    li      t1, CLINT_MSIP_RAISE
    sw      t1, 0(t0)
    j       trap_park

    .globl error_fatal
# error_fatal
#   What: reports "error <code> <words><detail>" and stops (see error_end).
#   Arguments: a0 = code, a1 = words (string), a2 = detail string or 0.
#   Results: never returns.
#   Clobbers: everything.
error_fatal:
    mv      s0, a1
    mv      s1, a2
    call    error_begin
    mv      a0, s0
    call    console_puts
    beqz    s1, 1f
    mv      a0, s1
    call    console_puts
1:  j       error_end

    .globl error_fatal_dec
# error_fatal_dec
#   What: reports "error <code> <words><value in decimal><tail>" and stops.
#   Arguments: a0 = code, a1 = words, a2 = value, a3 = tail string or 0.
#   Results: never returns.
#   Clobbers: everything.
error_fatal_dec:
    mv      s0, a1
    mv      s1, a2
    mv      s2, a3
    call    error_begin
    mv      a0, s0
    call    console_puts
    mv      a0, s1
    call    console_put_dec
    beqz    s2, 1f
    mv      a0, s2
    call    console_puts
1:  j       error_end

    .globl error_fatal_hex
# error_fatal_hex
#   What: reports "error <code> <words>0x<value in a3 hex digits>" and stops.
#   Arguments: a0 = code, a1 = words, a2 = value, a3 = digits (1 .. 16).
#   Results: never returns.
#   Clobbers: everything.
error_fatal_hex:
    mv      s0, a1
    mv      s1, a2
    mv      s2, a3
    call    error_begin
    mv      a0, s0
    call    console_puts
    la      a0, msg_hex_prefix
    call    console_puts
    mv      a0, s1
    mv      a1, s2
    call    console_put_hex
    j       error_end

# ---------------------------------------------------------------------------
    .bss
    .balign 4
# error_code: the code of the report in progress (for error_end's colour).
error_code:
    .space  4
