# pins.S: FPIOA pad routing, the GPIOHS lines of the LCD and the SD card's
# chip select.
#
# Pad words follow the SDK's fpioa_set_function / function_config table:
#   SPI0_SS3, SPI0_SCLK, SPI1_SCLK,
#   UARTHS_TX (outputs):                     function | drive 0xF | oe_en
#   UARTHS_RX (input):                       function | ie_en | Schmitt trigger
#   GPIOHS0/1/7, SPI1_D0/D1 (bidirectional): function | drive 0xF | oe_en |
#                                            ie_en | Schmitt trigger
# (the GPIOHS block's output_en, not the pad, decides the direction of a
# GPIOHS line; SPI1 in standard format drives D0 and listens on D1).
# The SD card's chip select (pad 29) is GPIOHS7 driven by software (sd_spi.S),
# not SPI1_SSn: the controller's own select drops whenever its FIFO runs dry.
# Unlike the SDK, no other pad is scanned for the same function: nothing but
# this firmware has routed pads since reset.

    .option norelax
    .include "k210.inc"
    .include "frame.inc"

    .section .rodata
    .balign 4
# (pad, pad word) pairs, one per routed pad.
pin_table:
    .word   PAD_UARTHS_RX, FUNC_UARTHS_RX | FPIOA_CFG_INPUT
    .word   PAD_UARTHS_TX, FUNC_UARTHS_TX | FPIOA_CFG_OUTPUT
    .word   PAD_LCD_CS,    FUNC_SPI0_SS3 | FPIOA_CFG_OUTPUT
    .word   PAD_LCD_RST,   (FUNC_GPIOHS0 + GPIOHS_LCD_RST) | FPIOA_CFG_GPIOHS
    .word   PAD_LCD_DC,    (FUNC_GPIOHS0 + GPIOHS_LCD_DC) | FPIOA_CFG_GPIOHS
    .word   PAD_LCD_SCLK,  FUNC_SPI0_SCLK | FPIOA_CFG_OUTPUT
    .word   PAD_SD_MISO,   FUNC_SPI1_D1 | FPIOA_CFG_BIDIR
    .word   PAD_SD_SCLK,   FUNC_SPI1_SCLK | FPIOA_CFG_OUTPUT
    .word   PAD_SD_MOSI,   FUNC_SPI1_D0 | FPIOA_CFG_BIDIR
    .word   PAD_SD_CS,     (FUNC_GPIOHS0 + GPIOHS_SD_CS) | FPIOA_CFG_GPIOHS
pin_table_end:
    .equ PIN_ENTRY_BYTES, 8

    .text
    .globl pins_init
# pins_init
#   What: routes the UARTHS, LCD chip select/clock, the LCD reset and D/C
#         GPIOHS lines, SPI1 (SD clock, MOSI, MISO) and the SD chip select
#         GPIOHS line to their Maix Dock pads; drives reset, D/C and the SD
#         chip select high (reset released, data mode, card deselected)
#         before making them outputs, so no line glitches low. Needs the
#         FPIOA clock (clocks_init).
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
pins_init:
    la      t0, pin_table
    la      t1, pin_table_end
    li      t2, FPIOA_BASE
1:  lw      t3, 0(t0)                   # pad
    lw      t4, 4(t0)                   # pad word
    slli    t3, t3, FPIOA_PAD_SHIFT
    add     t3, t3, t2
    sw      t4, 0(t3)
    addi    t0, t0, PIN_ENTRY_BYTES
    bltu    t0, t1, 1b

    li      t0, GPIOHS_BASE
    li      t1, GPIOHS_LCD_RST_BIT | GPIOHS_LCD_DC_BIT | GPIOHS_SD_CS_BIT
    lw      t2, GPIOHS_OUTPUT_VAL(t0)
    or      t2, t2, t1
    sw      t2, GPIOHS_OUTPUT_VAL(t0)
    not     t3, t1
    lw      t2, GPIOHS_INPUT_EN(t0)
    and     t2, t2, t3
    sw      t2, GPIOHS_INPUT_EN(t0)
    lw      t2, GPIOHS_OUTPUT_EN(t0)
    or      t2, t2, t1
    sw      t2, GPIOHS_OUTPUT_EN(t0)
    ret

    .globl gpiohs_set
# gpiohs_set
#   What: drives the GPIOHS lines in a0 high, leaving the others as they are.
#   Arguments: a0 = mask of GPIOHS lines. Results: none.
#   Clobbers: only ABI temporaries.
gpiohs_set:
    FRAME_SAVE 16, ra
    sd      a0, 0(sp)
    call    shared_io_lock
    ld      a0, 0(sp)
    li      t0, GPIOHS_BASE
    lw      t1, GPIOHS_OUTPUT_VAL(t0)
    or      t1, t1, a0
    sw      t1, GPIOHS_OUTPUT_VAL(t0)
    fence   o, o                        # the level is out before later device writes
    call    shared_io_unlock
    FRAME_RESTORE 16, ra
    ret

    .globl gpiohs_clear
# gpiohs_clear
#   What: drives the GPIOHS lines in a0 low, leaving the others as they are.
#   Arguments: a0 = mask of GPIOHS lines. Results: none.
#   Clobbers: only ABI temporaries.
gpiohs_clear:
    FRAME_SAVE 16, ra
    sd      a0, 0(sp)
    call    shared_io_lock
    ld      a0, 0(sp)
    li      t0, GPIOHS_BASE
    lw      t1, GPIOHS_OUTPUT_VAL(t0)
    not     t2, a0
    and     t1, t1, t2
    sw      t1, GPIOHS_OUTPUT_VAL(t0)
    fence   o, o
    call    shared_io_unlock
    FRAME_RESTORE 16, ra
    ret

    .globl shared_io_lock
# shared_io_lock
#   What: takes the lock on the device registers both harts change by
#         read-modify-write: GPIOHS output_val (hart 1 drives the LCD's reset
#         and D/C lines while hart 0 drives the SD card's chip select, all in
#         one register) and SYSCTL dma_sel0 (DMAC channel 0 for the LCD,
#         channel 1 for the card). Without it one hart's write could put back
#         a bit the other had just changed. Held for a few instructions, never
#         across a wait; a hart never takes it twice.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
shared_io_lock:
    la      t0, shared_io_owner
    csrr    t1, mhartid
    addi    t1, t1, 1
1:  lr.w.aq t2, (t0)
    bnez    t2, 1b
    sc.w    t2, t1, (t0)
    bnez    t2, 1b
    fence                               # device accesses stay after the lock is ours
    ret

    .globl shared_io_unlock
# shared_io_unlock
#   What: gives the lock shared_io_lock took back, after this hart's device
#         accesses under it.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
shared_io_unlock:
    la      t0, shared_io_owner
    fence
    amoswap.w.rl zero, zero, (t0)
    ret

# ---------------------------------------------------------------------------
    .data
    .balign 4
# shared_io_owner: 0 when free, else the holder's hart id + 1. In .data: valid
# before .bss is cleared.
shared_io_owner:
    .word   0
