# timer.S: delays on the CLINT timer, sleeping in WFI.
#
# mtime ticks at CPU clock / 50. A delay programs this hart's mtimecmp and
# enables only mie.MTIE while it sleeps; mstatus.MIE stays 0, so the pending
# timer interrupt wakes WFI without ever entering the trap handler.

    .option norelax
    .include "k210.inc"

    .text
    .globl delay_us
# delay_us
#   What: waits at least a0 microseconds.
#   Arguments: a0 = microseconds (0 returns at once), a1 = CPU clock in Hz
#         (mtime runs at a1 / 50; pass the clock in force at the time).
#   Results: none.
#   Clobbers: only ABI temporaries. mie.MTIE is left clear and this hart's
#         mtimecmp is left at all ones (never fires).
delay_us:
    beqz    a0, 9f
    # ticks = ceil(us * hz / (50 * 1e6)): rounding up keeps short waits
    # (1 us at 26 MHz is half a tick) from collapsing to zero.
    mul     t0, a0, a1
    li      t1, MTIME_DIV * 1000000
    add     t0, t0, t1
    addi    t0, t0, -1
    divu    t0, t0, t1                  # t0 = ticks (>= 1)

    li      t2, CLINT_MTIME
    ld      t3, 0(t2)
    add     a0, t0, t3                  # a0 = target mtime
    # fall through

    .globl delay_until
# delay_until
#   What: sleeps in WFI until mtime reaches a0 (returns at once when it
#         already has), for a wait whose end was fixed earlier (see
#         timer_deadline).
#   Arguments: a0 = the mtime value to wait for.
#   Results: none.
#   Clobbers: only ABI temporaries. mie.MTIE is left clear and this hart's
#         mtimecmp is left at all ones (never fires).
delay_until:
    mv      t0, a0                      # t0 = target mtime
    li      t2, CLINT_MTIME
    csrr    t4, mhartid
    slli    t4, t4, CLINT_MTIMECMP_SHIFT
    li      t5, CLINT_MTIMECMP
    add     t5, t5, t4                  # t5 = &mtimecmp[hart]
    sd      t0, 0(t5)

    li      t6, MIE_MTIE
    csrs    mie, t6
1:  ld      t3, 0(t2)
    bgeu    t3, t0, 2f
    wfi
    j       1b
2:  li      t3, MTIMECMP_NEVER
    sd      t3, 0(t5)                   # drops MTIP before MTIE goes away
    csrc    mie, t6
9:  ret

    .globl timer_deadline
# timer_deadline
#   What: the mtime value a0 microseconds from now, at the CPU clock in force
#         (cpu_hz), for timeouts checked with timer_expired between tries.
#   Arguments: a0 = microseconds.
#   Results: a0 = deadline (an mtime value).
#   Clobbers: only ABI temporaries (timer_ticks's t0, t1; t2, t3).
timer_deadline:
    mv      t3, ra                      # (timer_ticks leaves t3 alone)
    call    timer_ticks
    mv      ra, t3
    li      t2, CLINT_MTIME
    ld      t3, 0(t2)
    add     a0, a0, t3
    ret

    .globl timer_ticks
# timer_ticks
#   What: a0 microseconds in mtime ticks at the CPU clock in force (cpu_hz),
#         rounded up.
#   Arguments: a0 = microseconds.
#   Results: a0 = ticks.
#   Clobbers: t0 and t1 only.
timer_ticks:
    la      t0, cpu_hz
    lwu     t0, 0(t0)
    mul     t0, a0, t0
    li      t1, MTIME_DIV * 1000000
    add     t0, t0, t1
    addi    t0, t0, -1
    divu    a0, t0, t1
    ret

    .globl timer_expired
# timer_expired
#   What: whether mtime has reached a deadline from timer_deadline.
#   Arguments: a0 = deadline.
#   Results: a0 = 1 when it has passed, else 0.
#   Clobbers: only ABI temporaries.
timer_expired:
    li      t0, CLINT_MTIME
    ld      t0, 0(t0)
    sltu    a0, t0, a0
    xori    a0, a0, 1
    ret
