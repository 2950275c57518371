# raster_lines.S: lines into the framebuffer (pixel (x, y) at fb + 2 (320 y +
# (x ^ 1)), raster.S), without depth test, for the wireframe
# (render_wireframe.S):
#   - raster_segment clips a segment to the screen and draws it with
#     Bresenham's integer algorithm (raster_line);
#   - raster_aa_line, antialias = edge: a line 1 pixel wide by coverage,
#     blended over what is behind;
#   - raster_set_union, raster_union_line, raster_union_resolve,
#     antialias = supersample: each line's capsule merged into per-pixel
#     sub-row cells (render.inc WIRE_*), then the union of all of them drawn
#     once, so crossing lines do not darken each other.

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"
    .include "frame.inc"

    .text
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
    li      t5, AA_ROUND_SPREAD
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
    FRAME_SAVE 16, s0, s1
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
9:  FRAME_RESTORE 16, s0, s1
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
    li      t6, AA_ROUND_SPREAD
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
