# start.S: where QEMU's -M virt starts CoreMark (its reset vector jumps to 0x8000_0000 when
# -bios none is given) and where it ends: by the sifive_test device, so that QEMU exits by itself.
#
# Hart 0 sets up the C world as tests/firmware/start.S does on the K210 (global pointer, stack,
# .bss and .tbss cleared, thread-local storage for picolibc's errno, the FPU on), calls main() and,
# when it returns, asks QEMU to exit with status 0. Any other hart parks in wfi (the tool runs one
# hart; the park is there for -smp N). Every trap is unexpected here: it ends QEMU with exit status
# mcause + 1, so that a fault reads as a failed run, not a hung one.

    .equ    MSTATUS_FS_INITIAL, (1 << 13)
    .equ    SIFIVE_TEST, 0x00100000     # virt's test finisher
    .equ    FINISHER_PASS, 0x5555       # QEMU exits with status 0
    .equ    FINISHER_FAIL, 0x3333       # QEMU exits with the status in bits 31:16

    .section .text.start, "ax", @progbits
    .globl  _start
# _start: the reset entry of every hart. Arguments: a0 = mhartid, a1 = the device tree (QEMU's
# reset vector passes both; neither is needed). Does not return.
_start:
    csrw    mie, zero
    la      t0, trap_exit
    csrw    mtvec, t0
    .option push
    .option norelax
    la      gp, __global_pointer$
    .option pop
    csrr    t0, mhartid
    bnez    t0, park
    la      sp, __stack_top
    li      t0, MSTATUS_FS_INITIAL      # CoreMark's seconds are doubles: F/D trap until the FPU is on
    csrs    mstatus, t0
    fscsr   zero
    la      t0, __bss_start             # .tbss and .bss, one range, a doubleword at a time
    la      t1, __bss_end
1:  bgeu    t0, t1, 2f
    sd      zero, 0(t0)
    addi    t0, t0, 8
    j       1b
2:  la      tp, __tls_base
    call    main
    li      t0, SIFIVE_TEST
    li      t1, FINISHER_PASS
    sw      t1, 0(t0)
park:
    wfi                                 # no interrupt is enabled: this hart stays here
    j       park

# trap_exit: any trap. Ends QEMU with exit status mcause + 1 (mcause's low byte; interrupts are
# never enabled, so mcause is an exception code below 16). Clobbers t0, t1; does not return.
    .balign 4
trap_exit:
    csrr    t0, mcause
    andi    t0, t0, 0xff
    addi    t0, t0, 1
    slli    t0, t0, 16
    li      t1, FINISHER_FAIL
    or      t1, t1, t0
    li      t0, SIFIVE_TEST
    sw      t1, 0(t0)
    j       park
