# obj.S: the model, a Wavefront .obj, parsed into `scene`'s mesh fields
# (MESH_*; scene.inc).
#
# Lines end in LF or CRLF; '#' starts a comment anywhere (to the end of the
# line); blank lines are fine; tokens are separated by spaces and tabs.
# Statements (keywords are case-sensitive, as in the OBJ spec):
#   v x y z [w] [r g b]     a vertex: 3, 4, 6 or 7 numbers; x y z kept (w and
#                           vertex colours accepted, ignored)
#   vt u [v [w]]            a texture coordinate: 1 to 3 numbers; u v kept
#                           (v = 0 when absent, w ignored)
#   vn x y z                a normal: 3 numbers; stored only when they are
#                           drawn (shading = gouraud in a lit mode: textured,
#                           flat): otherwise vn lines are still parsed and
#                           checked as numbers, counted for index checks and
#                           on the console, but not stored (MESH_NCOUNT 0,
#                           MESH_N 0, every face's n index MESH_NO_INDEX)
#   f c1 c2 c3 [c4 ...]     a face of 3 or more corners v, v/vt, v//vn or
#                           v/vt/vn; a polygon (assumed convex) is fanned
#                           into triangles (c1, ci, ci+1); corners of one
#                           face may mix forms: a missing vt / vn index is
#                           stored as MESH_NO_INDEX
#   o g s mtllib usemtl     accepted and ignored (the whole line)
# Numbers are parse.S's (sign, fraction, exponent), rounded to single
# precision, which must be finite. Indices count from 1; a negative index -k
# is the k-th latest element defined before its line. A positive index may
# refer to an element defined further down (checked against the file's
# total); 0 is an error. Stored indices are 0-based. Line continuation with
# '\' is not supported.
#
# Two passes over the text: the first checks every line and counts vertices,
# texture coordinates, normals and triangles (after fanning); then the
# arrays are taken from the heap, sized from those counts; the second pass
# fills them.
#
# The text is not kept: each pass reads the file from the card through a
# window of OBJ_WINDOW_BYTES in the heap (fat32_stream_read), taken for the
# pass and given back after it, so that the model's memory is its arrays
# alone. Tokens (a keyword, a number, a face corner) are parsed whole: when
# one runs to the end of what the window holds, its bytes move to the
# window's start and the next sectors are read after them; a token longer
# than the window grows it by OBJ_WINDOW_BYTES (the window is the heap's
# latest block), so no token or line is too long but for the heap. The first
# pass also computes the file's CRC-32 and prints its "load <path> <size>
# crc32=<crc>" line (scene.S scene_print_load) once it has read it all. A
# model record with text in memory (FILE_RECORD_ADDRESS, scene.inc) is
# parsed through the same window, copied into it as if from the card.
#
# Errors: 10, "error 10 bad model line N: <what>" (an unknown
# statement, a malformed number, a wrong count of numbers, a malformed face
# corner, a face with fewer than 3 vertices, an index 0 or out of range, a
# number too large for single precision; a positive index past the file's
# total is found in the second pass, so after any other error of the file),
# "error 10 bad model: no faces" for a model without a face; 12 when the
# arrays do not fit in the heap ("model too large for memory: <n> bytes
# needed, <m> bytes free"), or the window ("model too large for memory
# (model text window: <n> bytes needed, <m> bytes free)", heap.S
# heap_alloc_or_fail; "(model text window for a longer word: ...)" when a
# word outgrows the heap). Errors of the card
# and its chains (4, 8) as in fat32_read.S and fat32_chain.S.

    .option norelax
    .include "k210.inc"
    .include "errors.inc"
    .include "fat32.inc"
    .include "heap.inc"
    .include "scene.inc"
    .include "text.inc"
    .include "frame.inc"

# obj_state (.bss): the pass in progress
    .equ OBJ_STORE,             0           # 0 first pass (count), 1 second (store)
    .equ OBJ_KEEP_NORMALS,      8           # 1 store normals (Gouraud in a lit mode)
    .equ OBJ_LINE,              16          # line being parsed, from 1
    .equ OBJ_COUNTS,            24          # elements so far: v, vt, vn (8 bytes each)
    .equ OBJ_NF,                48          # triangles so far
    .equ OBJ_TOTALS,            56          # first pass's counts of v, vt, vn
                                            # (all ones during the first pass)
    .equ OBJ_FIRST,             80          # face corners: first,
    .equ OBJ_PREV,              92          # latest,
    .equ OBJ_CORNER,            104         # this one (OBJ_CORNER_BYTES each)
    .equ OBJ_STATE_BYTES,       120
    .equ OBJ_COUNT_SHIFT,       3           # 8 bytes per count
# A corner while its face is parsed: three u32 indices (MESH_NO_INDEX for an
# absent one), packed into a MESH_CORNER_BYTES doubleword when stored.
    .equ OBJ_CORNER_V,          0
    .equ OBJ_CORNER_T,          4
    .equ OBJ_CORNER_N,          8
    .equ OBJ_CORNER_BYTES,      12
# index kinds (obj_index)
    .equ OBJ_KIND_V,            0
    .equ OBJ_KIND_T,            1
    .equ OBJ_KIND_N,            2
# obj_statements rows
    .equ OBJ_STMT_NAME,         0
    .equ OBJ_STMT_HANDLER,      8
    .equ OBJ_STMT_AUX,          16          # obj_stmt_vector's row
    .equ OBJ_STMT_BYTES,        24
# obj_vectors rows (v, vt, vn)
    .equ OBJ_VEC_COUNTS,        0           # bit n set: n numbers accepted
    .equ OBJ_VEC_STORED,        1           # numbers stored (f32 each)
    .equ OBJ_VEC_KIND,          2           # OBJ_KIND_*
    .equ OBJ_VEC_NORMALS,       3           # 1: stored only when OBJ_KEEP_NORMALS
    .equ OBJ_VEC_ARRAY,         4           # scene offset of its array pointer
    .equ OBJ_VEC_MESSAGE,       8           # wrong count message
    .equ OBJ_VEC_BYTES,         16
    .equ OBJ_NUMBERS_MAX,       7           # most numbers a vector takes
    .equ OBJ_DOUBLE_BYTES,      8
    .equ OBJ_DOUBLE_SHIFT,      3           # log2 of OBJ_DOUBLE_BYTES
    .equ OBJ_F32_SHIFT,         2           # log2 of OBJ_F32_BYTES
    .equ OBJ_POINTER_SHIFT,     3           # 8-byte table entries
    .equ OBJ_FACE_MIN_CORNERS,  3
    .equ OBJ_F32_BYTES,         4
    .equ OBJ_INDEX_LIMIT,       0x80000000  # indices saturate here (out of range)
    .equ OBJ_WINDOW_BYTES,      16384       # the window the text is read through
    .if (OBJ_WINDOW_BYTES % FAT_SECTOR_BYTES) || (OBJ_WINDOW_BYTES % HEAP_ALIGN)
    .error "the window holds whole sectors and grows in whole heap blocks"
    .endif
# obj_reader (.bss): the window the pass reads the text through
    .equ RD_BASE,               0           # window start (heap block)
    .equ RD_CAP,                8           # its bytes
    .equ RD_END,                16          # end of the text read into it
    .equ RD_CURSOR,             24          # next byte to parse
    .equ RD_LEFT,               32          # file bytes not yet read into it
    .equ RD_TEXT,               40          # text in memory: its next byte; 0: the card
    .equ RD_CRC_ON,             48          # 1: card reads extend the CRC (first pass)
    .equ RD_STREAM,             56          # fat32 stream record (STREAM_BYTES)
    .equ RD_BYTES,              RD_STREAM + STREAM_BYTES
    .equ OBJ_V_COUNTS,          (1 << 3) | (1 << 4) | (1 << 6) | (1 << 7)
    .equ OBJ_VT_COUNTS,         (1 << 1) | (1 << 2) | (1 << 3)
    .equ OBJ_VN_COUNTS,         (1 << 3)

    .section .rodata
    .balign 8
obj_statements:
    .dword  kw_v, obj_stmt_vector, obj_vector_v
    .dword  kw_vt, obj_stmt_vector, obj_vector_vt
    .dword  kw_vn, obj_stmt_vector, obj_vector_vn
    .dword  kw_f, obj_stmt_face, 0
    .dword  kw_o, obj_stmt_ignore, 0
    .dword  kw_g, obj_stmt_ignore, 0
    .dword  kw_s, obj_stmt_ignore, 0
    .dword  kw_mtllib, obj_stmt_ignore, 0
    .dword  kw_usemtl, obj_stmt_ignore, 0
obj_statements_end:

obj_vector_v:
    .byte   OBJ_V_COUNTS, 3, OBJ_KIND_V, 0
    .word   MESH_V
    .dword  msg_count_v
obj_vector_vt:
    .byte   OBJ_VT_COUNTS, 2, OBJ_KIND_T, 0
    .word   MESH_T
    .dword  msg_count_vt
obj_vector_vn:
    .byte   OBJ_VN_COUNTS, 3, OBJ_KIND_N, 1
    .word   MESH_N
    .dword  msg_count_vn

# Messages for an out-of-range index, by kind.
obj_range_messages:
    .dword  msg_range_v, msg_range_t, msg_range_n

kw_v:               .asciz "v"
kw_vt:              .asciz "vt"
kw_vn:              .asciz "vn"
kw_f:               .asciz "f"
kw_o:               .asciz "o"
kw_g:               .asciz "g"
kw_s:               .asciz "s"
kw_mtllib:          .asciz "mtllib"
kw_usemtl:          .asciz "usemtl"
msg_bad_model:      .asciz "bad model line "
msg_colon:          .asciz ": "
msg_unknown:        .asciz "unknown statement"
msg_number:         .asciz "malformed number"
msg_f32_range:      .asciz "number out of range"
msg_count_v:        .asciz "v takes 3, 4, 6 or 7 numbers"
msg_count_vt:       .asciz "vt takes 1, 2 or 3 numbers"
msg_count_vn:       .asciz "vn takes 3 numbers"
msg_corner:         .asciz "malformed face corner (expected v, v/vt, v//vn or v/vt/vn)"
msg_short_face:     .asciz "face with fewer than 3 vertices"
msg_index_0:        .asciz "index 0 (indices start at 1)"
msg_range_v:        .asciz "vertex index out of range"
msg_range_t:        .asciz "texture coordinate index out of range"
msg_range_n:        .asciz "normal index out of range"
msg_no_faces:       .asciz "bad model: no faces"
msg_window:         .asciz "model text window"
msg_window_grow:    .asciz "model text window for a longer word"
msg_too_large:      .asciz "model too large for memory: "
msg_too_large_need: .asciz " bytes needed, "
msg_too_large_free: .asciz " bytes free"
msg_model:          .asciz "model: "
msg_triangles:      .asciz " triangles, "
msg_vertices:       .asciz " vertices, "
msg_uv:             .asciz " uv, "
msg_normals:        .asciz " normals\n"
msg_normals_wireframe: .asciz " normals (not stored: wireframe)\n"
msg_normals_flat:   .asciz " normals (not stored: shading flat)\n"

    .text
    .globl obj_parse_model
# obj_parse_model
#   What: parses the model file scene.S found (scene_model) into the mesh
#         fields of `scene` (two passes over the file read from the card,
#         arrays from the heap; see the file comment), printing its "load"
#         line after the first and "model: <f> triangles, <v> vertices,
#         <t> uv, <n> normals" (the file's counts; "(not stored: ...)" after
#         normals it does not keep) after the second. Needs scene_load
#         (SCENE_MODE and SCENE_SHADING decide the normals).
#   Arguments: none. Results: none (errors are fatal).
#   Clobbers: only ABI temporaries.
obj_parse_model:
    FRAME_SAVE 64, ra, s0, s1, s2, s3, s4, s5
    la      s2, obj_state               # s2 = state
    la      s3, scene                   # s3 = scene
    # Normals only where they are drawn: Gouraud or Phong shading in a lit
    # mode.
    lwu     t0, SCENE_MODE(s3)
    addi    t0, t0, -MODE_WIREFRAME
    snez    t0, t0
    lwu     t1, SCENE_SHADING(s3)
    addi    t1, t1, -SHADING_FLAT
    snez    t1, t1
    and     t0, t0, t1
    sd      t0, OBJ_KEEP_NORMALS(s2)

    # First pass: check and count.
    sd      zero, OBJ_STORE(s2)
    li      t0, -1
    sd      t0, OBJ_TOTALS + (OBJ_KIND_V << OBJ_COUNT_SHIFT)(s2)
    sd      t0, OBJ_TOTALS + (OBJ_KIND_T << OBJ_COUNT_SHIFT)(s2)
    sd      t0, OBJ_TOTALS + (OBJ_KIND_N << OBJ_COUNT_SHIFT)(s2)
    li      a0, 1
    call    obj_reader_open
    call    obj_pass
    call    obj_reader_close
    la      t0, scene_model             # read from the card: its load line
    ld      t1, FILE_RECORD_ADDRESS(t0)
    bnez    t1, 1f
    ld      a0, FILE_RECORD_PATH(t0)
    ld      a1, FILE_RECORD_SIZE(t0)
    la      t0, obj_reader
    ld      a2, RD_STREAM + STREAM_CRC(t0)
    call    scene_print_load
1:  ld      t0, OBJ_NF(s2)
    beqz    t0, 80f
    ld      t0, OBJ_COUNTS + (OBJ_KIND_V << OBJ_COUNT_SHIFT)(s2)
    sd      t0, OBJ_TOTALS + (OBJ_KIND_V << OBJ_COUNT_SHIFT)(s2)
    sw      t0, MESH_VCOUNT(s3)
    ld      t0, OBJ_COUNTS + (OBJ_KIND_T << OBJ_COUNT_SHIFT)(s2)
    sd      t0, OBJ_TOTALS + (OBJ_KIND_T << OBJ_COUNT_SHIFT)(s2)
    sw      t0, MESH_TCOUNT(s3)
    ld      t0, OBJ_COUNTS + (OBJ_KIND_N << OBJ_COUNT_SHIFT)(s2)
    sd      t0, OBJ_TOTALS + (OBJ_KIND_N << OBJ_COUNT_SHIFT)(s2)
    ld      t1, OBJ_KEEP_NORMALS(s2)
    neg     t1, t1
    and     t0, t0, t1                  # 0 normals unless kept
    sw      t0, MESH_NCOUNT(s3)
    ld      t0, OBJ_NF(s2)
    sw      t0, MESH_FCOUNT(s3)

    # The arrays (none for a count of 0: its pointer stays 0).
    call    heap_free_bytes
    mv      s4, a0                      # s4 = free bytes before
    lwu     a0, MESH_VCOUNT(s3)
    li      a1, MESH_V_BYTES
    li      a2, MESH_V
    call    obj_alloc
    lwu     a0, MESH_TCOUNT(s3)
    li      a1, MESH_T_BYTES
    li      a2, MESH_T
    call    obj_alloc
    lwu     a0, MESH_NCOUNT(s3)
    li      a1, MESH_N_BYTES
    li      a2, MESH_N
    call    obj_alloc
    lwu     a0, MESH_FCOUNT(s3)
    li      a1, MESH_F_BYTES
    li      a2, MESH_F
    call    obj_alloc
    bnez    a0, 81f                     # any failed: error 12

    # Second pass: fill them.
    li      t0, 1
    sd      t0, OBJ_STORE(s2)
    li      a0, 0
    call    obj_reader_open
    call    obj_pass
    call    obj_reader_close

    call    console_lock
    la      a0, msg_model
    call    console_puts
    lwu     a0, MESH_FCOUNT(s3)
    call    console_put_dec
    la      a0, msg_triangles
    call    console_puts
    lwu     a0, MESH_VCOUNT(s3)
    call    console_put_dec
    la      a0, msg_vertices
    call    console_puts
    lwu     a0, MESH_TCOUNT(s3)
    call    console_put_dec
    la      a0, msg_uv
    call    console_puts
    ld      a0, OBJ_TOTALS + (OBJ_KIND_N << OBJ_COUNT_SHIFT)(s2)
    call    console_put_dec             # the file's normals, stored or not
    la      a0, msg_normals
    ld      t0, OBJ_KEEP_NORMALS(s2)
    bnez    t0, 2f
    la      a0, msg_normals_flat
    lwu     t0, SCENE_MODE(s3)
    li      t1, MODE_WIREFRAME
    bne     t0, t1, 2f
    la      a0, msg_normals_wireframe
2:  call    console_puts
    call    console_unlock
    FRAME_RESTORE 64, ra, s0, s1, s2, s3, s4, s5
    ret

80: li      a0, ERR_BAD_MODEL
    la      a1, msg_no_faces
    li      a2, 0
    call    error_fatal

    # Error 12: what the four arrays take from the heap (each rounded up to
    # HEAP_ALIGN, as heap_alloc hands them out: they fit exactly when this
    # is at most the bytes that were free), and what was free.
81: li      s5, 0
    lwu     t0, MESH_VCOUNT(s3)
    li      t1, MESH_V_BYTES
    jal     t6, 82f
    lwu     t0, MESH_TCOUNT(s3)
    li      t1, MESH_T_BYTES
    jal     t6, 82f
    lwu     t0, MESH_NCOUNT(s3)
    li      t1, MESH_N_BYTES
    jal     t6, 82f
    lwu     t0, MESH_FCOUNT(s3)
    li      t1, MESH_F_BYTES
    jal     t6, 82f
    j       83f
82: mul     t0, t0, t1                  # s5 += count * size, rounded up
    addi    t0, t0, HEAP_ALIGN - 1
    andi    t0, t0, -HEAP_ALIGN
    add     s5, s5, t0
    jr      t6
83:
    li      a0, ERR_MODEL_TOO_LARGE
    call    error_begin
    la      a0, msg_too_large
    call    console_puts
    mv      a0, s5
    call    console_put_dec
    la      a0, msg_too_large_need
    call    console_puts
    mv      a0, s4
    call    console_put_dec
    la      a0, msg_too_large_free
    call    console_puts
    j       error_end

# obj_alloc (file-local)
#   What: takes count * size bytes from the heap for one mesh array and
#         stores its address at scene + a2 (0 for a count of 0). Remembers a
#         failure in obj_alloc_failed instead of stopping, so that the
#         error can report what all the arrays need.
#   Arguments: a0 = count, a1 = element bytes, a2 = scene offset of the
#         pointer.
#   Results: a0 = 1 when this or an earlier array did not fit, else 0.
#   Clobbers: only ABI temporaries.
obj_alloc:
    FRAME_SAVE 16, ra, s0
    la      s0, scene
    add     s0, s0, a2                  # s0 = the pointer field
    sd      zero, 0(s0)
    beqz    a0, 1f
    mul     a0, a0, a1
    call    heap_alloc
    sd      a0, 0(s0)
    bnez    a0, 1f
    la      t0, obj_alloc_failed
    li      t1, 1
    sd      t1, 0(t0)
1:  la      t0, obj_alloc_failed
    ld      a0, 0(t0)
    FRAME_RESTORE 16, ra, s0
    ret

# obj_pass (file-local)
#   What: one pass over the text, read through the window obj_reader_open
#         set up: every line's statement is found in obj_statements and
#         handed to its handler (a2 = the row's aux), which reads the line's
#         tokens (obj_token); the rest of the line is then skipped (a
#         comment, the CR of a CRLF, an ignored statement's words). Resets
#         and leaves the counts in obj_state.
#   Arguments: none.
#   Results: none (errors are fatal).
#   Clobbers: only ABI temporaries.
obj_pass:
    FRAME_SAVE 16, ra, s0
    la      s0, obj_state
    sd      zero, OBJ_LINE(s0)
    sd      zero, OBJ_COUNTS + (OBJ_KIND_V << OBJ_COUNT_SHIFT)(s0)
    sd      zero, OBJ_COUNTS + (OBJ_KIND_T << OBJ_COUNT_SHIFT)(s0)
    sd      zero, OBJ_COUNTS + (OBJ_KIND_N << OBJ_COUNT_SHIFT)(s0)
    sd      zero, OBJ_NF(s0)
1:  call    obj_more
    beqz    a0, 90f
    ld      t0, OBJ_LINE(s0)
    addi    t0, t0, 1
    sd      t0, OBJ_LINE(s0)
    call    obj_token                   # the keyword
    beq     a0, a1, 60f                 # blank or comment only
    call    obj_find_statement
    beqz    a0, 80f
    ld      t0, OBJ_STMT_HANDLER(a0)
    ld      a2, OBJ_STMT_AUX(a0)
    jalr    t0
60: call    obj_next_line
    j       1b

80: la      a0, msg_unknown
    j       obj_error

90: FRAME_RESTORE 16, ra, s0
    ret

# obj_reader_open (file-local)
#   What: starts reading the model's text for a pass: takes the window from
#         the heap (OBJ_WINDOW_BYTES; error 12 when it does not fit) and opens
#         the file on the card by its path (scene_model), or the text in
#         memory when the record has an address.
#   Arguments: a0 = 1 to compute the file's CRC-32 while reading it (into
#         obj_reader's stream record), 0 not to.
#   Results: none.
#   Clobbers: only ABI temporaries.
obj_reader_open:
    FRAME_SAVE 16, ra, s0
    la      s0, obj_reader
    sd      a0, RD_CRC_ON(s0)
    li      a0, OBJ_WINDOW_BYTES
    la      a1, msg_window
    call    heap_alloc_or_fail
    sd      a0, RD_BASE(s0)
    sd      a0, RD_END(s0)
    sd      a0, RD_CURSOR(s0)
    li      t0, OBJ_WINDOW_BYTES
    sd      t0, RD_CAP(s0)
    la      t0, scene_model
    ld      t1, FILE_RECORD_ADDRESS(t0)
    sd      t1, RD_TEXT(s0)
    beqz    t1, 1f
    ld      t1, FILE_RECORD_SIZE(t0)
    sd      t1, RD_LEFT(s0)
    j       2f
1:  addi    a0, s0, RD_STREAM
    ld      a1, FILE_RECORD_PATH(t0)
    call    fat32_stream_open
    sd      a0, RD_LEFT(s0)
2:  FRAME_RESTORE 16, ra, s0
    ret

# obj_reader_close (file-local)
#   What: ends a pass's reading: gives the window back to the heap (it is
#         the latest block).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
obj_reader_close:
    la      t0, obj_reader
    ld      a0, RD_BASE(t0)
    tail    heap_release

# obj_refill (file-local)
#   What: reads more of the text into the window, keeping the bytes from the
#         cursor on: they move to the window's start (the cursor with them),
#         then as many whole sectors as the window has room for are read
#         after them. When less than a sector is free after them (a token as
#         long as the window) the window first grows by OBJ_WINDOW_BYTES: the
#         block heap_alloc hands out next starts where the window ends, as
#         nothing is taken from the heap during a pass.
#   Arguments: none.
#   Results: a0 = 1 when bytes were added, 0 when the text is read to its
#         end (the window is left as it was).
#   Clobbers: only ABI temporaries.
obj_refill:
    FRAME_SAVE 32, ra, s0, s1, s2
    la      s0, obj_reader
    li      a0, 0
    ld      t0, RD_LEFT(s0)
    beqz    t0, 90f
    ld      t1, RD_CURSOR(s0)
    ld      t2, RD_END(s0)
    ld      t3, RD_BASE(s0)
    beq     t1, t3, 2f
1:  bgeu    t1, t2, 11f                 # [cursor, end) to the start
    lbu     t4, 0(t1)
    sb      t4, 0(t3)
    addi    t1, t1, 1
    addi    t3, t3, 1
    j       1b
11: sd      t3, RD_END(s0)
    ld      t3, RD_BASE(s0)
    sd      t3, RD_CURSOR(s0)
2:  ld      t0, RD_BASE(s0)
    ld      t1, RD_CAP(s0)
    add     t0, t0, t1
    ld      t2, RD_END(s0)
    sub     s1, t0, t2                  # s1 = bytes free after the kept ones
    li      t0, FAT_SECTOR_BYTES
    bgeu    s1, t0, 3f
    li      a0, OBJ_WINDOW_BYTES
    la      a1, msg_window_grow
    call    heap_alloc_or_fail
    ld      t0, RD_CAP(s0)
    li      t1, OBJ_WINDOW_BYTES
    add     t0, t0, t1
    sd      t0, RD_CAP(s0)
    add     s1, s1, t1
3:  srli    s1, s1, FAT_SECTOR_SHIFT    # s1 = sectors that fit
    slli    s2, s1, FAT_SECTOR_SHIFT
    ld      t0, RD_LEFT(s0)
    bleu    s2, t0, 4f
    mv      s2, t0                      # s2 = text bytes coming in
4:  ld      t0, RD_TEXT(s0)
    beqz    t0, 6f
    ld      t1, RD_END(s0)              # text in memory: copied
    add     t2, t0, s2
5:  bgeu    t0, t2, 51f
    lbu     t3, 0(t0)
    sb      t3, 0(t1)
    addi    t0, t0, 1
    addi    t1, t1, 1
    j       5b
51: sd      t0, RD_TEXT(s0)
    j       7f
6:  addi    a0, s0, RD_STREAM           # from the card
    ld      a1, RD_END(s0)
    mv      a2, s1
    ld      a3, RD_CRC_ON(s0)
    call    fat32_stream_read
7:  ld      t0, RD_END(s0)
    add     t0, t0, s2
    sd      t0, RD_END(s0)
    ld      t0, RD_LEFT(s0)
    sub     t0, t0, s2
    sd      t0, RD_LEFT(s0)
    li      a0, 1
90: FRAME_RESTORE 32, ra, s0, s1, s2
    ret

# obj_more (file-local)
#   What: whether any text is left to parse (refilling an empty window).
#   Arguments: none.
#   Results: a0 = 1 some is, 0 the text is parsed to its end.
#   Clobbers: only ABI temporaries.
obj_more:
    la      t0, obj_reader
    ld      t1, RD_CURSOR(t0)
    ld      t2, RD_END(t0)
    li      a0, 1
    bgeu    t1, t2, 1f
    ret
1:  tail    obj_refill

# obj_next_line (file-local)
#   What: moves the cursor past the next LF (or to the end of the text).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
obj_next_line:
    FRAME_SAVE 16, ra
1:  la      t0, obj_reader
    ld      t1, RD_CURSOR(t0)
    ld      t2, RD_END(t0)
    li      t3, CHAR_LF
2:  bgeu    t1, t2, 3f
    lbu     t4, 0(t1)
    addi    t1, t1, 1
    bne     t4, t3, 2b
    sd      t1, RD_CURSOR(t0)
    j       9f
3:  sd      t1, RD_CURSOR(t0)
    call    obj_refill
    bnez    a0, 1b
9:  FRAME_RESTORE 16, ra
    ret

# obj_token (file-local)
#   What: the line's next token: skips spaces and tabs, then takes the bytes
#         up to a space or tab or the end of the line's content (a LF, a '#',
#         a CR followed by LF or by the end of the text, the end of the text),
#         refilling the window as needed so that the token lies whole in it.
#         A CR followed by anything else is part of the token.
#   Arguments: none.
#   Results: a0 = token start, a1 = token end (in the window, valid until
#         the next read); the cursor moves to a1. a0 = a1 where the content
#         ends (the cursor stays on what ends it).
#   Clobbers: only ABI temporaries.
obj_token:
    FRAME_SAVE 32, ra, s0, s1
    la      s0, obj_reader
1:  ld      t0, RD_CURSOR(s0)           # spaces and tabs
    ld      t1, RD_END(s0)
    li      t3, CHAR_SPACE
    li      t4, CHAR_TAB
2:  bgeu    t0, t1, 3f
    lbu     t2, 0(t0)
    beq     t2, t3, 21f
    bne     t2, t4, 4f
21: addi    t0, t0, 1
    j       2b
3:  sd      t0, RD_CURSOR(s0)
    call    obj_refill
    bnez    a0, 1b
    ld      t3, RD_CURSOR(s0)           # the end of the text: no token
    j       80f
4:  sd      t0, RD_CURSOR(s0)           # the token starts here
    li      s1, 0                       # s1 = its bytes scanned so far
5:  ld      t0, RD_CURSOR(s0)
    ld      t1, RD_END(s0)
    add     t3, t0, s1                  # t3 = scan
    li      t5, CHAR_COMMENT            # no byte above '#' ends a token
6:  bgeu    t3, t1, 7f
    lbu     t2, 0(t3)
    bgtu    t2, t5, 65f
    li      t4, CHAR_SPACE
    beq     t2, t4, 80f
    li      t4, CHAR_TAB
    beq     t2, t4, 80f
    li      t4, CHAR_LF
    beq     t2, t4, 80f
    beq     t2, t5, 80f
    li      t4, CHAR_CR
    bne     t2, t4, 65f
    addi    t4, t3, 1                   # a CR: what follows it decides
    bgeu    t4, t1, 7f
    lbu     t2, 1(t3)
    li      t4, CHAR_LF
    beq     t2, t4, 80f
65: addi    t3, t3, 1
    j       6b
7:  sub     s1, t3, t0                  # more text, the token kept: scan on
    call    obj_refill
    bnez    a0, 5b
    ld      t0, RD_CURSOR(s0)           # the end of the text ends the token
    add     t3, t0, s1
80: ld      a0, RD_CURSOR(s0)
    mv      a1, t3
    sd      a1, RD_CURSOR(s0)
    FRAME_RESTORE 32, ra, s0, s1
    ret

# obj_find_statement (file-local)
#   What: the obj_statements row whose keyword is exactly [a0, a1).
#   Arguments: a0 = keyword start, a1 = keyword end.
#   Results: a0 = row, or 0 when unknown; a1 = keyword end (unchanged).
#   Clobbers: only ABI temporaries.
obj_find_statement:
    la      t0, obj_statements
    la      t6, obj_statements_end
1:  ld      t1, OBJ_STMT_NAME(t0)       # t1 = keyword of the row
    mv      t2, a0                      # t2 = text
2:  lbu     t3, 0(t1)
    beqz    t3, 4f
    beq     t2, a1, 5f
    lbu     t4, 0(t2)
    bne     t3, t4, 5f
    addi    t1, t1, 1
    addi    t2, t2, 1
    j       2b
4:  bne     t2, a1, 5f
    mv      a0, t0
    ret
5:  addi    t0, t0, OBJ_STMT_BYTES
    bltu    t0, t6, 1b
    li      a0, 0
    ret

# obj_stmt_ignore (file-local)
#   What: a statement accepted and ignored (o, g, s, mtllib, usemtl): obj_pass
#         skips the rest of its line.
#   Arguments: a2 as obj_pass hands it. Results: none.
#   Clobbers: nothing.
obj_stmt_ignore:
    ret

# obj_stmt_vector (file-local)
#   What: v, vt or vn: reads its numbers (the line's tokens; one past
#         OBJ_NUMBERS_MAX is counted, not read: the count is wrong then),
#         checks them, stores them in the second pass (vn only when normals
#         are kept), counts it.
#   Arguments: a2 = obj_vectors row.
#   Results: none (errors are fatal).
#   Clobbers: only ABI temporaries.
obj_stmt_vector:
    FRAME_SAVE 96, ra, s0, s1
    # 0(sp): OBJ_NUMBERS_MAX doubles
    mv      s0, a2                      # s0 = row
    li      s1, 0                       # s1 = numbers
    sd      zero, OBJ_DOUBLE_BYTES(sp)  # vt: v = 0 when absent
4:  call    obj_token
    beq     a0, a1, 6f
    li      t0, OBJ_NUMBERS_MAX
    bltu    s1, t0, 5f
    addi    s1, s1, 1                   # one too many
    j       6f
5:  call    parse_number
    bnez    a1, 81f
    slli    t0, s1, OBJ_DOUBLE_SHIFT
    add     t0, t0, sp
    fsd     fa0, 0(t0)
    addi    s1, s1, 1
    j       4b
6:  lbu     t0, OBJ_VEC_COUNTS(s0)
    srl     t0, t0, s1
    andi    t0, t0, 1
    beqz    t0, 82f
    lbu     s1, OBJ_VEC_STORED(s0)      # s1 = numbers kept
    slli    s1, s1, OBJ_DOUBLE_SHIFT
    add     s1, s1, sp                  # s1 = end of them
    mv      t1, sp
1:  fld     ft0, 0(t1)                  # each must be finite in single precision
    fcvt.s.d ft0, ft0
    fclass.s t3, ft0
    andi    t3, t3, FCLASS_NOT_FINITE
    bnez    t3, 83f
    addi    t1, t1, OBJ_DOUBLE_BYTES
    bltu    t1, s1, 1b

    la      t5, obj_state
    lbu     t4, OBJ_VEC_KIND(s0)
    slli    t4, t4, OBJ_COUNT_SHIFT
    add     t4, t4, t5
    ld      t6, OBJ_COUNTS(t4)          # t6 = this kind's count so far
    addi    t0, t6, 1
    sd      t0, OBJ_COUNTS(t4)
    ld      t0, OBJ_STORE(t5)
    beqz    t0, 9f
    lbu     t0, OBJ_VEC_NORMALS(s0)
    beqz    t0, 2f
    ld      t0, OBJ_KEEP_NORMALS(t5)
    beqz    t0, 9f
2:  lwu     t0, OBJ_VEC_ARRAY(s0)
    la      t1, scene
    add     t1, t1, t0
    ld      t1, 0(t1)                   # t1 = the array
    lbu     t2, OBJ_VEC_STORED(s0)
    slli    t2, t2, OBJ_F32_SHIFT       # t2 = element bytes
    mul     t2, t2, t6
    add     t1, t1, t2                  # t1 = this element
    mv      t2, sp
3:  fld     ft0, 0(t2)
    fcvt.s.d ft0, ft0
    fsw     ft0, 0(t1)
    addi    t1, t1, OBJ_F32_BYTES
    addi    t2, t2, OBJ_DOUBLE_BYTES
    bltu    t2, s1, 3b
9:  FRAME_RESTORE 96, ra, s0, s1
    ret
81: la      a0, msg_number
    j       obj_error
82: ld      a0, OBJ_VEC_MESSAGE(s0)
    j       obj_error
83: la      a0, msg_f32_range
    j       obj_error

# obj_stmt_face (file-local)
#   What: f: reads its corners (the line's tokens, obj_corner) and fans them
#         into triangles (first, latest, this), stored in the second pass,
#         counted always.
#   Arguments: a2 unused.
#   Results: none (errors are fatal).
#   Clobbers: only ABI temporaries.
obj_stmt_face:
    FRAME_SAVE 48, ra, _, _, s2, s3
    li      s2, 0                       # s2 = corners so far
    la      s3, obj_state
1:  call    obj_token
    beq     a0, a1, 8f
    call    obj_corner
    beqz    s2, 4f
    li      t0, 1
    beq     s2, t0, 5f
    # A triangle: first, latest, this.
    ld      t0, OBJ_NF(s3)
    addi    t1, t0, 1
    sd      t1, OBJ_NF(s3)
    ld      t1, OBJ_STORE(s3)
    beqz    t1, 5f
    la      t1, scene
    ld      t1, MESH_F(t1)
    li      t2, MESH_F_BYTES
    mul     t0, t0, t2
    add     t1, t1, t0                  # t1 = the triangle
    addi    a0, s3, OBJ_FIRST
    mv      a1, t1
    call    obj_store_corner
    addi    a0, s3, OBJ_PREV
    addi    a1, t1, MESH_CORNER_BYTES
    call    obj_store_corner
    addi    a0, s3, OBJ_CORNER
    addi    a1, t1, 2 * MESH_CORNER_BYTES
    call    obj_store_corner
    j       5f
4:  addi    a0, s3, OBJ_CORNER          # the first corner
    addi    a1, s3, OBJ_FIRST
    call    obj_copy_corner
    j       6f
5:  addi    a0, s3, OBJ_CORNER          # now the latest
    addi    a1, s3, OBJ_PREV
    call    obj_copy_corner
6:  addi    s2, s2, 1
    j       1b
8:  li      t0, OBJ_FACE_MIN_CORNERS
    bltu    s2, t0, 80f
    FRAME_RESTORE 48, ra, _, _, s2, s3
    ret
80: la      a0, msg_short_face
    j       obj_error

# obj_copy_corner (file-local)
#   What: copies one corner of obj_state (v, t, n: three u32).
#   Arguments: a0 = from, a1 = to.
#   Results: none.
#   Clobbers: only ABI temporaries (t3 only: callers keep t0 .. t2).
obj_copy_corner:
    lw      t3, OBJ_CORNER_V(a0)
    sw      t3, OBJ_CORNER_V(a1)
    lw      t3, OBJ_CORNER_T(a0)
    sw      t3, OBJ_CORNER_T(a1)
    lw      t3, OBJ_CORNER_N(a0)
    sw      t3, OBJ_CORNER_N(a1)
    ret

# obj_store_corner (file-local)
#   What: stores one corner of obj_state into a triangle, its three indices
#         packed (scene.inc MESH_CORNER_*_SHIFT; each is below its array's
#         count, so below MESH_NO_INDEX, or MESH_NO_INDEX itself).
#   Arguments: a0 = the corner (obj_state), a1 = where in the triangle.
#   Results: none.
#   Clobbers: only ABI temporaries (t3, t4 only: callers keep t0 .. t2).
obj_store_corner:
    lwu     t3, OBJ_CORNER_N(a0)
    slli    t3, t3, MESH_CORNER_N_SHIFT - MESH_CORNER_T_SHIFT
    lwu     t4, OBJ_CORNER_T(a0)
    or      t3, t3, t4
    slli    t3, t3, MESH_CORNER_T_SHIFT - MESH_CORNER_V_SHIFT
    lwu     t4, OBJ_CORNER_V(a0)
    or      t3, t3, t4
    sd      t3, 0(a1)
    ret

# obj_corner (file-local)
#   What: one face corner, v, v/vt, v//vn or v/vt/vn, ending at a blank or
#         the end (a token: the end), into obj_state's OBJ_CORNER (0-based indices,
#         MESH_NO_INDEX for an absent one, and for vn when normals are not
#         kept).
#   Arguments: a0 = its first character, a1 = end of the content.
#   Results: a0 = the byte after it.
#   Clobbers: only ABI temporaries.
obj_corner:
    FRAME_SAVE 32, ra, s0, s1
    mv      s1, a1                      # s1 = end
    la      s0, obj_state
    li      t0, MESH_NO_INDEX
    sw      t0, OBJ_CORNER + OBJ_CORNER_T(s0)
    sw      t0, OBJ_CORNER + OBJ_CORNER_N(s0)
    li      a2, OBJ_KIND_V
    call    obj_index
    sw      a1, OBJ_CORNER + OBJ_CORNER_V(s0)
    li      t1, CHAR_SLASH
    bgeu    a0, s1, 8f
    lbu     t0, 0(a0)
    bne     t0, t1, 8f
    addi    a0, a0, 1
    bgeu    a0, s1, 80f
    lbu     t0, 0(a0)
    beq     t0, t1, 2f                  # v//vn
    mv      a1, s1
    li      a2, OBJ_KIND_T
    call    obj_index
    sw      a1, OBJ_CORNER + OBJ_CORNER_T(s0)
    li      t1, CHAR_SLASH
    bgeu    a0, s1, 8f
    lbu     t0, 0(a0)
    bne     t0, t1, 8f
2:  addi    a0, a0, 1                   # vn
    mv      a1, s1
    li      a2, OBJ_KIND_N
    call    obj_index
    ld      t0, OBJ_KEEP_NORMALS(s0)
    beqz    t0, 8f
    sw      a1, OBJ_CORNER + OBJ_CORNER_N(s0)
8:  bgeu    a0, s1, 9f                  # the corner ends here
    lbu     t0, 0(a0)
    li      t1, CHAR_SPACE
    beq     t0, t1, 9f
    li      t1, CHAR_TAB
    bne     t0, t1, 80f
9:  FRAME_RESTORE 32, ra, s0, s1
    ret
80: la      a0, msg_corner
    j       obj_error

# obj_index (file-local)
#   What: one index of a face corner: [+|-] digits, resolved against the
#         elements of its kind (1-based, or negative = counting back from the
#         latest defined before this line) to a 0-based index.
#   Arguments: a0 = its first character, a1 = end of the content,
#         a2 = kind (OBJ_KIND_V, _T, _N).
#   Results: a0 = the byte after its digits, a1 = 0-based index.
#   Errors: 10 no digits (malformed corner), index 0, out of range.
#   Clobbers: only ABI temporaries.
obj_index:
    li      t5, 0                       # t5 = 1 when negative
    bgeu    a0, a1, 80f
    lbu     t0, 0(a0)
    li      t1, CHAR_MINUS
    bne     t0, t1, 1f
    li      t5, 1
    addi    a0, a0, 1
    j       2f
1:  li      t1, CHAR_PLUS
    bne     t0, t1, 2f
    addi    a0, a0, 1
2:  li      t2, 0                       # t2 = value (saturating)
    li      t3, 0                       # t3 = digits
    li      t4, DECIMAL_BASE
    li      t6, OBJ_INDEX_LIMIT
3:  bgeu    a0, a1, 4f
    lbu     t0, 0(a0)
    addi    t0, t0, -CHAR_DIGIT_0
    bgeu    t0, t4, 4f
    addi    t3, t3, 1
    addi    a0, a0, 1
    bgeu    t2, t6, 3b
    mul     t2, t2, t4
    add     t2, t2, t0
    j       3b
4:  beqz    t3, 80f
    beqz    t2, 81f
    la      t0, obj_state
    slli    t1, a2, OBJ_COUNT_SHIFT
    add     t0, t0, t1
    beqz    t5, 5f
    ld      t1, OBJ_COUNTS(t0)          # -k: the k-th latest so far
    bgtu    t2, t1, 82f
    sub     a1, t1, t2
    ret
5:  ld      t1, OBJ_TOTALS(t0)          # k: 1 .. the file's total
    bgtu    t2, t1, 82f
    addi    a1, t2, -1
    ret
80: la      a0, msg_corner
    j       obj_error
81: la      a0, msg_index_0
    j       obj_error
82: la      t0, obj_range_messages
    slli    t1, a2, OBJ_POINTER_SHIFT
    add     t0, t0, t1
    ld      a0, 0(t0)
    j       obj_error

# obj_error (file-local)
#   What: error 10, "bad model line <n>: <what>" (n = obj_state's line).
#   Arguments: a0 = what (string).
#   Results: never returns.
#   Clobbers: everything.
obj_error:
    mv      s1, a0
    la      t0, obj_state
    ld      s0, OBJ_LINE(t0)
    li      a0, ERR_BAD_MODEL
    call    error_begin
    la      a0, msg_bad_model
    call    console_puts
    mv      a0, s0
    call    console_put_dec
    la      a0, msg_colon
    call    console_puts
    mv      a0, s1
    call    console_puts
    j       error_end

# ---------------------------------------------------------------------------
    .bss
    .balign 8
# obj_state: the pass in progress (offsets OBJ_* above).
obj_state:
    .space  OBJ_STATE_BYTES
# obj_alloc_failed: 1 once a mesh array did not fit in the heap.
obj_alloc_failed:
    .space  8
# obj_reader: the window the text is read through (RD_* offsets above).
obj_reader:
    .space  RD_BYTES
