/* uarths.c: the console on UARTHS, and picolibc's stdout on top of it. */
#include <stdio.h>

#include "drivers.h"
#include "k210.h"

/* Baud = CPU clock / (div + 1); transmitter and receiver on, no interrupts (uarths_init). */
void uarths_init(uint32_t baud)
{
    mmio_write32(UARTHS_BASE + UARTHS_DIV, cpu_hz() / baud - 1);
    mmio_write32(UARTHS_BASE + UARTHS_TXCTRL, UARTHS_TXEN);
    mmio_write32(UARTHS_BASE + UARTHS_RXCTRL, UARTHS_RXEN);
    mmio_write32(UARTHS_BASE + UARTHS_IE, 0);
}

/* Waits for room in the transmit FIFO (txdata bit 31), then stores the byte with a byte
 * store to txdata's data field: what uarths_putchar's `txdata.data = c` compiles to without
 * -fstrict-volatile-bitfields. */
void uarths_putc(char c)
{
    while (mmio_read32(UARTHS_BASE + UARTHS_TXDATA) & UARTHS_TXDATA_FULL)
        ;
    mmio_write8(UARTHS_BASE + UARTHS_TXDATA, (uint8_t)c);
}

/* Waits for a byte in the receive FIFO (rxdata bit 31 clear) and returns it; reading rxdata
 * takes the byte out of the FIFO. */
int uarths_getc(void)
{
    uint32_t word;
    while ((word = mmio_read32(UARTHS_BASE + UARTHS_RXDATA)) & UARTHS_RXDATA_EMPTY)
        ;
    return (int)(word & 0xFF);
}

static int console_get(FILE *file)
{
    (void)file;
    return uarths_getc();
}

static int console_put(char c, FILE *file)
{
    (void)file;
    if (c == '\n')
        uarths_putc('\r');
    uarths_putc(c);
    return (unsigned char)c;
}

static FILE console = FDEV_SETUP_STREAM(console_put, console_get, NULL, _FDEV_SETUP_RW);
FILE *const stdin = &console;
FILE *const stdout = &console;
FILE *const stderr = &console;
