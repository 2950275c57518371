/* uart.c: UART1-3, the DesignWare APB UARTs, polled, programmed as the SDK's uart_configure
 * programs them (the SDK's start-up makes UART3 the console, on pads 4 and 5). */
#include "drivers.h"
#include "k210.h"

static uintptr_t uart_base(int uart) { return UART1_BASE + 0x10000u * (uint32_t)(uart - 1); }

/* Clock on, reset pulsed, then 8N1 at `baud`: divisor = APB0 clock / baud, of which
 * DLH:DLL = divisor / 16 and DLF the remainder (the bit lasts 16 (DLH:DLL + DLF / 16) APB0
 * clocks); FIFOs on, programmable THRE mode (LSR bit 5 then means "transmit FIFO full"). */
void uart_init(int uart, uint32_t baud)
{
    uintptr_t base = uart_base(uart);
    clock_enable(CLOCK_UART1 + (uart - 1));
    uart_reset(uart);
    uint32_t divisor = apb0_hz() / baud;
    uint32_t dlh = divisor >> 12;
    uint32_t dll = (divisor - (dlh << 12)) / 16;
    uint32_t dlf = divisor - (dlh << 12) - dll * 16;
    mmio_write32(base + UART_LCR, mmio_read32(base + UART_LCR) | UART_LCR_DLAB);
    mmio_write32(base + UART_IER_DLH, dlh);
    mmio_write32(base + UART_RBR_THR_DLL, dll);
    mmio_write32(base + UART_DLF, dlf);
    mmio_write32(base + UART_LCR, 0);
    mmio_write32(base + UART_LCR, UART_LCR_8N1);
    mmio_write32(base + UART_IER_DLH, mmio_read32(base + UART_IER_DLH) | UART_IER_PTIME);
    mmio_write32(base + UART_FCR, UART_FCR_FIFOS);
}

/* Waits while the transmit FIFO is full, then queues the byte (the SDK's uart_channel_putc). */
void uart_putc(int uart, char c)
{
    uintptr_t base = uart_base(uart);
    while (mmio_read32(base + UART_LSR) & UART_LSR_TX_FULL)
        ;
    mmio_write32(base + UART_RBR_THR_DLL, (uint8_t)c);
}

/* Waits until the last byte has left the transmitter. */
void uart_flush(int uart)
{
    while (!(mmio_read32(uart_base(uart) + UART_LSR) & UART_LSR_TEMT))
        ;
}
