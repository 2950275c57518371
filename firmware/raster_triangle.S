# raster_triangle.S: one triangle's set-up (raster_triangle): from its three
# raster vertices to the fill loop that draws it (raster_fills.S), into the
# framebuffer and the depth buffer (raster.S).
#
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
#   - Depth: the reversed depth (float32) or z / w (int16) interpolated
#     linearly in screen space as a float and compared as a signed 32-bit
#     integer (render.inc); a fragment is drawn when it is strictly nearer
#     than what the buffer holds.
#   - Attributes are planes: gradients per pixel from the snapped corners
#     (float32 depth's from where they project before snapping:
#     DEPTH_GRADIENT), re-anchored at the first inside pixel of every row.
#     Depth is evaluated from its plane at every pixel and every row (one
#     rounding each), not stepped: a step under half an ulp would vanish.
#     Textured fills
#     interpolate u / w, v / w and 1 / w (perspective-correct) or the texel
#     column and row themselves (affine).
#   - Bands: each hart draws only the rows of its band (raster_set_band;
#     main.S splits a frame between the harts). The planes are still set up
#     at the bounding box's first row and carried to the band as the fill
#     loops carry them from row to row (depth from its plane, the others
#     stepped), so a pixel gets the same bits whichever hart draws it.
#   - antialias = edge (RASTER_EDGE_AA): a triangle with a silhouette edge
#     (SILHOUETTE: the mesh ends there, or folds away) is drawn by a
#     coverage fill: its box grown by half a pixel, its silhouette edges'
#     functions moved out by half a pixel (AA_EDGE), and each pixel blended
#     over what is behind by its coverage (render.inc AA_*); its other edges
#     stay hard, so closed meshes show no seams.
#   - antialias = supersample: the corners are moved by minus the hart's
#     sample offset (raster_supersample.S).

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"

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

# OVER_W field, r0, r1, r2
#   The corners' field (RV_S, RV_T, RV_NA ...) times their 1 / w (RV_Q): a
#   perspective-correct attribute's plane values, into r0, r1, r2 for corners
#   t0, t1, t2. Clobbers ft8.
.macro OVER_W field, r0, r1, r2
    flw     \r0, \field(t0)
    flw     ft8, RV_Q(t0)
    fmul.s  \r0, \r0, ft8
    flw     \r1, \field(t1)
    flw     ft8, RV_Q(t1)
    fmul.s  \r1, \r1, ft8
    flw     \r2, \field(t2)
    flw     ft8, RV_Q(t2)
    fmul.s  \r2, \r2, ft8
.endm

# PHONG_PLANE field, at, step
#   shading = phong: the plane of one component of the corners' normals
#   over w (RV_NA, RV_NB or RV_NC times RV_Q: perspective-correct, up to the
#   factor PHONG_K's normalisation drops): step right into step, per row and
#   at the first centre into RT_PHONG_DOWN + at, RT_PHONG_ORIGIN + at.
#   Clobbers ft1, ft2, ft8, ft11.
.macro PHONG_PLANE field, at, step
    OVER_W  \field, ft11, ft1, ft2
    GRADIENT ft11, ft1, ft2, \step, ft1, ft2
    fsw     ft1, RT_PHONG_DOWN + \at(sp)
    fsw     ft2, RT_PHONG_ORIGIN + \at(sp)
.endm

# DEPTH_GRADIENT
#   GRADIENT for float32 depth (ft11, ft4, ft0 = its values at corners t0,
#   t1, t2; into fa4 per pixel right, ft4 per row down, ft0 at the first
#   centre a2, a3), but through the corners where they project before
#   snapping (RV_FX, RV_FY, moved by the sample's offset as the snapped ones
#   are): snapping moves a corner by up to 1/32 pixel, and on a surface at 17
#   degrees that shifts its plane by 1.5e-6, where two quads crossing at a
#   slope of 1e-4 differ by 1.6e-8 a pixel from the crossing. Where the
#   unsnapped triangle has under half the snapped one's area (a sliver that
#   snapping fattened, or NaN), its plane would be ill-conditioned over the
#   snapped pixels, which it extrapolates to: the snapped plane, GRADIENT's,
#   stays. (int16 depth, 1000 times coarser, keeps GRADIENT's plane.)
#   Clobbers a0, a1, t3, ft1..ft3, ft5..ft8, fa5, fa6.
.macro DEPTH_GRADIENT
    flw     ft1, RV_FX(t0)
    flw     ft2, RV_FY(t0)
    flw     ft3, RV_FX(t1)
    flw     ft5, RV_FY(t1)
    flw     ft6, RV_FX(t2)
    flw     ft7, RV_FY(t2)
    fsub.s  ft3, ft3, ft1               # dx1
    fsub.s  ft5, ft5, ft2               # dy1
    fsub.s  ft6, ft6, ft1               # dx2
    fsub.s  ft7, ft7, ft2               # dy2
    fmul.s  fa5, ft3, ft7
    fnmsub.s fa5, ft6, ft5, fa5         # area = dx1 dy2 - dx2 dy1 (pixels^2)
    fcvt.s.l fa6, s6                    # half the snapped area: s6 (Q8) / 512
    li      t3, F32_HALF_Q8_AREA
    fmv.w.x ft8, t3
    fmul.s  fa6, fa6, ft8
    flt.s   t3, fa6, fa5
    bnez    t3, .Lexact\@
    GRADIENT ft11, ft4, ft0, fa4, ft4, ft0
    j       .Ldone\@
.Lexact\@:
    fsub.s  ft4, ft4, ft11              # d1
    fsub.s  ft0, ft0, ft11              # d2
    fmul.s  fa4, ft4, ft7
    fnmsub.s fa4, ft0, ft5, fa4
    fdiv.s  fa4, fa4, fa5               # (d1 dy2 - d2 dy1) / area
    fmul.s  fa6, ft0, ft3
    fnmsub.s ft4, ft4, ft6, fa6
    fdiv.s  ft4, ft4, fa5               # (d2 dx1 - d1 dx2) / area
    la      t3, raster_sample           # the first centre from corner 0
    add     t3, t3, tp                  # (pixels): the centre, in pixels from
    lw      a0, SAMPLE_OFFSET_X(t3)     # the screen's, where corner 0 lies
    lw      a1, SAMPLE_OFFSET_Y(t3)     # once moved by minus the offset
    add     a0, a0, a2
    add     a1, a1, a3
    li      t3, SCREEN_HALF_W_Q4
    sub     a0, a0, t3
    li      t3, SCREEN_HALF_H_Q4
    sub     a1, a1, t3
    fcvt.s.l ft3, a0
    fcvt.s.l ft5, a1
    li      t3, F32_Q4_TO_PIXEL
    fmv.w.x ft6, t3
    fmul.s  ft3, ft3, ft6
    fmul.s  ft5, ft5, ft6
    fsub.s  ft3, ft3, ft1
    fsub.s  ft5, ft5, ft2
    fmadd.s ft0, fa4, ft3, ft11
    fmadd.s ft0, ft4, ft5, ft0
.Ldone\@:
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

# EXIT_IF cond, rs1, rs2
#   raster_triangle's early exits: to its epilogue (raster_fills.S
#   raster_triangle_return) when `cond rs1, rs2` (cond beqz, bnez, bgt or
#   bge) holds. The epilogue lies past all the fill loops, beyond a branch's
#   reach, so the exit is the opposite branch over a jump: what the
#   assembler made of the far branch when both were in one file.
.macro EXIT_IF cond, rs1, rs2
    .ifc \cond, beqz
    bnez    \rs1, .Lstay\@
    .endif
    .ifc \cond, bnez
    beqz    \rs1, .Lstay\@
    .endif
    .ifc \cond, bgt
    ble     \rs1, \rs2, .Lstay\@
    .endif
    .ifc \cond, bge
    blt     \rs1, \rs2, .Lstay\@
    .endif
    j       raster_triangle_return
.Lstay\@:
.endm

    .if DEPTH16_ROW_BYTES != DEPTH_ROW_BYTES >> 1
    .error "raster_triangle steps depth rows by DEPTH_ROW_BYTES >> (16-bit depth)"
    .endif

    .text
    .globl raster_triangle
# raster_triangle
#   What: draws the rows of one triangle that lie in this hart's band
#         (raster_set_band), depth-tested (see the file comment).
#   Arguments: a0 = three raster vertices in a row (RV_BYTES each,
#              render.inc; RV_K only read with RASTER_GOURAUD, RV_NA..RV_NC
#              instead with raster_phong, RV_S, RV_T only with
#              RASTER_TEXTURED), a1 = 1 to drop back faces,
#              a2 = the colour: flat fill, RGB565 as drawn (or, with
#              RASTER_GOURAUD, before lighting); textured, the intensity k
#              0 .. LIGHT_ONE (WIDE_LIGHT_ONE when raster_fill_table is
#              raster_fills_wide; unused with RASTER_GOURAUD), a3 = RASTER_*
#              flags (render.inc). The depth format is raster_set_depth's.
#   Results: none.
#         With RASTER_EDGE_AA the corners' RV_OPP_* say what lies across
#         each edge (silhouette or not: a coverage fill for a silhouette).
#         The corners are moved by minus this hart's sample offset
#         (raster_set_sample; 0, 0 unless supersampling).
#   Clobbers: only ABI temporaries. The pixel loops use every integer
#         register but sp, gp and tp (ra holds a constant, saved here), every
#         temporary and argument float register, and fs0..fs3 and fs6..fs11
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
    fsd     fs9, RT_FSAVE4 + 0(sp)
    fsd     fs10, RT_FSAVE4 + 8(sp)
    fsd     fs11, RT_FSAVE4 + 16(sp)
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
    EXIT_IF beqz, s6                    # degenerate
    bltz    s6, 1f                      # counter-clockwise as seen: front
    EXIT_IF bnez, a1                    # back face, culled
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
4:  EXIT_IF bgt, a4, a5                 # nothing on screen
    EXIT_IF bgt, a6, a7
    la      t3, raster_band             # nothing in this hart's band
    add     t3, t3, tp
    lwu     a2, BAND_FIRST(t3)
    EXIT_IF bgt, a2, a7
    lwu     a3, BAND_END(t3)
    EXIT_IF bge, a6, a3
    EXIT_IF bge, a2, a3                 # (an empty band)
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
    # the reversed depth c1 (1 / w) - c0 (render.inc), or DEPTH16_NEAR + z /
    # w * DEPTH16_SPAN for 16-bit depth
    la      t3, raster_depth_mode
    ld      t3, 0(t3)
    bnez    t3, 4f
    la      t3, raster_depth_reverse
    flw     ft5, DEPTH_REVERSE_C1(t3)
    flw     ft6, DEPTH_REVERSE_C0(t3)
    flw     ft11, RV_Q(t0)
    flw     ft4, RV_Q(t1)
    flw     ft0, RV_Q(t2)
    fmsub.s ft11, ft11, ft5, ft6
    fmsub.s ft4, ft4, ft5, ft6
    fmsub.s ft0, ft0, ft5, ft6
    DEPTH_GRADIENT
    j       6f
4:  flw     ft11, RV_Z(t0)
    flw     ft4, RV_Z(t1)
    flw     ft0, RV_Z(t2)
    li      t3, F32_DEPTH16_SPAN
    fmv.w.x ft5, t3
    li      t3, F32_DEPTH16_NEAR
    fmv.w.x ft6, t3
    fmadd.s ft11, ft11, ft5, ft6
    fmadd.s ft4, ft4, ft5, ft6
    fmadd.s ft0, ft0, ft5, ft6
5:  GRADIENT ft11, ft4, ft0, fa4, ft4, ft0
6:  # depth is evaluated from its plane at every pixel (raster_fills.S
    # PLANES_DOWN, NEXT_PIXEL), not summed step by step: a step under half
    # an ulp of the depth would be lost at every addition
    fsw     ft0, RT_DEPTH_ORIGIN(sp)
    fmv.w.x fs10, zero                  # fs10 = rows below ymin
    li      t3, F32_ONE
    fmv.w.x fs11, t3                    # fs11 = 1.0
    andi    t3, t5, RASTER_GOURAUD
    beqz    t3, 5f
    la      t3, raster_phong
    ld      t3, 0(t3)
    bnez    t3, 47f
    # Gouraud: the intensity k (fs0 at the pixel, fs1 per pixel right, fs2 at
    # the row's first pixel, fs3 per row)
    flw     ft11, RV_K(t0)
    flw     fs3, RV_K(t1)
    flw     fs2, RV_K(t2)
    GRADIENT ft11, fs3, fs2, fs1, fs3, fs2
    j       5f
    # Phong: the normal's planes (steps right in fs0, fs1, fs3; the rest in
    # the frame, RT_PHONG_*) and the light's ambient and quantisation
47: PHONG_PLANE RV_NA, 0, fs0
    PHONG_PLANE RV_NB, 4, fs1
    PHONG_PLANE RV_NC, 8, fs3
    la      t3, scene
    flw     ft1, SCENE_AMBIENT(t3)
    fsw     ft1, RT_PHONG_AMBIENT(sp)
    la      t3, light_quantum
    flw     ft1, LIGHT_QUANTUM_LEVELS(t3)
    fsw     ft1, RT_PHONG_LEVELS(sp)
    flw     ft1, LIGHT_QUANTUM_STEP(t3)
    fsw     ft1, RT_PHONG_STEP(sp)
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
    OVER_W  RV_S, ft11, ft6, ft2
    GRADIENT ft11, ft6, ft2, fa6, ft6, ft2
    OVER_W  RV_T, ft11, ft7, ft3
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
    li      t3, F32_ONE                 # ft11 = the footprint's reach
    fmv.w.x ft11, t3
    andi    t3, t5, RASTER_SUPERSAMPLE  # supersampled: the four samples average
    beqz    t3, 60f                     # the pixel, each sampling a quarter of its
    li      t3, F32_SAMPLE_AREA         # area, so the level is one finer (rho^2 / 4):
    fmv.w.x ft10, t3                    # a pixel's level would blur once more
    fmul.s  ft9, ft9, ft10
    li      t3, F32_HALF                # (half the reach: anisotropic)
    fmv.w.x ft11, t3
60: la      t3, raster_mip_rho2
    add     t3, t3, tp                  # (this hart's)
    fsw     ft9, 0(t3)
    la      t3, raster_mip_footprint
    add     t3, t3, tp
    fsw     ft11, 0(t3)
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
    # from row to row (integers by multiples, depth from its plane, the other
    # floats one addition a row), so every value in the band is bit for bit
    # what a whole-screen draw gives.
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
    fcvt.s.l fs10, a0                   # depth: from its plane a0 rows down
    flw     ft9, RT_DEPTH_ORIGIN(sp)
    fmadd.s ft0, ft4, fs10, ft9
64: fadd.s  ft1, ft1, ft5               # the other planes (unused ones too: harmless)
    fadd.s  ft2, ft2, ft6
    fadd.s  ft3, ft3, ft7
    fadd.s  fs2, fs2, fs3
    addi    a0, a0, -1
    bnez    a0, 64b
65:
    # --- the fill loop for these settings: raster_fills[flags | depth16 << 3]
    # (or raster_fills_wide's: raster_fill_table)
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
    la      t3, raster_fill_table
    ld      t3, 0(t3)
    add     t3, t3, t0
    ld      t3, 0(t3)
    jr      t3
