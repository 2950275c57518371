# parse.S: text helpers shared by the scene.ini and OBJ readers: blank
# skipping and decimal numbers.
#
# A number is  [+|-] (digits [. digits] | . digits) [(e|E) [+|-] digits]
# (at least one mantissa digit, at least one exponent digit when there is an
# 'e'), e.g. 3, -0.25, .5, 5., -1.5e-3, 2E+10. It must end at the end of the
# text or at a space or tab. Its value is computed in double precision: the
# first 19 significant digits (digits are taken while the integer is below
# PARSE_MANTISSA_LIMIT; the rest are dropped, not rounded) as an exact 64-bit
# integer, converted to double (one rounding), then scaled by the decimal
# exponent with one multiplication or division by an exact power of ten (a
# second rounding) while the exponent is within the table (|e| <= 22), one
# more by 10^22 for each 22 beyond. Callers round once more to single
# precision, so results are the correctly rounded f32 but for double-rounding
# ties far below what a model or scene can show. The host's readers follow
# these steps exactly (reference/numbers.py), so they decide as the firmware
# does even at those ties.

    .option norelax
    .include "text.inc"
    .include "frame.inc"

    .equ PARSE_MANTISSA_LIMIT,  1000000000000000000    # 10^18: one more digit still fits 64 bits
    .equ PARSE_EXPONENT_CAP,    100000      # |exponent| saturates here (the result is 0 or inf)
    .equ PARSE_POW10_MAX,       22          # 10^22 is the largest power of ten exact in double
    .equ PARSE_POW10_SHIFT,     3           # 8 bytes per table entry
    .equ PARSE_DOUBLE_BYTES,    8

    .section .rodata
    .balign 8
# pow10_table: 10^0 .. 10^22, each exact in double precision.
pow10_table:
    .double 1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11
    .double 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22
pow10_table_end:
    .if (pow10_table_end - pow10_table) != (PARSE_POW10_MAX + 1) * PARSE_DOUBLE_BYTES
    .error "pow10_table needs 10^0 .. 10^PARSE_POW10_MAX"
    .endif

    .text
    .globl parse_skip_blanks
# parse_skip_blanks
#   What: skips spaces and tabs.
#   Arguments: a0 = cursor, a1 = end of the text.
#   Results: a0 = the first byte that is not a space or tab, or a1.
#   Clobbers: only ABI temporaries.
parse_skip_blanks:
    li      t1, CHAR_SPACE
    li      t2, CHAR_TAB
1:  bgeu    a0, a1, 2f
    lbu     t0, 0(a0)
    beq     t0, t1, 3f
    bne     t0, t2, 2f
3:  addi    a0, a0, 1
    j       1b
2:  ret

    .globl parse_number
# parse_number
#   What: reads one decimal number (see the file comment) into a double.
#   Arguments: a0 = its first character, a1 = end of the text.
#   Results: a1 = 0 and a0 = the byte after the number (a1 of the
#         arguments, a space or a tab), fa0 = its value; or a1 = 1 when the
#         text there is not a number that ends at a blank or the end
#         (a0, fa0 undefined).
#   Clobbers: only ABI temporaries (integer and floating point).
parse_number:
    li      t6, 0                       # t6 = 1 when negative
    li      t2, 0                       # t2 = mantissa (first digits, exact)
    li      t3, 0                       # t3 = decimal exponent of the mantissa
    li      t4, 0                       # t4 = mantissa digits seen
    li      t5, PARSE_MANTISSA_LIMIT
    li      a5, DECIMAL_BASE
    bgeu    a0, a1, 90f
    lbu     t0, 0(a0)
    li      t1, CHAR_MINUS
    bne     t0, t1, 1f
    li      t6, 1
    j       2f
1:  li      t1, CHAR_PLUS
    bne     t0, t1, 3f
2:  addi    a0, a0, 1

    # Integer digits: beyond the mantissa's capacity they only scale it.
3:  bgeu    a0, a1, 10f
    lbu     t0, 0(a0)
    addi    t1, t0, -CHAR_DIGIT_0
    bgeu    t1, a5, 5f
    addi    t4, t4, 1
    bgeu    t2, t5, 4f
    mul     t2, t2, a5
    add     t2, t2, t1
    addi    a0, a0, 1
    j       3b
4:  addi    t3, t3, 1
    addi    a0, a0, 1
    j       3b

    # Fraction digits: beyond the mantissa's capacity they are dropped.
5:  li      t1, CHAR_POINT
    bne     t0, t1, 10f
    addi    a0, a0, 1
6:  bgeu    a0, a1, 10f
    lbu     t0, 0(a0)
    addi    t1, t0, -CHAR_DIGIT_0
    bgeu    t1, a5, 10f
    addi    t4, t4, 1
    bgeu    t2, t5, 7f
    mul     t2, t2, a5
    add     t2, t2, t1
    addi    t3, t3, -1
7:  addi    a0, a0, 1
    j       6b

    # Exponent.
10: beqz    t4, 90f                     # no mantissa digit
    bgeu    a0, a1, 20f
    lbu     t0, 0(a0)
    ori     t0, t0, ASCII_CASE_BIT
    li      t1, CHAR_LOWER_E
    bne     t0, t1, 20f
    addi    a0, a0, 1
    li      a4, 0                       # a4 = 1 when the exponent is negative
    bgeu    a0, a1, 90f
    lbu     t0, 0(a0)
    li      t1, CHAR_MINUS
    bne     t0, t1, 11f
    li      a4, 1
    j       12f
11: li      t1, CHAR_PLUS
    bne     t0, t1, 13f
12: addi    a0, a0, 1
13: li      a3, 0                       # a3 = exponent value (saturating)
    li      a6, 0                       # a6 = exponent digits
    li      a7, PARSE_EXPONENT_CAP
14: bgeu    a0, a1, 16f
    lbu     t0, 0(a0)
    addi    t1, t0, -CHAR_DIGIT_0
    bgeu    t1, a5, 16f
    addi    a6, a6, 1
    bgeu    a3, a7, 15f
    mul     a3, a3, a5
    add     a3, a3, t1
15: addi    a0, a0, 1
    j       14b
16: beqz    a6, 90f
    beqz    a4, 17f
    neg     a3, a3
17: add     t3, t3, a3

    # The number must end here.
20: bgeu    a0, a1, 21f
    lbu     t0, 0(a0)
    li      t1, CHAR_SPACE
    beq     t0, t1, 21f
    li      t1, CHAR_TAB
    bne     t0, t1, 90f

    # Value = mantissa * 10^t3.
21: fcvt.d.lu fa0, t2
    beqz    t2, 30f
    la      a2, pow10_table
    li      a3, PARSE_POW10_MAX
    fld     ft1, PARSE_POW10_MAX * PARSE_DOUBLE_BYTES(a2)   # ft1 = 10^22
    bltz    t3, 25f
22: ble     t3, a3, 23f
    fmul.d  fa0, fa0, ft1
    addi    t3, t3, -PARSE_POW10_MAX
    j       22b
23: slli    t0, t3, PARSE_POW10_SHIFT
    add     t0, t0, a2
    fld     ft0, 0(t0)
    fmul.d  fa0, fa0, ft0
    j       30f
25: neg     t3, t3
26: ble     t3, a3, 27f
    fdiv.d  fa0, fa0, ft1
    addi    t3, t3, -PARSE_POW10_MAX
    j       26b
27: slli    t0, t3, PARSE_POW10_SHIFT
    add     t0, t0, a2
    fld     ft0, 0(t0)
    fdiv.d  fa0, fa0, ft0
30: beqz    t6, 31f
    fneg.d  fa0, fa0
31: li      a1, 0
    ret

90: li      a1, 1
    ret

    .globl parse_numbers
# parse_numbers
#   What: reads the blank-separated numbers from the cursor to the end of
#         the text into doubles (parse_number for each).
#   Arguments: a0 = cursor, a1 = end of the text, a2 = buffer of a3
#         doubles, a3 = most numbers wanted.
#   Results: a0 = how many numbers there are (a3 + 1 when there are more
#         than a3: only the first a3 are stored), a1 = 0, or a1 = 1 when
#         something there is not a number (a0 undefined).
#   Clobbers: only ABI temporaries.
parse_numbers:
    FRAME_SAVE 64, ra, s0, s1, s2, s3, s4
    mv      s0, a0                      # s0 = cursor
    mv      s1, a1                      # s1 = end
    mv      s2, a2                      # s2 = next slot
    mv      s3, a3                      # s3 = slots left
    li      s4, 0                       # s4 = numbers read
1:  mv      a0, s0
    mv      a1, s1
    call    parse_skip_blanks
    bgeu    a0, s1, 3f
    beqz    s3, 4f                      # one more than wanted
    mv      a1, s1
    call    parse_number
    bnez    a1, 9f
    mv      s0, a0
    fsd     fa0, 0(s2)
    addi    s2, s2, PARSE_DOUBLE_BYTES
    addi    s3, s3, -1
    addi    s4, s4, 1
    j       1b
4:  addi    s4, s4, 1
3:  mv      a0, s4
    li      a1, 0
    j       10f
9:  li      a1, 1
10: FRAME_RESTORE 64, ra, s0, s1, s2, s3, s4
    ret
