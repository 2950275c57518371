/* boot_key.c: the Dock's BOOT key (pad 16, GPIOHS line 5, the pad pulled up) through the PLIC,
 * both edges interrupting: each press and release is told on the console, and the green LED
 * (pad 13, GPIOHS line 6, lit when low) is lit while the key is down. Runs until the run ends;
 * the live view's test (tests/end_to_end/test_view_browser.py) presses the key from the page. */
#include <stdio.h>

#include "drivers.h"
#include "k210.h"

#define CONSOLE_BAUD 115200u
#define KEY_LINE     5
#define LED_LINE     6

static volatile int presses, releases;

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
    if (source == IRQ_GPIOHS0 + KEY_LINE) {
        uint32_t fell = mmio_read32(GPIOHS_BASE + GPIOHS_FALL_IP) & 1u << KEY_LINE;
        uint32_t rose = mmio_read32(GPIOHS_BASE + GPIOHS_RISE_IP) & 1u << KEY_LINE;
        mmio_write32(GPIOHS_BASE + GPIOHS_FALL_IP, fell);
        mmio_write32(GPIOHS_BASE + GPIOHS_RISE_IP, rose);
        if (fell)
            presses++;
        if (rose)
            releases++;
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
    fpioa_set_function(PAD_LED_GREEN, FUNC_GPIOHS0 + LED_LINE);
    gpiohs_write(LED_LINE, 1);
    gpiohs_make_output(LED_LINE);
    /* the key: the pad pulled up (gpiohs_set_drive_mode(GPIO_DM_INPUT_PULL_UP)), both edges */
    mmio_write32(FPIOA_BASE + 4u * PAD_BOOT, (FUNC_GPIOHS0 + KEY_LINE) | FPIOA_IE_EN | FPIOA_PU);
    mmio_write32(GPIOHS_BASE + GPIOHS_INPUT_EN, mmio_read32(GPIOHS_BASE + GPIOHS_INPUT_EN) | 1u << KEY_LINE);
    /* the pull-up's rise as the pad was routed is pending already: cleared before the interrupts */
    mmio_write32(GPIOHS_BASE + GPIOHS_FALL_IP, 1u << KEY_LINE);
    mmio_write32(GPIOHS_BASE + GPIOHS_RISE_IP, 1u << KEY_LINE);
    mmio_write32(GPIOHS_BASE + GPIOHS_FALL_IE, 1u << KEY_LINE);
    mmio_write32(GPIOHS_BASE + GPIOHS_RISE_IE, 1u << KEY_LINE);
    plic_enable(IRQ_GPIOHS0 + KEY_LINE, 1);
    set_csr(mie, MIE_MEIE);
    set_csr(mstatus, MSTATUS_MIE);
    printf("boot_key: press the BOOT key\n");
    int told_presses = 0, told_releases = 0;
    for (;;) {
        __asm__ volatile("wfi");
        while (told_presses < presses || told_releases < releases) {
            if (told_presses <= told_releases && told_presses < presses) {
                told_presses++;
                gpiohs_write(LED_LINE, 0);
                printf("BOOT key pressed (%d)\n", told_presses);
            } else if (told_releases < releases) {
                told_releases++;
                gpiohs_write(LED_LINE, 1);
                printf("BOOT key released (%d)\n", told_releases);
            }
        }
    }
}
