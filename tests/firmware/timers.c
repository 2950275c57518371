/* timers.c: the K210's time blocks through the PLIC, on drivers in the SDK's manner: TIMER0
 * channel 0 interrupting every 10 ms (five ticks), TIMER1 channel 2's PWM on pad 24 (1 kHz, a
 * quarter high), an RTC alarm two seconds after 12:34:56, and a key on pad 16 (GPIOHS line 5,
 * the pad pulled up, a falling edge interrupting). */
#include <stdio.h>

#include "drivers.h"
#include "k210.h"

#define CONSOLE_BAUD 115200u
#define PAD_PWM      24
#define PAD_KEY      16
#define KEY_LINE     5
#define TICKS        5

static volatile int ticks, alarms, keys;

static void rtc_write(uint32_t offset, uint32_t value) { mmio_write32(RTC_BASE + offset, value); }

/* rtc_init and rtc_timer_set(12:34:56), then the alarm at 12:34:58 (second, minute and hour compared). */
static void rtc_start(void)
{
    clock_enable(CLOCK_RTC);
    rtc_write(RTC_REGISTER_CTRL, RTC_UNPROTECTED | RTC_SETTING);
    rtc_write(RTC_INITIAL_COUNT, OSC_HZ);
    rtc_write(RTC_CURRENT_COUNT, 1);
    rtc_write(RTC_TIME, 56u << 10 | 34u << 16 | 12u << 24);
    rtc_write(RTC_ALARM_TIME, 58u << 10 | 34u << 16 | 12u << 24);
    rtc_write(RTC_INTERRUPT_CTRL, RTC_ALARM_ENABLE | RTC_MASK_SECOND_MINUTE_HOUR);
    rtc_write(RTC_REGISTER_CTRL, RTC_UNPROTECTED | RTC_RUNNING);
}

uintptr_t trap_handler(uintptr_t mcause, uintptr_t mepc, uintptr_t mtval, struct trap_frame *frame)
{
    (void)frame;
    if (mcause != (MCAUSE_INTERRUPT | IRQ_M_EXTERNAL)) {
        printf("trap: mcause 0x%lx mepc 0x%lx mtval 0x%lx\n", (unsigned long)mcause, (unsigned long)mepc,
               (unsigned long)mtval);
        for (;;)
            __asm__ volatile("wfi");
    }
    int source = plic_claim();
    if (source == IRQ_TIMER0A) {
        timer_clear(0, 0);
        printf("tick %d at %lu us\n", ++ticks, (unsigned long)(mtime_now() * 1000000 / mtime_per_second()));
        if (ticks == TICKS)
            mmio_write32(TIMER0_BASE + TIMER_CONTROL, TIMER_CR_INTERRUPT_MASK);      /* off */
    } else if (source == IRQ_RTC) {
        uint32_t time = mmio_read32(RTC_BASE + RTC_TIME);
        printf("alarm at %02lu:%02lu:%02lu\n", (unsigned long)(time >> 24 & 0x1F), (unsigned long)(time >> 16 & 0x3F),
               (unsigned long)(time >> 10 & 0x3F));
        alarms++;
    } else if (source == IRQ_GPIOHS0 + KEY_LINE) {
        mmio_write32(GPIOHS_BASE + GPIOHS_FALL_IP, 1u << KEY_LINE);
        printf("key pressed\n");
        keys++;
    }
    plic_complete(source);
    return mepc;
}

int main(void)
{
    clock_enable(CLOCK_FPIOA);
    fpioa_set_function(PAD_UARTHS_RX, FUNC_UARTHS_RX);
    fpioa_set_function(PAD_UARTHS_TX, FUNC_UARTHS_TX);
    uarths_init(CONSOLE_BAUD);
    /* the key: the pad pulled up (gpiohs_set_drive_mode(GPIO_DM_INPUT_PULL_UP)), a falling edge */
    mmio_write32(FPIOA_BASE + 4u * PAD_KEY, (FUNC_GPIOHS0 + KEY_LINE) | FPIOA_IE_EN | FPIOA_PU);
    mmio_write32(GPIOHS_BASE + GPIOHS_INPUT_EN, mmio_read32(GPIOHS_BASE + GPIOHS_INPUT_EN) | 1u << KEY_LINE);
    mmio_write32(GPIOHS_BASE + GPIOHS_FALL_IE, 1u << KEY_LINE);
    plic_enable(IRQ_TIMER0A, 1);
    plic_enable(IRQ_RTC, 1);
    plic_enable(IRQ_GPIOHS0 + KEY_LINE, 1);
    set_csr(mie, MIE_MEIE);
    set_csr(mstatus, MSTATUS_MIE);

    uint32_t pwm_period = timer_hz(1) / 1000;
    fpioa_set_function(PAD_PWM, FUNC_TIMER0_TOGGLE1 + 4 * 1 + 2);
    timer_pwm(1, 2, pwm_period - pwm_period / 4, pwm_period / 4);
    timer_start(0, 0, timer_hz(0) / 100, 1);
    rtc_start();
    printf("timers started: %lu Hz timer clock\n", (unsigned long)timer_hz(0));
    while (ticks < TICKS || !alarms || !keys)
        __asm__ volatile("wfi");
    printf("done: %d ticks, %d alarm, %d key\n", ticks, alarms, keys);
    return 0;
}
