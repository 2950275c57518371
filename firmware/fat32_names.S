# fat32_names.S: a directory entry's names against the path component
# looked up (fat32_lookup.S fat32_find): the component decoded from UTF-8 to
# UTF-16 once, a long name compared with it unit by unit, an 8.3 name as
# text, ASCII letters case-folded in both; and the checksum that ties a long
# name to its short entry.

    .option norelax
    .include "k210.inc"
    .include "fat32.inc"
    .include "text.inc"

    .text
    .globl short_name_checksum
# short_name_checksum
#   What: the long-name checksum of a short entry's 11 name bytes
#         (rotate right by one, add the next byte, modulo 256).
#   Arguments: a0 = directory entry.
#   Results: a0 = checksum (0 .. 255).
#   Clobbers: only ABI temporaries.
short_name_checksum:
    addi    t2, a0, DIR_NAME_BYTES
    li      t0, 0
1:  srli    t1, t0, 1
    slli    t0, t0, CHECKSUM_ROTATE
    or      t0, t0, t1
    andi    t0, t0, BYTE_MASK
    lbu     t1, 0(a0)
    add     t0, t0, t1
    andi    t0, t0, BYTE_MASK
    addi    a0, a0, 1
    bltu    a0, t2, 1b
    mv      a0, t0
    ret

# ascii_fold (file-local macro): upper-cases \reg if it is 'a' .. 'z'.
.macro ASCII_FOLD reg, tmp
    addi    \tmp, \reg, -ASCII_LOWER_A
    sltiu   \tmp, \tmp, ASCII_LOWER_Z - ASCII_LOWER_A + 1
    slli    \tmp, \tmp, ASCII_CASE_SHIFT              # ASCII_CASE_BIT when a lower-case letter
    sub     \reg, \reg, \tmp
.endm
    .if ASCII_CASE_BIT != (1 << ASCII_CASE_SHIFT)
    .error "ASCII_CASE_SHIFT does not match ASCII_CASE_BIT"
    .endif

    .globl long_name_matches
# long_name_matches
#   What: compares the long name in lfn_buffer (a0 entries' worth, ending
#         at its first NUL or after them all) with the path component in
#         fat_name16: same length; ASCII letters compared case-folded, every
#         other UTF-16 unit exactly.
#   Arguments: a0 = long-name entries (1 .. 20), a1 = component length in
#         UTF-16 units.
#   Results: a0 = 1 match, 0 not.
#   Clobbers: only ABI temporaries.
long_name_matches:
    li      t0, LFN_CHARS
    mul     t0, t0, a0
    la      t1, lfn_buffer
    slli    t0, t0, UTF16_UNIT_SHIFT
    add     t0, t0, t1                  # t0 = end of the stored units
    mv      t2, t1
1:  bgeu    t2, t0, 2f                  # t2 = scan for the terminating NUL
    lhu     t3, 0(t2)
    beqz    t3, 2f
    addi    t2, t2, UTF16_UNIT_BYTES
    j       1b
2:  sub     t2, t2, t1
    srli    t2, t2, UTF16_UNIT_SHIFT    # t2 = long name length
    bne     t2, a1, 9f
    la      t3, fat_name16
3:  beqz    t2, 8f
    lhu     t4, 0(t1)
    lhu     t5, 0(t3)
    beq     t4, t5, 4f
    li      t6, ASCII_LIMIT
    bgeu    t4, t6, 9f
    bgeu    t5, t6, 9f
    ASCII_FOLD t4, t6
    ASCII_FOLD t5, t6
    bne     t4, t5, 9f
4:  addi    t1, t1, UTF16_UNIT_BYTES
    addi    t3, t3, UTF16_UNIT_BYTES
    addi    t2, t2, -1
    j       3b
8:  li      a0, 1
    ret
9:  li      a0, 0
    ret

    .globl short_name_matches
# short_name_matches
#   What: compares a short entry's 8.3 name, written as text ("BASE.EXT"
#         without padding, no dot without an extension, a leading 0x05 read
#         as 0xE5), with a path component, ASCII letters case-folded.
#   Arguments: a0 = directory entry, a1 = component, a2 = its length.
#   Results: a0 = 1 match, 0 not.
#   Clobbers: only ABI temporaries.
short_name_matches:
    addi    sp, sp, -16                 # the text, at most 12 bytes
    mv      t0, sp                      # t0 = write pointer
    # base: up to its last non-space byte
    li      t1, DIR_BASE_BYTES
1:  add     t2, a0, t1
    lbu     t2, -1(t2)
    li      t3, DIR_NAME_PAD
    bne     t2, t3, 2f
    addi    t1, t1, -1
    bnez    t1, 1b
2:  li      t2, 0                       # t2 = index; t1 = base length
3:  bgeu    t2, t1, 5f
    add     t3, a0, t2
    lbu     t3, 0(t3)
    bnez    t2, 4f
    li      t4, DIR_MARK_KANJI_E5
    bne     t3, t4, 4f
    li      t3, DIR_MARK_DELETED
4:  sb      t3, 0(t0)
    addi    t0, t0, 1
    addi    t2, t2, 1
    j       3b
5:  # extension: up to its last non-space byte, after a dot
    li      t1, DIR_EXT_BYTES
6:  add     t2, a0, t1
    lbu     t2, DIR_BASE_BYTES - 1(t2)
    li      t3, DIR_NAME_PAD
    bne     t2, t3, 7f
    addi    t1, t1, -1
    bnez    t1, 6b
    j       9f
7:  li      t3, EXT_SEPARATOR
    sb      t3, 0(t0)
    addi    t0, t0, 1
    addi    t4, a0, DIR_BASE_BYTES
    add     t5, t4, t1
8:  lbu     t3, 0(t4)
    sb      t3, 0(t0)
    addi    t0, t0, 1
    addi    t4, t4, 1
    bltu    t4, t5, 8b
9:  sub     t1, t0, sp                  # t1 = text length
    bne     t1, a2, 12f
    mv      t0, sp
10: beqz    t1, 11f
    lbu     t2, 0(t0)
    lbu     t3, 0(a1)
    ASCII_FOLD t2, t4
    ASCII_FOLD t3, t4
    bne     t2, t3, 12f
    addi    t0, t0, 1
    addi    a1, a1, 1
    addi    t1, t1, -1
    j       10b
11: li      a0, 1
    addi    sp, sp, 16
    ret
12: li      a0, 0
    addi    sp, sp, 16
    ret

    .globl utf8_to_utf16
# utf8_to_utf16
#   What: decodes a path component from UTF-8 into UTF-16 units in
#         fat_name16 (characters above U+FFFF as surrogate pairs). A byte
#         that does not start a valid sequence stands for itself. Units past
#         the buffer are counted but not stored (such a name matches no
#         long name anyway).
#   Arguments: a0 = bytes, a1 = byte count.
#   Results: a0 = number of UTF-16 units.
#   Clobbers: only ABI temporaries.
utf8_to_utf16:
    add     a1, a1, a0                  # a1 = end
    la      a2, fat_name16
    li      a3, 0                       # a3 = units
1:  bgeu    a0, a1, 9f
    lbu     t0, 0(a0)
    addi    a0, a0, 1
    li      t1, ASCII_LIMIT
    bltu    t0, t1, 7f                  # ASCII
    andi    t1, t0, UTF8_LEAD2_MASK
    li      t2, UTF8_LEAD2_TAG
    li      t3, UTF8_LEAD2_CONTS                     # t3 = continuation bytes
    andi    t4, t0, ~UTF8_LEAD2_MASK & BYTE_MASK
    beq     t1, t2, 2f
    andi    t1, t0, UTF8_LEAD3_MASK
    li      t2, UTF8_LEAD3_TAG
    li      t3, UTF8_LEAD3_CONTS
    andi    t4, t0, ~UTF8_LEAD3_MASK & BYTE_MASK
    beq     t1, t2, 2f
    andi    t1, t0, UTF8_LEAD4_MASK
    li      t2, UTF8_LEAD4_TAG
    li      t3, UTF8_LEAD4_CONTS
    andi    t4, t0, ~UTF8_LEAD4_MASK & BYTE_MASK
    beq     t1, t2, 2f
    j       7f                          # not a lead byte: itself
2:  mv      t5, a0                      # t5 = scan; t4 = code point so far
3:  bgeu    t5, a1, 7f                  # truncated: the lead byte stands for itself
    lbu     t1, 0(t5)
    andi    t2, t1, UTF8_CONT_MASK
    li      t6, UTF8_CONT_TAG
    bne     t2, t6, 7f
    andi    t1, t1, UTF8_CONT_BITS
    slli    t4, t4, UTF8_CONT_SHIFT
    or      t4, t4, t1
    addi    t5, t5, 1
    addi    t3, t3, -1
    bnez    t3, 3b
    mv      a0, t5
    mv      t0, t4
    li      t1, UTF16_SUPPLEMENTARY
    bltu    t0, t1, 7f
    sub     t0, t0, t1                  # a surrogate pair
    srli    t1, t0, UTF16_SURROGATE_SHIFT
    li      t2, UTF16_HIGH_SURROGATE
    add     t1, t1, t2
    li      t2, LFN_BUFFER_UNITS
    bgeu    a3, t2, 4f
    slli    t2, a3, UTF16_UNIT_SHIFT
    add     t2, t2, a2
    sh      t1, 0(t2)
4:  addi    a3, a3, 1
    andi    t0, t0, UTF16_SURROGATE_BITS
    li      t2, UTF16_LOW_SURROGATE
    add     t0, t0, t2
7:  li      t2, LFN_BUFFER_UNITS        # store unit t0
    bgeu    a3, t2, 8f
    slli    t2, a3, UTF16_UNIT_SHIFT
    add     t2, t2, a2
    sh      t0, 0(t2)
8:  addi    a3, a3, 1
    j       1b
9:  mv      a0, a3
    ret

