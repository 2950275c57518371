# boot.S: reset entry of both harts, .bss clearing and the hart 1 release.
#
# Both harts start at _start (0x8000_0000) running the same code. Hart 0
# clears .bss and goes on to main_hart0, which brings up what both harts need
# and then calls boot_release_hart1. Hart 1 parks in WFI until it sees the release
# word: it must not touch .bss before then, because hart 0 is still zeroing
# it. The release word lives in .data so it is valid (0) straight from the
# image, before anybody has run.

    .option norelax
    .include "k210.inc"

# ---------------------------------------------------------------------------
    .section .text.start, "ax"
    .globl _start
# _start
#   What: per-hart machine-mode set-up (interrupt enables off, stack, trap
#         vector, trap save area in mscratch, FPU on), then hart 0 clears
#         .bss and enters main_hart0 while hart 1 waits for its release and
#         enters main_hart1.
#   Arguments: none (reset state). Results: never returns.
#   Clobbers: everything; sp ends at this hart's stack top minus the trap
#         save area, tp at mhartid << HART_LOCAL_SHIFT (k210.inc) for good.
_start:
    # The boot ROM may leave interrupt enables behind: the firmware runs with
    # mstatus.MIE = 0 throughout and uses mie only as a WFI wake-up mask.
    csrci   mstatus, MSTATUS_MIE
    csrw    mie, zero
    csrr    a0, mhartid
    slli    tp, a0, HART_LOCAL_SHIFT    # this hart's offset into hart-local blocks

    # Hart h's 16 KiB region ends at __stack_top - h * 16 KiB. Its top
    # TRAP_FRAME_SIZE bytes are the trap save area (pointed to by mscratch, so
    # the handler never depends on sp being sane); the stack grows below it.
    la      t0, __stack_top
    slli    t1, a0, STACK_SIZE_SHIFT
    sub     t0, t0, t1
    addi    t0, t0, -TRAP_FRAME_SIZE
    csrw    mscratch, t0
    mv      sp, t0

    la      t1, trap_entry              # 4-aligned: mode bits = direct
    csrw    mtvec, t1

    # FS = Initial: F/D instructions (and fcsr) stop trapping as illegal.
    li      t1, MSTATUS_FS_INITIAL
    csrs    mstatus, t1

    bnez    a0, boot_hart1_wait

    # --- hart 0: clear .bss, 64 bytes per round (the linker aligns both ends
    # to 64). The framebuffers make this the longest loop of the boot.
    la      t0, __bss_start
    la      t1, __bss_end
    bgeu    t0, t1, 2f
1:  sd      zero, 0(t0)
    sd      zero, 8(t0)
    sd      zero, 16(t0)
    sd      zero, 24(t0)
    sd      zero, 32(t0)
    sd      zero, 40(t0)
    sd      zero, 48(t0)
    sd      zero, 56(t0)
    addi    t0, t0, 64
    bltu    t0, t1, 1b
2:
    j       main_hart0

# --- hart 1: wait for the release word. Only the CLINT and .data are touched
# here. msip is cleared before each check, so a release that lands between
# the check and the WFI still leaves msip pending and WFI falls through.
boot_hart1_wait:
    li      t0, MIE_MSIE
    csrs    mie, t0
    li      t0, CLINT_MSIP
    slli    t1, a0, CLINT_MSIP_SHIFT
    add     t0, t0, t1                  # t0 = &msip[1]
    la      t1, boot_release
    li      t2, BOOT_RELEASE_MAGIC
1:  sw      zero, 0(t0)
    fence                               # msip clear lands before the check
    lw      t3, 0(t1)
    beq     t3, t2, 2f
    wfi
    j       1b
2:  fence   r, rw                       # acquire: .bss reads come after the release
    sw      zero, 0(t0)                 # the release IPI itself may still be pending
    li      t0, MIE_MSIE
    csrc    mie, t0
    j       main_hart1

# ---------------------------------------------------------------------------
    .text
    .globl boot_release_hart1
# boot_release_hart1
#   What: lets hart 1 out of its boot wait: publishes BOOT_RELEASE_MAGIC in
#         the release word (after everything hart 0 wrote so far, .bss
#         clearing included) and raises hart 1's software interrupt.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
boot_release_hart1:
    la      t0, boot_release
    li      t1, BOOT_RELEASE_MAGIC
    fence   rw, w
    amoswap.w.rl zero, t1, (t0)
    fence                               # the word is visible before the IPI
    li      t0, CLINT_MSIP + (1 << CLINT_MSIP_SHIFT)
    li      t1, CLINT_MSIP_RAISE
    sw      t1, 0(t0)
    ret

# ---------------------------------------------------------------------------
    .data
    .balign 4
    .globl boot_release
# boot_release: 0 in the image; BOOT_RELEASE_MAGIC once hart 0 has cleared
# .bss and brought up what both harts need (main.S).
boot_release:
    .word   0
