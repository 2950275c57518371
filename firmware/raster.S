# raster.S: triangle setup and rasterisation, lines, and the per-frame
# clears, into a 320 x 240 RGB565 framebuffer laid out for the LCD (pixel
# (x, y) is the halfword at fb + 2 (320 y + (x ^ 1)), see framebuffers in main.S)
# and the depth buffer (depth_buffer, below).
#
# Triangles (raster_triangle):
#   - Vertices are in Q4 (1/16 pixel, render.inc), snapped once by
#     project_clip, so a vertex shared by two triangles is bit-identical in
#     both. Edge functions E(p) = (b - a) x (p - a) are exact 64-bit
#     integers (Q8), evaluated at pixel centres (16 x + 8, 16 y + 8) and
#     stepped by integer additions.
#   - Orientation: with y down, a triangle that is counter-clockwise as the
#     camera sees it (a front face) has a negative signed area. Back faces
#     (positive area) are dropped when culling, else drawn like front faces;
#     either way the corners are put in positive order first, so every edge
#     of every drawn triangle runs one way round.
#   - Tie rule (top-left): a pixel centre exactly on an edge belongs to the
#     triangle when the edge is a top edge (horizontal, dy = 0, running
#     right, dx > 0, in positive order) or a left edge (dy < 0); other edges
#     get E - 1, so the test is E >= 0 everywhere. An edge shared by two
#     triangles runs opposite ways in them, so exactly one of them owns its
#     centres: no cracks and no pixel drawn twice.
#   - The bounding box (pixel centres inside the corners' box), clipped to
#     the screen, is scanned row by row: each row skips to its first inside
#     pixel and stops at the first outside one after it (triangles are
#     convex).
#   - Depth: z / w interpolated linearly in screen space as a float and
#     compared as a signed 32-bit integer (render.inc); a fragment is drawn
#     when it is strictly nearer than what the buffer holds.
#   - Textured fill: u / w, v / w and 1 / w are interpolated linearly in
#     screen space; per pixel one fdiv.s gives w, hence the texel (nearest,
#     repeating), which is lit by the triangle's intensity k / 64. With
#     filter = bilinear or mipmap the FILTERED fills blend four texels (of
#     the mip level the footprint picks), README "Texture filtering".
#   - Attributes are planes: gradients per pixel from the snapped corners,
#     re-anchored at the first inside pixel of every row.
#   - Bands: each hart draws only the rows of its band (raster_set_band;
#     main.S splits a frame between the harts). The planes are still set up
#     at the bounding box's first row and stepped row by row to the band,
#     so a pixel gets the same bits whichever hart draws it.
#   - antialias = edge (RASTER_EDGE_AA): a triangle with a silhouette edge
#     (SILHOUETTE: the mesh ends there, or folds away) is drawn by a
#     coverage fill (FILL / FILTERED with aa): its box grown by half a
#     pixel, its silhouette edges' functions moved out by half a pixel, and
#     each pixel blended over what is behind by its coverage (render.inc
#     AA_*); its other edges stay hard, so closed meshes show no seams.
#   - antialias = supersample: raster_set_sample moves the corners by minus
#     a sample's offset, raster_accumulate sums the samples' frames and
#     leaves their means (render.S draws each band once per sample).
#
# Lines: raster_segment / raster_line (Bresenham's), raster_aa_line (by
# coverage, antialias = edge wireframes), or raster_union_line and
# raster_union_resolve (their union, antialias = supersample wireframes).

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"

# raster_triangle's stack frame
    .equ RT_SAVE,               0           # s0 .. s11
    .equ RT_FSAVE,              96          # fs0 .. fs3 (the Gouraud intensity)
    .equ RT_RA,                 128         # ra (the lit fills' rounding constant)
# the filtered fills' row state (FILTERED), and fs4, fs5
    .equ RT_ROW_E0,             136         # edge functions at the row's first pixel
    .equ RT_ROW_E1,             144
    .equ RT_ROW_E2,             152
    .equ RT_ROW_D0,             160         # their steps down
    .equ RT_ROW_D1,             168
    .equ RT_ROW_D2,             176
    .equ RT_ROW_FB,             184         # framebuffer at (xmin, row)
    .equ RT_ROW_DEPTH,          192         # depth at (xmin, row)
    .equ RT_ROW_LEFT,           200         # rows left
    .equ RT_FSAVE2,             208         # fs4, fs5
    .equ RT_FSAVE3,             224         # fs6, fs7, fs8 (the coverage fills' scales)
    .equ RT_AA,                 248         # the filtered coverage fills' pixel coverage
    .equ RT_FRAME,              256

# EDGE xa, ya, xb, yb, E, A, B
#   The edge function of the edge a -> b at the first pixel centre
#   (a2, a3) = (16 xmin + 8, 16 ymin + 8), tie-rule bias included, and its
#   steps per pixel: E += A to the right, E += B downwards.
#   Clobbers t3.
.macro EDGE xa, ya, xb, yb, E, A, B
    sub     \B, \xb, \xa                # dx
    sub     \A, \yb, \ya                # dy
    sub     t3, a3, \ya
    mul     \E, \B, t3                  # dx (py - ya)
    sub     t3, a2, \xa
    mul     t3, \A, t3                  # dy (px - xa)
    sub     \E, \E, t3
    bltz    \A, .Ltopleft\@             # dy < 0: a left edge
    bnez    \A, .Lbias\@
    bgtz    \B, .Ltopleft\@             # dy = 0, dx > 0: a top edge
.Lbias\@:
    addi    \E, \E, -1
.Ltopleft\@:
    neg     \A, \A
    slli    \A, \A, SUBPIXEL_BITS
    slli    \B, \B, SUBPIXEL_BITS
.endm

# GRADIENT v0, v1, v2, ddx, ddy, base
#   The plane through an attribute's values v0, v1, v2 at the three corners:
#   ddx, ddy = change per pixel right / down, base = value at the first
#   pixel centre. Needs fa0..fa3 = x1 - x0, y1 - y0, x2 - x0, y2 - y0 (Q4)
#   times 16 / area (Q8), ft9, ft10 = first pixel centre - corner 0 in
#   pixels. v1 may be ddy and v2 may be base; ddx must be neither.
#   Clobbers ft8, v1, v2.
.macro GRADIENT v0, v1, v2, ddx, ddy, base
    fsub.s  \v1, \v1, \v0               # d1
    fsub.s  \v2, \v2, \v0               # d2
    fmul.s  \ddx, \v1, fa3
    fnmsub.s \ddx, \v2, fa1, \ddx       # (d1 dy2 - d2 dy1) / area
    fmul.s  ft8, \v2, fa0
    fnmsub.s \ddy, \v1, fa2, ft8        # (d2 dx1 - d1 dx2) / area
    fmadd.s \base, \ddx, ft9, \v0
    fmadd.s \base, \ddy, ft10, \base
.endm

# SILHOUETTE rec, xa, ya, xb, yb, bit
#   antialias = edge: sets RASTER_SILHOUETTE_SHIFT + bit in t5 when the edge
#   a -> b (the triangle inside on its E >= 0 side) is a silhouette: the
#   corner record rec (opposite the edge) says the mesh ends there
#   (OPP_OPEN), or its neighbour's far corner lies on this triangle's side
#   of the edge, E > 0 (the surface folds away: one of the two faces turns
#   its back). On the other side the two are one surface, drawn hard, so no
#   background shows between them; exactly on the line (a degenerate
#   neighbour), or OPP_HARD, hard too. Clobbers a0..a3.
.macro SILHOUETTE rec, xa, ya, xb, yb, bit
    lwu     a0, RV_OPP_KIND(\rec)
    li      a1, OPP_OPEN
    beq     a0, a1, .Lsilhouette\@
    li      a1, OPP_CORNER
    bne     a0, a1, .Lhard\@
    lw      a2, RV_OPP_X(\rec)
    lw      a3, RV_OPP_Y(\rec)
    sub     a0, \xb, \xa               # dx
    sub     a1, \yb, \ya               # dy
    sub     a3, a3, \ya
    mul     a3, a0, a3                  # dx (cy - ya)
    sub     a2, a2, \xa
    mul     a2, a1, a2                  # dy (cx - xa)
    sub     a3, a3, a2
    blez    a3, .Lhard\@
.Lsilhouette\@:
    ori     t5, t5, 1 << (RASTER_SILHOUETTE_SHIFT + \bit)
.Lhard\@:
.endm

# AA_EDGE bit, E, A, B, scale
#   A coverage fill's edge (render.inc AA_*): a silhouette edge's function
#   E moved out by M = ceil(8 |edge|) (sqrt(A^2 + B^2) = 16 |edge| from its
#   steps), scale = AA_HALF / M; a hard edge's by 1, scale = AA_FULL.
#   Clobbers t0, ft9, ft10.
.macro AA_EDGE bit, E, A, B, scale
    andi    t0, t5, 1 << (RASTER_SILHOUETTE_SHIFT + \bit)
    bnez    t0, .Lsilhouette\@
    addi    \E, \E, 1
    li      t0, F32_AA_FULL
    fmv.w.x \scale, t0
    j       .Ldone\@
.Lsilhouette\@:
    fcvt.s.l ft9, \A
    fmul.s  ft9, ft9, ft9
    fcvt.s.l ft10, \B
    fmadd.s ft9, ft10, ft10, ft9
    fsqrt.s ft9, ft9                    # 16 |edge|
    li      t0, F32_HALF
    fmv.w.x ft10, t0
    fmul.s  ft9, ft9, ft10
    fcvt.l.s t0, ft9, rup               # M
    add     \E, \E, t0
    fcvt.s.l ft9, t0
    li      t0, F32_AA_HALF
    fmv.w.x ft10, t0
    fdiv.s  \scale, ft10, ft9
.Ldone\@:
.endm

# The pieces FILL and FILTERED share (registers as FILL describes them).
# SKIP_TO_INSIDE: from the row's first pixel (2), steps the edge functions to
#   the first pixel inside the triangle (on to 3), or to the row's end (8).
.macro SKIP_TO_INSIDE
2:  or      t0, s0, s1                  # skip to the first inside pixel
    or      t0, t0, s2
    bgez    t0, 3f
    add     s0, s0, s3
    add     s1, s1, s4
    add     s2, s2, s5
    addi    a0, a0, LCD_BYTES_PER_PIXEL
    bltu    a0, a2, 2b
    j       8f
.endm

# PLANES_AT_X textured, gouraud, affine
#   The attribute planes at the span's first pixel: t0 = 2 (x - xmin).
#   Clobbers t0, ft9.
.macro PLANES_AT_X textured, gouraud, affine
    srli    t0, t0, 1
    fcvt.s.l ft9, t0
    fmadd.s fa0, fa4, ft9, ft0
    .if \textured
    .if !\affine
    fmadd.s fa1, fa5, ft9, ft1
    .endif
    fmadd.s fa2, fa6, ft9, ft2
    fmadd.s fa3, fa7, ft9, ft3
    .endif
    .if \gouraud
    fmadd.s fs0, fs1, ft9, fs2
    .endif
.endm

# DEPTH_TEST depth16, gouraud
#   The pixel's depth against the buffer's: not nearer, on to 7; nearer, the
#   depth stored and (Gouraud) t4 = k. Clobbers t0, t1.
.macro DEPTH_TEST depth16, gouraud
    .if \depth16
    lhu     t1, 0(a1)
    fcvt.w.s t0, fa0, rtz
    bge     t0, t1, 7f                  # not nearer
    sh      t0, 0(a1)
    .else
    lw      t1, 0(a1)
    fmv.x.w t0, fa0
    bge     t0, t1, 7f                  # not nearer
    sw      t0, 0(a1)
    .endif
    .if \gouraud
    fcvt.wu.s t4, fs0, rne              # k (a rounding-noise negative -> 0)
    .endif
.endm

# NEXT_PIXEL textured, gouraud, affine, depth16
#   Steps the planes, edge functions and buffer pointers one pixel right:
#   back to 4 while inside the triangle and the row, else on to 8.
#   Clobbers t0.
.macro NEXT_PIXEL textured, gouraud, affine, depth16
    fadd.s  fa0, fa0, fa4
    .if \textured
    .if !\affine
    fadd.s  fa1, fa1, fa5
    .endif
    fadd.s  fa2, fa2, fa6
    fadd.s  fa3, fa3, fa7
    .endif
    .if \gouraud
    fadd.s  fs0, fs0, fs1
    .endif
    add     s0, s0, s3
    add     s1, s1, s4
    add     s2, s2, s5
    addi    a0, a0, LCD_BYTES_PER_PIXEL
    .if \depth16
    addi    a1, a1, DEPTH16_BYTES_PER_PIXEL
    .else
    addi    a1, a1, DEPTH_BYTES_PER_PIXEL
    .endif
    bgeu    a0, a2, 8f
    or      t0, s0, s1
    or      t0, t0, s2
    bgez    t0, 4b
.endm

# The pieces of the coverage fills (antialias = edge; render.inc AA_*).
# COVERAGE: t1 = the pixel's coverage a (0 .. AA_FULL, or more: whole) from
#   the moved-out edge functions s0..s2 and their scales fs6..fs8 (the least
#   of the three); none, on to 7. Clobbers ft9, ft10.
.macro COVERAGE
    fcvt.s.l ft9, s0
    fmul.s  ft9, ft9, fs6
    fcvt.s.l ft10, s1
    fmul.s  ft10, ft10, fs7
    fmin.s  ft9, ft9, ft10
    fcvt.s.l ft10, s2
    fmul.s  ft10, ft10, fs8
    fmin.s  ft9, ft9, ft10
    fcvt.w.s t1, ft9, rne
    blez    t1, 7f                      # no coverage
.endm

# DEPTH_TEST_AA depth16, gouraud
#   DEPTH_TEST for a pixel of coverage t1: the depth test at the pixel
#   centre (the planes extended past the edge for a pixel whose centre is
#   outside), the depth stored only when at least half the pixel is covered
#   (as the tie rule stores it without antialiasing), so what is drawn later
#   behind a partly covered pixel still blends into it. Gouraud's k is
#   clamped to LIGHT_ONE (extended past the corners it can exceed it).
#   Clobbers t0, t3.
.macro DEPTH_TEST_AA depth16, gouraud
    .if \depth16
    lhu     t3, 0(a1)
    fcvt.w.s t0, fa0, rtz
    bge     t0, t3, 7f                  # not nearer
    li      t3, AA_DEPTH_WRITE
    blt     t1, t3, .Ldepth_kept\@
    sh      t0, 0(a1)
    .else
    lw      t3, 0(a1)
    fmv.x.w t0, fa0
    bge     t0, t3, 7f                  # not nearer
    li      t3, AA_DEPTH_WRITE
    blt     t1, t3, .Ldepth_kept\@
    sw      t0, 0(a1)
    .endif
.Ldepth_kept\@:
    .if \gouraud
    fcvt.wu.s t4, fs0, rne              # k (a rounding-noise negative -> 0)
    li      t3, LIGHT_ONE
    ble     t4, t3, .Lk_ok\@
    mv      t4, t3
.Lk_ok\@:
    .endif
.endm

# BLEND_COVERAGE
#   t2 = the spread colour (RGB565_SPREAD_MASK) drawn over the framebuffer's
#   pixel (at a0 ^ FB_PAIR_XOR) by coverage t1: (c a + old (64 - a)) / 64 per
#   channel, rounded to nearest, in one multiplication as the light is (the
#   fields' borrows cancel: every field's result fits it); a whole pixel
#   keeps c. Needs t5 = RGB565_SPREAD_MASK, ra = LIGHT_ROUND_SPREAD.
#   Clobbers t0, t3.
.macro BLEND_COVERAGE
    li      t3, AA_FULL
    bge     t1, t3, .Lwhole\@
    xori    t3, a0, FB_PAIR_XOR
    lhu     t0, 0(t3)                   # what is behind
    slli    t3, t0, RGB565_SPREAD_SHIFT
    or      t0, t0, t3
    and     t0, t0, t5
    sub     t2, t2, t0
    mul     t2, t2, t1
    slli    t0, t0, AA_SHIFT
    add     t2, t2, t0
    add     t2, t2, ra
    srli    t2, t2, AA_SHIFT
    and     t2, t2, t5
.Lwhole\@:
.endm

# FILL textured, gouraud, affine, depth16, aa
#   One fill loop (registers: see raster_fills): every row of the bounding
#   box from the first inside pixel to the first outside one after it;
#   per pixel the depth test, then the colour: the flat colour t4, the base
#   colour a5 times the Gouraud intensity, or the texel (perspective-correct
#   or affine, nearest, repeating) times the face's or the Gouraud
#   intensity. With aa (a coverage fill, antialias = edge), the edge
#   functions are moved out by half a pixel on silhouette edges (raster_
#   triangle), and each pixel's colour is blended by its coverage
#   (COVERAGE, DEPTH_TEST_AA, BLEND_COVERAGE). Ends at 90 (raster_triangle's
#   epilogue).
.macro FILL textured, gouraud, affine, depth16, aa=0
    .if \textured
    la      t0, raster_texture
    ld      a5, 0(t0)
    la      t0, raster_tex_w
    ld      a6, 0(t0)
    la      t0, raster_tex_h
    ld      a7, 0(t0)
    .endif
    li      t5, RGB565_SPREAD_MASK
    .if \textured || \gouraud || \aa
    li      ra, LIGHT_ROUND_SPREAD
    .endif
    .if \gouraud && !\textured
    slli    t0, t4, RGB565_SPREAD_SHIFT
    or      a5, t4, t0
    and     a5, a5, t5
    .endif
1:  mv      s0, s6
    mv      s1, s7
    mv      s2, s8
    mv      a0, a3
    SKIP_TO_INSIDE
3:  sub     t0, a0, a3                  # 2 (x - xmin)
    .if \depth16
    add     a1, t6, t0
    .else
    slli    t1, t0, 1
    add     a1, t6, t1
    .endif
    PLANES_AT_X \textured, \gouraud, \affine
4:
    .if \aa
    COVERAGE
    DEPTH_TEST_AA \depth16, \gouraud
    .else
    DEPTH_TEST \depth16, \gouraud
    .endif
    .if \textured
    .if \affine
    fcvt.lu.s t2, fa2, rtz              # texel column, row
    fcvt.lu.s t3, fa3, rtz
    .else
    fdiv.s  ft9, ft8, fa1               # w
    fmul.s  ft10, fa2, ft9              # texel column
    fmul.s  ft11, fa3, ft9              # texel row
    fcvt.lu.s t2, ft10, rtz             # (negative rounding noise -> 0)
    fcvt.lu.s t3, ft11, rtz
    .endif
    bgeu    t2, a6, 10f                 # repeat
5:  bgeu    t3, a7, 11f
6:  mul     t3, t3, a6
    add     t2, t2, t3
    slli    t2, t2, 1
    add     t2, t2, a5
    lhu     t2, 0(t2)                   # texel
    slli    t3, t2, RGB565_SPREAD_SHIFT # light: all channels times k / 64
    or      t2, t2, t3
    and     t2, t2, t5
    mul     t2, t2, t4
    .elseif \gouraud
    mul     t2, a5, t4                  # the base colour times k / 64
    .endif
    .if \textured || \gouraud
    add     t2, t2, ra                  # rounded to nearest
    srli    t2, t2, LIGHT_SHIFT
    and     t2, t2, t5
    .if \aa
    BLEND_COVERAGE
    .endif
    srli    t3, t2, RGB565_SPREAD_SHIFT
    or      t2, t2, t3
    xori    t3, a0, FB_PAIR_XOR
    sh      t2, 0(t3)
    .elseif \aa
    slli    t2, t4, RGB565_SPREAD_SHIFT # the flat colour, spread
    or      t2, t2, t4
    and     t2, t2, t5
    BLEND_COVERAGE
    srli    t3, t2, RGB565_SPREAD_SHIFT
    or      t2, t2, t3
    xori    t3, a0, FB_PAIR_XOR
    sh      t2, 0(t3)
    .else
    xori    t2, a0, FB_PAIR_XOR
    sh      t4, 0(t2)
    .endif
7:  NEXT_PIXEL \textured, \gouraud, \affine, \depth16
8:  add     s6, s6, s9                  # next row
    add     s7, s7, s10
    add     s8, s8, s11
    addi    a3, a3, FB_ROW_BYTES
    addi    a2, a2, FB_ROW_BYTES
    .if \depth16
    addi    t6, t6, DEPTH16_ROW_BYTES
    .else
    addi    t6, t6, DEPTH_ROW_BYTES
    .endif
    fadd.s  ft0, ft0, ft4
    .if \textured
    .if !\affine
    fadd.s  ft1, ft1, ft5
    .endif
    fadd.s  ft2, ft2, ft6
    fadd.s  ft3, ft3, ft7
    .endif
    .if \gouraud
    fadd.s  fs2, fs2, fs3
    .endif
    addi    a4, a4, -1
    bnez    a4, 1b
    j       90f
    .if \textured
10: remu    t2, t2, a6                  # texel column past the width
    j       5b
11: remu    t3, t3, a7
    j       6b
    .endif
.endm

# FILTERED gouraud, affine, depth16, mipmap
#   A textured fill with filtering (filter = bilinear, or mipmap with
#   mipmap = 1): as FILL, but each pixel blends the four texels around
#   (s - 1/2, t - 1/2) by the fractions, rounded to 1/32 texel, lit by k in the same
#   multiplication (render.inc BLEND_*): round((sum of w c) k / 2^16) per
#   channel, one rounding. With mipmap, the level comes first (render.inc:
#   (e + 1) >> 1 from the float exponent e of rho^2 = |det H| w^3, or the
#   triangle's constant rho^2 with affine planes) and indexes the level
#   table (raster_mip_table) for the level's texels, size and scale.
#   The texel coordinate planes are 32 times the texel column and row
#   (raster_triangle scales them). Needs more registers than FILL: the row
#   state (s6..s11, a3, t6, a4) lives in raster_triangle's frame (RT_ROW_*)
#   and the span loop uses those registers freely; fs4 (the constant rho^2)
#   and fs5 are saved here. Registers of the span loop beyond FILL's:
#   s9 BLEND_SPREAD_MUL, t5 BLEND_SPREAD_MASK, ra BLEND_ROUND, s10 the level
#   table's entry for level 0 (mipmap); temporaries t0..t3, t6, a3, a4,
#   s6 (fx), s7 (fy), s8 (x1), fs5. With aa, a coverage fill as FILL's,
#   the coverage kept on the stack (RT_AA) over the texel blend. Ends at 90
#   (raster_triangle's epilogue).
.macro FILTERED gouraud, affine, depth16, mipmap, aa=0
    sd      s6, RT_ROW_E0(sp)
    sd      s7, RT_ROW_E1(sp)
    sd      s8, RT_ROW_E2(sp)
    sd      s9, RT_ROW_D0(sp)
    sd      s10, RT_ROW_D1(sp)
    sd      s11, RT_ROW_D2(sp)
    sd      a3, RT_ROW_FB(sp)
    sd      t6, RT_ROW_DEPTH(sp)
    sd      a4, RT_ROW_LEFT(sp)
    fsd     fs4, RT_FSAVE2(sp)
    fsd     fs5, RT_FSAVE2 + 8(sp)
    .if \mipmap
    la      t0, raster_mip_rho2
    add     t0, t0, tp                  # (this hart's)
    flw     fs4, 0(t0)
    la      t0, raster_mip_table
    ld      s10, 0(t0)
    li      t0, MIP_TABLE_BIAS << MIP_ENTRY_SHIFT
    add     s10, s10, t0                # s10 = level 0's entry
    .else
    la      t0, raster_texture
    ld      a5, 0(t0)
    la      t0, raster_tex_w
    ld      a6, 0(t0)
    la      t0, raster_tex_h
    ld      a7, 0(t0)
    .endif
    li      t5, BLEND_SPREAD_MASK
    li      s9, BLEND_SPREAD_MUL
    li      ra, BLEND_ROUND
1:  ld      s0, RT_ROW_E0(sp)
    ld      s1, RT_ROW_E1(sp)
    ld      s2, RT_ROW_E2(sp)
    ld      a0, RT_ROW_FB(sp)
    SKIP_TO_INSIDE
3:  ld      t6, RT_ROW_FB(sp)
    sub     t0, a0, t6                  # 2 (x - xmin)
    ld      t6, RT_ROW_DEPTH(sp)
    .if \depth16
    add     a1, t6, t0
    .else
    slli    t1, t0, 1
    add     a1, t6, t1
    .endif
    PLANES_AT_X 1, \gouraud, \affine
4:
    .if \aa
    COVERAGE
    DEPTH_TEST_AA \depth16, \gouraud
    sd      t1, RT_AA(sp)
    .else
    DEPTH_TEST \depth16, \gouraud
    .endif
    .if \affine
    fmv.s   ft10, fa2                   # 32 s, 32 t
    fmv.s   ft11, fa3
    .else
    fdiv.s  ft9, ft8, fa1               # w
    fmul.s  ft10, fa2, ft9              # 32 s, 32 t
    fmul.s  ft11, fa3, ft9
    .endif
    .if \mipmap
    .if \affine
    fmv.x.w t0, fs4                     # rho^2, the triangle's
    .else
    fmul.s  fs5, ft9, ft9
    fmul.s  fs5, fs5, ft9
    fmul.s  fs5, fs5, fs4               # rho^2 = |det H| w^3
    fmv.x.w t0, fs5
    .endif
    srliw   t0, t0, F32_EXP_SHIFT
    andi    t0, t0, F32_EXP_MASK        # e + bias (a noise sign bit dropped)
    addi    t0, t0, 1 - F32_EXP_BIAS
    srai    t0, t0, 1                   # the level, -63 .. 64
    slli    t0, t0, MIP_ENTRY_SHIFT
    add     t0, t0, s10
    ld      a5, MIP_PIXELS(t0)
    lwu     a6, MIP_W(t0)
    lwu     a7, MIP_H(t0)
    flw     fs5, MIP_SCALE_S(t0)
    fmul.s  ft10, ft10, fs5
    flw     fs5, MIP_SCALE_T(t0)
    fmul.s  ft11, ft11, fs5
    .endif
    fcvt.l.s t2, ft10, rne              # 32 s, 32 t to the nearest 1/32 texel
    fcvt.l.s t3, ft11, rne
    addi    t2, t2, -TEXEL_HALF_FRACTION    # floor(32 (s - 1/2)): texel centres
    addi    t3, t3, -TEXEL_HALF_FRACTION
    andi    s6, t2, TEXEL_FRACTION_MASK     # fx, fy in 1/32
    andi    s7, t3, TEXEL_FRACTION_MASK
    srai    t2, t2, TEXEL_FRACTION_BITS     # x0, y0
    srai    t3, t3, TEXEL_FRACTION_BITS
    bgeu    t2, a6, 10f                 # x0 outside 0 .. W - 1: repeat
5:  addi    s8, t2, 1                   # x1
    bltu    s8, a6, 12f
    li      s8, 0
12: bgeu    t3, a7, 11f
6:  addi    a3, t3, 1                   # y1
    bltu    a3, a7, 13f
    li      a3, 0
13: mul     t3, t3, a6
    mul     a3, a3, a6
    slli    t3, t3, 1
    add     t3, t3, a5                  # row y0
    slli    a3, a3, 1
    add     a3, a3, a5                  # row y1
    slli    t2, t2, 1
    slli    s8, s8, 1
    add     t0, t3, t2
    lhu     t0, 0(t0)                   # (x0, y0)
    add     t1, t3, s8
    lhu     t1, 0(t1)                   # (x1, y0)
    add     t6, a3, t2
    lhu     t6, 0(t6)                   # (x0, y1)
    add     a4, a3, s8
    lhu     a4, 0(a4)                   # (x1, y1)
    mul     t0, t0, s9                  # each spread (BLEND_SPREAD_*)
    and     t0, t0, t5
    mul     t1, t1, s9
    and     t1, t1, t5
    mul     t6, t6, s9
    and     t6, t6, t5
    mul     a4, a4, s9
    and     a4, a4, t5
    # c0 (32 - f) + c1 f = 32 c0 + (c1 - c0) f: exact in the fields even
    # where c1 - c0 borrows across them, since the result fits each field
    sub     t1, t1, t0
    mul     t1, t1, s6
    slli    t0, t0, TEXEL_FRACTION_BITS
    add     t0, t0, t1                  # row y0 blended (32 c)
    sub     a4, a4, t6
    mul     a4, a4, s6
    slli    t6, t6, TEXEL_FRACTION_BITS
    add     t6, t6, a4                  # row y1 blended
    sub     t6, t6, t0
    mul     t6, t6, s7
    slli    t0, t0, TEXEL_FRACTION_BITS
    add     t0, t0, t6                  # 1024 c
    mul     t0, t0, t4                  # lit: 1024 c k, up to 2^16 c
    add     t0, t0, ra                  # rounded to nearest
    srli    t1, t0, BLEND_R_SHIFT
    slli    t1, t1, RGB565_R_SHIFT
    srli    t2, t0, BLEND_G_SHIFT
    andi    t2, t2, BLEND_G_MASK
    or      t1, t1, t2
    srli    t2, t0, BLEND_B_SHIFT
    andi    t2, t2, BLEND_B_MASK
    or      t1, t1, t2
    .if \aa
    # the lit texel t1 over what is behind, by the coverage (BLEND_COVERAGE's
    # arithmetic with this loop's registers)
    ld      t6, RT_AA(sp)
    li      t3, AA_FULL
    bge     t6, t3, .Lwhole\@
    li      t0, RGB565_SPREAD_MASK
    slli    t3, t1, RGB565_SPREAD_SHIFT
    or      t2, t1, t3
    and     t2, t2, t0
    xori    t3, a0, FB_PAIR_XOR
    lhu     t1, 0(t3)                   # what is behind
    slli    t3, t1, RGB565_SPREAD_SHIFT
    or      t1, t1, t3
    and     t1, t1, t0
    sub     t2, t2, t1
    mul     t2, t2, t6
    slli    t1, t1, AA_SHIFT
    add     t2, t2, t1
    li      t1, LIGHT_ROUND_SPREAD
    add     t2, t2, t1
    srli    t2, t2, AA_SHIFT
    and     t2, t2, t0
    srli    t1, t2, RGB565_SPREAD_SHIFT
    or      t1, t1, t2
.Lwhole\@:
    .endif
    xori    t2, a0, FB_PAIR_XOR
    sh      t1, 0(t2)
7:  NEXT_PIXEL 1, \gouraud, \affine, \depth16
8:  ld      t0, RT_ROW_E0(sp)           # next row
    ld      t1, RT_ROW_D0(sp)
    add     t0, t0, t1
    sd      t0, RT_ROW_E0(sp)
    ld      t0, RT_ROW_E1(sp)
    ld      t1, RT_ROW_D1(sp)
    add     t0, t0, t1
    sd      t0, RT_ROW_E1(sp)
    ld      t0, RT_ROW_E2(sp)
    ld      t1, RT_ROW_D2(sp)
    add     t0, t0, t1
    sd      t0, RT_ROW_E2(sp)
    ld      t0, RT_ROW_FB(sp)
    addi    t0, t0, FB_ROW_BYTES
    sd      t0, RT_ROW_FB(sp)
    addi    a2, a2, FB_ROW_BYTES
    ld      t0, RT_ROW_DEPTH(sp)
    .if \depth16
    addi    t0, t0, DEPTH16_ROW_BYTES
    .else
    addi    t0, t0, DEPTH_ROW_BYTES
    .endif
    sd      t0, RT_ROW_DEPTH(sp)
    fadd.s  ft0, ft0, ft4
    .if !\affine
    fadd.s  ft1, ft1, ft5
    .endif
    fadd.s  ft2, ft2, ft6
    fadd.s  ft3, ft3, ft7
    .if \gouraud
    fadd.s  fs2, fs2, fs3
    .endif
    ld      t0, RT_ROW_LEFT(sp)
    addi    t0, t0, -1
    sd      t0, RT_ROW_LEFT(sp)
    bnez    t0, 1b
    fld     fs4, RT_FSAVE2(sp)
    fld     fs5, RT_FSAVE2 + 8(sp)
    j       90f
10: rem     t2, t2, a6                  # x0 past either side: into 0 .. W - 1
    bgez    t2, 5b
    add     t2, t2, a6
    j       5b
11: rem     t3, t3, a7
    bgez    t3, 6b
    add     t3, t3, a7
    j       6b
.endm

    .if (FB_ROW_BYTES % CLEAR_UNROLL_BYTES) || (DEPTH16_ROW_BYTES % CLEAR_UNROLL_BYTES)
    .error "raster_clear clears whole rows CLEAR_UNROLL_BYTES at a time"
    .endif
    .if DEPTH16_ROW_BYTES != DEPTH_ROW_BYTES >> 1
    .error "raster_triangle steps depth rows by DEPTH_ROW_BYTES >> (16-bit depth)"
    .endif

    .text
    .globl raster_begin
# raster_begin
#   What: sets the framebuffer that the following drawing goes to.
#   Arguments: a0 = framebuffer (LCD_FB_BYTES, 64-aligned).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_begin:
    la      t0, raster_fb
    sd      a0, 0(t0)
    ret

    .globl raster_set_band
# raster_set_band
#   What: sets the rows the calling hart draws from now on: raster_clear and
#         raster_triangle touch rows a0 .. a1 - 1 only (the two harts draw
#         disjoint bands of one frame, main.S). Lines (raster_segment,
#         raster_line) ignore it. Until it is first called the band is empty.
#   Arguments: a0 = first row, a1 = the row past the last (0 <= a0 <= a1 <=
#              LCD_HEIGHT).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_set_band:
    la      t0, raster_band
    add     t0, t0, tp
    sw      a0, BAND_FIRST(t0)
    sw      a1, BAND_END(t0)
    ret

    .globl raster_set_sample
# raster_set_sample
#   What: antialias = supersample: the sample the calling hart's triangles
#         are drawn for from now on (raster_triangle moves their corners by
#         minus the offset, so pixel centres sample the offset's point).
#   Arguments: a0, a1 = the offset from the pixel centre, x and y in Q4
#              (0, 0: the centre, as without supersampling).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_set_sample:
    la      t0, raster_sample
    add     t0, t0, tp
    sw      a0, SAMPLE_OFFSET_X(t0)
    sw      a1, SAMPLE_OFFSET_Y(t0)
    ret

    .globl raster_set_sums
# raster_set_sums
#   What: sets the sums buffer of raster_accumulate.
#   Arguments: a0 = the buffer (SUM_BUFFER_BYTES).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_set_sums:
    la      t0, raster_sums
    sd      a0, 0(t0)
    ret

# SUMS_BAND
#   t0 = the framebuffer at the calling hart's band, t1 = past its end,
#   t2 = the sums at the band (the same pixel order); empty band: on to 9.
#   Clobbers t3, t4.
.macro SUMS_BAND
    la      t3, raster_band
    add     t3, t3, tp
    lwu     t4, BAND_FIRST(t3)
    lwu     t1, BAND_END(t3)
    bgeu    t4, t1, 9f
    li      t3, LCD_WIDTH
    mul     t4, t4, t3                  # first pixel
    mul     t1, t1, t3                  # past the last
    la      t3, raster_sums
    ld      t2, 0(t3)
    slli    t3, t4, SUM_SHIFT
    add     t2, t2, t3
    la      t3, raster_fb
    ld      t0, 0(t3)
    slli    t1, t1, FB_PIXEL_SHIFT
    add     t1, t1, t0
    slli    t4, t4, FB_PIXEL_SHIFT
    add     t0, t0, t4
.endm

    .globl raster_accumulate
# raster_accumulate
#   What: antialias = supersample: the calling hart's band of the
#         framebuffer (one sample's colours) into the sums (render.inc
#         SUM_*): the first sample sets them, the others add to them, and
#         the last, added, leaves each pixel's mean in the framebuffer,
#         per channel rounded to nearest (halves up).
#   Arguments: a0 = SAMPLE_FIRST, SAMPLE_MORE or SAMPLE_LAST.
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_accumulate:
    SUMS_BAND
    li      t5, SUM_RB_MASK
    li      a1, SUM_ROUND
    li      a2, SUM_R_MASK
    li      a3, SAMPLE_LAST
1:  lhu     t3, 0(t0)                   # c spread into the sum's fields
    and     t4, t3, t5
    andi    t6, t3, SUM_G_MASK
    slli    t6, t6, SUM_G_SHIFT
    or      t4, t4, t6
    beqz    a0, 2f                      # (SAMPLE_FIRST)
    lwu     t3, 0(t2)
    add     t4, t4, t3
    beq     a0, a3, 3f
2:  sw      t4, 0(t2)
    addi    t0, t0, LCD_BYTES_PER_PIXEL
    addi    t2, t2, SUM_BYTES_PER_PIXEL
    bltu    t0, t1, 1b
    ret
3:  add     t4, t4, a1                  # the last: the mean
    srli    t4, t4, SUM_MEAN_SHIFT
    andi    t3, t4, SUM_B_MASK          # (each mean where one sample's channel
    and     t6, t4, a2                  # is in the sum, the remainders below it)
    or      t3, t3, t6
    srli    t6, t4, SUM_G_SHIFT
    andi    t6, t6, SUM_G_MASK
    or      t3, t3, t6
    sh      t3, 0(t0)
    addi    t0, t0, LCD_BYTES_PER_PIXEL
    addi    t2, t2, SUM_BYTES_PER_PIXEL
    bltu    t0, t1, 1b
9:  ret

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
    addi    sp, sp, -112
    sd      ra, 104(sp)
    sd      s0, 96(sp)
    sd      s1, 88(sp)
    sd      s2, 80(sp)
    sd      s3, 72(sp)
    sd      s4, 64(sp)
    sd      s5, 56(sp)
    sd      s6, 48(sp)
    sd      s7, 40(sp)
    sd      s8, 32(sp)
    sd      s9, 24(sp)
    sd      s10, 16(sp)
    sd      s11, 8(sp)
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
    ld      s11, 8(sp)
    ld      s10, 16(sp)
    ld      s9, 24(sp)
    ld      s8, 32(sp)
    ld      s7, 40(sp)
    ld      s6, 48(sp)
    ld      s5, 56(sp)
    ld      s4, 64(sp)
    ld      s3, 72(sp)
    ld      s2, 80(sp)
    ld      s1, 88(sp)
    ld      s0, 96(sp)
    ld      ra, 104(sp)
    addi    sp, sp, 112
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
    addi    sp, sp, -32
    sd      s0, 24(sp)
    sd      s1, 16(sp)
    sd      s2, 8(sp)
    sd      s3, 0(sp)
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
    ld      s3, 0(sp)
    ld      s2, 8(sp)
    ld      s1, 16(sp)
    ld      s0, 24(sp)
    addi    sp, sp, 32
    ret

    .globl raster_set_depth
# raster_set_depth
#   What: sets the depth buffer and its format for the following frames.
#   Arguments: a0 = the buffer (LCD_PIXELS entries, 64-aligned), a1 =
#              DEPTH_FLOAT32 (f32 z / w) or DEPTH_INT16 (u16, render.inc).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_set_depth:
    la      t0, raster_depth
    sd      a0, 0(t0)
    la      t0, raster_depth_mode
    sd      a1, 0(t0)
    ret

    .globl raster_clear
# raster_clear
#   What: fills this hart's band (raster_set_band) of the framebuffer with
#         one colour and, when asked, of the depth buffer with the far plane
#         (DEPTH_CLEAR or DEPTH16_CLEAR). (Rows are whole multiples of
#         CLEAR_UNROLL_BYTES in both buffers.)
#   Arguments: a0 = RGB565 colour, a1 = 1 to clear the depth buffer too.
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_clear:
    slli    t0, a0, 48                  # four pixels per doubleword
    srli    t0, t0, 48
    slli    t1, t0, 16
    or      t0, t0, t1
    slli    t1, t0, 32
    or      t0, t0, t1
    la      t4, raster_band
    add     t4, t4, tp
    lwu     t5, BAND_FIRST(t4)          # t5, t6 = the band's rows
    lwu     t6, BAND_END(t4)
    bgeu    t5, t6, 3f                  # empty
    la      t2, raster_fb
    ld      t2, 0(t2)
    li      t4, FB_ROW_BYTES
    mul     t3, t6, t4
    add     t3, t3, t2
    mul     t4, t5, t4
    add     t2, t2, t4
1:  sd      t0, 0(t2)
    sd      t0, 8(t2)
    sd      t0, 16(t2)
    sd      t0, 24(t2)
    sd      t0, 32(t2)
    sd      t0, 40(t2)
    sd      t0, 48(t2)
    sd      t0, 56(t2)
    addi    t2, t2, CLEAR_UNROLL_BYTES
    bltu    t2, t3, 1b
    beqz    a1, 3f
    la      t2, raster_depth
    ld      t2, 0(t2)
    la      t0, raster_depth_mode
    ld      t0, 0(t0)
    bnez    t0, 4f
    li      t0, DEPTH_CLEAR             # two f32 per doubleword
    slli    t1, t0, 32
    or      t0, t0, t1
    li      t4, DEPTH_ROW_BYTES
    j       5f
4:  li      t0, DEPTH16_CLEAR_DWORD     # four u16 per doubleword
    li      t4, DEPTH16_ROW_BYTES
5:  mul     t3, t6, t4
    add     t3, t3, t2
    mul     t4, t5, t4
    add     t2, t2, t4
2:  sd      t0, 0(t2)
    sd      t0, 8(t2)
    sd      t0, 16(t2)
    sd      t0, 24(t2)
    sd      t0, 32(t2)
    sd      t0, 40(t2)
    sd      t0, 48(t2)
    sd      t0, 56(t2)
    addi    t2, t2, CLEAR_UNROLL_BYTES
    bltu    t2, t3, 2b
3:  ret

    .globl raster_triangle
# raster_triangle
#   What: draws the rows of one triangle that lie in this hart's band
#         (raster_set_band), depth-tested (see the file comment).
#   Arguments: a0 = three raster vertices in a row (RV_BYTES each,
#              render.inc; RV_K only read with RASTER_GOURAUD, RV_S, RV_T
#              only with RASTER_TEXTURED), a1 = 1 to drop back faces,
#              a2 = the colour: flat fill, RGB565 as drawn (or, with
#              RASTER_GOURAUD, before lighting); textured, the intensity k
#              0 .. LIGHT_ONE (unused with RASTER_GOURAUD), a3 = RASTER_*
#              flags (render.inc). The depth format is raster_set_depth's.
#   Results: none.
#         With RASTER_EDGE_AA the corners' RV_OPP_* say what lies across
#         each edge (silhouette or not: a coverage fill for a silhouette).
#         The corners are moved by minus this hart's sample offset
#         (raster_set_sample; 0, 0 unless supersampling).
#   Clobbers: only ABI temporaries. The pixel loops use every integer
#         register but sp, gp and tp (ra holds a constant, saved here), every
#         temporary and argument float register, and fs0..fs3 and fs6..fs8
#         (saved here: the Gouraud intensity, the coverage fills' scales;
#         the filtered fills save and use fs4, fs5 too).
raster_triangle:
    addi    sp, sp, -RT_FRAME
    sd      s0, RT_SAVE + 0(sp)
    sd      s1, RT_SAVE + 8(sp)
    sd      s2, RT_SAVE + 16(sp)
    sd      s3, RT_SAVE + 24(sp)
    sd      s4, RT_SAVE + 32(sp)
    sd      s5, RT_SAVE + 40(sp)
    sd      s6, RT_SAVE + 48(sp)
    sd      s7, RT_SAVE + 56(sp)
    sd      s8, RT_SAVE + 64(sp)
    sd      s9, RT_SAVE + 72(sp)
    sd      s10, RT_SAVE + 80(sp)
    sd      s11, RT_SAVE + 88(sp)
    fsd     fs0, RT_FSAVE + 0(sp)
    fsd     fs1, RT_FSAVE + 8(sp)
    fsd     fs2, RT_FSAVE + 16(sp)
    fsd     fs3, RT_FSAVE + 24(sp)
    fsd     fs6, RT_FSAVE3 + 0(sp)
    fsd     fs7, RT_FSAVE3 + 8(sp)
    fsd     fs8, RT_FSAVE3 + 16(sp)
    sd      ra, RT_RA(sp)
    mv      t4, a2                      # t4 = colour / intensity (kept to the end)
    mv      t5, a3                      # t5 = RASTER_* flags (until the loops)

    # --- corners: t0, t1, t2 = records; s0..s5 = x0, y0, x1, y1, x2, y2
    mv      t0, a0
    addi    t1, a0, RV_BYTES
    addi    t2, a0, 2 * RV_BYTES
    lw      s0, RV_X(t0)
    lw      s1, RV_Y(t0)
    lw      s2, RV_X(t1)
    lw      s3, RV_Y(t1)
    lw      s4, RV_X(t2)
    lw      s5, RV_Y(t2)
    la      t3, raster_sample           # antialias = supersample: the corners
    add     t3, t3, tp                  # moved by minus the sample's offset
    lw      a4, SAMPLE_OFFSET_X(t3)     # (0, 0 otherwise)
    lw      a5, SAMPLE_OFFSET_Y(t3)
    sub     s0, s0, a4
    sub     s2, s2, a4
    sub     s4, s4, a4
    sub     s1, s1, a5
    sub     s3, s3, a5
    sub     s5, s5, a5
    # s6 = signed area (Q8) = (x1 - x0)(y2 - y0) - (x2 - x0)(y1 - y0)
    sub     a4, s2, s0
    sub     a5, s5, s1
    mul     a4, a4, a5
    sub     a5, s4, s0
    sub     a6, s3, s1
    mul     a5, a5, a6
    sub     s6, a4, a5
    beqz    s6, 90f                     # degenerate
    bltz    s6, 1f                      # counter-clockwise as seen: front
    bnez    a1, 90f                     # back face, culled
    j       2f
1:  mv      t3, t1                      # front face: corners 1 and 2 swap
    mv      t1, t2
    mv      t2, t3
    mv      t3, s2
    mv      s2, s4
    mv      s4, t3
    mv      t3, s3
    mv      s3, s5
    mv      s5, t3
    neg     s6, s6
2:
    # --- antialias = edge: which edges are silhouettes (RASTER_SILHOUETTE_*
    # in t5); edge k runs from corner k + 1 to corner k + 2
    andi    t3, t5, RASTER_EDGE_AA
    beqz    t3, 29f
    SILHOUETTE t0, s2, s3, s4, s5, 0
    SILHOUETTE t1, s4, s5, s0, s1, 1
    SILHOUETTE t2, s0, s1, s2, s3, 2
29:
    # --- bounding box of the pixel centres: a4..a7 = xmin, xmax, ymin, ymax
    mv      a4, s0                      # min x
    ble     a4, s2, 3f
    mv      a4, s2
3:  ble     a4, s4, 3f
    mv      a4, s4
3:  mv      a5, s0                      # max x
    bge     a5, s2, 3f
    mv      a5, s2
3:  bge     a5, s4, 3f
    mv      a5, s4
3:  mv      a6, s1                      # min y
    ble     a6, s3, 3f
    mv      a6, s3
3:  ble     a6, s5, 3f
    mv      a6, s5
3:  mv      a7, s1                      # max y
    bge     a7, s3, 3f
    mv      a7, s3
3:  bge     a7, s5, 3f
    mv      a7, s5
3:  li      t3, RASTER_SILHOUETTE_MASK  # coverage reaches half a pixel past
    and     t3, t5, t3                  # a silhouette edge: the box grows
    beqz    t3, 39f
    addi    a4, a4, -AA_BOX_GROW
    addi    a5, a5, AA_BOX_GROW
    addi    a6, a6, -AA_BOX_GROW
    addi    a7, a7, AA_BOX_GROW
39: addi    a4, a4, SUBPIXEL_CEIL       # first centre >= min: (min + 7) >> 4
    srai    a4, a4, SUBPIXEL_BITS
    addi    a5, a5, -SUBPIXEL_HALF      # last centre <= max: (max - 8) >> 4
    srai    a5, a5, SUBPIXEL_BITS
    addi    a6, a6, SUBPIXEL_CEIL
    srai    a6, a6, SUBPIXEL_BITS
    addi    a7, a7, -SUBPIXEL_HALF
    srai    a7, a7, SUBPIXEL_BITS
    bgez    a4, 4f                      # clip to the screen
    li      a4, 0
4:  bgez    a6, 4f
    li      a6, 0
4:  li      t3, LCD_WIDTH - 1
    ble     a5, t3, 4f
    mv      a5, t3
4:  li      t3, LCD_HEIGHT - 1
    ble     a7, t3, 4f
    mv      a7, t3
4:  bgt     a4, a5, 90f                 # nothing on screen
    bgt     a6, a7, 90f
    la      t3, raster_band             # nothing in this hart's band
    add     t3, t3, tp
    lwu     a2, BAND_FIRST(t3)
    bgt     a2, a7, 90f
    lwu     a3, BAND_END(t3)
    bge     a6, a3, 90f
    bge     a2, a3, 90f                 # (an empty band)
    slli    a2, a4, SUBPIXEL_BITS       # a2, a3 = first pixel centre (Q4)
    addi    a2, a2, SUBPIXEL_HALF
    slli    a3, a6, SUBPIXEL_BITS
    addi    a3, a3, SUBPIXEL_HALF

    # --- attribute planes (float). fa0..fa3 = corner differences (Q4)
    # times 16 / area, ft9, ft10 = first centre - corner 0 (pixels).
    sub     t3, s2, s0
    fcvt.s.l fa0, t3
    sub     t3, s3, s1
    fcvt.s.l fa1, t3
    sub     t3, s4, s0
    fcvt.s.l fa2, t3
    sub     t3, s5, s1
    fcvt.s.l fa3, t3
    fcvt.s.l ft9, s6
    li      t3, SUBPIXEL_ONE
    fcvt.s.w ft10, t3
    fdiv.s  ft9, ft10, ft9              # 16 / area
    fmul.s  fa0, fa0, ft9
    fmul.s  fa1, fa1, ft9
    fmul.s  fa2, fa2, ft9
    fmul.s  fa3, fa3, ft9
    li      t3, F32_Q4_TO_PIXEL
    fmv.w.x ft8, t3
    sub     t3, a2, s0
    fcvt.s.l ft9, t3
    fmul.s  ft9, ft9, ft8
    sub     t3, a3, s1
    fcvt.s.l ft10, t3
    fmul.s  ft10, ft10, ft8
    # depth: fa4 = per pixel right, ft4 = per row, ft0 = at the first centre;
    # z / w itself, or DEPTH16_NEAR + z / w * DEPTH16_SPAN for 16-bit depth
    flw     ft11, RV_Z(t0)
    flw     ft4, RV_Z(t1)
    flw     ft0, RV_Z(t2)
    la      t3, raster_depth_mode
    ld      t3, 0(t3)
    beqz    t3, 5f
    li      t3, F32_DEPTH16_SPAN
    fmv.w.x ft5, t3
    li      t3, F32_DEPTH16_NEAR
    fmv.w.x ft6, t3
    fmadd.s ft11, ft11, ft5, ft6
    fmadd.s ft4, ft4, ft5, ft6
    fmadd.s ft0, ft0, ft5, ft6
5:  GRADIENT ft11, ft4, ft0, fa4, ft4, ft0
    andi    t3, t5, RASTER_GOURAUD
    beqz    t3, 5f
    # Gouraud: the intensity k (fs0 at the pixel, fs1 per pixel right, fs2 at
    # the row's first pixel, fs3 per row)
    flw     ft11, RV_K(t0)
    flw     fs3, RV_K(t1)
    flw     fs2, RV_K(t2)
    GRADIENT ft11, fs3, fs2, fs1, fs3, fs2
5:  andi    t3, t5, RASTER_TEXTURED
    beqz    t3, 6f
    andi    t3, t5, RASTER_AFFINE
    beqz    t3, 5f
    # affine: the texel column (fa6, ft6, ft2) and row (fa7, ft7, ft3) are
    # planes in screen space themselves
    flw     ft11, RV_S(t0)
    flw     ft6, RV_S(t1)
    flw     ft2, RV_S(t2)
    GRADIENT ft11, ft6, ft2, fa6, ft6, ft2
    flw     ft11, RV_T(t0)
    flw     ft7, RV_T(t1)
    flw     ft3, RV_T(t2)
    GRADIENT ft11, ft7, ft3, fa7, ft7, ft3
    j       6f
    # perspective-correct: 1 / w (fa5, ft5, ft1), u / w (fa6, ft6, ft2),
    # v / w (fa7, ft7, ft3)
5:  flw     ft11, RV_Q(t0)
    flw     ft5, RV_Q(t1)
    flw     ft1, RV_Q(t2)
    GRADIENT ft11, ft5, ft1, fa5, ft5, ft1
    flw     ft11, RV_S(t0)
    flw     ft8, RV_Q(t0)
    fmul.s  ft11, ft11, ft8
    flw     ft6, RV_S(t1)
    flw     ft8, RV_Q(t1)
    fmul.s  ft6, ft6, ft8
    flw     ft2, RV_S(t2)
    flw     ft8, RV_Q(t2)
    fmul.s  ft2, ft2, ft8
    GRADIENT ft11, ft6, ft2, fa6, ft6, ft2
    flw     ft11, RV_T(t0)
    flw     ft8, RV_Q(t0)
    fmul.s  ft11, ft11, ft8
    flw     ft7, RV_T(t1)
    flw     ft8, RV_Q(t1)
    fmul.s  ft7, ft7, ft8
    flw     ft3, RV_T(t2)
    flw     ft8, RV_Q(t2)
    fmul.s  ft3, ft3, ft8
    GRADIENT ft11, ft7, ft3, fa7, ft7, ft3
    li      t3, F32_ONE
    fmv.w.x ft8, t3                     # ft8 = 1 (for 1 / (1 / w))
6:  andi    t3, t5, RASTER_FILTERED     # (only ever with RASTER_TEXTURED)
    beqz    t3, 62f
    # filtered fills interpolate 32 s and 32 t (render.inc TEXEL_FRACTION_*)
    li      t3, F32_TEXEL_FRACTIONS
    fmv.w.x ft9, t3
    fmul.s  fa6, fa6, ft9
    fmul.s  ft6, ft6, ft9
    fmul.s  ft2, ft2, ft9
    fmul.s  fa7, fa7, ft9
    fmul.s  ft7, ft7, ft9
    fmul.s  ft3, ft3, ft9
    andi    t3, t5, RASTER_MIPMAP
    beqz    t3, 62f
    # the footprint's area rho^2 (render.inc), 32^2 times with these planes:
    # affine, det J = s_x t_y - t_x s_y itself; perspective, det H of the
    # planes (u/w, v/w, 1/w), det J = det H w^3, w per pixel
    fmul.s  ft9, fa6, ft7
    fnmsub.s ft9, fa7, ft6, ft9         # s_x t_y - t_x s_y
    andi    t3, t5, RASTER_AFFINE
    bnez    t3, 61f
    fmul.s  ft10, fa7, ft5
    fnmsub.s ft10, ft7, fa5, ft10       # V_x Q_y - V_y Q_x
    fmul.s  ft11, fa6, ft5
    fnmsub.s ft11, ft6, fa5, ft11       # U_x Q_y - U_y Q_x
    fmul.s  ft9, ft9, ft1               # det H = Q (U_x V_y - U_y V_x)
    fmadd.s ft9, ft2, ft10, ft9         #   + U (V_x Q_y - V_y Q_x)
    fnmsub.s ft9, ft3, ft11, ft9        #   - V (U_x Q_y - U_y Q_x)
61: fabs.s  ft9, ft9
    li      t3, F32_TEXEL_FRACTIONS_INV2
    fmv.w.x ft10, t3
    fmul.s  ft9, ft9, ft10
    la      t3, raster_mip_rho2
    add     t3, t3, tp                  # (this hart's)
    fsw     ft9, 0(t3)
62:
    # --- edge functions: s6..s8 = at the first centre of the row, s3..s5 =
    # steps right, s9..s11 = steps down (edge k is opposite corner k)
    EDGE    s2, s3, s4, s5, s6, t0, s9  # corner 1 -> corner 2
    EDGE    s4, s5, s0, s1, s7, t1, s10 # corner 2 -> corner 0
    EDGE    s0, s1, s2, s3, s8, t2, s11 # corner 0 -> corner 1
    mv      s3, t0
    mv      s4, t1
    mv      s5, t2
    # coverage fills: silhouette edges moved out by half a pixel, hard ones
    # by one Q8 unit, and the scales that make their coverage (render.inc)
    li      t3, RASTER_SILHOUETTE_MASK
    and     t3, t5, t3
    beqz    t3, 69f
    AA_EDGE 0, s6, s3, s9, fs6
    AA_EDGE 1, s7, s4, s10, fs7
    AA_EDGE 2, s8, s5, s11, fs8
69:
    # --- pointers: a3 = framebuffer at (xmin, row), a2 = its end of row
    # (past xmax), t6 = depth at (xmin, row), a4 = rows left
    la      t3, raster_fb
    ld      t3, 0(t3)
    li      t0, FB_ROW_BYTES
    mul     t0, a6, t0
    add     t3, t3, t0
    slli    t0, a4, 1
    add     a3, t3, t0
    sub     t0, a5, a4
    addi    t0, t0, 1
    slli    t0, t0, 1
    add     a2, a3, t0
    li      t0, LCD_WIDTH               # t6 = depth + (W ymin + xmin) << shift
    mul     t0, a6, t0
    add     t0, t0, a4
    la      t3, raster_depth_mode
    ld      t1, 0(t3)                   # t1 = 16-bit depth
    li      t3, DEPTH_SHIFT
    sub     t3, t3, t1                  # (DEPTH16_SHIFT = DEPTH_SHIFT - 1)
    sll     t0, t0, t3
    la      t3, raster_depth
    ld      t6, 0(t3)
    add     t6, t6, t0
    sub     a4, a7, a6
    addi    a4, a4, 1
    # --- the band (raster_set_band): the rows past its end are dropped; the
    # rows above its first are stepped over exactly as the fill loops step
    # from row to row (integers by multiples, floats one addition a row), so
    # every value in the band is bit for bit what a whole-screen draw gives.
    la      t3, raster_band
    add     t3, t3, tp
    lwu     t0, BAND_END(t3)
    sub     t0, t0, a6                  # rows from ymin to the band's end
    ble     a4, t0, 63f
    mv      a4, t0
63: lwu     t0, BAND_FIRST(t3)
    sub     a0, t0, a6                  # a0 = rows above the band
    blez    a0, 65f
    sub     a4, a4, a0
    mul     t3, a0, s9                  # edge functions
    add     s6, s6, t3
    mul     t3, a0, s10
    add     s7, s7, t3
    mul     t3, a0, s11
    add     s8, s8, t3
    li      t3, FB_ROW_BYTES            # framebuffer
    mul     t3, t3, a0
    add     a3, a3, t3
    add     a2, a2, t3
    li      t3, DEPTH_ROW_BYTES         # depth (DEPTH16_ROW_BYTES = DEPTH_ROW_BYTES >> 1)
    srl     t3, t3, t1
    mul     t3, t3, a0
    add     t6, t6, t3
64: fadd.s  ft0, ft0, ft4               # the planes (unused ones too: harmless)
    fadd.s  ft1, ft1, ft5
    fadd.s  ft2, ft2, ft6
    fadd.s  ft3, ft3, ft7
    fadd.s  fs2, fs2, fs3
    addi    a0, a0, -1
    bnez    a0, 64b
65:
    # --- the fill loop for these settings: raster_fills[flags | depth16 << 3]
    # (flags with RASTER_BILINEAR or RASTER_MIPMAP index past the first 16),
    # RASTER_FILLS further for a coverage fill (a silhouette edge)
    slli    t1, t1, RASTER_DEPTH16_SHIFT
    andi    t0, t5, RASTER_FILL_INDEX_MASK
    or      t0, t0, t1
    li      t3, RASTER_SILHOUETTE_MASK
    and     t3, t5, t3
    beqz    t3, 66f
    addi    t0, t0, RASTER_FILLS
66: slli    t0, t0, 3
    la      t3, raster_fills
    add     t3, t3, t0
    ld      t3, 0(t3)
    jr      t3

# The fill loops, one per combination of settings (FILL expands each).
# Registers of the hot loops:
#   s0, s1, s2 edge functions at the pixel; s3, s4, s5 their steps right;
#   s6, s7, s8 at the row's first pixel; s9, s10, s11 steps down;
#   a0 framebuffer address of 2 x (the pixel is at a0 ^ 2), a1 its depth,
#   a2 end of the row, a3 row start at xmin, t6 its depth, a4 rows left;
#   a5 texels (textured) or the spread base colour (flat Gouraud), a6 width,
#   a7 height; t4 colour (flat) or intensity k; t5 RGB565_SPREAD_MASK;
#   ra LIGHT_ROUND_SPREAD (lit fills; ra is saved on the stack meanwhile);
#   fa0 depth, fa1 1 / w, fa2, fa3 texel column and row (affine) or u / w,
#   v / w (perspective) at the pixel, fa4..fa7 their steps right; ft0..ft3
#   at the row's first pixel, ft4..ft7 their steps down; ft8 = 1;
#   fs0..fs3 the Gouraud intensity: at the pixel, step right, at the row's
#   first pixel, step down.
fill_flat:              FILL 0, 0, 0, 0
fill_flat_gouraud:      FILL 0, 1, 0, 0
fill_textured:          FILL 1, 0, 0, 0
fill_textured_gouraud:  FILL 1, 1, 0, 0
fill_affine:            FILL 1, 0, 1, 0
fill_affine_gouraud:    FILL 1, 1, 1, 0
fill_flat_d16:          FILL 0, 0, 0, 1
fill_flat_gouraud_d16:  FILL 0, 1, 0, 1
fill_textured_d16:      FILL 1, 0, 0, 1
fill_textured_gouraud_d16: FILL 1, 1, 0, 1
fill_affine_d16:        FILL 1, 0, 1, 1
fill_affine_gouraud_d16: FILL 1, 1, 1, 1
# FILTERED gouraud, affine, depth16, mipmap
fill_bilinear:          FILTERED 0, 0, 0, 0
fill_bilinear_gouraud:  FILTERED 1, 0, 0, 0
fill_bilinear_affine:   FILTERED 0, 1, 0, 0
fill_bilinear_affine_gouraud: FILTERED 1, 1, 0, 0
fill_bilinear_d16:      FILTERED 0, 0, 1, 0
fill_bilinear_gouraud_d16: FILTERED 1, 0, 1, 0
fill_bilinear_affine_d16: FILTERED 0, 1, 1, 0
fill_bilinear_affine_gouraud_d16: FILTERED 1, 1, 1, 0
fill_mipmap:            FILTERED 0, 0, 0, 1
fill_mipmap_gouraud:    FILTERED 1, 0, 0, 1
fill_mipmap_affine:     FILTERED 0, 1, 0, 1
fill_mipmap_affine_gouraud: FILTERED 1, 1, 0, 1
fill_mipmap_d16:        FILTERED 0, 0, 1, 1
fill_mipmap_gouraud_d16: FILTERED 1, 0, 1, 1
fill_mipmap_affine_d16: FILTERED 0, 1, 1, 1
fill_mipmap_affine_gouraud_d16: FILTERED 1, 1, 1, 1
# the coverage fills (antialias = edge, a triangle with a silhouette edge)
aa_flat:                FILL 0, 0, 0, 0, 1
aa_flat_gouraud:        FILL 0, 1, 0, 0, 1
aa_textured:            FILL 1, 0, 0, 0, 1
aa_textured_gouraud:    FILL 1, 1, 0, 0, 1
aa_affine:              FILL 1, 0, 1, 0, 1
aa_affine_gouraud:      FILL 1, 1, 1, 0, 1
aa_flat_d16:            FILL 0, 0, 0, 1, 1
aa_flat_gouraud_d16:    FILL 0, 1, 0, 1, 1
aa_textured_d16:        FILL 1, 0, 0, 1, 1
aa_textured_gouraud_d16: FILL 1, 1, 0, 1, 1
aa_affine_d16:          FILL 1, 0, 1, 1, 1
aa_affine_gouraud_d16:  FILL 1, 1, 1, 1, 1
aa_bilinear:            FILTERED 0, 0, 0, 0, 1
aa_bilinear_gouraud:    FILTERED 1, 0, 0, 0, 1
aa_bilinear_affine:     FILTERED 0, 1, 0, 0, 1
aa_bilinear_affine_gouraud:FILTERED 1, 1, 0, 0, 1
aa_bilinear_d16:        FILTERED 0, 0, 1, 0, 1
aa_bilinear_gouraud_d16:FILTERED 1, 0, 1, 0, 1
aa_bilinear_affine_d16: FILTERED 0, 1, 1, 0, 1
aa_bilinear_affine_gouraud_d16:FILTERED 1, 1, 1, 0, 1
aa_mipmap:              FILTERED 0, 0, 0, 1, 1
aa_mipmap_gouraud:      FILTERED 1, 0, 0, 1, 1
aa_mipmap_affine:       FILTERED 0, 1, 0, 1, 1
aa_mipmap_affine_gouraud:FILTERED 1, 1, 0, 1, 1
aa_mipmap_d16:          FILTERED 0, 0, 1, 1, 1
aa_mipmap_gouraud_d16:  FILTERED 1, 0, 1, 1, 1
aa_mipmap_affine_d16:   FILTERED 0, 1, 1, 1, 1
aa_mipmap_affine_gouraud_d16:FILTERED 1, 1, 1, 1, 1

90: ld      s0, RT_SAVE + 0(sp)
    ld      s1, RT_SAVE + 8(sp)
    ld      s2, RT_SAVE + 16(sp)
    ld      s3, RT_SAVE + 24(sp)
    ld      s4, RT_SAVE + 32(sp)
    ld      s5, RT_SAVE + 40(sp)
    ld      s6, RT_SAVE + 48(sp)
    ld      s7, RT_SAVE + 56(sp)
    ld      s8, RT_SAVE + 64(sp)
    ld      s9, RT_SAVE + 72(sp)
    ld      s10, RT_SAVE + 80(sp)
    ld      s11, RT_SAVE + 88(sp)
    fld     fs0, RT_FSAVE + 0(sp)
    fld     fs1, RT_FSAVE + 8(sp)
    fld     fs2, RT_FSAVE + 16(sp)
    fld     fs3, RT_FSAVE + 24(sp)
    fld     fs6, RT_FSAVE3 + 0(sp)
    fld     fs7, RT_FSAVE3 + 8(sp)
    fld     fs8, RT_FSAVE3 + 16(sp)
    ld      ra, RT_RA(sp)
    addi    sp, sp, RT_FRAME
    ret

    .globl raster_segment
# raster_segment
#   What: draws the part of a line segment that lies on the screen: clipped
#         to the screen rectangle [0, LCD_WIDTH] x [0, LCD_HEIGHT]
#         (Liang-Barsky, in float), each end then drawn in the pixel it lies
#         in (pixel (x, y) covers [x, x + 1) x [y, y + 1)), by raster_line.
#   Arguments: fa0, fa1 = one end, fa2, fa3 = the other, screen positions in
#              pixels (y down); a0 = RGB565 colour.
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_segment:
    # both ends on the screen (the usual case): no clipping
    fmv.w.x ft0, zero
    li      t0, LCD_WIDTH
    fcvt.s.w ft1, t0
    li      t0, LCD_HEIGHT
    fcvt.s.w ft2, t0
    fle.s   t0, ft0, fa0
    flt.s   t1, fa0, ft1
    and     t0, t0, t1
    fle.s   t1, ft0, fa2
    and     t0, t0, t1
    flt.s   t1, fa2, ft1
    and     t0, t0, t1
    fle.s   t1, ft0, fa1
    and     t0, t0, t1
    flt.s   t1, fa1, ft2
    and     t0, t0, t1
    fle.s   t1, ft0, fa3
    and     t0, t0, t1
    flt.s   t1, fa3, ft2
    and     t0, t0, t1
    beqz    t0, 10f
    mv      a4, a0
    fcvt.w.s a0, fa0, rdn
    fcvt.w.s a1, fa1, rdn
    fcvt.w.s a2, fa2, rdn
    fcvt.w.s a3, fa3, rdn
    j       raster_line
10: fsub.s  ft0, fa2, fa0               # dx
    fsub.s  ft1, fa3, fa1               # dy
    fmv.w.x ft2, zero                   # ft2 = t entering (0)
    li      t0, F32_ONE
    fmv.w.x ft3, t0                     # ft3 = t leaving (1)
    # four boundaries, each p t <= q: (p, q) = (-dx, x0), (dx, W - x0),
    # (-dy, y0), (dy, H - y0)
    fneg.s  ft4, ft0
    fmv.s   ft5, fa0
    jal     t6, 1f
    fmv.s   ft4, ft0
    li      t0, LCD_WIDTH
    fcvt.s.w ft5, t0
    fsub.s  ft5, ft5, fa0
    jal     t6, 1f
    fneg.s  ft4, ft1
    fmv.s   ft5, fa1
    jal     t6, 1f
    fmv.s   ft4, ft1
    li      t0, LCD_HEIGHT
    fcvt.s.w ft5, t0
    fsub.s  ft5, ft5, fa1
    jal     t6, 1f
    # the ends at t entering and t leaving, their pixels (clamped: an end
    # on the right or bottom border belongs to the last column or row)
    fmadd.s ft6, ft0, ft3, fa0
    fmadd.s ft7, ft1, ft3, fa1
    fmadd.s fa0, ft0, ft2, fa0
    fmadd.s fa1, ft1, ft2, fa1
    mv      a4, a0
    fcvt.w.s a0, fa0, rdn
    fcvt.w.s a1, fa1, rdn
    fcvt.w.s a2, ft6, rdn
    fcvt.w.s a3, ft7, rdn
    li      t0, LCD_WIDTH - 1
    li      t1, LCD_HEIGHT - 1
    bgez    a0, 5f
    li      a0, 0
5:  ble     a0, t0, 5f
    mv      a0, t0
5:  bgez    a2, 5f
    li      a2, 0
5:  ble     a2, t0, 5f
    mv      a2, t0
5:  bgez    a1, 5f
    li      a1, 0
5:  ble     a1, t1, 5f
    mv      a1, t1
5:  bgez    a3, 5f
    li      a3, 0
5:  ble     a3, t1, 5f
    mv      a3, t1
5:  j       raster_line
    # one boundary (ft4 = p, ft5 = q); returns through t6, or leaves
    # raster_segment when nothing of the segment is left
1:  fmv.w.x ft6, zero
    feq.s   t0, ft4, ft6
    beqz    t0, 2f
    flt.s   t0, ft5, ft6                # parallel to the boundary: outside?
    bnez    t0, 9f
    jr      t6
2:  fdiv.s  ft7, ft5, ft4               # r = q / p
    flt.s   t0, ft4, ft6
    beqz    t0, 3f
    fmax.s  ft2, ft2, ft7               # p < 0: entering
    j       4f
3:  fmin.s  ft3, ft3, ft7               # p > 0: leaving
4:  flt.s   t0, ft3, ft2
    bnez    t0, 9f
    jr      t6
9:  ret

    .globl raster_aa_line
# raster_aa_line
#   What: antialias = edge, wireframe: a line 1 pixel wide
#         drawn by coverage (the reference's ideal wireframe: the points
#         within half a pixel of the segment), a Wu-style walk along the
#         major axis: per column (row, for a steep line) the band of the
#         line's thickness across it, h = |segment| / |major extent| pixels
#         about the line's centre there, and each pixel its overlap with the
#         band times the share of the column inside the segment, which is
#         lengthened by half a pixel of its length at each end (the round
#         ends' reach). Each coverage a (1/64) blends the colour over the
#         framebuffer's pixel as the coverage fills do (c a + old (64 - a))
#         / 64; where lines cross, coverages combine as 1 - (1 - a1)(1 -
#         a2). Columns are clamped to the screen and pixels off it skipped,
#         so any finite ends are safe. No depth test.
#   Arguments: fa0, fa1 = one end, fa2, fa3 = the other, screen positions in
#              pixels (pixel (x, y) covers [x, x + 1) x [y, y + 1), y down);
#              a0 = RGB565 colour.
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_aa_line:
    li      t0, F32_HALF
    fmv.w.x fa7, t0                     # fa7 = 1/2
    li      t0, F32_ONE
    fmv.w.x ft2, t0                     # ft2 = 1
    li      t0, F32_AA_FULL
    fmv.w.x ft3, t0                     # ft3 = 64
    li      t4, RGB565_SPREAD_MASK
    slli    t3, a0, RGB565_SPREAD_SHIFT
    or      t3, t3, a0
    and     t3, t3, t4                  # t3 = the colour, spread
    li      t5, LIGHT_ROUND_SPREAD
    # u, v = the major and minor axis (a7 = 1: u is y), a6, a5 = their sizes
    fsub.s  ft0, fa2, fa0
    fsub.s  ft1, fa3, fa1
    fabs.s  ft4, ft0
    fabs.s  ft5, ft1
    li      a7, 0
    li      a6, LCD_WIDTH
    li      a5, LCD_HEIGHT
    flt.s   t0, ft4, ft5
    beqz    t0, 1f
    li      a7, 1
    li      a6, LCD_HEIGHT
    li      a5, LCD_WIDTH
    fmv.s   ft6, fa0
    fmv.s   fa0, fa1
    fmv.s   fa1, ft6
    fmv.s   ft6, fa2
    fmv.s   fa2, fa3
    fmv.s   fa3, ft6
    fmv.s   ft6, ft0
    fmv.s   ft0, ft1
    fmv.s   ft1, ft6
1:  flt.s   t0, fa2, fa0                # from the end of smaller u
    beqz    t0, 2f
    fmv.s   ft6, fa0
    fmv.s   fa0, fa2
    fmv.s   fa2, ft6
    fmv.s   ft6, fa1
    fmv.s   fa1, fa3
    fmv.s   fa3, ft6
    fneg.s  ft0, ft0
    fneg.s  ft1, ft1
    # ft0 = du >= 0, ft1 = dv; ft5 = slope dv / du, ft6 = h / 2, ft7, ft8 =
    # the lengthened segment's u range (a point: slope 0, h 1, half a pixel)
2:  fmul.s  ft4, ft0, ft0
    fmadd.s ft4, ft1, ft1, ft4
    fsqrt.s ft4, ft4                    # |segment|
    fmv.w.x ft5, zero
    fmv.s   ft6, fa7
    fmv.s   ft9, fa7                    # ft9 = the lengthening along u
    fmv.w.x ft10, zero
    feq.s   t0, ft0, ft10
    bnez    t0, 3f
    fdiv.s  ft5, ft1, ft0
    fdiv.s  ft6, ft4, ft0
    fmul.s  ft6, ft6, fa7
    fdiv.s  ft9, ft0, ft4
    fmul.s  ft9, ft9, fa7
3:  fsub.s  ft7, fa0, ft9
    fadd.s  ft8, fa2, ft9
    fcvt.w.s t1, ft7, rdn               # t1 = first column (saturating)
    fcvt.w.s t2, ft8, rdn               # t2 = last column
    bgez    t1, 4f
    li      t1, 0
4:  addi    t0, a6, -1
    ble     t2, t0, 5f
    mv      t2, t0
5:  bgt     t1, t2, 9f
    # column t1: fa4 = its share inside the segment, ft10, ft11 = the band
6:  fcvt.s.w ft9, t1
    fadd.s  fa5, ft9, ft2               # i + 1
    fmin.s  fa4, ft8, fa5
    fmax.s  fa6, ft7, ft9
    fsub.s  fa4, fa4, fa6
    fadd.s  fa6, ft9, fa7               # the column's centre
    fsub.s  fa6, fa6, fa0
    fmadd.s fa6, ft5, fa6, fa1          # the line's v there
    fsub.s  ft10, fa6, ft6
    fadd.s  ft11, fa6, ft6
    fcvt.w.s t6, ft10, rdn              # t6 = first row of the band
    fcvt.w.s a1, ft11, rdn              # a1 = its last
7:  bgt     t6, a1, 8f
    bltz    t6, 71f                     # off the screen
    bge     t6, a5, 71f
    fcvt.s.w fa5, t6
    fadd.s  fa6, fa5, ft2
    fmin.s  fa6, fa6, ft11
    fmax.s  fa5, fa5, ft10
    fsub.s  fa5, fa6, fa5               # the overlap
    fmul.s  fa5, fa5, fa4
    fmul.s  fa5, fa5, ft3
    fcvt.w.s a2, fa5, rne               # a
    blez    a2, 71f
    li      t0, AA_FULL
    ble     a2, t0, 72f
    mv      a2, t0
72: mv      a3, t1                      # x, y
    mv      a4, t6
    beqz    a7, 73f
    mv      a3, t6
    mv      a4, t1
73: xori    a3, a3, 1                   # the pixel's address (see the file comment)
    li      t0, LCD_WIDTH
    mul     a4, a4, t0
    add     a3, a3, a4
    slli    a3, a3, FB_PIXEL_SHIFT
    la      t0, raster_fb
    ld      t0, 0(t0)
    add     a3, a3, t0
    lhu     a4, 0(a3)                   # what is behind, spread
    slli    t0, a4, RGB565_SPREAD_SHIFT
    or      a4, a4, t0
    and     a4, a4, t4
    sub     t0, t3, a4                  # (c a + old (64 - a)) / 64, rounded
    mul     t0, t0, a2
    slli    a4, a4, AA_SHIFT
    add     t0, t0, a4
    add     t0, t0, t5
    srli    t0, t0, AA_SHIFT
    and     t0, t0, t4
    srli    a4, t0, RGB565_SPREAD_SHIFT
    or      t0, t0, a4
    sh      t0, 0(a3)
71: addi    t6, t6, 1
    j       7b
8:  addi    t1, t1, 1
    ble     t1, t2, 6b
9:  ret

    .globl raster_set_union
# raster_set_union
#   What: antialias = supersample, wireframe: sets the union lines' buffer
#         (render.inc WIRE_*) and clears it: every cell 0, every row's span
#         empty. raster_union_resolve leaves it so again after each frame.
#   Arguments: a0 = the buffer (WIRE_BUFFER_BYTES, 8-aligned).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_set_union:
    la      t0, raster_union
    sd      a0, 0(t0)
    li      t1, WIRE_CELLS_BYTES
    add     t1, t1, a0
1:  sd      zero, 0(a0)
    sd      zero, 8(a0)
    addi    a0, a0, WIRE_PIXEL_BYTES
    bltu    a0, t1, 1b
    li      t1, LCD_HEIGHT
    li      t2, WIRE_SPAN_EMPTY
2:  sw      t2, 0(a0)
    addi    a0, a0, WIRE_SPAN_BYTES
    addi    t1, t1, -1
    bnez    t1, 2b
    ret

# WIRE_MERGE cell, fl, fh: adds [fl, fh] (1/64 of a pixel, 0 <= fl < fh <=
# WIRE_CELL_FULL) to the cell at address \cell (render.inc WIRE_*): the
# union kept as the extents [0, L] and [1 - R, 1]. Clobbers t5, t6, a4, a5.
.macro WIRE_MERGE cell, fl, fh
    lhu     t5, 0(\cell)
    andi    t6, t5, WIRE_CELL_L_MASK    # t6 = L
    srli    t5, t5, WIRE_CELL_R_SHIFT   # t5 = R
    li      a4, WIRE_CELL_FULL
    bnez    \fl, 81f
    bgeu    t6, \fh, 85f                # from the left side: L = max(L, fh)
    mv      t6, \fh
    j       85f
81: bne     \fh, a4, 82f
    sub     a5, a4, \fl                 # to the right side: R = max(R, 64 - fl)
    bgeu    t5, a5, 85f
    mv      t5, a5
    j       85f
82: bltu    t6, \fl, 83f
    bgeu    t6, \fh, 85f                # overlapping [0, L]
    mv      t6, \fh
    j       85f
83: sub     a5, a4, t5
    bltu    \fh, a5, 84f
    sub     a5, a4, \fl                 # overlapping [1 - R, 1]
    bgeu    t5, a5, 85f
    mv      t5, a5
    j       85f
84: sub     a5, \fh, \fl                # touching neither (a round end): its
    bltu    t5, t6, 86f                 # length to the smaller extent
    add     t6, t6, a5
    j       85f
86: add     t5, t5, a5
85: add     a5, t6, t5
    bltu    a5, a4, 87f
    mv      t6, a4                      # all of it
    li      t5, 0
87: slli    t5, t5, WIRE_CELL_R_SHIFT
    or      t5, t5, t6
    sh      t5, 0(\cell)
.endm

# WIRE_SUBROW out, y, eight, mode: the sub-row index of height y: the first
# (mode rup) or last (rdn) j whose centre (j + 1/2) / 8 is at or past (before)
# y, \out = 8 y - 1/2 rounded so (\eight = 8, ft8 = 1/2; \y clobbered).
.macro WIRE_SUBROW out, y, eight, mode
    fmul.s  \y, \y, \eight
    fsub.s  \y, \y, ft8
    fcvt.w.s \out, \y, \mode
.endm

# WIRE_DISC x, y: widens the crossing [fa7, fa6] of sub-row fa4 by the disc
# of radius 1/2 about (\x, \y), where the row meets it: x -+ sqrt(1/4 - (fa4
# - y)^2) (ft8 = 1/4). Clobbers t0, ft1, fa5.
.macro WIRE_DISC x, y
    fsub.s  fa5, fa4, \y
    fnmsub.s fa5, fa5, fa5, ft8
    fmv.w.x ft1, zero
    flt.s   t0, fa5, ft1
    bnez    t0, 88f
    fsqrt.s fa5, fa5
    fsub.s  ft1, \x, fa5
    fmin.s  fa7, fa7, ft1
    fadd.s  ft1, \x, fa5
    fmax.s  fa6, fa6, ft1
88:
.endm

    .globl raster_union_line
# raster_union_line
#   What: antialias = supersample, wireframe: adds a line 1 pixel wide (the
#         points within half a pixel of the segment, its round ends
#         included: the ideal wireframe's capsule) to the union lines'
#         cells (render.inc WIRE_*; raster_set_union). Per sub-row y = (j +
#         1/2) / 8 the capsule's crossing, exact along x: the hull of its
#         crossings with the end discs (x_e -+ sqrt(1/4 - (y - y_e)^2))
#         and with the rectangle the segment sweeps, the strip within half
#         a pixel of its line (x = x_a + (y - y_a) dx / dy -+ |s| / (2 |dy|))
#         cut by the slab of points projecting onto it (x = x_a - (y - y_a)
#         dy / dx, + |s|^2 / dx); a horizontal strip or a vertical slab
#         bounds y instead of x. The crossing, clamped to the screen and in
#         1/64 pixel, is merged into each pixel's cell (WIRE_MERGE; the
#         pixels wholly inside set full) and the row's span widened. Rows
#         are clamped to the screen, so any finite ends are safe; nothing
#         is drawn until raster_union_resolve. In the middle of a line
#         (no disc or slab reaching beyond the strip) only the strip is
#         computed. Register use: a leaf, all temporaries, s0 and s1 saved.
#   Arguments: fa0, fa1 = one end, fa2, fa3 = the other, screen positions in
#              pixels (pixel (x, y) covers [x, x + 1) x [y, y + 1), y down).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_union_line:
    addi    sp, sp, -16
    sd      s0, 8(sp)
    sd      s1, 0(sp)
    li      s0, 1                       # s0 .. s1 = the middle sub-rows (none)
    li      s1, 0
    li      t0, F32_WIRE_FAR
    fmv.w.x ft11, t0                    # ft11 = FAR
    fneg.s  ft6, ft11                   # ft6, ft7 = the y - y_a range where
    fmv.s   ft7, ft11                   # strip and slab cross the row
    li      t0, F32_HALF
    fmv.w.x ft8, t0                     # ft8 = 1/2 (for now)
    fsub.s  ft9, fa2, fa0               # ft9 = dx
    fsub.s  ft10, fa3, fa1              # ft10 = dy
    fmul.s  fa4, ft9, ft9
    fmadd.s fa4, ft10, ft10, fa4        # fa4 = |s|^2
    fsqrt.s fa5, fa4                    # fa5 = |s|
    fmv.w.x fa6, zero
    feq.s   t1, ft9, fa6                # t1: dx = 0
    feq.s   t2, ft10, fa6               # t2: dy = 0
    and     t0, t1, t2
    beqz    t0, 1f
    fmv.s   ft6, ft11                   # a point: the discs only
    fneg.s  ft7, ft11
    j       3f
    # the strip: ft0 = its x change per y, -ft2, ft2 = its sides' offsets
1:  bnez    t2, 11f
    fdiv.s  ft0, ft9, ft10
    fabs.s  fa7, ft10
    fdiv.s  ft2, fa5, fa7
    fmul.s  ft2, ft2, ft8               # |s| / (2 |dy|)
    # the middle: the sub-rows whose strip crossing lies inside the slab
    # (its ends project m = |dx| / (2 |s|) from its centre's along y), where
    # the ends' discs do not reach beyond it either: y - y_a in [min(0, dy)
    # + m, max(0, dy) - m]
    fabs.s  fa7, ft9
    fdiv.s  fa7, fa7, fa5
    fmul.s  fa7, fa7, ft8               # m
    li      t0, F32_WIRE_SUBROWS
    fmv.w.x ft3, t0                     # (8, for now)
    fmin.s  ft1, ft10, fa6
    fadd.s  ft1, ft1, fa7
    fadd.s  ft1, ft1, fa1
    WIRE_SUBROW s0, ft1, ft3, rup
    fmax.s  ft1, ft10, fa6
    fsub.s  ft1, ft1, fa7
    fadd.s  ft1, ft1, fa1
    WIRE_SUBROW s1, ft1, ft3, rdn
    j       2f
11: fmv.w.x ft0, zero                   # horizontal: |y - y_a| <= 1/2
    fmv.s   ft2, ft11
    fneg.s  ft6, ft8
    fmv.s   ft7, ft8
    # the slab: ft3 = its x change per y, ft4, ft5 = its sides' offsets
2:  bnez    t1, 21f
    fdiv.s  ft3, ft10, ft9
    fneg.s  ft3, ft3
    fdiv.s  fa7, fa4, ft9               # |s|^2 / dx
    fmin.s  ft4, fa7, fa6
    fmax.s  ft5, fa7, fa6
    j       3f
21: fmv.w.x ft3, zero                   # vertical: 0 <= (y - y_a) / dy <= 1
    fneg.s  ft4, ft11
    fmv.s   ft5, ft11
    fmin.s  fa7, ft10, fa6
    fmax.s  ft6, ft6, fa7
    fmax.s  fa7, ft10, fa6
    fmin.s  ft7, ft7, fa7
    # the sub-rows j the capsule reaches, a0 .. a1 (clamped to the screen)
3:  li      t0, F32_WIRE_SUBROWS
    fmv.w.x ft9, t0                     # ft9 = 8
    fmin.s  fa4, fa1, fa3
    fsub.s  fa4, fa4, ft8
    WIRE_SUBROW a0, fa4, ft9, rup       # first: ceil(8 (top - 1/2) - 1/2)
    fmax.s  fa4, fa1, fa3
    fadd.s  fa4, fa4, ft8
    WIRE_SUBROW a1, fa4, ft9, rdn       # last: floor(8 (bottom + 1/2) - 1/2)
    bgez    a0, 31f
    li      a0, 0
31: li      t0, WIRE_SUBROW_LAST
    ble     a1, t0, 32f
    mv      a1, t0
32: bgt     a0, a1, 9f
    slli    t0, a0, 1                   # fa4 = y = (2 j + 1) / 16, exact
    addi    t0, t0, 1
    fcvt.s.w fa4, t0
    li      t0, F32_WIRE_HALF_SUBROW
    fmv.w.x fa5, t0
    fmul.s  fa4, fa4, fa5
    li      t0, F32_WIRE_SUBROW
    fmv.w.x ft9, t0                     # ft9 = 1/8, the step
    li      t0, F32_WIRE_RADIUS2
    fmv.w.x ft8, t0                     # ft8 = 1/4
    li      t0, F32_AA_FULL
    fmv.w.x ft10, t0                    # ft10 = 64
    la      t0, raster_union
    ld      a2, 0(t0)                   # a2 = the cells
    li      t0, WIRE_CELLS_BYTES
    add     a3, a2, t0                  # a3 = the spans
    li      a7, WIRE_ROW_BYTES

    # sub-row a0: fa7, fa6 = the crossing's low and high x (ft1, fa5
    # scratch); in the middle, the strip's
4:  blt     a0, s0, 40f
    bgt     a0, s1, 40f
    fsub.s  fa5, fa4, fa1
    fmadd.s ft1, fa5, ft0, fa0
    fsub.s  fa7, ft1, ft2
    fadd.s  fa6, ft1, ft2
    j       43f
40: fneg.s  fa6, ft11
    fmv.s   fa7, ft11
    fsub.s  fa5, fa4, fa1               # y - y_a
    flt.s   t0, fa5, ft6
    bnez    t0, 41f
    flt.s   t0, ft7, fa5
    bnez    t0, 41f
    fmadd.s ft1, fa5, ft0, fa0          # the strip
    fsub.s  fa7, ft1, ft2
    fadd.s  fa6, ft1, ft2
    fmadd.s ft1, fa5, ft3, fa0          # the slab
    fadd.s  fa5, ft1, ft4
    fmax.s  fa7, fa7, fa5
    fadd.s  fa5, ft1, ft5
    fmin.s  fa6, fa6, fa5
    flt.s   t0, fa6, fa7
    beqz    t0, 41f
    fneg.s  fa6, ft11                   # (an empty cut: nothing)
    fmv.s   fa7, ft11
41: WIRE_DISC fa0, fa1                  # the ends' discs
    WIRE_DISC fa2, fa3
43: flt.s   t0, fa7, fa6
    beqz    t0, 8f                      # nothing on this sub-row
    fmul.s  fa7, fa7, ft10
    fcvt.w.s t1, fa7, rne               # t1 = low x, 1/64 pixel
    fmul.s  fa6, fa6, ft10
    fcvt.w.s t2, fa6, rne               # t2 = high x
    bgez    t1, 44f
    li      t1, 0
44: li      t0, WIRE_X_END
    ble     t2, t0, 45f
    mv      t2, t0
45: bge     t1, t2, 8f
    mv      a6, t2                      # a6 = high x, clamped
    # the pixels p0 = t3 .. p1 = t4 of row a0 >> 3, its sub-row a0 & 7
    srli    t3, t1, WIRE_CELL_SHIFT
    addi    t4, t2, -1
    srli    t4, t4, WIRE_CELL_SHIFT
    srli    t0, a0, WIRE_SUBROW_SHIFT
    slli    t6, t0, WIRE_SPAN_SHIFT     # the row's span: [min, max]
    add     t6, t6, a3
    lhu     t5, WIRE_SPAN_FIRST(t6)
    bleu    t5, t3, 46f
    sh      t3, WIRE_SPAN_FIRST(t6)
46: lhu     t5, WIRE_SPAN_END(t6)
    addi    a4, t4, 1
    bgeu    t5, a4, 47f
    sh      a4, WIRE_SPAN_END(t6)
47: mul     t0, t0, a7                  # the row's cells
    add     t0, t0, a2
    andi    t6, a0, WIRE_SUBROWS - 1
    slli    t6, t6, WIRE_CELL_BYTES_SHIFT
    add     t0, t0, t6
    slli    t6, t3, WIRE_PIXEL_SHIFT
    add     t0, t0, t6                  # t0 = pixel p0's cell
    slli    t6, t3, WIRE_CELL_SHIFT
    sub     t1, t1, t6                  # t1 = fl in p0
    sub     t2, t2, t6                  # t2 = fh in p0 (beyond 64: more pixels)
    bne     t3, t4, 5f
    WIRE_MERGE t0, t1, t2               # one pixel
    j       8f
5:  li      t2, WIRE_CELL_FULL
    WIRE_MERGE t0, t1, t2               # p0: to its right side
    li      t1, WIRE_CELL_FULL
    sub     t3, t4, t3                  # the pixels after p0
6:  addi    t0, t0, WIRE_PIXEL_BYTES
    addi    t3, t3, -1
    beqz    t3, 7f
    sh      t1, 0(t0)                   # wholly inside (full: L 64, R 0)
    j       6b
7:  slli    t6, t4, WIRE_CELL_SHIFT     # p1: from its left side
    sub     t2, a6, t6
    WIRE_MERGE t0, zero, t2
8:  fadd.s  fa4, fa4, ft9
    addi    a0, a0, 1
    ble     a0, a1, 4b
9:  ld      s1, 0(sp)
    ld      s0, 8(sp)
    addi    sp, sp, 16
    ret

    .globl raster_union_resolve
# raster_union_resolve
#   What: antialias = supersample, wireframe: draws the union lines' pixels
#         (raster_union_line) into the framebuffer, which holds the cleared
#         background: each pixel within a row's span whose cells cover some
#         of it, coverage a = its cells' sum / 8 in 1/64 (rounded), blends
#         the line colour over the background (c a + bg (64 - a)) / 64,
#         rounded per channel as the coverage fills. Its cells and the
#         spans are cleared for the next frame.
#   Arguments: a0 = the lines' RGB565 colour, a1 = the background's.
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_union_resolve:
    li      t4, RGB565_SPREAD_MASK
    slli    t3, a0, RGB565_SPREAD_SHIFT
    or      t3, t3, a0
    and     t3, t3, t4
    slli    t5, a1, RGB565_SPREAD_SHIFT
    or      t5, t5, a1
    and     t5, t5, t4
    sub     a3, t3, t5                  # a3 = (c - bg), spread
    slli    a4, t5, AA_SHIFT
    li      t6, LIGHT_ROUND_SPREAD
    add     a4, a4, t6                  # a4 = bg 64 + the rounding
    la      t0, raster_fb
    ld      a0, 0(t0)                   # a0 = the framebuffer's row
    la      t0, raster_union
    ld      a1, 0(t0)                   # a1 = the row's cells
    li      t0, WIRE_CELLS_BYTES
    add     a2, a1, t0                  # a2 = its span
    li      a5, LCD_HEIGHT
    li      a6, WIRE_BYTE_LANES
    li      a7, WIRE_LANE_SUM
1:  lhu     t1, WIRE_SPAN_FIRST(a2)     # t1 = first column, t2 = past the last
    lhu     t2, WIRE_SPAN_END(a2)
    bgeu    t1, t2, 8f
    li      t0, WIRE_SPAN_EMPTY
    sw      t0, 0(a2)
    slli    t0, t1, WIRE_PIXEL_SHIFT
    add     t0, t0, a1                  # t0 = column t1's cells
2:  ld      t3, 0(t0)
    ld      t5, 8(t0)
    or      t6, t3, t5
    beqz    t6, 3f
    sd      zero, 0(t0)
    sd      zero, 8(t0)
    add     t3, t3, t5                  # bytes: at most 2 x 64, no carry
    srli    t5, t3, 8
    and     t5, t5, a6
    and     t3, t3, a6
    add     t3, t3, t5                  # four u16 lanes
    mul     t3, t3, a7
    srli    t3, t3, WIRE_LANE_SUM_SHIFT # the sum, 1/512
    addi    t3, t3, WIRE_SUM_ROUND
    srli    t3, t3, WIRE_SUM_SHIFT      # a, 1/64
    mul     t3, t3, a3
    add     t3, t3, a4
    srli    t3, t3, AA_SHIFT
    and     t3, t3, t4
    srli    t5, t3, RGB565_SPREAD_SHIFT
    or      t3, t3, t5
    xori    t5, t1, 1                   # the pixel's address (file comment)
    slli    t5, t5, FB_PIXEL_SHIFT
    add     t5, t5, a0
    sh      t3, 0(t5)
3:  addi    t0, t0, WIRE_PIXEL_BYTES
    addi    t1, t1, 1
    bltu    t1, t2, 2b
8:  li      t0, FB_ROW_BYTES
    add     a0, a0, t0
    li      t0, WIRE_ROW_BYTES
    add     a1, a1, t0
    addi    a2, a2, WIRE_SPAN_BYTES
    addi    a5, a5, -1
    bnez    a5, 1b
    ret

    .globl raster_line
# raster_line
#   What: a line between two on-screen pixels, both ends included
#         (Bresenham's integer algorithm, all octants). No depth test.
#   Arguments: a0, a1 = x0, y0; a2, a3 = x1, y1 (0 <= x < LCD_WIDTH,
#              0 <= y < LCD_HEIGHT); a4 = RGB565 colour.
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_line:
    sub     t0, a2, a0                  # t0 = dx = |x1 - x0|, t2 = x step
    li      t2, 1
    bgez    t0, 1f
    neg     t0, t0
    li      t2, -1
1:  sub     t1, a3, a1                  # t1 = dy = -|y1 - y0|, a6 = y step,
    li      a6, 1                       # t3 = its address step
    li      t3, FB_ROW_BYTES
    bgez    t1, 2f
    neg     t1, t1
    li      a6, -1
    li      t3, -FB_ROW_BYTES
2:  neg     t1, t1
    add     t4, t0, t1                  # t4 = error
    la      t5, raster_fb
    ld      t5, 0(t5)
    li      t6, FB_ROW_BYTES
    mul     t6, a1, t6
    add     t5, t5, t6                  # t5 = row y0
3:  xori    t6, a0, 1                   # plot (x0, y0)
    slli    t6, t6, 1
    add     t6, t6, t5
    sh      a4, 0(t6)
    bne     a0, a2, 4f
    beq     a1, a3, 9f                  # at the far end
4:  slli    t6, t4, 1                   # e2 = 2 error
    blt     t6, t1, 5f
    add     t4, t4, t1                  # e2 >= dy: step x
    add     a0, a0, t2
5:  bgt     t6, t0, 3b
    add     t4, t4, t0                  # e2 <= dx: step y
    add     t5, t5, t3
    add     a1, a1, a6
    j       3b
9:  ret

# ---------------------------------------------------------------------------
    .bss
    .balign 8
# Where raster_* draw, and the texture of textured fills.
raster_fb:
    .space  8
raster_texture:
    .space  8
raster_tex_w:
    .space  8
raster_tex_h:
    .space  8
raster_depth:
    .space  8
raster_depth_mode:
    .space  8
# filter = mipmap: the level table (raster_build_mips) and the triangle's
# rho^2 constant (|det H| or, affine, |det J|; raster_triangle)
raster_mip_table:
    .space  8
# antialias = supersample: the sums of the samples (raster_set_sums)
raster_sums:
    .space  8
# antialias = supersample, wireframe: the union lines' cells and spans
# (raster_set_union)
raster_union:
    .space  8
# Hart-local (k210.inc HART_LOCAL_STRIDE; tp selects the copy): the rows this
# hart draws (raster_set_band), and filter = mipmap's rho^2 constant of the
# triangle being drawn (|det H| or, affine, |det J|; raster_triangle).
    .balign 8
raster_band:
    .space  BAND_BYTES
raster_mip_rho2:
    .space  4
    .balign 8
raster_sample:
    .space  SAMPLE_BYTES
raster_hart_local_end:
    .space  HART_LOCAL_STRIDE - (raster_hart_local_end - raster_band)
    .space  raster_hart_local_end - raster_band     # hart 1's copy

    .section .rodata
msg_mip_chain:      .asciz "mip chain"
    .balign 8
# raster_fills: the fill loop for RASTER_* flags | 16-bit depth << 3
# (RASTER_AFFINE, RASTER_BILINEAR, RASTER_MIPMAP mean nothing without
# RASTER_TEXTURED).
raster_fills:
    .dword  fill_flat, fill_textured, fill_flat_gouraud, fill_textured_gouraud
    .dword  fill_flat, fill_affine, fill_flat_gouraud, fill_affine_gouraud
    .dword  fill_flat_d16, fill_textured_d16, fill_flat_gouraud_d16, fill_textured_gouraud_d16
    .dword  fill_flat_d16, fill_affine_d16, fill_flat_gouraud_d16, fill_affine_gouraud_d16
# RASTER_BILINEAR (flat fills never have it)
    .dword  fill_flat, fill_bilinear, fill_flat_gouraud, fill_bilinear_gouraud
    .dword  fill_flat, fill_bilinear_affine, fill_flat_gouraud, fill_bilinear_affine_gouraud
    .dword  fill_flat_d16, fill_bilinear_d16, fill_flat_gouraud_d16, fill_bilinear_gouraud_d16
    .dword  fill_flat_d16, fill_bilinear_affine_d16, fill_flat_gouraud_d16, fill_bilinear_affine_gouraud_d16
# RASTER_MIPMAP
    .dword  fill_flat, fill_mipmap, fill_flat_gouraud, fill_mipmap_gouraud
    .dword  fill_flat, fill_mipmap_affine, fill_flat_gouraud, fill_mipmap_affine_gouraud
    .dword  fill_flat_d16, fill_mipmap_d16, fill_flat_gouraud_d16, fill_mipmap_gouraud_d16
    .dword  fill_flat_d16, fill_mipmap_affine_d16, fill_flat_gouraud_d16, fill_mipmap_affine_gouraud_d16
# the coverage fills, in the same order (RASTER_FILLS + the same index)
    .dword  aa_flat, aa_textured, aa_flat_gouraud, aa_textured_gouraud
    .dword  aa_flat, aa_affine, aa_flat_gouraud, aa_affine_gouraud
    .dword  aa_flat_d16, aa_textured_d16, aa_flat_gouraud_d16, aa_textured_gouraud_d16
    .dword  aa_flat_d16, aa_affine_d16, aa_flat_gouraud_d16, aa_affine_gouraud_d16
    .dword  aa_flat, aa_bilinear, aa_flat_gouraud, aa_bilinear_gouraud
    .dword  aa_flat, aa_bilinear_affine, aa_flat_gouraud, aa_bilinear_affine_gouraud
    .dword  aa_flat_d16, aa_bilinear_d16, aa_flat_gouraud_d16, aa_bilinear_gouraud_d16
    .dword  aa_flat_d16, aa_bilinear_affine_d16, aa_flat_gouraud_d16, aa_bilinear_affine_gouraud_d16
    .dword  aa_flat, aa_mipmap, aa_flat_gouraud, aa_mipmap_gouraud
    .dword  aa_flat, aa_mipmap_affine, aa_flat_gouraud, aa_mipmap_affine_gouraud
    .dword  aa_flat_d16, aa_mipmap_d16, aa_flat_gouraud_d16, aa_mipmap_gouraud_d16
    .dword  aa_flat_d16, aa_mipmap_affine_d16, aa_flat_gouraud_d16, aa_mipmap_affine_gouraud_d16
raster_fills_end:
    .if (raster_fills_end - raster_fills) != 2 * RASTER_FILLS * 8
    .error "raster_fills must have 2 RASTER_FILLS entries"
    .endif
