# pins.S: FPIOA pad routing and the GPIOHS lines of the LCD.
#
# Pad words follow the SDK's fpioa_set_function / function_config table:
#   SPI0_SS3, SPI0_SCLK, UARTHS_TX (outputs): function | drive 0xF | oe_en
#   UARTHS_RX (input):                       function | ie_en | Schmitt trigger
#   GPIOHS0/1 (bidirectional lines):         function | drive 0xF | oe_en |
#                                            ie_en | Schmitt trigger
# (the GPIOHS block's output_en, not the pad, decides the direction there).
# Unlike the SDK, no other pad is scanned for the same function: nothing but
# this firmware has routed pads since reset.

    .option norelax
    .include "k210.inc"

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
pin_table_end:
    .equ PIN_ENTRY_BYTES, 8

    .text
    .globl pins_init
# pins_init
#   What: routes the UARTHS, LCD chip select/clock and the LCD reset and D/C
#         GPIOHS lines to their Maix Dock pads; drives reset and D/C high
#         (reset released, data mode) before making them outputs, so neither
#         line glitches low. Needs the FPIOA clock (clocks_init).
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
    li      t1, GPIOHS_LCD_RST_BIT | GPIOHS_LCD_DC_BIT
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
    li      t0, GPIOHS_BASE
    lw      t1, GPIOHS_OUTPUT_VAL(t0)
    or      t1, t1, a0
    sw      t1, GPIOHS_OUTPUT_VAL(t0)
    fence   o, o                        # the level is out before later device writes
    ret

    .globl gpiohs_clear
# gpiohs_clear
#   What: drives the GPIOHS lines in a0 low, leaving the others as they are.
#   Arguments: a0 = mask of GPIOHS lines. Results: none.
#   Clobbers: only ABI temporaries.
gpiohs_clear:
    li      t0, GPIOHS_BASE
    lw      t1, GPIOHS_OUTPUT_VAL(t0)
    not     t2, a0
    and     t1, t1, t2
    sw      t1, GPIOHS_OUTPUT_VAL(t0)
    fence   o, o
    ret
