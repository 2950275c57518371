/* drivers.h: a small driver layer for the K210 that uses the chip the way the Kendryte
 * standalone SDK's drivers do (read-modify-write of whole 32-bit registers, 64-bit
 * accesses to the DMAC, the LCD in octal SPI mode fed by DMA, clocks enabled per
 * peripheral and computed from what SYSCTL holds), plus two accesses that firmware built
 * without the SDK's -fstrict-volatile-bitfields makes: a byte store to UARTHS txdata and a
 * 64-bit load of the reset_status/dma_sel0 pair. Our own code; the SDK was read for facts. */
#ifndef DRIVERS_H
#define DRIVERS_H

#include <stddef.h>
#include <stdint.h>

/* sysctl.c: clocks, as handed over; nothing here touches the PLLs */
enum clock { CLOCK_FPIOA, CLOCK_GPIO, CLOCK_SPI0, CLOCK_DMA, CLOCK_UART1, CLOCK_UART2, CLOCK_UART3, CLOCK_TIMER0,
             CLOCK_TIMER1, CLOCK_TIMER2, CLOCK_WDT0, CLOCK_RTC, CLOCK_SPI3 };
void clock_enable(enum clock clock);
uint32_t pll0_hz(void);
uint32_t cpu_hz(void);
uint32_t spi0_source_hz(void);
uint32_t spi3_source_hz(void);
uint32_t apb0_hz(void);
uint32_t timer_hz(int timer);
uint32_t wdt_hz(void);
void uart_reset(int uart);
void dma_select(int channel, uint32_t request);
void spi0_dvp_data_enable(void);
void io_banks_1v8(uint32_t banks);
uint32_t reset_status(void);

/* fpioa.c */
void fpioa_set_function(int pad, int function);
uint32_t fpioa_pad_config(int pad);

/* gpio.c: the slow GPIO block (8 lines) and GPIOHS (32 lines) */
void gpio_make_output(int line);
void gpio_write(int line, int level);
int gpio_read(int line);
void gpiohs_make_output(int line);
void gpiohs_write(int line, int level);

/* uarths.c: the console; stdout goes here */
void uarths_init(uint32_t baud);
void uarths_putc(char c);
int uarths_getc(void);

/* uart.c: UART1-3 (DesignWare), polled */
void uart_init(int uart, uint32_t baud);
void uart_putc(int uart, char c);
void uart_flush(int uart);

/* plic.c: interrupts to hart 0 (M-mode, context 0) */
void plic_enable(int source, uint32_t priority);
int plic_claim(void);
void plic_complete(int source);

/* timer.c: TIMER0-2 channels */
void timer_start(int timer, int channel, uint32_t counts, int interrupt);
void timer_pwm(int timer, int channel, uint32_t low_counts, uint32_t high_counts);
void timer_clear(int timer, int channel);

/* trap.c: what start.S hands trap_handler (the caller-saved registers as trap_entry saved them) */
struct trap_frame {
    uint64_t ra, t0, t1, t2, t3, t4, t5, t6, a[8];
};
uint64_t *trap_frame_register(struct trap_frame *frame, int number);
uintptr_t trap_handler(uintptr_t mcause, uintptr_t mepc, uintptr_t mtval, struct trap_frame *frame);

/* clint.c: time */
uint64_t mtime_now(void);
uint64_t mtime_per_second(void);
void mtimecmp_set(uint64_t when);
void delay_us(uint32_t us);

/* dmac.c */
enum dma_width { DMA_WIDTH_8 = 0, DMA_WIDTH_16 = 1, DMA_WIDTH_32 = 2 };
void dmac_init(void);
void dmac_start(int channel, const void *source, volatile void *destination, int source_fixed,
                enum dma_width width, size_t items);
void dmac_receive(int channel, volatile const void *source, void *destination, enum dma_width width, size_t items);
void dmac_wait_done(int channel);

/* spi.c: either SSI layout's configuration, and SPI0, transmit only */
void ssi_init(uintptr_t base, unsigned frf_shift, unsigned dfs_shift, int frame_format, int frame_bits);
void ssi_init_non_standard(uintptr_t base, int instruction_bits, int address_bits, int wait_cycles, int trans_mode);
void spi0_init(int frame_format, int frame_bits);
void spi0_init_non_standard(int instruction_bits, int address_bits, int wait_cycles, int trans_mode);
uint32_t spi0_set_clock(uint32_t hz);
void spi0_send_dma(int channel, int chip_select, const void *items, size_t count, enum dma_width width);
void spi0_fill_dma(int channel, int chip_select, const uint32_t *word, size_t count);

/* spi3.c: SPI3 (DWC_ssi), whose chip select 0 is the Dock's flash */
void spi3_init(int frame_format, int frame_bits);
void spi3_init_non_standard(int instruction_bits, int address_bits, int wait_cycles, int trans_mode);
uint32_t spi3_set_clock(uint32_t hz);
void spi3_send(const uint8_t *bytes, size_t count);
void spi3_receive(const uint8_t *command, size_t command_length, uint8_t *reply, size_t count);
void spi3_send_dma(int channel, const uint32_t *items, size_t count);
void spi3_receive_dma(int channel, uint32_t instruction, uint32_t address, uint32_t *items, size_t count);
void spi3_receive_dma_start(int channel, uint32_t instruction, uint32_t address, uint32_t *items, size_t count);
void spi3_receive_end(void);

/* lcd.c: the Maix Dock's ST7789V, 8-bit parallel on SPI0's octal lines */
#define LCD_WIDTH 320
#define LCD_HEIGHT 240
#define MADCTL_MY 0x80
#define MADCTL_MX 0x40
#define MADCTL_MV 0x20
#define MADCTL_BGR 0x08
void lcd_init(void);
void lcd_madctl(uint8_t value);
void lcd_window(uint16_t x0, uint16_t y0, uint16_t x1, uint16_t y1);
void lcd_fill(uint16_t colour, size_t pixels);
void lcd_pixels32(const uint32_t *pairs, size_t words);
void lcd_pixels16(const uint16_t *pixels, size_t count);
void lcd_bytes(const uint8_t *bytes, size_t count);

#endif
