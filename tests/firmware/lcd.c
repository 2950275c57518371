/* lcd.c: the Maix Dock's ST7789V. Its 8-bit parallel bus is SPI0's eight data lines in the
 * octal frame format, its write strobe SPI0's clock (pad 39), its chip select SPI0's slave
 * select 3 (pad 36); D/C is a GPIOHS line (pad 38) and reset a slow-GPIO line (pad 37).
 * Every transfer goes by DMA, as the SDK's LCD driver sends: commands and parameters as
 * 8-bit frames, pixels as 16- or 32-bit frames, a fill as one word repeated. */
#include "drivers.h"
#include "k210.h"

#define LCD_DMA_CHANNEL     0
#define LCD_CHIP_SELECT     3
#define LCD_DC_GPIOHS_LINE  2
#define LCD_RST_GPIO_LINE   0
#define LCD_SPI_HZ          10000000u
#define LCD_RESET_PULSE_US  1000u         /* the datasheet asks for 10 us at least */
#define LCD_RESET_WAIT_US   120000u       /* after RESX release, SWRESET and SLPOUT */

#define ST_SWRESET 0x01
#define ST_SLPOUT  0x11
#define ST_DISPON  0x29
#define ST_CASET   0x2A
#define ST_RASET   0x2B
#define ST_RAMWR   0x2C
#define ST_MADCTL  0x36
#define ST_COLMOD  0x3A
#define COLMOD_RGB565 0x55
#define MADCTL_DOCK_UPRIGHT (MADCTL_MY | MADCTL_MV)

enum dc { DC_COMMAND = 0, DC_DATA = 1 };

/* The bus set up for one kind of transfer, as the SDK's tft_write_* functions do each time:
 * octal frames of frame_bits, the instruction phase (8 or 16 bits) or the address phase
 * (32 bits) the same length as a frame, sent in the frame format. */
static void lcd_bus(enum dc dc, int frame_bits)
{
    gpiohs_write(LCD_DC_GPIOHS_LINE, dc);
    spi0_init(SPI_FF_OCTAL, frame_bits);
    if (frame_bits == 32)
        spi0_init_non_standard(0, 32, 0, SPI_AITM_AS_FRAME_FORMAT);
    else
        spi0_init_non_standard(frame_bits, 0, 0, SPI_AITM_AS_FRAME_FORMAT);
}

/* A command byte, sent as the SDK's tft_write_command does: one 32-bit DMA item. */
static void lcd_command(uint8_t command)
{
    uint32_t item = command;
    lcd_bus(DC_COMMAND, 8);
    spi0_send_dma(LCD_DMA_CHANNEL, LCD_CHIP_SELECT, &item, 1, DMA_WIDTH_32);
}

/* Parameter or pixel bytes, 8-bit DMA items into 8-bit frames. */
void lcd_bytes(const uint8_t *bytes, size_t count)
{
    lcd_bus(DC_DATA, 8);
    spi0_send_dma(LCD_DMA_CHANNEL, LCD_CHIP_SELECT, bytes, count, DMA_WIDTH_8);
}

/* RGB565 pixels, 16-bit DMA items into 16-bit frames (each sent high byte first). */
void lcd_pixels16(const uint16_t *pixels, size_t count)
{
    lcd_bus(DC_DATA, 16);
    spi0_send_dma(LCD_DMA_CHANNEL, LCD_CHIP_SELECT, pixels, count, DMA_WIDTH_16);
}

/* Pixel pairs, 32-bit DMA items into 32-bit frames: the pixel in the upper half goes first. */
void lcd_pixels32(const uint32_t *pairs, size_t words)
{
    lcd_bus(DC_DATA, 32);
    spi0_send_dma(LCD_DMA_CHANNEL, LCD_CHIP_SELECT, pairs, words, DMA_WIDTH_32);
}

/* `pixels` (even) pixels of one colour: one word repeated by a fixed-source DMA. */
void lcd_fill(uint16_t colour, size_t pixels)
{
    uint32_t pair = (uint32_t)colour << 16 | colour;
    lcd_bus(DC_DATA, 32);
    spi0_fill_dma(LCD_DMA_CHANNEL, LCD_CHIP_SELECT, &pair, pixels / 2);
}

void lcd_madctl(uint8_t value)
{
    lcd_command(ST_MADCTL);
    lcd_bytes(&value, 1);
}

/* CASET, RASET (inclusive ends) and RAMWR: the next pixels fill that window. */
void lcd_window(uint16_t x0, uint16_t y0, uint16_t x1, uint16_t y1)
{
    uint8_t columns[4] = {(uint8_t)(x0 >> 8), (uint8_t)x0, (uint8_t)(x1 >> 8), (uint8_t)x1};
    uint8_t rows[4] = {(uint8_t)(y0 >> 8), (uint8_t)y0, (uint8_t)(y1 >> 8), (uint8_t)y1};
    lcd_command(ST_CASET);
    lcd_bytes(columns, 4);
    lcd_command(ST_RASET);
    lcd_bytes(rows, 4);
    lcd_command(ST_RAMWR);
}

/* Pins, the DMAC and SPI0, a hardware reset pulse, then SWRESET, SLPOUT, 16-bit colour,
 * the Dock's upright landscape orientation and DISPON, with the datasheet's waits. */
void lcd_init(void)
{
    clock_enable(CLOCK_FPIOA);
    clock_enable(CLOCK_GPIO);
    fpioa_set_function(PAD_LCD_CS, FUNC_SPI0_SS3);
    fpioa_set_function(PAD_LCD_WR, FUNC_SPI0_SCLK);
    fpioa_set_function(PAD_LCD_DC, FUNC_GPIOHS0 + LCD_DC_GPIOHS_LINE);
    fpioa_set_function(PAD_LCD_RST, FUNC_GPIO0 + LCD_RST_GPIO_LINE);
    spi0_dvp_data_enable();
    io_banks_1v8(POWER_BANK6_1V8 | POWER_BANK7_1V8);
    gpiohs_make_output(LCD_DC_GPIOHS_LINE);
    gpiohs_write(LCD_DC_GPIOHS_LINE, DC_DATA);
    gpio_write(LCD_RST_GPIO_LINE, 1);
    gpio_make_output(LCD_RST_GPIO_LINE);
    dmac_init();
    spi0_init(SPI_FF_OCTAL, 8);
    spi0_set_clock(LCD_SPI_HZ);

    gpio_write(LCD_RST_GPIO_LINE, 0);
    delay_us(LCD_RESET_PULSE_US);
    gpio_write(LCD_RST_GPIO_LINE, 1);
    delay_us(LCD_RESET_WAIT_US);
    lcd_command(ST_SWRESET);
    delay_us(LCD_RESET_WAIT_US);
    lcd_command(ST_SLPOUT);
    delay_us(LCD_RESET_WAIT_US);
    uint8_t colmod = COLMOD_RGB565;
    lcd_command(ST_COLMOD);
    lcd_bytes(&colmod, 1);
    lcd_madctl(MADCTL_DOCK_UPRIGHT);
    lcd_command(ST_DISPON);
}
