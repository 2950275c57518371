# heap.S: a bump allocator over the SRAM between the end of .bss and the
# hart stacks ([__heap_start, __heap_end), from k210.ld).
#
# Blocks are handed out in order and given back only from the top: a block
# that is needed for a while (scene.ini's text, the window obj.S reads the
# model through) is given back with every block after it (heap_release) while
# it is still the latest. Everything else is kept. Only hart 0 allocates,
# before hart 1 is released, so there is no lock.

    .option norelax
    .include "k210.inc"
    .include "errors.inc"
    .include "heap.inc"
    .include "frame.inc"

    .text
    .globl heap_init
# heap_init
#   What: empties the heap (the next block starts at __heap_start).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
heap_init:
    la      t0, heap_next
    la      t1, __heap_start
    sd      t1, 0(t0)
    ret

    .globl heap_alloc
# heap_alloc
#   What: hands out a0 bytes, HEAP_ALIGN-aligned, or reports that they do not
#         fit (the heap is left as it was).
#   Arguments: a0 = bytes (any 64-bit value; 0 gives an empty block).
#   Results: a0 = address, or 0 when the block does not fit.
#   Clobbers: only ABI temporaries.
heap_alloc:
    la      t0, heap_next
    ld      t1, 0(t0)                   # t1 = next free byte (aligned)
    la      t2, __heap_end
    sub     t3, t2, t1                  # t3 = bytes free
    bgtu    a0, t3, 1f
    add     t4, t1, a0
    addi    t4, t4, HEAP_ALIGN - 1
    andi    t4, t4, -HEAP_ALIGN
    bleu    t4, t2, 2f
    mv      t4, t2                      # the rounding ran past the end: heap now full
2:  sd      t4, 0(t0)
    mv      a0, t1
    ret
1:  li      a0, 0
    ret

    .globl heap_release
# heap_release
#   What: gives back the block at a0 and every block handed out after it (the
#         next block starts at a0 again). a0 must be an address heap_alloc
#         returned, not given back since.
#   Arguments: a0 = the block's address.
#   Results: none.
#   Clobbers: only ABI temporaries.
heap_release:
    la      t0, heap_next
    sd      a0, 0(t0)
    ret

    .globl heap_alloc_or_fail
# heap_alloc_or_fail
#   What: heap_alloc for the renderer's working memory: when the block does
#         not fit, fatal error 12, "model too large for memory (<block>: <n>
#         bytes needed, <m> bytes free)". A block fits exactly when n <= m
#         (the heap's start and end are HEAP_ALIGN-aligned), so the two
#         figures say by how much it failed.
#   Arguments: a0 = bytes, a1 = the block's name (string).
#   Results: a0 = address (never 0).
#   Clobbers: only ABI temporaries.
heap_alloc_or_fail:
    FRAME_SAVE 32, ra, s0, s1
    mv      s0, a0                      # s0 = bytes
    mv      s1, a1                      # s1 = name
    call    heap_alloc
    beqz    a0, 1f
    FRAME_RESTORE 32, ra, s0, s1
    ret
1:  li      a0, ERR_MODEL_TOO_LARGE
    call    error_begin
    la      a0, msg_too_large
    call    console_puts
    mv      a0, s1
    call    console_puts
    la      a0, msg_too_large_need
    call    console_puts
    mv      a0, s0
    call    console_put_dec
    la      a0, msg_too_large_free
    call    console_puts
    call    heap_free_bytes
    call    console_put_dec
    la      a0, msg_too_large_tail
    call    console_puts
    j       error_end

    .globl heap_free_bytes
# heap_free_bytes
#   What: how many bytes the heap can still hand out.
#   Arguments: none.
#   Results: a0 = free bytes.
#   Clobbers: only ABI temporaries.
heap_free_bytes:
    la      t0, heap_next
    ld      t1, 0(t0)
    la      a0, __heap_end
    sub     a0, a0, t1
    ret

# ---------------------------------------------------------------------------
    .section .rodata
msg_too_large:      .asciz "model too large for memory ("
msg_too_large_need: .asciz ": "
msg_too_large_free: .asciz " bytes needed, "
msg_too_large_tail: .asciz " bytes free)"

# ---------------------------------------------------------------------------
    .bss
    .balign 8
# heap_next: the next free byte of the heap (HEAP_ALIGN-aligned).
heap_next:
    .space  8
