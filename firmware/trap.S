# trap.S: the machine-mode trap handler (mtvec, direct mode).
#
# The firmware never enables mstatus.MIE, so any trap is a fault: the handler
# saves the registers, reports the trap on UARTHS, has the screen painted
# red if the LCD is up, and parks the hart. It never returns.
#
# Who paints: SPI0 must have one user at a time. Once hart 1 runs the display
# loop it owns SPI0, so a trap on hart 0 after the release only raises
# halt_request and hart 1's msip; hart 1 finishes the frame it is sending,
# sees the request in its wait and paints the error screen itself. A trap on
# hart 1, or on hart 0 before the release, paints directly. Either way
# halt_request also stops the other hart's frame loop.
#
# mscratch holds this hart's trap save area (set by boot.S; the top
# TRAP_FRAME_SIZE bytes of its stack region), so the handler does not trust
# sp. While the handler runs, mscratch is 0: a trap inside the handler finds
# 0 and parks at once instead of recursing.

    .option norelax
    .include "k210.inc"

# Save area layout: x1..x31 at 8 * n (slot 0 unused), then the trap CSRs.
    .equ TF_MEPC,               32 * XLEN_BYTES
    .equ TF_MCAUSE,             33 * XLEN_BYTES
    .equ TF_MTVAL,              34 * XLEN_BYTES
    .equ TF_SP_SLOT,            2 * XLEN_BYTES

    .text
    .balign 4                           # mtvec needs a 4-aligned base
    .globl trap_entry
# trap_entry
#   What: handles every trap of either hart: save, report, error screen, park.
#   Arguments: none (entered by the hardware).
#   Results: never returns.
#   Clobbers: everything (the hart stops).
trap_entry:
    csrrw   sp, mscratch, sp            # sp = save area, mscratch = interrupted sp
    beqz    sp, trap_park               # a trap while handling a trap
    sd      x1, 1 * XLEN_BYTES(sp)
    sd      x3, 3 * XLEN_BYTES(sp)
    sd      x4, 4 * XLEN_BYTES(sp)
    sd      x5, 5 * XLEN_BYTES(sp)
    sd      x6, 6 * XLEN_BYTES(sp)
    sd      x7, 7 * XLEN_BYTES(sp)
    sd      x8, 8 * XLEN_BYTES(sp)
    sd      x9, 9 * XLEN_BYTES(sp)
    sd      x10, 10 * XLEN_BYTES(sp)
    sd      x11, 11 * XLEN_BYTES(sp)
    sd      x12, 12 * XLEN_BYTES(sp)
    sd      x13, 13 * XLEN_BYTES(sp)
    sd      x14, 14 * XLEN_BYTES(sp)
    sd      x15, 15 * XLEN_BYTES(sp)
    sd      x16, 16 * XLEN_BYTES(sp)
    sd      x17, 17 * XLEN_BYTES(sp)
    sd      x18, 18 * XLEN_BYTES(sp)
    sd      x19, 19 * XLEN_BYTES(sp)
    sd      x20, 20 * XLEN_BYTES(sp)
    sd      x21, 21 * XLEN_BYTES(sp)
    sd      x22, 22 * XLEN_BYTES(sp)
    sd      x23, 23 * XLEN_BYTES(sp)
    sd      x24, 24 * XLEN_BYTES(sp)
    sd      x25, 25 * XLEN_BYTES(sp)
    sd      x26, 26 * XLEN_BYTES(sp)
    sd      x27, 27 * XLEN_BYTES(sp)
    sd      x28, 28 * XLEN_BYTES(sp)
    sd      x29, 29 * XLEN_BYTES(sp)
    sd      x30, 30 * XLEN_BYTES(sp)
    sd      x31, 31 * XLEN_BYTES(sp)
    csrrw   t0, mscratch, zero          # mark "in the handler"
    sd      t0, TF_SP_SLOT(sp)
    csrr    s1, mcause
    csrr    s2, mepc
    csrr    s3, mtval
    csrr    s4, mhartid
    sd      s1, TF_MCAUSE(sp)
    sd      s2, TF_MEPC(sp)
    sd      s3, TF_MTVAL(sp)
    # From here on the save area's bottom is the handler's stack top; the
    # interrupted code's stack below it is overwritten, which is fine since
    # it never resumes.

    # Nothing asynchronous may interrupt the report.
    csrci   mstatus, MSTATUS_MIE
    csrw    mie, zero

    # The console may not be up yet (early fault): bring UARTHS up at the
    # clock the CPU runs at now.
    la      t0, console_ready
    lw      t0, 0(t0)
    bnez    t0, 1f
    la      t0, cpu_hz
    lwu     a0, 0(t0)
    call    console_init
1:
    # Take the console, unless this hart already holds it (the fault hit
    # its own console output): then end the half-printed line and go on.
    la      t0, console_owner
    lw      t0, 0(t0)
    addi    t1, s4, 1
    bne     t0, t1, 2f
    li      a0, '\n'
    call    console_putc
    j       3f
2:  call    console_lock
3:  call    console_relay_stop          # what is queued, then the report, by this hart
    la      a0, msg_trap_mcause
    call    console_puts
    mv      a0, s1
    call    console_put_hex64
    la      a0, msg_trap_mepc
    call    console_puts
    mv      a0, s2
    call    console_put_hex64
    la      a0, msg_trap_mtval
    call    console_puts
    mv      a0, s3
    call    console_put_hex64
    la      a0, msg_trap_hart
    call    console_puts
    mv      a0, s4
    call    console_put_dec
    li      a0, '\n'
    call    console_putc

    # Second line: the cause by name, when it has one.
    la      a0, msg_trap_cause
    call    console_puts
    slli    t0, s1, 1
    srli    t0, t0, 1                   # t0 = cause code without the interrupt bit
    la      t1, exception_names
    bgez    s1, 4f
    la      t1, interrupt_names
4:  li      t2, MCAUSE_CODE_NAMED
    la      a0, msg_cause_unknown
    bgeu    t0, t2, 5f
    slli    t0, t0, 3
    add     t1, t1, t0
    ld      t1, 0(t1)
    beqz    t1, 5f
    mv      a0, t1
5:  call    console_puts
    li      a0, '\n'
    call    console_putc
    call    console_unlock

    # Stop the other hart's frame loop and wake it so it sees the request.
    la      t0, halt_request
    li      t1, 1
    amoswap.w.rl zero, t1, (t0)
    fence
    xori    t0, s4, OTHER_HART_XOR
    slli    t0, t0, CLINT_MSIP_SHIFT
    li      t1, CLINT_MSIP
    add     t0, t0, t1
    li      t1, CLINT_MSIP_RAISE
    sw      t1, 0(t0)

    # Paint here unless hart 1 is running the display loop and will do it.
    bnez    s4, 6f
    la      t0, boot_release
    lw      t0, 0(t0)
    li      t1, BOOT_RELEASE_MAGIC
    beq     t0, t1, trap_park
6:  call    lcd_error_screen

    .globl trap_park
# trap_park
#   What: stops this hart for good: interrupts masked, WFI forever.
#   Arguments: none. Results: never returns.
#   Clobbers: nothing that matters any more.
trap_park:
    csrci   mstatus, MSTATUS_MIE
    csrw    mie, zero
1:  wfi
    j       1b

# ---------------------------------------------------------------------------
    .section .rodata
msg_trap_mcause:    .asciz "trap: mcause=0x"
msg_trap_mepc:      .asciz " mepc=0x"
msg_trap_mtval:     .asciz " mtval=0x"
msg_trap_hart:      .asciz " hart="
msg_trap_cause:     .asciz "trap: cause: "
msg_cause_unknown:  .asciz "unknown"

msg_exc_0:  .asciz "instruction address misaligned"
msg_exc_1:  .asciz "instruction access fault"
msg_exc_2:  .asciz "illegal instruction"
msg_exc_3:  .asciz "breakpoint"
msg_exc_4:  .asciz "load address misaligned"
msg_exc_5:  .asciz "load access fault"
msg_exc_6:  .asciz "store/AMO address misaligned"
msg_exc_7:  .asciz "store/AMO access fault"
msg_exc_8:  .asciz "environment call from U-mode"
msg_exc_9:  .asciz "environment call from S-mode"
msg_exc_11: .asciz "environment call from M-mode"
msg_exc_12: .asciz "instruction page fault"
msg_exc_13: .asciz "load page fault"
msg_exc_15: .asciz "store/AMO page fault"
msg_int_1:  .asciz "supervisor software interrupt"
msg_int_3:  .asciz "machine software interrupt"
msg_int_5:  .asciz "supervisor timer interrupt"
msg_int_7:  .asciz "machine timer interrupt"
msg_int_9:  .asciz "supervisor external interrupt"
msg_int_11: .asciz "machine external interrupt"

    .balign 8
# Cause code -> name (0: reserved, printed as "unknown").
exception_names:
    .dword  msg_exc_0, msg_exc_1, msg_exc_2, msg_exc_3
    .dword  msg_exc_4, msg_exc_5, msg_exc_6, msg_exc_7
    .dword  msg_exc_8, msg_exc_9, 0, msg_exc_11
    .dword  msg_exc_12, msg_exc_13, 0, msg_exc_15
interrupt_names:
    .dword  0, msg_int_1, 0, msg_int_3
    .dword  0, msg_int_5, 0, msg_int_7
    .dword  0, msg_int_9, 0, msg_int_11
    .dword  0, 0, 0, 0

# ---------------------------------------------------------------------------
    .data
    .balign 4
    .globl halt_request
# halt_request: 0 normally; 1 once a hart has trapped (frame loops stop and
# the display hart paints the error screen). In .data: valid before .bss
# clearing.
halt_request:
    .word   0
