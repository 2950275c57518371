# raster_supersample.S: antialias = supersample, the rasteriser's part. The
# frame is drawn once per sample (render.S render_band): raster_set_sample
# moves the corners of the triangles that follow by minus the sample's offset
# (raster_triangle), so that every pixel centre samples that point instead;
# raster_accumulate sums the samples' colours per pixel and, after the last,
# leaves their means in the framebuffer.

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"

    .text
    .globl raster_set_sample
# raster_set_sample
#   What: antialias = supersample: the sample the calling hart's triangles
#         are drawn for from now on (raster_triangle moves their corners by
#         minus the offset, so pixel centres sample the offset's point).
#   Arguments: a0, a1 = the offset from the pixel centre, x and y in Q4
#              (0, 0: the centre, as without supersampling).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_set_sample:
    la      t0, raster_sample
    add     t0, t0, tp
    sw      a0, SAMPLE_OFFSET_X(t0)
    sw      a1, SAMPLE_OFFSET_Y(t0)
    ret

    .globl raster_set_sums
# raster_set_sums
#   What: sets the sums buffer of raster_accumulate.
#   Arguments: a0 = the buffer (SUM_BUFFER_BYTES).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_set_sums:
    la      t0, raster_sums
    sd      a0, 0(t0)
    ret

# SUMS_BAND
#   t0 = the framebuffer at the calling hart's band, t1 = past its end,
#   t2 = the sums at the band (the same pixel order); empty band: on to 9.
#   Clobbers t3, t4.
.macro SUMS_BAND
    la      t3, raster_band
    add     t3, t3, tp
    lwu     t4, BAND_FIRST(t3)
    lwu     t1, BAND_END(t3)
    bgeu    t4, t1, 9f
    li      t3, LCD_WIDTH
    mul     t4, t4, t3                  # first pixel
    mul     t1, t1, t3                  # past the last
    la      t3, raster_sums
    ld      t2, 0(t3)
    slli    t3, t4, SUM_SHIFT
    add     t2, t2, t3
    la      t3, raster_fb
    ld      t0, 0(t3)
    slli    t1, t1, FB_PIXEL_SHIFT
    add     t1, t1, t0
    slli    t4, t4, FB_PIXEL_SHIFT
    add     t0, t0, t4
.endm

    .globl raster_accumulate
# raster_accumulate
#   What: antialias = supersample: the calling hart's band of the
#         framebuffer (one sample's colours) into the sums (render.inc
#         SUM_*): the first sample sets them, the others add to them, and
#         the last, added, leaves each pixel's mean in the framebuffer,
#         per channel rounded to nearest (halves up).
#   Arguments: a0 = SAMPLE_FIRST, SAMPLE_MORE or SAMPLE_LAST.
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_accumulate:
    SUMS_BAND
    li      t5, SUM_RB_MASK
    li      a1, SUM_ROUND
    li      a2, SUM_R_MASK
    li      a3, SAMPLE_LAST
1:  lhu     t3, 0(t0)                   # c spread into the sum's fields
    and     t4, t3, t5
    andi    t6, t3, SUM_G_MASK
    slli    t6, t6, SUM_G_SHIFT
    or      t4, t4, t6
    beqz    a0, 2f                      # (SAMPLE_FIRST)
    lwu     t3, 0(t2)
    add     t4, t4, t3
    beq     a0, a3, 3f
2:  sw      t4, 0(t2)
    addi    t0, t0, LCD_BYTES_PER_PIXEL
    addi    t2, t2, SUM_BYTES_PER_PIXEL
    bltu    t0, t1, 1b
    ret
3:  add     t4, t4, a1                  # the last: the mean
    srli    t4, t4, SUM_MEAN_SHIFT
    andi    t3, t4, SUM_B_MASK          # (each mean where one sample's channel
    and     t6, t4, a2                  # is in the sum, the remainders below it)
    or      t3, t3, t6
    srli    t6, t4, SUM_G_SHIFT
    andi    t6, t6, SUM_G_MASK
    or      t3, t3, t6
    sh      t3, 0(t0)
    addi    t0, t0, LCD_BYTES_PER_PIXEL
    addi    t2, t2, SUM_BYTES_PER_PIXEL
    bltu    t0, t1, 1b
9:  ret
