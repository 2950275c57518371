# render_triangles.S: every triangle of a band (draw_triangles; modes textured
# and flat), each in these steps:
#   1. Trivial rejection: the three vertices outside the same frustum plane
#      (their outcodes share one of the six OUT_FRUSTUM bits, vertex.S) ->
#      skipped. A back face wholly in front of the near plane is dropped
#      when culling, and a triangle whose rows all lie outside the band is
#      skipped, both before any work on it.
#   2. Lighting per face, or per corner with Gouraud shading
#      (render_light.S): an intensity k in 0 .. 64; with Phong shading the
#      corners' normals, lit per pixel by the fills. Flat mode draws
#      FLAT_BASE_COLOUR (0xC618, light grey) with every RGB565 channel times
#      k / 64; textured mode multiplies each texel the same way.
#   3. Texture coordinates (textured; render_texels.S).
#   4. Clipping in homogeneous clip space, only where it is needed: a
#      triangle with a corner behind the near plane or beyond the guard band
#      is cut and drawn as a fan (render_clip.S).
#   5. raster_triangle (raster_triangle.S): back-face culling (SCENE_CULL),
#      fill, depth test. With antialias = edge each corner also says what
#      lies across the edge opposite it (aa_neighbours, render_edges.S), so
#      that raster_triangle antialiases silhouette edges only; with
#      antialias = supersample render_band (render.S) draws its band once
#      per sample and takes the means.

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"
    .include "frame.inc"

    .text
    .globl draw_triangles
# draw_triangles
#   What: every triangle's pixels in rows a0 .. a1 - 1 (render_band's loop:
#         the file comment's steps; a triangle whose rows all lie outside is
#         skipped before its lighting and texture set-up).
#   Arguments: a0 = first row, a1 = the row past the last, a2 = vertex
#              records.
#   Results: none.
#   Clobbers: only ABI temporaries.
draw_triangles:
    FRAME_SAVE 112, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11
    mv      s0, a0                      # s0 = the band's first row
    mv      s2, a1                      # s2 = the row past its last
    mv      s1, a2                      # s1 = vertex records
    la      t1, scene
    ld      s3, MESH_F(t1)              # s3 = face
    lwu     s4, MESH_FCOUNT(t1)         # s4 = faces left
    la      t0, render_fill
    lwu     s10, 0(t0)                  # s10 = RASTER_FLAT / RASTER_TEXTURED
    lwu     s11, SCENE_CULL(t1)         # s11 = cull
    beqz    s4, 9f
2:  # s5, s6, s7 = the corners' vertex records
    ld      t0, 0(s3)
    slli    t0, t0, MESH_INDEX_LOW_SHIFT
    srli    t0, t0, MESH_INDEX_LOW_SHIFT
    ld      t1, MESH_CORNER_BYTES(s3)
    slli    t1, t1, MESH_INDEX_LOW_SHIFT
    srli    t1, t1, MESH_INDEX_LOW_SHIFT
    ld      t2, 2 * MESH_CORNER_BYTES(s3)
    slli    t2, t2, MESH_INDEX_LOW_SHIFT
    srli    t2, t2, MESH_INDEX_LOW_SHIFT
    li      t3, VTX_BYTES
    mul     t0, t0, t3
    add     s5, s1, t0
    mul     t1, t1, t3
    add     s6, s1, t1
    mul     t2, t2, t3
    add     s7, s1, t2
    lw      t0, VTX_OUTCODE(s5)
    lw      t1, VTX_OUTCODE(s6)
    lw      t2, VTX_OUTCODE(s7)
    and     t3, t0, t1
    and     t3, t3, t2
    andi    t3, t3, OUT_FRUSTUM
    bnez    t3, 8f                      # all outside one plane
    or      s8, t0, t1
    or      s8, s8, t2                  # s8 = outcodes of any corner
    # A back face in front of the near plane is dropped before the work on
    # it: the same signed area (from the same Q4 positions) raster_triangle
    # would find.
    beqz    s11, 10f
    andi    t0, s8, OUT_CLIP
    bnez    t0, 1f
    lw      t0, VTX_SX(s5)
    lw      t1, VTX_SY(s5)
    lw      t2, VTX_SX(s6)
    sub     t2, t2, t0
    lw      t3, VTX_SY(s7)
    sub     t3, t3, t1
    mul     t2, t2, t3                  # (x1 - x0)(y2 - y0)
    lw      t3, VTX_SX(s7)
    sub     t3, t3, t0
    lw      t4, VTX_SY(s6)
    sub     t4, t4, t1
    mul     t3, t3, t4                  # (x2 - x0)(y1 - y0)
    bge     t2, t3, 8f                  # area >= 0: back face or degenerate
    # Outside the band: the rows of its pixel centres as raster_triangle
    # finds them (a clipped triangle is left to raster_triangle).
10: andi    t0, s8, OUT_CLIP
    bnez    t0, 1f
    lw      t0, VTX_SY(s5)
    lw      t1, VTX_SY(s6)
    lw      t2, VTX_SY(s7)
    mv      t3, t0                      # t3 = min y
    ble     t3, t1, 11f
    mv      t3, t1
11: ble     t3, t2, 11f
    mv      t3, t2
11: mv      t4, t0                      # t4 = max y
    bge     t4, t1, 11f
    mv      t4, t1
11: bge     t4, t2, 11f
    mv      t4, t2
11: andi    t0, s10, RASTER_EDGE_AA | RASTER_SUPERSAMPLE
    beqz    t0, 12f
    addi    t3, t3, -AA_BOX_GROW        # coverage reaches half a pixel further
    addi    t4, t4, AA_BOX_GROW         # (raster_triangle's grown box), samples
                                        # lie up to 3/8 of a pixel off the centre
12: addi    t3, t3, SUBPIXEL_CEIL       # first row: (min + 7) >> 4
    srai    t3, t3, SUBPIXEL_BITS
    addi    t4, t4, -SUBPIXEL_HALF      # last row: (max - 8) >> 4
    srai    t4, t4, SUBPIXEL_BITS
    blt     t4, s0, 8f
    bge     t3, s2, 8f
1:  andi    t0, s10, RASTER_GOURAUD
    bnez    t0, 20f
    mv      a0, s3
    call    face_light
    mv      s9, a0                      # s9 = intensity, or the lit colour
    andi    t0, s10, RASTER_TEXTURED
    bnez    t0, 3f
    mv      a1, a0
    li      a0, FLAT_BASE_COLOUR
    call    shade_rgb565
    mv      s9, a0
    j       4f
20: mv      a0, s3                      # Gouraud: RV_K of render_rv
    la      t0, raster_phong
    ld      t0, 0(t0)
    bnez    t0, 21f
    call    corner_light
    j       22f
21: call    corner_phong                # Phong: RV_NA .. RV_NC
22:    li      s9, FLAT_BASE_COLOUR        # (flat fill: lit per pixel)
    andi    t0, s10, RASTER_TEXTURED
    beqz    t0, 4f
3:  mv      a0, s3
    call    face_texels                 # RV_S, RV_T of render_rv
4:  andi    t0, s8, OUT_CLIP
    bnez    t0, 6f
    # in front of the near plane and inside the guard band: the vertex
    # records' projections
    la      a0, render_rv
    add     a0, a0, tp
    mv      t0, a0
    mv      t1, s5                      # t1 = corner 0, then t4, then t5
    mv      t4, s6
    mv      t5, s7
    li      t2, TRIANGLE_CORNERS
    la      a2, vertex_snap_kept
    ld      a2, 0(a2)                   # a2 = the records keep the snap's residual
5:  lw      t3, VTX_SX(t1)
    sw      t3, RV_X(t0)
    lw      t3, VTX_SY(t1)
    sw      t3, RV_Y(t0)
    lw      t3, VTX_ZW(t1)
    sw      t3, RV_Z(t0)
    lw      t3, VTX_Q(t1)
    sw      t3, RV_Q(t0)
    beqz    a2, 51f
    # float32 depth: the corner before snapping (RV_FX, RV_FY), pixels from
    # the screen's centre: the snapped position plus the snap's residual
    li      t3, F32_Q4_TO_PIXEL
    fmv.w.x ft2, t3
    li      t3, F32_SNAP_UNIT
    fmv.w.x ft3, t3
    UNSNAPPED t1, VTX_SNAP_X, VTX_SX, ft0, SCREEN_HALF_W_Q4
    fsw     ft0, RV_FX(t0)
    UNSNAPPED t1, VTX_SNAP_Y, VTX_SY, ft0, SCREEN_HALF_H_Q4
    fsw     ft0, RV_FY(t0)
51: addi    t0, t0, RV_BYTES
    mv      t1, t4
    mv      t4, t5
    addi    t2, t2, -1
    bnez    t2, 5b
    andi    t0, s10, RASTER_EDGE_AA
    beqz    t0, 7f
    mv      a0, s3
    mv      a1, s1
    la      a2, render_rv
    add     a2, a2, tp
    call    aa_neighbours
7:  la      a0, render_rv
    add     a0, a0, tp
    mv      a1, s11
    mv      a2, s9
    mv      a3, s10
    call    raster_triangle
    j       8f
    # cut in clip space: drawn hard (the fan's corners carry no neighbours)
6:  mv      a0, s3
    mv      a3, s11
    mv      a4, s9
    andi    a5, s10, ~RASTER_EDGE_AA
    mv      a6, s8
    call    clip_and_draw
8:  addi    s3, s3, MESH_F_BYTES
    addi    s4, s4, -1
    bnez    s4, 2b

9:  FRAME_RESTORE 112, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11
    ret
