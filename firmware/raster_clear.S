# raster_clear.S: the depth buffer (raster_set_depth: where it is and its
# format, f32 or u16) and the clear at the start of every band (raster_clear:
# the band's rows of the framebuffer to the background colour and of the
# depth buffer to the far plane, so that the first fragment anywhere wins).

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"

    .if (FB_ROW_BYTES % CLEAR_UNROLL_BYTES) || (DEPTH16_ROW_BYTES % CLEAR_UNROLL_BYTES)
    .error "raster_clear clears whole rows CLEAR_UNROLL_BYTES at a time"
    .endif

    .text
    .globl raster_set_depth
# raster_set_depth
#   What: sets the depth buffer and its format for the following frames.
#   Arguments: a0 = the buffer (LCD_PIXELS entries, 64-aligned), a1 =
#              DEPTH_FLOAT32 (f32 reversed depth) or DEPTH_INT16 (u16,
#              render.inc); fa0, fa1 = the near and far planes' distances
#              (0 < near < far), from which the reversed depth's constants
#              (raster_depth_reverse) come.
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_set_depth:
    la      t0, raster_depth
    sd      a0, 0(t0)
    la      t0, raster_depth_mode
    sd      a1, 0(t0)
    fsub.s  ft0, fa1, fa0
    fdiv.s  ft0, fa0, ft0               # c0 = near / (far - near)
    fmul.s  ft1, ft0, fa1               # c1 = c0 far
    la      t0, raster_depth_reverse
    fsw     ft1, DEPTH_REVERSE_C1(t0)
    fsw     ft0, DEPTH_REVERSE_C0(t0)
    ret

    .globl raster_clear
# raster_clear
#   What: fills this hart's band (raster_set_band) of the framebuffer with
#         one colour and, when asked, of the depth buffer with the far plane
#         (DEPTH_CLEAR or DEPTH16_CLEAR). (Rows are whole multiples of
#         CLEAR_UNROLL_BYTES in both buffers.)
#   Arguments: a0 = RGB565 colour, a1 = 1 to clear the depth buffer too.
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_clear:
    slli    t0, a0, 48                  # four pixels per doubleword
    srli    t0, t0, 48
    slli    t1, t0, 16
    or      t0, t0, t1
    slli    t1, t0, 32
    or      t0, t0, t1
    la      t4, raster_band
    add     t4, t4, tp
    lwu     t5, BAND_FIRST(t4)          # t5, t6 = the band's rows
    lwu     t6, BAND_END(t4)
    bgeu    t5, t6, 3f                  # empty
    la      t2, raster_fb
    ld      t2, 0(t2)
    li      t4, FB_ROW_BYTES
    mul     t3, t6, t4
    add     t3, t3, t2
    mul     t4, t5, t4
    add     t2, t2, t4
1:  sd      t0, 0(t2)
    sd      t0, 8(t2)
    sd      t0, 16(t2)
    sd      t0, 24(t2)
    sd      t0, 32(t2)
    sd      t0, 40(t2)
    sd      t0, 48(t2)
    sd      t0, 56(t2)
    addi    t2, t2, CLEAR_UNROLL_BYTES
    bltu    t2, t3, 1b
    beqz    a1, 3f
    la      t2, raster_depth
    ld      t2, 0(t2)
    la      t0, raster_depth_mode
    ld      t0, 0(t0)
    bnez    t0, 4f
    li      t0, DEPTH_CLEAR             # two f32 per doubleword
    slli    t1, t0, 32
    or      t0, t0, t1
    li      t4, DEPTH_ROW_BYTES
    j       5f
4:  li      t0, DEPTH16_CLEAR_DWORD     # four u16 per doubleword
    li      t4, DEPTH16_ROW_BYTES
5:  mul     t3, t6, t4
    add     t3, t3, t2
    mul     t4, t5, t4
    add     t2, t2, t4
2:  sd      t0, 0(t2)
    sd      t0, 8(t2)
    sd      t0, 16(t2)
    sd      t0, 24(t2)
    sd      t0, 32(t2)
    sd      t0, 40(t2)
    sd      t0, 48(t2)
    sd      t0, 56(t2)
    addi    t2, t2, CLEAR_UNROLL_BYTES
    bltu    t2, t3, 2b
3:  ret
