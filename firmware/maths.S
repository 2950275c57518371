# maths.S: the renderer's floating-point helpers: sine and cosine of an
# angle in degrees, quaternions, 3x3 and 4x4 matrices, 3-vectors.
#
# Layouts (render.inc): a quaternion is 4 x f32 (w, x, y, z); matrices are
# row-major f32 and act on column vectors (p' = M p), so element (r, c) of a
# 4x4 is at byte 16 r + 4 c; a 3-vector is 3 x f32.
#
# Accuracy of sincos_deg: the angle (a double, in degrees) is reduced exactly
# to r = angle - 90 k with |r| <= 45 degrees (k = nearest integer to
# angle / 90; exact for |angle| < 2^52 degrees), converted to radians and
# rounded to single, then evaluated with the Cephes sinf/cosf minimax
# polynomials (degree 7 and 8) in single precision with fused multiply-adds.
# Measured on the board model against a double-precision reference over
# [-720, 720] degrees in 0.01-degree steps: largest absolute error 7.8e-8
# for both sin and cos (about one unit in the last place of a single).
# Angles that differ by whole turns give bit-identical results (the
# reduction is exact), and sin(0) = 0, cos(0) = 1 exactly.

    .option norelax
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"
    .include "frame.inc"

    .text
    .globl sincos_deg
# sincos_deg
#   What: sine and cosine of an angle in degrees (accuracy: file comment).
#   Arguments: fa0 = angle in degrees (double).
#   Results: fa0 = sin, fa1 = cos (single).
#   Clobbers: only ABI temporaries.
sincos_deg:
    li      t0, F64_INV_NINETY
    fmv.d.x ft0, t0
    fmul.d  ft0, fa0, ft0
    fcvt.l.d t1, ft0, rne               # t1 = k, the nearest quadrant
    fcvt.d.l ft0, t1
    li      t0, F64_NINETY
    fmv.d.x ft1, t0
    fnmsub.d ft0, ft0, ft1, fa0         # r = angle - 90 k, exact
    li      t0, F64_DEG_TO_RAD
    fmv.d.x ft1, t0
    fmul.d  ft0, ft0, ft1
    fcvt.s.d ft0, ft0                   # ft0 = x, |x| <= pi/4, single
    fmul.s  ft1, ft0, ft0               # ft1 = x^2
    # sin x
    li      t0, F32_SIN_S3
    fmv.w.x ft2, t0
    li      t0, F32_SIN_S2
    fmv.w.x ft3, t0
    fmadd.s ft2, ft2, ft1, ft3
    li      t0, F32_SIN_S1
    fmv.w.x ft3, t0
    fmadd.s ft2, ft2, ft1, ft3          # S1 + x^2 (S2 + x^2 S3)
    fmul.s  ft3, ft1, ft0               # x^3
    fmadd.s ft2, ft2, ft3, ft0          # ft2 = sin x
    # cos x
    li      t0, F32_COS_C3
    fmv.w.x ft3, t0
    li      t0, F32_COS_C2
    fmv.w.x ft4, t0
    fmadd.s ft3, ft3, ft1, ft4
    li      t0, F32_COS_C1
    fmv.w.x ft4, t0
    fmadd.s ft3, ft3, ft1, ft4          # C1 + x^2 (C2 + x^2 C3)
    fmul.s  ft4, ft1, ft1               # x^4
    li      t0, F32_HALF
    fmv.w.x ft5, t0
    li      t0, F32_ONE
    fmv.w.x ft6, t0
    fnmsub.s ft5, ft5, ft1, ft6         # 1 - x^2 / 2
    fmadd.s ft3, ft3, ft4, ft5          # ft3 = cos x
    # quadrant q = k mod 4: (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s)
    andi    t1, t1, QUADRANT_MASK
    andi    t2, t1, QUADRANT_ODD
    beqz    t2, 1f
    fmv.s   ft4, ft2                    # odd quadrant: swap
    fmv.s   ft2, ft3
    fmv.s   ft3, ft4
1:  andi    t2, t1, QUADRANT_NEG
    beqz    t2, 2f
    fneg.s  ft2, ft2                    # quadrants 2, 3: sin negative
2:  addi    t2, t1, QUADRANT_ODD
    andi    t2, t2, QUADRANT_NEG
    beqz    t2, 3f
    fneg.s  ft3, ft3                    # quadrants 1, 2: cos negative
3:  fmv.s   fa0, ft2
    fmv.s   fa1, ft3
    ret

    .globl angle_table_build
# angle_table_build
#   What: fills angle_table with cos(n degrees), n = 0 .. ANGLE_TABLE_ENTRIES
#         - 1 (sincos_deg), for angles = table: the thesis's table of the
#         rotation in 2-degree steps, as the half angles of quaternions.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
angle_table_build:
    FRAME_SAVE 32, ra, s0, s1
    la      s0, angle_table
    li      s1, 0                       # s1 = n
1:  fcvt.d.w fa0, s1
    call    sincos_deg
    fsw     fa1, 0(s0)
    addi    s0, s0, ANGLE_TABLE_ENTRY_BYTES
    addi    s1, s1, 1
    li      t0, ANGLE_TABLE_ENTRIES
    bne     s1, t0, 1b
    FRAME_RESTORE 32, ra, s0, s1
    ret

    .globl sincos_deg_table
# sincos_deg_table
#   What: sine and cosine of an angle rounded to whole degrees (ties to
#         even), read from angle_table (angle_table_build first): cos n =
#         angle_table[n mod 360], sin n = cos(n - 90).
#   Arguments: fa0 = angle in degrees (double; beyond +-2^63 it saturates,
#              still giving a table entry).
#   Results: fa0 = sin, fa1 = cos (single).
#   Clobbers: only ABI temporaries.
sincos_deg_table:
    fcvt.l.d t0, fa0, rne
    li      t1, ANGLE_TABLE_ENTRIES
    rem     t0, t0, t1
    bgez    t0, 1f
    add     t0, t0, t1                  # n mod 360 in 0 .. 359
1:  addi    t2, t0, ANGLE_TABLE_ENTRIES - ANGLE_QUARTER
    bltu    t2, t1, 2f
    sub     t2, t2, t1                  # (n - 90) mod 360
2:  la      t3, angle_table
    slli    t0, t0, ANGLE_TABLE_ENTRY_SHIFT
    add     t0, t0, t3
    flw     fa1, 0(t0)
    slli    t2, t2, ANGLE_TABLE_ENTRY_SHIFT
    add     t2, t2, t3
    flw     fa0, 0(t2)
    ret

    .globl quat_from_axis_angle
# quat_from_axis_angle
#   What: the unit quaternion of a rotation by an angle about a unit axis
#         (right-hand rule): (cos(a/2), sin(a/2) axis), sine and cosine from
#         sincos_deg, or with ANGLES_TABLE from sincos_deg_table (the angle
#         then in effect rounded to 2 degrees).
#   Arguments: a0 = quaternion out (QUAT_BYTES), a1 = axis (3 x f32, unit),
#              a2 = ANGLES_POLYNOMIAL or ANGLES_TABLE, fa0 = angle in
#              degrees (double).
#   Results: none.
#   Clobbers: only ABI temporaries.
quat_from_axis_angle:
    FRAME_SAVE 32, ra, s0, s1
    mv      s0, a0
    mv      s1, a1
    li      t0, F64_HALF
    fmv.d.x ft0, t0
    fmul.d  fa0, fa0, ft0
    bnez    a2, 1f
    call    sincos_deg
    j       2f
1:  call    sincos_deg_table
2:  fsw     fa1, QUAT_W(s0)
    flw     ft0, 0(s1)
    fmul.s  ft0, ft0, fa0
    fsw     ft0, QUAT_X(s0)
    flw     ft0, 4(s1)
    fmul.s  ft0, ft0, fa0
    fsw     ft0, QUAT_Y(s0)
    flw     ft0, 8(s1)
    fmul.s  ft0, ft0, fa0
    fsw     ft0, QUAT_Z(s0)
    FRAME_RESTORE 32, ra, s0, s1
    ret

    .globl quat_to_mat3
# quat_to_mat3
#   What: the rotation matrix of a unit quaternion (w, x, y, z):
#         [1-2(yy+zz)  2(xy-wz)    2(xz+wy)  ]
#         [2(xy+wz)    1-2(xx+zz)  2(yz-wx)  ]
#         [2(xz-wy)    2(yz+wx)    1-2(xx+yy)]
#         q and -q give bit-identical matrices (every term is a product of
#         two components).
#   Arguments: a0 = matrix out (MAT3_BYTES), a1 = quaternion.
#   Results: none.
#   Clobbers: only ABI temporaries.
quat_to_mat3:
    flw     ft0, QUAT_W(a1)
    flw     ft1, QUAT_X(a1)
    flw     ft2, QUAT_Y(a1)
    flw     ft3, QUAT_Z(a1)
    li      t0, F32_ONE
    fmv.w.x ft11, t0                    # ft11 = 1
    li      t0, F32_TWO
    fmv.w.x ft10, t0                    # ft10 = 2
    fmul.s  ft4, ft1, ft1               # xx
    fmul.s  ft5, ft2, ft2               # yy
    fmul.s  ft6, ft3, ft3               # zz
    # diagonal
    fadd.s  ft7, ft5, ft6
    fnmsub.s ft7, ft10, ft7, ft11       # 1 - 2 (yy + zz)
    fsw     ft7, 0(a0)
    fadd.s  ft7, ft4, ft6
    fnmsub.s ft7, ft10, ft7, ft11
    fsw     ft7, 16(a0)
    fadd.s  ft7, ft4, ft5
    fnmsub.s ft7, ft10, ft7, ft11
    fsw     ft7, 32(a0)
    # xy -+ wz
    fmul.s  ft4, ft1, ft2               # xy
    fmul.s  ft5, ft0, ft3               # wz
    fsub.s  ft7, ft4, ft5
    fmul.s  ft7, ft7, ft10
    fsw     ft7, 4(a0)
    fadd.s  ft7, ft4, ft5
    fmul.s  ft7, ft7, ft10
    fsw     ft7, 12(a0)
    # xz +- wy
    fmul.s  ft4, ft1, ft3               # xz
    fmul.s  ft5, ft0, ft2               # wy
    fadd.s  ft7, ft4, ft5
    fmul.s  ft7, ft7, ft10
    fsw     ft7, 8(a0)
    fsub.s  ft7, ft4, ft5
    fmul.s  ft7, ft7, ft10
    fsw     ft7, 24(a0)
    # yz -+ wx
    fmul.s  ft4, ft2, ft3               # yz
    fmul.s  ft5, ft0, ft1               # wx
    fsub.s  ft7, ft4, ft5
    fmul.s  ft7, ft7, ft10
    fsw     ft7, 20(a0)
    fadd.s  ft7, ft4, ft5
    fmul.s  ft7, ft7, ft10
    fsw     ft7, 28(a0)
    ret

    .globl mat4_model
# mat4_model
#   What: the model matrix T R S: scale first, then rotate, then translate:
#         [R00 sx  R01 sy  R02 sz  tx]
#         [R10 sx  R11 sy  R12 sz  ty]
#         [R20 sx  R21 sy  R22 sz  tz]
#         [0       0       0       1 ]
#   Arguments: a0 = matrix out (MAT4_BYTES), a1 = R (3x3), a2 = scale
#              (3 x f32), a3 = translation (3 x f32).
#   Results: none.
#   Clobbers: only ABI temporaries.
mat4_model:
    flw     ft0, 0(a2)
    flw     ft1, 4(a2)
    flw     ft2, 8(a2)
    li      t0, 3                       # t0 = rows left
1:  flw     ft3, 0(a1)
    fmul.s  ft3, ft3, ft0
    fsw     ft3, 0(a0)
    flw     ft3, 4(a1)
    fmul.s  ft3, ft3, ft1
    fsw     ft3, 4(a0)
    flw     ft3, 8(a1)
    fmul.s  ft3, ft3, ft2
    fsw     ft3, 8(a0)
    flw     ft3, 0(a3)
    fsw     ft3, 12(a0)
    addi    a0, a0, MAT4_ROW_BYTES
    addi    a1, a1, VEC3_BYTES
    addi    a3, a3, 4
    addi    t0, t0, -1
    bnez    t0, 1b
    sw      zero, 0(a0)
    sw      zero, 4(a0)
    sw      zero, 8(a0)
    li      t0, F32_ONE
    sw      t0, 12(a0)
    ret

    .globl mat4_perspective
# mat4_perspective
#   What: the perspective projection for a camera at the origin looking
#         down -z, with depth 0 at the near plane and 1 at the far plane
#         (clip z / w; D3D-style, so the near plane is simply z_clip >= 0):
#         [f / aspect  0   0            0              ]
#         [0           f   0            0              ]
#         [0           0   far/(n-f)    near far/(n-f) ]
#         [0           0   -1           0              ]
#         with f = cot(fov / 2), n = near, f(ar) = far.
#   Arguments: a0 = matrix out (MAT4_BYTES), fa0 = vertical field of view in
#              degrees, fa1 = aspect (width / height), fa2 = near, fa3 = far
#              (single).
#   Results: none.
#   Clobbers: only ABI temporaries.
mat4_perspective:
    FRAME_SAVE 48, ra, s0, fs0, fs1, fs2
    mv      s0, a0
    fmv.s   fs0, fa1
    fmv.s   fs1, fa2
    fmv.s   fs2, fa3
    fcvt.d.s fa0, fa0
    li      t0, F64_HALF
    fmv.d.x ft0, t0
    fmul.d  fa0, fa0, ft0
    call    sincos_deg
    fdiv.s  ft0, fa1, fa0               # f = cos / sin of fov / 2
    li      t0, MAT4_BYTES
    mv      t1, s0
1:  sw      zero, 0(t1)                 # zero everything first
    addi    t1, t1, 4
    addi    t0, t0, -4
    bnez    t0, 1b
    fdiv.s  ft1, ft0, fs0
    fsw     ft1, 0(s0)                  # (0, 0)
    fsw     ft0, 20(s0)                 # (1, 1)
    fsub.s  ft2, fs1, fs2               # n - f
    fdiv.s  ft3, fs2, ft2
    fsw     ft3, 40(s0)                 # (2, 2) = far / (n - f)
    fmul.s  ft3, ft3, fs1
    fsw     ft3, 44(s0)                 # (2, 3) = near far / (n - f)
    li      t0, F32_ONE
    fmv.w.x ft4, t0
    fneg.s  ft4, ft4
    fsw     ft4, 56(s0)                 # (3, 2) = -1
    FRAME_RESTORE 48, ra, s0, fs0, fs1, fs2
    ret

    .globl mat4_mul
# mat4_mul
#   What: the product A B of two 4x4 matrices (apply B, then A).
#   Arguments: a0 = result out (must not overlap A or B), a1 = A, a2 = B.
#   Results: none.
#   Clobbers: only ABI temporaries.
mat4_mul:
    li      t0, 4                       # t0 = rows of A left
1:  flw     ft0, 0(a1)                  # row of A
    flw     ft1, 4(a1)
    flw     ft2, 8(a1)
    flw     ft3, 12(a1)
    mv      t1, a2                      # t1 = column of B
    li      t2, 4                       # t2 = columns left
2:  flw     ft4, 0(t1)
    fmul.s  ft8, ft0, ft4
    flw     ft5, 16(t1)
    fmadd.s ft8, ft1, ft5, ft8
    flw     ft6, 32(t1)
    fmadd.s ft8, ft2, ft6, ft8
    flw     ft7, 48(t1)
    fmadd.s ft8, ft3, ft7, ft8
    fsw     ft8, 0(a0)
    addi    a0, a0, 4
    addi    t1, t1, 4
    addi    t2, t2, -1
    bnez    t2, 2b
    addi    a1, a1, MAT4_ROW_BYTES
    addi    t0, t0, -1
    bnez    t0, 1b
    ret

    .globl vec3_sub
# vec3_sub
#   What: difference of two 3-vectors in memory, into registers.
#   Arguments: a0 = a, a1 = b (3 x f32 each).
#   Results: fa0, fa1, fa2 = a - b.
#   Clobbers: only ABI temporaries.
vec3_sub:
    flw     fa0, 0(a0)
    flw     ft0, 0(a1)
    fsub.s  fa0, fa0, ft0
    flw     fa1, 4(a0)
    flw     ft0, 4(a1)
    fsub.s  fa1, fa1, ft0
    flw     fa2, 8(a0)
    flw     ft0, 8(a1)
    fsub.s  fa2, fa2, ft0
    ret

    .globl vec3_cross
# vec3_cross
#   What: cross product a x b.
#   Arguments: fa0, fa1, fa2 = a; fa3, fa4, fa5 = b.
#   Results: fa0, fa1, fa2 = a x b.
#   Clobbers: only ABI temporaries.
vec3_cross:
    fmul.s  ft0, fa1, fa5
    fnmsub.s ft0, fa2, fa4, ft0         # ay bz - az by
    fmul.s  ft1, fa2, fa3
    fnmsub.s ft1, fa0, fa5, ft1         # az bx - ax bz
    fmul.s  ft2, fa0, fa4
    fnmsub.s ft2, fa1, fa3, ft2         # ax by - ay bx
    fmv.s   fa0, ft0
    fmv.s   fa1, ft1
    fmv.s   fa2, ft2
    ret

    .globl vec3_dot
# vec3_dot
#   What: dot product a . b.
#   Arguments: fa0, fa1, fa2 = a; fa3, fa4, fa5 = b.
#   Results: fa0 = a . b.
#   Clobbers: only ABI temporaries.
vec3_dot:
    fmul.s  fa0, fa0, fa3
    fmadd.s fa0, fa1, fa4, fa0
    fmadd.s fa0, fa2, fa5, fa0
    ret

    .globl vec3_length
# vec3_length
#   What: Euclidean length |a|.
#   Arguments: fa0, fa1, fa2 = a.
#   Results: fa0 = |a|.
#   Clobbers: only ABI temporaries.
vec3_length:
    fmul.s  fa0, fa0, fa0
    fmadd.s fa0, fa1, fa1, fa0
    fmadd.s fa0, fa2, fa2, fa0
    fsqrt.s fa0, fa0
    ret

# ---------------------------------------------------------------------------
    .bss
    .balign 4
# angle_table: cos(n degrees), n = 0 .. 359 (angle_table_build).
angle_table:
    .space  ANGLE_TABLE_ENTRIES * ANGLE_TABLE_ENTRY_BYTES
