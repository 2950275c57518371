# raster_texture.S: the texture the textured fills read (raster_set_texture)
# and, with filter = mipmap, its mip chain: the levels, each half the size of
# the one above, and the level table the FILTERED fills index per pixel
# (raster_build_mips; render.inc MIP_*, docs/reference/scene-keys.md "Texture filtering").

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"
    .include "frame.inc"

    .text
    .globl raster_set_texture
# raster_set_texture
#   What: sets the texture of textured fills.
#   Arguments: a0 = RGB565 texels (row-major, row 0 at the top), a1 = width,
#              a2 = height (both > 0).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_set_texture:
    la      t0, raster_texture
    sd      a0, 0(t0)
    la      t0, raster_tex_w
    sd      a1, 0(t0)
    la      t0, raster_tex_h
    sd      a2, 0(t0)
    ret

    .globl raster_build_mips
# raster_build_mips
#   What: filter = mipmap: builds the mip chain of the texture and its level
#         table in one heap block ("mip chain": MIP_TABLE_BYTES, then the
#         levels 1 .. L - 1 one after another), and sets raster_mip_table.
#         Level l is max(1, W >> l) x max(1, H >> l), L levels down to 1 x 1
#         (L = the bit length of max(W, H)); level 0 is the texture itself.
#         Texel (i, j) of level l + 1 is the mean of texels 2i, 2i + 1 by
#         2j, 2j + 1 of level l, each channel rounded to nearest (halves
#         up); where level l's side is odd, the last texel of level l + 1
#         takes its last three columns (rows), so every texel counts; a side
#         of 1 stays 1. (reference/render.py mip_chain builds the same.)
#         Level l's entry scales base texel coordinates by W_l / W, H_l / H,
#         so each level repeats where the texture does. Running out of heap
#         is fatal (heap_alloc_or_fail, error 12).
#   Arguments: a0 = RGB565 texels, a1 = width, a2 = height (both > 0).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_build_mips:
    FRAME_SAVE 112, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11
    mv      s0, a0                      # s0, s1, s2 = the texture
    mv      s1, a1
    mv      s2, a2
    # s3 = the block's bytes, s4 = L
    mv      t0, s1                      # t0 = max(W, H)
    bgeu    t0, s2, 1f
    mv      t0, s2
1:  li      s3, MIP_TABLE_BYTES
    li      s4, 1
2:  srl     t1, t0, s4
    beqz    t1, 4f                      # level s4 would be past 1 x 1
    srl     t2, s1, s4
    bnez    t2, 3f
    li      t2, 1
3:  srl     t3, s2, s4
    bnez    t3, 31f
    li      t3, 1
31: mul     t2, t2, t3
    slli    t2, t2, 1                   # TEX_PIXEL_BYTES
    add     s3, s3, t2
    addi    s4, s4, 1
    j       2b
4:  mv      a0, s3
    la      a1, msg_mip_chain
    call    heap_alloc_or_fail
    mv      s5, a0                      # s5 = the block: the table first
    la      t0, raster_mip_table
    sd      s5, 0(t0)
    # level 0's entry (the texture, scale 1)
    li      t0, MIP_TABLE_BIAS << MIP_ENTRY_SHIFT
    add     t0, t0, s5
    sd      s0, MIP_PIXELS(t0)
    sw      s1, MIP_W(t0)
    sw      s2, MIP_H(t0)
    li      t1, F32_ONE
    sw      t1, MIP_SCALE_S(t0)
    sw      t1, MIP_SCALE_T(t0)
    # levels 1 .. L - 1: s6, s7, s8 = the level above (texels, W, H),
    # s9 = the new level's texels, s10, s11 = its W, H, s3 = l
    mv      s6, s0
    mv      s7, s1
    mv      s8, s2
    li      t0, MIP_TABLE_BYTES
    add     s9, s5, t0
    li      s3, 1
5:  bgeu    s3, s4, 20f
    srl     s10, s1, s3
    bnez    s10, 6f
    li      s10, 1
6:  srl     s11, s2, s3
    bnez    s11, 7f
    li      s11, 1
7:  addi    t0, s3, MIP_TABLE_BIAS      # the entry of level l
    slli    t0, t0, MIP_ENTRY_SHIFT
    add     t0, t0, s5
    sd      s9, MIP_PIXELS(t0)
    sw      s10, MIP_W(t0)
    sw      s11, MIP_H(t0)
    fcvt.s.wu ft0, s10
    fcvt.s.wu ft1, s1
    fdiv.s  ft0, ft0, ft1
    fsw     ft0, MIP_SCALE_S(t0)
    fcvt.s.wu ft0, s11
    fcvt.s.wu ft1, s2
    fdiv.s  ft0, ft0, ft1
    fsw     ft0, MIP_SCALE_T(t0)
    mv      a0, s6
    mv      a1, s7
    mv      a2, s8
    mv      a3, s9
    mv      a4, s10
    mv      a5, s11
    call    mip_halve
    mv      s6, s9                      # the new level is the next one's source
    mv      s7, s10
    mv      s8, s11
    mul     t0, s10, s11
    slli    t0, t0, 1                   # TEX_PIXEL_BYTES
    add     s9, s9, t0
    addi    s3, s3, 1
    j       5b
    # the entries around the levels: below 0 repeat level 0, past L - 1
    # repeat level L - 1 (t3 = the entry copied, t4 = the entry written)
20: li      t4, 0
21: li      t0, MIP_TABLE_BIAS
    sub     t1, t4, t0                  # the entry's level
    bgez    t1, 22f
    li      t1, 0
22: blt     t1, s4, 23f
    addi    t1, s4, -1
23: add     t1, t1, t0
    slli    t3, t1, MIP_ENTRY_SHIFT
    add     t3, t3, s5
    slli    t2, t4, MIP_ENTRY_SHIFT
    add     t2, t2, s5
    ld      t0, MIP_PIXELS(t3)
    sd      t0, MIP_PIXELS(t2)
    ld      t0, MIP_W(t3)               # W and H
    sd      t0, MIP_W(t2)
    ld      t0, MIP_SCALE_S(t3)         # both scales
    sd      t0, MIP_SCALE_S(t2)
    addi    t4, t4, 1
    li      t0, MIP_TABLE_ENTRIES
    bltu    t4, t0, 21b
    FRAME_RESTORE 112, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11
    ret

# mip_halve (file-local)
#   What: one mip level from the one above (raster_build_mips): each texel
#         the rounded mean of its 2 x 2 block (the last column and row take
#         three at an odd side; a side of 1 stays 1), the three channels
#         summed at once in the blend spread (render.inc: 9 texels fit each
#         field many times over), then divided apart.
#   Arguments: a0 = the level above's texels, a1, a2 = its W, H; a3 = the
#              new level's texels, a4, a5 = its W, H.
#   Results: none.
#   Clobbers: only ABI temporaries.
mip_halve:
    FRAME_SAVE 32, s0, s1, s2, s3
    li      s2, BLEND_SPREAD_MUL
    li      s3, BLEND_SPREAD_MASK
    li      s0, 0                       # s0 = j
1:  li      t0, 0                       # t0, t1 = the rows summed
    li      t1, 1
    li      t2, 1
    beq     a2, t2, 3f
    slli    t0, s0, 1
    addi    t1, t0, 2
    addi    t2, a5, -1
    bne     s0, t2, 3f
    mv      t1, a2                      # the last row takes what is left
3:  li      s1, 0                       # s1 = i
4:  li      t2, 0                       # t2, t3 = the columns summed
    li      t3, 1
    li      t4, 1
    beq     a1, t4, 5f
    slli    t2, s1, 1
    addi    t3, t2, 2
    addi    t4, a4, -1
    bne     s1, t4, 5f
    mv      t3, a1
5:  li      a6, 0                       # a6 = the spread sum
    mv      t4, t0                      # t4 = row
6:  mul     t5, t4, a1
    add     t5, t5, t2
    slli    t5, t5, 1
    add     t5, t5, a0                  # t5 -> (c0, row)
    sub     t6, t3, t2                  # t6 = columns left
7:  lhu     a7, 0(t5)
    mul     a7, a7, s2
    and     a7, a7, s3
    add     a6, a6, a7
    addi    t5, t5, TEX_PIXEL_BYTES
    addi    t6, t6, -1
    bnez    t6, 7b
    addi    t4, t4, 1
    bltu    t4, t1, 6b
    sub     t4, t1, t0
    sub     t5, t3, t2
    mul     t4, t4, t5                  # t4 = texels summed
    srli    t5, t4, 1                   # half of it: rounds to nearest
    li      t6, MIP_SUM_B_MASK
    and     t6, a6, t6
    add     t6, t6, t5
    divu    a7, t6, t4                  # B
    srli    t6, a6, MIP_SUM_G_SHIFT
    li      t2, MIP_SUM_G_MASK
    and     t6, t6, t2
    add     t6, t6, t5
    divu    t6, t6, t4                  # G
    slli    t6, t6, RGB565_G_SHIFT
    or      a7, a7, t6
    srli    t6, a6, MIP_SUM_R_SHIFT
    add     t6, t6, t5
    divu    t6, t6, t4                  # R
    slli    t6, t6, RGB565_R_SHIFT
    or      a7, a7, t6
    sh      a7, 0(a3)
    addi    a3, a3, TEX_PIXEL_BYTES
    addi    s1, s1, 1
    bltu    s1, a4, 4b
    addi    s0, s0, 1
    bltu    s0, a5, 1b
    FRAME_RESTORE 32, s0, s1, s2, s3
    ret

# ---------------------------------------------------------------------------
    .section .rodata
    .balign 8                           # (the rodata layout the cycle counts were
                                        # measured with: Makefile FW_ORDER)
msg_mip_chain:      .asciz "mip chain"
