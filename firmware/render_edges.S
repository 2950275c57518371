# render_edges.S: what the mesh's edges join, found once at render_init by
# sorting keys (sort_u64):
#   - antialias = edge: the triangle adjacency (adjacency_build; vertices
#     matched by position, vertex_canon), and per triangle drawn what lies
#     across each of its edges (aa_neighbours), so that raster_triangle
#     antialiases silhouette edges only;
#   - wireframe: the unique edge list (edges_build), each edge shared by two
#     triangles once (render_wireframe.S draws it).

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"
    .include "frame.inc"

    .text
    .globl aa_neighbours
# aa_neighbours
#   What: antialias = edge: each corner's RV_OPP_* (render.inc) from the
#         adjacency (adjacency_build) and this frame's vertex records: the
#         far corner of the neighbour across the edge opposite the corner
#         (OPP_CORNER, its Q4 screen position), OPP_OPEN where the mesh ends,
#         OPP_HARD where there are several neighbours or the far corner is
#         cut in clip space (not projected).
#   Arguments: a0 = the face (in MESH_F), a1 = vertex records, a2 = its
#              three raster vertices.
#   Results: none.
#   Clobbers: only ABI temporaries.
aa_neighbours:
    la      t0, scene
    ld      t1, MESH_F(t0)
    sub     t1, a0, t1
    srli    t1, t1, ADJ_FACE_FROM_MESH_F
    la      t0, adjacency
    ld      t0, 0(t0)
    add     t0, t0, t1                  # t0 = the face's entries
    li      t3, TRIANGLE_CORNERS
1:  lwu     t1, 0(t0)
    li      t4, ADJ_OPEN
    beq     t1, t4, 2f
    li      t4, ADJ_MANY
    beq     t1, t4, 3f
    li      t4, VTX_BYTES
    mul     t1, t1, t4
    add     t1, t1, a1
    lw      t4, VTX_OUTCODE(t1)
    andi    t4, t4, OUT_CLIP
    bnez    t4, 3f
    lw      t4, VTX_SX(t1)
    sw      t4, RV_OPP_X(a2)
    lw      t4, VTX_SY(t1)
    sw      t4, RV_OPP_Y(a2)
    li      t4, OPP_CORNER
    j       4f
2:  li      t4, OPP_OPEN
    j       4f
3:  li      t4, OPP_HARD
4:  sw      t4, RV_OPP_KIND(a2)
    addi    t0, t0, ADJ_BYTES
    addi    a2, a2, RV_BYTES
    addi    t3, t3, -1
    bnez    t3, 1b
    ret

# CANON_COORD reg, addr
#   vertex_canon's view of one coordinate: its bit pattern with -0 as +0
#   (ft0 must hold +0). Clobbers ft1.
.macro CANON_COORD reg, addr
    flw     ft1, \addr
    fadd.s  ft1, ft1, ft0
    fmv.x.w \reg, ft1
    slli    \reg, \reg, 32             # zero-extended
    srli    \reg, \reg, 32
.endm

# vertex_canon (file-local)
#   What: for adjacency_build, each vertex's canonical index: the smallest
#         index of a vertex with the same position bits (x, y, z). One key
#         per vertex, (hash of the position) << MESH_INDEX_BITS | index,
#         sorted (sort_u64) in a block given back before returning; within a
#         run of one hash (ascending index) a vertex takes the first earlier
#         one at the same position (a collision of two positions only leaves
#         them apart).
#   Arguments: none.
#   Results: a0 = the indices (a heap block, u32 each; the last block).
#   Clobbers: only ABI temporaries.
vertex_canon:
    FRAME_SAVE 48, ra, s0, s1, s2, s3
    la      t0, scene
    lwu     s0, MESH_VCOUNT(t0)         # s0 = vertices
    ld      s3, MESH_V(t0)              # s3 = their positions
    slli    a0, s0, ADJ_SHIFT
    la      a1, msg_canonical_vertices
    call    heap_alloc_or_fail
    mv      s1, a0                      # s1 = canonical indices
    slli    a0, s0, ADJ_KEY_SHIFT
    la      a1, msg_vertex_keys
    call    heap_alloc_or_fail
    mv      s2, a0                      # s2 = keys
    li      t0, 0                       # t0 = vertex
    li      t5, CANON_HASH_X
    li      t6, CANON_HASH_Y
    li      a2, CANON_HASH_Z
    fmv.w.x ft0, zero                   # + 0: -0 becomes +0 (a position
                                        # written "-0.000000" is the same point)
1:  bgeu    t0, s0, 2f
    li      t1, MESH_V_BYTES
    mul     t1, t1, t0
    add     t1, t1, s3
    CANON_COORD t2, 0(t1)
    mul     t2, t2, t5
    CANON_COORD t3, 4(t1)
    mul     t3, t3, t6
    xor     t2, t2, t3
    CANON_COORD t3, 8(t1)
    mul     t3, t3, a2
    xor     t2, t2, t3
    srli    t3, t2, CANON_HASH_FOLD     # the high bits into the kept ones
    xor     t2, t2, t3
    srli    t2, t2, MESH_INDEX_BITS     # hash << MESH_INDEX_BITS | index
    slli    t2, t2, MESH_INDEX_BITS
    or      t2, t2, t0
    slli    t1, t0, ADJ_KEY_SHIFT
    add     t1, t1, s2
    sd      t2, 0(t1)
    addi    t0, t0, 1
    j       1b
2:  mv      a0, s2
    mv      a1, s0
    call    sort_u64
    li      t0, 0                       # t0 = key
3:  bgeu    t0, s0, 9f
    slli    t1, t0, ADJ_KEY_SHIFT
    add     t1, t1, s2
    ld      t2, 0(t1)                   # t2 = this key
    slli    a3, t2, MESH_INDEX_LOW_SHIFT
    srli    a3, a3, MESH_INDEX_LOW_SHIFT    # a3 = its vertex
    mv      a4, a3                      # a4 = its canonical index
    li      t3, MESH_V_BYTES
    mul     a5, a3, t3
    add     a5, a5, s3                  # a5 -> its position
    mv      t4, t0                      # t4 = earlier keys of the same hash
4:  beqz    t4, 8f
    addi    t4, t4, -1
    slli    t1, t4, ADJ_KEY_SHIFT
    add     t1, t1, s2
    ld      t1, 0(t1)
    xor     t3, t1, t2
    srli    t3, t3, MESH_INDEX_BITS
    bnez    t3, 8f                      # another hash: the run's start
    slli    t1, t1, MESH_INDEX_LOW_SHIFT
    srli    t1, t1, MESH_INDEX_LOW_SHIFT    # t1 = the earlier vertex
    li      t3, MESH_V_BYTES
    mul     t3, t1, t3
    add     t3, t3, s3
    CANON_COORD a6, 0(t3)
    CANON_COORD a7, 0(a5)
    bne     a6, a7, 4b
    CANON_COORD a6, 4(t3)
    CANON_COORD a7, 4(a5)
    bne     a6, a7, 4b
    CANON_COORD a6, 8(t3)
    CANON_COORD a7, 8(a5)
    bne     a6, a7, 4b
    mv      a4, t1                      # the same position: the earliest wins
    j       4b
8:  slli    t1, a3, ADJ_SHIFT
    add     t1, t1, s1
    sw      a4, 0(t1)
    addi    t0, t0, 1
    j       3b
9:  mv      a0, s2
    call    heap_release
    mv      a0, s1
    FRAME_RESTORE 48, ra, s0, s1, s2, s3
    ret

    .globl adjacency_build
# adjacency_build
#   What: antialias = edge: the triangle adjacency (render.inc ADJ_*) into
#         a heap block (adjacency). Vertices are matched by position, not
#         index (vertex_canon): models repeat a vertex where its texture
#         coordinates or normal change (a seam), and the triangles on the
#         two sides are still one surface. Then one key per triangle edge,
#         sorted (sort_u64), and each run of keys with one vertex pair: a
#         single key is ADJ_OPEN, a pair points each at the other's far
#         corner, three or more are ADJ_MANY. The keys and the canonical
#         indices live in blocks given back afterwards. Fatal when the heap
#         is short (heap_alloc_or_fail).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
adjacency_build:
    FRAME_SAVE 64, ra, s0, s1, s2, s3, s4, s5
    la      t0, scene
    lwu     s0, MESH_FCOUNT(t0)         # s0 = triangles
    ld      s3, MESH_F(t0)              # s3 = the triangles' corners
    li      t1, ADJ_FACE_BYTES
    mul     a0, s0, t1
    la      a1, msg_adjacency
    call    heap_alloc_or_fail
    mv      s1, a0                      # s1 = adjacency
    la      t0, adjacency
    sd      a0, 0(t0)
    call    vertex_canon
    mv      s5, a0                      # s5 = canonical vertex indices
    li      t1, TRIANGLE_CORNERS * ADJ_KEY_BYTES
    mul     a0, s0, t1
    la      a1, msg_adjacency_keys
    call    heap_alloc_or_fail
    mv      s2, a0                      # s2 = keys
    # the keys: triangle t (a3), corner k (a4): the edge of corners k + 1, k + 2
    mv      t3, s2
    li      a3, 0
1:  bgeu    a3, s0, 5f
    li      t0, MESH_F_BYTES
    mul     t0, t0, a3
    add     t0, t0, s3                  # t0 -> corners
    li      a4, 0
2:  li      t1, TRIANGLE_CORNERS
    addi    t2, a4, 1
    remu    t2, t2, t1
    slli    t2, t2, MESH_CORNER_SHIFT
    add     t2, t2, t0
    ld      a1, 0(t2)
    slli    a1, a1, MESH_INDEX_LOW_SHIFT
    srli    a1, a1, MESH_INDEX_LOW_SHIFT
    slli    a1, a1, ADJ_SHIFT
    add     a1, a1, s5
    lwu     a1, 0(a1)                   # canonical
    addi    t2, a4, 2
    remu    t2, t2, t1
    slli    t2, t2, MESH_CORNER_SHIFT
    add     t2, t2, t0
    ld      a2, 0(t2)
    slli    a2, a2, MESH_INDEX_LOW_SHIFT
    srli    a2, a2, MESH_INDEX_LOW_SHIFT
    slli    a2, a2, ADJ_SHIFT
    add     a2, a2, s5
    lwu     a2, 0(a2)
    bleu    a1, a2, 3f
    mv      t1, a1
    mv      a1, a2
    mv      a2, t1
3:  slli    a1, a1, ADJ_KEY_MIN_SHIFT
    slli    a2, a2, ADJ_KEY_MAX_SHIFT
    or      a1, a1, a2
    slli    a2, a3, ADJ_KEY_FACE_SHIFT
    or      a1, a1, a2
    or      a1, a1, a4
    sd      a1, 0(t3)
    addi    t3, t3, ADJ_KEY_BYTES
    addi    a4, a4, 1
    li      t1, TRIANGLE_CORNERS
    bltu    a4, t1, 2b
    addi    a3, a3, 1
    j       1b
5:  li      t1, TRIANGLE_CORNERS
    mul     s4, s0, t1                  # s4 = keys
    mv      a0, s2
    mv      a1, s4
    call    sort_u64
    sd      s5, 0(sp)                   # (given back at the end, the keys with it)
    # the runs: s5 = the run's first key's index, t5 = past its last
    li      s5, 0
6:  bgeu    s5, s4, 9f
    slli    t0, s5, ADJ_KEY_SHIFT
    add     t0, t0, s2
    ld      t0, 0(t0)
    srli    t0, t0, ADJ_KEY_MAX_SHIFT   # t0 = the vertex pair
    addi    t5, s5, 1
7:  bgeu    t5, s4, 8f
    slli    t1, t5, ADJ_KEY_SHIFT
    add     t1, t1, s2
    ld      t1, 0(t1)
    srli    t1, t1, ADJ_KEY_MAX_SHIFT
    bne     t1, t0, 8f
    addi    t5, t5, 1
    j       7b
8:  sub     t6, t5, s5                  # t6 = the run's length
    li      t1, 2
    beq     t6, t1, 10f
    li      a5, ADJ_OPEN                # one triangle, or (below) many
    li      t1, 1
    beq     t6, t1, 11f
    li      a5, ADJ_MANY
11: mv      t4, s5                      # every key of the run gets a5
12: bgeu    t4, t5, 13f
    slli    t1, t4, ADJ_KEY_SHIFT
    add     t1, t1, s2
    ld      a0, 0(t1)
    jal     t2, 21f
    sw      a5, 0(a1)
    addi    t4, t4, 1
    j       12b
13: mv      s5, t5
    j       6b
10: slli    t1, s5, ADJ_KEY_SHIFT      # a pair: each gets the other's far corner
    add     t1, t1, s2
    ld      a0, 0(t1)
    jal     t2, 21f
    mv      a6, a0                      # a6, a7 = the first's far corner, entry
    mv      a7, a1
    ld      a0, ADJ_KEY_BYTES(t1)
    jal     t2, 21f
    sw      a6, 0(a1)
    sw      a0, 0(a7)
    j       13b
    # 21: key a0's triangle corner: a0 = its vertex index (the far corner
    # of the key's edge), a1 = its adjacency entry (returns through t2;
    # clobbers t0, t3)
21: srli    t0, a0, ADJ_KEY_FACE_SHIFT
    li      t3, (1 << ADJ_KEY_FACE_BITS) - 1
    and     t0, t0, t3                  # t0 = triangle
    andi    a0, a0, ADJ_KEY_CORNER_MASK # a0 = k
    li      t3, ADJ_FACE_BYTES
    mul     a1, t0, t3
    add     a1, a1, s1
    slli    t3, a0, ADJ_SHIFT
    add     a1, a1, t3
    li      t3, MESH_F_BYTES
    mul     t0, t0, t3
    add     t0, t0, s3
    slli    t3, a0, MESH_CORNER_SHIFT
    add     t0, t0, t3
    ld      a0, 0(t0)
    slli    a0, a0, MESH_INDEX_LOW_SHIFT
    srli    a0, a0, MESH_INDEX_LOW_SHIFT
    jr      t2
9:  ld      a0, 0(sp)                   # the canonical indices and the keys
    call    heap_release                # are not needed any more
    FRAME_RESTORE 64, ra, s0, s1, s2, s3, s4, s5
    ret

    .globl edges_build
# edges_build
#   What: the unique edge list of the mesh into edge_list / edge_count:
#         every triangle's three (min, max) vertex index pairs, sorted
#         (Shell sort), duplicates removed. Fatal when the heap is short
#         (heap_alloc_or_fail).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
edges_build:
    FRAME_SAVE 32, ra, s0, s1
    la      t0, scene
    lwu     s0, MESH_FCOUNT(t0)
    li      t1, EDGES_PER_TRIANGLE
    mul     s0, s0, t1                  # s0 = pairs
    slli    a0, s0, 3                   # EDGE_BYTES each
    la      a1, msg_edge_list
    call    heap_alloc_or_fail
    mv      s1, a0                      # s1 = list
    la      t0, edge_list
    sd      a0, 0(t0)
    la      t0, scene
    ld      t1, MESH_F(t0)
    lwu     t2, MESH_FCOUNT(t0)
    mv      t3, s1
    beqz    t2, 5f
1:  ld      a1, 0(t1)
    slli    a1, a1, MESH_INDEX_LOW_SHIFT
    srli    a1, a1, MESH_INDEX_LOW_SHIFT
    ld      a2, MESH_CORNER_BYTES(t1)
    slli    a2, a2, MESH_INDEX_LOW_SHIFT
    srli    a2, a2, MESH_INDEX_LOW_SHIFT
    ld      a3, 2 * MESH_CORNER_BYTES(t1)
    slli    a3, a3, MESH_INDEX_LOW_SHIFT
    srli    a3, a3, MESH_INDEX_LOW_SHIFT
    mv      a4, a1                      # (v0, v1), (v1, v2), (v2, v0)
    mv      a5, a2
    jal     t6, 3f
    mv      a4, a2
    mv      a5, a3
    jal     t6, 3f
    mv      a4, a3
    mv      a5, a1
    jal     t6, 3f
    addi    t1, t1, MESH_F_BYTES
    addi    t2, t2, -1
    bnez    t2, 1b
    j       5f
3:  bleu    a4, a5, 4f                  # store (min << 32) | max at t3
    mv      t4, a4
    mv      a4, a5
    mv      a5, t4
4:  slli    a4, a4, EDGE_INDEX_SHIFT
    or      a4, a4, a5
    sd      a4, 0(t3)
    addi    t3, t3, EDGE_BYTES
    jr      t6
5:  mv      a0, s1
    mv      a1, s0
    call    sort_u64
    # remove duplicates (now adjacent)
    li      t0, 0                       # t0 = unique count
    beqz    s0, 7f
    li      t0, 1
    li      t1, 1                       # t1 = next read
    mv      t2, s1                      # t2 = last kept
6:  bgeu    t1, s0, 7f
    slli    t3, t1, 3
    add     t3, t3, s1
    ld      t3, 0(t3)
    ld      t4, 0(t2)
    addi    t1, t1, 1
    beq     t3, t4, 6b
    addi    t2, t2, EDGE_BYTES
    sd      t3, 0(t2)
    addi    t0, t0, 1
    j       6b
7:  la      t1, edge_count
    sd      t0, 0(t1)
    FRAME_RESTORE 32, ra, s0, s1
    ret

# sort_u64 (file-local)
#   What: sorts unsigned 64-bit values in place, ascending (Shell sort with
#         Knuth's gaps 1, 4, 13, 40, ...).
#   Arguments: a0 = array, a1 = count.
#   Results: none.
#   Clobbers: only ABI temporaries.
sort_u64:
    li      t0, 1                       # t0 = gap h: largest 3h+1 below n / 3
    li      t1, SHELL_GAP_FACTOR
    divu    t2, a1, t1                  # n / 3
1:  bgeu    t0, t2, 2f
    mul     t0, t0, t1
    addi    t0, t0, 1
    j       1b
2:  mv      t3, t0                      # t3 = i (from h)
3:  bgeu    t3, a1, 6f
    slli    t4, t3, 3
    add     t4, t4, a0
    ld      a2, 0(t4)                   # a2 = value to insert
    mv      t5, t3                      # t5 = j
4:  bltu    t5, t0, 5f
    sub     a3, t5, t0
    slli    a3, a3, 3
    add     a3, a3, a0
    ld      a4, 0(a3)                   # a[j - h]
    bleu    a4, a2, 5f
    slli    a5, t5, 3
    add     a5, a5, a0
    sd      a4, 0(a5)
    sub     t5, t5, t0
    j       4b
5:  slli    a5, t5, 3
    add     a5, a5, a0
    sd      a2, 0(a5)
    addi    t3, t3, 1
    j       3b
6:  divu    t0, t0, t1                  # next gap (h - 1) / 3 = h / 3
    bnez    t0, 2b
    ret
