# start.S: where both harts begin (0x8000_0000) and where every trap enters.
#
# Hart 0 sets up the C world (global pointer, its stack, .bss, thread-local storage for
# picolibc's errno, the FPU) and calls main(); a main() that returns ends in a wfi loop
# with interrupts off. Hart 1 parks in wfi with every interrupt masked, unless the program
# defines hart1_main: then it waits for hart 0's software interrupt (msip[1]) and calls it. Traps save the caller-saved registers
# and call trap_handler(mcause, mepc, mtval, frame) in C, which returns the pc to resume at;
# frame holds the saved registers (ra, t0-t6, a0-a7: struct trap_frame), which the handler
# may change (a system call's result, an emulated load's destination).

    .equ    STACK_SIZE, 16384           # per hart, as k210.ld lays out
    .equ    FRAME, 20 * 8               # ra, t0-t6, a0-a7, and mepc's slot (one spare)
    .equ    MSTATUS_FS_INITIAL, (1 << 13)
    .equ    MIE_MSIE, (1 << 3)
    .equ    CLINT_MSIP1, 0x02000004     # hart 1's msip (CLINT_BASE + 4)

    .section .text.start, "ax", @progbits
    .globl  _start
_start:
    csrw    mie, zero
    la      t0, trap_entry
    csrw    mtvec, t0
    .option push
    .option norelax
    la      gp, __global_pointer$
    .option pop
    csrr    a0, mhartid
    la      sp, __stack_top
    li      t0, STACK_SIZE
    mul     t0, t0, a0
    sub     sp, sp, t0
    bnez    a0, park
    li      t0, MSTATUS_FS_INITIAL      # F/D instructions trap until the FPU is on
    csrs    mstatus, t0
    fscsr   zero
    la      t0, __bss_start             # .tbss and .bss, one range
    la      t1, __bss_end
1:  bgeu    t0, t1, 2f
    sd      zero, 0(t0)
    addi    t0, t0, 8
    j       1b
2:  la      tp, __tls_base
    call    main
park:
    csrw    mie, zero
    csrr    t0, mhartid
    beqz    t0, 3f                      # hart 0, after main
    ld      t1, hart1_main_address      # 0 unless the program defines hart1_main
    beqz    t1, 3f
    li      t0, MSTATUS_FS_INITIAL
    csrs    mstatus, t0
    fscsr   zero
    la      tp, __tls_base              # hart 0's thread-local block: errno is shared
    li      t0, MIE_MSIE                # wake on hart 0's software interrupt (no trap: MIE stays clear)
    csrw    mie, t0
    li      t2, CLINT_MSIP1
4:  wfi
    lw      t0, 0(t2)
    beqz    t0, 4b
    sw      zero, 0(t2)
    csrw    mie, zero
    jalr    t1                          # hart1_main; parks when it returns
    csrw    mie, zero
3:  wfi
    j       3b

    .section .data
    .balign 8
    .weak   hart1_main
hart1_main_address:
    .dword  hart1_main                  # (an absolute word: a weak symbol left undefined is 0)
    .previous

# trap_entry: saves the registers a C function may clobber, calls trap_handler(mcause, mepc,
# mtval, frame), resumes at the pc it returns with the registers from the frame.
    .balign 4
trap_entry:
    addi    sp, sp, -FRAME
    sd      ra, 0(sp)
    sd      t0, 8(sp)
    sd      t1, 16(sp)
    sd      t2, 24(sp)
    sd      t3, 32(sp)
    sd      t4, 40(sp)
    sd      t5, 48(sp)
    sd      t6, 56(sp)
    sd      a0, 64(sp)
    sd      a1, 72(sp)
    sd      a2, 80(sp)
    sd      a3, 88(sp)
    sd      a4, 96(sp)
    sd      a5, 104(sp)
    sd      a6, 112(sp)
    sd      a7, 120(sp)
    csrr    a0, mcause
    csrr    a1, mepc
    csrr    a2, mtval
    mv      a3, sp
    call    trap_handler
    csrw    mepc, a0
    ld      ra, 0(sp)
    ld      t0, 8(sp)
    ld      t1, 16(sp)
    ld      t2, 24(sp)
    ld      t3, 32(sp)
    ld      t4, 40(sp)
    ld      t5, 48(sp)
    ld      t6, 56(sp)
    ld      a0, 64(sp)
    ld      a1, 72(sp)
    ld      a2, 80(sp)
    ld      a3, 88(sp)
    ld      a4, 96(sp)
    ld      a5, 104(sp)
    ld      a6, 112(sp)
    ld      a7, 120(sp)
    addi    sp, sp, FRAME
    mret
