# render.S: one frame of the scene: clear, then every triangle (textured or
# flat) or every edge (wireframe). render_init prepares the renderer once the
# scene is loaded. Per frame, the set-up (render_prepare) runs once; the
# vertex stage (render_vertex_share) and the drawing (render_band) run on one
# hart for the whole mesh and screen or on both, each for its share of the
# vertices and its band of rows (main.S), with per-hart scratch (the
# hart-local block below).
#
# The renderer's variables and tables (.rodata, .bss, below) live here for
# all the render_*.S files, in the order the image has always had them (the
# Makefile's FW_ORDER keeps code and data where the cycle counts were
# measured); each says who uses it.
#
# The renderer's files, in link order:
#   render.S              render_init, a frame, a band; the shared state
#   render_triangles.S    a band's triangles: rejection, culling, then each
#                         lit, textured, clipped if need be, rasterised
#   render_light.S        light intensities: per face, per corner (Gouraud)
#   render_texels.S       a face's texel coordinates
#   render_clip.S         triangles cut in clip space (near plane, guard band)
#   render_wireframe.S    the wireframe's edges, cut in clip space, drawn
#   render_edges.S        the mesh's edges: the triangle adjacency
#                         (antialias = edge) and the unique edge list
#                         (wireframe), built at render_init

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"
    .include "frame.inc"

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
    FRAME_SAVE 16, ra, s0
    la      s0, scene
    call    vertex_init
    lwu     t1, SCENE_ANGLES(s0)
    li      t2, ANGLES_TABLE
    bne     t1, t2, 1f
    call    angle_table_build

    # The fill: textured (with a texture) or flat; affine or perspective;
    # Gouraud or Phong (the Gouraud fills' twins, raster_phong) or one
    # intensity per face.
1:  li      t1, RASTER_FLAT
    lwu     t0, SCENE_SHADING(s0)
    li      t2, SHADING_PHONG
    sub     t3, t0, t2
    seqz    t3, t3
    la      t2, raster_phong
    sd      t3, 0(t2)
    li      t2, SHADING_FLAT
    beq     t0, t2, 2f
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
22: li      t2, FILTER_ANISOTROPIC      # anisotropic: the mipmap fills, which
    sub     t3, t0, t2                  # then walk the footprint (raster_aniso)
    seqz    t3, t3
    la      t2, raster_aniso
    sd      t3, 0(t2)
    bnez    t3, 24f
    li      t2, FILTER_MIPMAP
    bne     t0, t2, 23f
24: ori     t1, t1, RASTER_MIPMAP
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

    # The light quantisation: levels - 1 and one / (levels - 1), where one
    # is LIGHT_ONE up to LIGHT_LEVELS_NARROW levels (the fills of
    # raster_fills), WIDE_LIGHT_ONE above (raster_fills_wide's, which cost
    # 2 to 11 instructions more a lit pixel).
    la      t0, light_quantum
    flw     ft0, SCENE_LIGHT_LEVELS(s0)
    li      t1, F32_ONE
    fmv.w.x ft1, t1
    fsub.s  ft0, ft0, ft1
    fsw     ft0, LIGHT_QUANTUM_LEVELS(t0)
    fcvt.w.s t3, ft0, rtz
    li      t1, F32_LIGHT_ONE
    li      t2, WIDE_WIDEN
    la      t4, raster_fills
    li      t5, LIGHT_LEVELS_NARROW - 1
    ble     t3, t5, 34f
    li      t1, F32_WIDE_LIGHT_ONE
    li      t2, 0
    la      t4, raster_fills_wide
34: fmv.w.x ft1, t1
    fsw     ft1, LIGHT_QUANTUM_ONE(t0)
    sw      t2, LIGHT_QUANTUM_WIDEN(t0)
    fdiv.s  ft1, ft1, ft0
    fsw     ft1, LIGHT_QUANTUM_STEP(t0)
    la      t0, raster_phong            # Phong: the table's twin
    ld      t0, 0(t0)
    beqz    t0, 35f
    la      t4, raster_fills_phong
    bnez    t2, 35f                     # (t2 = 0: wide)
    la      t4, raster_fills_phong_wide
35: la      t0, raster_fill_table
    sd      t4, 0(t0)

    lwu     t1, SCENE_MODE(s0)
    li      t2, MODE_WIREFRAME
    bne     t1, t2, 4f
    call    edges_build
    # antialias = supersample: the union lines' cells, and the lines from
    # where their ends project before snapping to 1/16 pixel (the vertex
    # records keep the snap's residual: a 1/32-pixel move of an end shows in
    # the union's coverage); snap = pixel keeps its whole pixels
    la      t0, render_fill
    lwu     t0, 0(t0)
    andi    t0, t0, RASTER_SUPERSAMPLE
    beqz    t0, 9f
    lwu     t0, SCENE_SNAP(s0)
    xori    t0, t0, SNAP_PIXEL
    snez    t0, t0
    la      t1, vertex_snap_kept
    sd      t0, 0(t1)
    li      a0, WIRE_BUFFER_BYTES
    la      a1, msg_wire_cells
    call    heap_alloc_or_fail
    call    raster_set_union
    j       9f
    # Triangles: the depth buffer, and the normals' Gouraud intensities (or
    # Phong's coordinates in the light's basis).
4:  li      a0, DEPTH_BUFFER_BYTES
    lwu     t0, SCENE_DEPTH(s0)
    li      t1, DEPTH_INT16
    bne     t0, t1, 5f
    li      a0, DEPTH16_BUFFER_BYTES
5:  la      a1, msg_depth_buffer
    call    heap_alloc_or_fail
    lwu     a1, SCENE_DEPTH(s0)
    flw     fa0, SCENE_NEAR(s0)
    flw     fa1, SCENE_FAR(s0)
    call    raster_set_depth
    lwu     t0, SCENE_DEPTH(s0)         # float32: the vertex records keep the
    xori    t0, t0, DEPTH_INT16         # snap's residual for the depth plane
    snez    t0, t0
    la      t1, vertex_snap_kept
    sd      t0, 0(t1)
    la      t0, render_fill
    lwu     t0, 0(t0)
    andi    t0, t0, RASTER_GOURAUD
    beqz    t0, 8f
    lwu     a0, MESH_NCOUNT(s0)
    slli    a0, a0, NORMAL_LIGHT_SHIFT
    la      a1, msg_normal_intensities
    la      t0, raster_phong
    ld      t0, 0(t0)
    beqz    t0, 7f
    call    phong_basis_init            # Phong: each normal in the light's basis
    lwu     a0, MESH_NCOUNT(s0)
    slli    a0, a0, NORMAL_PHONG_SHIFT
    la      a1, msg_normals_turned
7:  call    heap_alloc_or_fail
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
9:  FRAME_RESTORE 16, ra, s0
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
    FRAME_SAVE 16, ra
    call    render_prepare
    li      a0, 0
    li      a1, 1
    call    render_vertex_share
    li      a0, 0
    li      a1, LCD_HEIGHT
    call    render_band
    FRAME_RESTORE 16, ra
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
    FRAME_SAVE 16, ra, s0
    mv      s0, a0                      # s0 = framebuffer
    mv      a0, a1
    call    vertex_setup
    la      t0, render_vertices
    sd      a0, 0(t0)
    mv      a0, s0
    call    raster_begin
    FRAME_RESTORE 16, ra, s0
    ret

    .globl render_vertex_share
# render_vertex_share
#   What: share a0 of a1 of frame n's vertex stage, after render_prepare:
#         the vertex records (and flat shading's world positions) of mesh
#         vertices [a0 V / a1, (a0 + 1) V / a1) (vertex_range), and with
#         shading = gouraud the intensities of normals [a0 N / a1,
#         (a0 + 1) N / a1) (normals_light; with shading = phong their
#         coordinates in the light's basis, normals_phong); V, N the mesh's
#         counts. The
#         shares of one frame may run on both harts at once; each item is
#         computed as in one pass over all, so the records are the same
#         however the stage is split. Every share must be done before any
#         render_band of the frame.
#   Arguments: a0 = the share (0 .. a1 - 1), a1 = the number of shares
#              (1 or 2).
#   Results: none.
#   Clobbers: only ABI temporaries.
render_vertex_share:
    FRAME_SAVE 32, ra, s0, s1
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
    la      t0, raster_phong
    ld      t0, 0(t0)
    bnez    t0, 8f
    call    normals_light
    j       9f
8:  call    normals_phong
9:  FRAME_RESTORE 32, ra, s0, s1
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
    FRAME_SAVE 112, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11
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
    # cleared, its colours summed; then the sums' means (raster_supersample.S)
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
9:  FRAME_RESTORE 112, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11
    ret

# ---------------------------------------------------------------------------
    .section .rodata
    .balign 4
# The clip planes, d = a x + b y + c z + e w >= 0 inside (render.inc
# PLANE_*): the near plane, then the guard band's sides (render_clip.S,
# render_wireframe.S).
    .globl clip_planes
clip_planes:
    .word   0, 0, F32_ONE, 0                            # z >= 0
    .word   F32_ONE, 0, 0, F32_GUARD_BAND               # x >= -G w
    .word   F32_MINUS_ONE, 0, 0, F32_GUARD_BAND         # x <= G w
    .word   0, F32_ONE, 0, F32_GUARD_BAND               # y >= -G w
    .word   0, F32_MINUS_ONE, 0, F32_GUARD_BAND         # y <= G w
.if CLIP_PLANES != 5
    .error "clip_planes lists five planes"
.endif
# The heap blocks' names, for heap_alloc_or_fail's message: render_init's,
# and those of render_edges.S (edges_build, adjacency_build, vertex_canon).
    .globl msg_edge_list
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
    .globl msg_adjacency
msg_adjacency:      .asciz "adjacency"
    .globl msg_adjacency_keys
msg_adjacency_keys: .asciz "adjacency keys"
    .globl msg_canonical_vertices
msg_canonical_vertices: .asciz "canonical vertices"
    .globl msg_vertex_keys
msg_vertex_keys:    .asciz "vertex keys"
msg_depth_buffer:   .asciz "depth buffer"
msg_normal_intensities: .asciz "normal intensities"
msg_normals_turned: .asciz "normals in the light's basis"

# ---------------------------------------------------------------------------
    .bss
    .balign 8
# render_fill: the RASTER_* flags of every triangle (render_init).
    .globl render_fill
render_fill:
    .space  8
# normal_light: address (heap) of one f32 intensity (0 .. one, light_quantum) per
# mesh normal, this frame's (Gouraud only; render_light.S normals_light), or
# with Phong shading the normal in the light's basis (NORMAL_PHONG_BYTES,
# normals_phong).
    .globl normal_light
normal_light:
    .space  8
# light_quantum: f32 levels - 1, f32 one / (levels - 1), f32 one (LIGHT_ONE,
# or WIDE_LIGHT_ONE above LIGHT_LEVELS_NARROW levels), u32 the shift from k
# to 1 / WIDE_LIGHT_ONE (render_light.S light_level, shade_rgb565; render_init).
    .globl light_quantum
light_quantum:
    .space  LIGHT_QUANTUM_BYTES
# The wireframe's unique edges: address (heap) and count (render_edges.S
# edges_build; render_wireframe.S draws them).
    .globl edge_list
edge_list:
    .space  8
    .globl edge_count
edge_count:
    .space  8
# adjacency: address (heap) of the triangle adjacency (antialias = edge;
# render_edges.S adjacency_build, aa_neighbours).
    .globl adjacency
adjacency:
    .space  8
# render_vertices: this frame's vertex records (render_prepare).
render_vertices:
    .space  8
# Hart-local (k210.inc HART_LOCAL_STRIDE; tp selects the copy): scratch of
# one triangle: its corners for raster_triangle (render_triangles.S, with
# render_light.S's intensities and render_texels.S's texel coordinates); when
# it is clipped (render_clip.S), the polygon as clip vertices (two buffers:
# each plane's output is the next one's input), projected, and one triangle
# of its fan.
    .balign 8
render_hart_local:
    .globl render_rv
render_rv:
    .space  TRIANGLE_CORNERS * RV_BYTES
    .globl clip_polygon_a
clip_polygon_a:
    .space  CLIP_MAX_OUT * CV_BYTES
    .globl clip_polygon_b
clip_polygon_b:
    .space  CLIP_MAX_OUT * CV_BYTES
    .globl render_rv_out
render_rv_out:
    .space  CLIP_MAX_OUT * RV_BYTES
    .globl render_rv_fan
render_rv_fan:
    .space  TRIANGLE_CORNERS * RV_BYTES
# A wireframe edge cut in clip space: its ends' clip-space positions
# (render_wireframe.S).
    .globl segment_ends
segment_ends:
    .space  2 * CLIP_POS_BYTES
render_hart_local_end:
    .space  HART_LOCAL_STRIDE - (render_hart_local_end - render_hart_local)
    .space  render_hart_local_end - render_hart_local   # hart 1's copy
