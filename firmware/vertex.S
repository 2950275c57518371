# vertex.S: the per-frame vertex stage. Once a frame it builds the model
# matrix (scale, rotation by a quaternion about SCENE_AXIS by SCENE_ANGLE +
# frame * SCENE_STEP, translation), the perspective projection (SCENE_FOV,
# aspect LCD_WIDTH / LCD_HEIGHT, SCENE_NEAR, SCENE_FAR) and their product
# (vertex_setup), then transforms every mesh vertex once into a VTX_BYTES
# record (vertex_range, over the whole mesh or, when both harts draw, each
# hart over its share of it: render.S render_vertex_share; render.inc):
#   outcode (which frustum planes its clip-space position is outside of, and
#   whether it lies beyond the guard band), and, for vertices in front of the
#   near plane and inside the guard band, the projected screen position in
#   Q4, z / w and 1 / w (project_clip).
# With flat shading it also fills vertex_world_array, every vertex's
# world-space position (the faces' lighting). Triangles and edges then only
# look these up (render_triangles.S, render_wireframe.S). The few that need a vertex's clip-space position
# (to be cut) ask vertex_clip, which computes it again, bit for bit as here,
# rather than keep it for every vertex; so do Gouraud's faces without
# normals for their world-space positions (face_world).
#
# The camera sits at the origin looking down -z, so world space is also eye
# space: no view matrix.

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"
    .include "frame.inc"

# SNAP_RESIDUAL q4, exact, half
#   t1 = how far snapping moved one coordinate of a projected corner: exact
#   (pixels from the screen's centre, project_clip's fa2 or fa3) minus q4
#   (its snapped Q4 position; half = the centre's), in 2^-15 pixel (render.inc
#   F32_SNAP_*), clamped to half a pixel (which only snap = pixel's ties
#   reach, and NaN positions pass).
#   Clobbers t0, ft0, ft1.
.macro SNAP_RESIDUAL q4, exact, half
    li      t0, \half
    sub     t0, \q4, t0
    fcvt.s.w ft0, t0
    li      t0, F32_Q4_TO_PIXEL
    fmv.w.x ft1, t0
    fmul.s  ft0, ft0, ft1               # snapped, pixels from the centre (exact)
    fsub.s  ft0, \exact, ft0
    li      t0, F32_SNAP_UNITS
    fmv.w.x ft1, t0
    fmul.s  ft0, ft0, ft1
    li      t0, F32_SNAP_LIMIT
    fmv.w.x ft1, t0
    fmin.s  ft0, ft0, ft1
    fneg.s  ft1, ft1
    fmax.s  ft0, ft0, ft1
    fcvt.w.s t1, ft0, rne
.endm

    .text
    .globl vertex_init
# vertex_init
#   What: allocates the vertex records (MESH_VCOUNT of them) from the heap,
#         and, when every drawn face is lit from its corners' world-space
#         positions (shading = flat in a lit mode), an array of those
#         positions, filled once a frame (vertex_world_array; 0 otherwise:
#         Gouraud and Phong shading keep the memory for their normals, which flat
#         shading does not store, and computes the few it needs, face_world).
#         Not enough memory is fatal (heap_alloc_or_fail).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
vertex_init:
    FRAME_SAVE 16, ra, s0
    la      s0, scene
    lwu     a0, MESH_VCOUNT(s0)
    li      t1, VTX_BYTES
    mul     a0, a0, t1
    la      a1, msg_vertex_records
    call    heap_alloc_or_fail
    la      t0, vertex_records
    sd      a0, 0(t0)
    la      t0, vertex_world_array
    sd      zero, 0(t0)
    lwu     t0, SCENE_MODE(s0)
    li      t1, MODE_WIREFRAME
    beq     t0, t1, 9f
    lwu     t0, SCENE_SHADING(s0)
    li      t1, SHADING_FLAT
    bne     t0, t1, 9f                  # Gouraud, Phong: lit from the normals
    lwu     a0, MESH_VCOUNT(s0)
    li      t1, WORLD_POS_BYTES
    mul     a0, a0, t1
    la      a1, msg_world_positions
    call    heap_alloc_or_fail
    la      t0, vertex_world_array
    sd      a0, 0(t0)
9:  FRAME_RESTORE 16, ra, s0
    ret

    .globl vertex_setup
# vertex_setup
#   What: builds this frame's matrices (the model matrix, the projection
#         and their product: see the file comment), which vertex_range,
#         vertex_clip and face_world read. Once a frame, before any
#         vertex_range of the frame (on both harts: render.S).
#   Arguments: a0 = frame number (unsigned).
#   Results: a0 = the vertex records (VTX_BYTES each, in mesh order).
#   Clobbers: only ABI temporaries.
vertex_setup:
    FRAME_SAVE 16, ra, s0
    la      s0, scene

    # angle = start + frame * step, in double so that long runs keep it exact
    fcvt.d.lu ft0, a0
    flw     ft1, SCENE_STEP(s0)
    fcvt.d.s ft1, ft1
    flw     ft2, SCENE_ANGLE(s0)
    fcvt.d.s ft2, ft2
    fmadd.d fa0, ft0, ft1, ft2
    la      a0, vertex_quat
    addi    a1, s0, SCENE_AXIS
    lwu     a2, SCENE_ANGLES(s0)
    call    quat_from_axis_angle
    la      a0, vertex_rotation
    la      a1, vertex_quat
    call    quat_to_mat3
    la      a0, vertex_model
    la      a1, vertex_rotation
    addi    a2, s0, SCENE_SCALE
    addi    a3, s0, SCENE_TRANSLATE
    call    mat4_model
    li      t0, LCD_WIDTH
    fcvt.s.w ft0, t0
    li      t0, LCD_HEIGHT
    fcvt.s.w ft1, t0
    fdiv.s  fa1, ft0, ft1               # aspect
    flw     fa0, SCENE_FOV(s0)
    flw     fa2, SCENE_NEAR(s0)
    flw     fa3, SCENE_FAR(s0)
    la      a0, vertex_projection
    call    mat4_perspective
    la      a0, vertex_mvp
    la      a1, vertex_projection
    la      a2, vertex_model
    call    mat4_mul
    la      t0, vertex_records
    ld      a0, 0(t0)
    FRAME_RESTORE 16, ra, s0
    ret

    .globl vertex_range
# vertex_range
#   What: fills the vertex records of mesh vertices a0 .. a1 - 1 from this
#         frame's matrices (vertex_setup), and with flat shading their
#         world-space positions (file comment). A vertex's results depend
#         on nothing but the vertex and the matrices, so the two harts may
#         each fill a disjoint range at once (render.S render_vertex_share)
#         and the records are those of one pass over all of them.
#   Arguments: a0 = first vertex, a1 = the vertex past the last (0 <= a0 <=
#              a1 <= MESH_VCOUNT).
#   Results: none.
#   Clobbers: only ABI temporaries.
vertex_range:
    FRAME_SAVE 64, ra, s0, s1, s2, s3, s4, s5
    la      s0, scene
    mv      s4, a0                      # s4 = first vertex
    sub     s5, a1, a0                  # s5 = vertices in the range
    mv      s2, s5                      # s2 = vertices left
    beqz    s2, 9f

    # --- every vertex of the range: clip = P M p, outcode, projection.
    ld      s1, MESH_V(s0)
    li      t0, MESH_V_BYTES
    mul     t0, t0, s4
    add     s1, s1, t0                  # s1 = mesh position
    la      t0, vertex_records
    ld      s3, 0(t0)
    li      t0, VTX_BYTES
    mul     t0, t0, s4
    add     s3, s3, t0                  # s3 = record
    # The MVP's rows x, y, z stay in fs0..fs11 (callee-saved: kept on the
    # stack meanwhile); row w is loaded per vertex. The products are those of
    # vertex_clip, in the same order.
    addi    sp, sp, -96
    fsd     fs0, 0(sp)
    fsd     fs1, 8(sp)
    fsd     fs2, 16(sp)
    fsd     fs3, 24(sp)
    fsd     fs4, 32(sp)
    fsd     fs5, 40(sp)
    fsd     fs6, 48(sp)
    fsd     fs7, 56(sp)
    fsd     fs8, 64(sp)
    fsd     fs9, 72(sp)
    fsd     fs10, 80(sp)
    fsd     fs11, 88(sp)
    la      t0, vertex_mvp
    flw     fs0, 0(t0)
    flw     fs1, 4(t0)
    flw     fs2, 8(t0)
    flw     fs3, 12(t0)
    flw     fs4, 16(t0)
    flw     fs5, 20(t0)
    flw     fs6, 24(t0)
    flw     fs7, 28(t0)
    flw     fs8, 32(t0)
    flw     fs9, 36(t0)
    flw     fs10, 40(t0)
    flw     fs11, 44(t0)
1:  flw     ft8, 0(s1)                  # ft8, ft9, ft10 = model-space p
    flw     ft9, 4(s1)
    flw     ft10, 8(s1)
    fmadd.s fa0, fs0, ft8, fs3          # clip x -> fa0
    fmadd.s fa0, fs1, ft9, fa0
    fmadd.s fa0, fs2, ft10, fa0
    fmadd.s fa1, fs4, ft8, fs7          # clip y -> fa1
    fmadd.s fa1, fs5, ft9, fa1
    fmadd.s fa1, fs6, ft10, fa1
    fmadd.s fa2, fs8, ft8, fs11         # clip z -> fa2
    fmadd.s fa2, fs9, ft9, fa2
    fmadd.s fa2, fs10, ft10, fa2
    la      t0, vertex_mvp
    flw     ft0, 48(t0)                 # clip w -> fa3
    flw     ft1, 52(t0)
    flw     ft2, 56(t0)
    flw     ft3, 60(t0)
    fmadd.s fa3, ft0, ft8, ft3
    fmadd.s fa3, ft1, ft9, fa3
    fmadd.s fa3, ft2, ft10, fa3
    # outcode
    fneg.s  ft0, fa3                    # -w
    flt.s   t0, fa0, ft0                # x < -w (OUT_LEFT_BIT = 0)
    flt.s   t1, fa3, fa0                # x > w
    slli    t1, t1, OUT_RIGHT_BIT
    or      t0, t0, t1
    flt.s   t1, fa1, ft0                # y < -w
    slli    t1, t1, OUT_BOTTOM_BIT
    or      t0, t0, t1
    flt.s   t1, fa3, fa1                # y > w
    slli    t1, t1, OUT_TOP_BIT
    or      t0, t0, t1
    fmv.w.x ft1, zero
    flt.s   t1, fa2, ft1                # z < 0
    slli    t1, t1, OUT_NEAR_BIT
    or      t0, t0, t1
    flt.s   t1, fa3, fa2                # z > w
    slli    t1, t1, OUT_FAR_BIT
    or      t0, t0, t1
    li      t1, F32_GUARD_BAND
    fmv.w.x ft1, t1
    fmul.s  ft1, ft1, fa3               # guard band G w
    fabs.s  ft2, fa0
    fabs.s  ft3, fa1
    fmax.s  ft2, ft2, ft3
    flt.s   t1, ft1, ft2                # max(|x|, |y|) > G w
    slli    t1, t1, OUT_GUARD_BIT
    or      t0, t0, t1
    sw      t0, VTX_OUTCODE(s3)
    andi    t0, t0, OUT_CLIP
    bnez    t0, 2f                      # to be cut in clip space: no projection
    call    project_clip
    sw      a0, VTX_SX(s3)
    sw      a1, VTX_SY(s3)
    fsw     fa1, VTX_Q(s3)
    la      t0, vertex_snap_kept
    ld      t0, 0(t0)
    bnez    t0, 3f
    fsw     fa0, VTX_ZW(s3)             # int16 depth (or none): z / w
    j       2f
3:  SNAP_RESIDUAL a0, fa2, SCREEN_HALF_W_Q4 # float32 depth: where snapping
    sh      t1, VTX_SNAP_X(s3)          # moved the corner
    SNAP_RESIDUAL a1, fa3, SCREEN_HALF_H_Q4
    sh      t1, VTX_SNAP_Y(s3)
2:  addi    s1, s1, MESH_V_BYTES
    addi    s3, s3, VTX_BYTES
    addi    s2, s2, -1
    bnez    s2, 1b

    # Flat shading: every vertex's world-space position, M p, with the model
    # matrix's top rows in fs0..fs11 (face_world's products, in its order).
    la      t0, vertex_world_array
    ld      s3, 0(t0)
    beqz    s3, 8f
    li      t0, WORLD_POS_BYTES
    mul     t0, t0, s4
    add     s3, s3, t0                  # s3 = world position
    ld      s1, MESH_V(s0)
    li      t0, MESH_V_BYTES
    mul     t0, t0, s4
    add     s1, s1, t0                  # s1 = mesh position
    mv      s2, s5                      # s2 = vertices left
    la      t0, vertex_model
    flw     fs0, 0(t0)
    flw     fs1, 4(t0)
    flw     fs2, 8(t0)
    flw     fs3, 12(t0)
    flw     fs4, 16(t0)
    flw     fs5, 20(t0)
    flw     fs6, 24(t0)
    flw     fs7, 28(t0)
    flw     fs8, 32(t0)
    flw     fs9, 36(t0)
    flw     fs10, 40(t0)
    flw     fs11, 44(t0)
3:  flw     ft8, 0(s1)
    flw     ft9, 4(s1)
    flw     ft10, 8(s1)
    fmadd.s ft0, fs0, ft8, fs3
    fmadd.s ft0, fs1, ft9, ft0
    fmadd.s ft0, fs2, ft10, ft0
    fsw     ft0, 0(s3)
    fmadd.s ft0, fs4, ft8, fs7
    fmadd.s ft0, fs5, ft9, ft0
    fmadd.s ft0, fs6, ft10, ft0
    fsw     ft0, 4(s3)
    fmadd.s ft0, fs8, ft8, fs11
    fmadd.s ft0, fs9, ft9, ft0
    fmadd.s ft0, fs10, ft10, ft0
    fsw     ft0, 8(s3)
    addi    s1, s1, MESH_V_BYTES
    addi    s3, s3, WORLD_POS_BYTES
    addi    s2, s2, -1
    bnez    s2, 3b
8:
    fld     fs0, 0(sp)
    fld     fs1, 8(sp)
    fld     fs2, 16(sp)
    fld     fs3, 24(sp)
    fld     fs4, 32(sp)
    fld     fs5, 40(sp)
    fld     fs6, 48(sp)
    fld     fs7, 56(sp)
    fld     fs8, 64(sp)
    fld     fs9, 72(sp)
    fld     fs10, 80(sp)
    fld     fs11, 88(sp)
    addi    sp, sp, 96
9:  FRAME_RESTORE 64, ra, s0, s1, s2, s3, s4, s5
    ret

    .globl vertex_clip
# vertex_clip
#   What: a mesh vertex's clip-space position this frame, P M p, exactly as
#         vertex_range computed it for its outcode and projection (the
#         same products in the same order), for the triangles and edges cut
#         in clip space.
#   Arguments: a0 = the vertex's index, a1 = where to write x, y, z, w
#              (CLIP_POS_BYTES).
#   Results: none.
#   Clobbers: only ABI temporaries.
vertex_clip:
    la      t0, scene
    ld      t0, MESH_V(t0)
    li      t1, MESH_V_BYTES
    mul     t1, t1, a0
    add     t0, t0, t1
    flw     ft8, 0(t0)
    flw     ft9, 4(t0)
    flw     ft10, 8(t0)
    la      t0, vertex_mvp
    li      t1, CLIP_POS_BYTES / 4      # rows
1:  flw     ft0, 0(t0)
    flw     ft1, 4(t0)
    flw     ft2, 8(t0)
    flw     ft3, 12(t0)
    fmadd.s ft4, ft0, ft8, ft3
    fmadd.s ft4, ft1, ft9, ft4
    fmadd.s ft4, ft2, ft10, ft4
    fsw     ft4, 0(a1)
    addi    t0, t0, 16
    addi    a1, a1, 4
    addi    t1, t1, -1
    bnez    t1, 1b
    ret

    .globl face_world
# face_world
#   What: the world-space positions this frame, M p, of a triangle's three
#         corners (a face normal where vertex_world_array is not kept:
#         Gouraud shading's faces without normals), with the model matrix's
#         products in the order of vertex_range's.
#   Arguments: a0 = the triangle (MESH_F_BYTES), a1 = where to write the
#              corners' x, y, z (TRIANGLE_CORNERS * WORLD_POS_BYTES).
#   Results: none.
#   Clobbers: only ABI temporaries. M's top rows stay in ft0..ft11 while the
#         corners go through fa0..fa3.
face_world:
    la      t0, vertex_model
    flw     ft0, 0(t0)
    flw     ft1, 4(t0)
    flw     ft2, 8(t0)
    flw     ft3, 12(t0)
    flw     ft4, 16(t0)
    flw     ft5, 20(t0)
    flw     ft6, 24(t0)
    flw     ft7, 28(t0)
    flw     ft8, 32(t0)
    flw     ft9, 36(t0)
    flw     ft10, 40(t0)
    flw     ft11, 44(t0)
    la      t0, scene
    ld      t0, MESH_V(t0)              # t0 = mesh positions
    li      t1, MESH_V_BYTES
    addi    t2, a0, TRIANGLE_CORNERS * MESH_CORNER_BYTES
1:  ld      t3, 0(a0)
    slli    t3, t3, MESH_INDEX_LOW_SHIFT
    srli    t3, t3, MESH_INDEX_LOW_SHIFT
    mul     t3, t3, t1
    add     t3, t3, t0
    flw     fa0, 0(t3)
    flw     fa1, 4(t3)
    flw     fa2, 8(t3)
    fmadd.s fa3, ft0, fa0, ft3
    fmadd.s fa3, ft1, fa1, fa3
    fmadd.s fa3, ft2, fa2, fa3
    fsw     fa3, 0(a1)
    fmadd.s fa3, ft4, fa0, ft7
    fmadd.s fa3, ft5, fa1, fa3
    fmadd.s fa3, ft6, fa2, fa3
    fsw     fa3, 4(a1)
    fmadd.s fa3, ft8, fa0, ft11
    fmadd.s fa3, ft9, fa1, fa3
    fmadd.s fa3, ft10, fa2, fa3
    fsw     fa3, 8(a1)
    addi    a0, a0, MESH_CORNER_BYTES
    addi    a1, a1, WORLD_POS_BYTES
    bne     a0, t2, 1b
    ret

    .globl project_clip
# project_clip
#   What: perspective divide and viewport of a clip-space point in front of
#         the near plane (w > 0): screen x = (x / w + 1) * LCD_WIDTH / 2,
#         y = (1 - y / w) * LCD_HEIGHT / 2 (down), both rounded to the
#         nearest 1/16 pixel (Q4, ties to even) after clamping to +-2^27
#         (a safety net for NaN: points inside the guard band, the only
#         ones drawn, are far inside it);
#         with SCENE_SNAP = SNAP_PIXEL then to the nearest whole pixel
#         (a multiple of 16, ties up), as the thesis's integer positions.
#         Every projected position goes through here, so a point projects to
#         the same Q4 position whichever triangle or edge it belongs to.
#   Arguments: fa0, fa1, fa2, fa3 = clip-space x, y, z, w.
#   Results: a0 = screen x (Q4), a1 = screen y (Q4), fa0 = z / w,
#            fa1 = 1 / w, fa2, fa3 = screen x, y in pixels from the
#            screen's centre (right, down), neither clamped nor snapped (the
#            depth plane's corners: raster_triangle).
#   Clobbers: only ABI temporaries.
project_clip:
    li      t0, F32_ONE
    fmv.w.x ft0, t0
    fdiv.s  ft0, ft0, fa3               # ft0 = 1 / w
    fmul.s  ft1, fa0, ft0               # x / w
    fmul.s  ft2, fa1, ft0               # y / w
    fmv.s   ft5, ft1
    fmv.s   ft6, ft2
    li      t0, SCREEN_HALF_W_Q4
    fcvt.s.w ft3, t0
    fmadd.s ft1, ft1, ft3, ft3          # (x / w + 1) * half width
    li      t0, SCREEN_HALF_H_Q4
    fcvt.s.w ft3, t0
    fnmsub.s ft2, ft2, ft3, ft3         # (1 - y / w) * half height
    li      t0, F32_Q4_LIMIT
    fmv.w.x ft3, t0
    fneg.s  ft4, ft3
    fmin.s  ft1, ft1, ft3               # clamp (a NaN becomes the limit)
    fmax.s  ft1, ft1, ft4
    fmin.s  ft2, ft2, ft3
    fmax.s  ft2, ft2, ft4
    fcvt.w.s a0, ft1, rne
    fcvt.w.s a1, ft2, rne
    fmul.s  fa0, fa2, ft0
    fmv.s   fa1, ft0
    li      t0, LCD_WIDTH / 2
    fcvt.s.w ft3, t0
    fmul.s  fa2, ft5, ft3               # x / w * half width
    li      t0, -LCD_HEIGHT / 2
    fcvt.s.w ft3, t0
    fmul.s  fa3, ft6, ft3               # - y / w * half height
    la      t0, scene
    lwu     t0, SCENE_SNAP(t0)
    bnez    t0, 1f
    ret
1:  addi    a0, a0, SUBPIXEL_HALF       # snap = pixel: the nearest whole pixel
    andi    a0, a0, -SUBPIXEL_ONE
    addi    a1, a1, SUBPIXEL_HALF
    andi    a1, a1, -SUBPIXEL_ONE
    ret

# ---------------------------------------------------------------------------
    .section .rodata
msg_vertex_records: .asciz "vertex records"
msg_world_positions: .asciz "world positions"

# ---------------------------------------------------------------------------
    .bss
    .balign 8
    .globl vertex_records
# vertex_records: address of the MESH_VCOUNT vertex records (heap).
vertex_records:
    .space  8
    .globl vertex_snap_kept
# vertex_snap_kept: nonzero when the vertex records keep the snap's residual
# in VTX_ZW's place (float32 depth, and the supersampled wireframe's union
# lines unless snap = pixel: render_init), zero when they keep z / w
vertex_snap_kept:
    .space  8
    .globl vertex_world_array
# vertex_world_array: address of the MESH_VCOUNT world-space positions
# (WORLD_POS_BYTES each, heap), or 0 when they are not kept (vertex_init).
vertex_world_array:
    .space  8
    .balign 16
# This frame's rotation, matrices (render.inc layouts).
vertex_quat:
    .space  QUAT_BYTES
    .globl vertex_rotation
vertex_rotation:
    .space  MAT3_BYTES
    .balign 16
vertex_model:
    .space  MAT4_BYTES
vertex_projection:
    .space  MAT4_BYTES
vertex_mvp:
    .space  MAT4_BYTES
