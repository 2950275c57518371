# ppm.S: the texture, a netpbm PPM (P6 binary or P3 plain), converted to
# RGB565 into `scene` (TEX_W, TEX_H, TEX_PIXELS; scene.inc).
#
# Header (netpbm rules): the magic "P6" or "P3", then width, height and
# maxval as unsigned decimal numbers, each preceded by whitespace (space,
# tab, CR, LF, VT, FF). A comment runs from '#' to the next CR or LF and
# counts as whitespace; it may stand anywhere in the header (it ends a
# token, as libnetpbm reads it). Width and height >= 1, maxval 1..65535,
# each below 2^31.
#
# P6: exactly one whitespace character (or one comment with its line end)
# after maxval, then the raster: width x height pixels of R, G, B, one byte
# per sample when maxval < 256, else two, most significant first. Bytes after
# the raster are ignored (netpbm allows more images to follow).
# P3: the samples are decimal numbers separated by whitespace (comments
# allowed between them too).
#
# Every sample must be <= maxval. Each is scaled to its RGB565 field with
# rounding to nearest: r5 = (r * 31 + maxval / 2) / maxval (ppm_rgb565).
# Pixels are stored row-major, row 0 = the first row of the file (the top of
# the image), over the file's own bytes: a pixel takes 2 bytes and its
# samples at least 3 (P6) or 6 (P3, digits and separators), so writing pixel
# i never overtakes the reading; the raw file is thereby freed for the
# pixels and a texture needs no memory beyond its file (a file too large
# for memory is error 7 when scene.S loads it).
#
# A truncated file, a bad magic, header or maxval, a sample above maxval or
# a P3 sample that is not a number is error 11: "error 11 bad texture: <what>".
# Only textured mode draws a texture: in flat and wireframe mode scene.S
# loads none (the file need not exist), TEX_W, TEX_H and TEX_PIXELS stay 0
# and the console says "texture: not loaded (mode flat)" (or wireframe).

    .option norelax
    .include "k210.inc"
    .include "errors.inc"
    .include "scene.inc"
    .include "text.inc"
    .include "frame.inc"

    .equ PPM_MAGIC_P,           'P'
    .equ PPM_MAGIC_P6,          '6'
    .equ PPM_MAGIC_P3,          '3'
    .equ PPM_MAGIC_BYTES,       2
    .equ PPM_FORMAT_P3,         0
    .equ PPM_FORMAT_P6,         1
    .equ PPM_NUMBER_MAX,        0x7FFFFFFF  # header numbers stay below 2^31
    .equ PPM_MAXVAL_MAX,        65535
    .equ PPM_MAXVAL_ONE_BYTE,   255         # above: two bytes per P6 sample
    .equ PPM_SAMPLES,           3           # R, G, B
    .equ PPM_SAMPLE_MAX,        0x10000     # a P3 sample saturates here (> any maxval)
    .equ PPM_BYTE_BITS,         8
    .equ PPM_NARROW_SAMPLE,     1           # bytes per P6 sample, maxval < 256
    .equ PPM_WIDE_SAMPLE,       2           # bytes per P6 sample, maxval >= 256
    # One-byte P6 samples are looked up in tables of each sample value's RGB565 field (ppm_rgb565's, built
    # once a texture), on ppm_parse_texture's stack: three divisions a pixel were 42 cycles of it
    .equ PPM_BYTE_VALUES,       256
    .equ PPM_FIELD_BYTES,       2           # a field, in its place in the RGB565 half-word
    .equ PPM_RED_TABLE,         0
    .equ PPM_GREEN_TABLE,       PPM_BYTE_VALUES * PPM_FIELD_BYTES
    .equ PPM_BLUE_TABLE,        2 * PPM_BYTE_VALUES * PPM_FIELD_BYTES
    .equ PPM_TABLES_BYTES,      3 * PPM_BYTE_VALUES * PPM_FIELD_BYTES
    .equ PPM_FRAME,             96 + PPM_TABLES_BYTES   # saved registers above the tables

    .section .rodata
msg_bad_texture:    .asciz "bad texture: "
msg_bad_magic:      .asciz "not a PPM (magic is not P6 or P3)"
msg_short_header:   .asciz "truncated header"
msg_bad_header:     .asciz "bad header (a width, height or maxval that is not a decimal number below 2^31)"
msg_zero_size:      .asciz "bad header (width or height 0)"
msg_bad_maxval:     .asciz "bad maxval (not 1..65535)"
msg_short_raster:   .asciz "truncated raster (fewer samples than width x height x 3)"
msg_bad_sample:     .asciz "bad sample (not a decimal number)"
msg_big_sample:     .asciz "sample above maxval"
msg_texture:        .asciz "texture: "
msg_not_loaded_flat: .asciz "texture: not loaded (mode flat)\n"
msg_not_loaded_wireframe: .asciz "texture: not loaded (mode wireframe)\n"
msg_times:          .asciz "x"

    .text
    .globl ppm_parse_texture
# ppm_parse_texture
#   What: parses the texture file scene.S loaded (scene_texture) and fills
#         TEX_W, TEX_H, TEX_PIXELS (over the file's bytes, see the file
#         comment); prints "texture: <w>x<h>", or "texture: not loaded
#         (mode <mode>)" when the mode draws none (scene.S loaded none).
#   Arguments: none. Results: none (errors are fatal).
#   Clobbers: only ABI temporaries.
ppm_parse_texture:
    FRAME_SAVE PPM_FRAME, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9
    la      t0, scene_texture
    ld      s0, 0(t0)                   # s0 = file (and pixels)
    ld      s1, 8(t0)
    bnez    s0, 1f
    la      a0, msg_not_loaded_flat
    la      t0, scene
    lwu     t0, SCENE_MODE(t0)
    li      t1, MODE_FLAT
    beq     t0, t1, 3f
    la      a0, msg_not_loaded_wireframe
3:  call    console_line
    j       90f
1:  add     s1, s1, s0                  # s1 = end of the file

    # Magic.
    sub     t0, s1, s0
    li      t1, PPM_MAGIC_BYTES
    bltu    t0, t1, 80f
    lbu     t0, 0(s0)
    li      t1, PPM_MAGIC_P
    bne     t0, t1, 80f
    lbu     t0, 1(s0)
    li      s2, PPM_FORMAT_P6           # s2 = format
    li      t1, PPM_MAGIC_P6
    beq     t0, t1, 2f
    li      s2, PPM_FORMAT_P3
    li      t1, PPM_MAGIC_P3
    bne     t0, t1, 80f
2:  addi    a0, s0, PPM_MAGIC_BYTES

    # Width, height, maxval.
    mv      a1, s1
    call    ppm_header_number
    mv      s3, a1                      # s3 = width
    mv      a1, s1
    call    ppm_header_number
    mv      s4, a1                      # s4 = height
    mv      a1, s1
    call    ppm_header_number
    mv      s5, a1                      # s5 = maxval
    beqz    s3, 83f
    beqz    s4, 83f
    beqz    s5, 84f
    li      t0, PPM_MAXVAL_MAX
    bgtu    s5, t0, 84f
    mul     s6, s3, s4                  # s6 = pixels (< 2^62)
    mv      s7, s0                      # s7 = next pixel out
    li      t0, PPM_FORMAT_P3
    beq     s2, t0, 30f

    # P6: one whitespace character (a comment with its line end counts as
    # one), then the raster.
    bgeu    a0, s1, 81f
    lbu     t0, 0(a0)
    addi    a0, a0, 1
    li      t1, CHAR_COMMENT
    bne     t0, t1, 4f
3:  bgeu    a0, s1, 81f
    lbu     t0, 0(a0)
    addi    a0, a0, 1
    li      t1, CHAR_LF
    beq     t0, t1, 4f
    li      t1, CHAR_CR
    bne     t0, t1, 3b
4:  mv      s8, a0                      # s8 = next sample in
    li      s9, PPM_NARROW_SAMPLE       # s9 = bytes per sample
    li      t0, PPM_MAXVAL_ONE_BYTE
    bleu    s5, t0, 5f
    li      s9, PPM_WIDE_SAMPLE
5:  sub     t0, s1, s8                  # the raster must be all there
    li      t1, PPM_SAMPLES
    mul     t1, t1, s9
    divu    t0, t0, t1                  # t0 = whole pixels in the file
    bltu    t0, s6, 85f
    beqz    s6, 20f
    li      t0, PPM_WIDE_SAMPLE
    beq     s9, t0, 10f
    # One byte a sample: each value's fields, 0 .. maxval, into the tables
    li      s2, 0                       # s2 = value (the format is no longer needed)
7:  mv      a0, s2
    mv      a1, s2
    mv      a2, s2
    mv      a3, s5
    call    ppm_rgb565
    slli    t0, s2, 1
    add     t0, t0, sp
    li      t1, RGB565_RED_MAX << RGB565_RED_SHIFT
    and     t1, a0, t1
    sh      t1, PPM_RED_TABLE(t0)
    li      t1, RGB565_GREEN_MAX << RGB565_GREEN_SHIFT
    and     t1, a0, t1
    sh      t1, PPM_GREEN_TABLE(t0)
    andi    t1, a0, RGB565_BLUE_MAX
    sh      t1, PPM_BLUE_TABLE(t0)
    addi    s2, s2, 1
    bleu    s2, s5, 7b
6:  lbu     a0, 0(s8)
    lbu     a1, 1(s8)
    lbu     a2, 2(s8)
    addi    s8, s8, PPM_SAMPLES
    bgtu    a0, s5, 87f
    bgtu    a1, s5, 87f
    bgtu    a2, s5, 87f
    slli    a0, a0, 1
    add     a0, a0, sp
    lhu     a0, PPM_RED_TABLE(a0)
    slli    a1, a1, 1
    add     a1, a1, sp
    lhu     a1, PPM_GREEN_TABLE(a1)
    slli    a2, a2, 1
    add     a2, a2, sp
    lhu     a2, PPM_BLUE_TABLE(a2)
    or      a0, a0, a1
    or      a0, a0, a2
    sh      a0, 0(s7)
    addi    s7, s7, TEX_PIXEL_BYTES
    addi    s6, s6, -1
    bnez    s6, 6b
    j       20f
10: lbu     a0, 0(s8)                   # two bytes, big-endian
    lbu     t0, 1(s8)
    slli    a0, a0, PPM_BYTE_BITS
    or      a0, a0, t0
    lbu     a1, 2(s8)
    lbu     t0, 3(s8)
    slli    a1, a1, PPM_BYTE_BITS
    or      a1, a1, t0
    lbu     a2, 4(s8)
    lbu     t0, 5(s8)
    slli    a2, a2, PPM_BYTE_BITS
    or      a2, a2, t0
    addi    s8, s8, PPM_WIDE_SAMPLE * PPM_SAMPLES
    bgtu    a0, s5, 87f
    bgtu    a1, s5, 87f
    bgtu    a2, s5, 87f
    mv      a3, s5
    call    ppm_rgb565
    sh      a0, 0(s7)
    addi    s7, s7, TEX_PIXEL_BYTES
    addi    s6, s6, -1
    bnez    s6, 10b
    j       20f

    # P3: whitespace-separated decimal samples.
30: mv      s8, a0                      # s8 = cursor
31: mv      a0, s8
    mv      a1, s1
    call    ppm_plain_sample
    mv      s2, a1                      # s2 = red (the format is no longer needed)
    mv      a1, s1
    call    ppm_plain_sample
    mv      s9, a1                      # s9 = green
    mv      a1, s1
    call    ppm_plain_sample
    mv      s8, a0
    mv      a2, a1
    mv      a0, s2
    mv      a1, s9
    bgtu    a0, s5, 87f
    bgtu    a1, s5, 87f
    bgtu    a2, s5, 87f
    mv      a3, s5
    call    ppm_rgb565
    sh      a0, 0(s7)
    addi    s7, s7, TEX_PIXEL_BYTES
    addi    s6, s6, -1
    bnez    s6, 31b

20: la      t0, scene
    sw      s3, TEX_W(t0)
    sw      s4, TEX_H(t0)
    sd      s0, TEX_PIXELS(t0)
    call    console_lock
    la      a0, msg_texture
    call    console_puts
    mv      a0, s3
    call    console_put_dec
    la      a0, msg_times
    call    console_puts
    mv      a0, s4
    call    console_put_dec
    li      a0, CHAR_LF
    call    console_putc
    call    console_unlock

90: FRAME_RESTORE PPM_FRAME, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9
    ret

80: la      a0, msg_bad_magic
    j       ppm_error
81: la      a0, msg_short_header
    j       ppm_error
83: la      a0, msg_zero_size
    j       ppm_error
84: la      a0, msg_bad_maxval
    j       ppm_error
85: la      a0, msg_short_raster
    j       ppm_error
87: la      a0, msg_big_sample
    j       ppm_error

# ppm_error (file-local)
#   What: error 11, "bad texture: <what>".
#   Arguments: a0 = what (string).
#   Results: never returns.
#   Clobbers: everything.
ppm_error:
    mv      a2, a0
    li      a0, ERR_BAD_TEXTURE
    la      a1, msg_bad_texture
    j       error_fatal

# ppm_is_space (file-local)
#   What: whether a byte is netpbm whitespace (space, tab, LF, VT, FF, CR).
#   Arguments: a0 = byte.
#   Results: a0 = 1 whitespace, 0 not.
#   Clobbers: only ABI temporaries.
ppm_is_space:
    li      t0, CHAR_SPACE
    beq     a0, t0, 1f
    addi    t0, a0, -CHAR_TAB           # TAB, LF, VT, FF, CR are 9 .. 13
    sltiu   a0, t0, CHAR_CR - CHAR_TAB + 1
    ret
1:  li      a0, 1
    ret

# ppm_skip_space (file-local)
#   What: skips whitespace and comments ('#' to the next CR or LF).
#   Arguments: a0 = cursor, a1 = end.
#   Results: a0 = first byte of something else, or a1; a1 = how many
#         whitespace characters and comments were skipped (0 = none).
#   Clobbers: only ABI temporaries.
ppm_skip_space:
    FRAME_SAVE 32, ra, s0, s1, s2
    mv      s0, a0
    mv      s1, a1
    li      s2, 0
1:  bgeu    s0, s1, 9f
    lbu     a0, 0(s0)
    li      t0, CHAR_COMMENT
    beq     a0, t0, 3f
    call    ppm_is_space
    beqz    a0, 9f
    addi    s0, s0, 1
    addi    s2, s2, 1
    j       1b
3:  addi    s2, s2, 1                   # a comment: to its CR or LF (not taken:
4:  addi    s0, s0, 1                   # that is whitespace of its own)
    bgeu    s0, s1, 9f
    lbu     t0, 0(s0)
    li      t1, CHAR_LF
    beq     t0, t1, 1b
    li      t1, CHAR_CR
    beq     t0, t1, 1b
    j       4b
9:  mv      a0, s0
    mv      a1, s2
    FRAME_RESTORE 32, ra, s0, s1, s2
    ret

# ppm_decimal (file-local)
#   What: reads unsigned decimal digits, saturating at a1's limit + 1.
#   Arguments: a0 = cursor, a1 = end, a2 = limit.
#   Results: a0 = byte after the digits, a1 = value (limit + 1 when above
#         the limit), a2 = digits read (0 = none).
#   Clobbers: only ABI temporaries.
ppm_decimal:
    li      t0, 0                       # t0 = value
    li      t1, 0                       # t1 = digits
    li      t4, DECIMAL_BASE
    addi    t5, a2, 1
1:  bgeu    a0, a1, 3f
    lbu     t2, 0(a0)
    addi    t2, t2, -CHAR_DIGIT_0
    bgeu    t2, t4, 3f
    addi    t1, t1, 1
    addi    a0, a0, 1
    bgeu    t0, t5, 1b                  # saturated
    mul     t0, t0, t4
    add     t0, t0, t2
    bleu    t0, a2, 1b
    mv      t0, t5
    j       1b
3:  mv      a1, t0
    mv      a2, t1
    ret

# ppm_header_number (file-local)
#   What: one header number: whitespace or comments (at least one), then
#         decimal digits ending at whitespace or '#'.
#   Arguments: a0 = cursor, a1 = end.
#   Results: a0 = the byte after the digits, a1 = value.
#   Errors: 11 truncated header, bad header.
#   Clobbers: only ABI temporaries.
ppm_header_number:
    FRAME_SAVE 16, ra, s0
    mv      s0, a1                      # s0 = end
    call    ppm_skip_space
    bgeu    a0, s0, 81f
    beqz    a1, 82f                     # nothing between the tokens
    mv      a1, s0
    li      a2, PPM_NUMBER_MAX
    call    ppm_decimal
    beqz    a2, 82f
    li      t0, PPM_NUMBER_MAX
    bgtu    a1, t0, 82f
    bgeu    a0, s0, 81f                 # the header goes on after each number
    lbu     t1, 0(a0)
    li      t0, CHAR_COMMENT
    beq     t1, t0, 1f
    mv      s0, a0
    mv      a0, t1
    call    ppm_is_space
    mv      t0, a0
    mv      a0, s0
    beqz    t0, 82f
1:  FRAME_RESTORE 16, ra, s0
    ret
81: la      a0, msg_short_header
    j       ppm_error
82: la      a0, msg_bad_header
    j       ppm_error

# ppm_plain_sample (file-local)
#   What: one P3 sample: whitespace or comments, then decimal digits ending
#         at whitespace, '#' or the end of the file.
#   Arguments: a0 = cursor, a1 = end.
#   Results: a0 = the byte after the digits, a1 = value (saturated above
#         any maxval).
#   Errors: 11 truncated raster, bad sample.
#   Clobbers: only ABI temporaries.
ppm_plain_sample:
    FRAME_SAVE 32, ra, s0, s1
    mv      s0, a1                      # s0 = end
    call    ppm_skip_space
    bgeu    a0, s0, 85f
    mv      a1, s0
    li      a2, PPM_SAMPLE_MAX
    call    ppm_decimal
    beqz    a2, 86f
    mv      s1, a1                      # s1 = value
    bgeu    a0, s0, 1f
    lbu     t1, 0(a0)
    li      t0, CHAR_COMMENT
    beq     t1, t0, 1f
    mv      s0, a0
    mv      a0, t1
    call    ppm_is_space
    beqz    a0, 86f
    mv      a0, s0
1:  mv      a1, s1
    FRAME_RESTORE 32, ra, s0, s1
    ret
85: la      a0, msg_short_raster
    j       ppm_error
86: la      a0, msg_bad_sample
    j       ppm_error

    .globl ppm_rgb565
# ppm_rgb565
#   What: packs a colour of samples 0..maxval into RGB565, each field
#         rounded to nearest: (sample * field max + maxval / 2) / maxval.
#   Arguments: a0 = red, a1 = green, a2 = blue (each <= a3), a3 = maxval
#         (1 .. 65535).
#   Results: a0 = RGB565.
#   Clobbers: only ABI temporaries.
ppm_rgb565:
    srli    t0, a3, 1                   # t0 = maxval / 2
    li      t1, RGB565_RED_MAX
    mul     a0, a0, t1
    add     a0, a0, t0
    divu    a0, a0, a3
    li      t1, RGB565_GREEN_MAX
    mul     a1, a1, t1
    add     a1, a1, t0
    divu    a1, a1, a3
    li      t1, RGB565_BLUE_MAX
    mul     a2, a2, t1
    add     a2, a2, t0
    divu    a2, a2, a3
    slli    a0, a0, RGB565_RED_SHIFT
    slli    a1, a1, RGB565_GREEN_SHIFT
    or      a0, a0, a1
    or      a0, a0, a2
    ret
