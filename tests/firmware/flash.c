/* flash.c: the Dock's W25Q128 flash on SPI3, through drivers in the SDK's manner. Its JEDEC ID;
 * a sector erased, a page programmed in quad mode by DMA and read back in quad I/O by DMA and
 * with the standard read; programming that only clears bits; the sector erased again; and the
 * 16 bytes a test put at TEST_DATA read in quad I/O as 32-bit frames (each word as the wire
 * gives it: the first byte in the top bits). Then a run count kept in the flash: the zero bytes
 * at COUNTER are the runs before this one, and this run clears one more (page program, 1 line). */
#include <stdio.h>
#include <string.h>

#include "drivers.h"
#include "k210.h"

#define CONSOLE_BAUD  115200u
#define FLASH_HZ      25000000u
#define SCRATCH       0x200000u        /* a sector the program erases and writes */
#define TEST_DATA     0x100000u        /* 16 bytes the test wrote into the flash image */
#define COUNTER       0x300000u        /* a run count: one byte cleared per run */
#define PAGE          256
#define DMA_CHANNEL   0

enum { PAGE_PROGRAM = 0x02, WRITE_ENABLE = 0x06, READ_STATUS1 = 0x05, READ_STATUS2 = 0x35, JEDEC_ID = 0x9F, READ_DATA = 0x03,
       SECTOR_ERASE = 0x20, QUAD_PAGE_PROGRAM = 0x32, FAST_READ_QUAD_IO = 0xEB };
#define STATUS1_BUSY  0x01
#define STATUS2_QE    0x02

static uint8_t page[PAGE];
static uint32_t words[2 + PAGE / 4];

static uint8_t status(uint8_t command)
{
    uint8_t value;
    spi3_init(SPI_FF_STANDARD, 8);
    spi3_receive(&command, 1, &value, 1);
    return value;
}

static void command(const uint8_t *bytes, size_t count)
{
    spi3_init(SPI_FF_STANDARD, 8);
    spi3_send(bytes, count);
}

/* Polls BUSY every 50 us (a program takes about 0.7 ms, a sector erase 45 ms). */
static void wait_ready(void)
{
    while (status(READ_STATUS1) & STATUS1_BUSY)
        delay_us(50);
}

static void erase_sector(uint32_t address)
{
    const uint8_t enable = WRITE_ENABLE;
    const uint8_t erase[4] = {SECTOR_ERASE, address >> 16, address >> 8, address};
    command(&enable, 1);
    command(erase, sizeof erase);
    wait_ready();
}

/* Quad page program: 32-bit frames, each word's top byte first on the wire. */
static void program_page(uint32_t address, const uint8_t *bytes)
{
    const uint8_t enable = WRITE_ENABLE;
    command(&enable, 1);
    words[0] = QUAD_PAGE_PROGRAM;
    words[1] = address;
    for (int i = 0; i < PAGE / 4; i++)
        words[2 + i] = (uint32_t)bytes[4 * i] << 24 | (uint32_t)bytes[4 * i + 1] << 16
                     | (uint32_t)bytes[4 * i + 2] << 8 | bytes[4 * i + 3];
    spi3_init(SPI_FF_QUAD, 32);
    spi3_init_non_standard(8, 24, 0, SPI_AITM_STANDARD);
    spi3_send_dma(DMA_CHANNEL, words, 2 + PAGE / 4);
    wait_ready();
}

/* Fast read quad I/O (EBh): address and mode byte 0 on four lines, four wait cycles; `bits`-bit
 * frames, each stored as one word. */
static void read_quad(uint32_t address, int bits, uint32_t *items, size_t count)
{
    spi3_init(SPI_FF_QUAD, bits);
    spi3_init_non_standard(8, 32, 4, SPI_AITM_ADDR_STANDARD);
    spi3_receive_dma(DMA_CHANNEL, FAST_READ_QUAD_IO, address << 8, items, count);
}

static void read_standard(uint32_t address, uint8_t *bytes, size_t count)
{
    const uint8_t read[4] = {READ_DATA, address >> 16, address >> 8, address};
    spi3_init(SPI_FF_STANDARD, 8);
    spi3_receive(read, sizeof read, bytes, count);
}

static int all(const uint8_t *bytes, size_t count, uint8_t value)
{
    for (size_t i = 0; i < count; i++)
        if (bytes[i] != value)
            return 0;
    return 1;
}

int main(void)
{
    static uint32_t frames[PAGE];
    static uint8_t back[PAGE];
    clock_enable(CLOCK_FPIOA);
    fpioa_set_function(PAD_UARTHS_RX, FUNC_UARTHS_RX);
    fpioa_set_function(PAD_UARTHS_TX, FUNC_UARTHS_TX);
    uarths_init(CONSOLE_BAUD);
    dmac_init();
    spi3_init(SPI_FF_STANDARD, 8);
    printf("flash clock %lu Hz\n", (unsigned long)spi3_set_clock(FLASH_HZ));

    uint8_t id[3];
    const uint8_t jedec = JEDEC_ID;
    spi3_init(SPI_FF_STANDARD, 8);
    spi3_receive(&jedec, 1, id, sizeof id);
    printf("jedec id %02x %02x %02x, quad %s\n", id[0], id[1], id[2], status(READ_STATUS2) & STATUS2_QE ? "on" : "off");

    erase_sector(SCRATCH);
    read_standard(SCRATCH, back, PAGE);
    printf("erased: %s\n", all(back, PAGE, 0xFF) ? "all ff" : "not erased");

    for (int i = 0; i < PAGE; i++)
        page[i] = (uint8_t)(7 * i + 3);
    program_page(SCRATCH, page);
    read_quad(SCRATCH, 8, frames, PAGE);
    int quad_ok = 1;
    for (int i = 0; i < PAGE; i++)
        quad_ok &= frames[i] == page[i];
    read_standard(SCRATCH, back, PAGE);
    printf("programmed: quad read %s, standard read %s\n", quad_ok ? "matches" : "differs",
           memcmp(back, page, PAGE) ? "differs" : "matches");

    memset(page, 0xF0, PAGE);
    program_page(SCRATCH + PAGE, page);
    memset(page, 0x0F, PAGE);
    program_page(SCRATCH + PAGE, page);
    read_standard(SCRATCH + PAGE, back, PAGE);
    printf("f0 then 0f: %s\n", all(back, PAGE, 0x00) ? "all 00" : "not 00");

    erase_sector(SCRATCH);
    read_standard(SCRATCH, back, PAGE);
    printf("erased again: %s\n", all(back, PAGE, 0xFF) ? "all ff" : "not erased");

    read_quad(TEST_DATA, 32, frames, 4);
    printf("test data %08lx %08lx %08lx %08lx\n", (unsigned long)frames[0], (unsigned long)frames[1],
           (unsigned long)frames[2], (unsigned long)frames[3]);
    read_standard(COUNTER, back, 16);
    int runs = 0;
    while (runs < 16 && back[runs] == 0)
        runs++;
    printf("runs before this one: %d\n", runs);
    if (runs < 16) {
        const uint8_t enable = WRITE_ENABLE;
        uint32_t at = COUNTER + runs;
        const uint8_t program[5] = {PAGE_PROGRAM, at >> 16, at >> 8, at, 0x00};
        command(&enable, 1);
        command(program, sizeof program);
        wait_ready();
    }
    printf("flash done\n");
    return 0;
}
