/* lcd.c: the Maix Dock's ST7789V. Its 8-bit parallel bus is SPI0's eight data lines in the
 * octal frame format, its write strobe SPI0's clock (pad 39), its chip select SPI0's slave
 * select 3 (pad 36); D/C is a GPIOHS line (pad 38) and reset a slow-GPIO line (pad 37).
 * Built with LCD_SERIAL, it drives a 4-line serial ST7789V module on the same pins instead,
 * as MaixPy's driver does such panels: standard SPI frames on SPI0's data line 0 (pad 40),
 * D/C a slow-GPIO line and reset a GPIOHS line.
 * Every transfer goes by DMA, as the SDK's LCD driver sends: commands and parameters as
 * 8-bit frames, pixels as 16- or 32-bit frames, a fill as one word repeated. */
#include "drivers.h"
#include "k210.h"

#define LCD_DMA_CHANNEL     0
#define LCD_CHIP_SELECT     3
#ifdef LCD_SERIAL
#define PAD_LCD_SDA         40
#define LCD_DC_IS_GPIOHS    0
#define LCD_DC_LINE         1
#define LCD_RST_IS_GPIOHS   1
#define LCD_RST_LINE        3
#else
#define LCD_DC_IS_GPIOHS    1
#define LCD_DC_LINE         2
#define LCD_RST_IS_GPIOHS   0
#define LCD_RST_LINE        0
#endif
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

static void line_write(int is_gpiohs, int line, int level)
{
    if (is_gpiohs)
        gpiohs_write(line, level);
    else
        gpio_write(line, level);
}

static void line_make_output(int is_gpiohs, int line)
{
    if (is_gpiohs)
        gpiohs_make_output(line);
    else
        gpio_make_output(line);
}

/* The bus set up for one kind of transfer, as the SDK's tft_write_* functions do each time:
 * frames of frame_bits; in octal, the instruction phase (8 or 16 bits) or the address phase
 * (32 bits) the same length as a frame, sent in the frame format. */
static void lcd_bus(enum dc dc, int frame_bits)
{
    line_write(LCD_DC_IS_GPIOHS, LCD_DC_LINE, dc);
#ifdef LCD_SERIAL
    spi0_init(SPI_FF_STANDARD, frame_bits);
#else
    spi0_init(SPI_FF_OCTAL, frame_bits);
    if (frame_bits == 32)
        spi0_init_non_standard(0, 32, 0, SPI_AITM_AS_FRAME_FORMAT);
    else
        spi0_init_non_standard(frame_bits, 0, 0, SPI_AITM_AS_FRAME_FORMAT);
#endif
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
    fpioa_set_function(PAD_LCD_DC, (LCD_DC_IS_GPIOHS ? FUNC_GPIOHS0 : FUNC_GPIO0) + LCD_DC_LINE);
    fpioa_set_function(PAD_LCD_RST, (LCD_RST_IS_GPIOHS ? FUNC_GPIOHS0 : FUNC_GPIO0) + LCD_RST_LINE);
#ifdef LCD_SERIAL
    fpioa_set_function(PAD_LCD_SDA, FUNC_SPI0_D0);
#else
    spi0_dvp_data_enable();
#endif
    io_banks_1v8(POWER_BANK6_1V8 | POWER_BANK7_1V8);
    line_write(LCD_DC_IS_GPIOHS, LCD_DC_LINE, DC_DATA);
    line_make_output(LCD_DC_IS_GPIOHS, LCD_DC_LINE);
    line_write(LCD_RST_IS_GPIOHS, LCD_RST_LINE, 1);
    line_make_output(LCD_RST_IS_GPIOHS, LCD_RST_LINE);
    dmac_init();
    spi0_init(SPI_FF_OCTAL, 8);
    spi0_set_clock(LCD_SPI_HZ);

    line_write(LCD_RST_IS_GPIOHS, LCD_RST_LINE, 0);
    delay_us(LCD_RESET_PULSE_US);
    line_write(LCD_RST_IS_GPIOHS, LCD_RST_LINE, 1);
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
