# scene.S: scene.ini, the card's description of what to show; the `scene`
# structure (scene.inc) it fills; the loading of the files it names.
#
# scene.ini (in the card's root) is text, one setting per line:
#     key = value
# '#' starts a comment (to the end of the line), except as the first
# character of a value (background = #RRGGBB); blank lines are fine; lines
# end in LF or CRLF; spaces and tabs around keys and values are ignored; a
# UTF-8 byte-order mark at the start is skipped. Keys are matched
# case-insensitively against scene_keys, and so are the words of mode and
# cull. Every key has a default, so scene.ini may leave any of them out, and
# a card without scene.ini at all shows the defaults (that is not an error).
#
# key         value                                   default       scene field
# ----------  --------------------------------------  ------------  ----------------
# model       path of a Wavefront .obj (obj.S)        model.obj     (scene_model)
# texture     path of a P3 / P6 .ppm (ppm.S); loaded  texture.ppm   (scene_texture)
#             only in textured mode
# mode        textured | flat | wireframe             textured      SCENE_MODE
# cull        on|off|yes|no|true|false|1|0            on            SCENE_CULL
# scale       s  or  sx sy sz                         1 1 1         SCENE_SCALE
# axis        x y z, not all zero (stored normalised) 0 1 0         SCENE_AXIS
# angle       degrees at frame 0                      0             SCENE_ANGLE
# step        degrees per frame                       4             SCENE_STEP
# translate   x y z                                   0 0 -3        SCENE_TRANSLATE
# fov         vertical, degrees, 0 < fov < 180        60            SCENE_FOV
# near        near plane, > 0                         0.1           SCENE_NEAR
# far         far plane, > near                       100           SCENE_FAR
# light       x y z towards the light, not all zero   0 0 1         SCENE_LIGHT
#             (stored normalised)
# ambient     0 <= ambient <= 1                       0.2           SCENE_AMBIENT
# background  R G B (integers 0..255) or #RRGGBB      #101410       SCENE_BACKGROUND
#                                                     (RGB565 0x10A2)
#
# Precision settings (what the renderer approximates; docs/reference/scene-keys.md "Precision
# settings" has what each costs and loses):
# interpolation  perspective | affine                 perspective   SCENE_INTERPOLATION
# shading     flat | gouraud | phong                  flat          SCENE_SHADING
# light_levels   whole number 2..65537                65            SCENE_LIGHT_LEVELS
# angles      polynomial | table                      polynomial    SCENE_ANGLES
# depth       int16 | float32                         int16         SCENE_DEPTH
# snap        subpixel | pixel                        subpixel      SCENE_SNAP
# filter      nearest | bilinear | mipmap | anisotropic nearest      SCENE_FILTER
#             (texture filtering, raster_fills.S; its default, 0, is the
#             zeros scene_defaults leaves after scene_default_values)
# antialias   off | edge | supersample                off           SCENE_ANTIALIAS
#             (edge: silhouette pixels blended by their coverage,
#             raster_fills.S; supersample: four samples a pixel,
#             render.S render_band;
#             the same zero default)
#
# Not what is drawn, only how fast (main.S; the same default, 0):
# harts       auto | 1 | 2                            auto          SCENE_HARTS
#             (which harts draw: 1 hart 0 alone, 2 both, auto both
#             once hart 0 alone takes longer than the LCD's transfer)
#
# Conventions (scene.inc): right-handed, camera at the origin looking down
# -z (a model in view has negative z), angles in degrees about the axis.
#
# Numbers are parse.S's (sign, digits, fraction, exponent: -1.5e-3), each
# rounded to single precision, which must be finite. Vectors are numbers
# separated by spaces or tabs. Paths are from the card's root (fat32_lookup.S).
#
# An unknown key, a duplicate key, a line without '=', an empty key or value,
# a path of SCENE_VALUE_MAX bytes or more, a control character outside a
# comment, or a bad value (not a number, the wrong count of numbers, out of
# range as listed, an unknown word, a zero vector) is error 9 naming the line
# (counted from 1): "error 9 bad scene.ini line N: <what>". far <= near is
# reported on far's line (near's when far is left at its default).
#
# The parser is table-driven: a key is one scene_keys row (SCENE_KEY macro:
# name, kind, count of numbers, check, target, aux, extra, line word).
#
# Every file loaded (scene.ini included) is reported on the console as
#     load <path> <size> crc32=<8 lowercase hex digits>
# with the CRC-32 zlib.crc32 gives for the same bytes. The model is only
# looked up here (a missing model is error 6 before the texture is read):
# obj.S reads it from the card as it parses it, without keeping its text, and
# prints its line (scene_print_load) once it has read it all. scene.ini's
# text is given back to the heap once it is parsed.

    .option norelax
    .include "k210.inc"
    .include "errors.inc"
    .include "scene.inc"
    .include "text.inc"
    .include "frame.inc"

    .equ SCENE_VALUE_MAX,       256         # path bytes, NUL included
# Kinds of value (SCENE_KEY_KIND)
    .equ SCENE_KIND_FILE,       1           # a path, loaded by scene_load
    .equ SCENE_KIND_WORD,       2           # one word of a list -> u32
    .equ SCENE_KIND_NUMBERS,    3           # SCENE_KEY_COUNT numbers -> f32 each
    .equ SCENE_KIND_COLOUR,     4           # R G B or #RRGGBB -> RGB565 u32
# Checks (SCENE_KEY_CHECK) on a SCENE_KIND_NUMBERS value
    .equ SCENE_CHECK_NONE,      0
    .equ SCENE_CHECK_BROADCAST, 1           # one number stands for all of them
    .equ SCENE_CHECK_DIRECTION, 2           # 3 numbers, not all 0; normalised
    .equ SCENE_CHECK_FOV,       3           # 0 < x < SCENE_FOV_LIMIT
    .equ SCENE_CHECK_POSITIVE,  4           # x > 0
    .equ SCENE_CHECK_UNIT,      5           # 0 <= x <= 1
    .equ SCENE_CHECK_LEVELS,    6           # whole, LIGHT_LEVELS_MIN .. LIGHT_LEVELS_MAX
# When a SCENE_KIND_FILE file is loaded (its SCENE_KEY_CHECK)
    .equ SCENE_FILE_ALWAYS,     0
    .equ SCENE_FILE_TEXTURED,   1           # only in textured mode
    .equ SCENE_FILE_STREAM,     2           # always; looked up, not loaded: obj.S
                                            # reads it from the card itself
    .equ SCENE_FOV_LIMIT,       180         # degrees, excluded
    .equ SCENE_NUMBERS_MAX,     3           # most numbers a key takes
    .equ SCENE_DOUBLE_BYTES,    8
    .equ SCENE_DOUBLE_SHIFT,    3           # log2 of SCENE_DOUBLE_BYTES
# scene_parse's scan of a line (t5)
    .equ SCAN_KEY,              0           # before the first '='
    .equ SCAN_VALUE_START,      1           # after it, only blanks since
    .equ SCAN_VALUE,            2           # in the value
    .equ SCENE_F32_BYTES,       4
    .equ SCENE_HEX_DIGITS,      6           # "#RRGGBB" after the '#'
    .equ SCENE_HEX_MAX,         0xF
    .equ SCENE_BYTE_BITS,       8
    .equ SCENE_BYTE_MASK,       0xFF
# scene_keys rows
    .equ SCENE_KEY_NAME,        0           # key (NUL-terminated, lower case)
    .equ SCENE_KEY_KIND,        8           # byte: SCENE_KIND_*
    .equ SCENE_KEY_COUNT,       9           # byte: numbers (SCENE_KIND_NUMBERS)
    .equ SCENE_KEY_CHECK,       10          # byte: SCENE_CHECK_* / SCENE_FILE_*
    .equ SCENE_KEY_TARGET,      16          # where the value goes
    .equ SCENE_KEY_AUX,         24          # FILE: file record; WORD: word list
    .equ SCENE_KEY_EXTRA,       32          # FILE: default path; WORD: message
    .equ SCENE_KEY_LINE,        40          # u32 word: line that set it, 0 = none
    .equ SCENE_KEY_BYTES,       48
# word lists (SCENE_KIND_WORD): rows of word, value; a 0 word ends the list
    .equ SCENE_WORD_NAME,       0
    .equ SCENE_WORD_VALUE,      8
    .equ SCENE_WORD_BYTES,      16

    .equ UTF8_BOM_0,            0xEF
    .equ UTF8_BOM_1,            0xBB
    .equ UTF8_BOM_2,            0xBF
    .equ UTF8_BOM_BYTES,        3

# SCENE_KEY name, kind, count, check, target, aux, extra: one scene_keys row,
# its name string and its line word (scene_line_<name>).
.macro SCENE_KEY name, kind, count, check, target, aux=0, extra=0
    .dword  scene_key_name_\name
    .byte   \kind, \count, \check, 0
    .word   0
    .dword  \target, \aux, \extra, scene_line_\name
    .pushsection .rodata.scene_key_names, "a"
scene_key_name_\name:
    .asciz  "\name"
    .popsection
    .pushsection .bss
    .balign 4
scene_line_\name:
    .space  4
    .popsection
.endm

    .section .rodata
    .balign 8
# The keys scene.ini may set. Adding a key: one row here, its default in
# scene_default_values (or a default path), its field in scene.inc.
scene_keys:
    SCENE_KEY model, SCENE_KIND_FILE, 0, SCENE_FILE_STREAM, scene_model_path, scene_model, default_model_path
    SCENE_KEY texture, SCENE_KIND_FILE, 0, SCENE_FILE_TEXTURED, scene_texture_path, scene_texture, default_texture_path
    SCENE_KEY mode, SCENE_KIND_WORD, 0, 0, scene + SCENE_MODE, words_mode, msg_expect_mode
    SCENE_KEY cull, SCENE_KIND_WORD, 0, 0, scene + SCENE_CULL, words_cull, msg_expect_cull
    SCENE_KEY scale, SCENE_KIND_NUMBERS, 3, SCENE_CHECK_BROADCAST, scene + SCENE_SCALE
    SCENE_KEY axis, SCENE_KIND_NUMBERS, 3, SCENE_CHECK_DIRECTION, scene + SCENE_AXIS
    SCENE_KEY angle, SCENE_KIND_NUMBERS, 1, SCENE_CHECK_NONE, scene + SCENE_ANGLE
    SCENE_KEY step, SCENE_KIND_NUMBERS, 1, SCENE_CHECK_NONE, scene + SCENE_STEP
    SCENE_KEY translate, SCENE_KIND_NUMBERS, 3, SCENE_CHECK_NONE, scene + SCENE_TRANSLATE
    SCENE_KEY fov, SCENE_KIND_NUMBERS, 1, SCENE_CHECK_FOV, scene + SCENE_FOV
    SCENE_KEY near, SCENE_KIND_NUMBERS, 1, SCENE_CHECK_POSITIVE, scene + SCENE_NEAR
    SCENE_KEY far, SCENE_KIND_NUMBERS, 1, SCENE_CHECK_POSITIVE, scene + SCENE_FAR
    SCENE_KEY light, SCENE_KIND_NUMBERS, 3, SCENE_CHECK_DIRECTION, scene + SCENE_LIGHT
    SCENE_KEY ambient, SCENE_KIND_NUMBERS, 1, SCENE_CHECK_UNIT, scene + SCENE_AMBIENT
    SCENE_KEY background, SCENE_KIND_COLOUR, 0, 0, scene + SCENE_BACKGROUND
    SCENE_KEY interpolation, SCENE_KIND_WORD, 0, 0, scene + SCENE_INTERPOLATION, words_interpolation, msg_expect_interpolation
    SCENE_KEY shading, SCENE_KIND_WORD, 0, 0, scene + SCENE_SHADING, words_shading, msg_expect_shading
    SCENE_KEY light_levels, SCENE_KIND_NUMBERS, 1, SCENE_CHECK_LEVELS, scene + SCENE_LIGHT_LEVELS
    SCENE_KEY angles, SCENE_KIND_WORD, 0, 0, scene + SCENE_ANGLES, words_angles, msg_expect_angles
    SCENE_KEY depth, SCENE_KIND_WORD, 0, 0, scene + SCENE_DEPTH, words_depth, msg_expect_depth
    SCENE_KEY snap, SCENE_KIND_WORD, 0, 0, scene + SCENE_SNAP, words_snap, msg_expect_snap
    SCENE_KEY filter, SCENE_KIND_WORD, 0, 0, scene + SCENE_FILTER, words_filter, msg_expect_filter
    SCENE_KEY harts, SCENE_KIND_WORD, 0, 0, scene + SCENE_HARTS, words_harts, msg_expect_harts
    SCENE_KEY antialias, SCENE_KIND_WORD, 0, 0, scene + SCENE_ANTIALIAS, words_antialias, msg_expect_antialias
scene_keys_end:

    .balign 8
words_mode:
    .dword  word_textured, MODE_TEXTURED
    .dword  word_flat, MODE_FLAT
    .dword  word_wireframe, MODE_WIREFRAME
    .dword  0
words_cull:
    .dword  word_on, CULL_ON
    .dword  word_off, CULL_OFF
    .dword  word_yes, CULL_ON
    .dword  word_no, CULL_OFF
    .dword  word_true, CULL_ON
    .dword  word_false, CULL_OFF
    .dword  word_1, CULL_ON
    .dword  word_0, CULL_OFF
    .dword  0
words_interpolation:
    .dword  word_perspective, INTERP_PERSPECTIVE
    .dword  word_affine, INTERP_AFFINE
    .dword  0
words_shading:
    .dword  word_flat, SHADING_FLAT
    .dword  word_gouraud, SHADING_GOURAUD
    .dword  word_phong, SHADING_PHONG
    .dword  0
words_angles:
    .dword  word_polynomial, ANGLES_POLYNOMIAL
    .dword  word_table, ANGLES_TABLE
    .dword  0
words_depth:
    .dword  word_float32, DEPTH_FLOAT32
    .dword  word_int16, DEPTH_INT16
    .dword  0
words_snap:
    .dword  word_subpixel, SNAP_SUBPIXEL
    .dword  word_pixel, SNAP_PIXEL
    .dword  0
words_filter:
    .dword  word_nearest, FILTER_NEAREST
    .dword  word_bilinear, FILTER_BILINEAR
    .dword  word_mipmap, FILTER_MIPMAP
    .dword  word_anisotropic, FILTER_ANISOTROPIC
    .dword  0
words_harts:
    .dword  word_auto, HARTS_AUTO
    .dword  word_1, HARTS_ONE
    .dword  word_2, HARTS_TWO
    .dword  0
words_antialias:
    .dword  word_off, ANTIALIAS_OFF
    .dword  word_edge, ANTIALIAS_EDGE
    .dword  word_supersample, ANTIALIAS_SUPERSAMPLE
    .dword  0

    .balign 4
# scene_default_values: the scene structure's settings, SCENE_MODE up to
# MESH_VCOUNT, before scene.ini (the mesh and texture fields start at 0).
scene_default_values:
    .word   MODE_TEXTURED               # SCENE_MODE
    .word   CULL_ON                     # SCENE_CULL
    .float  1.0, 1.0, 1.0               # SCENE_SCALE
    .float  0.0, 1.0, 0.0               # SCENE_AXIS
    .float  0.0                         # SCENE_ANGLE
    .float  4.0                         # SCENE_STEP
    .float  0.0, 0.0, -3.0              # SCENE_TRANSLATE
    .float  60.0                        # SCENE_FOV
    .float  0.1                         # SCENE_NEAR
    .float  100.0                       # SCENE_FAR
    .float  0.0, 0.0, 1.0               # SCENE_LIGHT
    .float  0.2                         # SCENE_AMBIENT
    .word   0x10A2                      # SCENE_BACKGROUND: RGB 16, 20, 16
    .word   INTERP_PERSPECTIVE          # SCENE_INTERPOLATION
    .word   SHADING_FLAT                # SCENE_SHADING
    .float  65.0                        # SCENE_LIGHT_LEVELS (LIGHT_LEVELS_NARROW)
    .word   ANGLES_POLYNOMIAL           # SCENE_ANGLES
    .word   DEPTH_INT16                 # SCENE_DEPTH
    .word   SNAP_SUBPIXEL               # SCENE_SNAP
scene_default_values_end:
    .if (scene_default_values_end - scene_default_values) != MESH_VCOUNT
    .error "scene_default_values must cover SCENE_MODE .. SCENE_SNAP"
    .endif

default_model_path:     .asciz "model.obj"
default_texture_path:   .asciz "texture.ppm"
word_textured:      .asciz "textured"
word_flat:          .asciz "flat"
word_wireframe:     .asciz "wireframe"
word_on:            .asciz "on"
word_off:           .asciz "off"
word_yes:           .asciz "yes"
word_no:            .asciz "no"
word_true:          .asciz "true"
word_false:         .asciz "false"
word_1:             .asciz "1"
word_0:             .asciz "0"
word_perspective:   .asciz "perspective"
word_affine:        .asciz "affine"
word_gouraud:       .asciz "gouraud"
word_phong:         .asciz "phong"
word_polynomial:    .asciz "polynomial"
word_table:         .asciz "table"
word_float32:       .asciz "float32"
word_int16:         .asciz "int16"
word_subpixel:      .asciz "subpixel"
word_pixel:         .asciz "pixel"
word_nearest:       .asciz "nearest"
word_bilinear:      .asciz "bilinear"
word_mipmap:        .asciz "mipmap"
word_anisotropic:   .asciz "anisotropic"
word_auto:          .asciz "auto"
word_2:             .asciz "2"
word_edge:          .asciz "edge"
word_supersample:   .asciz "supersample"
path_scene_ini:     .asciz "scene.ini"
msg_load:           .asciz "load "
msg_crc32:          .asciz " crc32="
msg_no_scene_ini:   .asciz "scene: no scene.ini, defaults\n"
msg_bad_scene:      .asciz "bad scene.ini line "
msg_colon:          .asciz ": "
msg_unknown_key:    .asciz "unknown key"
msg_duplicate_key:  .asciz "duplicate key"
msg_no_equals:      .asciz "malformed line (no '=')"
msg_empty_key:      .asciz "malformed line (no key)"
msg_empty_value:    .asciz "malformed line (no value)"
msg_long_value:     .asciz "malformed line (value too long)"
msg_control:        .asciz "malformed line (control character)"
msg_expect_mode:    .asciz "bad value (expected textured, flat or wireframe)"
msg_expect_cull:    .asciz "bad value (expected on, off, yes, no, true, false, 1 or 0)"
msg_not_number:     .asciz "bad value (not a number)"
msg_expect_1:       .asciz "bad value (expected 1 number)"
msg_expect_3:       .asciz "bad value (expected 3 numbers)"
msg_expect_1_or_3:  .asciz "bad value (expected 1 or 3 numbers)"
msg_out_of_range:   .asciz "bad value (number out of range)"
msg_zero_vector:    .asciz "bad value (zero vector)"
msg_fov_range:      .asciz "bad value (fov must be between 0 and 180 degrees)"
msg_positive:       .asciz "bad value (must be greater than 0)"
msg_unit_range:     .asciz "bad value (must be between 0 and 1)"
msg_colour:         .asciz "bad value (expected R G B with 0..255 each, or #RRGGBB)"
msg_far_near:       .asciz "bad value (far must be greater than near)"
msg_expect_interpolation: .asciz "bad value (expected perspective or affine)"
msg_expect_shading: .asciz "bad value (expected flat, gouraud or phong)"
msg_expect_angles:  .asciz "bad value (expected polynomial or table)"
msg_expect_depth:   .asciz "bad value (expected int16 or float32)"
msg_expect_snap:    .asciz "bad value (expected subpixel or pixel)"
msg_expect_filter:  .asciz "bad value (expected nearest, bilinear, mipmap or anisotropic)"
msg_expect_harts:   .asciz "bad value (expected auto, 1 or 2)"
msg_expect_antialias: .asciz "bad value (expected off, edge or supersample)"
msg_levels:         .asciz "bad value (must be a whole number from 2 to 65537)"

    .text
    .globl scene_load
# scene_load
#   What: fills `scene` with the defaults, reads and parses scene.ini from
#         the card's root when there is one (then gives its text back to the
#         heap), checks far > near, then finds the files the scene needs: the
#         model is looked up (obj.S reads it), the texture loaded only in
#         textured mode (flat and wireframe draw none); each is recorded in
#         its file record (scene_model, scene_texture; FILE_RECORD_*,
#         scene.inc; 0, 0 for a file not loaded). Once per boot. Needs
#         fat32_mount and heap_init.
#   Arguments: none. Results: none (errors are fatal).
#   Clobbers: only ABI temporaries.
scene_load:
    FRAME_SAVE 32, ra, s0, s1
    call    scene_defaults
    la      a0, path_scene_ini
    call    fat32_lookup
    bnez    a2, 1f
    la      a0, msg_no_scene_ini
    call    console_line
    j       2f
1:  la      a0, path_scene_ini
    call    scene_load_file
    mv      s0, a0
    call    scene_parse
    mv      a0, s0                      # its values are stored: the text goes
    call    heap_release
2:  call    scene_check_planes

    la      s0, scene_keys
    la      s1, scene_keys_end
3:  lbu     t0, SCENE_KEY_KIND(s0)
    li      t1, SCENE_KIND_FILE
    bne     t0, t1, 4f
    lbu     t0, SCENE_KEY_CHECK(s0)
    li      t1, SCENE_FILE_STREAM
    beq     t0, t1, 32f
    li      t1, SCENE_FILE_TEXTURED
    bne     t0, t1, 31f
    la      t2, scene
    lwu     t2, SCENE_MODE(t2)
    li      t1, MODE_TEXTURED
    bne     t2, t1, 4f                  # flat, wireframe: no texture drawn, none read
31: ld      a0, SCENE_KEY_TARGET(s0)
    call    scene_load_file
    j       33f
32: ld      a0, SCENE_KEY_TARGET(s0)
    call    fat32_open                  # a0 = first cluster, a1 = size
    li      a0, 0                       # not in memory
33: ld      t0, SCENE_KEY_AUX(s0)
    sd      a0, FILE_RECORD_ADDRESS(t0)
    sd      a1, FILE_RECORD_SIZE(t0)
    ld      t1, SCENE_KEY_TARGET(s0)
    sd      t1, FILE_RECORD_PATH(t0)
4:  addi    s0, s0, SCENE_KEY_BYTES
    bltu    s0, s1, 3b
    FRAME_RESTORE 32, ra, s0, s1
    ret

# scene_defaults (file-local)
#   What: `scene` = scene_default_values then zeros up to SCENE_SIZE; every
#         path buffer = its key's default path.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
scene_defaults:
    la      t0, scene_default_values
    la      t1, scene
    addi    t2, t1, MESH_VCOUNT
1:  lw      t3, 0(t0)
    sw      t3, 0(t1)
    addi    t0, t0, SCENE_F32_BYTES
    addi    t1, t1, SCENE_F32_BYTES
    bltu    t1, t2, 1b
    la      t2, scene + SCENE_SIZE
2:  sw      zero, 0(t1)
    addi    t1, t1, SCENE_F32_BYTES
    bltu    t1, t2, 2b

    la      t0, scene_keys
    la      t1, scene_keys_end
3:  lbu     t2, SCENE_KEY_KIND(t0)
    li      t3, SCENE_KIND_FILE
    bne     t2, t3, 5f
    ld      t2, SCENE_KEY_EXTRA(t0)     # default path
    ld      t3, SCENE_KEY_TARGET(t0)    # path buffer
4:  lbu     t4, 0(t2)
    sb      t4, 0(t3)
    addi    t2, t2, 1
    addi    t3, t3, 1
    bnez    t4, 4b
5:  addi    t0, t0, SCENE_KEY_BYTES
    bltu    t0, t1, 3b
    ret

# scene_check_planes (file-local)
#   What: error 9 unless SCENE_FAR > SCENE_NEAR, on far's line (near's when
#         scene.ini did not set far).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
scene_check_planes:
    la      t0, scene
    flw     ft0, SCENE_NEAR(t0)
    flw     ft1, SCENE_FAR(t0)
    flt.s   t1, ft0, ft1
    beqz    t1, 1f
    ret
1:  la      t0, scene_line_far
    lwu     a0, 0(t0)
    bnez    a0, 2f
    la      t0, scene_line_near
    lwu     a0, 0(t0)
2:  la      a1, msg_far_near
    j       scene_error

    .globl scene_load_file
# scene_load_file
#   What: loads a file into the heap (fat32_load, which also computes its
#         CRC-32) and prints "load <path> <size> crc32=<crc>" for it.
#   Arguments: a0 = path (NUL-terminated).
#   Results: a0 = address of the bytes, a1 = size.
#   Clobbers: only ABI temporaries.
scene_load_file:
    FRAME_SAVE 32, ra, s0, s1, s2
    mv      s0, a0                      # s0 = path
    call    fat32_load
    mv      s1, a0                      # s1 = address
    mv      s2, a1                      # s2 = size
    mv      a1, s2
    mv      a0, s0
    call    scene_print_load
    mv      a0, s1
    mv      a1, s2
    FRAME_RESTORE 32, ra, s0, s1, s2
    ret

    .globl scene_print_load
# scene_print_load
#   What: prints "load <path> <size> crc32=<crc>" (the CRC-32 as 8
#         lowercase hex digits), the line of a file read from the card.
#   Arguments: a0 = path (NUL-terminated), a1 = size, a2 = CRC-32.
#   Results: none.
#   Clobbers: only ABI temporaries.
scene_print_load:
    FRAME_SAVE 32, ra, s0, s1, s2
    mv      s0, a0                      # s0 = path
    mv      s1, a1                      # s1 = size
    mv      s2, a2                      # s2 = CRC-32
    call    console_lock
    la      a0, msg_load
    call    console_puts
    mv      a0, s0
    call    console_puts
    li      a0, CHAR_SPACE
    call    console_putc
    mv      a0, s1
    call    console_put_dec
    la      a0, msg_crc32
    call    console_puts
    mv      a0, s2
    call    console_put_hex32
    li      a0, CHAR_LF
    call    console_putc
    call    console_unlock
    FRAME_RESTORE 32, ra, s0, s1, s2
    ret

# scene_parse (file-local)
#   What: parses scene.ini's text (see the file comment), storing each
#         value (scene_set_value).
#   Arguments: a0 = text, a1 = length in bytes.
#   Results: none (errors are fatal).
#   Clobbers: only ABI temporaries.
scene_parse:
    FRAME_SAVE 80, ra, s0, s1, s2, s3, s4, s5, s6, s7
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
    # t5 = where the scan is (SCAN_*): a '#' at SCAN_VALUE_START starts
    # the value (#RRGGBB), elsewhere a comment.
4:  mv      t2, s0
    li      t5, SCAN_KEY
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
    li      t1, CHAR_SPACE
    beq     t0, t1, 51f
    li      t1, CHAR_EQUALS
    bne     t0, t1, 52f
    bnez    t5, 52f                     # past SCAN_KEY (0)
    li      t5, SCAN_VALUE_START    # the first '='
    j       51f
52: beqz    t5, 51f
    li      t5, SCAN_VALUE          # a value character
51: addi    t2, t2, 1
    j       5b
6:  li      t1, SCAN_VALUE_START
    bne     t5, t1, 61f
    li      t5, SCAN_VALUE          # '#' opening the value: kept
    j       51b
61: mv      s5, t2
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
    ld      t0, SCENE_KEY_LINE(s7)
    lwu     t1, 0(t0)
    bnez    t1, 85f                     # set before: duplicate
    sw      s2, 0(t0)
    # value = (s6, s5) trimmed
    addi    a0, s6, 1
    mv      a1, s5
    call    trim_blanks
    beq     a0, a1, 83f
    mv      a2, a1
    mv      a1, a0
    mv      a0, s7
    mv      a3, s2
    call    scene_set_value
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
89: mv      a0, s2
    j       scene_error

90: FRAME_RESTORE 80, ra, s0, s1, s2, s3, s4, s5, s6, s7
    ret

# scene_set_value (file-local)
#   What: checks one key's value by its row's kind and stores it (path
#         buffer, u32 word, f32 numbers or RGB565 colour; see the file
#         comment).
#   Arguments: a0 = row, a1 = value start, a2 = value end (non-empty,
#         trimmed), a3 = line number (for errors).
#   Results: none (a bad value is error 9).
#   Clobbers: only ABI temporaries.
scene_set_value:
    FRAME_SAVE 96, ra, s0, s1, s2, s3, s4, s5
    # 0(sp): SCENE_NUMBERS_MAX doubles
    mv      s0, a0                      # s0 = row
    mv      s1, a1                      # s1 = value start
    mv      s2, a2                      # s2 = value end
    mv      s3, a3                      # s3 = line
    lbu     t0, SCENE_KEY_KIND(s0)
    li      t1, SCENE_KIND_FILE
    beq     t0, t1, 10f
    li      t1, SCENE_KIND_WORD
    beq     t0, t1, 20f
    li      t1, SCENE_KIND_NUMBERS
    beq     t0, t1, 30f
    j       50f

    # A path: copied into its buffer.
10: sub     t0, s2, s1
    li      t1, SCENE_VALUE_MAX
    bgeu    t0, t1, 86f
    ld      t2, SCENE_KEY_TARGET(s0)
11: lbu     t3, 0(s1)
    sb      t3, 0(t2)
    addi    s1, s1, 1
    addi    t2, t2, 1
    bltu    s1, s2, 11b
    sb      zero, 0(t2)
    j       90f

    # A word of the row's list.
20: ld      s4, SCENE_KEY_AUX(s0)       # s4 = word row
21: ld      a0, SCENE_WORD_NAME(s4)
    beqz    a0, 29f
    mv      a1, s1
    mv      a2, s2
    call    scene_name_equals
    bnez    a0, 22f
    addi    s4, s4, SCENE_WORD_BYTES
    j       21b
22: ld      t0, SCENE_WORD_VALUE(s4)
    ld      t1, SCENE_KEY_TARGET(s0)
    sw      t0, 0(t1)
    j       90f
29: ld      a1, SCENE_KEY_EXTRA(s0)
    j       89f

    # Numbers.
30: mv      a0, s1
    mv      a1, s2
    mv      a2, sp
    lbu     a3, SCENE_KEY_COUNT(s0)
    call    parse_numbers
    bnez    a1, 81f
    lbu     s4, SCENE_KEY_COUNT(s0)     # s4 = numbers wanted
    lbu     s5, SCENE_KEY_CHECK(s0)     # s5 = check
    beq     a0, s4, 32f
    li      t0, SCENE_CHECK_BROADCAST
    bne     s5, t0, 82f
    li      t0, 1
    bne     a0, t0, 82f
    fld     ft0, 0(sp)                  # one number: copied to every slot
    mv      t1, sp
    slli    t2, s4, SCENE_DOUBLE_SHIFT
    add     t2, t2, sp
31: fsd     ft0, 0(t1)
    addi    t1, t1, SCENE_DOUBLE_BYTES
    bltu    t1, t2, 31b
    # Every number must be finite in single precision.
32: mv      t1, sp
    slli    t2, s4, SCENE_DOUBLE_SHIFT
    add     t2, t2, sp
33: fld     ft0, 0(t1)
    fcvt.s.d ft1, ft0
    fclass.s t3, ft1
    andi    t3, t3, FCLASS_NOT_FINITE
    bnez    t3, 83f
    addi    t1, t1, SCENE_DOUBLE_BYTES
    bltu    t1, t2, 33b
    # The row's check (single-number checks on the value as stored).
    fld     ft0, 0(sp)
    fcvt.s.d ft0, ft0                   # ft0 = first number, single
    fmv.w.x ft1, zero                   # ft1 = 0
    li      t0, SCENE_CHECK_DIRECTION
    beq     s5, t0, 40f
    li      t0, SCENE_CHECK_FOV
    beq     s5, t0, 41f
    li      t0, SCENE_CHECK_POSITIVE
    beq     s5, t0, 42f
    li      t0, SCENE_CHECK_UNIT
    beq     s5, t0, 43f
    li      t0, SCENE_CHECK_LEVELS
    beq     s5, t0, 44f
    j       48f
40: fld     ft2, 0(sp)                  # direction: normalised in double
    fld     ft3, SCENE_DOUBLE_BYTES(sp)
    fld     ft4, 2 * SCENE_DOUBLE_BYTES(sp)
    fmul.d  ft5, ft2, ft2
    fmadd.d ft5, ft3, ft3, ft5
    fmadd.d ft5, ft4, ft4, ft5
    fmv.d.x ft6, zero
    feq.d   t0, ft5, ft6
    bnez    t0, 84f
    fsqrt.d ft5, ft5
    fdiv.d  ft2, ft2, ft5
    fdiv.d  ft3, ft3, ft5
    fdiv.d  ft4, ft4, ft5
    fsd     ft2, 0(sp)
    fsd     ft3, SCENE_DOUBLE_BYTES(sp)
    fsd     ft4, 2 * SCENE_DOUBLE_BYTES(sp)
    j       48f
41: fle.s   t0, ft0, ft1                # fov: 0 < x < 180
    bnez    t0, 87f
    li      t0, SCENE_FOV_LIMIT
    fcvt.s.w ft2, t0
    fle.s   t0, ft2, ft0
    bnez    t0, 87f
    j       48f
42: fle.s   t0, ft0, ft1                # x > 0
    bnez    t0, 88f
    j       48f
43: flt.s   t0, ft0, ft1                # 0 <= x <= 1
    bnez    t0, 79f
    li      t0, 1
    fcvt.s.w ft2, t0
    flt.s   t0, ft2, ft0
    bnez    t0, 79f
    j       48f
44: fcvt.w.s t0, ft0, rtz              # light levels: whole, in range
    fcvt.s.w ft2, t0
    feq.s   t1, ft2, ft0
    beqz    t1, 78f
    li      t1, LIGHT_LEVELS_MIN
    blt     t0, t1, 78f
    li      t1, LIGHT_LEVELS_MAX
    bgt     t0, t1, 78f
    # Store them, single precision.
48: ld      t0, SCENE_KEY_TARGET(s0)
    mv      t1, sp
    slli    t2, s4, SCENE_DOUBLE_SHIFT
    add     t2, t2, sp
49: fld     ft0, 0(t1)
    fcvt.s.d ft0, ft0
    fsw     ft0, 0(t0)
    addi    t0, t0, SCENE_F32_BYTES
    addi    t1, t1, SCENE_DOUBLE_BYTES
    bltu    t1, t2, 49b
    j       90f

    # A colour: #RRGGBB, or R G B.
50: lbu     t0, 0(s1)
    li      t1, CHAR_COMMENT
    bne     t0, t1, 55f
    sub     t0, s2, s1
    li      t1, SCENE_HEX_DIGITS + 1
    bne     t0, t1, 85f
    addi    t0, s1, 1
    li      t2, 0                       # t2 = 0xRRGGBB
51: bgeu    t0, s2, 53f
    lbu     t3, 0(t0)
    addi    t4, t3, -CHAR_DIGIT_0
    li      t5, DECIMAL_BASE
    bltu    t4, t5, 52f
    ori     t3, t3, ASCII_CASE_BIT
    addi    t4, t3, -CHAR_LOWER_A
    li      t5, SCENE_HEX_MAX - HEX_LETTER_VALUE + 1
    bgeu    t4, t5, 85f
    addi    t4, t4, HEX_LETTER_VALUE
52: slli    t2, t2, HEX_DIGIT_BITS
    or      t2, t2, t4
    addi    t0, t0, 1
    j       51b
53: srli    a0, t2, 2 * SCENE_BYTE_BITS
    srli    a1, t2, SCENE_BYTE_BITS
    andi    a1, a1, SCENE_BYTE_MASK
    andi    a2, t2, SCENE_BYTE_MASK
    j       58f
55: mv      a0, s1
    mv      a1, s2
    mv      a2, sp
    li      a3, SCENE_NUMBERS_MAX
    call    parse_numbers
    bnez    a1, 85f
    li      t0, SCENE_NUMBERS_MAX
    bne     a0, t0, 85f
    mv      t1, sp
    addi    t2, sp, SCENE_NUMBERS_MAX * SCENE_DOUBLE_BYTES
    li      t5, RGB888_MAX
56: fld     ft0, 0(t1)                  # each an integer 0 .. 255, kept in place
    fcvt.l.d t3, ft0, rtz
    fcvt.d.l ft1, t3
    feq.d   t4, ft0, ft1
    beqz    t4, 85f
    bltz    t3, 85f
    bgtu    t3, t5, 85f
    sd      t3, 0(t1)
    addi    t1, t1, SCENE_DOUBLE_BYTES
    bltu    t1, t2, 56b
    ld      a0, 0(sp)
    ld      a1, SCENE_DOUBLE_BYTES(sp)
    ld      a2, 2 * SCENE_DOUBLE_BYTES(sp)
58: li      a3, RGB888_MAX
    call    ppm_rgb565
    ld      t0, SCENE_KEY_TARGET(s0)
    sw      a0, 0(t0)
    j       90f

78: la      a1, msg_levels
    j       89f
79: la      a1, msg_unit_range
    j       89f
81: la      a1, msg_not_number
    j       89f
82: la      a1, msg_expect_1_or_3
    li      t0, SCENE_CHECK_BROADCAST
    beq     s5, t0, 89f
    la      a1, msg_expect_1
    li      t0, 1
    beq     s4, t0, 89f
    la      a1, msg_expect_3
    j       89f
83: la      a1, msg_out_of_range
    j       89f
84: la      a1, msg_zero_vector
    j       89f
85: la      a1, msg_colour
    j       89f
86: la      a1, msg_long_value
    j       89f
87: la      a1, msg_fov_range
    j       89f
88: la      a1, msg_positive
89: mv      a0, s3
    j       scene_error

90: FRAME_RESTORE 96, ra, s0, s1, s2, s3, s4, s5
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
#   What: the scene_keys row whose name equals [a0, a1) (scene_name_equals).
#   Arguments: a0 = key start, a1 = key end (non-empty).
#   Results: a0 = row address, or 0 when no key has that name.
#   Clobbers: only ABI temporaries.
scene_find_key:
    FRAME_SAVE 32, ra, s0, s1, s2
    mv      s1, a0
    mv      s2, a1
    la      s0, scene_keys
1:  ld      a0, SCENE_KEY_NAME(s0)
    mv      a1, s1
    mv      a2, s2
    call    scene_name_equals
    bnez    a0, 2f
    addi    s0, s0, SCENE_KEY_BYTES
    la      t0, scene_keys_end
    bltu    s0, t0, 1b
    li      a0, 0
    j       3f
2:  mv      a0, s0
3:  FRAME_RESTORE 32, ra, s0, s1, s2
    ret

# scene_name_equals (file-local)
#   What: whether [a1, a2) spells the name a0, ASCII letters compared
#         case-insensitively.
#   Arguments: a0 = name (NUL-terminated, lower case), a1 = text start,
#         a2 = text end.
#   Results: a0 = 1 equal, 0 not.
#   Clobbers: only ABI temporaries.
scene_name_equals:
1:  lbu     t2, 0(a0)
    beqz    t2, 4f                      # name ended
    beq     a1, a2, 5f                  # text ended first
    lbu     t3, 0(a1)
    addi    t4, t3, -ASCII_UPPER_A      # an upper-case letter goes to lower
    sltiu   t4, t4, ASCII_UPPER_Z - ASCII_UPPER_A + 1   # case (the name's)
    slli    t4, t4, ASCII_CASE_SHIFT
    or      t3, t3, t4
    bne     t2, t3, 5f
    addi    a0, a0, 1
    addi    a1, a1, 1
    j       1b
4:  bne     a1, a2, 5f                  # both ended: equal
    li      a0, 1
    ret
5:  li      a0, 0
    ret

# ---------------------------------------------------------------------------
    .bss
    .balign 1 << SCENE_ALIGN_SHIFT
    .globl scene
# scene: what to show and how (scene.inc): settings from scene.ini, the mesh
# (obj.S) and the texture (ppm.S).
scene:
    .space  SCENE_SIZE
    .balign 8
    .globl scene_model
    .globl scene_texture
# File records of what the scene loaded: address, size (both 0 when not
# loaded).
scene_model:
    .space  FILE_RECORD_BYTES
scene_texture:
    .space  FILE_RECORD_BYTES
# Paths (NUL-terminated): the default, or the value from scene.ini.
scene_model_path:
    .space  SCENE_VALUE_MAX
scene_texture_path:
    .space  SCENE_VALUE_MAX
