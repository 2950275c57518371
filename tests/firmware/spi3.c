/* spi3.c: SPI3, the K210's DWC_ssi, whose chip select 0 is the Dock's flash. Its ctrlr0 puts
 * every field elsewhere than SPI0's (the SDK's spi.c, spi_num == 3); the rest is the SDK's
 * order: configure while disabled, enable, fill the FIFO (or start the DMA), then select. */
#include "drivers.h"
#include "k210.h"

#define FLASH_SELECT (1u << 0)

static uint32_t spi_read(uint32_t offset) { return mmio_read32(SPI3_BASE + offset); }
static void spi_write(uint32_t offset, uint32_t value) { mmio_write32(SPI3_BASE + offset, value); }

static void set_tmod(uint32_t tmod)
{
    spi_write(SPI_CTRLR0, (spi_read(SPI_CTRLR0) & ~(3u << SPI3_TMOD_SHIFT)) | tmod << SPI3_TMOD_SHIFT);
}

/* Waits for the wire to go idle with the transmit FIFO empty, then deselects and disables. */
static void finish(void)
{
    while ((spi_read(SPI_SR) & (SPI_SR_TFE | SPI_SR_BUSY)) != SPI_SR_TFE)
        ;
    spi_write(SPI_SER, 0);
    spi_write(SPI_SSIENR, 0);
}

/* Disabled, no interrupts or DMA, mode 0, the given frame format and size, plain phases. */
void spi3_init(int frame_format, int frame_bits)
{
    clock_enable(CLOCK_SPI3);
    ssi_init(SPI3_BASE, SPI3_FRF_SHIFT, SPI3_DFS_SHIFT, frame_format, frame_bits);
}

void spi3_init_non_standard(int instruction_bits, int address_bits, int wait_cycles, int trans_mode)
{
    ssi_init_non_standard(SPI3_BASE, instruction_bits, address_bits, wait_cycles, trans_mode);
}

/* The fastest serial clock at or below hz (the divider is even, 2..65534); returns it. */
uint32_t spi3_set_clock(uint32_t hz)
{
    uint32_t source = spi3_source_hz();
    uint32_t divider = (source + hz - 1) / hz;
    divider = divider < 2 ? 2 : divider > 65534 ? 65534 : (divider + 1) & ~1u;
    spi_write(SPI_BAUDR, divider);
    return source / divider;
}

/* Standard format, 8-bit frames: sends count bytes from the CPU, keeping the FIFO topped up. */
void spi3_send(const uint8_t *bytes, size_t count)
{
    set_tmod(SPI_TMOD_TRANSMIT);
    spi_write(SPI_SSIENR, 1);
    spi_write(SPI_SER, FLASH_SELECT);
    while (count) {
        size_t room = SPI_FIFO_DEPTH - spi_read(SPI_TXFLR);
        for (; room && count; room--, count--)
            spi_write(SPI_DR0, *bytes++);
    }
    finish();
}

/* Standard format, 8-bit frames, EEPROM-read mode: the command goes out, then count bytes of
 * reply come in (the SDK's spi_receive_data_standard with a command). */
void spi3_receive(const uint8_t *command, size_t command_length, uint8_t *reply, size_t count)
{
    set_tmod(SPI_TMOD_EEPROM);
    spi_write(SPI_CTRLR1, (uint32_t)(count - 1));
    spi_write(SPI_SSIENR, 1);
    for (size_t i = 0; i < command_length; i++)
        spi_write(SPI_DR0, command[i]);
    spi_write(SPI_SER, FLASH_SELECT);
    while (count) {
        for (size_t ready = spi_read(SPI_RXFLR); ready && count; ready--, count--)
            *reply++ = (uint8_t)spi_read(SPI_DR0);
    }
    spi_write(SPI_SER, 0);
    spi_write(SPI_SSIENR, 0);
}

/* A dual/quad transmit by DMA: items[0] is the instruction, items[1] the address, the rest the
 * data frames (spi_send_data_multiple_dma's buffer). */
void spi3_send_dma(int channel, const uint32_t *items, size_t count)
{
    set_tmod(SPI_TMOD_TRANSMIT);
    spi_write(SPI_DMACR, SPI_DMACR_TDMAE);
    spi_write(SPI_SSIENR, 1);
    dma_select(channel, DMA_REQ_SSI3_TX);
    dmac_start(channel, items, (volatile void *)(uintptr_t)(SPI3_BASE + SPI_DR0), 0, DMA_WIDTH_32, count);
    spi_write(SPI_SER, FLASH_SELECT);
    dmac_wait_done(channel);
    finish();
    spi_write(SPI_DMACR, 0);
}

/* A dual/quad receive: the instruction and address go out as their phases, then count frames
 * come in and the DMA stores each as a 32-bit item (receive-only mode, as the FreeRTOS SDK's
 * spi.cpp reads the flash). */
void spi3_receive_dma(int channel, uint32_t instruction, uint32_t address, uint32_t *items, size_t count)
{
    spi3_receive_dma_start(channel, instruction, address, items, count);
    dmac_wait_done(channel);
    spi3_receive_end();
}

/* spi3_receive_dma's first half: the transfer under way, the channel completing when the last
 * frame is in memory (its interrupt, or dmac_wait_done, says when). */
void spi3_receive_dma_start(int channel, uint32_t instruction, uint32_t address, uint32_t *items, size_t count)
{
    set_tmod(SPI_TMOD_RECEIVE);
    spi_write(SPI_CTRLR1, (uint32_t)(count - 1));
    spi_write(SPI_DMACR, SPI_DMACR_RDMAE);
    spi_write(SPI_SSIENR, 1);
    dma_select(channel, DMA_REQ_SSI3_RX);
    dmac_receive(channel, (volatile const void *)(uintptr_t)(SPI3_BASE + SPI_DR0), items, DMA_WIDTH_32, count);
    spi_write(SPI_DR0, instruction);
    spi_write(SPI_DR0, address);
    spi_write(SPI_SER, FLASH_SELECT);
}

/* Deselects the flash, disables the controller and its DMA requests. */
void spi3_receive_end(void)
{
    spi_write(SPI_SER, 0);
    spi_write(SPI_SSIENR, 0);
    spi_write(SPI_DMACR, 0);
}
