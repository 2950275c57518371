# render_texels.S: a face's texture coordinates (render_triangles.S, step 3;
# textured mode): texel column s = u W, row t = (1 - v) H (OBJ's v = 0 is the
# bottom row), each shifted by the same whole number of texture repeats for
# the three corners so that the smallest is in [0, 1) repeats; the rasteriser
# wraps the rest. A corner without vt takes (u, v) = (0, 0).

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"

    .text
    .globl face_texels
# face_texels
#   What: the texel coordinates of a face's three corners (file comment)
#         into RV_S and RV_T of the three records of render_rv.
#   Arguments: a0 = the face (MESH_F_BYTES).
#   Results: none.
#   Clobbers: only ABI temporaries.
face_texels:
    la      t0, scene
    ld      t1, MESH_T(t0)              # t1 = vt array
    lwu     t2, MESH_TCOUNT(t0)         # t2 = vt count
    la      t3, render_rv
    add     t3, t3, tp
    li      t4, TRIANGLE_CORNERS
    li      t5, F32_ONE
    fmv.w.x ft3, t5                     # ft3 = 1
1:  ld      t5, 0(a0)
    slli    t5, t5, MESH_INDEX_MID_SHIFT
    srli    t5, t5, MESH_INDEX_LOW_SHIFT  # the vt index (MESH_NO_INDEX is past any count)
    fmv.w.x ft0, zero                   # no vt (or out of range): (0, 0)
    fmv.w.x ft1, zero
    bgeu    t5, t2, 2f
    slli    t5, t5, 3                   # MESH_T_BYTES
    add     t5, t5, t1
    flw     ft0, 0(t5)
    flw     ft1, 4(t5)
2:  fsub.s  ft1, ft3, ft1               # 1 - v
    fsw     ft0, RV_S(t3)
    fsw     ft1, RV_T(t3)
    addi    a0, a0, MESH_CORNER_BYTES
    addi    t3, t3, RV_BYTES
    addi    t4, t4, -1
    bnez    t4, 1b
    # shift by whole repeats: the smallest of each into [0, 1), then scale
    la      t3, render_rv
    add     t3, t3, tp
    flw     ft0, RV_S(t3)
    flw     ft1, RV_S + RV_BYTES(t3)
    flw     ft2, RV_S + 2 * RV_BYTES(t3)
    fmin.s  ft4, ft0, ft1
    fmin.s  ft4, ft4, ft2
    fcvt.l.s t5, ft4, rdn
    fcvt.s.l ft4, t5                    # floor of the smallest
    lwu     t5, TEX_W(t0)
    fcvt.s.w ft5, t5
    fsub.s  ft0, ft0, ft4
    fmul.s  ft0, ft0, ft5
    fsw     ft0, RV_S(t3)
    fsub.s  ft1, ft1, ft4
    fmul.s  ft1, ft1, ft5
    fsw     ft1, RV_S + RV_BYTES(t3)
    fsub.s  ft2, ft2, ft4
    fmul.s  ft2, ft2, ft5
    fsw     ft2, RV_S + 2 * RV_BYTES(t3)
    flw     ft0, RV_T(t3)
    flw     ft1, RV_T + RV_BYTES(t3)
    flw     ft2, RV_T + 2 * RV_BYTES(t3)
    fmin.s  ft4, ft0, ft1
    fmin.s  ft4, ft4, ft2
    fcvt.l.s t5, ft4, rdn
    fcvt.s.l ft4, t5
    lwu     t5, TEX_H(t0)
    fcvt.s.w ft5, t5
    fsub.s  ft0, ft0, ft4
    fmul.s  ft0, ft0, ft5
    fsw     ft0, RV_T(t3)
    fsub.s  ft1, ft1, ft4
    fmul.s  ft1, ft1, ft5
    fsw     ft1, RV_T + RV_BYTES(t3)
    fsub.s  ft2, ft2, ft4
    fmul.s  ft2, ft2, ft5
    fsw     ft2, RV_T + 2 * RV_BYTES(t3)
    ret
