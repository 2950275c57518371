# render_clip.S: clipping in homogeneous clip space (render_triangles.S,
# step 4), only where it is needed: a triangle with a corner behind the near
# plane (clip z >= 0) or beyond the guard band (|x|, |y| <= 16 w, render.inc
# GUARD_BAND) is cut against each of those planes one of its corners is
# outside of (Sutherland-Hodgman), the new corners interpolated linearly in
# clip space (x, y, z, w, s, t, k and Phong's normal), and drawn as a fan. The corners'
# clip-space positions come from vertex.S vertex_clip: the vertex stage's
# own values, computed again. An edge is always cut from its corner inside
# towards the one outside, so the two triangles sharing an edge compute
# bit-identical new corners (no cracks). The screen's own sides are left to
# the rasteriser's bounding box, the far plane to the depth test (whose
# clear value is the far plane): the guard band only keeps projected
# positions small enough to be exact in Q4 and in the attribute planes.
# Without it, a corner projecting beyond 2^23 pixels would be clamped,
# bending the triangle. The planes are render.S's clip_planes; clip_plane
# and plane_distance serve the wireframe's cuts too (render_wireframe.S).

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"
    .include "frame.inc"

    .text
    .globl clip_and_draw
# clip_and_draw
#   What: a triangle with a corner behind the near plane or beyond the guard
#         band (file comment): cut in clip space against each plane
#         one of its corners is outside of, projected, and drawn as a fan of
#         triangles (0, 1, 2), then (i, i + 1, 0) for i = 2, 3, ...
#   Arguments: a0 = the face (its texel coordinates and intensities in
#              render_rv), a3 = cull, a4 = colour or
#              intensity, a5 = fill mode (raster_triangle's a1..a3), a6 =
#              the corners' outcodes ORed.
#   Results: none.
#   Clobbers: only ABI temporaries.
clip_and_draw:
    FRAME_SAVE 80, ra, s0, s1, s2, s3, s4, s5, s6, s7
    mv      s3, a3
    mv      s4, a4
    mv      s5, a5
    mv      s6, a6                      # s6 = outcodes
    # the corners as clip vertices: clip-space positions (vertex_clip, as
    # the vertex stage found them), texel coordinates and intensities
    mv      s0, a0                      # s0 = corner
    la      s1, clip_polygon_a          # s1 = its clip vertex
    add     s1, s1, tp
    la      s2, render_rv               # s2 = its raster vertex
    add     s2, s2, tp
    li      s7, TRIANGLE_CORNERS
1:  ld      a0, 0(s0)
    slli    a0, a0, MESH_INDEX_LOW_SHIFT
    srli    a0, a0, MESH_INDEX_LOW_SHIFT
    addi    a1, s1, CV_X
    call    vertex_clip
    lw      t3, RV_S(s2)
    sw      t3, CV_S(s1)
    lw      t3, RV_T(s2)
    sw      t3, CV_T(s1)
    lw      t3, RV_K(s2)
    sw      t3, CV_K(s1)
    lw      t3, RV_NA(s2)               # (Phong's normal)
    sw      t3, CV_NA(s1)
    lw      t3, RV_NB(s2)
    sw      t3, CV_NB(s1)
    lw      t3, RV_NC(s2)
    sw      t3, CV_NC(s1)
    addi    s0, s0, MESH_CORNER_BYTES
    addi    s1, s1, CV_BYTES
    addi    s2, s2, RV_BYTES
    addi    s7, s7, -1
    bnez    s7, 1b

    # each plane in turn, the output of one the input of the next
    la      s0, clip_polygon_a          # s0 = the polygon
    add     s0, s0, tp
    la      s1, clip_polygon_b          # s1 = the other buffer
    add     s1, s1, tp
    li      s2, TRIANGLE_CORNERS        # s2 = its corners
    li      s7, 0                       # s7 = plane number (clip_planes)
2:  mv      a0, s7
    mv      a1, s6
    call    clip_plane
    beqz    a0, 4f                      # no corner outside: nothing to cut
    mv      a3, a0
    mv      a0, s0
    mv      a1, s2
    mv      a2, s1
    call    clip_polygon
    mv      s2, a0
    mv      t0, s0
    mv      s0, s1
    mv      s1, t0
    li      t0, TRIANGLE_CORNERS
    blt     s2, t0, 9f                  # nothing left
4:  addi    s7, s7, 1
    li      t0, CLIP_PLANES
    bne     s7, t0, 2b

    # project the corners into render_rv_out
    mv      s7, s2                      # s7 = corners left
    la      s1, render_rv_out
    add     s1, s1, tp
5:  flw     fa0, CV_X(s0)
    flw     fa1, CV_Y(s0)
    flw     fa2, CV_Z(s0)
    flw     fa3, CV_W(s0)
    call    project_clip
    sw      a0, RV_X(s1)
    sw      a1, RV_Y(s1)
    fsw     fa0, RV_Z(s1)
    fsw     fa1, RV_Q(s1)
    fsw     fa2, RV_FX(s1)
    fsw     fa3, RV_FY(s1)
    lw      t1, CV_S(s0)
    sw      t1, RV_S(s1)
    lw      t1, CV_T(s0)
    sw      t1, RV_T(s1)
    lw      t1, CV_K(s0)
    sw      t1, RV_K(s1)
    lw      t1, CV_NA(s0)
    sw      t1, RV_NA(s1)
    lw      t1, CV_NB(s0)
    sw      t1, RV_NB(s1)
    lw      t1, CV_NC(s0)
    sw      t1, RV_NC(s1)
    addi    s0, s0, CV_BYTES
    addi    s1, s1, RV_BYTES
    addi    s7, s7, -1
    bnez    s7, 5b

    # the fan
    la      a0, render_rv_out
    add     a0, a0, tp
    mv      a1, s3
    mv      a2, s4
    mv      a3, s5
    call    raster_triangle             # corners 0, 1, 2
    li      s7, 2                       # s7 = i
6:  addi    t0, s7, 2
    bgt     t0, s2, 9f                  # i + 1 is past the last corner
    la      a0, render_rv_fan
    add     a0, a0, tp
    li      t0, RV_BYTES
    mul     t0, t0, s7
    la      a1, render_rv_out
    add     a1, a1, tp
    add     a1, a1, t0
    li      a2, 2 * RV_BYTES
    call    rv_copy                     # corners i, i + 1
    la      a0, render_rv_fan + 2 * RV_BYTES
    add     a0, a0, tp
    la      a1, render_rv_out
    add     a1, a1, tp
    li      a2, RV_BYTES
    call    rv_copy                     # corner 0
    la      a0, render_rv_fan
    add     a0, a0, tp
    mv      a1, s3
    mv      a2, s4
    mv      a3, s5
    call    raster_triangle
    addi    s7, s7, 1
    j       6b
9:  FRAME_RESTORE 80, ra, s0, s1, s2, s3, s4, s5, s6, s7
    ret

# clip_polygon (file-local)
#   What: one Sutherland-Hodgman step: the part of a convex polygon inside
#         one clip plane. For each edge a -> b: a when it is inside, then
#         the crossing point when exactly one of a, b is, always cut from the
#         inside corner towards the outside one, so that two triangles
#         sharing an edge cut it into bit-identical corners (no cracks). A
#         cut on the near plane gets z = 0 exactly (its depth is the near
#         plane's).
#   Arguments: a0 = corners (clip vertices), a1 = their count (at least
#              3), a2 = output (room for a1 + a1 / 2: see CLIP_MAX_OUT),
#              a3 = the plane (in clip_planes, whose first is the near
#              plane).
#   Results: a0 = the output's corner count.
#   Clobbers: only ABI temporaries.
clip_polygon:
    FRAME_SAVE 96, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, fs0, fs1
    mv      s0, a0                      # s0 = a
    mv      s1, a2                      # s1 = next output
    mv      s2, a2                      # s2 = output start
    li      t0, CV_BYTES
    mul     t0, t0, a1
    add     s3, a0, t0                  # s3 = end of the corners
    mv      s4, a0                      # s4 = first corner (b of the last edge)
    mv      s5, a3                      # s5 = plane
    la      s6, clip_planes             # s6 = the near plane
    mv      a1, s5
    call    plane_distance
    fmv.s   fs0, fa0                    # fs0 = d(a)
1:  addi    s7, s0, CV_BYTES            # s7 = b
    bltu    s7, s3, 2f
    mv      s7, s4
2:  mv      a0, s7
    mv      a1, s5
    call    plane_distance
    fmv.s   fs1, fa0                    # fs1 = d(b)
    fmv.w.x ft0, zero
    fle.s   s8, ft0, fs0                # s8 = a inside
    beqz    s8, 3f
    mv      a0, s1
    mv      a1, s0
    call    cv_copy
    addi    s1, s1, CV_BYTES
3:  fmv.w.x ft0, zero
    fle.s   t1, ft0, fs1                # b inside
    beq     s8, t1, 5f                  # both on the same side
    mv      a1, s0                      # cut from the corner inside
    mv      a2, s7
    fmv.s   fa0, fs0
    fmv.s   fa1, fs1
    bnez    s8, 4f
    mv      a1, s7
    mv      a2, s0
    fmv.s   fa0, fs1
    fmv.s   fa1, fs0
4:  mv      a0, s1
    call    cv_cut
    bne     s5, s6, 41f
    sw      zero, CV_Z(s1)              # on the near plane
41: addi    s1, s1, CV_BYTES
5:  fmv.s   fs0, fs1                    # b is the next edge's a
    addi    s0, s0, CV_BYTES
    bltu    s0, s3, 1b
    sub     a0, s1, s2
    li      t0, CV_BYTES
    divu    a0, a0, t0
    FRAME_RESTORE 96, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, fs0, fs1
    ret

    .globl clip_plane
# clip_plane
#   What: plane n of clip_planes if a shape with these corners must be cut
#         against it: the near plane (n = 0) when a corner is behind it
#         (OUT_NEAR), a side of the guard band (n = 1 .. 4) when a corner is
#         beyond the band (OUT_GUARD).
#   Arguments: a0 = n, a1 = the corners' outcodes ORed.
#   Results: a0 = the plane's address, or 0 when no corner is outside it.
#   Clobbers: only ABI temporaries.
clip_plane:
    li      t0, OUT_NEAR
    beqz    a0, 1f
    li      t0, OUT_GUARD
1:  and     t0, t0, a1
    beqz    t0, 2f
    li      t0, PLANE_BYTES
    mul     t0, t0, a0
    la      a0, clip_planes
    add     a0, a0, t0
    ret
2:  li      a0, 0
    ret

    .globl plane_distance
# plane_distance
#   What: d = a x + b y + c z + e w of a clip-space point and a plane of
#         clip_planes; the point is inside when d >= 0. For the near plane
#         d is z itself, exactly (the other products are 0).
#   Arguments: a0 = clip vertex or clip-space position (vertex_clip's:
#              both begin with clip x, y, z, w), a1 = plane.
#   Results: fa0 = d.
#   Clobbers: only ABI temporaries.
.if (CV_X != CLIP_POS_X) || (CV_Y != CLIP_POS_Y) || (CV_Z != CLIP_POS_Z) || (CV_W != CLIP_POS_W)
    .error "plane_distance reads clip vertices and clip-space positions alike"
.endif
plane_distance:
    flw     ft0, PLANE_E(a1)
    flw     ft1, CV_W(a0)
    fmul.s  fa0, ft0, ft1
    flw     ft0, PLANE_C(a1)
    flw     ft1, CV_Z(a0)
    fmadd.s fa0, ft0, ft1, fa0
    flw     ft0, PLANE_B(a1)
    flw     ft1, CV_Y(a0)
    fmadd.s fa0, ft0, ft1, fa0
    flw     ft0, PLANE_A(a1)
    flw     ft1, CV_X(a0)
    fmadd.s fa0, ft0, ft1, fa0
    ret

# cv_copy (file-local)
#   What: copies one clip vertex.
#   Arguments: a0 = destination, a1 = source.
#   Results: none.
#   Clobbers: only ABI temporaries.
cv_copy:
    li      a2, CV_BYTES
# rv_copy (file-local)
#   What: copies a2 bytes (a multiple of 4).
#   Arguments: a0 = destination, a1 = source, a2 = bytes.
#   Results: none.
#   Clobbers: only ABI temporaries.
rv_copy:
1:  lw      t5, 0(a1)
    sw      t5, 0(a0)
    addi    a0, a0, 4
    addi    a1, a1, 4
    addi    a2, a2, -4
    bnez    a2, 1b
    ret

# cv_cut (file-local)
#   What: the point where the segment from p (inside a clip plane) to q
#         (outside it) crosses the plane: p + t (q - p), t = dp / (dp - dq),
#         every field interpolated.
#   Arguments: a0 = output clip vertex, a1 = p, a2 = q; fa0, fa1 = the
#              plane distances dp, dq (plane_distance).
#   Results: none.
#   Clobbers: only ABI temporaries.
cv_cut:
    fsub.s  ft1, fa0, fa1
    fdiv.s  ft0, fa0, ft1               # ft0 = t
    li      t0, CV_BYTES / 4
1:  flw     ft1, 0(a1)
    flw     ft2, 0(a2)
    fsub.s  ft2, ft2, ft1
    fmadd.s ft1, ft2, ft0, ft1
    fsw     ft1, 0(a0)
    addi    a0, a0, 4
    addi    a1, a1, 4
    addi    a2, a2, 4
    addi    t0, t0, -1
    bnez    t0, 1b
    ret
