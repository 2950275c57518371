# raster.S: the rasteriser's state, which every raster_*.S draws through:
# where it draws (raster_begin: the framebuffer), the rows the calling hart
# draws (raster_set_band: its band), and the variables below (.bss) that the
# other files set: the depth buffer and its format, the texture and its mip
# table, the supersample offset and sums, the union lines' cells. They stay
# together here, in the order the image has always had them (the Makefile's
# FW_ORDER keeps code and data where the cycle counts were measured).
#
# The framebuffer is 320 x 240 RGB565 laid out for the LCD: pixel (x, y) is
# the halfword at fb + 2 (320 y + (x ^ 1)) (see framebuffers in main.S). The
# depth buffer holds one entry per pixel, row by row (render.inc DEPTH_*).
#
# The rasteriser's files, in link order:
#   raster.S              this state; raster_begin, raster_set_band
#   raster_supersample.S  antialias = supersample: sample offsets, the sums
#   raster_texture.S      the texture, and its mip chain (filter = mipmap)
#   raster_clear.S        the depth buffer's setting; clearing a band
#   raster_triangle.S     one triangle: culling, bounding box, edge functions,
#                         attribute planes, then the fill loop for its settings
#   raster_fills.S        the fill loops (FILL, FILTERED) and their table
#   raster_lines.S        lines: Bresenham's, by coverage, and their union

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"
    .include "render.inc"

    .text
    .globl raster_begin
# raster_begin
#   What: sets the framebuffer that the following drawing goes to.
#   Arguments: a0 = framebuffer (LCD_FB_BYTES, 64-aligned).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_begin:
    la      t0, raster_fb
    sd      a0, 0(t0)
    ret

    .globl raster_set_band
# raster_set_band
#   What: sets the rows the calling hart draws from now on: raster_clear and
#         raster_triangle touch rows a0 .. a1 - 1 only (the two harts draw
#         disjoint bands of one frame, main.S). Lines (raster_segment,
#         raster_line) ignore it. Until it is first called the band is empty.
#   Arguments: a0 = first row, a1 = the row past the last (0 <= a0 <= a1 <=
#              LCD_HEIGHT).
#   Results: none.
#   Clobbers: only ABI temporaries.
raster_set_band:
    la      t0, raster_band
    add     t0, t0, tp
    sw      a0, BAND_FIRST(t0)
    sw      a1, BAND_END(t0)
    ret

# ---------------------------------------------------------------------------
    .bss
    .balign 8
# Where the raster_*.S files draw (raster_begin; the depth buffer:
# raster_clear.S raster_set_depth), and the texture of textured fills
# (raster_texture.S raster_set_texture).
    .globl raster_fb
raster_fb:
    .space  8
    .globl raster_texture
raster_texture:
    .space  8
    .globl raster_tex_w
raster_tex_w:
    .space  8
    .globl raster_tex_h
raster_tex_h:
    .space  8
    .globl raster_depth
raster_depth:
    .space  8
    .globl raster_depth_mode
raster_depth_mode:
    .space  8
    .globl raster_depth_reverse
raster_depth_reverse:
    .space  8
# filter = mipmap: the level table (raster_texture.S raster_build_mips)
    .globl raster_mip_table
raster_mip_table:
    .space  8
# filter = anisotropic: nonzero when the mipmap fills walk the footprint
# (render_init)
    .globl raster_aniso
raster_aniso:
    .space  8
# shading = phong: nonzero when the Gouraud fills' triangles carry normals
# (RV_NA..RV_NC) and light per pixel (render_init)
    .globl raster_phong
raster_phong:
    .space  8
# antialias = supersample: the sums of the samples (raster_supersample.S
# raster_set_sums)
    .globl raster_sums
raster_sums:
    .space  8
# antialias = supersample, wireframe: the union lines' cells and spans
# (raster_lines.S raster_set_union)
    .globl raster_union
raster_union:
    .space  8
# Hart-local (k210.inc HART_LOCAL_STRIDE; tp selects the copy): the rows this
# hart draws (raster_set_band), filter = mipmap's rho^2 constant of the
# triangle being drawn (|det H| or, affine, |det J|; raster_triangle), and
# the offset of the sample it draws (raster_supersample.S raster_set_sample).
    .balign 8
    .globl raster_band
raster_band:
    .space  BAND_BYTES
    .globl raster_mip_rho2
raster_mip_rho2:
    .space  4
# filter = anisotropic: how far a sample's footprint reaches, as a share of
# the pixel's (1, or 1/2 supersampled; raster_triangle)
    .globl raster_mip_footprint
raster_mip_footprint:
    .space  4
    .balign 8
    .globl raster_sample
raster_sample:
    .space  SAMPLE_BYTES
raster_hart_local_end:
    .space  HART_LOCAL_STRIDE - (raster_hart_local_end - raster_band)
    .space  raster_hart_local_end - raster_band     # hart 1's copy
