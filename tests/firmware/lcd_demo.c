/* lcd_demo.c: four frames on the Dock's LCD, each sent a different way, for a golden check.
 *   frame 0: the whole screen filled with one colour (one word repeated by DMA);
 *   frame 1: a landscape picture as 32-bit pixel pairs (upright: MADCTL MY|MV);
 *   frame 2: the same picture as 16-bit pixels with MADCTL MX|MV (shown turned 180 degrees);
 *   frame 3: a portrait picture as bytes with MADCTL BGR (portrait, red and blue exchanged).
 * tests/end_to_end/test_c_firmware.py computes what each frame must look like. */
#include <stdio.h>

#include "drivers.h"
#include "k210.h"

#define CONSOLE_BAUD 115200u
#define FILL_COLOUR  0x2945u
#define WHITE        0xFFFFu
#define RED          0xF800u
#define GREEN        0x07E0u
#define BLUE         0x001Fu
#define PORTRAIT_WIDTH  LCD_HEIGHT
#define PORTRAIT_HEIGHT LCD_WIDTH

static uint32_t pairs[LCD_WIDTH * LCD_HEIGHT / 2];
static uint16_t pixels[LCD_WIDTH * LCD_HEIGHT];
static uint8_t portrait[PORTRAIT_WIDTH * PORTRAIT_HEIGHT * 2];

static uint16_t rgb565(uint32_t r5, uint32_t g6, uint32_t b5) { return (uint16_t)(r5 << 11 | g6 << 5 | b5); }

static int inside(int x, int y, int x0, int y0, int size) { return x >= x0 && x < x0 + size && y >= y0 && y < y0 + size; }

/* Landscape: red rises left to right, green top to bottom, a blue checkerboard of 20-pixel
 * squares, a white square near the top left and a red one near the bottom right. */
static uint16_t landscape_pixel(int x, int y)
{
    if (inside(x, y, 20, 20, 40))
        return WHITE;
    if (inside(x, y, 250, 170, 50))
        return RED;
    return rgb565((uint32_t)x * 32 / LCD_WIDTH, (uint32_t)y * 64 / LCD_HEIGHT, (x / 20 + y / 20) % 2 ? 31 : 0);
}

/* Portrait: red falls top to bottom, green rises left to right, blue at half, a green square
 * near the top left and a blue one near the bottom right. */
static uint16_t portrait_pixel(int x, int y)
{
    if (inside(x, y, 10, 10, 40))
        return GREEN;
    if (inside(x, y, 180, 260, 50))
        return BLUE;
    return rgb565(31 - (uint32_t)y * 32 / PORTRAIT_HEIGHT, (uint32_t)x * 64 / PORTRAIT_WIDTH, 16);
}

static void draw_pictures(void)
{
    for (int y = 0; y < LCD_HEIGHT; y++) {
        for (int x = 0; x < LCD_WIDTH; x++) {
            uint16_t colour = landscape_pixel(x, y);
            int index = y * LCD_WIDTH + x;
            pixels[index] = colour;
            if (index % 2 == 0)
                pairs[index / 2] = (uint32_t)colour << 16;
            else
                pairs[index / 2] |= colour;
        }
    }
    for (int y = 0; y < PORTRAIT_HEIGHT; y++) {
        for (int x = 0; x < PORTRAIT_WIDTH; x++) {
            uint16_t colour = portrait_pixel(x, y);
            portrait[2 * (y * PORTRAIT_WIDTH + x)] = (uint8_t)(colour >> 8);
            portrait[2 * (y * PORTRAIT_WIDTH + x) + 1] = (uint8_t)colour;
        }
    }
}

int main(void)
{
    clock_enable(CLOCK_FPIOA);
    fpioa_set_function(PAD_UARTHS_RX, FUNC_UARTHS_RX);
    fpioa_set_function(PAD_UARTHS_TX, FUNC_UARTHS_TX);
    uarths_init(CONSOLE_BAUD);
    draw_pictures();
    lcd_init();
    printf("lcd: ready\n");

    lcd_window(0, 0, LCD_WIDTH - 1, LCD_HEIGHT - 1);
    lcd_fill(FILL_COLOUR, LCD_WIDTH * LCD_HEIGHT);
    printf("lcd: frame 0 sent (fill)\n");

    lcd_window(0, 0, LCD_WIDTH - 1, LCD_HEIGHT - 1);
    lcd_pixels32(pairs, LCD_WIDTH * LCD_HEIGHT / 2);
    printf("lcd: frame 1 sent (32-bit pairs)\n");

    lcd_madctl(MADCTL_MX | MADCTL_MV);
    lcd_window(0, 0, LCD_WIDTH - 1, LCD_HEIGHT - 1);
    lcd_pixels16(pixels, LCD_WIDTH * LCD_HEIGHT);
    printf("lcd: frame 2 sent (16-bit, turned)\n");

    lcd_madctl(MADCTL_BGR);
    lcd_window(0, 0, PORTRAIT_WIDTH - 1, PORTRAIT_HEIGHT - 1);
    lcd_bytes(portrait, sizeof portrait);
    printf("lcd: frame 3 sent (bytes, portrait, BGR)\n");
    return 0;
}
