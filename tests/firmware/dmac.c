/* dmac.c: the DesignWare AXI DMAC, single-block transfers from memory to a peripheral's
 * FIFO, its registers read and written 64 bits at a time as the SDK's readq/writeq do. */
#include "drivers.h"
#include "k210.h"

static uint64_t dmac_read(uint32_t offset) { return mmio_read64(DMAC_BASE + offset); }
static void dmac_write(uint32_t offset, uint64_t value) { mmio_write64(DMAC_BASE + offset, value); }

/* Clock on, controller reset (waiting for the reset bit to drop), disabled while the
 * channels' interrupt status is masked, then enabled: dmac_init's order. */
void dmac_init(void)
{
    clock_enable(CLOCK_DMA);
    dmac_write(DMAC_RESET, dmac_read(DMAC_RESET) | DMAC_RESET_RST);
    while (dmac_read(DMAC_RESET) & DMAC_RESET_RST)
        ;
    dmac_write(DMAC_CFG, dmac_read(DMAC_CFG) & ~(DMAC_CFG_EN | DMAC_CFG_INT_EN));
    while (dmac_read(DMAC_CFG))
        ;
    for (int channel = 0; channel < 6; channel++)
        dmac_write(DMAC_CH(channel) + DMAC_CH_INTSTATUS_EN, 0);
    dmac_write(DMAC_CFG, dmac_read(DMAC_CFG) | DMAC_CFG_EN | DMAC_CFG_INT_EN);
}

static int channel_busy(int channel) { return (int)((dmac_read(DMAC_CHEN) >> channel) & 1); }

/* Stops the channel, gives it its flow and handshakes (cfg_bits: the channel's own interface
 * number, which SYSCTL dma_sel routes to a request, on both sides), addresses, ctl (ctl_bits) and
 * block size, then enables it: dmac_set_single_mode's order. */
static void start(int channel, uint64_t cfg_bits, uint64_t source, uint64_t destination, uint64_t ctl_bits,
                  size_t items)
{
    uint32_t ch = DMAC_CH(channel);
    uint64_t enable_bit = 1ull << channel;
    dmac_write(ch + DMAC_CH_INTCLEAR, 0xFFFFFFFFu);
    dmac_write(DMAC_CHEN, (dmac_read(DMAC_CHEN) & ~enable_bit) | enable_bit << DMAC_CHEN_WE_SHIFT);
    while (channel_busy(channel))
        ;
    /* flow, handshakes, handshake interfaces and block types change; the rest stays */
    uint64_t cfg = dmac_read(ch + DMAC_CH_CFG) & ~(DMAC_CFG_FIELDS_SET | DMAC_CFG_MULTBLK_TYPES);
    cfg |= cfg_bits | (uint64_t)channel << DMAC_CFG_SRC_PER_SHIFT | (uint64_t)channel << DMAC_CFG_DST_PER_SHIFT;
    dmac_write(ch + DMAC_CH_CFG, cfg);
    dmac_write(ch + DMAC_CH_SAR, source);
    dmac_write(ch + DMAC_CH_DAR, destination);
    dmac_write(ch + DMAC_CH_CTL, (dmac_read(ch + DMAC_CH_CTL) & ~DMAC_CTL_FIELDS_SET) | ctl_bits);
    dmac_write(ch + DMAC_CH_BLOCK_TS, items - 1);
    dmac_write(DMAC_CFG, dmac_read(DMAC_CFG) | DMAC_CFG_EN | DMAC_CFG_INT_EN);
    dmac_write(DMAC_CHEN, dmac_read(DMAC_CHEN) | enable_bit | enable_bit << DMAC_CHEN_WE_SHIFT);
}

/* One block of `items` items of `width` from memory (incrementing, or one fixed word) to a
 * fixed peripheral address, in bursts of four. */
void dmac_start(int channel, const void *source, volatile void *destination, int source_fixed,
                enum dma_width width, size_t items)
{
    start(channel, (uint64_t)DMAC_TT_MEM2PRF << DMAC_CFG_TT_FC_SHIFT | DMAC_CFG_HS_SEL_SRC,
          (uint64_t)(uintptr_t)source, (uint64_t)(uintptr_t)destination,
          1ull << DMAC_CTL_DMS_SHIFT | (uint64_t)(source_fixed != 0) << DMAC_CTL_SINC_SHIFT
          | 1ull << DMAC_CTL_DINC_SHIFT | (uint64_t)width << DMAC_CTL_SRC_WIDTH_SHIFT
          | (uint64_t)width << DMAC_CTL_DST_WIDTH_SHIFT | (uint64_t)DMAC_MSIZE_4 << DMAC_CTL_SRC_MSIZE_SHIFT
          | (uint64_t)DMAC_MSIZE_4 << DMAC_CTL_DST_MSIZE_SHIFT, items);
}

/* One block of `items` items of `width` from a fixed peripheral address (its FIFO) to memory,
 * incrementing, in bursts of one item, as the SDK reads SPI: the peripheral's request paces it. */
void dmac_receive(int channel, volatile const void *source, void *destination, enum dma_width width, size_t items)
{
    start(channel, (uint64_t)DMAC_TT_PRF2MEM << DMAC_CFG_TT_FC_SHIFT | DMAC_CFG_HS_SEL_DST,
          (uint64_t)(uintptr_t)source, (uint64_t)(uintptr_t)destination,
          1ull << DMAC_CTL_SMS_SHIFT | 1ull << DMAC_CTL_SINC_SHIFT | (uint64_t)width << DMAC_CTL_SRC_WIDTH_SHIFT
          | (uint64_t)width << DMAC_CTL_DST_WIDTH_SHIFT, items);
}

/* The block is done when the channel's enable bit drops (dmac_wait_done polls chen). */
void dmac_wait_done(int channel)
{
    while (channel_busy(channel))
        ;
    dmac_write(DMAC_CH(channel) + DMAC_CH_INTCLEAR, 0xFFFFFFFFu);
}
