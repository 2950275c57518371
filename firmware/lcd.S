# lcd.S: the ST7789V on the Maix Dock: bring-up, windows, whole frames.
#
# D/C (GPIOHS1) is 0 for a command byte and 1 for its parameters and for
# pixel data; it only changes between SPI transfers (spi_dma.S waits for the
# bus to drain before returning). Reset is GPIOHS0, active low.
#
# INVOFF: the Kendryte SDK's lcd_init for this board sends no inversion
# command and MaixPy's default for the Dock is invert = False, so the panel
# needs none; INVOFF is sent explicitly so the state does not depend on
# what the boot ROM or a previous program left behind.

    .option norelax
    .include "k210.inc"
    .include "st7789v.inc"
    .include "frame.inc"

    .text
    .globl lcd_init
# lcd_init
#   What: SPI0 to its idle LCD set-up, hardware reset pulse, then SLPOUT,
#         COLMOD 16-bit, MADCTL upright landscape, INVOFF, NORON, full-screen
#         window, DISPON; marks the LCD ready for the error screen. Runs on
#         hart 1 while hart 0 loads the card (main.S): it sleeps through the
#         datasheet's waits (st7789v.inc), about 125 ms in all, sending the
#         console's relayed output meanwhile (console_wait_us).
#         No SWRESET: the RESX pulse already puts every register at its
#         default, and a SWRESET would start the 120 ms before SLPOUT again.
#   Arguments: a0 = CPU clock in Hz (for the reset pulse; the longer waits
#         use cpu_hz, the same clock).
#   Results: none.
#   Clobbers: only ABI temporaries.
lcd_init:
    FRAME_SAVE 16, ra, s0
    mv      s0, a0

    call    spi0_init

    li      a0, GPIOHS_LCD_DC_BIT
    call    gpiohs_set
    li      a0, GPIOHS_LCD_RST_BIT
    call    gpiohs_clear
    li      a0, LCD_RESET_LOW_US
    mv      a1, s0
    call    delay_us
    li      a0, GPIOHS_LCD_RST_BIT
    call    gpiohs_set
    li      a0, LCD_RESET_WAIT_US
    call    console_wait_us

    li      a0, LCD_CMD_SLPOUT
    call    lcd_command
    li      a0, LCD_SLPOUT_WAIT_US
    call    console_wait_us

    li      a0, LCD_CMD_COLMOD
    li      a1, COLMOD_RGB565
    call    lcd_command_byte
    li      a0, LCD_CMD_MADCTL
    li      a1, LCD_MADCTL_DOCK
    call    lcd_command_byte
    li      a0, LCD_CMD_INVOFF
    call    lcd_command
    li      a0, LCD_CMD_NORON
    call    lcd_command
    li      a0, 0
    li      a1, 0
    li      a2, LCD_WIDTH - 1
    li      a3, LCD_HEIGHT - 1
    call    lcd_set_window
    li      a0, LCD_CMD_DISPON
    call    lcd_command

    fence   rw, w
    la      t0, lcd_ready
    li      t1, 1
    sw      t1, 0(t0)

    FRAME_RESTORE 16, ra, s0
    ret

    .globl lcd_command
# lcd_command
#   What: sends one command byte with D/C low.
#   Arguments: a0 = command code.
#   Results: none.
#   Clobbers: only ABI temporaries.
lcd_command:
    FRAME_SAVE 16, ra
    sb      a0, 0(sp)
    li      a0, GPIOHS_LCD_DC_BIT
    call    gpiohs_clear
    mv      a0, sp
    li      a1, 1
    call    spi0_send_bytes
    FRAME_RESTORE 16, ra
    ret

    .globl lcd_command_params
# lcd_command_params
#   What: sends a command byte (D/C low) followed by its parameter bytes
#         (D/C high).
#   Arguments: a0 = command code, a1 = parameter address, a2 = count (> 0).
#   Results: none.
#   Clobbers: only ABI temporaries.
lcd_command_params:
    FRAME_SAVE 32, ra, s0, s1
    mv      s0, a1
    mv      s1, a2
    call    lcd_command
    li      a0, GPIOHS_LCD_DC_BIT
    call    gpiohs_set
    mv      a0, s0
    mv      a1, s1
    call    spi0_send_bytes
    FRAME_RESTORE 32, ra, s0, s1
    ret

# lcd_command_byte (file-local)
#   What: a command with a single parameter byte.
#   Arguments: a0 = command code, a1 = parameter.
#   Results: none.
#   Clobbers: only ABI temporaries.
lcd_command_byte:
    FRAME_SAVE 16, ra
    sb      a1, 0(sp)
    mv      a1, sp
    li      a2, 1
    call    lcd_command_params
    FRAME_RESTORE 16, ra
    ret

# lcd_command_range (file-local)
#   What: CASET or RASET: start and end as two big-endian 16-bit values.
#   Arguments: a0 = command code, a1 = start, a2 = end.
#   Results: none.
#   Clobbers: only ABI temporaries.
lcd_command_range:
    FRAME_SAVE 16, ra
    srli    t0, a1, 8
    sb      t0, 0(sp)
    sb      a1, 1(sp)
    srli    t0, a2, 8
    sb      t0, 2(sp)
    sb      a2, 3(sp)
    mv      a1, sp
    li      a2, LCD_WINDOW_BYTES
    call    lcd_command_params
    FRAME_RESTORE 16, ra
    ret

    .globl lcd_set_window
# lcd_set_window
#   What: sets the GRAM window the next RAMWR fills (inclusive corners, in
#         the landscape coordinates MADCTL set up).
#   Arguments: a0 = x start, a1 = y start, a2 = x end, a3 = y end.
#   Results: none.
#   Clobbers: only ABI temporaries.
lcd_set_window:
    FRAME_SAVE 32, ra, s0, s1
    mv      s0, a1
    mv      s1, a3
    mv      a1, a0
    li      a0, LCD_CMD_CASET
    call    lcd_command_range
    li      a0, LCD_CMD_RASET
    mv      a1, s0
    mv      a2, s1
    call    lcd_command_range
    FRAME_RESTORE 32, ra, s0, s1
    ret

# lcd_begin_full_frame (file-local)
#   What: RAMWR, D/C high: the LCD now takes a whole screen of pixels. The
#         window is the whole screen, as lcd_init set it and nothing changes
#         it, and RAMWR starts writing at the window's first pixel (ST7789V
#         datasheet, RAMWR: the column and page registers go back to the
#         start column and page), so it is not sent again each frame.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
lcd_begin_full_frame:
    FRAME_SAVE 16, ra
    li      a0, LCD_CMD_RAMWR
    call    lcd_command
    li      a0, GPIOHS_LCD_DC_BIT
    call    gpiohs_set
    FRAME_RESTORE 16, ra
    ret

    .globl lcd_send_frame
# lcd_send_frame
#   What: sends a whole 320 x 240 RGB565 framebuffer to the LCD by DMA
#         (sleeps in WFI while it goes): lcd_frame_start, then
#         lcd_frame_finish. The buffer holds 32-bit words with the earlier
#         pixel of each pair in bits 31:16.
#   Arguments: a0 = framebuffer address.
#   Results: none.
#   Clobbers: only ABI temporaries.
lcd_send_frame:
    FRAME_SAVE 16, ra
    call    lcd_frame_start
    call    lcd_frame_finish
    FRAME_RESTORE 16, ra
    ret

    .globl lcd_frame_start
# lcd_frame_start
#   What: starts sending a whole framebuffer to the LCD (RAMWR,
#         then the pixels by DMA) and returns while the DMA runs: the
#         caller may do other work, leaving the buffer and SPI0 alone, until
#         it calls lcd_frame_finish.
#   Arguments: a0 = framebuffer address.
#   Results: none.
#   Clobbers: only ABI temporaries.
lcd_frame_start:
    FRAME_SAVE 16, ra, s0
    mv      s0, a0
    call    lcd_begin_full_frame
    mv      a0, s0
    li      a1, LCD_FB_WORDS
    call    spi0_dma_send_start
    FRAME_RESTORE 16, ra, s0
    ret

    .globl lcd_frame_finish
# lcd_frame_finish
#   What: waits (in WFI) until the frame lcd_frame_start began is out.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
lcd_frame_finish:
    tail    spi0_dma_send_finish

    .globl lcd_error_screen
# lcd_error_screen
#   What: fills the whole screen with the error colour (lcd_error_colour:
#         solid red for a trap unless errors.S chose the colour of a fatal
#         error), after letting any DMA in flight finish: by a polled DMA
#         fill once dma_init has run, else by a polled SPI transfer. For the
#         trap handler and fatal errors: needs no framebuffer, no interrupts,
#         no delays. Does nothing if the LCD was never brought up.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
lcd_error_screen:
    la      t0, lcd_ready
    lw      t0, 0(t0)
    beqz    t0, 2f
    FRAME_SAVE 16, ra
    call    dma_quiesce
    call    lcd_begin_full_frame
    la      t0, lcd_error_colour
    lhu     a0, 0(t0)
    slli    t1, a0, 16
    or      a0, a0, t1                  # both pixels of each 32-bit frame
    li      a1, LCD_FB_WORDS
    la      t0, dma_ready
    lw      t0, 0(t0)
    beqz    t0, 1f
    la      t0, lcd_error_word          # the DMAC reads the colour from memory
    sw      a0, 0(t0)
    mv      a0, t0
    call    spi0_dma_fill_words
    j       3f
1:  call    spi0_fill_words
3:  FRAME_RESTORE 16, ra
2:  ret

# ---------------------------------------------------------------------------
    .data
    .balign 4
    .globl lcd_ready
# lcd_ready: 1 once lcd_init has brought the panel up. In .data so that a
# trap on hart 1 before .bss is cleared reads a valid 0.
lcd_ready:
    .word   0
    .globl lcd_error_colour
# lcd_error_colour: RGB565 colour lcd_error_screen fills the screen with; red
# (a trap) unless errors.S stored the colour of a fatal error first.
lcd_error_colour:
    .word   RGB565_RED
# lcd_error_word: the error colour twice, the word a DMA fill sends over and over.
lcd_error_word:
    .word   0
