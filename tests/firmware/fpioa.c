/* fpioa.c: routing functions to pads, with the SDK's per-function pad settings. */
#include "drivers.h"
#include "k210.h"

#define FPIOA_PADS 48
#define FUNC_RESV0 120             /* a reserved function: the pad drives nothing */

/* The pad word fpioa.c's function_config table gives each function this layer uses:
 * outputs drive strongly, inputs get their Schmitt trigger, GPIO lines are both. */
static uint32_t pad_defaults(int function)
{
    if (function == FUNC_UARTHS_RX)
        return FPIOA_IE_EN | FPIOA_ST;
    if (function >= FUNC_GPIOHS0 && function < FUNC_GPIO0 + 8)
        return FPIOA_DS_MAX | FPIOA_OE_EN | FPIOA_IE_EN | FPIOA_ST;
    return FPIOA_DS_MAX | FPIOA_OE_EN;
}

uint32_t fpioa_pad_config(int pad) { return mmio_read32(FPIOA_BASE + 4u * (uint32_t)pad); }

/* Puts a function on a pad; a pad that carried the function before gives it up (it gets the
 * reserved function, as in the SDK). */
void fpioa_set_function(int pad, int function)
{
    for (int other = 0; other < FPIOA_PADS; other++) {
        if (other != pad && (int)(fpioa_pad_config(other) & FPIOA_FUNCTION_MASK) == function)
            mmio_write32(FPIOA_BASE + 4u * (uint32_t)other, FUNC_RESV0);
    }
    mmio_write32(FPIOA_BASE + 4u * (uint32_t)pad, (uint32_t)function | pad_defaults(function));
}
