# scene.S: scene.ini, the card's description of what to show, and the
# loading of the files it names.
#
# scene.ini (in the card's root) is text, one setting per line:
#     key = value
# '#' starts a comment (to the end of the line); blank lines are fine; lines
# end in LF or CRLF; spaces and tabs around keys and values are ignored; a
# UTF-8 byte-order mark at the start is skipped. Keys are matched
# case-insensitively against scene_keys. An unknown key, a duplicate key, a
# line without '=', an empty key or value, a value of SCENE_VALUE_MAX bytes
# or more, or a control character outside a comment is error 9 naming the
# line (counted from 1).
#
# The parser is table-driven: a key is one scene_keys row (name, kind, value
# buffer, loaded-file record). Kind SCENE_KIND_FILE values are paths that
# scene_load then loads; a key that is absent is skipped silently.
#
# Every file loaded (scene.ini included) is reported on the console as
#     load <path> <size> crc32=<8 lowercase hex digits>
# with the CRC-32 zlib.crc32 gives for the same bytes.

    .option norelax
    .include "k210.inc"
    .include "errors.inc"

    .equ SCENE_VALUE_MAX,       256         # value bytes, NUL included
    .equ SCENE_KIND_FILE,       1           # the value is a path to load
# scene_keys rows
    .equ SCENE_KEY_NAME,        0           # key (NUL-terminated, lower case)
    .equ SCENE_KEY_KIND,        8
    .equ SCENE_KEY_VALUE,       16          # value buffer, SCENE_VALUE_MAX bytes
    .equ SCENE_KEY_FILE,        24          # file record: address, size (0, 0 = none)
    .equ SCENE_KEY_BYTES,       32
    .equ FILE_RECORD_ADDRESS,   0
    .equ FILE_RECORD_SIZE,      8
    .equ FILE_RECORD_BYTES,     16

    .equ CHAR_TAB,              '\t'
    .equ CHAR_LF,               '\n'
    .equ CHAR_CR,               '\r'
    .equ CHAR_SPACE,            ' '
    .equ CHAR_COMMENT,          '#'
    .equ CHAR_EQUALS,           '='
    .equ CHAR_FIRST_PRINTABLE,  0x20
    .equ CHAR_DELETE,           0x7F
    .equ ASCII_UPPER_A,         'A'
    .equ ASCII_UPPER_Z,         'Z'
    .equ ASCII_CASE_SHIFT,      5           # 'a' - 'A' = 1 << 5
    .equ UTF8_BOM_0,            0xEF
    .equ UTF8_BOM_1,            0xBB
    .equ UTF8_BOM_2,            0xBF
    .equ UTF8_BOM_BYTES,        3

    .section .rodata
    .balign 8
# The keys scene.ini may set. Adding a key: one row here plus its buffers.
scene_keys:
    .dword  key_model, SCENE_KIND_FILE, scene_model_path, scene_model
    .dword  key_texture, SCENE_KIND_FILE, scene_texture_path, scene_texture
scene_keys_end:

key_model:          .asciz "model"
key_texture:        .asciz "texture"
path_scene_ini:     .asciz "scene.ini"
msg_load:           .asciz "load "
msg_crc32:          .asciz " crc32="
msg_bad_scene:      .asciz "bad scene.ini line "
msg_colon:          .asciz ": "
msg_unknown_key:    .asciz "unknown key"
msg_duplicate_key:  .asciz "duplicate key"
msg_no_equals:      .asciz "malformed line (no '=')"
msg_empty_key:      .asciz "malformed line (no key)"
msg_empty_value:    .asciz "malformed line (no value)"
msg_long_value:     .asciz "malformed line (value too long)"
msg_control:        .asciz "malformed line (control character)"

    .text
    .globl scene_load
# scene_load
#   What: loads and parses scene.ini from the card's root, then loads every
#         file it names (model, texture), recording each in its file record
#         (scene_model, scene_texture). Needs fat32_mount and heap_init.
#   Arguments: none. Results: none (errors are fatal).
#   Clobbers: only ABI temporaries.
scene_load:
    addi    sp, sp, -32
    sd      ra, 24(sp)
    sd      s0, 16(sp)
    sd      s1, 8(sp)
    la      a0, path_scene_ini
    call    scene_load_file
    call    scene_parse
    la      s0, scene_keys
    la      s1, scene_keys_end
1:  ld      t0, SCENE_KEY_KIND(s0)
    li      t1, SCENE_KIND_FILE
    bne     t0, t1, 2f
    ld      a0, SCENE_KEY_VALUE(s0)
    lbu     t0, 0(a0)
    beqz    t0, 2f                      # not in scene.ini: skipped
    call    scene_load_file
    ld      t0, SCENE_KEY_FILE(s0)
    sd      a0, FILE_RECORD_ADDRESS(t0)
    sd      a1, FILE_RECORD_SIZE(t0)
2:  addi    s0, s0, SCENE_KEY_BYTES
    bltu    s0, s1, 1b
    ld      s1, 8(sp)
    ld      s0, 16(sp)
    ld      ra, 24(sp)
    addi    sp, sp, 32
    ret

    .globl scene_load_file
# scene_load_file
#   What: loads a file into the heap (fat32_load, which also computes its
#         CRC-32) and prints "load <path> <size> crc32=<crc>" for it.
#   Arguments: a0 = path (NUL-terminated).
#   Results: a0 = address of the bytes, a1 = size.
#   Clobbers: only ABI temporaries.
scene_load_file:
    addi    sp, sp, -48
    sd      ra, 40(sp)
    sd      s0, 32(sp)
    sd      s1, 24(sp)
    sd      s2, 16(sp)
    sd      s3, 8(sp)
    mv      s0, a0                      # s0 = path
    call    fat32_load
    mv      s1, a0                      # s1 = address
    mv      s2, a1                      # s2 = size
    mv      s3, a2                      # s3 = CRC-32
    call    console_lock
    la      a0, msg_load
    call    console_puts
    mv      a0, s0
    call    console_puts
    li      a0, CHAR_SPACE
    call    console_putc
    mv      a0, s2
    call    console_put_dec
    la      a0, msg_crc32
    call    console_puts
    mv      a0, s3
    call    console_put_hex32
    li      a0, CHAR_LF
    call    console_putc
    call    console_unlock
    mv      a0, s1
    mv      a1, s2
    ld      s3, 8(sp)
    ld      s2, 16(sp)
    ld      s1, 24(sp)
    ld      s0, 32(sp)
    ld      ra, 40(sp)
    addi    sp, sp, 48
    ret

# scene_parse (file-local)
#   What: parses scene.ini's text (see the file comment), copying each
#         value into its key's buffer.
#   Arguments: a0 = text, a1 = length in bytes.
#   Results: none (errors are fatal).
#   Clobbers: only ABI temporaries.
scene_parse:
    addi    sp, sp, -80
    sd      ra, 72(sp)
    sd      s0, 64(sp)
    sd      s1, 56(sp)
    sd      s2, 48(sp)
    sd      s3, 40(sp)
    sd      s4, 32(sp)
    sd      s5, 24(sp)
    sd      s6, 16(sp)
    sd      s7, 8(sp)
    mv      s0, a0                      # s0 = start of the line
    add     s1, a0, a1                  # s1 = end of the text
    li      s2, 1                       # s2 = line number

    # A UTF-8 byte-order mark is not part of the first line.
    li      t0, UTF8_BOM_BYTES
    bltu    a1, t0, 1f
    lbu     t0, 0(s0)
    li      t1, UTF8_BOM_0
    bne     t0, t1, 1f
    lbu     t0, 1(s0)
    li      t1, UTF8_BOM_1
    bne     t0, t1, 1f
    lbu     t0, 2(s0)
    li      t1, UTF8_BOM_2
    bne     t0, t1, 1f
    addi    s0, s0, UTF8_BOM_BYTES

1:  bgeu    s0, s1, 90f
    # s3 = the line's LF (or the end of the text)
    mv      s3, s0
2:  bgeu    s3, s1, 3f
    lbu     t0, 0(s3)
    li      t1, CHAR_LF
    beq     t0, t1, 3f
    addi    s3, s3, 1
    j       2b
    # s5 = end of the content: before a CR ending the line, before a comment
3:  mv      s5, s3
    bleu    s5, s0, 4f
    lbu     t0, -1(s5)
    li      t1, CHAR_CR
    bne     t0, t1, 4f
    addi    s5, s5, -1
4:  mv      t2, s0
5:  bgeu    t2, s5, 7f
    lbu     t0, 0(t2)
    li      t1, CHAR_COMMENT
    beq     t0, t1, 6f
    li      t1, CHAR_TAB
    beq     t0, t1, 51f
    li      t1, CHAR_FIRST_PRINTABLE
    bltu    t0, t1, 80f
    li      t1, CHAR_DELETE
    beq     t0, t1, 80f
51: addi    t2, t2, 1
    j       5b
6:  mv      s5, t2
7:  # trim: s4 = first, s5 = end
    mv      a0, s0
    mv      a1, s5
    call    trim_blanks
    mv      s4, a0
    mv      s5, a1
    beq     s4, s5, 60f                 # blank or comment only
    # s6 = the '='
    mv      s6, s4
8:  bgeu    s6, s5, 81f
    lbu     t0, 0(s6)
    li      t1, CHAR_EQUALS
    beq     t0, t1, 9f
    addi    s6, s6, 1
    j       8b
9:  # key = [s4, s6) trimmed
    mv      a0, s4
    mv      a1, s6
    call    trim_blanks
    beq     a0, a1, 82f
    call    scene_find_key
    beqz    a0, 84f
    mv      s7, a0                      # s7 = the key's row
    # value = (s6, s5) trimmed
    addi    a0, s6, 1
    mv      a1, s5
    call    trim_blanks
    beq     a0, a1, 83f
    sub     t0, a1, a0                  # t0 = value length
    li      t1, SCENE_VALUE_MAX
    bgeu    t0, t1, 86f
    ld      t2, SCENE_KEY_VALUE(s7)
    lbu     t3, 0(t2)
    bnez    t3, 85f                     # set before: duplicate
10: lbu     t3, 0(a0)
    sb      t3, 0(t2)
    addi    a0, a0, 1
    addi    t2, t2, 1
    bltu    a0, a1, 10b
    sb      zero, 0(t2)
60: addi    s0, s3, 1                   # next line
    addi    s2, s2, 1
    j       1b

80: la      a1, msg_control
    j       89f
81: la      a1, msg_no_equals
    j       89f
82: la      a1, msg_empty_key
    j       89f
83: la      a1, msg_empty_value
    j       89f
84: la      a1, msg_unknown_key
    j       89f
85: la      a1, msg_duplicate_key
    j       89f
86: la      a1, msg_long_value
89: mv      a0, s2
    j       scene_error

90: ld      s7, 8(sp)
    ld      s6, 16(sp)
    ld      s5, 24(sp)
    ld      s4, 32(sp)
    ld      s3, 40(sp)
    ld      s2, 48(sp)
    ld      s1, 56(sp)
    ld      s0, 64(sp)
    ld      ra, 72(sp)
    addi    sp, sp, 80
    ret

# scene_error (file-local)
#   What: error 9, "bad scene.ini line <n>: <reason>".
#   Arguments: a0 = line number, a1 = reason (string).
#   Results: never returns.
#   Clobbers: everything.
scene_error:
    mv      s0, a0
    mv      s1, a1
    li      a0, ERR_BAD_SCENE
    call    error_begin
    la      a0, msg_bad_scene
    call    console_puts
    mv      a0, s0
    call    console_put_dec
    la      a0, msg_colon
    call    console_puts
    mv      a0, s1
    call    console_puts
    j       error_end

# trim_blanks (file-local)
#   What: narrows [a0, a1) past leading and trailing spaces and tabs.
#   Arguments: a0 = start, a1 = end.
#   Results: a0 = first non-blank (or a1), a1 = end after the last non-blank.
#   Clobbers: only ABI temporaries.
trim_blanks:
    li      t1, CHAR_SPACE
    li      t2, CHAR_TAB
1:  bgeu    a0, a1, 3f
    lbu     t0, 0(a0)
    beq     t0, t1, 2f
    bne     t0, t2, 3f
2:  addi    a0, a0, 1
    j       1b
3:  bleu    a1, a0, 5f
    lbu     t0, -1(a1)
    beq     t0, t1, 4f
    bne     t0, t2, 5f
4:  addi    a1, a1, -1
    j       3b
5:  ret

# scene_find_key (file-local)
#   What: the scene_keys row whose name equals [a0, a1), ASCII letters
#         compared case-insensitively.
#   Arguments: a0 = key start, a1 = key end (non-empty).
#   Results: a0 = row address, or 0 when no key has that name.
#   Clobbers: only ABI temporaries.
scene_find_key:
    la      a2, scene_keys
    la      a3, scene_keys_end
1:  ld      t0, SCENE_KEY_NAME(a2)      # t0 = table name
    mv      t1, a0                      # t1 = key byte
2:  lbu     t2, 0(t0)
    beqz    t2, 4f                      # table name ended
    beq     t1, a1, 5f                  # key ended first
    lbu     t3, 0(t1)
    addi    t4, t3, -ASCII_UPPER_A      # an upper-case letter goes to lower
    sltiu   t4, t4, ASCII_UPPER_Z - ASCII_UPPER_A + 1   # case (the table's)
    slli    t4, t4, ASCII_CASE_SHIFT
    or      t3, t3, t4
    bne     t2, t3, 5f
    addi    t0, t0, 1
    addi    t1, t1, 1
    j       2b
4:  bne     t1, a1, 5f                  # both ended: a match
    mv      a0, a2
    ret
5:  addi    a2, a2, SCENE_KEY_BYTES
    bltu    a2, a3, 1b
    li      a0, 0
    ret

# ---------------------------------------------------------------------------
    .bss
    .balign 8
    .globl scene_model
    .globl scene_texture
# File records of what scene.ini named: address, size (both 0 when absent).
scene_model:
    .space  FILE_RECORD_BYTES
scene_texture:
    .space  FILE_RECORD_BYTES
# Values as written in scene.ini (NUL-terminated; empty = key absent).
scene_model_path:
    .space  SCENE_VALUE_MAX
scene_texture_path:
    .space  SCENE_VALUE_MAX
