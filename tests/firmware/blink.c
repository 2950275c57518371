/* blink.c: two LEDs blinking on the CLINT timer interrupt, one on a slow-GPIO line (blue,
 * pad 12), one on a GPIOHS line (green, pad 13) at half the rate. The LEDs light when
 * their pad is low. Stops after BLINK_TICKS ticks. */
#include <stdio.h>

#include "drivers.h"
#include "k210.h"

#define BLUE_GPIO_LINE    3
#define GREEN_GPIOHS_LINE 5
#define TICK_MS           50u
#define BLINK_TICKS       10u
#define CONSOLE_BAUD      115200u

static volatile uint32_t ticks;
static uint64_t next_tick;
static uint64_t tick_length;

/* The timer interrupt: a tick; the next one is one period after this one was due, so the
 * LEDs keep the timer's pace whatever the interrupt's latency. */
uintptr_t trap_handler(uintptr_t mcause, uintptr_t mepc, uintptr_t mtval, struct trap_frame *frame)
{
    (void)frame;
    if (mcause != (MCAUSE_INTERRUPT | IRQ_M_TIMER)) {
        printf("trap: mcause 0x%lx mepc 0x%lx mtval 0x%lx\n", (unsigned long)mcause, (unsigned long)mepc,
               (unsigned long)mtval);
        for (;;)
            __asm__ volatile("wfi");
    }
    uint32_t tick = ++ticks;
    gpio_write(BLUE_GPIO_LINE, !gpio_read(BLUE_GPIO_LINE));
    if (tick % 2 == 0)
        gpiohs_write(GREEN_GPIOHS_LINE, !(tick / 2 % 2));
    next_tick += tick_length;
    mtimecmp_set(tick < BLINK_TICKS ? next_tick : UINT64_MAX);
    return mepc;
}

int main(void)
{
    clock_enable(CLOCK_FPIOA);
    clock_enable(CLOCK_GPIO);
    fpioa_set_function(PAD_UARTHS_RX, FUNC_UARTHS_RX);
    fpioa_set_function(PAD_UARTHS_TX, FUNC_UARTHS_TX);
    fpioa_set_function(PAD_LED_BLUE, FUNC_GPIO0 + BLUE_GPIO_LINE);
    fpioa_set_function(PAD_LED_GREEN, FUNC_GPIOHS0 + GREEN_GPIOHS_LINE);
    uarths_init(CONSOLE_BAUD);
    gpio_write(BLUE_GPIO_LINE, 1);
    gpio_make_output(BLUE_GPIO_LINE);
    gpiohs_write(GREEN_GPIOHS_LINE, 1);
    gpiohs_make_output(GREEN_GPIOHS_LINE);

    tick_length = mtime_per_second() * TICK_MS / 1000;
    printf("blink: %u ms ticks, %lu mtime counts each\n", TICK_MS, (unsigned long)tick_length);
    next_tick = mtime_now() + tick_length;
    mtimecmp_set(next_tick);
    set_csr(mie, MIE_MTIE);
    set_csr(mstatus, MSTATUS_MIE);
    uint32_t reported = 0;
    while (reported < BLINK_TICKS) {
        __asm__ volatile("wfi");
        while (reported < ticks) {
            reported++;
            printf("tick %lu: blue %s, green %s\n", (unsigned long)reported,
                   gpio_read(BLUE_GPIO_LINE) ? "off" : "on", reported / 2 % 2 ? "on" : "off");
        }
    }
    clear_csr(mstatus, MSTATUS_MIE);
    printf("blink: done\n");
    return 0;
}
