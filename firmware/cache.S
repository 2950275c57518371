# cache.S: handing memory between the harts' data caches and the DMA.
#
# The K210's DMAC reads and writes SRAM around the cores' L1 data caches:
# it is not coherent with them (the Kendryte SDK stages every DMA buffer in
# SRAM's uncached view for that reason). So a buffer a hart has written
# must be written back before a DMA reads it, and a buffer a DMA writes is
# read through the uncached view (sd_read.S's staging buffers). Rocket, the
# K210's core, has no instruction that writes back one line; FENCE.I writes
# back and drops the whole data cache (rocket-chip 2017: FENCE.I's memory
# command is M_FLUSH_ALL, a walk of every way of every set, skipped when no
# line came in since the last one) as well as the instruction cache.

    .option norelax

    .text
    .globl dcache_write_back
# dcache_write_back
#   What: writes this hart's dirty data-cache lines back to SRAM, so that a
#         DMA started afterwards reads what this hart stored. Drops every
#         line of both of this hart's caches (they fill again as used).
#   Arguments: none. Results: none.
#   Clobbers: nothing.
dcache_write_back:
    fence.i
    ret
