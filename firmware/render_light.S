# render_light.S: light intensities (render_triangles.S, step 2). Per face:
# N = (w1 - w0) x (w2 - w0) from the world-space positions of the corners
# (never from vn; with flat shading the vertex stage keeps them,
# vertex_world_array; otherwise vertex.S face_world computes them for the
# face), intensity I = max(SCENE_AMBIENT, N . L / |N|) with L = SCENE_LIGHT,
# as an integer k = round(64 I) in 0 .. 64, or with more light levels than
# the narrow fills take k = round(65536 I) in 0 .. 65536 (render.inc
# LIGHT_LEVELS_NARROW; quantised to SCENE_LIGHT_LEVELS, light_level). With shading = gouraud, per mesh normal
# once a frame (normals_light), and each corner takes its normal's
# (corner_light). With shading = phong each mesh normal is put in the light's
# basis once a frame (normals_phong), each corner takes its normal's
# (corner_phong), and the fills light every pixel from the normal
# interpolated there (raster_fills.S PHONG_K). shade_rgb565 lights a colour
# by k.

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"
    .include "frame.inc"

# CORNER_NORMALS
#   corner_light's and corner_phong's start, for the face at a0: t2, t3, t4 =
#   its corners' normal indices, t0 = normal_light's array, t1 = this hart's
#   render_rv; on to 2 (ahead) when a corner has no vn. Clobbers nothing
#   else.
.macro CORNER_NORMALS
    la      t0, scene
    lwu     t1, MESH_NCOUNT(t0)         # (MESH_NO_INDEX is past any count)
    ld      t2, 0(a0)
    srli    t2, t2, MESH_CORNER_N_SHIFT
    bgeu    t2, t1, 2f
    ld      t3, MESH_CORNER_BYTES(a0)
    srli    t3, t3, MESH_CORNER_N_SHIFT
    bgeu    t3, t1, 2f
    ld      t4, 2 * MESH_CORNER_BYTES(a0)
    srli    t4, t4, MESH_CORNER_N_SHIFT
    bgeu    t4, t1, 2f
    la      t0, normal_light
    ld      t0, 0(t0)
    la      t1, render_rv
    add     t1, t1, tp
.endm

# NORMAL_MATRIX
#   normals_light's and normals_phong's M = R C (their comments) into ft3..
#   ft11, row by row. Needs t0 = scene. Clobbers t1, fa0..fa3.
.macro NORMAL_MATRIX
    flw     fa0, SCENE_SCALE(t0)        # C = fa1, fa2, fa3
    flw     fa1, SCENE_SCALE + 4(t0)
    flw     fa2, SCENE_SCALE + 8(t0)
    fmul.s  fa3, fa0, fa1               # sx sy
    fmul.s  fa1, fa1, fa2               # sy sz
    fmul.s  fa2, fa0, fa2               # sx sz
    la      t1, vertex_rotation         # M = R C: column c of R times C[c]
    flw     ft3, 0(t1)
    fmul.s  ft3, ft3, fa1
    flw     ft4, 4(t1)
    fmul.s  ft4, ft4, fa2
    flw     ft5, 8(t1)
    fmul.s  ft5, ft5, fa3
    flw     ft6, 12(t1)
    fmul.s  ft6, ft6, fa1
    flw     ft7, 16(t1)
    fmul.s  ft7, ft7, fa2
    flw     ft8, 20(t1)
    fmul.s  ft8, ft8, fa3
    flw     ft9, 24(t1)
    fmul.s  ft9, ft9, fa1
    flw     ft10, 28(t1)
    fmul.s  ft10, ft10, fa2
    flw     ft11, 32(t1)
    fmul.s  ft11, ft11, fa3
.endm

# NORMAL_TURNED
#   fa0, fa1, fa2 = n' = M n for the mesh normal at s0 (M in ft3..ft11).
#   Clobbers ft0..ft2.
.macro NORMAL_TURNED
    flw     ft0, 0(s0)
    flw     ft1, 4(s0)
    flw     ft2, 8(s0)
    fmul.s  fa0, ft3, ft0               # n' = M n
    fmadd.s fa0, ft4, ft1, fa0
    fmadd.s fa0, ft5, ft2, fa0
    fmul.s  fa1, ft6, ft0
    fmadd.s fa1, ft7, ft1, fa1
    fmadd.s fa1, ft8, ft2, fa1
    fmul.s  fa2, ft9, ft0
    fmadd.s fa2, ft10, ft1, fa2
    fmadd.s fa2, ft11, ft2, fa2
.endm

    .text
    .globl shade_rgb565
# shade_rgb565
#   What: an RGB565 colour with each channel multiplied by k / one (the
#         light_quantum's: 64, or 65536 with wide light) and rounded to
#         nearest (ties up; the lit fills do the same inline): k is taken to
#         1 / WIDE_LIGHT_ONE (exact: k << LIGHT_QUANTUM_WIDEN) and c spread
#         over 64 bits so that one multiplication scales R, G and B
#         (WIDE_SPREAD_MASK). With one = 64 the result is the narrow fills'
#         round(c k / 64), since (1024 c k + 32768) >> 16 = (c k + 32) >> 6.
#   Arguments: a0 = colour, a1 = k (0 .. one).
#   Results: a0 = lit colour.
#   Clobbers: only ABI temporaries.
shade_rgb565:
    la      t0, light_quantum
    lwu     t0, LIGHT_QUANTUM_WIDEN(t0)
    sll     a1, a1, t0
    li      t0, WIDE_SPREAD_MASK
    slli    t1, a0, WIDE_SPREAD_R_SHIFT
    slli    t2, a0, WIDE_SPREAD_G_SHIFT
    or      a0, a0, t1
    or      a0, a0, t2
    and     a0, a0, t0
    mul     a0, a0, a1
    li      t1, WIDE_ROUND_SPREAD
    add     a0, a0, t1                  # rounded to nearest
    srli    a0, a0, WIDE_LIGHT_SHIFT
    and     a0, a0, t0
    srli    t1, a0, WIDE_SPREAD_R_SHIFT
    srli    t2, a0, WIDE_SPREAD_G_SHIFT
    or      a0, a0, t1
    or      a0, a0, t2
    slli    a0, a0, 48
    srli    a0, a0, 48
    ret

    .globl face_light
# face_light
#   What: the face's light intensity (file comment), from its
#         corners' world-space positions: the vertex stage's
#         (vertex_world_array, flat shading) or, where it keeps none,
#         computed (face_world).
#   Arguments: a0 = the face (MESH_F_BYTES).
#   Results: a0 = k, 0 .. one (light_level); fa0 = the same before rounding to a
#            whole k (light_level).
#   Clobbers: only ABI temporaries.
    .equ FACE_LIGHT_CORNERS,    16          # stack: N and |N| below, then the corners'
    .equ FACE_LIGHT_WORLD,      40          # world positions' addresses, then the positions
    .equ FACE_LIGHT_FRAME,      96          # when computed here, then ra
.if FACE_LIGHT_CORNERS + TRIANGLE_CORNERS * 8 > FACE_LIGHT_WORLD
    .error "face_light's stack frame is too small"
.endif
.if FACE_LIGHT_WORLD + TRIANGLE_CORNERS * WORLD_POS_BYTES > FACE_LIGHT_FRAME - 8
    .error "face_light's stack frame is too small"
.endif
face_light:
    FRAME_SAVE FACE_LIGHT_FRAME, ra
    la      t0, vertex_world_array
    ld      t0, 0(t0)
    beqz    t0, 2f
    li      t1, WORLD_POS_BYTES         # kept: their addresses in the array
    addi    t2, sp, FACE_LIGHT_CORNERS
    addi    t3, a0, TRIANGLE_CORNERS * MESH_CORNER_BYTES
1:  ld      t4, 0(a0)
    slli    t4, t4, MESH_INDEX_LOW_SHIFT
    srli    t4, t4, MESH_INDEX_LOW_SHIFT
    mul     t4, t4, t1
    add     t4, t4, t0
    sd      t4, 0(t2)
    addi    a0, a0, MESH_CORNER_BYTES
    addi    t2, t2, 8
    bne     a0, t3, 1b
    j       3f
2:  addi    a1, sp, FACE_LIGHT_WORLD    # not kept: computed into the frame
    call    face_world
    addi    t0, sp, FACE_LIGHT_WORLD
    sd      t0, FACE_LIGHT_CORNERS(sp)
    addi    t0, t0, WORLD_POS_BYTES
    sd      t0, FACE_LIGHT_CORNERS + 8(sp)
    addi    t0, t0, WORLD_POS_BYTES
    sd      t0, FACE_LIGHT_CORNERS + 16(sp)
3:  ld      a0, FACE_LIGHT_CORNERS + 16(sp)
    ld      a1, FACE_LIGHT_CORNERS(sp)
    call    vec3_sub                    # w2 - w0
    fmv.s   fa3, fa0
    fmv.s   fa4, fa1
    fmv.s   fa5, fa2
    ld      a0, FACE_LIGHT_CORNERS + 8(sp)
    ld      a1, FACE_LIGHT_CORNERS(sp)
    call    vec3_sub                    # w1 - w0
    call    vec3_cross                  # N
    fsw     fa0, 0(sp)
    fsw     fa1, 4(sp)
    fsw     fa2, 8(sp)
    call    vec3_length
    fsw     fa0, 12(sp)                 # |N|
    flw     fa0, 0(sp)
    flw     fa1, 4(sp)
    flw     fa2, 8(sp)
    la      t0, scene
    flw     fa3, SCENE_LIGHT(t0)
    flw     fa4, SCENE_LIGHT + 4(t0)
    flw     fa5, SCENE_LIGHT + 8(t0)
    call    vec3_dot                    # N . L
    flw     ft0, 12(sp)
    fdiv.s  fa0, fa0, ft0               # cos; NaN when |N| = 0
    call    light_level
    FRAME_RESTORE FACE_LIGHT_FRAME, ra
    ret

# light_level (file-local)
#   What: the intensity of a surface whose normal makes an angle with the
#         light: I = max(SCENE_AMBIENT, cos), quantised to SCENE_LIGHT_LEVELS
#         evenly spaced levels from 0 to 1 (level = round(I (levels - 1))),
#         in units of 1 / one: kf = level (one / (levels - 1)), one =
#         LIGHT_ONE or WIDE_LIGHT_ONE (light_quantum, set by render_init).
#         With 65, 33, 17, 9, 5, 3 or 2 levels (or 65537, 32769, ... wide)
#         the step is exact; with 65 (the default) kf = round(64 I), with
#         65537 round(65536 I).
#   Arguments: fa0 = cos (NaN, for a zero normal, gives the ambient).
#   Results: fa0 = kf; a0 = kf rounded to a whole k, 0 .. one.
#   Clobbers: only ft0..ft2, t0 and t1 (normals_light keeps its matrix in
#         the other temporaries).
light_level:
    la      t0, scene
    flw     ft1, SCENE_AMBIENT(t0)
    fmax.s  fa0, fa0, ft1               # (fmax of NaN and ambient = ambient)
    la      t0, light_quantum
    flw     ft1, LIGHT_QUANTUM_LEVELS(t0)   # levels - 1
    fmul.s  fa0, fa0, ft1
    fcvt.w.s t1, fa0, rne               # the level
    fcvt.s.w fa0, t1
    flw     ft1, LIGHT_QUANTUM_STEP(t0)     # one / (levels - 1)
    fmul.s  fa0, fa0, ft1               # kf
    fmv.w.x ft2, zero                   # 0 <= kf <= one (cos just above 1)
    fmax.s  fa0, fa0, ft2
    flw     ft2, LIGHT_QUANTUM_ONE(t0)
    fmin.s  fa0, fa0, ft2
    fcvt.w.s a0, fa0, rne
    ret

    .globl corner_light
# corner_light
#   What: Gouraud: the intensity of each corner of a face into RV_K of the
#         three records of render_rv: normal_light of the corner's vn, or,
#         when any corner has none, the face's own intensity (face_light)
#         at all three, so that a model without normals looks as with flat
#         shading.
#   Arguments: a0 = the face (MESH_F_BYTES).
#   Results: none.
#   Clobbers: only ABI temporaries.
corner_light:
    CORNER_NORMALS
    slli    t2, t2, NORMAL_LIGHT_SHIFT
    add     t2, t2, t0
    lw      t2, 0(t2)
    sw      t2, RV_K(t1)
    slli    t3, t3, NORMAL_LIGHT_SHIFT
    add     t3, t3, t0
    lw      t3, 0(t3)
    sw      t3, RV_BYTES + RV_K(t1)
    slli    t4, t4, NORMAL_LIGHT_SHIFT
    add     t4, t4, t0
    lw      t4, 0(t4)
    sw      t4, 2 * RV_BYTES + RV_K(t1)
    ret
2:  FRAME_SAVE 16, ra
    call    face_light                  # (a0 is still the face)
    la      t1, render_rv
    add     t1, t1, tp
    fsw     fa0, RV_K(t1)
    fsw     fa0, RV_BYTES + RV_K(t1)
    fsw     fa0, 2 * RV_BYTES + RV_K(t1)
    FRAME_RESTORE 16, ra
    ret

    .globl normals_light
# normals_light
#   What: Gouraud: this frame's intensity of mesh normals a0 .. a1 - 1 into
#         normal_light: n' = R C n, with R the frame's rotation
#         (vertex_rotation) and C = diag(sy sz, sx sz, sx sy) the cofactor
#         matrix of the scale (det(S) S^-T: normals stay perpendicular to
#         the scaled surface, and a zero scale gives a zero normal, hence
#         the ambient), then light_level(n' . L / |n'|).
#   Arguments: a0 = first normal, a1 = the normal past the last (0 <= a0
#              <= a1 <= MESH_NCOUNT).
#   Results: none.
#   Clobbers: only ABI temporaries. The loop keeps M = R C in ft3..ft11
#         and L in fa4..fa6.
normals_light:
    FRAME_SAVE 32, ra, s0, s1, s2
    sub     s1, a1, a0                  # s1 = normals left
    beqz    s1, 9f
    la      t0, scene
    ld      s0, MESH_N(t0)
    li      t1, MESH_N_BYTES
    mul     t1, t1, a0
    add     s0, s0, t1                  # s0 = normal
    la      t1, normal_light
    ld      s2, 0(t1)
    slli    t1, a0, NORMAL_LIGHT_SHIFT
    add     s2, s2, t1                  # s2 = its intensity
    NORMAL_MATRIX
    flw     fa4, SCENE_LIGHT(t0)
    flw     fa5, SCENE_LIGHT + 4(t0)
    flw     fa6, SCENE_LIGHT + 8(t0)
1:  NORMAL_TURNED
    fmul.s  fa3, fa0, fa0               # |n'|
    fmadd.s fa3, fa1, fa1, fa3
    fmadd.s fa3, fa2, fa2, fa3
    fsqrt.s fa3, fa3
    fmul.s  fa0, fa0, fa4               # n' . L / |n'| (NaN when n' = 0)
    fmadd.s fa0, fa1, fa5, fa0
    fmadd.s fa0, fa2, fa6, fa0
    fdiv.s  fa0, fa0, fa3
    call    light_level
    fsw     fa0, 0(s2)
    addi    s0, s0, MESH_N_BYTES
    addi    s2, s2, NORMAL_LIGHT_BYTES
    addi    s1, s1, -1
    bnez    s1, 1b
9:  FRAME_RESTORE 32, ra, s0, s1, s2
    ret

    .globl phong_basis_init
# phong_basis_init
#   What: shading = phong: the light's basis into phong_basis, three unit
#         rows: e1 and e2 across the light, then L (SCENE_LIGHT, stored
#         normalised): e1 = L x X / |L x X|, or L x Y / |L x Y| when L lies
#         within 60 degrees of the x axis (|Lx| > 1/2, so |L x Y| >= 1/2),
#         e2 = L x e1. A normal's coordinates in it keep its length, and
#         its third is N . L: the fills need no L (PHONG_K).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
phong_basis_init:
    FRAME_SAVE 16, ra
    la      t0, scene
    flw     fa3, SCENE_LIGHT(t0)
    flw     fa4, SCENE_LIGHT + 4(t0)
    flw     fa5, SCENE_LIGHT + 8(t0)
    fabs.s  ft0, fa3
    li      t1, F32_HALF
    fmv.w.x ft1, t1
    flt.s   t1, ft1, ft0                # |Lx| > 1/2
    fmv.w.x ft2, zero
    bnez    t1, 1f
    fmv.s   fa0, ft2                    # L x X = (0, Lz, -Ly)
    fmv.s   fa1, fa5
    fneg.s  fa2, fa4
    j       2f
1:  fneg.s  fa0, fa5                    # L x Y = (-Lz, 0, Lx)
    fmv.s   fa1, ft2
    fmv.s   fa2, fa3
2:  fmul.s  ft0, fa0, fa0
    fmadd.s ft0, fa1, fa1, ft0
    fmadd.s ft0, fa2, fa2, ft0
    fsqrt.s ft0, ft0
    fdiv.s  fa0, fa0, ft0               # e1
    fdiv.s  fa1, fa1, ft0
    fdiv.s  fa2, fa2, ft0
    la      t1, phong_basis
    fsw     fa0, 0(t1)
    fsw     fa1, 4(t1)
    fsw     fa2, 8(t1)
    fsw     fa3, 24(t1)                 # L
    fsw     fa4, 28(t1)
    fsw     fa5, 32(t1)
    fmv.s   ft3, fa0                    # e2 = L x e1
    fmv.s   ft4, fa1
    fmv.s   ft5, fa2
    fmv.s   fa0, fa3
    fmv.s   fa1, fa4
    fmv.s   fa2, fa5
    fmv.s   fa3, ft3
    fmv.s   fa4, ft4
    fmv.s   fa5, ft5
    call    vec3_cross
    la      t1, phong_basis
    fsw     fa0, 12(t1)
    fsw     fa1, 16(t1)
    fsw     fa2, 20(t1)
    FRAME_RESTORE 16, ra
    ret

    .globl normals_phong
# normals_phong
#   What: Phong: this frame's mesh normals a0 .. a1 - 1 in the light's
#         basis (phong_basis) into normal_light (NORMAL_PHONG_BYTES each):
#         B n' / |n'| with n' = R C n as normals_light's: unit, as a model's
#         author means its vn whatever their lengths, so that a corner's
#         length does not weigh its normal in the interpolation (the fills
#         normalise again per pixel); a zero n' stays zero (no light of its
#         own: the other corners', or the ambient).
#   Arguments: a0 = first normal, a1 = the normal past the last (0 <= a0
#              <= a1 <= MESH_NCOUNT).
#   Results: none.
#   Clobbers: only ABI temporaries. The loop keeps M = R C in ft3..ft11
#         and B in fs0..fs8.
normals_phong:
    FRAME_SAVE 112, ra, s0, s1, s2, fs0, fs1, fs2, fs3, fs4, fs5, fs6, fs7, fs8
    sub     s1, a1, a0                  # s1 = normals left
    beqz    s1, 9f
    la      t0, scene
    ld      s0, MESH_N(t0)
    li      t1, MESH_N_BYTES
    mul     t1, t1, a0
    add     s0, s0, t1                  # s0 = normal
    la      t1, normal_light
    ld      s2, 0(t1)
    slli    t1, a0, NORMAL_PHONG_SHIFT
    add     s2, s2, t1                  # s2 = its coordinates
    NORMAL_MATRIX
    la      t1, phong_basis
    flw     fs0, 0(t1)
    flw     fs1, 4(t1)
    flw     fs2, 8(t1)
    flw     fs3, 12(t1)
    flw     fs4, 16(t1)
    flw     fs5, 20(t1)
    flw     fs6, 24(t1)
    flw     fs7, 28(t1)
    flw     fs8, 32(t1)
1:  NORMAL_TURNED
    fmul.s  fa3, fs0, fa0               # a = e1 . n'
    fmadd.s fa3, fs1, fa1, fa3
    fmadd.s fa3, fs2, fa2, fa3
    fmul.s  fa4, fs3, fa0               # b = e2 . n'
    fmadd.s fa4, fs4, fa1, fa4
    fmadd.s fa4, fs5, fa2, fa4
    fmul.s  fa5, fs6, fa0               # c = L . n'
    fmadd.s fa5, fs7, fa1, fa5
    fmadd.s fa5, fs8, fa2, fa5
    fmul.s  fa0, fa3, fa3               # |n'|^2 (B keeps lengths)
    fmadd.s fa0, fa4, fa4, fa0
    fmadd.s fa0, fa5, fa5, fa0
    fmv.w.x fa1, zero
    feq.s   t0, fa0, fa1
    bnez    t0, 2f                      # zero stays zero
    fsqrt.s fa0, fa0
    fdiv.s  fa3, fa3, fa0
    fdiv.s  fa4, fa4, fa0
    fdiv.s  fa5, fa5, fa0
2:  fsw     fa3, 0(s2)
    fsw     fa4, 4(s2)
    fsw     fa5, 8(s2)
    addi    s0, s0, MESH_N_BYTES
    addi    s2, s2, NORMAL_PHONG_BYTES
    addi    s1, s1, -1
    bnez    s1, 1b
9:  FRAME_RESTORE 112, ra, s0, s1, s2, fs0, fs1, fs2, fs3, fs4, fs5, fs6, fs7, fs8
    ret

    .globl corner_phong
# corner_phong
#   What: Phong: the normal of each corner of a face into RV_NA, RV_NB,
#         RV_NC of the three records of render_rv: its vn's (normals_phong),
#         or, when any corner has none, at all three a vector whose
#         intensity is the face's own (face_light: kf / one = I, as (0,
#         sqrt(1 - I^2), I)), so that a model without normals looks as with
#         flat shading.
#   Arguments: a0 = the face (MESH_F_BYTES).
#   Results: none.
#   Clobbers: only ABI temporaries.
corner_phong:
    CORNER_NORMALS
    slli    t2, t2, NORMAL_PHONG_SHIFT
    add     t2, t2, t0
    slli    t3, t3, NORMAL_PHONG_SHIFT
    add     t3, t3, t0
    slli    t4, t4, NORMAL_PHONG_SHIFT
    add     t4, t4, t0
    .irp at, 0, 4, 8
    lw      t5, \at(t2)
    sw      t5, RV_NA + \at(t1)
    lw      t5, \at(t3)
    sw      t5, RV_BYTES + RV_NA + \at(t1)
    lw      t5, \at(t4)
    sw      t5, 2 * RV_BYTES + RV_NA + \at(t1)
    .endr
    ret
2:  FRAME_SAVE 16, ra
    call    face_light                  # (a0 is still the face)
    la      t0, light_quantum
    flw     ft0, LIGHT_QUANTUM_ONE(t0)
    fdiv.s  fa0, fa0, ft0               # I
    li      t0, F32_ONE
    fmv.w.x ft0, t0
    fnmsub.s ft0, fa0, fa0, ft0         # 1 - I^2
    fsqrt.s ft0, ft0
    fmv.w.x ft1, zero
    la      t1, render_rv
    add     t1, t1, tp
    .irp at, 0, RV_BYTES, 2 * RV_BYTES
    fsw     ft1, \at + RV_NA(t1)
    fsw     ft0, \at + RV_NB(t1)
    fsw     fa0, \at + RV_NC(t1)
    .endr
    FRAME_RESTORE 16, ra
    ret

    .bss
    .balign 4
# phong_basis: shading = phong: the light's basis, three rows of f32 x, y, z:
# e1, e2 across the light, then L (phong_basis_init).
phong_basis:
    .space  36
