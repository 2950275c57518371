# render_wireframe.S: the wireframe. The mesh's unique edges (each edge
# shared by two triangles once: render_edges.S edges_build, at render_init)
# are drawn in WIRE_COLOUR over the background, without depth test or
# culling: trivially rejected by outcodes, cut at the near plane and the
# guard band in clip space (Liang-Barsky; the planes of render_clip.S),
# clipped to the screen and drawn with Bresenham's algorithm
# (raster_segment), by coverage with antialias = edge (raster_aa_line), or
# as their union with antialias = supersample (raster_union_line, then
# raster_union_resolve once all are in; raster_lines.S).

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"
    .include "frame.inc"

    .text
    .globl render_wireframe
# render_wireframe
#   What: draws the unique edge list (file comment).
#   Arguments: a0 = vertex records.
#   Results: none.
#   Clobbers: only ABI temporaries.
render_wireframe:
    FRAME_SAVE 64, ra, s0, s1, s2, s3, s4
    mv      s0, a0                      # s0 = vertex records
    la      t0, edge_list
    ld      s1, 0(t0)                   # s1 = edge
    la      t0, edge_count
    ld      s2, 0(t0)                   # s2 = edges left
    beqz    s2, 9f
1:  ld      t0, 0(s1)
    srli    t1, t0, EDGE_INDEX_SHIFT    # smaller index
    slli    t0, t0, EDGE_INDEX_SHIFT
    srli    t0, t0, EDGE_INDEX_SHIFT    # larger index
    li      t2, VTX_BYTES
    mul     t1, t1, t2
    add     s3, s0, t1                  # s3 = a
    mul     t0, t0, t2
    add     s4, s0, t0                  # s4 = b
    lw      t0, VTX_OUTCODE(s3)
    lw      t1, VTX_OUTCODE(s4)
    and     t2, t0, t1
    andi    t2, t2, OUT_FRUSTUM
    bnez    t2, 8f                      # both outside one plane
    or      a2, t0, t1
    andi    t2, a2, OUT_CLIP
    beqz    t2, 3f
    # an end behind the near plane or beyond the guard band: cut in clip
    # space (the ends' positions from vertex_clip), from the end in front
    # of the near plane when one is behind
    mv      s3, a2                      # s3 = outcodes ORed
    ld      t1, 0(s1)
    srli    a0, t1, EDGE_INDEX_SHIFT    # a0 = a, a1 = b
    slli    a1, t1, EDGE_INDEX_SHIFT
    srli    a1, a1, EDGE_INDEX_SHIFT
    andi    t0, t0, OUT_NEAR
    beqz    t0, 2f
    mv      t0, a0
    mv      a0, a1
    mv      a1, t0
2:  mv      s4, a1
    la      a1, segment_ends
    add     a1, a1, tp
    call    vertex_clip
    mv      a0, s4
    la      a1, segment_ends + CLIP_POS_BYTES
    add     a1, a1, tp
    call    vertex_clip
    la      a0, segment_ends
    add     a0, a0, tp
    la      a1, segment_ends + CLIP_POS_BYTES
    add     a1, a1, tp
    mv      a2, s3
    call    clip_segment
    beqz    a0, 8f                      # nothing left
    la      t0, vertex_snap_kept        # the union lines: the ends before
    ld      t0, 0(t0)                   # snapping
    bnez    t0, 6f
    mv      a0, a1
    mv      a1, a2
    mv      a2, a3
    mv      a3, a4
    j       4f
3:  la      t0, vertex_snap_kept
    ld      t0, 0(t0)
    bnez    t0, 7f
    lw      a0, VTX_SX(s3)
    lw      a1, VTX_SY(s3)
    lw      a2, VTX_SX(s4)
    lw      a3, VTX_SY(s4)
4:  li      t0, F32_Q4_TO_PIXEL         # Q4 to pixels
    fmv.w.x ft0, t0
    fcvt.s.w fa0, a0
    fmul.s  fa0, fa0, ft0
    fcvt.s.w fa1, a1
    fmul.s  fa1, fa1, ft0
    fcvt.s.w fa2, a2
    fmul.s  fa2, fa2, ft0
    fcvt.s.w fa3, a3
    fmul.s  fa3, fa3, ft0
    li      a0, WIRE_COLOUR
    la      t0, scene                   # antialias: lines by coverage, or
    lwu     t0, SCENE_ANTIALIAS(t0)     # (supersample) their union's
    li      t1, ANTIALIAS_SUPERSAMPLE
    beq     t0, t1, 6f
    li      t1, ANTIALIAS_OFF
    beq     t0, t1, 5f
    call    raster_aa_line
    j       8f
6:  call    raster_union_line
    j       8f
    # the union lines (render_init keeps the snap's residual for them): the
    # ends where they project before snapping, Q4 / 16 + residual 2^-15
7:  li      t0, F32_Q4_TO_PIXEL
    fmv.w.x ft2, t0
    li      t0, F32_SNAP_UNIT
    fmv.w.x ft3, t0
    UNSNAPPED s3, VTX_SNAP_X, VTX_SX, fa0
    UNSNAPPED s3, VTX_SNAP_Y, VTX_SY, fa1
    UNSNAPPED s4, VTX_SNAP_X, VTX_SX, fa2
    UNSNAPPED s4, VTX_SNAP_Y, VTX_SY, fa3
    j       6b
5:  call    raster_segment
8:  addi    s1, s1, EDGE_BYTES
    addi    s2, s2, -1
    bnez    s2, 1b
9:  la      t1, scene                   # supersample: the union drawn
    lwu     t0, SCENE_ANTIALIAS(t1)
    li      t2, ANTIALIAS_SUPERSAMPLE
    bne     t0, t2, 10f
    li      a0, WIRE_COLOUR
    lwu     a1, SCENE_BACKGROUND(t1)
    call    raster_union_resolve
10: FRAME_RESTORE 64, ra, s0, s1, s2, s3, s4
    ret

# clip_segment (file-local)
#   What: the part of an edge a -> b in front of the near plane and inside
#         the guard band (Liang-Barsky in clip space, against the planes an
#         end is outside of: t from 0 to 1 narrowed at each crossing), its
#         ends projected (project_clip). An end that is not cut off is the
#         vertex itself, exactly.
#   Arguments: a0 = a's clip-space position (CLIP_POS_BYTES), a1 = b's,
#              a2 = their outcodes ORed.
#   Results: a0 = 1 when a part is left, else 0; then a1, a2 = its end
#            towards a (screen x, y in Q4), a3, a4 = its end towards b;
#            fa0, fa1 and fa2, fa3 = the same ends in pixels before snapping
#            (the union lines').
#   Clobbers: only ABI temporaries.
clip_segment:
    FRAME_SAVE 96, ra, s0, s1, s2, s3, s4, fs0, fs1, fs2
    mv      s0, a0                      # s0 = a
    mv      s1, a1                      # s1 = b
    mv      s2, a2                      # s2 = outcodes
    fmv.w.x fs0, zero                   # fs0 = t entering
    li      t0, F32_ONE
    fmv.w.x fs1, t0                     # fs1 = t leaving
    li      s3, 0                       # s3 = plane number
1:  mv      a0, s3
    mv      a1, s2
    call    clip_plane
    beqz    a0, 5f                      # no end outside it
    mv      s4, a0                      # s4 = plane
    mv      a0, s0
    mv      a1, s4
    call    plane_distance
    fmv.s   fs2, fa0                    # fs2 = d(a)
    mv      a0, s1
    mv      a1, s4
    call    plane_distance              # fa0 = d(b)
    fmv.w.x ft0, zero
    fle.s   t0, ft0, fs2
    xori    t0, t0, 1                   # t0 = a outside
    fle.s   t1, ft0, fa0
    xori    t1, t1, 1                   # t1 = b outside
    and     t2, t0, t1
    bnez    t2, 8f                      # both outside: nothing left
    or      t2, t0, t1
    beqz    t2, 5f
    fsub.s  ft1, fs2, fa0
    fdiv.s  ft1, fs2, ft1               # the crossing, d(a) / (d(a) - d(b))
    beqz    t0, 3f
    fmax.s  fs0, fs0, ft1               # a outside: enters there
    j       5f
3:  fmin.s  fs1, fs1, ft1               # b outside: leaves there
5:  addi    s3, s3, 1
    li      t0, CLIP_PLANES
    bne     s3, t0, 1b
    flt.s   t0, fs1, fs0
    bnez    t0, 8f                      # leaves before it enters
    mv      a0, s0
    mv      a1, s1
    fmv.s   fa0, fs0
    call    segment_point
    call    project_clip
    mv      s3, a0
    mv      s4, a1
    fsw     fa2, 0(sp)                  # unsnapped, from the screen's centre
    fsw     fa3, 4(sp)
    mv      a0, s0
    mv      a1, s1
    fmv.s   fa0, fs1
    call    segment_point
    call    project_clip
    mv      a3, a0
    mv      a4, a1
    mv      a1, s3
    mv      a2, s4
    li      a0, LCD_WIDTH / 2           # the unsnapped ends from the corner
    fcvt.s.w ft0, a0
    li      a0, LCD_HEIGHT / 2
    fcvt.s.w ft1, a0
    fadd.s  fa2, fa2, ft0
    fadd.s  fa3, fa3, ft1
    flw     fa0, 0(sp)
    fadd.s  fa0, fa0, ft0
    flw     fa1, 4(sp)
    fadd.s  fa1, fa1, ft1
    li      a0, 1
    j       9f
8:  li      a0, 0
9:  FRAME_RESTORE 96, ra, s0, s1, s2, s3, s4, fs0, fs1, fs2
    ret

# segment_point (file-local)
#   What: the clip-space point a + t (b - a) of an edge; at t = 1, b itself
#         (as b + 0 (a - b)), so that an end not cut off is the vertex.
#   Arguments: a0 = a's clip-space position, a1 = b's, fa0 = t (0 .. 1).
#   Results: fa0, fa1, fa2, fa3 = clip x, y, z, w (project_clip's arguments).
#   Clobbers: only ABI temporaries.
segment_point:
    li      t0, F32_ONE
    fmv.w.x ft0, t0
    feq.s   t0, fa0, ft0
    fmv.s   ft0, fa0                    # ft0 = t from a0's end towards a1's
    beqz    t0, 1f
    mv      t0, a0
    mv      a0, a1
    mv      a1, t0
    fmv.w.x ft0, zero
1:  flw     ft1, CLIP_POS_X(a0)
    flw     ft2, CLIP_POS_X(a1)
    fsub.s  ft2, ft2, ft1
    fmadd.s fa0, ft2, ft0, ft1
    flw     ft1, CLIP_POS_Y(a0)
    flw     ft2, CLIP_POS_Y(a1)
    fsub.s  ft2, ft2, ft1
    fmadd.s fa1, ft2, ft0, ft1
    flw     ft1, CLIP_POS_Z(a0)
    flw     ft2, CLIP_POS_Z(a1)
    fsub.s  ft2, ft2, ft1
    fmadd.s fa2, ft2, ft0, ft1
    flw     ft1, CLIP_POS_W(a0)
    flw     ft2, CLIP_POS_W(a1)
    fsub.s  ft2, ft2, ft1
    fmadd.s fa3, ft2, ft0, ft1
    ret
