/* spi.c: SPI0 (DesignWare SSI) transmitting through DMA, in the SDK's order: the DMA channel
 * is started (and fills the transmit FIFO) before the slave select is written. */
#include "drivers.h"
#include "k210.h"

#define SPI0_DMA_REQUEST DMA_REQ_SSI0_TX

static uint32_t spi_read(uint32_t offset) { return mmio_read32(SPI0_BASE + offset); }
static void spi_write(uint32_t offset, uint32_t value) { mmio_write32(SPI0_BASE + offset, value); }

/* A DesignWare SSI at `base` (SPI0's ctrlr0 layout, or SPI3's: the shifts say where its frame
 * format and frame size go), clocked: disabled, no interrupts or DMA, mode 0, the given frame
 * format and size, plain phases, in spi_init's order. */
void ssi_init(uintptr_t base, unsigned frf_shift, unsigned dfs_shift, int frame_format, int frame_bits)
{
    if (mmio_read32(base + SPI_BAUDR) == 0)
        mmio_write32(base + SPI_BAUDR, 0x14);
    mmio_write32(base + SPI_IMR, 0);
    mmio_write32(base + SPI_DMACR, 0);
    mmio_write32(base + SPI_DMATDLR, 0x10);
    mmio_write32(base + SPI_DMARDLR, 0);
    mmio_write32(base + SPI_SER, 0);
    mmio_write32(base + SPI_SSIENR, 0);
    mmio_write32(base + SPI_CTRLR0, (uint32_t)frame_format << frf_shift | (uint32_t)(frame_bits - 1) << dfs_shift);
    mmio_write32(base + SPI_SPI_CTRLR0, 0);
    mmio_write32(base + SPI_ENDIAN, 0);
}

/* The instruction, address and wait phases of the dual/quad/octal formats (spi_ctrlr0, at the same
 * place on both layouts). */
void ssi_init_non_standard(uintptr_t base, int instruction_bits, int address_bits, int wait_cycles, int trans_mode)
{
    uint32_t inst_l = instruction_bits == 0 ? 0 : instruction_bits == 4 ? 1 : instruction_bits == 8 ? 2 : 3;
    mmio_write32(base + SPI_SPI_CTRLR0, (uint32_t)wait_cycles << SPI_WAIT_CYCLES_SHIFT | inst_l << SPI_INST_L_SHIFT
                 | (uint32_t)(address_bits / 4) << SPI_ADDR_L_SHIFT | (uint32_t)trans_mode);
}

void spi0_init(int frame_format, int frame_bits)
{
    clock_enable(CLOCK_SPI0);
    ssi_init(SPI0_BASE, SPI_FRF_SHIFT, SPI_DFS_SHIFT, frame_format, frame_bits);
}

void spi0_init_non_standard(int instruction_bits, int address_bits, int wait_cycles, int trans_mode)
{
    ssi_init_non_standard(SPI0_BASE, instruction_bits, address_bits, wait_cycles, trans_mode);
}

/* A serial clock at or above hz: the divider is source / hz rounded down to even (2..65534), as
 * the SDK's spi_set_clk_rate divides; returns the clock. */
uint32_t spi0_set_clock(uint32_t hz)
{
    uint32_t source = spi0_source_hz();
    uint32_t divider = source / hz;
    divider = divider < 2 ? 2 : divider > 65534 ? 65534 : divider & ~1u;
    spi_write(SPI_BAUDR, divider);
    return source / divider;
}

/* Sends count items of `width` from memory (or count times one word, source_fixed) with
 * TX DMA on channel `channel`, then waits for the wire to go idle and deselects. */
static void send(int channel, int chip_select, const void *items, int source_fixed, size_t count,
                 enum dma_width width)
{
    spi_write(SPI_CTRLR0, (spi_read(SPI_CTRLR0) & ~SPI_TMOD_MASK) | SPI_TMOD_TRANSMIT << SPI_TMOD_SHIFT);
    spi_write(SPI_DMACR, SPI_DMACR_TDMAE);
    spi_write(SPI_SSIENR, 1);
    dma_select(channel, SPI0_DMA_REQUEST);
    dmac_start(channel, items, (volatile void *)(uintptr_t)(SPI0_BASE + SPI_DR0), source_fixed, width, count);
    spi_write(SPI_SER, 1u << chip_select);
    dmac_wait_done(channel);
    while ((spi_read(SPI_SR) & (SPI_SR_TFE | SPI_SR_BUSY)) != SPI_SR_TFE)
        ;
    spi_write(SPI_SER, 0);
    spi_write(SPI_SSIENR, 0);
}

void spi0_send_dma(int channel, int chip_select, const void *items, size_t count, enum dma_width width)
{
    send(channel, chip_select, items, 0, count, width);
}

void spi0_fill_dma(int channel, int chip_select, const uint32_t *word, size_t count)
{
    send(channel, chip_select, word, 1, count, DMA_WIDTH_32);
}
