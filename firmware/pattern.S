# pattern.S: the animated test pattern, drawn into a 320 x 240 RGB565
# framebuffer laid out for the LCD's 32-bit SPI frames.
#
# Picture (rows top to bottom):
#   0 .. 159    8 vertical colour bars, 40 px each: white, yellow, cyan,
#               green, magenta, red, blue, black
#   160 .. 223  grey band with a 40 x 40 orange square (rows 172 .. 211)
#               whose left edge is at x = (8 * frame) mod 320, wrapping
#               around the right edge
#   224 .. 239  the frame number's low 16 bits as 16 blocks of 20 px,
#               most significant bit on the left: white = 1, dark grey = 0
#
# Memory layout: SPI0 sends each 32-bit word most significant byte first,
# so the earlier pixel of each pair lives in bits 31:16 of its word (the
# SDK's LCD code swaps the same way); pixel x of a row is the halfword at
# byte offset 2 * (x ^ 1). Every region edge here falls on a multiple of 4
# pixels, so the pattern is written a doubleword (4 pixels, 2 words) at a
# time, each doubleword one colour.

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"

    .equ PAT_ROW_BYTES,         LCD_WIDTH * LCD_BYTES_PER_PIXEL
    .equ PAT_PIXELS_PER_DWORD,  4
    .equ PAT_DWORD_BYTES,       8
    .equ PAT_ROW_DWORDS,        LCD_WIDTH / PAT_PIXELS_PER_DWORD

    .equ PAT_BAR_COUNT,         8
    .equ PAT_BAR_DWORDS,        LCD_WIDTH / PAT_BAR_COUNT / PAT_PIXELS_PER_DWORD
    .equ PAT_BARS_ROWS,         LCD_HEIGHT * 2 / 3

    .equ PAT_BITS_ROWS,         16
    .equ PAT_BITS_COUNT,        16
    .equ PAT_BIT_DWORDS,        LCD_WIDTH / PAT_BITS_COUNT / PAT_PIXELS_PER_DWORD

    .equ PAT_BAND_ROWS,         LCD_HEIGHT - PAT_BARS_ROWS - PAT_BITS_ROWS
    .equ PAT_SQUARE_SIZE,       40
    .equ PAT_SQUARE_DWORDS,     PAT_SQUARE_SIZE / PAT_PIXELS_PER_DWORD
    .equ PAT_SQUARE_FIRST,      (PAT_BAND_ROWS - PAT_SQUARE_SIZE) / 2   # band row
    .equ PAT_SQUARE_STEP_PX,    8
    .equ PAT_SQUARE_STEP_DWORDS, PAT_SQUARE_STEP_PX / PAT_PIXELS_PER_DWORD

    .equ PAT_BAND_COLOUR,       RGB565_GREY
    .equ PAT_SQUARE_COLOUR,     RGB565_ORANGE
    .equ PAT_BIT_ONE_COLOUR,    RGB565_WHITE
    .equ PAT_BIT_ZERO_COLOUR,   RGB565_DARK_GREY

    .section .rodata
    .balign 2
bar_colours:
    .hword  RGB565_WHITE, RGB565_YELLOW, RGB565_CYAN, RGB565_GREEN
    .hword  RGB565_MAGENTA, RGB565_RED, RGB565_BLUE, RGB565_BLACK

    .text
    .globl pixel_pair
# pixel_pair
#   What: packs two RGB565 pixels into the 32-bit word SPI0 sends for them:
#         the first (left) pixel in bits 31:16 because it must go out first.
#   Arguments: a0 = first pixel, a1 = second pixel (low 16 bits used).
#   Results: a0 = packed word (zero-extended).
#   Clobbers: only ABI temporaries.
pixel_pair:
    slli    a0, a0, 48
    srli    a0, a0, 32
    slli    a1, a1, 48
    srli    a1, a1, 48
    or      a0, a0, a1
    ret

# colour_dword (file-local)
#   What: a doubleword of four pixels of one colour (two packed words).
#   Arguments: a0 = RGB565 colour.
#   Results: a0 = the doubleword.
#   Clobbers: only ABI temporaries.
colour_dword:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    mv      a1, a0
    call    pixel_pair
    slli    t0, a0, 32
    or      a0, a0, t0
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

# fill_dwords (file-local)
#   What: stores one doubleword a1 times from a0 on (4 at a time while it can:
#         this loop is where the pattern spends its time).
#   Arguments: a0 = 8-aligned address, a1 = count (> 0), a2 = doubleword.
#   Results: a0 = address just past the last store.
#   Clobbers: only ABI temporaries.
fill_dwords:
    slli    t0, a1, 3
    add     t0, t0, a0                  # t0 = end
    addi    t1, t0, -4 * PAT_DWORD_BYTES
    bltu    t1, a0, 2f                  # fewer than 4 left
1:  sd      a2, 0(a0)
    sd      a2, 8(a0)
    sd      a2, 16(a0)
    sd      a2, 24(a0)
    addi    a0, a0, 4 * PAT_DWORD_BYTES
    bgeu    t1, a0, 1b
2:  bgeu    a0, t0, 3f
    sd      a2, 0(a0)
    addi    a0, a0, PAT_DWORD_BYTES
    j       2b
3:  ret

    .globl pattern_draw
# pattern_draw
#   What: draws frame a1 of the test pattern into the framebuffer at a0.
#   Arguments: a0 = framebuffer (8-aligned, LCD_FB_BYTES), a1 = frame number.
#   Results: none.
#   Clobbers: only ABI temporaries.
    .equ PAT_FRAME,             160     # stack frame: 12 saved regs + 8 bar dwords
    .equ PAT_BAR_TABLE,         0       # offset of the 8 bar doublewords
pattern_draw:
    addi    sp, sp, -PAT_FRAME
    sd      ra, 152(sp)
    sd      s0, 144(sp)
    sd      s1, 136(sp)
    sd      s2, 128(sp)
    sd      s3, 120(sp)
    sd      s4, 112(sp)
    sd      s5, 104(sp)
    sd      s6, 96(sp)
    sd      s7, 88(sp)
    sd      s8, 80(sp)
    sd      s9, 72(sp)
    sd      s10, 64(sp)
    mv      s0, a0                      # s0 = write pointer, row after row
    mv      s1, a1                      # s1 = frame number

    # --- colour bars: the 8 doublewords once, then row after row.
    la      s2, bar_colours
    addi    s3, sp, PAT_BAR_TABLE
    li      s4, PAT_BAR_COUNT
1:  lhu     a0, 0(s2)
    call    colour_dword
    sd      a0, 0(s3)
    addi    s2, s2, 2
    addi    s3, s3, PAT_DWORD_BYTES
    addi    s4, s4, -1
    bnez    s4, 1b

    li      s2, PAT_BARS_ROWS
2:  addi    s3, sp, PAT_BAR_TABLE
    li      s4, PAT_BAR_COUNT
3:  mv      a0, s0
    li      a1, PAT_BAR_DWORDS
    ld      a2, 0(s3)
    call    fill_dwords
    mv      s0, a0
    addi    s3, s3, PAT_DWORD_BYTES
    addi    s4, s4, -1
    bnez    s4, 3b
    addi    s2, s2, -1
    bnez    s2, 2b

    # --- grey band with the square. The square's first doubleword column is
    # d0 = (frame * step) mod 80; it covers n1 = min(10, 80 - d0) columns from
    # d0 and, when it wraps, n2 = 10 - n1 columns from 0.
    li      a0, PAT_BAND_COLOUR
    call    colour_dword
    mv      s8, a0                      # s8 = grey doubleword
    li      a0, PAT_SQUARE_COLOUR
    call    colour_dword
    mv      s9, a0                      # s9 = square doubleword
    li      t0, PAT_SQUARE_STEP_DWORDS
    mul     t0, s1, t0
    li      t1, PAT_ROW_DWORDS
    remu    s5, t0, t1                  # s5 = d0
    sub     s6, t1, s5                  # s6 = 80 - d0
    li      t0, PAT_SQUARE_DWORDS
    bleu    s6, t0, 4f
    mv      s6, t0
4:  sub     s7, t0, s6                  # s6 = n1, s7 = n2
    slli    s5, s5, 3                   # s5 = d0 in bytes

    li      s2, 0                       # s2 = band row
5:  mv      s10, s0                     # s10 = start of this row
    mv      a0, s0
    li      a1, PAT_ROW_DWORDS
    mv      a2, s8
    call    fill_dwords
    mv      s0, a0
    addi    t0, s2, -PAT_SQUARE_FIRST
    li      t1, PAT_SQUARE_SIZE
    bgeu    t0, t1, 6f                  # row outside the square (unsigned test)
    add     a0, s10, s5
    mv      a1, s6
    mv      a2, s9
    call    fill_dwords
    beqz    s7, 6f
    mv      a0, s10
    mv      a1, s7
    mv      a2, s9
    call    fill_dwords
6:  addi    s2, s2, 1
    li      t0, PAT_BAND_ROWS
    bltu    s2, t0, 5b

    # --- frame number in binary, bit 15 leftmost.
    li      a0, PAT_BIT_ONE_COLOUR
    call    colour_dword
    mv      s8, a0                      # s8 = "1" doubleword
    li      a0, PAT_BIT_ZERO_COLOUR
    call    colour_dword
    mv      s9, a0                      # s9 = "0" doubleword
    li      s2, PAT_BITS_ROWS
7:  li      s3, PAT_BITS_COUNT          # s3 - 1 = bit number of this block
8:  addi    s3, s3, -1
    srl     t0, s1, s3
    andi    t0, t0, 1
    mv      a2, s9
    beqz    t0, 9f
    mv      a2, s8
9:  mv      a0, s0
    li      a1, PAT_BIT_DWORDS
    call    fill_dwords
    mv      s0, a0
    bnez    s3, 8b
    addi    s2, s2, -1
    bnez    s2, 7b

    ld      s10, 64(sp)
    ld      s9, 72(sp)
    ld      s8, 80(sp)
    ld      s7, 88(sp)
    ld      s6, 96(sp)
    ld      s5, 104(sp)
    ld      s4, 112(sp)
    ld      s3, 120(sp)
    ld      s2, 128(sp)
    ld      s1, 136(sp)
    ld      s0, 144(sp)
    ld      ra, 152(sp)
    addi    sp, sp, PAT_FRAME
    ret
