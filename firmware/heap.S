# heap.S: a bump allocator over the SRAM between the end of .bss and the
# hart stacks ([__heap_start, __heap_end), from k210.ld).
#
# Blocks are never freed: the firmware loads its files once at boot and keeps
# them. Only hart 0 allocates, before hart 1 is released, so there is no lock.

    .option norelax
    .include "k210.inc"

    .equ HEAP_ALIGN,            64          # one cache line: DMA targets start on a line

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
    .bss
    .balign 8
# heap_next: the next free byte of the heap (HEAP_ALIGN-aligned).
heap_next:
    .space  8
