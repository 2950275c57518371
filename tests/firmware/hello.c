/* hello.c: printf on UARTHS through picolibc's stdio, with the clocks as handed over. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "drivers.h"
#include "k210.h"

#define CONSOLE_BAUD 115200u

int main(void)
{
    clock_enable(CLOCK_FPIOA);
    fpioa_set_function(PAD_UARTHS_RX, FUNC_UARTHS_RX);
    fpioa_set_function(PAD_UARTHS_TX, FUNC_UARTHS_TX);
    uarths_init(CONSOLE_BAUD);
    uint32_t cause = reset_status();

    printf("hello from C on the K210\n");
    printf("cpu %lu Hz, pll0 %lu Hz, reset by %s\n", (unsigned long)cpu_hz(), (unsigned long)pll0_hz(),
           cause & RESET_STS_PIN ? "the reset pin" : "power-on");
    char *copy = malloc(64);
    strcpy(copy, "malloc works");
    printf("%s; sqrt(2) = %.6f; hart %lu\n", copy, sqrt(2.0), read_csr(mhartid));
    free(copy);
    return 0;
}
