/* timer.c: TIMER0-2 channels as the SDK's timer.c and pwm.c program them. */
#include "drivers.h"
#include "k210.h"

static uintptr_t channel_base(int timer, int channel)
{
    return TIMER0_BASE + 0x10000u * (uint32_t)timer + TIMER_CHANNEL_STRIDE * (uint32_t)channel;
}

/* A channel counting `counts` timer clocks over and over (user mode), its interrupt on or masked. */
void timer_start(int timer, int channel, uint32_t counts, int interrupt)
{
    clock_enable(CLOCK_TIMER0 + timer);
    uintptr_t base = channel_base(timer, channel);
    mmio_write32(base + TIMER_LOAD_COUNT, counts);
    mmio_write32(base + TIMER_CONTROL, TIMER_CR_USER_MODE | TIMER_CR_ENABLE | (interrupt ? 0 : TIMER_CR_INTERRUPT_MASK));
}

/* PWM: the toggle output low for `low_counts`, high for `high_counts` (pwm_set_frequency). */
void timer_pwm(int timer, int channel, uint32_t low_counts, uint32_t high_counts)
{
    clock_enable(CLOCK_TIMER0 + timer);
    uintptr_t base = channel_base(timer, channel);
    mmio_write32(base + TIMER_LOAD_COUNT, low_counts);
    mmio_write32(TIMER0_BASE + 0x10000u * (uint32_t)timer + TIMER_LOAD_COUNT2 + 4u * (uint32_t)channel, high_counts);
    mmio_write32(base + TIMER_CONTROL, TIMER_CR_INTERRUPT_MASK | TIMER_CR_PWM | TIMER_CR_USER_MODE | TIMER_CR_ENABLE);
}

/* Clears the channel's interrupt: a read of its eoi (timer_channel_clear_interrupt). */
void timer_clear(int timer, int channel) { (void)mmio_read32(channel_base(timer, channel) + TIMER_EOI); }
