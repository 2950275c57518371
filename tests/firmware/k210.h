/* k210.h: the K210's memory map and the register fields this driver layer uses.
 *
 * Facts from the Kendryte K210 datasheet and the standalone SDK's headers
 * (platform.h, sysctl.h, fpioa.h, gpio.h, gpiohs.h, uarths.h, spi.h, dmac.h,
 * clint.h), read for the addresses and bit positions; the code here is our own.
 */
#ifndef K210_H
#define K210_H

#include <stdint.h>

/* --- bus accesses: the width of each access is explicit, as the SDK's io.h makes it --- */
static inline uint8_t mmio_read8(uintptr_t address) { return *(volatile uint8_t *)address; }
static inline uint32_t mmio_read32(uintptr_t address) { return *(volatile uint32_t *)address; }
static inline uint64_t mmio_read64(uintptr_t address) { return *(volatile uint64_t *)address; }
static inline void mmio_write8(uintptr_t address, uint8_t value) { *(volatile uint8_t *)address = value; }
static inline void mmio_write32(uintptr_t address, uint32_t value) { *(volatile uint32_t *)address = value; }
static inline void mmio_write64(uintptr_t address, uint64_t value) { *(volatile uint64_t *)address = value; }

/* --- memory map (platform.h) ----------------------------------------------------------- */
#define CLINT_BASE      0x02000000u
#define UARTHS_BASE     0x38000000u
#define GPIOHS_BASE     0x38001000u
#define DMAC_BASE       0x50000000u
#define GPIO_BASE       0x50200000u
#define FPIOA_BASE      0x502B0000u
#define SYSCTL_BASE     0x50440000u
#define SPI0_BASE       0x52000000u
#define SPI3_BASE       0x54000000u        /* the on-board flash's controller */
#define UART1_BASE      0x50210000u        /* UARTn at UART1_BASE + 0x10000 (n - 1) */
#define PLIC_BASE       0x0C000000u
#define TIMER0_BASE     0x502D0000u        /* TIMERn at TIMER0_BASE + 0x10000 n */
#define WDT0_BASE       0x50400000u
#define RTC_BASE        0x50460000u

#define OSC_HZ          26000000u          /* the board's crystal, IN0 */

/* --- SYSCTL (sysctl.h) ------------------------------------------------------------------- */
#define SYSCTL_PLL0             0x08
#define SYSCTL_CLK_SEL0         0x20
#define SYSCTL_CLK_EN_CENT      0x28
#define SYSCTL_CLK_EN_PERI      0x2C
#define SYSCTL_CLK_TH1          0x3C
#define SYSCTL_MISC             0x54
#define SYSCTL_RESET_STATUS     0x60       /* reset_status and dma_sel0 share a 64-bit word */
#define SYSCTL_DMA_SEL0         0x64
#define SYSCTL_POWER_SEL        0x6C

#define PLL_CLKR_SHIFT          0          /* [3:0] */
#define PLL_CLKF_SHIFT          4          /* [9:4] */
#define PLL_CLKOD_SHIFT         10         /* [13:10] */
#define PLL_BYPASS              (1u << 23)
#define CLK_SEL0_ACLK_PLL0      (1u << 0)
#define CLK_SEL0_ACLK_DIV_SHIFT 1          /* [2:1]: ACLK = PLL0 / (2 << div) */

#define CENT_APB0               (1u << 3)  /* GPIO, FPIOA, ... */
#define CENT_APB2               (1u << 5)  /* SPI0, SPI1 */
#define PERI_DMA                (1u << 1)
#define PERI_GPIO               (1u << 5)
#define PERI_SPI0               (1u << 6)
#define PERI_SPI3               (1u << 9)  /* SPI3 sits on no APB bus */
#define CLK_SEL0_SPI3_PLL0      (1u << 12) /* SPI3's source: 0 IN0, 1 PLL0 */
#define PERI_FPIOA              (1u << 20)
#define PERI_UART1              (1u << 16) /* UART2, UART3: the next two bits */
#define PERI_TIMER0             (1u << 21) /* TIMER1, TIMER2: the next two bits */
#define PERI_WDT0               (1u << 24)
#define PERI_RTC                (1u << 29)
#define CENT_APB1               (1u << 4)  /* WDT, RTC, ... */
#define SYSCTL_CLK_TH2          0x40       /* timer n's threshold: byte n */
#define SYSCTL_CLK_TH6          0x50       /* WDT n's threshold: byte n */
#define SYSCTL_RESET_STS_WDT0   (1u << 2)
#define SYSCTL_PERI_RESET       0x34
#define CLK_SEL0_APB0_SHIFT     3          /* [5:3]: APB0 = ACLK / (apb0_clk_sel + 1) */

#define MISC_SPI_DVP_DATA       (1u << 10) /* SPI0's eight data lines reach the LCD connector */
#define POWER_BANK6_1V8         (1u << 6)  /* IO bank 6 (pads 36..41, the LCD's) at 1.8 V */
#define POWER_BANK7_1V8         (1u << 7)

#define RESET_STS_PIN           (1u << 1)
#define DMA_SEL_WIDTH           6
#define DMA_REQ_SSI0_TX         1          /* sysctl_dma_select_t */
#define DMA_REQ_SSI3_RX         6
#define DMA_REQ_SSI3_TX         7

/* --- FPIOA (fpioa.h, fpioa.c's function_config) ------------------------------------------ */
#define FPIOA_DS_MAX            (0xFu << 8)
#define FPIOA_OE_EN             (1u << 12)
#define FPIOA_PU                (1u << 16)
#define FPIOA_PD                (1u << 17)
#define FPIOA_IE_EN             (1u << 20)
#define FPIOA_ST                (1u << 23)
#define FPIOA_FUNCTION_MASK     0xFFu

#define FUNC_SPI0_D0            4
#define FUNC_SPI0_SS3           15
#define FUNC_SPI0_SCLK          17
#define FUNC_UARTHS_RX          18
#define FUNC_UARTHS_TX          19
#define FUNC_GPIOHS0            24
#define FUNC_GPIO0              56
#define FUNC_UART1_RX           64         /* UARTn_RX = 64 + 2 (n - 1), UARTn_TX the next */
#define FUNC_UART1_TX           65
#define FUNC_TIMER0_TOGGLE1     190        /* TIMERn_TOGGLEc = 190 + 4 n + c - 1 */

/* Maix Dock pads */
#define PAD_UARTHS_RX           4
#define PAD_UARTHS_TX           5
#define PAD_LED_BLUE            12         /* LEDs light when their pad is low */
#define PAD_LED_GREEN           13
#define PAD_BOOT                16         /* the BOOT key: pulled up, pressed pulls it low */
#define PAD_LCD_CS              36
#define PAD_LCD_RST             37
#define PAD_LCD_DC              38
#define PAD_LCD_WR              39         /* the LCD's write strobe: SPI0's serial clock */

/* --- GPIO (gpio.h: DesignWare APB GPIO, port A) ------------------------------------------- */
#define GPIO_DATA_OUTPUT        0x00
#define GPIO_DIRECTION          0x04       /* 1 = output */
#define GPIO_DATA_INPUT         0x50

/* --- GPIOHS (gpiohs.h: SiFive GPIO) ----------------------------------------------------- */
#define GPIOHS_INPUT_EN         0x04
#define GPIOHS_OUTPUT_EN        0x08
#define GPIOHS_OUTPUT_VAL       0x0C

/* --- UARTHS (uarths.h: SiFive UART) ------------------------------------------------------ */
#define UARTHS_TXDATA           0x00
#define UARTHS_RXDATA           0x04
#define UARTHS_TXCTRL           0x08
#define UARTHS_RXCTRL           0x0C
#define UARTHS_IE               0x10
#define UARTHS_DIV              0x18
#define UARTHS_TXDATA_FULL      (1u << 31)
#define UARTHS_RXDATA_EMPTY     (1u << 31)
#define UARTHS_TXEN             (1u << 0)
#define UARTHS_RXEN             (1u << 0)

/* --- UART1-3 (uart.h: DesignWare APB UART, 32-bit registers 4 apart) ------------------------ */
#define UART_RBR_THR_DLL        0x00
#define UART_IER_DLH            0x04
#define UART_FCR                0x08
#define UART_LCR                0x0C
#define UART_LSR                0x14
#define UART_DLF                0xC0
#define UART_LCR_DLAB           (1u << 7)
#define UART_LCR_8N1            3u
#define UART_IER_PTIME          (1u << 7)  /* programmable THRE: LSR bit 5 = transmit FIFO full */
#define UART_FCR_FIFOS          (1u | 1u << 3 | 3u << 4)   /* on, DMA mode 1, transmit threshold 1/2 */
#define UART_LSR_DR             (1u << 0)
#define UART_LSR_TX_FULL        (1u << 5)  /* with UART_IER_PTIME */
#define UART_LSR_TEMT           (1u << 6)

/* --- PLIC (plic.h): hart 0's M-mode context is context 0 (hart h's: 2 h) ------------------- */
#define PLIC_PRIORITY           0x000000   /* + 4 x source */
#define PLIC_ENABLE0            0x002000   /* + 4 x (source / 32) */
#define PLIC_THRESHOLD0         0x200000
#define PLIC_CLAIM0             0x200004
#define IRQ_TIMER0A             14         /* TIMERn's channels 0-1: 14 + 2 n */
#define IRQ_RTC                 20
#define IRQ_WDT0                21
#define IRQ_GPIOHS0             34

/* --- TIMER0-2 (timer.h: DesignWare APB timers) ------------------------------------------ */
#define TIMER_CHANNEL_STRIDE    0x14
#define TIMER_LOAD_COUNT        0x00
#define TIMER_CONTROL           0x08
#define TIMER_EOI               0x0C
#define TIMER_LOAD_COUNT2       0xB0       /* + 4 x channel */
#define TIMER_CR_ENABLE         1u
#define TIMER_CR_USER_MODE      2u
#define TIMER_CR_INTERRUPT_MASK 4u
#define TIMER_CR_PWM            8u

/* --- WDT0-1 (wdt.h: DesignWare APB watchdog) -------------------------------------------- */
#define WDT_CR                  0x00
#define WDT_TORR                0x04
#define WDT_CRR                 0x0C
#define WDT_EOI                 0x14
#define WDT_CR_ENABLE           1u
#define WDT_CR_INTERRUPT_FIRST  2u
#define WDT_RESTART             0x76u

/* --- RTC (rtc.h) -------------------------------------------------------------------------- */
#define RTC_DATE                0x00
#define RTC_TIME                0x04
#define RTC_ALARM_TIME          0x0C
#define RTC_INITIAL_COUNT       0x10
#define RTC_CURRENT_COUNT       0x14
#define RTC_INTERRUPT_CTRL      0x18
#define RTC_REGISTER_CTRL       0x1C
#define RTC_UNPROTECTED         (0xFFu << 13 | 0xFFu << 21 | 1u << 29 | 1u << 30)
#define RTC_RUNNING             1u
#define RTC_SETTING             2u
#define RTC_ALARM_ENABLE        2u
#define RTC_MASK_SECOND_MINUTE_HOUR (0x0Eu << 24)

/* --- GPIOHS interrupts (gpiohs.h) --------------------------------------------------------- */
#define GPIOHS_INPUT_VAL        0x00
#define GPIOHS_RISE_IE          0x18
#define GPIOHS_RISE_IP          0x1C
#define GPIOHS_FALL_IE          0x20
#define GPIOHS_FALL_IP          0x24

/* --- exceptions (encoding.h) ----------------------------------------------------------- */
#define CAUSE_LOAD_MISALIGNED   4
#define CAUSE_ECALL_M           11
#define SYS_WRITE               64         /* newlib's system call numbers (a7) */

/* --- CLINT (clint.h) ------------------------------------------------------------------- */
#define CLINT_MSIP1_OFFSET      0x0004     /* hart 1's msip */
#define CLINT_MTIMECMP0         0x4000
#define CLINT_MTIME             0xBFF8
#define CLINT_MTIME_DIVIDER     50         /* mtime counts CPU clock / 50 */

/* --- SPI0 (spi.h: DesignWare SSI; ctrlr0 as on SPI0 and SPI1) --------------------------- */
#define SPI_CTRLR0              0x00
#define SPI_CTRLR1              0x04       /* receive: frames to clock in, less one */
#define SPI_SSIENR              0x08
#define SPI_SER                 0x10
#define SPI_BAUDR               0x14
#define SPI_TXFLR               0x20
#define SPI_RXFLR               0x24
#define SPI_SR                  0x28
#define SPI_IMR                 0x2C
#define SPI_DMACR               0x4C
#define SPI_DMATDLR             0x50
#define SPI_DMARDLR             0x54
#define SPI_DR0                 0x60
#define SPI_SPI_CTRLR0          0xF4
#define SPI_ENDIAN              0x118

#define SPI_WORK_MODE_SHIFT     6
#define SPI_TMOD_SHIFT          8
#define SPI_TMOD_MASK           (3u << SPI_TMOD_SHIFT)
#define SPI_TMOD_TRANSMIT       1
#define SPI_TMOD_RECEIVE        2
#define SPI_TMOD_EEPROM         3          /* send a command, then clock the reply in */
#define SPI_DFS_SHIFT           16         /* data frame size - 1, [20:16] */
#define SPI_FRF_SHIFT           21         /* frame format, [22:21] */
#define SPI_FF_STANDARD         0
#define SPI_FF_QUAD             2
#define SPI_FF_OCTAL            3
#define SPI_SR_BUSY             (1u << 0)
#define SPI_SR_TFE              (1u << 2)
#define SPI_DMACR_RDMAE         (1u << 0)
#define SPI_DMACR_TDMAE         (1u << 1)
#define SPI_AITM_STANDARD       0          /* instruction and address on one line */
#define SPI_AITM_ADDR_STANDARD  1          /* instruction on one line, address in the frame format */
#define SPI_AITM_AS_FRAME_FORMAT 2         /* instruction and address in the frame format */
#define SPI_INST_L_SHIFT        8
#define SPI_ADDR_L_SHIFT        2
#define SPI_WAIT_CYCLES_SHIFT   11
#define SPI_FIFO_DEPTH          32
/* SPI3 is a DWC_ssi: ctrlr0's fields sit elsewhere (the SDK's spi.c, spi_num == 3) */
#define SPI3_DFS_SHIFT          0          /* [4:0] */
#define SPI3_WORK_MODE_SHIFT    8
#define SPI3_TMOD_SHIFT         10
#define SPI3_FRF_SHIFT          22

/* --- DMAC (dmac.h: DesignWare AXI DMAC, 64-bit registers) ------------------------------- */
#define DMAC_CFG                0x10
#define DMAC_CHEN               0x18
#define DMAC_COM_INTCLEAR       0x38
#define DMAC_RESET              0x58
#define DMAC_CH(n)              (0x100u + 0x100u * (n))
#define DMAC_CH_SAR             0x00
#define DMAC_CH_DAR             0x08
#define DMAC_CH_BLOCK_TS        0x10
#define DMAC_CH_CTL             0x18
#define DMAC_CH_CFG             0x20
#define DMAC_CH_INTSTATUS_EN    0x80
#define DMAC_CH_INTCLEAR        0x98

#define DMAC_CFG_EN             (1ull << 0)
#define DMAC_CFG_INT_EN         (1ull << 1)
#define DMAC_RESET_RST          (1ull << 0)
#define DMAC_CHEN_WE_SHIFT      8
#define DMAC_CTL_SMS_SHIFT      0          /* master select: 0 = AXI master 1 */
#define DMAC_CTL_DMS_SHIFT      2
#define DMAC_CTL_SINC_SHIFT     4          /* 0 = increment, 1 = fixed */
#define DMAC_CTL_DINC_SHIFT     6
#define DMAC_CTL_SRC_WIDTH_SHIFT 8         /* 0 = 8, 1 = 16, 2 = 32, 3 = 64 bits */
#define DMAC_CTL_DST_WIDTH_SHIFT 11
#define DMAC_CTL_SRC_MSIZE_SHIFT 14
#define DMAC_CTL_DST_MSIZE_SHIFT 18
#define DMAC_MSIZE_4            1
#define DMAC_CFG_TT_FC_SHIFT    32
#define DMAC_TT_MEM2PRF         1
#define DMAC_TT_PRF2MEM         2
#define DMAC_CFG_HS_SEL_SRC     (1ull << 35) /* 1 = software handshake (memory side) */
#define DMAC_CFG_HS_SEL_DST     (1ull << 36)
#define DMAC_CFG_SRC_PER_SHIFT  39
#define DMAC_CFG_DST_PER_SHIFT  44
#define DMAC_INT_DMA_TFR_DONE   (1ull << 1)
#define DMAC_CFG_MULTBLK_TYPES  0xFull     /* src [1:0], dst [3:2]: 0 = one contiguous block */
#define DMAC_CFG_FIELDS_SET     (0x7ull << 32 | 0x3ull << 35 | 0xFull << 39 | 0xFull << 44)
#define DMAC_CTL_FIELDS_SET     0x3FFFFFull  /* masters, increments, widths and bursts, [21:0] */

/* --- machine CSRs ---------------------------------------------------------------------- */
#define MSTATUS_MIE             (1ul << 3)
#define MIE_MTIE                (1ul << 7)
#define MIE_MEIE                (1ul << 11)
#define MCAUSE_INTERRUPT        (1ul << 63)
#define IRQ_M_TIMER             7
#define IRQ_M_EXTERNAL          11

#define read_csr(name) ({ unsigned long value_; __asm__ volatile("csrr %0, " #name : "=r"(value_)); value_; })
#define set_csr(name, bits) __asm__ volatile("csrs " #name ", %0" : : "r"(bits))
#define clear_csr(name, bits) __asm__ volatile("csrc " #name ", %0" : : "r"(bits))

#endif
