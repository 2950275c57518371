/* sysctl.c: clock gates, clock frequencies, DMA request selects and the LCD's IO banks. */
#include "drivers.h"
#include "k210.h"

static uint32_t sysctl_read(uint32_t offset) { return mmio_read32(SYSCTL_BASE + offset); }
static void sysctl_write(uint32_t offset, uint32_t value) { mmio_write32(SYSCTL_BASE + offset, value); }
static void sysctl_set_bits(uint32_t offset, uint32_t bits) { sysctl_write(offset, sysctl_read(offset) | bits); }

/* Opens a peripheral's clock: first its APB bus's gate (clk_en_cent), then its own
 * (clk_en_peri), as the SDK's sysctl_clock_enable does. SPI0's clock threshold goes to 0
 * (SPI0 clock = PLL0 / 2), as the SDK's spi_init does. */
void clock_enable(enum clock clock)
{
    switch (clock) {
    case CLOCK_FPIOA:
        sysctl_set_bits(SYSCTL_CLK_EN_CENT, CENT_APB0);
        sysctl_set_bits(SYSCTL_CLK_EN_PERI, PERI_FPIOA);
        break;
    case CLOCK_GPIO:
        sysctl_set_bits(SYSCTL_CLK_EN_CENT, CENT_APB0);
        sysctl_set_bits(SYSCTL_CLK_EN_PERI, PERI_GPIO);
        break;
    case CLOCK_SPI0:
        sysctl_set_bits(SYSCTL_CLK_EN_CENT, CENT_APB2);
        sysctl_set_bits(SYSCTL_CLK_EN_PERI, PERI_SPI0);
        sysctl_write(SYSCTL_CLK_TH1, sysctl_read(SYSCTL_CLK_TH1) & ~0xFFu);
        break;
    case CLOCK_DMA:
        sysctl_set_bits(SYSCTL_CLK_EN_PERI, PERI_DMA);
        break;
    case CLOCK_SPI3:        /* from PLL0, threshold 0, as spi_init's spi_clk_init sets it */
        sysctl_set_bits(SYSCTL_CLK_SEL0, CLK_SEL0_SPI3_PLL0);
        sysctl_set_bits(SYSCTL_CLK_EN_PERI, PERI_SPI3);
        sysctl_write(SYSCTL_CLK_TH1, sysctl_read(SYSCTL_CLK_TH1) & ~0xFF000000u);
        break;
    case CLOCK_UART1:
    case CLOCK_UART2:
    case CLOCK_UART3:
        sysctl_set_bits(SYSCTL_CLK_EN_CENT, CENT_APB0);
        sysctl_set_bits(SYSCTL_CLK_EN_PERI, PERI_UART1 << (clock - CLOCK_UART1));
        break;
    case CLOCK_TIMER0:
    case CLOCK_TIMER1:
    case CLOCK_TIMER2:
        sysctl_set_bits(SYSCTL_CLK_EN_CENT, CENT_APB0);
        sysctl_set_bits(SYSCTL_CLK_EN_PERI, PERI_TIMER0 << (clock - CLOCK_TIMER0));
        break;
    case CLOCK_WDT0:
        sysctl_set_bits(SYSCTL_CLK_EN_CENT, CENT_APB1);
        sysctl_set_bits(SYSCTL_CLK_EN_PERI, PERI_WDT0);
        break;
    case CLOCK_RTC:
        sysctl_set_bits(SYSCTL_CLK_EN_CENT, CENT_APB1);
        sysctl_set_bits(SYSCTL_CLK_EN_PERI, PERI_RTC);
        break;
    }
}

/* Pulses UARTn's reset (peri_reset), as the SDK's sysctl_reset does. */
void uart_reset(int uart)
{
    uint32_t bit = PERI_UART1 << (uart - 1);
    sysctl_set_bits(SYSCTL_PERI_RESET, bit);
    sysctl_write(SYSCTL_PERI_RESET, sysctl_read(SYSCTL_PERI_RESET) & ~bit);
}

/* TIMERn's clock with its threshold left at 0 and its source at IN0: 26 MHz / 2 (the SDK's
 * sysctl_clock_get_freq: source / ((threshold + 1) x 2)). */
uint32_t timer_hz(int timer)
{
    return OSC_HZ / (((sysctl_read(SYSCTL_CLK_TH2) >> (8 * timer)) & 0xFF) + 1) / 2;
}

/* WDT0's clock: IN0 / ((threshold + 1) x 2). */
uint32_t wdt_hz(void) { return OSC_HZ / ((sysctl_read(SYSCTL_CLK_TH6) & 0xFF) + 1) / 2; }

/* APB0's clock (UART1-3 count in it): ACLK / (apb0_clk_sel + 1). */
uint32_t apb0_hz(void)
{
    return cpu_hz() / (((sysctl_read(SYSCTL_CLK_SEL0) >> CLK_SEL0_APB0_SHIFT) & 7) + 1);
}

/* PLL0's output: 26 MHz * (clkf + 1) / ((clkr + 1) * (clkod + 1)), or 26 MHz bypassed. */
uint32_t pll0_hz(void)
{
    uint32_t pll = sysctl_read(SYSCTL_PLL0);
    if (pll & PLL_BYPASS)
        return OSC_HZ;
    uint64_t clkr = (pll >> PLL_CLKR_SHIFT) & 0xF, clkf = (pll >> PLL_CLKF_SHIFT) & 0x3F;
    uint64_t clkod = (pll >> PLL_CLKOD_SHIFT) & 0xF;
    return (uint32_t)(OSC_HZ * (clkf + 1) / ((clkr + 1) * (clkod + 1)));
}

/* The CPU clock (ACLK): PLL0 / (2 << aclk_divider_sel) when clk_sel0 selects PLL0, else 26 MHz. */
uint32_t cpu_hz(void)
{
    uint32_t select = sysctl_read(SYSCTL_CLK_SEL0);
    if (!(select & CLK_SEL0_ACLK_PLL0))
        return OSC_HZ;
    return pll0_hz() / (2u << ((select >> CLK_SEL0_ACLK_DIV_SHIFT) & 3));
}

/* SPI0's source clock: PLL0 / ((threshold + 1) * 2). */
uint32_t spi0_source_hz(void)
{
    uint32_t threshold = sysctl_read(SYSCTL_CLK_TH1) & 0xFF;
    return pll0_hz() / ((threshold + 1) * 2);
}

/* SPI3's clock: IN0 or PLL0 (clk_sel0.spi3_clk_sel) / ((clk_th1 byte 3 + 1) x 2). */
uint32_t spi3_source_hz(void)
{
    uint32_t threshold = sysctl_read(SYSCTL_CLK_TH1) >> 24;
    uint32_t source = sysctl_read(SYSCTL_CLK_SEL0) & CLK_SEL0_SPI3_PLL0 ? pll0_hz() : OSC_HZ;
    return source / ((threshold + 1) * 2);
}

/* Routes a DMA request (sysctl_dma_select_t) to a DMAC channel's handshake interface 0..4. */
void dma_select(int channel, uint32_t request)
{
    uint32_t shift = DMA_SEL_WIDTH * (uint32_t)channel;
    uint32_t value = sysctl_read(SYSCTL_DMA_SEL0) & ~(0x3Fu << shift);
    sysctl_write(SYSCTL_DMA_SEL0, value | request << shift);
}

/* SPI0's data lines 1..7 reach the LCD connector (shared with the DVP pins). */
void spi0_dvp_data_enable(void) { sysctl_set_bits(SYSCTL_MISC, MISC_SPI_DVP_DATA); }

/* IO banks powered at 1.8 V (power_sel bit per bank), as sysctl_set_power_mode does. */
void io_banks_1v8(uint32_t banks) { sysctl_set_bits(SYSCTL_POWER_SEL, banks); }

/* The reset cause, then cleared. The read is one 64-bit load of reset_status and the
 * dma_sel0 register beside it, as firmware built without -fstrict-volatile-bitfields
 * reads a struct of two bitfield words; the clear is the SDK's 32-bit write. */
uint32_t reset_status(void)
{
    uint64_t pair = mmio_read64(SYSCTL_BASE + SYSCTL_RESET_STATUS);
    sysctl_set_bits(SYSCTL_RESET_STATUS, 1u);
    return (uint32_t)pair;
}
