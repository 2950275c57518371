# depth_check.S: whether the depth buffer can tell the model's surfaces apart
# with the scene's near and far planes. int16 depth is z / w = far / (far -
# near) * (1 - near / D) at a view distance D, so a far plane many times the
# near one crowds every distance past a few near-plane lengths into the top
# of 0 .. 1, where 65534 steps resolve few values: surfaces that fall on one
# step hide each other by their drawing order. float32 depth is reversed
# (render.inc), c1 / D - c0, whose floats grow finer towards the far plane;
# but it is computed from 1 / D rounded to a float, so two distances whose
# 1 / D round alike get one depth: its steps are the fewer of the floats
# from d1 to d0 and of those from 1 / D1 to 1 / D0 (about 2^23 a doubling
# of the distance; few only for a model thin against its distance). The model's depth spans at most D = -tz -+ r, r its largest scaled
# vertex distance from its origin (any rotation), clipped to near .. far;
# fewer than DEPTH_WARN_STEPS steps of the buffer over that span is said on
# the console once, at load (not in wireframe mode, which draws without
# a depth buffer). The card builder says the same (reference/depth.py).

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"
    .include "frame.inc"

    .text
    .globl depth_check
# depth_check
#   What: the steps of the depth buffer over the model's depth span (file
#         comment); fewer than DEPTH_WARN_STEPS is a console warning.
#   Arguments: none (the scene and its mesh, loaded).
#   Results: a0 = the steps, or -1 when there is nothing to count (no
#            warning): wireframe mode, or a span of no length inside near ..
#            far (wholly outside them, a zero scale, a single point).
#   Clobbers: only ABI temporaries.
depth_check:
    FRAME_SAVE 16, ra, s0
    li      s0, -1
    la      t0, scene
    lwu     t1, SCENE_MODE(t0)
    li      t2, MODE_WIREFRAME
    beq     t1, t2, 9f                  # no depth buffer
    ld      t1, MESH_V(t0)
    lwu     t2, MESH_VCOUNT(t0)
    flw     ft0, SCENE_SCALE(t0)
    flw     ft1, SCENE_SCALE + 4(t0)
    flw     ft2, SCENE_SCALE + 8(t0)
    fmv.w.x fa0, zero                   # the largest |S v|^2
    beqz    t2, 2f
1:  flw     ft3, 0(t1)
    fmul.s  ft3, ft3, ft0
    fmul.s  ft3, ft3, ft3
    flw     ft4, 4(t1)
    fmul.s  ft4, ft4, ft1
    fmadd.s ft3, ft4, ft4, ft3
    flw     ft4, 8(t1)
    fmul.s  ft4, ft4, ft2
    fmadd.s ft3, ft4, ft4, ft3
    fmax.s  fa0, fa0, ft3
    addi    t1, t1, MESH_V_BYTES
    addi    t2, t2, -1
    bnez    t2, 1b
2:  fsqrt.s fa0, fa0                    # r
    flw     ft0, SCENE_TRANSLATE + 8(t0)
    fneg.s  ft0, ft0                    # the origin's view distance
    flw     ft1, SCENE_NEAR(t0)
    flw     ft2, SCENE_FAR(t0)
    fsub.s  ft3, ft0, fa0
    fmax.s  ft3, ft3, ft1               # D0
    fadd.s  ft4, ft0, fa0
    fmin.s  ft4, ft4, ft2               # D1
    flt.s   t3, ft3, ft4
    beqz    t3, 9f                      # nothing between near and far
    lwu     t3, SCENE_DEPTH(t0)
    li      t4, DEPTH_INT16
    beq     t3, t4, 3f
    fsub.s  ft5, ft2, ft1               # float32: as raster_set_depth and
    fdiv.s  ft5, ft1, ft5               # raster_triangle compute it,
    fmul.s  ft6, ft5, ft2               # c0 = near / (far - near), c1 = c0 far,
    li      t5, F32_ONE                 # d = c1 (1 / D) - c0
    fmv.w.x ft9, t5
    fdiv.s  ft7, ft9, ft3               # 1 / D0
    fdiv.s  ft8, ft9, ft4               # 1 / D1
    fmv.x.w t5, ft7                     # the floats from 1 / D1 to 1 / D0,
    fmv.x.w t6, ft8                     # which order as their bits (> 0)
    sub     s0, t5, t6
    fmsub.s ft7, ft7, ft6, ft5          # d0 (near side: the larger)
    fmsub.s ft8, ft8, ft6, ft5          # d1
    fmv.x.w t5, ft7                     # and from d1 to d0 (>= 0)
    fmv.x.w t6, ft8
    sub     t5, t5, t6
    bge     t5, s0, 4f
    mv      s0, t5
    j       4f
3:  fsub.s  ft5, ft2, ft1
    fdiv.s  ft5, ft2, ft5               # k = far / (far - near)
    fmul.s  ft6, ft5, ft1               # k near
    fdiv.s  ft7, ft6, ft3
    fsub.s  ft7, ft5, ft7               # d0 = k - k near / D0
    fdiv.s  ft8, ft6, ft4
    fsub.s  ft8, ft5, ft8               # d1
    li      t5, F32_DEPTH16_SPAN        # int16: floor(65534 d) from d0 to d1
    fmv.w.x ft9, t5
    fmul.s  ft7, ft7, ft9
    fcvt.w.s t5, ft7, rdn
    fmul.s  ft8, ft8, ft9
    fcvt.w.s t6, ft8, rdn
    sub     s0, t6, t5
4:  li      t3, DEPTH_WARN_STEPS
    bge     s0, t3, 9f
    call    console_lock
    la      a0, msg_depth_steps
    call    console_puts
    mv      a0, s0
    call    console_put_dec
    la      a0, msg_depth_fewer
    call    console_puts
    li      a0, DEPTH_WARN_STEPS
    call    console_put_dec
    la      a0, msg_depth_end
    call    console_puts
    call    console_unlock
9:  mv      a0, s0
    FRAME_RESTORE 16, ra, s0
    ret

    .section .rodata
msg_depth_steps:    .asciz "warning: depth: near and far leave "
msg_depth_fewer:    .asciz " steps of the depth buffer over the model's depth (fewer than "
msg_depth_end:      .asciz ": its surfaces may hide each other wrongly)\n"
