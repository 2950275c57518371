# main.S: what each hart does after boot, and the frame handoff between them.
#
# Start-up runs on both harts at once. Hart 0 brings up what both need
# (clocks, pins, console, the DMAC's reset) and releases hart 1; then hart 1
# brings the LCD up (lcd.S: about 125 ms, nearly all of it the ST7789V's
# datasheet waits, asleep in WFI) while hart 0 loads scene.ini and the files it
# names from the SD card (sd*.S, fat32*.S, scene.S), parses the model and the
# texture into `scene` (obj.S, ppm.S; any failure there is fatal, errors.S)
# and draws frames forever. Hart 1 then sends finished frames to the LCD and
# reports each one.
#
# Who owns what from the release on (nothing else is shared):
#   hart 1 only: SPI0, DMAC channel 0 and its PLIC enable, lcd_ready, the
#         LCD's panel state; hart 0 only: SPI1, DMAC channel 1 and its PLIC
#         enable, the heap, `scene`, the renderer's state (render_prepare
#         writes it while hart 1 draws nothing; when both draw, each then
#         writes its share of the vertex records, and both read all of
#         them while they draw their bands; see "Both harts draw" below).
#   written before the release, read-only after it: cpu_hz, .bss cleared,
#         the console's UART set-up, the FPIOA, the DMAC's common set-up
#         (dma_init: its reset would stop the other hart's channel).
#   registers both change by read-modify-write: GPIOHS output_val (LCD reset
#         and D/C on hart 1, the card's chip select on hart 0) and SYSCTL
#         dma_sel0 (channel 0's and channel 1's request lines), each change
#         under shared_io_lock (pins.S).
#   the console: whole lines under console_lock (console.S), so lines of the
#         two harts interleave but never mix. From the release until frame 0
#         is on the LCD, what either hart prints waits in the console's ring
#         and hart 1 sends it while it waits (for the LCD's datasheet delays,
#         then for frame 0; console.S, the relay), so hart 0 does not wait on
#         the UART while it loads.
#   framebuffers, fb_state, fb_frame: the handoff below. Hart 0 may draw
#         frame 0 before the LCD is up; hart 1 takes it once it is.
#   a fatal error or a trap on hart 0: halt_request (trap.S, errors.S) after
#         the error colour; hart 1 sees it when it next waits for a frame,
#         after lcd_init has finished, and paints the error screen.
#
# Handoff: two framebuffers, frame n goes into buffer n & 1. Each buffer has
# a state word, FB_FREE (hart 0 may draw into it) or FB_FULL (hart 1 may
# send it), and the number of the frame it holds.
#   hart 0: wait state[b] == FREE; draw; frame[b] = n;
#           state[b] = FULL (release order); msip[1] = 1
#   hart 1: wait state[b] == FULL (acquire); send by DMA;
#           state[b] = FREE (release order); msip[0] = 1; print "frame N"
# A waiting hart clears its own msip *before* reading the state, then WFIs:
# a signal sent after the read leaves msip pending and WFI falls through, so
# no wake-up is lost (a signal that comes while hart 1 sleeps in lcd_init's
# delays, which wake on the timer only, stays pending likewise). Both walk the
# buffers in the same order (0, 1, 0, ...), so frames reach the LCD in the
# order they were drawn.
# A trap on either hart raises halt_request (trap.S): a waiting hart then
# leaves its loop, hart 1 painting the error screen on the way out.
#
# Both harts draw: frame n >= 1 is split in two bands of rows, hart 0's
# rows 0 .. s - 1 and hart 1's s .. LCD_HEIGHT - 1 (s = LCD_HEIGHT: hart 0
# draws it all; draw_split decides, docs/design/firmware.md "Rendering"), each hart's rows of
# the colour and depth buffers its own (render_band, raster_set_band), so
# no pixel is written by both and the frame is the one hart 0 draws alone.
# The vertex stage before it is split too when hart 1 has rows: each hart
# fills the records of its share of the vertices (render_vertex_share,
# VERTEX_SHARES of them), and neither draws before both shares are in
# memory (a barrier: one word per hart in the job, SHARE_DONE).
#   hart 0: wait state[b] == FREE; render_prepare (the matrices, once for
#           both); from frame 1 on post band_job (first row s, both
#           shares SHARE_PENDING, JOB_POSTED, msip[1]); its share of the
#           vertex stage (all of it when s = LCD_HEIGHT); if s <
#           LCD_HEIGHT: share 0 = SHARE_DONE (release, msip[1]), wait
#           share 1 == SHARE_DONE (acquire); draw rows 0 .. s - 1; if s <
#           LCD_HEIGHT wait band_job == JOB_DONE (acquire: hart 1's rows
#           are in memory); then FULL as above
#   hart 1: wait state[b] == FULL; start frame n's DMA; wait band_job ==
#           JOB_POSTED (the job of frame n + 1, drawn into the other
#           buffer, which hart 1 itself handed back); if it has rows: its
#           share of the vertex stage, share 1 = SHARE_DONE (release,
#           msip[0]), wait share 0 == SHARE_DONE (acquire), draw its rows;
#           band_job = JOB_DONE (release; msip[0] only when hart 0 waits
#           for it); wait for the DMA; FREE as above
# Job n + 1 is taken before hart 1 frees buffer b, and hart 0 posts job
# n + 2 only once buffer b is free: one job is in flight at a time, so
# one state word and one word per share are enough (hart 0 resets the
# shares' words before it posts, when hart 1 no longer reads them). Hart
# 0 does not run render_prepare again before hart 1's band is done (it
# waits for JOB_DONE first). Each share's word is written by its hart
# only, so each waits for a word that nothing changes after it is set:
# whichever hart comes to the barrier second finds the other's word set.

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "scene.inc"

# band_job's layout
    .equ JOB_STATE,             0           # u32 JOB_NONE / JOB_POSTED / JOB_DONE
    .equ JOB_FIRST,             4           # u32 first row of hart 1's band (LCD_HEIGHT: none)
    .equ JOB_FRAME,             8           # u64 the frame's number
    .equ JOB_CYCLES,            16          # u64 hart 1's band, cycles (hart 1 writes it)
    .equ JOB_SHARE_CYCLES,      24          # u64 hart 1's share of the vertex stage, cycles (hart 1)
    .equ JOB_SHARE0,            32          # u32 SHARE_PENDING / SHARE_DONE: hart 0's share
    .equ JOB_SHARE1,            36          # u32 the same, hart 1's (hart 1 writes it)
    .equ JOB_BYTES,             40
    .equ SIGNAL_NONE,           -1          # set_state: signal no hart
    .equ DRAW_BAND_MIN,         8           # rows each hart keeps when both draw
# CPU cycles one frame takes on the LCD's SPI link: one byte per serial
# clock (octal), the serial clock SPI0's source / SPI0_BAUDR_LCD, and SPI0's
# source (PLL0 / 2) is the CPU's clock: 3 072 000 cycles, 7.62 ms.
    .equ LCD_FRAME_CYCLES,      LCD_FB_BYTES * SPI0_BAUDR_LCD

    .text
    .globl main_hart0
# main_hart0
#   What: hart 0 after .bss clearing: the bring-up both harts need, release
#         of hart 1, SD card loading, draw loop.
#   Arguments: none. Results: never returns.
#   Clobbers: everything (it is the bottom of hart 0's call stack).
main_hart0:
    call    clocks_init
    mv      s0, a0                      # s0 = CPU Hz
    mv      s1, a1                      # s1 = PLL0 Hz
    call    pins_init
    mv      a0, s0
    call    console_init
    call    dma_init
    call    console_relay_start         # hart 1 sends hart 0's lines while it waits
    call    boot_release_hart1          # hart 1 brings the LCD up meanwhile

    call    console_lock                # whole lines: hart 1 prints too
    la      a0, msg_boot
    call    console_puts
    la      a0, msg_clocks_pll0
    call    console_puts
    mv      a0, s1
    call    console_put_dec
    la      a0, msg_clocks_cpu
    call    console_puts
    mv      a0, s0
    call    console_put_dec
    la      a0, msg_hz_nl
    call    console_puts
    la      a0, msg_pins
    call    console_puts
    call    console_unlock

    # The card's files, while hart 1 brings the LCD up; a failure is shown
    # by hart 1 once the LCD is up (errors.S).
    call    crc_init
    call    heap_init
    call    sd_init
    call    fat32_mount
    call    scene_load                  # scene.ini, the model and texture files
    call    obj_parse_model             # the mesh into `scene` (obj.S)
    call    ppm_parse_texture           # the texture into `scene` (ppm.S)
    call    render_init                 # renderer buffers for this scene (render.S)
    call    depth_check                 # near and far against the model (depth_check.S)

    li      s2, 0                       # s2 = frame number n
1:  andi    s3, s2, 1                   # s3 = buffer index b
    mv      a0, s3
    li      a1, FB_FREE
    call    fb_wait_state
    bnez    a0, trap_park
    csrr    s4, mcycle                  # s4 = the frame's start
    mv      a0, s3
    call    fb_address
    mv      a1, s2
    call    render_prepare              # the matrices, once
    mv      a0, s2
    call    draw_split
    mv      s5, a0                      # s5 = hart 1's first row
    li      s9, 1                       # s9 = the vertex stage's shares: all hart 0's,
    li      t0, LCD_HEIGHT              # or one per hart when both draw
    beq     s5, t0, 2f
    li      s9, VERTEX_SHARES
    # every frame from 1 on has a job for hart 1, maybe without rows (frame
    # 0's comes before hart 1 takes jobs: it brings the LCD up meanwhile)
2:  beqz    s2, 3f
    la      t0, band_job
    sw      s5, JOB_FIRST(t0)
    sd      s2, JOB_FRAME(t0)
    li      t1, SHARE_PENDING
    sw      t1, JOB_SHARE0(t0)
    sw      t1, JOB_SHARE1(t0)
    addi    a0, t0, JOB_STATE
    li      a1, JOB_POSTED
    li      a2, 1
    call    set_state
3:  li      a0, 0                       # this hart's share of the vertex stage
    mv      a1, s9
    call    render_vertex_share
    csrr    t0, mcycle
    sub     s10, t0, s4                 # s10 = hart 0's cycles so far
    li      t0, LCD_HEIGHT
    beq     s5, t0, 4f                  # hart 1 draws nothing: no one waits
    la      a0, band_job + JOB_SHARE0   # hart 1 may draw once it is done
    li      a1, SHARE_DONE
    li      a2, 1
    call    set_state
    la      a0, band_job + JOB_SHARE1   # this hart draws once hart 1's is
    li      a1, SHARE_DONE
    call    wait_state
    bnez    a0, trap_park
4:  csrr    s6, mcycle                  # s6 = hart 0's band's start
    li      a0, 0
    mv      a1, s5
    call    render_band
    csrr    t0, mcycle
    sub     s6, t0, s6                  # s6 = hart 0's band, cycles
    add     s7, s10, s6                 # s7 = hart 0's frame, cycles (not waiting)
    li      s8, 0                       # s8 = hart 1's band, cycles
    li      t0, LCD_HEIGHT
    beq     s5, t0, 5f                  # no rows for hart 1: no need to wait
    la      a0, band_job + JOB_STATE
    li      a1, JOB_DONE
    call    wait_state
    bnez    a0, trap_park
    la      t0, band_job
    ld      s8, JOB_CYCLES(t0)
    ld      t1, JOB_SHARE_CYCLES(t0)
    add     s7, s7, t1                  # and hart 1's share of the vertex stage
5:  mv      a0, s5
    mv      a1, s6
    mv      a2, s7
    mv      a3, s8
    call    draw_record
    slli    t0, s3, 3
    la      t1, fb_frame
    add     t1, t1, t0
    sd      s2, 0(t1)
    mv      a0, s3
    li      a1, FB_FULL
    li      a2, 1                       # tell hart 1 (the display hart)
    call    fb_set_state
    addi    s2, s2, 1
    j       1b

    .globl main_hart1
# main_hart1
#   What: hart 1 after its release: LCD bring-up and the console's relay
#         (console.S) until frame 0 is out, then the display loop, sending
#         each full buffer to the LCD, handing it back and printing its frame
#         number.
#   Arguments: none. Results: never returns.
#   Clobbers: everything (it is the bottom of hart 1's call stack).
main_hart1:
    la      t0, cpu_hz
    lwu     a0, 0(t0)
    call    lcd_init
    la      a0, msg_lcd
    call    console_line
    # A fatal error or a trap on hart 0 while the LCD came up: show it now,
    # without announcing a display loop that will never show a frame.
    la      t0, halt_request
    lw      t0, 0(t0)
    bnez    t0, 3f
    la      a0, msg_hart1
    call    console_line
    call    dma_irq_init

    # Until hart 0 has drawn frame 0 it may still be loading and printing:
    # keep the relay going meanwhile (fb_wait_state's WFI would not).
    la      a0, fb_state                # buffer 0's state: frame 0 goes there
    li      a1, FB_FULL
    call    console_relay_until
    bnez    a0, 3f

    li      s2, 0                       # s2 = frames shown
1:  andi    s3, s2, 1                   # s3 = buffer index b
    mv      a0, s3
    li      a1, FB_FULL
    call    fb_wait_state
    bnez    a0, 2f
    slli    t0, s3, 3
    la      t1, fb_frame
    add     t1, t1, t0
    ld      s4, 0(t1)                   # s4 = frame number in the buffer
    mv      a0, s3
    call    fb_address
    call    lcd_frame_start             # the DMA sends it meanwhile
    # hart 0's job for the next frame, which it is drawing into the other
    # buffer: this hart's rows of it, if any
    la      a0, band_job + JOB_STATE
    li      a1, JOB_POSTED
    call    wait_state
    bnez    a0, 2f
    la      t0, band_job
    lwu     s5, JOB_FIRST(t0)           # s5 = this hart's first row
    li      s6, 0                       # s6 = its band, cycles
    li      s7, 0                       # s7 = its share of the vertex stage, cycles
    li      t1, LCD_HEIGHT
    bgeu    s5, t1, 7f
    csrr    s7, mcycle
    li      a0, 1                       # share 1 of the vertex stage
    li      a1, VERTEX_SHARES
    call    render_vertex_share
    csrr    t0, mcycle
    sub     s7, t0, s7
    la      a0, band_job + JOB_SHARE1
    li      a1, SHARE_DONE
    li      a2, 0                       # tell hart 0, which waits for it
    call    set_state
    la      a0, band_job + JOB_SHARE0   # hart 0's share of it
    li      a1, SHARE_DONE
    call    wait_state
    bnez    a0, 2f
    csrr    s6, mcycle
    mv      a0, s5
    li      a1, LCD_HEIGHT
    call    render_band
    csrr    t0, mcycle
    sub     s6, t0, s6
7:  la      t0, band_job
    sd      s6, JOB_CYCLES(t0)
    sd      s7, JOB_SHARE_CYCLES(t0)
    addi    a0, t0, JOB_STATE
    li      a1, JOB_DONE
    li      a2, 0                       # tell hart 0, which waits for it when
    li      t0, LCD_HEIGHT              # this hart had rows (only then: a
    bltu    s5, t0, 8f                  # signal it does not wait for would
    li      a2, SIGNAL_NONE             # cut one of its other waits short)
8:  call    set_state
    call    lcd_frame_finish
    mv      a0, s3
    li      a1, FB_FREE
    li      a2, 0                       # tell hart 0
    call    fb_set_state
    # The relay ends once frame 0 is out (then it has nothing left to do):
    # what it still holds goes first, then this and every later line
    # straight to the UART.
    bnez    s2, 6f
    call    console_lock
    call    console_relay_stop
    call    console_unlock
6:  la      a0, msg_frame
    mv      a1, s4
    call    console_line_dec
    addi    s2, s2, 1
    j       1b

    # Hart 0 trapped: it no longer draws and leaves SPI0 to this hart.
3:  fence   r, rw                       # acquire: the error colour stored before the request
2:  call    lcd_error_screen
    j       trap_park

# fb_address (file-local)
#   What: address of framebuffer a0.
#   Arguments: a0 = buffer index (0 or 1).
#   Results: a0 = address.
#   Clobbers: only ABI temporaries.
fb_address:
    li      t0, LCD_FB_BYTES
    mul     t0, t0, a0
    la      a0, framebuffers
    add     a0, a0, t0
    ret

# fb_wait_state (file-local)
#   What: wait_state on buffer a0's state word.
#   Arguments: a0 = buffer index, a1 = wanted state.
#   Results: a0 = 0 when the state was reached, 1 when halted.
#   Clobbers: only ABI temporaries. Leaves this hart's msip clear.
fb_wait_state:
    slli    t0, a0, 2
    la      a0, fb_state
    add     a0, a0, t0
    # fall through

# wait_state (file-local)
#   What: sleeps until the word at a0 equals a1, woken by this hart's
#         CLINT software interrupt. Acquire: what the other hart wrote before
#         setting the word is visible after return. Gives up when a trap
#         on the other hart has raised halt_request.
#   Arguments: a0 = address of the state word, a1 = wanted state.
#   Results: a0 = 0 when the state was reached, 1 when halted.
#   Clobbers: only ABI temporaries. Leaves this hart's msip clear.
wait_state:
    mv      t1, a0                      # t1 = &state
    csrr    t2, mhartid
    slli    t2, t2, CLINT_MSIP_SHIFT
    li      t3, CLINT_MSIP
    add     t2, t2, t3                  # t2 = &msip[this hart]
    li      t4, MIE_MSIE
    csrs    mie, t4
    la      t5, halt_request
1:  sw      zero, 0(t2)
    fence                               # the clear lands before the reads
    lw      t3, 0(t5)
    bnez    t3, 3f
    lw      t3, 0(t1)
    beq     t3, a1, 2f
    wfi
    j       1b
2:  fence   r, rw
    csrc    mie, t4
    li      a0, 0
    ret
3:  fence   r, rw                       # acquire: the error colour stored before the request
    csrc    mie, t4
    li      a0, 1
    ret

# fb_set_state (file-local)
#   What: set_state on buffer a0's state word.
#   Arguments: a0 = buffer index, a1 = new state, a2 = hart to signal.
#   Results: none.
#   Clobbers: only ABI temporaries.
fb_set_state:
    slli    t0, a0, 2
    la      a0, fb_state
    add     a0, a0, t0
    # fall through

# set_state (file-local)
#   What: publishes a state word's new value (after every earlier memory
#         access of this hart) and raises hart a2's software interrupt.
#   Arguments: a0 = address of the state word, a1 = new state, a2 = hart
#              to signal, or SIGNAL_NONE.
#   Results: none.
#   Clobbers: only ABI temporaries.
set_state:
    fence   rw, w
    amoswap.w.rl zero, a1, (a0)
    bltz    a2, 1f                      # SIGNAL_NONE
    fence                               # state visible before the IPI
    slli    t2, a2, CLINT_MSIP_SHIFT
    li      t3, CLINT_MSIP
    add     t2, t2, t3
    li      t3, CLINT_MSIP_RAISE
    sw      t3, 0(t2)
1:  ret

# draw_split (file-local)
#   What: where hart 1's band of frame n begins (hart 0 draws the rows
#         above it): LCD_HEIGHT (hart 0 draws everything) for frame 0 (hart
#         1 brings the LCD up then), in wireframe mode (lines are cheap and
#         not split), with harts = 1, and with harts = auto while the last
#         frame's drawing (draw_work) took no longer than the LCD's transfer
#         (LCD_FRAME_CYCLES): then hart 1 drawing would not show. Else
#         draw_balance (draw_record). Depends on cycle counts only through
#         the choice of rows, never on what is drawn.
#   Arguments: a0 = frame number.
#   Results: a0 = first row of hart 1's band, 1 .. LCD_HEIGHT.
#   Clobbers: only ABI temporaries.
draw_split:
    beqz    a0, 8f
    la      t0, scene
    lwu     t1, SCENE_MODE(t0)
    li      t2, MODE_WIREFRAME
    beq     t1, t2, 8f
    lwu     t1, SCENE_HARTS(t0)
    li      t2, HARTS_ONE
    beq     t1, t2, 8f
    li      t2, HARTS_AUTO
    bne     t1, t2, 1f
    la      t0, draw_work
    ld      t0, 0(t0)
    li      t1, LCD_FRAME_CYCLES
    bleu    t0, t1, 8f
1:  la      t0, draw_balance
    lwu     a0, 0(t0)
    ret
8:  li      a0, LCD_HEIGHT
    ret

# draw_record (file-local)
#   What: keeps what frame n's drawing cost for draw_split: draw_work =
#         hart 0's cycles from render_prepare to the end of its band, but
#         for its wait at the vertex stage's barrier, plus hart 1's share
#         of the vertex stage and its band (the work of one hart drawing
#         alone, whatever the split), and, when both drew, a new
#         draw_balance: the row where
#         the two bands' cycles would be equal if each band's cost were
#         spread evenly over its rows, s' = H c1 s / (c0 (H - s) + c1 s)
#         (H = LCD_HEIGHT, s the split, c0, c1 the bands' cycles), kept
#         within DRAW_BAND_MIN rows of either edge.
#   Arguments: a0 = the split (draw_split), a1 = hart 0's band cycles,
#              a2 = the frame's cycles on both harts but for the bands'
#              of hart 1 and the barrier's wait, a3 = hart 1's band cycles.
#   Results: none.
#   Clobbers: only ABI temporaries.
draw_record:
    add     t0, a2, a3
    la      t1, draw_work
    sd      t0, 0(t1)
    li      t0, LCD_HEIGHT
    bgeu    a0, t0, 9f                  # hart 0 drew alone
    sub     t1, t0, a0                  # H - s
    mul     t1, t1, a1                  # c0 (H - s)
    mul     t2, a3, a0                  # c1 s
    add     t1, t1, t2
    beqz    t1, 9f
    mul     t2, t2, t0                  # H c1 s
    divu    t2, t2, t1                  # s'
    li      t3, DRAW_BAND_MIN
    bgeu    t2, t3, 1f
    mv      t2, t3
1:  li      t3, LCD_HEIGHT - DRAW_BAND_MIN
    bleu    t2, t3, 2f
    mv      t2, t3
2:  la      t1, draw_balance
    sw      t2, 0(t1)
9:  ret

# ---------------------------------------------------------------------------
    .section .rodata
msg_boot:           .asciz "boot: hart 0 up\n"
msg_clocks_pll0:    .asciz "clocks: PLL0 "
msg_clocks_cpu:     .asciz " Hz, CPU "
msg_hz_nl:          .asciz " Hz\n"
msg_pins:           .asciz "pins: LCD, UART and SD routed\n"
msg_lcd:            .asciz "lcd: ST7789V ready\n"
msg_hart1:          .asciz "hart 1: display loop\n"
msg_frame:          .asciz "frame "

# ---------------------------------------------------------------------------
    .bss
    .balign 64
    .globl framebuffers
# framebuffers: two 320 x 240 RGB565 frames; each 32-bit word holds a pixel pair with the first
# pixel in its upper half (the LCD takes 32-bit SPI frames most significant byte first).
framebuffers:
    .space  NUM_FRAMEBUFFERS * LCD_FB_BYTES
    .balign 8
# fb_frame: frame number held by each buffer (written by hart 0 before FULL).
fb_frame:
    .space  NUM_FRAMEBUFFERS * XLEN_BYTES
    .balign 4
# fb_state: FB_FREE / FB_FULL per buffer; 0 = FREE after .bss clearing.
fb_state:
    .space  NUM_FRAMEBUFFERS * 4
# band_job: hart 0's job for hart 1 (the handoff above).
    .balign 8
band_job:
    .space  JOB_BYTES
# draw_work: the last frame's drawing, cycles on both harts (draw_record).
draw_work:
    .space  8

    .data
    .balign 4
# draw_balance: the row where hart 1's band begins when both draw
# (draw_record), half the screen until both have drawn a frame.
draw_balance:
    .word   LCD_HEIGHT / 2
