# render.S: one frame of the scene: clear, then every triangle (textured or
# flat) or every edge (wireframe). The per-frame set-up (render_prepare)
# runs once; the vertex stage (render_vertex_share) and the drawing
# (render_band) run on one hart for the whole mesh and screen or on both,
# each for its share of the vertices and its band of rows (main.S), with
# per-hart scratch (the hart-local block below).
#
# Per triangle (modes textured and flat):
#   1. Trivial rejection: the three vertices outside the same frustum plane
#      (their outcodes share one of the six OUT_FRUSTUM bits, vertex.S) ->
#      skipped.
#   2. Lighting per face: N = (w1 - w0) x (w2 - w0) from the world-space
#      positions of the corners (never from vn; with flat shading the vertex
#      stage keeps them, vertex_world_array; otherwise vertex.S face_world
#      computes them for the face), intensity
#      I = max(SCENE_AMBIENT, N . L / |N|) with L = SCENE_LIGHT, as an integer
#      k = round(64 I) in 0 .. 64 (render.inc). Flat mode draws
#      FLAT_BASE_COLOUR (0xC618, light grey) with every RGB565 channel times
#      k / 64; textured mode multiplies each texel the same way.
#   3. Texture coordinates (textured): texel column s = u W, row
#      t = (1 - v) H (OBJ's v = 0 is the bottom row), each shifted by the
#      same whole number of texture repeats for the three corners so that
#      the smallest is in [0, 1) repeats; the rasteriser wraps the rest.
#      A corner without vt takes (u, v) = (0, 0).
#   4. Clipping in homogeneous clip space, only where it is needed: a
#      triangle with a corner behind the near plane (clip z >= 0) or beyond
#      the guard band (|x|, |y| <= 16 w, render.inc GUARD_BAND) is cut
#      against each of those planes one of its corners is outside of
#      (Sutherland-Hodgman), the new corners interpolated linearly in clip
#      space (x, y, z, w, s, t, k), and drawn as a fan. The corners'
#      clip-space positions come from vertex.S vertex_clip: the vertex
#      stage's own values, computed again. An edge is always
#      cut from its corner inside towards the one outside, so the two
#      triangles sharing an edge compute bit-identical new corners (no
#      cracks). The screen's own sides are left to the rasteriser's bounding
#      box, the far plane to the depth test (whose clear value is the far
#      plane): the guard band only keeps projected positions small enough
#      to be exact in Q4 and in the attribute planes. Without it, a corner
#      projecting beyond 2^23 pixels would be clamped, bending the triangle.
#   5. raster_triangle: back-face culling (SCENE_CULL), fill, depth test.
#      With antialias = edge each corner also says what lies across the edge
#      opposite it (aa_neighbours, from the adjacency adjacency_build makes at
#      render_init), so that raster_triangle antialiases silhouette edges
#      only; with antialias = supersample render_band draws its band once per
#      sample and takes the means (raster.S).
#
# Wireframe: the mesh's unique edges (each edge shared by two triangles
# once: built at render_init by sorting (min, max) index pairs) are drawn in
# WIRE_COLOUR over the background, without depth test or culling: trivially
# rejected by outcodes, cut at the near plane and the guard band in clip
# space (Liang-Barsky), clipped to the screen and drawn with Bresenham's
# algorithm (raster_segment), by coverage with antialias = edge
# (raster_aa_line), or as their union with antialias = supersample
# (raster_union_line, then raster_union_resolve once all are in).

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"

    .text
    .globl render_init
# render_init
#   What: prepares the renderer once the scene is loaded: vertex records,
#         the texture (textured mode with a texture; else flat fills) and
#         its filtering (with filter = mipmap its mip chain, the last block
#         allocated), and in wireframe mode the unique edge list (and with
#         antialias = supersample the union lines' cells). Running
#         out of heap is fatal (heap_alloc_or_fail).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
render_init:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    sd      s0, 0(sp)
    la      s0, scene
    call    vertex_init
    lwu     t1, SCENE_ANGLES(s0)
    li      t2, ANGLES_TABLE
    bne     t1, t2, 1f
    call    angle_table_build

    # The fill: textured (with a texture) or flat; affine or perspective;
    # Gouraud or one intensity per face.
1:  li      t1, RASTER_FLAT
    lwu     t0, SCENE_SHADING(s0)
    li      t2, SHADING_GOURAUD
    bne     t0, t2, 2f
    ori     t1, t1, RASTER_GOURAUD
2:  lwu     t0, SCENE_MODE(s0)
    li      t2, MODE_TEXTURED
    bne     t0, t2, 3f
    ld      a0, TEX_PIXELS(s0)
    lwu     a1, TEX_W(s0)
    lwu     a2, TEX_H(s0)
    beqz    a0, 3f                      # no texture: flat
    beqz    a1, 3f
    beqz    a2, 3f
    ori     t1, t1, RASTER_TEXTURED
    lwu     t0, SCENE_INTERPOLATION(s0)
    li      t2, INTERP_AFFINE
    bne     t0, t2, 21f
    ori     t1, t1, RASTER_AFFINE
21: lwu     t0, SCENE_FILTER(s0)        # texture filtering
    li      t2, FILTER_BILINEAR
    bne     t0, t2, 22f
    ori     t1, t1, RASTER_BILINEAR
22: li      t2, FILTER_MIPMAP
    bne     t0, t2, 23f
    ori     t1, t1, RASTER_MIPMAP
23: la      t0, render_fill
    sw      t1, 0(t0)
    call    raster_set_texture
    j       31f
3:  la      t0, render_fill
    sw      t1, 0(t0)
31: lwu     t0, SCENE_ANTIALIAS(s0)     # antialias = edge: the coverage fills;
    li      t1, RASTER_EDGE_AA          # supersample: the frame drawn per sample
    li      t2, ANTIALIAS_EDGE
    beq     t0, t2, 32f
    li      t1, RASTER_SUPERSAMPLE
    li      t2, ANTIALIAS_SUPERSAMPLE
    bne     t0, t2, 33f
32: la      t0, render_fill
    lwu     t2, 0(t0)
    or      t2, t2, t1
    sw      t2, 0(t0)
33:

    # The light quantisation: levels - 1 and LIGHT_ONE / (levels - 1).
    la      t0, light_quantum
    flw     ft0, SCENE_LIGHT_LEVELS(s0)
    li      t1, F32_ONE
    fmv.w.x ft1, t1
    fsub.s  ft0, ft0, ft1
    fsw     ft0, LIGHT_QUANTUM_LEVELS(t0)
    li      t1, F32_LIGHT_ONE
    fmv.w.x ft1, t1
    fdiv.s  ft1, ft1, ft0
    fsw     ft1, LIGHT_QUANTUM_STEP(t0)

    lwu     t1, SCENE_MODE(s0)
    li      t2, MODE_WIREFRAME
    bne     t1, t2, 4f
    call    edges_build
    # antialias = supersample: the union lines' cells
    la      t0, render_fill
    lwu     t0, 0(t0)
    andi    t0, t0, RASTER_SUPERSAMPLE
    beqz    t0, 9f
    li      a0, WIRE_BUFFER_BYTES
    la      a1, msg_wire_cells
    call    heap_alloc_or_fail
    call    raster_set_union
    j       9f
    # Triangles: the depth buffer, and the Gouraud intensities of the normals.
4:  li      a0, DEPTH_BUFFER_BYTES
    lwu     t0, SCENE_DEPTH(s0)
    li      t1, DEPTH_INT16
    bne     t0, t1, 5f
    li      a0, DEPTH16_BUFFER_BYTES
5:  la      a1, msg_depth_buffer
    call    heap_alloc_or_fail
    lwu     a1, SCENE_DEPTH(s0)
    call    raster_set_depth
    la      t0, render_fill
    lwu     t0, 0(t0)
    andi    t0, t0, RASTER_GOURAUD
    beqz    t0, 8f
    lwu     a0, MESH_NCOUNT(s0)
    slli    a0, a0, NORMAL_LIGHT_SHIFT
    la      a1, msg_normal_intensities
    call    heap_alloc_or_fail
    la      t0, normal_light
    sd      a0, 0(t0)
    # antialias = edge: what lies across each triangle edge
8:  la      t0, render_fill
    lwu     t0, 0(t0)
    andi    t0, t0, RASTER_EDGE_AA
    beqz    t0, 81f
    call    adjacency_build
    # antialias = supersample: the sums of the samples
81: la      t0, render_fill
    lwu     t0, 0(t0)
    andi    t0, t0, RASTER_SUPERSAMPLE
    beqz    t0, 82f
    li      a0, SUM_BUFFER_BYTES
    la      a1, msg_supersample_sums
    call    heap_alloc_or_fail
    call    raster_set_sums
    # filter = mipmap: the mip chain, built from the texture in memory
82: la      t0, render_fill
    lwu     t0, 0(t0)
    andi    t0, t0, RASTER_MIPMAP
    beqz    t0, 9f
    ld      a0, TEX_PIXELS(s0)
    lwu     a1, TEX_W(s0)
    lwu     a2, TEX_H(s0)
    call    raster_build_mips
9:  ld      s0, 0(sp)
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

    .globl render_frame
# render_frame
#   What: draws frame n of the scene into a framebuffer (file comment), all
#         of it on the calling hart: render_prepare, render_vertex_share of
#         the whole vertex stage, then render_band over the whole screen.
#   Arguments: a0 = framebuffer (LCD_FB_BYTES, 64-aligned), a1 = frame
#              number.
#   Results: none.
#   Clobbers: only ABI temporaries.
render_frame:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    call    render_prepare
    li      a0, 0
    li      a1, 1
    call    render_vertex_share
    li      a0, 0
    li      a1, LCD_HEIGHT
    call    render_band
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

    .globl render_prepare
# render_prepare
#   What: the part of frame n done once, on hart 0, before any other: this
#         frame's matrices (vertex_setup), the vertex records' address into
#         render_vertices and the framebuffer to draw into (raster_begin).
#         Then the vertex stage (render_vertex_share, on one hart or split
#         between both), and once all of it is done, render_band, maybe on
#         both harts at once for disjoint bands. render_prepare must not run
#         again before every band of the frame is drawn (it rewrites what
#         they read).
#   Arguments: a0 = framebuffer (LCD_FB_BYTES, 64-aligned), a1 = frame
#              number.
#   Results: none.
#   Clobbers: only ABI temporaries.
render_prepare:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    sd      s0, 0(sp)
    mv      s0, a0                      # s0 = framebuffer
    mv      a0, a1
    call    vertex_setup
    la      t0, render_vertices
    sd      a0, 0(t0)
    mv      a0, s0
    call    raster_begin
    ld      s0, 0(sp)
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

    .globl render_vertex_share
# render_vertex_share
#   What: share a0 of a1 of frame n's vertex stage, after render_prepare:
#         the vertex records (and flat shading's world positions) of mesh
#         vertices [a0 V / a1, (a0 + 1) V / a1) (vertex_range), and with
#         shading = gouraud the intensities of normals [a0 N / a1,
#         (a0 + 1) N / a1) (normals_light); V, N the mesh's counts. The
#         shares of one frame may run on both harts at once; each item is
#         computed as in one pass over all, so the records are the same
#         however the stage is split. Every share must be done before any
#         render_band of the frame.
#   Arguments: a0 = the share (0 .. a1 - 1), a1 = the number of shares
#              (1 or 2).
#   Results: none.
#   Clobbers: only ABI temporaries.
render_vertex_share:
    addi    sp, sp, -32
    sd      ra, 24(sp)
    sd      s0, 16(sp)
    sd      s1, 8(sp)
    mv      s0, a0                      # s0 = the share
    mv      s1, a1                      # s1 = the number of shares
    la      t0, scene
    lwu     a0, MESH_VCOUNT(t0)
    mv      a1, s0
    mv      a2, s1
    call    share_range
    call    vertex_range
    la      t0, render_fill
    lwu     t0, 0(t0)
    andi    t0, t0, RASTER_GOURAUD
    beqz    t0, 9f
    la      t0, scene
    lwu     a0, MESH_NCOUNT(t0)
    mv      a1, s0
    mv      a2, s1
    call    share_range
    call    normals_light
9:  ld      s1, 8(sp)
    ld      s0, 16(sp)
    ld      ra, 24(sp)
    addi    sp, sp, 32
    ret

# share_range (file-local)
#   What: share a1 of a2 of the items 0 .. a0 - 1: [a1 a0 / a2, (a1 + 1)
#         a0 / a2), so that the shares, in order, cover every item once
#         (whatever a0: odd, smaller than a2, 0).
#   Arguments: a0 = the number of items (< 2^32), a1 = the share, a2 = the
#              number of shares.
#   Results: a0 = first item, a1 = the item past the last.
#   Clobbers: only ABI temporaries.
share_range:
    mul     t0, a0, a1
    divu    t0, t0, a2
    addi    t1, a1, 1
    mul     t1, a0, t1
    divu    a1, t1, a2
    mv      a0, t0
    ret

    .globl render_band
# render_band
#   What: draws rows a0 .. a1 - 1 of the frame render_prepare set up, on
#         the calling hart: those rows cleared, then every triangle's pixels
#         in them (raster_set_band; a triangle whose rows all lie outside
#         is skipped before its lighting and texture set-up: draw_triangles;
#         with antialias = supersample once per sample, cleared each time,
#         the samples summed and their means kept). The pixels
#         are bit for bit those of a whole-screen draw, whichever hart
#         draws which rows. Wireframe: the whole frame, so only ever called
#         with the whole screen (main.S splits triangle modes only).
#   Arguments: a0 = first row, a1 = the row past the last (0 <= a0 <= a1
#              <= LCD_HEIGHT).
#   Results: none.
#   Clobbers: only ABI temporaries.
render_band:
    addi    sp, sp, -112
    sd      ra, 104(sp)
    sd      s0, 96(sp)
    sd      s1, 88(sp)
    sd      s2, 80(sp)
    sd      s3, 72(sp)
    sd      s4, 64(sp)
    sd      s5, 56(sp)
    sd      s6, 48(sp)
    sd      s7, 40(sp)
    sd      s8, 32(sp)
    sd      s9, 24(sp)
    sd      s10, 16(sp)
    sd      s11, 8(sp)
    mv      s0, a0                      # s0 = the band's first row
    mv      s2, a1                      # s2 = the row past its last
    call    raster_set_band
    la      t0, render_vertices
    ld      s1, 0(t0)                   # s1 = vertex records
    la      t1, scene
    lwu     a0, SCENE_BACKGROUND(t1)
    lwu     t0, SCENE_MODE(t1)
    addi    a1, t0, -MODE_WIREFRAME
    snez    a1, a1                      # depth only when not wireframe
    call    raster_clear
    la      t1, scene
    lwu     t0, SCENE_MODE(t1)
    li      t2, MODE_WIREFRAME
    bne     t0, t2, 1f
    mv      a0, s1
    call    render_wireframe
    j       9f
1:  la      t0, render_fill
    lwu     t0, 0(t0)
    andi    t0, t0, RASTER_SUPERSAMPLE
    bnez    t0, 2f
    mv      a0, s0
    mv      a1, s2
    mv      a2, s1
    call    draw_triangles
    j       9f
    # antialias = supersample: the band drawn once per sample, each time
    # cleared, its colours summed; then the sums' means (raster.S)
2:  li      s3, 0                       # s3 = sample
3:  la      t0, supersample_offsets
    slli    t1, s3, SAMPLE_OFFSET_SHIFT
    add     t0, t0, t1
    lw      a0, SAMPLE_OFFSET_X(t0)
    lw      a1, SAMPLE_OFFSET_Y(t0)
    call    raster_set_sample
    beqz    s3, 4f                      # (sample 0's clear is done)
    la      t1, scene
    lwu     a0, SCENE_BACKGROUND(t1)
    li      a1, 1
    call    raster_clear
4:  mv      a0, s0
    mv      a1, s2
    mv      a2, s1
    call    draw_triangles
    li      a0, SAMPLE_FIRST            # the first sample starts the sums,
    beqz    s3, 5f                      # the last leaves the means
    li      a0, SAMPLE_MORE
    li      t0, SUPERSAMPLES - 1
    bne     s3, t0, 5f
    li      a0, SAMPLE_LAST
5:  call    raster_accumulate
    addi    s3, s3, 1
    li      t0, SUPERSAMPLES
    bltu    s3, t0, 3b
    li      a0, 0
    li      a1, 0
    call    raster_set_sample
9:  ld      s11, 8(sp)
    ld      s10, 16(sp)
    ld      s9, 24(sp)
    ld      s8, 32(sp)
    ld      s7, 40(sp)
    ld      s6, 48(sp)
    ld      s5, 56(sp)
    ld      s4, 64(sp)
    ld      s3, 72(sp)
    ld      s2, 80(sp)
    ld      s1, 88(sp)
    ld      s0, 96(sp)
    ld      ra, 104(sp)
    addi    sp, sp, 112
    ret

# draw_triangles (file-local)
#   What: every triangle's pixels in rows a0 .. a1 - 1 (render_band's loop:
#         the file comment's steps; a triangle whose rows all lie outside is
#         skipped before its lighting and texture set-up).
#   Arguments: a0 = first row, a1 = the row past the last, a2 = vertex
#              records.
#   Results: none.
#   Clobbers: only ABI temporaries.
draw_triangles:
    addi    sp, sp, -112
    sd      ra, 104(sp)
    sd      s0, 96(sp)
    sd      s1, 88(sp)
    sd      s2, 80(sp)
    sd      s3, 72(sp)
    sd      s4, 64(sp)
    sd      s5, 56(sp)
    sd      s6, 48(sp)
    sd      s7, 40(sp)
    sd      s8, 32(sp)
    sd      s9, 24(sp)
    sd      s10, 16(sp)
    sd      s11, 8(sp)
    mv      s0, a0                      # s0 = the band's first row
    mv      s2, a1                      # s2 = the row past its last
    mv      s1, a2                      # s1 = vertex records
    la      t1, scene
    ld      s3, MESH_F(t1)              # s3 = face
    lwu     s4, MESH_FCOUNT(t1)         # s4 = faces left
    la      t0, render_fill
    lwu     s10, 0(t0)                  # s10 = RASTER_FLAT / RASTER_TEXTURED
    lwu     s11, SCENE_CULL(t1)         # s11 = cull
    beqz    s4, 9f
2:  # s5, s6, s7 = the corners' vertex records
    ld      t0, 0(s3)
    slli    t0, t0, MESH_INDEX_LOW_SHIFT
    srli    t0, t0, MESH_INDEX_LOW_SHIFT
    ld      t1, MESH_CORNER_BYTES(s3)
    slli    t1, t1, MESH_INDEX_LOW_SHIFT
    srli    t1, t1, MESH_INDEX_LOW_SHIFT
    ld      t2, 2 * MESH_CORNER_BYTES(s3)
    slli    t2, t2, MESH_INDEX_LOW_SHIFT
    srli    t2, t2, MESH_INDEX_LOW_SHIFT
    li      t3, VTX_BYTES
    mul     t0, t0, t3
    add     s5, s1, t0
    mul     t1, t1, t3
    add     s6, s1, t1
    mul     t2, t2, t3
    add     s7, s1, t2
    lw      t0, VTX_OUTCODE(s5)
    lw      t1, VTX_OUTCODE(s6)
    lw      t2, VTX_OUTCODE(s7)
    and     t3, t0, t1
    and     t3, t3, t2
    andi    t3, t3, OUT_FRUSTUM
    bnez    t3, 8f                      # all outside one plane
    or      s8, t0, t1
    or      s8, s8, t2                  # s8 = outcodes of any corner
    # A back face in front of the near plane is dropped before the work on
    # it: the same signed area (from the same Q4 positions) raster_triangle
    # would find.
    beqz    s11, 10f
    andi    t0, s8, OUT_CLIP
    bnez    t0, 1f
    lw      t0, VTX_SX(s5)
    lw      t1, VTX_SY(s5)
    lw      t2, VTX_SX(s6)
    sub     t2, t2, t0
    lw      t3, VTX_SY(s7)
    sub     t3, t3, t1
    mul     t2, t2, t3                  # (x1 - x0)(y2 - y0)
    lw      t3, VTX_SX(s7)
    sub     t3, t3, t0
    lw      t4, VTX_SY(s6)
    sub     t4, t4, t1
    mul     t3, t3, t4                  # (x2 - x0)(y1 - y0)
    bge     t2, t3, 8f                  # area >= 0: back face or degenerate
    # Outside the band: the rows of its pixel centres as raster_triangle
    # finds them (a clipped triangle is left to raster_triangle).
10: andi    t0, s8, OUT_CLIP
    bnez    t0, 1f
    lw      t0, VTX_SY(s5)
    lw      t1, VTX_SY(s6)
    lw      t2, VTX_SY(s7)
    mv      t3, t0                      # t3 = min y
    ble     t3, t1, 11f
    mv      t3, t1
11: ble     t3, t2, 11f
    mv      t3, t2
11: mv      t4, t0                      # t4 = max y
    bge     t4, t1, 11f
    mv      t4, t1
11: bge     t4, t2, 11f
    mv      t4, t2
11: andi    t0, s10, RASTER_EDGE_AA | RASTER_SUPERSAMPLE
    beqz    t0, 12f
    addi    t3, t3, -AA_BOX_GROW        # coverage reaches half a pixel further
    addi    t4, t4, AA_BOX_GROW         # (raster_triangle's grown box), samples
                                        # lie up to 3/8 of a pixel off the centre
12: addi    t3, t3, SUBPIXEL_CEIL       # first row: (min + 7) >> 4
    srai    t3, t3, SUBPIXEL_BITS
    addi    t4, t4, -SUBPIXEL_HALF      # last row: (max - 8) >> 4
    srai    t4, t4, SUBPIXEL_BITS
    blt     t4, s0, 8f
    bge     t3, s2, 8f
1:  andi    t0, s10, RASTER_GOURAUD
    bnez    t0, 20f
    mv      a0, s3
    call    face_light
    mv      s9, a0                      # s9 = intensity, or the lit colour
    andi    t0, s10, RASTER_TEXTURED
    bnez    t0, 3f
    mv      a1, a0
    li      a0, FLAT_BASE_COLOUR
    call    shade_rgb565
    mv      s9, a0
    j       4f
20: mv      a0, s3                      # Gouraud: RV_K of render_rv
    call    corner_light
    li      s9, FLAT_BASE_COLOUR        # (flat fill: lit per pixel)
    andi    t0, s10, RASTER_TEXTURED
    beqz    t0, 4f
3:  mv      a0, s3
    call    face_texels                 # RV_S, RV_T of render_rv
4:  andi    t0, s8, OUT_CLIP
    bnez    t0, 6f
    # in front of the near plane and inside the guard band: the vertex
    # records' projections
    la      a0, render_rv
    add     a0, a0, tp
    mv      t0, a0
    mv      t1, s5                      # t1 = corner 0, then t4, then t5
    mv      t4, s6
    mv      t5, s7
    li      t2, TRIANGLE_CORNERS
5:  lw      t3, VTX_SX(t1)
    sw      t3, RV_X(t0)
    lw      t3, VTX_SY(t1)
    sw      t3, RV_Y(t0)
    lw      t3, VTX_ZW(t1)
    sw      t3, RV_Z(t0)
    lw      t3, VTX_Q(t1)
    sw      t3, RV_Q(t0)
    addi    t0, t0, RV_BYTES
    mv      t1, t4
    mv      t4, t5
    addi    t2, t2, -1
    bnez    t2, 5b
    andi    t0, s10, RASTER_EDGE_AA
    beqz    t0, 7f
    mv      a0, s3
    mv      a1, s1
    la      a2, render_rv
    add     a2, a2, tp
    call    aa_neighbours
7:  la      a0, render_rv
    add     a0, a0, tp
    mv      a1, s11
    mv      a2, s9
    mv      a3, s10
    call    raster_triangle
    j       8f
    # cut in clip space: drawn hard (the fan's corners carry no neighbours)
6:  mv      a0, s3
    mv      a3, s11
    mv      a4, s9
    andi    a5, s10, ~RASTER_EDGE_AA
    mv      a6, s8
    call    clip_and_draw
8:  addi    s3, s3, MESH_F_BYTES
    addi    s4, s4, -1
    bnez    s4, 2b

9:  ld      s11, 8(sp)
    ld      s10, 16(sp)
    ld      s9, 24(sp)
    ld      s8, 32(sp)
    ld      s7, 40(sp)
    ld      s6, 48(sp)
    ld      s5, 56(sp)
    ld      s4, 64(sp)
    ld      s3, 72(sp)
    ld      s2, 80(sp)
    ld      s1, 88(sp)
    ld      s0, 96(sp)
    ld      ra, 104(sp)
    addi    sp, sp, 112
    ret

    .globl shade_rgb565
# shade_rgb565
#   What: an RGB565 colour with each channel multiplied by k / 64 and
#         rounded to nearest (ties up; the lit fills do the same inline): c is spread over 64 bits so
#         that one multiplication scales R, G and B (RGB565_SPREAD_MASK).
#   Arguments: a0 = colour, a1 = k (0 .. LIGHT_ONE).
#   Results: a0 = lit colour.
#   Clobbers: only ABI temporaries.
shade_rgb565:
    li      t0, RGB565_SPREAD_MASK
    slli    t1, a0, RGB565_SPREAD_SHIFT
    or      a0, a0, t1
    and     a0, a0, t0
    mul     a0, a0, a1
    li      t1, LIGHT_ROUND_SPREAD
    add     a0, a0, t1                  # rounded to nearest
    srli    a0, a0, LIGHT_SHIFT
    and     a0, a0, t0
    srli    t1, a0, RGB565_SPREAD_SHIFT
    or      a0, a0, t1
    slli    a0, a0, 48
    srli    a0, a0, 48
    ret

# face_light (file-local)
#   What: the face's light intensity (file comment, step 2), from its
#         corners' world-space positions: the vertex stage's
#         (vertex_world_array, flat shading) or, where it keeps none,
#         computed (face_world).
#   Arguments: a0 = the face (MESH_F_BYTES).
#   Results: a0 = k, 0 .. LIGHT_ONE; fa0 = the same before rounding to a
#            whole k (light_level).
#   Clobbers: only ABI temporaries.
    .equ FACE_LIGHT_CORNERS,    16          # stack: N and |N| below, then the corners'
    .equ FACE_LIGHT_WORLD,      40          # world positions' addresses, then the positions
    .equ FACE_LIGHT_FRAME,      96          # when computed here, then ra
.if FACE_LIGHT_CORNERS + TRIANGLE_CORNERS * 8 > FACE_LIGHT_WORLD
    .error "face_light's stack frame is too small"
.endif
.if FACE_LIGHT_WORLD + TRIANGLE_CORNERS * WORLD_POS_BYTES > FACE_LIGHT_FRAME - 8
    .error "face_light's stack frame is too small"
.endif
face_light:
    addi    sp, sp, -FACE_LIGHT_FRAME
    sd      ra, FACE_LIGHT_FRAME - 8(sp)
    la      t0, vertex_world_array
    ld      t0, 0(t0)
    beqz    t0, 2f
    li      t1, WORLD_POS_BYTES         # kept: their addresses in the array
    addi    t2, sp, FACE_LIGHT_CORNERS
    addi    t3, a0, TRIANGLE_CORNERS * MESH_CORNER_BYTES
1:  ld      t4, 0(a0)
    slli    t4, t4, MESH_INDEX_LOW_SHIFT
    srli    t4, t4, MESH_INDEX_LOW_SHIFT
    mul     t4, t4, t1
    add     t4, t4, t0
    sd      t4, 0(t2)
    addi    a0, a0, MESH_CORNER_BYTES
    addi    t2, t2, 8
    bne     a0, t3, 1b
    j       3f
2:  addi    a1, sp, FACE_LIGHT_WORLD    # not kept: computed into the frame
    call    face_world
    addi    t0, sp, FACE_LIGHT_WORLD
    sd      t0, FACE_LIGHT_CORNERS(sp)
    addi    t0, t0, WORLD_POS_BYTES
    sd      t0, FACE_LIGHT_CORNERS + 8(sp)
    addi    t0, t0, WORLD_POS_BYTES
    sd      t0, FACE_LIGHT_CORNERS + 16(sp)
3:  ld      a0, FACE_LIGHT_CORNERS + 16(sp)
    ld      a1, FACE_LIGHT_CORNERS(sp)
    call    vec3_sub                    # w2 - w0
    fmv.s   fa3, fa0
    fmv.s   fa4, fa1
    fmv.s   fa5, fa2
    ld      a0, FACE_LIGHT_CORNERS + 8(sp)
    ld      a1, FACE_LIGHT_CORNERS(sp)
    call    vec3_sub                    # w1 - w0
    call    vec3_cross                  # N
    fsw     fa0, 0(sp)
    fsw     fa1, 4(sp)
    fsw     fa2, 8(sp)
    call    vec3_length
    fsw     fa0, 12(sp)                 # |N|
    flw     fa0, 0(sp)
    flw     fa1, 4(sp)
    flw     fa2, 8(sp)
    la      t0, scene
    flw     fa3, SCENE_LIGHT(t0)
    flw     fa4, SCENE_LIGHT + 4(t0)
    flw     fa5, SCENE_LIGHT + 8(t0)
    call    vec3_dot                    # N . L
    flw     ft0, 12(sp)
    fdiv.s  fa0, fa0, ft0               # cos; NaN when |N| = 0
    call    light_level
    ld      ra, FACE_LIGHT_FRAME - 8(sp)
    addi    sp, sp, FACE_LIGHT_FRAME
    ret

# light_level (file-local)
#   What: the intensity of a surface whose normal makes an angle with the
#         light: I = max(SCENE_AMBIENT, cos), quantised to SCENE_LIGHT_LEVELS
#         evenly spaced levels from 0 to 1 (level = round(I (levels - 1))),
#         in units of 1 / LIGHT_ONE: kf = level (LIGHT_ONE / (levels - 1))
#         (light_quantum, set by render_init). With 65, 33, 17, 9, 5, 3 or 2
#         levels the step is exact; with 65 (the default) kf = round(64 I).
#   Arguments: fa0 = cos (NaN, for a zero normal, gives the ambient).
#   Results: fa0 = kf; a0 = kf rounded to a whole k, 0 .. LIGHT_ONE.
#   Clobbers: only ft0..ft2, t0 and t1 (normals_light keeps its matrix in
#         the other temporaries).
light_level:
    la      t0, scene
    flw     ft1, SCENE_AMBIENT(t0)
    fmax.s  fa0, fa0, ft1               # (fmax of NaN and ambient = ambient)
    la      t0, light_quantum
    flw     ft1, LIGHT_QUANTUM_LEVELS(t0)   # levels - 1
    fmul.s  fa0, fa0, ft1
    fcvt.w.s t1, fa0, rne               # the level
    fcvt.s.w fa0, t1
    flw     ft1, LIGHT_QUANTUM_STEP(t0)     # LIGHT_ONE / (levels - 1)
    fmul.s  fa0, fa0, ft1               # kf
    fmv.w.x ft2, zero                   # 0 <= kf <= LIGHT_ONE (cos just above 1)
    fmax.s  fa0, fa0, ft2
    li      t1, F32_LIGHT_ONE
    fmv.w.x ft2, t1
    fmin.s  fa0, fa0, ft2
    fcvt.w.s a0, fa0, rne
    ret

# corner_light (file-local)
#   What: Gouraud: the intensity of each corner of a face into RV_K of the
#         three records of render_rv: normal_light of the corner's vn, or,
#         when any corner has none, the face's own intensity (face_light)
#         at all three, so that a model without normals looks as with flat
#         shading.
#   Arguments: a0 = the face (MESH_F_BYTES).
#   Results: none.
#   Clobbers: only ABI temporaries.
corner_light:
    la      t0, scene
    lwu     t1, MESH_NCOUNT(t0)         # (MESH_NO_INDEX is past any count)
    ld      t2, 0(a0)
    srli    t2, t2, MESH_CORNER_N_SHIFT
    bgeu    t2, t1, 2f
    ld      t3, MESH_CORNER_BYTES(a0)
    srli    t3, t3, MESH_CORNER_N_SHIFT
    bgeu    t3, t1, 2f
    ld      t4, 2 * MESH_CORNER_BYTES(a0)
    srli    t4, t4, MESH_CORNER_N_SHIFT
    bgeu    t4, t1, 2f
    la      t0, normal_light
    ld      t0, 0(t0)
    la      t1, render_rv
    add     t1, t1, tp
    slli    t2, t2, NORMAL_LIGHT_SHIFT
    add     t2, t2, t0
    lw      t2, 0(t2)
    sw      t2, RV_K(t1)
    slli    t3, t3, NORMAL_LIGHT_SHIFT
    add     t3, t3, t0
    lw      t3, 0(t3)
    sw      t3, RV_BYTES + RV_K(t1)
    slli    t4, t4, NORMAL_LIGHT_SHIFT
    add     t4, t4, t0
    lw      t4, 0(t4)
    sw      t4, 2 * RV_BYTES + RV_K(t1)
    ret
2:  addi    sp, sp, -16
    sd      ra, 8(sp)
    call    face_light                  # (a0 is still the face)
    la      t1, render_rv
    add     t1, t1, tp
    fsw     fa0, RV_K(t1)
    fsw     fa0, RV_BYTES + RV_K(t1)
    fsw     fa0, 2 * RV_BYTES + RV_K(t1)
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

# normals_light (file-local)
#   What: Gouraud: this frame's intensity of mesh normals a0 .. a1 - 1 into
#         normal_light: n' = R C n, with R the frame's rotation
#         (vertex_rotation) and C = diag(sy sz, sx sz, sx sy) the cofactor
#         matrix of the scale (det(S) S^-T: normals stay perpendicular to
#         the scaled surface, and a zero scale gives a zero normal, hence
#         the ambient), then light_level(n' . L / |n'|).
#   Arguments: a0 = first normal, a1 = the normal past the last (0 <= a0
#              <= a1 <= MESH_NCOUNT).
#   Results: none.
#   Clobbers: only ABI temporaries. The loop keeps M = R C in ft3..ft11
#         and L in fa4..fa6.
normals_light:
    addi    sp, sp, -32
    sd      ra, 24(sp)
    sd      s0, 16(sp)
    sd      s1, 8(sp)
    sd      s2, 0(sp)
    sub     s1, a1, a0                  # s1 = normals left
    beqz    s1, 9f
    la      t0, scene
    ld      s0, MESH_N(t0)
    li      t1, MESH_N_BYTES
    mul     t1, t1, a0
    add     s0, s0, t1                  # s0 = normal
    la      t1, normal_light
    ld      s2, 0(t1)
    slli    t1, a0, NORMAL_LIGHT_SHIFT
    add     s2, s2, t1                  # s2 = its intensity
    flw     fa0, SCENE_SCALE(t0)        # C = fa1, fa2, fa3
    flw     fa1, SCENE_SCALE + 4(t0)
    flw     fa2, SCENE_SCALE + 8(t0)
    fmul.s  fa3, fa0, fa1               # sx sy
    fmul.s  fa1, fa1, fa2               # sy sz
    fmul.s  fa2, fa0, fa2               # sx sz
    flw     fa4, SCENE_LIGHT(t0)
    flw     fa5, SCENE_LIGHT + 4(t0)
    flw     fa6, SCENE_LIGHT + 8(t0)
    la      t1, vertex_rotation         # M = R C: column c of R times C[c]
    flw     ft3, 0(t1)
    fmul.s  ft3, ft3, fa1
    flw     ft4, 4(t1)
    fmul.s  ft4, ft4, fa2
    flw     ft5, 8(t1)
    fmul.s  ft5, ft5, fa3
    flw     ft6, 12(t1)
    fmul.s  ft6, ft6, fa1
    flw     ft7, 16(t1)
    fmul.s  ft7, ft7, fa2
    flw     ft8, 20(t1)
    fmul.s  ft8, ft8, fa3
    flw     ft9, 24(t1)
    fmul.s  ft9, ft9, fa1
    flw     ft10, 28(t1)
    fmul.s  ft10, ft10, fa2
    flw     ft11, 32(t1)
    fmul.s  ft11, ft11, fa3
1:  flw     ft0, 0(s0)
    flw     ft1, 4(s0)
    flw     ft2, 8(s0)
    fmul.s  fa0, ft3, ft0               # n' = M n
    fmadd.s fa0, ft4, ft1, fa0
    fmadd.s fa0, ft5, ft2, fa0
    fmul.s  fa1, ft6, ft0
    fmadd.s fa1, ft7, ft1, fa1
    fmadd.s fa1, ft8, ft2, fa1
    fmul.s  fa2, ft9, ft0
    fmadd.s fa2, ft10, ft1, fa2
    fmadd.s fa2, ft11, ft2, fa2
    fmul.s  fa3, fa0, fa0               # |n'|
    fmadd.s fa3, fa1, fa1, fa3
    fmadd.s fa3, fa2, fa2, fa3
    fsqrt.s fa3, fa3
    fmul.s  fa0, fa0, fa4               # n' . L / |n'| (NaN when n' = 0)
    fmadd.s fa0, fa1, fa5, fa0
    fmadd.s fa0, fa2, fa6, fa0
    fdiv.s  fa0, fa0, fa3
    call    light_level
    fsw     fa0, 0(s2)
    addi    s0, s0, MESH_N_BYTES
    addi    s2, s2, NORMAL_LIGHT_BYTES
    addi    s1, s1, -1
    bnez    s1, 1b
9:  ld      s2, 0(sp)
    ld      s1, 8(sp)
    ld      s0, 16(sp)
    ld      ra, 24(sp)
    addi    sp, sp, 32
    ret

# face_texels (file-local)
#   What: the texel coordinates of a face's three corners (file comment,
#         step 3) into RV_S and RV_T of the three records of render_rv.
#   Arguments: a0 = the face (MESH_F_BYTES).
#   Results: none.
#   Clobbers: only ABI temporaries.
face_texels:
    la      t0, scene
    ld      t1, MESH_T(t0)              # t1 = vt array
    lwu     t2, MESH_TCOUNT(t0)         # t2 = vt count
    la      t3, render_rv
    add     t3, t3, tp
    li      t4, TRIANGLE_CORNERS
    li      t5, F32_ONE
    fmv.w.x ft3, t5                     # ft3 = 1
1:  ld      t5, 0(a0)
    slli    t5, t5, MESH_INDEX_MID_SHIFT
    srli    t5, t5, MESH_INDEX_LOW_SHIFT  # the vt index (MESH_NO_INDEX is past any count)
    fmv.w.x ft0, zero                   # no vt (or out of range): (0, 0)
    fmv.w.x ft1, zero
    bgeu    t5, t2, 2f
    slli    t5, t5, 3                   # MESH_T_BYTES
    add     t5, t5, t1
    flw     ft0, 0(t5)
    flw     ft1, 4(t5)
2:  fsub.s  ft1, ft3, ft1               # 1 - v
    fsw     ft0, RV_S(t3)
    fsw     ft1, RV_T(t3)
    addi    a0, a0, MESH_CORNER_BYTES
    addi    t3, t3, RV_BYTES
    addi    t4, t4, -1
    bnez    t4, 1b
    # shift by whole repeats: the smallest of each into [0, 1), then scale
    la      t3, render_rv
    add     t3, t3, tp
    flw     ft0, RV_S(t3)
    flw     ft1, RV_S + RV_BYTES(t3)
    flw     ft2, RV_S + 2 * RV_BYTES(t3)
    fmin.s  ft4, ft0, ft1
    fmin.s  ft4, ft4, ft2
    fcvt.l.s t5, ft4, rdn
    fcvt.s.l ft4, t5                    # floor of the smallest
    lwu     t5, TEX_W(t0)
    fcvt.s.w ft5, t5
    fsub.s  ft0, ft0, ft4
    fmul.s  ft0, ft0, ft5
    fsw     ft0, RV_S(t3)
    fsub.s  ft1, ft1, ft4
    fmul.s  ft1, ft1, ft5
    fsw     ft1, RV_S + RV_BYTES(t3)
    fsub.s  ft2, ft2, ft4
    fmul.s  ft2, ft2, ft5
    fsw     ft2, RV_S + 2 * RV_BYTES(t3)
    flw     ft0, RV_T(t3)
    flw     ft1, RV_T + RV_BYTES(t3)
    flw     ft2, RV_T + 2 * RV_BYTES(t3)
    fmin.s  ft4, ft0, ft1
    fmin.s  ft4, ft4, ft2
    fcvt.l.s t5, ft4, rdn
    fcvt.s.l ft4, t5
    lwu     t5, TEX_H(t0)
    fcvt.s.w ft5, t5
    fsub.s  ft0, ft0, ft4
    fmul.s  ft0, ft0, ft5
    fsw     ft0, RV_T(t3)
    fsub.s  ft1, ft1, ft4
    fmul.s  ft1, ft1, ft5
    fsw     ft1, RV_T + RV_BYTES(t3)
    fsub.s  ft2, ft2, ft4
    fmul.s  ft2, ft2, ft5
    fsw     ft2, RV_T + 2 * RV_BYTES(t3)
    ret

# clip_and_draw (file-local)
#   What: a triangle with a corner behind the near plane or beyond the guard
#         band (file comment, step 4): cut in clip space against each plane
#         one of its corners is outside of, projected, and drawn as a fan of
#         triangles (0, 1, 2), then (i, i + 1, 0) for i = 2, 3, ...
#   Arguments: a0 = the face (its texel coordinates and intensities in
#              render_rv), a3 = cull, a4 = colour or
#              intensity, a5 = fill mode (raster_triangle's a1..a3), a6 =
#              the corners' outcodes ORed.
#   Results: none.
#   Clobbers: only ABI temporaries.
clip_and_draw:
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
    mv      s3, a3
    mv      s4, a4
    mv      s5, a5
    mv      s6, a6                      # s6 = outcodes
    # the corners as clip vertices: clip-space positions (vertex_clip, as
    # the vertex stage found them), texel coordinates and intensities
    mv      s0, a0                      # s0 = corner
    la      s1, clip_polygon_a          # s1 = its clip vertex
    add     s1, s1, tp
    la      s2, render_rv               # s2 = its raster vertex
    add     s2, s2, tp
    li      s7, TRIANGLE_CORNERS
1:  ld      a0, 0(s0)
    slli    a0, a0, MESH_INDEX_LOW_SHIFT
    srli    a0, a0, MESH_INDEX_LOW_SHIFT
    addi    a1, s1, CV_X
    call    vertex_clip
    lw      t3, RV_S(s2)
    sw      t3, CV_S(s1)
    lw      t3, RV_T(s2)
    sw      t3, CV_T(s1)
    lw      t3, RV_K(s2)
    sw      t3, CV_K(s1)
    addi    s0, s0, MESH_CORNER_BYTES
    addi    s1, s1, CV_BYTES
    addi    s2, s2, RV_BYTES
    addi    s7, s7, -1
    bnez    s7, 1b

    # each plane in turn, the output of one the input of the next
    la      s0, clip_polygon_a          # s0 = the polygon
    add     s0, s0, tp
    la      s1, clip_polygon_b          # s1 = the other buffer
    add     s1, s1, tp
    li      s2, TRIANGLE_CORNERS        # s2 = its corners
    li      s7, 0                       # s7 = plane number (clip_planes)
2:  mv      a0, s7
    mv      a1, s6
    call    clip_plane
    beqz    a0, 4f                      # no corner outside: nothing to cut
    mv      a3, a0
    mv      a0, s0
    mv      a1, s2
    mv      a2, s1
    call    clip_polygon
    mv      s2, a0
    mv      t0, s0
    mv      s0, s1
    mv      s1, t0
    li      t0, TRIANGLE_CORNERS
    blt     s2, t0, 9f                  # nothing left
4:  addi    s7, s7, 1
    li      t0, CLIP_PLANES
    bne     s7, t0, 2b

    # project the corners into render_rv_out
    mv      s7, s2                      # s7 = corners left
    la      s1, render_rv_out
    add     s1, s1, tp
5:  flw     fa0, CV_X(s0)
    flw     fa1, CV_Y(s0)
    flw     fa2, CV_Z(s0)
    flw     fa3, CV_W(s0)
    call    project_clip
    sw      a0, RV_X(s1)
    sw      a1, RV_Y(s1)
    fsw     fa0, RV_Z(s1)
    fsw     fa1, RV_Q(s1)
    lw      t1, CV_S(s0)
    sw      t1, RV_S(s1)
    lw      t1, CV_T(s0)
    sw      t1, RV_T(s1)
    lw      t1, CV_K(s0)
    sw      t1, RV_K(s1)
    addi    s0, s0, CV_BYTES
    addi    s1, s1, RV_BYTES
    addi    s7, s7, -1
    bnez    s7, 5b

    # the fan
    la      a0, render_rv_out
    add     a0, a0, tp
    mv      a1, s3
    mv      a2, s4
    mv      a3, s5
    call    raster_triangle             # corners 0, 1, 2
    li      s7, 2                       # s7 = i
6:  addi    t0, s7, 2
    bgt     t0, s2, 9f                  # i + 1 is past the last corner
    la      a0, render_rv_fan
    add     a0, a0, tp
    li      t0, RV_BYTES
    mul     t0, t0, s7
    la      a1, render_rv_out
    add     a1, a1, tp
    add     a1, a1, t0
    li      a2, 2 * RV_BYTES
    call    rv_copy                     # corners i, i + 1
    la      a0, render_rv_fan + 2 * RV_BYTES
    add     a0, a0, tp
    la      a1, render_rv_out
    add     a1, a1, tp
    li      a2, RV_BYTES
    call    rv_copy                     # corner 0
    la      a0, render_rv_fan
    add     a0, a0, tp
    mv      a1, s3
    mv      a2, s4
    mv      a3, s5
    call    raster_triangle
    addi    s7, s7, 1
    j       6b
9:  ld      s7, 8(sp)
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

# clip_polygon (file-local)
#   What: one Sutherland-Hodgman step: the part of a convex polygon inside
#         one clip plane. For each edge a -> b: a when it is inside, then
#         the crossing point when exactly one of a, b is, always cut from the
#         inside corner towards the outside one, so that two triangles
#         sharing an edge cut it into bit-identical corners (no cracks). A
#         cut on the near plane gets z = 0 exactly (its depth is the near
#         plane's).
#   Arguments: a0 = corners (clip vertices), a1 = their count (at least
#              3), a2 = output (room for a1 + a1 / 2: see CLIP_MAX_OUT),
#              a3 = the plane (in clip_planes, whose first is the near
#              plane).
#   Results: a0 = the output's corner count.
#   Clobbers: only ABI temporaries.
clip_polygon:
    addi    sp, sp, -96
    sd      ra, 88(sp)
    sd      s0, 80(sp)
    sd      s1, 72(sp)
    sd      s2, 64(sp)
    sd      s3, 56(sp)
    sd      s4, 48(sp)
    sd      s5, 40(sp)
    sd      s6, 32(sp)
    sd      s7, 24(sp)
    sd      s8, 16(sp)
    fsd     fs0, 8(sp)
    fsd     fs1, 0(sp)
    mv      s0, a0                      # s0 = a
    mv      s1, a2                      # s1 = next output
    mv      s2, a2                      # s2 = output start
    li      t0, CV_BYTES
    mul     t0, t0, a1
    add     s3, a0, t0                  # s3 = end of the corners
    mv      s4, a0                      # s4 = first corner (b of the last edge)
    mv      s5, a3                      # s5 = plane
    la      s6, clip_planes             # s6 = the near plane
    mv      a1, s5
    call    plane_distance
    fmv.s   fs0, fa0                    # fs0 = d(a)
1:  addi    s7, s0, CV_BYTES            # s7 = b
    bltu    s7, s3, 2f
    mv      s7, s4
2:  mv      a0, s7
    mv      a1, s5
    call    plane_distance
    fmv.s   fs1, fa0                    # fs1 = d(b)
    fmv.w.x ft0, zero
    fle.s   s8, ft0, fs0                # s8 = a inside
    beqz    s8, 3f
    mv      a0, s1
    mv      a1, s0
    call    cv_copy
    addi    s1, s1, CV_BYTES
3:  fmv.w.x ft0, zero
    fle.s   t1, ft0, fs1                # b inside
    beq     s8, t1, 5f                  # both on the same side
    mv      a1, s0                      # cut from the corner inside
    mv      a2, s7
    fmv.s   fa0, fs0
    fmv.s   fa1, fs1
    bnez    s8, 4f
    mv      a1, s7
    mv      a2, s0
    fmv.s   fa0, fs1
    fmv.s   fa1, fs0
4:  mv      a0, s1
    call    cv_cut
    bne     s5, s6, 41f
    sw      zero, CV_Z(s1)              # on the near plane
41: addi    s1, s1, CV_BYTES
5:  fmv.s   fs0, fs1                    # b is the next edge's a
    addi    s0, s0, CV_BYTES
    bltu    s0, s3, 1b
    sub     a0, s1, s2
    li      t0, CV_BYTES
    divu    a0, a0, t0
    fld     fs1, 0(sp)
    fld     fs0, 8(sp)
    ld      s8, 16(sp)
    ld      s7, 24(sp)
    ld      s6, 32(sp)
    ld      s5, 40(sp)
    ld      s4, 48(sp)
    ld      s3, 56(sp)
    ld      s2, 64(sp)
    ld      s1, 72(sp)
    ld      s0, 80(sp)
    ld      ra, 88(sp)
    addi    sp, sp, 96
    ret

# clip_plane (file-local)
#   What: plane n of clip_planes if a shape with these corners must be cut
#         against it: the near plane (n = 0) when a corner is behind it
#         (OUT_NEAR), a side of the guard band (n = 1 .. 4) when a corner is
#         beyond the band (OUT_GUARD).
#   Arguments: a0 = n, a1 = the corners' outcodes ORed.
#   Results: a0 = the plane's address, or 0 when no corner is outside it.
#   Clobbers: only ABI temporaries.
clip_plane:
    li      t0, OUT_NEAR
    beqz    a0, 1f
    li      t0, OUT_GUARD
1:  and     t0, t0, a1
    beqz    t0, 2f
    li      t0, PLANE_BYTES
    mul     t0, t0, a0
    la      a0, clip_planes
    add     a0, a0, t0
    ret
2:  li      a0, 0
    ret

# plane_distance (file-local)
#   What: d = a x + b y + c z + e w of a clip-space point and a plane of
#         clip_planes; the point is inside when d >= 0. For the near plane
#         d is z itself, exactly (the other products are 0).
#   Arguments: a0 = clip vertex or clip-space position (vertex_clip's:
#              both begin with clip x, y, z, w), a1 = plane.
#   Results: fa0 = d.
#   Clobbers: only ABI temporaries.
.if (CV_X != CLIP_POS_X) || (CV_Y != CLIP_POS_Y) || (CV_Z != CLIP_POS_Z) || (CV_W != CLIP_POS_W)
    .error "plane_distance reads clip vertices and clip-space positions alike"
.endif
plane_distance:
    flw     ft0, PLANE_E(a1)
    flw     ft1, CV_W(a0)
    fmul.s  fa0, ft0, ft1
    flw     ft0, PLANE_C(a1)
    flw     ft1, CV_Z(a0)
    fmadd.s fa0, ft0, ft1, fa0
    flw     ft0, PLANE_B(a1)
    flw     ft1, CV_Y(a0)
    fmadd.s fa0, ft0, ft1, fa0
    flw     ft0, PLANE_A(a1)
    flw     ft1, CV_X(a0)
    fmadd.s fa0, ft0, ft1, fa0
    ret

# cv_copy (file-local)
#   What: copies one clip vertex.
#   Arguments: a0 = destination, a1 = source.
#   Results: none.
#   Clobbers: only ABI temporaries.
cv_copy:
    li      a2, CV_BYTES
# rv_copy (file-local)
#   What: copies a2 bytes (a multiple of 4).
#   Arguments: a0 = destination, a1 = source, a2 = bytes.
#   Results: none.
#   Clobbers: only ABI temporaries.
rv_copy:
1:  lw      t5, 0(a1)
    sw      t5, 0(a0)
    addi    a0, a0, 4
    addi    a1, a1, 4
    addi    a2, a2, -4
    bnez    a2, 1b
    ret

# cv_cut (file-local)
#   What: the point where the segment from p (inside a clip plane) to q
#         (outside it) crosses the plane: p + t (q - p), t = dp / (dp - dq),
#         every field interpolated.
#   Arguments: a0 = output clip vertex, a1 = p, a2 = q; fa0, fa1 = the
#              plane distances dp, dq (plane_distance).
#   Results: none.
#   Clobbers: only ABI temporaries.
cv_cut:
    fsub.s  ft1, fa0, fa1
    fdiv.s  ft0, fa0, ft1               # ft0 = t
    li      t0, CV_BYTES / 4
1:  flw     ft1, 0(a1)
    flw     ft2, 0(a2)
    fsub.s  ft2, ft2, ft1
    fmadd.s ft1, ft2, ft0, ft1
    fsw     ft1, 0(a0)
    addi    a0, a0, 4
    addi    a1, a1, 4
    addi    a2, a2, 4
    addi    t0, t0, -1
    bnez    t0, 1b
    ret

# render_wireframe (file-local)
#   What: draws the unique edge list (file comment).
#   Arguments: a0 = vertex records.
#   Results: none.
#   Clobbers: only ABI temporaries.
render_wireframe:
    addi    sp, sp, -64
    sd      ra, 56(sp)
    sd      s0, 48(sp)
    sd      s1, 40(sp)
    sd      s2, 32(sp)
    sd      s3, 24(sp)
    sd      s4, 16(sp)
    mv      s0, a0                      # s0 = vertex records
    la      t0, edge_list
    ld      s1, 0(t0)                   # s1 = edge
    la      t0, edge_count
    ld      s2, 0(t0)                   # s2 = edges left
    beqz    s2, 9f
1:  ld      t0, 0(s1)
    srli    t1, t0, EDGE_INDEX_SHIFT    # smaller index
    slli    t0, t0, EDGE_INDEX_SHIFT
    srli    t0, t0, EDGE_INDEX_SHIFT    # larger index
    li      t2, VTX_BYTES
    mul     t1, t1, t2
    add     s3, s0, t1                  # s3 = a
    mul     t0, t0, t2
    add     s4, s0, t0                  # s4 = b
    lw      t0, VTX_OUTCODE(s3)
    lw      t1, VTX_OUTCODE(s4)
    and     t2, t0, t1
    andi    t2, t2, OUT_FRUSTUM
    bnez    t2, 8f                      # both outside one plane
    or      a2, t0, t1
    andi    t2, a2, OUT_CLIP
    beqz    t2, 3f
    # an end behind the near plane or beyond the guard band: cut in clip
    # space (the ends' positions from vertex_clip), from the end in front
    # of the near plane when one is behind
    mv      s3, a2                      # s3 = outcodes ORed
    ld      t1, 0(s1)
    srli    a0, t1, EDGE_INDEX_SHIFT    # a0 = a, a1 = b
    slli    a1, t1, EDGE_INDEX_SHIFT
    srli    a1, a1, EDGE_INDEX_SHIFT
    andi    t0, t0, OUT_NEAR
    beqz    t0, 2f
    mv      t0, a0
    mv      a0, a1
    mv      a1, t0
2:  mv      s4, a1
    la      a1, segment_ends
    add     a1, a1, tp
    call    vertex_clip
    mv      a0, s4
    la      a1, segment_ends + CLIP_POS_BYTES
    add     a1, a1, tp
    call    vertex_clip
    la      a0, segment_ends
    add     a0, a0, tp
    la      a1, segment_ends + CLIP_POS_BYTES
    add     a1, a1, tp
    mv      a2, s3
    call    clip_segment
    beqz    a0, 8f                      # nothing left
    mv      a0, a1
    mv      a1, a2
    mv      a2, a3
    mv      a3, a4
    j       4f
3:  lw      a0, VTX_SX(s3)
    lw      a1, VTX_SY(s3)
    lw      a2, VTX_SX(s4)
    lw      a3, VTX_SY(s4)
4:  li      t0, F32_Q4_TO_PIXEL         # Q4 to pixels
    fmv.w.x ft0, t0
    fcvt.s.w fa0, a0
    fmul.s  fa0, fa0, ft0
    fcvt.s.w fa1, a1
    fmul.s  fa1, fa1, ft0
    fcvt.s.w fa2, a2
    fmul.s  fa2, fa2, ft0
    fcvt.s.w fa3, a3
    fmul.s  fa3, fa3, ft0
    li      a0, WIRE_COLOUR
    la      t0, scene                   # antialias: lines by coverage, or
    lwu     t0, SCENE_ANTIALIAS(t0)     # (supersample) their union's
    li      t1, ANTIALIAS_SUPERSAMPLE
    beq     t0, t1, 6f
    li      t1, ANTIALIAS_OFF
    beq     t0, t1, 5f
    call    raster_aa_line
    j       8f
6:  call    raster_union_line
    j       8f
5:  call    raster_segment
8:  addi    s1, s1, EDGE_BYTES
    addi    s2, s2, -1
    bnez    s2, 1b
9:  la      t1, scene                   # supersample: the union drawn
    lwu     t0, SCENE_ANTIALIAS(t1)
    li      t2, ANTIALIAS_SUPERSAMPLE
    bne     t0, t2, 10f
    li      a0, WIRE_COLOUR
    lwu     a1, SCENE_BACKGROUND(t1)
    call    raster_union_resolve
10: ld      s4, 16(sp)
    ld      s3, 24(sp)
    ld      s2, 32(sp)
    ld      s1, 40(sp)
    ld      s0, 48(sp)
    ld      ra, 56(sp)
    addi    sp, sp, 64
    ret

# clip_segment (file-local)
#   What: the part of an edge a -> b in front of the near plane and inside
#         the guard band (Liang-Barsky in clip space, against the planes an
#         end is outside of: t from 0 to 1 narrowed at each crossing), its
#         ends projected (project_clip). An end that is not cut off is the
#         vertex itself, exactly.
#   Arguments: a0 = a's clip-space position (CLIP_POS_BYTES), a1 = b's,
#              a2 = their outcodes ORed.
#   Results: a0 = 1 when a part is left, else 0; then a1, a2 = its end
#            towards a (screen x, y in Q4), a3, a4 = its end towards b.
#   Clobbers: only ABI temporaries.
clip_segment:
    addi    sp, sp, -80
    sd      ra, 72(sp)
    sd      s0, 64(sp)
    sd      s1, 56(sp)
    sd      s2, 48(sp)
    sd      s3, 40(sp)
    sd      s4, 32(sp)
    fsd     fs0, 24(sp)
    fsd     fs1, 16(sp)
    fsd     fs2, 8(sp)
    mv      s0, a0                      # s0 = a
    mv      s1, a1                      # s1 = b
    mv      s2, a2                      # s2 = outcodes
    fmv.w.x fs0, zero                   # fs0 = t entering
    li      t0, F32_ONE
    fmv.w.x fs1, t0                     # fs1 = t leaving
    li      s3, 0                       # s3 = plane number
1:  mv      a0, s3
    mv      a1, s2
    call    clip_plane
    beqz    a0, 5f                      # no end outside it
    mv      s4, a0                      # s4 = plane
    mv      a0, s0
    mv      a1, s4
    call    plane_distance
    fmv.s   fs2, fa0                    # fs2 = d(a)
    mv      a0, s1
    mv      a1, s4
    call    plane_distance              # fa0 = d(b)
    fmv.w.x ft0, zero
    fle.s   t0, ft0, fs2
    xori    t0, t0, 1                   # t0 = a outside
    fle.s   t1, ft0, fa0
    xori    t1, t1, 1                   # t1 = b outside
    and     t2, t0, t1
    bnez    t2, 8f                      # both outside: nothing left
    or      t2, t0, t1
    beqz    t2, 5f
    fsub.s  ft1, fs2, fa0
    fdiv.s  ft1, fs2, ft1               # the crossing, d(a) / (d(a) - d(b))
    beqz    t0, 3f
    fmax.s  fs0, fs0, ft1               # a outside: enters there
    j       5f
3:  fmin.s  fs1, fs1, ft1               # b outside: leaves there
5:  addi    s3, s3, 1
    li      t0, CLIP_PLANES
    bne     s3, t0, 1b
    flt.s   t0, fs1, fs0
    bnez    t0, 8f                      # leaves before it enters
    mv      a0, s0
    mv      a1, s1
    fmv.s   fa0, fs0
    call    segment_point
    call    project_clip
    mv      s3, a0
    mv      s4, a1
    mv      a0, s0
    mv      a1, s1
    fmv.s   fa0, fs1
    call    segment_point
    call    project_clip
    mv      a3, a0
    mv      a4, a1
    mv      a1, s3
    mv      a2, s4
    li      a0, 1
    j       9f
8:  li      a0, 0
9:  fld     fs2, 8(sp)
    fld     fs1, 16(sp)
    fld     fs0, 24(sp)
    ld      s4, 32(sp)
    ld      s3, 40(sp)
    ld      s2, 48(sp)
    ld      s1, 56(sp)
    ld      s0, 64(sp)
    ld      ra, 72(sp)
    addi    sp, sp, 80
    ret

# segment_point (file-local)
#   What: the clip-space point a + t (b - a) of an edge; at t = 1, b itself
#         (as b + 0 (a - b)), so that an end not cut off is the vertex.
#   Arguments: a0 = a's clip-space position, a1 = b's, fa0 = t (0 .. 1).
#   Results: fa0, fa1, fa2, fa3 = clip x, y, z, w (project_clip's arguments).
#   Clobbers: only ABI temporaries.
segment_point:
    li      t0, F32_ONE
    fmv.w.x ft0, t0
    feq.s   t0, fa0, ft0
    fmv.s   ft0, fa0                    # ft0 = t from a0's end towards a1's
    beqz    t0, 1f
    mv      t0, a0
    mv      a0, a1
    mv      a1, t0
    fmv.w.x ft0, zero
1:  flw     ft1, CLIP_POS_X(a0)
    flw     ft2, CLIP_POS_X(a1)
    fsub.s  ft2, ft2, ft1
    fmadd.s fa0, ft2, ft0, ft1
    flw     ft1, CLIP_POS_Y(a0)
    flw     ft2, CLIP_POS_Y(a1)
    fsub.s  ft2, ft2, ft1
    fmadd.s fa1, ft2, ft0, ft1
    flw     ft1, CLIP_POS_Z(a0)
    flw     ft2, CLIP_POS_Z(a1)
    fsub.s  ft2, ft2, ft1
    fmadd.s fa2, ft2, ft0, ft1
    flw     ft1, CLIP_POS_W(a0)
    flw     ft2, CLIP_POS_W(a1)
    fsub.s  ft2, ft2, ft1
    fmadd.s fa3, ft2, ft0, ft1
    ret

# aa_neighbours (file-local)
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
    addi    sp, sp, -48
    sd      ra, 40(sp)
    sd      s0, 32(sp)
    sd      s1, 24(sp)
    sd      s2, 16(sp)
    sd      s3, 8(sp)
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
    ld      s3, 8(sp)
    ld      s2, 16(sp)
    ld      s1, 24(sp)
    ld      s0, 32(sp)
    ld      ra, 40(sp)
    addi    sp, sp, 48
    ret

# adjacency_build (file-local)
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
    addi    sp, sp, -64
    sd      ra, 56(sp)
    sd      s0, 48(sp)
    sd      s1, 40(sp)
    sd      s2, 32(sp)
    sd      s3, 24(sp)
    sd      s4, 16(sp)
    sd      s5, 8(sp)
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
    ld      s5, 8(sp)
    ld      s4, 16(sp)
    ld      s3, 24(sp)
    ld      s2, 32(sp)
    ld      s1, 40(sp)
    ld      s0, 48(sp)
    ld      ra, 56(sp)
    addi    sp, sp, 64
    ret

# edges_build (file-local)
#   What: the unique edge list of the mesh into edge_list / edge_count:
#         every triangle's three (min, max) vertex index pairs, sorted
#         (Shell sort), duplicates removed. Fatal when the heap is short
#         (heap_alloc_or_fail).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
edges_build:
    addi    sp, sp, -32
    sd      ra, 24(sp)
    sd      s0, 16(sp)
    sd      s1, 8(sp)
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
    ld      s1, 8(sp)
    ld      s0, 16(sp)
    ld      ra, 24(sp)
    addi    sp, sp, 32
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

# ---------------------------------------------------------------------------
    .section .rodata
    .balign 4
# The clip planes, d = a x + b y + c z + e w >= 0 inside (render.inc
# PLANE_*): the near plane, then the guard band's sides.
clip_planes:
    .word   0, 0, F32_ONE, 0                            # z >= 0
    .word   F32_ONE, 0, 0, F32_GUARD_BAND               # x >= -G w
    .word   F32_MINUS_ONE, 0, 0, F32_GUARD_BAND         # x <= G w
    .word   0, F32_ONE, 0, F32_GUARD_BAND               # y >= -G w
    .word   0, F32_MINUS_ONE, 0, F32_GUARD_BAND         # y <= G w
.if CLIP_PLANES != 5
    .error "clip_planes lists five planes"
.endif
msg_edge_list:      .asciz "edge list"
msg_supersample_sums: .asciz "supersample sums"
msg_wire_cells:     .asciz "line coverage cells"
    .balign 4
# The samples of antialias = supersample (render.inc SAMPLE_OFFSET_*): each
# sample's offset from the pixel centre in Q4, a rotated grid.
supersample_offsets:
    .word   2, 6
    .word   6, -2
    .word   -2, -6
    .word   -6, 2
supersample_offsets_end:
.if supersample_offsets_end - supersample_offsets != SUPERSAMPLES * SAMPLE_OFFSET_BYTES
    .error "supersample_offsets must list SUPERSAMPLES offsets"
.endif
msg_adjacency:      .asciz "adjacency"
msg_adjacency_keys: .asciz "adjacency keys"
msg_canonical_vertices: .asciz "canonical vertices"
msg_vertex_keys:    .asciz "vertex keys"
msg_depth_buffer:   .asciz "depth buffer"
msg_normal_intensities: .asciz "normal intensities"

# ---------------------------------------------------------------------------
    .bss
    .balign 8
# render_fill: the RASTER_* flags of every triangle (render_init).
render_fill:
    .space  8
# normal_light: address (heap) of one f32 intensity (0 .. LIGHT_ONE) per
# mesh normal, this frame's (Gouraud only).
normal_light:
    .space  8
# light_quantum: f32 levels - 1, then f32 LIGHT_ONE / (levels - 1)
# (light_level; render_init).
light_quantum:
    .space  LIGHT_QUANTUM_BYTES
# The wireframe's unique edges: address (heap) and count.
edge_list:
    .space  8
edge_count:
    .space  8
# adjacency: address (heap) of the triangle adjacency (antialias = edge;
# adjacency_build).
adjacency:
    .space  8
# render_vertices: this frame's vertex records (render_prepare).
render_vertices:
    .space  8
# Hart-local (k210.inc HART_LOCAL_STRIDE; tp selects the copy): scratch of
# one triangle: its corners for raster_triangle; when it is clipped, the
# polygon as clip vertices (two buffers: each plane's output is the next
# one's input), projected, and one triangle of its fan.
    .balign 8
render_hart_local:
render_rv:
    .space  TRIANGLE_CORNERS * RV_BYTES
clip_polygon_a:
    .space  CLIP_MAX_OUT * CV_BYTES
clip_polygon_b:
    .space  CLIP_MAX_OUT * CV_BYTES
render_rv_out:
    .space  CLIP_MAX_OUT * RV_BYTES
render_rv_fan:
    .space  TRIANGLE_CORNERS * RV_BYTES
# A wireframe edge cut in clip space: its ends' clip-space positions.
segment_ends:
    .space  2 * CLIP_POS_BYTES
render_hart_local_end:
    .space  HART_LOCAL_STRIDE - (render_hart_local_end - render_hart_local)
    .space  render_hart_local_end - render_hart_local   # hart 1's copy
