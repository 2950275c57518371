# console.S: text output on UARTHS (115200 8N1 to the Dock's USB serial).
#
# Lines end in "\n" only. Both harts print, so whole lines are bracketed by
# console_lock / console_unlock; the lock word records the owner (hart id + 1)
# so the trap handler can tell a trap inside this hart's own console output
# from the other hart printing.

    .option norelax
    .include "k210.inc"

    .text
    .globl console_init
# console_init
#   What: sets UARTHS to 115200 baud from the given core clock and enables
#         the transmitter; marks the console ready.
#   Arguments: a0 = CPU clock in Hz.
#   Results: none.
#   Clobbers: only ABI temporaries.
console_init:
    li      t0, UARTHS_BASE
    li      t1, UARTHS_BAUD
    divu    t1, a0, t1
    addi    t1, t1, -1                  # baud = clk / (div + 1)
    sw      t1, UARTHS_DIV(t0)
    li      t1, UARTHS_TXCTRL_TXEN
    sw      t1, UARTHS_TXCTRL(t0)
    la      t0, console_ready
    li      t1, 1
    sw      t1, 0(t0)
    ret

    .globl console_putc
# console_putc
#   What: sends one byte, waiting while the TX FIFO is full.
#   Arguments: a0 = byte.
#   Results: none.
#   Clobbers: only ABI temporaries.
console_putc:
    li      t0, UARTHS_BASE
1:  lw      t1, UARTHS_TXDATA(t0)
    bltz    t1, 1b                      # bit 31 (sign) = FIFO full
    sw      a0, UARTHS_TXDATA(t0)
    ret

    .globl console_puts
# console_puts
#   What: sends a NUL-terminated string.
#   Arguments: a0 = string address.
#   Results: none.
#   Clobbers: only ABI temporaries.
console_puts:
    li      t0, UARTHS_BASE
1:  lbu     t2, 0(a0)
    beqz    t2, 3f
2:  lw      t1, UARTHS_TXDATA(t0)
    bltz    t1, 2b
    sw      t2, UARTHS_TXDATA(t0)
    addi    a0, a0, 1
    j       1b
3:  ret

    .globl console_put_hex64
# console_put_hex64
#   What: sends a0 as 16 hexadecimal digits (lower case, no prefix), so that
#         addresses and CSRs always line up.
#   Arguments: a0 = value.
#   Results: none.
#   Clobbers: only ABI temporaries.
console_put_hex64:
    li      a1, 16
    j       console_put_hex

    .globl console_put_hex32
# console_put_hex32
#   What: sends the low 32 bits of a0 as 8 hexadecimal digits (lower case, no
#         prefix), e.g. CRC-32 values.
#   Arguments: a0 = value.
#   Results: none.
#   Clobbers: only ABI temporaries.
console_put_hex32:
    li      a1, 8
    j       console_put_hex

    .globl console_put_hex
# console_put_hex
#   What: sends the low a1 nibbles of a0 as hexadecimal digits, most
#         significant first (lower case, no prefix, leading zeros kept).
#   Arguments: a0 = value, a1 = number of digits (1 .. 16).
#   Results: none.
#   Clobbers: only ABI temporaries.
console_put_hex:
    addi    sp, sp, -32
    sd      ra, 24(sp)
    sd      s0, 16(sp)
    sd      s1, 8(sp)
    mv      s0, a0
    slli    s1, a1, 2                   # s1 = bit position above the next digit
1:  addi    s1, s1, -4
    srl     t0, s0, s1
    andi    t0, t0, 0xF
    la      t1, hex_digits
    add     t1, t1, t0
    lbu     a0, 0(t1)
    call    console_putc
    bnez    s1, 1b
    ld      s1, 8(sp)
    ld      s0, 16(sp)
    ld      ra, 24(sp)
    addi    sp, sp, 32
    ret

    .globl console_put_dec
# console_put_dec
#   What: sends a0 as an unsigned decimal number without leading zeros.
#   Arguments: a0 = value.
#   Results: none.
#   Clobbers: only ABI temporaries.
    .equ DEC_DIGITS_MAX, 20             # 2^64 - 1 has 20 digits
console_put_dec:
    addi    sp, sp, -48
    sd      ra, 40(sp)
    sd      s0, 32(sp)
    # Digits come out least significant first: build them backwards in a
    # buffer on the stack, then print the buffer forwards.
    addi    s0, sp, DEC_DIGITS_MAX
    sb      zero, 0(s0)
    li      t1, 10
1:  remu    t0, a0, t1
    divu    a0, a0, t1
    addi    t0, t0, '0'
    addi    s0, s0, -1
    sb      t0, 0(s0)
    bnez    a0, 1b
    mv      a0, s0
    call    console_puts
    ld      s0, 32(sp)
    ld      ra, 40(sp)
    addi    sp, sp, 48
    ret

    .globl console_lock
# console_lock
#   What: takes the console for this hart (spins: lines are short).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
console_lock:
    csrr    t1, mhartid
    addi    t1, t1, 1
    la      t0, console_owner
1:  lr.w.aq t2, (t0)
    bnez    t2, 1b
    sc.w    t2, t1, (t0)
    bnez    t2, 1b
    ret

    .globl console_unlock
# console_unlock
#   What: gives the console back (release: the other hart's text follows ours).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
console_unlock:
    la      t0, console_owner
    amoswap.w.rl zero, zero, (t0)
    ret

    .globl console_line_dec
# console_line_dec
#   What: prints "<prefix><decimal value>\n" as one locked line.
#   Arguments: a0 = prefix string, a1 = value.
#   Results: none.
#   Clobbers: only ABI temporaries.
console_line_dec:
    addi    sp, sp, -32
    sd      ra, 24(sp)
    sd      s0, 16(sp)
    sd      s1, 8(sp)
    mv      s0, a0
    mv      s1, a1
    call    console_lock
    mv      a0, s0
    call    console_puts
    mv      a0, s1
    call    console_put_dec
    li      a0, '\n'
    call    console_putc
    call    console_unlock
    ld      s1, 8(sp)
    ld      s0, 16(sp)
    ld      ra, 24(sp)
    addi    sp, sp, 32
    ret

    .globl console_line
# console_line
#   What: prints a string (which carries its own "\n") as one locked line.
#   Arguments: a0 = string. Results: none.
#   Clobbers: only ABI temporaries.
console_line:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    sd      s0, 0(sp)
    mv      s0, a0
    call    console_lock
    mv      a0, s0
    call    console_puts
    call    console_unlock
    ld      s0, 0(sp)
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

# ---------------------------------------------------------------------------
    .section .rodata
hex_digits:
    .ascii  "0123456789abcdef"

# In .data, not .bss: the trap handler may read them on hart 1 before hart 0
# has cleared .bss, and hart 0's clearing must not wipe a held lock.
    .data
    .balign 4
    .globl console_ready
# console_ready: 1 once console_init has run (the trap handler inits otherwise).
console_ready:
    .word   0
    .globl console_owner
# console_owner: 0 = free, else hart id + 1 of the hart printing a line.
console_owner:
    .word   0
