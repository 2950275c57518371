# console.S: text output on UARTHS (115200 8N1 to the Dock's USB serial).
#
# Lines end in "\n" only. Both harts print, so whole lines are bracketed by
# console_lock / console_unlock; the lock word records the owner (hart id + 1)
# so the trap handler can tell a trap inside this hart's own console output
# from the other hart printing.
#
# The relay. At 115200 baud a line costs 2-7 ms of waiting on the UART, and
# hart 0 prints about 450 bytes while it loads the card, 39 ms in all. So
# during start-up (console_relay_start .. console_relay_stop) what any hart
# prints goes into console_ring, and hart 1, which meanwhile sleeps through the
# LCD's waits, copies it to the UART (console_wait_us); during those waits
# and once the LCD is up (console_relay_until, until frame 0 is ready) it
# sleeps until hart 0 puts a byte into the empty ring, which raises hart 1's
# software interrupt, and looks again every CONSOLE_RELAY_POLL_US only while
# bytes wait for room in the UART's FIFO. The ring is only ever
# touched with the console lock held, and whoever holds the lock may move
# bytes from it to the UART: a hart that finds it full sends its oldest byte
# itself. When the relay stops (hart 1's LCD is up, or a fatal error or a trap
# is being reported: that report must not depend on the other hart), the
# ring is emptied first, so bytes reach the UART in the order they were
# printed, and printing goes straight to the UART again.

    .option norelax
    .include "k210.inc"
    .include "frame.inc"

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
#   What: prints one byte: into the ring while the relay runs (sending the
#         ring's oldest byte first when it is full), else to the UART after
#         whatever the ring still holds, waiting while the TX FIFO is full.
#         The caller holds the console lock (or is alone: early boot, traps).
#   Arguments: a0 = byte.
#   Results: none.
#   Clobbers: only ABI temporaries.
console_putc:
    la      t0, console_relay
    lw      t0, 0(t0)
    bnez    t0, 5f
    la      t0, console_ring_head
    lw      t1, 0(t0)
    la      t0, console_ring_tail
    lw      t2, 0(t0)
    bne     t1, t2, 4f                  # the ring's bytes go first
3:  li      t0, UARTHS_BASE
1:  lw      t1, UARTHS_TXDATA(t0)
    bltz    t1, 1b                      # bit 31 (sign) = FIFO full
    sw      a0, UARTHS_TXDATA(t0)
    ret
4:  FRAME_SAVE 16, ra
    sd      a0, 0(sp)
    call    console_drain
    ld      a0, 0(sp)
    FRAME_RESTORE 16, ra
    j       3b

    # Relayed: append at head (indices run freely; full at RING_BYTES apart).
5:  la      t0, console_ring_head
    lw      t1, 0(t0)
    la      t2, console_ring_tail
    lw      t2, 0(t2)
    subw    t5, t1, t2                  # t5 = bytes held (the indices wrap at 2^32)
    li      t4, CONSOLE_RING_BYTES
    bltu    t5, t4, 6f
    FRAME_SAVE 16, ra
    sd      a0, 0(sp)
    call    console_send_oldest
    ld      a0, 0(sp)
    FRAME_RESTORE 16, ra
    j       5b
6:  andi    t3, t1, CONSOLE_RING_MASK
    la      t2, console_ring
    add     t2, t2, t3
    sb      a0, 0(t2)
    addiw   t1, t1, 1
    sw      t1, 0(t0)
    # The first byte in an empty ring wakes the relaying hart if it sleeps
    # in console_wait_us or console_relay_until (its software interrupt; it
    # clears it itself).
    bnez    t5, 7f
    srli    t3, tp, HART_LOCAL_SHIFT    # mhartid (boot.S)
    li      t4, CONSOLE_RELAY_HART
    beq     t3, t4, 7f
    fence   w, o                        # the byte is in the ring before the signal
    li      t0, CLINT_MSIP + (CONSOLE_RELAY_HART << CLINT_MSIP_SHIFT)
    li      t1, CLINT_MSIP_RAISE
    sw      t1, 0(t0)
7:  ret

    .globl console_puts
# console_puts
#   What: prints a NUL-terminated string (console_putc for each byte).
#   Arguments: a0 = string address.
#   Results: none.
#   Clobbers: only ABI temporaries.
console_puts:
    FRAME_SAVE 16, ra, s0
    mv      s0, a0
1:  lbu     a0, 0(s0)
    beqz    a0, 2f
    call    console_putc
    addi    s0, s0, 1
    j       1b
2:  FRAME_RESTORE 16, ra, s0
    ret

# console_send_oldest (file-local)
#   What: sends the ring's oldest byte to the UART, waiting while the TX FIFO
#         is full. The caller holds the console lock and the ring is not
#         empty.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
console_send_oldest:
    la      t0, console_ring_tail
    lw      t1, 0(t0)
    andi    t2, t1, CONSOLE_RING_MASK
    la      t3, console_ring
    add     t3, t3, t2
    lbu     t3, 0(t3)
    li      t4, UARTHS_BASE
1:  lw      t2, UARTHS_TXDATA(t4)
    bltz    t2, 1b
    sw      t3, UARTHS_TXDATA(t4)
    addiw   t1, t1, 1
    sw      t1, 0(t0)
    ret

# console_drain (file-local)
#   What: sends everything the ring holds to the UART, waiting on the TX
#         FIFO. The caller holds the console lock.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
console_drain:
    FRAME_SAVE 16, ra
1:  la      t0, console_ring_head
    lw      t1, 0(t0)
    la      t0, console_ring_tail
    lw      t2, 0(t0)
    beq     t1, t2, 2f
    call    console_send_oldest
    j       1b
2:  FRAME_RESTORE 16, ra
    ret

# console_pump (file-local)
#   What: moves bytes from the ring into the UART's TX FIFO while both have
#         some: never waits. The caller holds the console lock.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
console_pump:
    la      t0, console_ring_tail
    lw      t1, 0(t0)
    la      t2, console_ring_head
    lw      t2, 0(t2)
    li      t3, UARTHS_BASE
    la      t4, console_ring
1:  beq     t1, t2, 2f
    lw      t5, UARTHS_TXDATA(t3)
    bltz    t5, 2f                      # FIFO full: the rest waits
    andi    t5, t1, CONSOLE_RING_MASK
    add     t5, t5, t4
    lbu     t5, 0(t5)
    sw      t5, UARTHS_TXDATA(t3)
    addiw   t1, t1, 1
    j       1b
2:  sw      t1, 0(t0)
    ret

    .globl console_relay_start
# console_relay_start
#   What: from now on what is printed waits in the ring until a hart in
#         console_wait_us sends it (see the file's comment). Called by hart 0
#         before it releases hart 1, which does the sending.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
console_relay_start:
    FRAME_SAVE 16, ra
    call    console_lock
    la      t0, console_relay
    li      t1, 1
    sw      t1, 0(t0)
    call    console_unlock
    FRAME_RESTORE 16, ra
    ret

    .globl console_relay_stop
# console_relay_stop
#   What: ends the relay: sends what the ring holds (waiting on the UART), and
#         printing goes straight to the UART again. Does nothing more when the
#         relay is not running. The caller holds the console lock (error and
#         trap reports call it before they print).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
console_relay_stop:
    la      t0, console_relay
    sw      zero, 0(t0)
    j       console_drain

    .globl console_wait_us
# console_wait_us
#   What: waits at least a0 microseconds (asleep in WFI), meanwhile sending
#         what the relay's ring holds, so the UART never runs dry while there
#         is something to send: woken by this hart's software interrupt (the
#         other hart raises it when it puts a byte into the empty ring) and,
#         while bytes wait for room in the FIFO, every CONSOLE_RELAY_POLL_US.
#         An empty ring costs no wake-ups until the wait ends.
#   Arguments: a0 = microseconds.
#   Results: none.
#   Clobbers: only ABI temporaries. Leaves this hart's msip clear and its
#         timer off.
console_wait_us:
    FRAME_SAVE 32, ra, s0, s1, s2
    call    timer_deadline
    mv      s0, a0                      # s0 = the wait's end (mtime)
    call    console_relay_sleep_begin
    mv      s1, a0                      # s1 = &msip[this hart]
    mv      s2, a1                      # s2 = &mtimecmp[this hart]
1:  sw      zero, 0(s1)
    fence                               # the clear lands before the ring is read
    mv      a0, s0
    mv      a1, s2
    call    console_relay_nap
    beqz    a0, 1b
    mv      a0, s2
    call    console_relay_sleep_end
    FRAME_RESTORE 32, ra, s0, s1, s2
    ret

    .globl console_relay_until
# console_relay_until
#   What: the relay while this hart has nothing else to do: sends what the
#         ring holds as the UART's FIFO takes it, until the word at a0 equals
#         a1 or halt_request is raised. Asleep in WFI meanwhile, woken by this
#         hart's software interrupt (the other hart raises it when it puts a
#         byte into an empty ring, sets the word, or halts; it is cleared
#         before the reads, as in main.S's protocol) or, while bytes wait for
#         room in the FIFO, every CONSOLE_RELAY_POLL_US: an idle relay costs
#         no wake-ups. Acquire, as wait_state (main.S).
#   Arguments: a0 = address of the word, a1 = wanted value.
#   Results: a0 = 0 when the word was reached, 1 when halted.
#   Clobbers: only ABI temporaries. Leaves this hart's msip clear and its
#         timer off.
console_relay_until:
    FRAME_SAVE 48, ra, s0, s1, s2, s3
    mv      s0, a0
    mv      s1, a1
    call    console_relay_sleep_begin
    mv      s2, a0                      # s2 = &msip[this hart]
    mv      s3, a1                      # s3 = &mtimecmp[this hart]
1:  sw      zero, 0(s2)
    fence                               # the clear lands before the reads
    la      t0, halt_request
    lw      t0, 0(t0)
    bnez    t0, 3f
    lw      t0, 0(s0)
    beq     t0, s1, 2f
    li      a0, MTIMECMP_NEVER          # no end: only a signal (or bytes left) wakes it
    mv      a1, s3
    call    console_relay_nap
    j       1b
2:  li      s1, 0
    j       5f
3:  li      s1, 1
5:  mv      a0, s3
    call    console_relay_sleep_end
    fence   r, rw                       # acquire: what was written before the word
    mv      a0, s1
    FRAME_RESTORE 48, ra, s0, s1, s2, s3
    ret

# console_relay_sleep_begin (file-local)
#   What: lets this hart's software interrupt and timer wake it from WFI
#         (mie.MSIE, mie.MTIE; mstatus.MIE stays as it is), for the relay's
#         sleeps (console_relay_nap).
#   Arguments: none.
#   Results: a0 = &msip[this hart], a1 = &mtimecmp[this hart].
#   Clobbers: only ABI temporaries.
console_relay_sleep_begin:
    srli    t0, tp, HART_LOCAL_SHIFT    # mhartid (boot.S)
    slli    t1, t0, CLINT_MSIP_SHIFT
    li      a0, CLINT_MSIP
    add     a0, a0, t1
    slli    t1, t0, CLINT_MTIMECMP_SHIFT
    li      a1, CLINT_MTIMECMP
    add     a1, a1, t1
    li      t0, MIE_MSIE | MIE_MTIE
    csrs    mie, t0
    ret

# console_relay_sleep_end (file-local)
#   What: ends the relay's sleeps: this hart's timer off (which drops MTIP
#         before MTIE goes away), mie.MSIE and mie.MTIE clear.
#   Arguments: a0 = &mtimecmp[this hart].
#   Results: none.
#   Clobbers: only ABI temporaries.
console_relay_sleep_end:
    li      t0, MTIMECMP_NEVER
    sd      t0, 0(a0)
    li      t0, MIE_MSIE | MIE_MTIE
    csrc    mie, t0
    ret

# console_relay_nap (file-local)
#   What: one round of the relay's sleep: sends what the ring holds as the
#         UART's FIFO takes it; then, unless mtime has reached a0, sleeps in
#         WFI until this hart's software interrupt, a0, or (bytes left: the
#         FIFO was full) CONSOLE_RELAY_POLL_US from now, whichever comes
#         first. The caller has cleared its msip before reading what it waits
#         for (a byte added since then signals) and called
#         console_relay_sleep_begin.
#   Arguments: a0 = the latest wake-up (mtime; MTIMECMP_NEVER: none),
#         a1 = &mtimecmp[this hart].
#   Results: a0 = 1 when mtime had reached a0 (no sleep), else 0.
#   Clobbers: only ABI temporaries.
console_relay_nap:
    FRAME_SAVE 32, ra, s0, s1
    mv      s0, a0
    mv      s1, a1
    call    console_lock
    call    console_pump
    call    console_unlock
    mv      a0, s0
    call    timer_expired
    bnez    a0, 2f
    la      t0, console_ring_head
    lw      t1, 0(t0)
    la      t0, console_ring_tail
    lw      t2, 0(t0)
    mv      a0, s0
    beq     t1, t2, 1f
    li      a0, CONSOLE_RELAY_POLL_US
    call    timer_deadline
    bltu    a0, s0, 1f
    mv      a0, s0
1:  sd      a0, 0(s1)                   # (also drops an earlier MTIP)
    wfi
    li      a0, 0
2:  FRAME_RESTORE 32, ra, s0, s1
    ret

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
    FRAME_SAVE 32, ra, s0, s1
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
    FRAME_RESTORE 32, ra, s0, s1
    ret

    .globl console_put_dec
# console_put_dec
#   What: sends a0 as an unsigned decimal number without leading zeros.
#   Arguments: a0 = value.
#   Results: none.
#   Clobbers: only ABI temporaries.
    .equ DEC_DIGITS_MAX, 20             # 2^64 - 1 has 20 digits
console_put_dec:
    FRAME_SAVE 48, ra, s0
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
    FRAME_RESTORE 48, ra, s0
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
    FRAME_SAVE 32, ra, s0, s1
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
    FRAME_RESTORE 32, ra, s0, s1
    ret

    .globl console_line
# console_line
#   What: prints a string (which carries its own "\n") as one locked line.
#   Arguments: a0 = string. Results: none.
#   Clobbers: only ABI temporaries.
console_line:
    FRAME_SAVE 16, ra, s0
    mv      s0, a0
    call    console_lock
    mv      a0, s0
    call    console_puts
    call    console_unlock
    FRAME_RESTORE 16, ra, s0
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
# console_relay: 1 while printed bytes wait in the ring (console_relay_start).
console_relay:
    .word   0
# console_ring_head / _tail: bytes ever put into / taken out of the ring (the
# ring holds head - tail of them, at index & CONSOLE_RING_MASK). In .data with
# the rest, so that an early trap finds the ring empty.
console_ring_head:
    .word   0
console_ring_tail:
    .word   0

    .bss
# console_ring: the relay's bytes (only touched with the console lock held).
console_ring:
    .space  CONSOLE_RING_BYTES
