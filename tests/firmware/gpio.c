/* gpio.c: the slow GPIO block (DesignWare APB GPIO, lines 0..7) and GPIOHS (SiFive GPIO,
 * lines 0..31). Every change is a read-modify-write of the whole 32-bit register, as the
 * SDK's set_gpio_bit does. */
#include "drivers.h"
#include "k210.h"

static void set_bit32(uintptr_t address, int bit, int value)
{
    uint32_t word = mmio_read32(address) & ~(1u << bit);
    mmio_write32(address, word | (uint32_t)(value != 0) << bit);
}

/* A GPIO line becomes an output; its pad gets the pull-down the SDK's gpio_set_drive_mode
 * gives outputs. */
void gpio_make_output(int line)
{
    for (int pad = 0; pad < 48; pad++) {
        uint32_t config = fpioa_pad_config(pad);
        if ((int)(config & FPIOA_FUNCTION_MASK) == FUNC_GPIO0 + line)
            mmio_write32(FPIOA_BASE + 4u * (uint32_t)pad, (config & ~FPIOA_PU) | FPIOA_PD);
    }
    set_bit32(GPIO_BASE + GPIO_DIRECTION, line, 1);
}

void gpio_write(int line, int level) { set_bit32(GPIO_BASE + GPIO_DATA_OUTPUT, line, level); }

/* An output reads back what it drives (data_output), an input the pad (data_input), as the
 * SDK's gpio_get_pin picks the register by the line's direction. */
int gpio_read(int line)
{
    int output = (mmio_read32(GPIO_BASE + GPIO_DIRECTION) >> line) & 1;
    uint32_t word = mmio_read32(GPIO_BASE + (output ? GPIO_DATA_OUTPUT : GPIO_DATA_INPUT));
    return (int)((word >> line) & 1);
}

void gpiohs_make_output(int line)
{
    set_bit32(GPIOHS_BASE + GPIOHS_INPUT_EN, line, 0);
    set_bit32(GPIOHS_BASE + GPIOHS_OUTPUT_EN, line, 1);
}

void gpiohs_write(int line, int level) { set_bit32(GPIOHS_BASE + GPIOHS_OUTPUT_VAL, line, level); }
