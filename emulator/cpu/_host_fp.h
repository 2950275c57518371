/* What the fast engine needs to know of the host's floating point (_fast_engine.c's notes). */
#ifndef K210_HOST_FP_H
#define K210_HOST_FP_H

#include <fenv.h>

/* Whether the host detects tininess before rounding (AArch64 with FPCR.AH = 0) rather than after
 * (x86-64 SSE, and RISC-V): (1 + 2^-52) x (2^-1022 - 2^-1074) lies below the smallest normal before
 * rounding and rounds to it, so only a before-rounding host raises underflow. Asked once. */
static int host_tiny_before_rounding(void)
{
    static int answer = -1;
    if (answer < 0) {
        fenv_t saved;
        volatile double a = 0x1.0000000000001p0, b = 0x1.ffffffffffffep-1023, r;
        feholdexcept(&saved);
        feclearexcept(FE_ALL_EXCEPT);
        r = a * b;
        (void)r;
        answer = fetestexcept(FE_UNDERFLOW) != 0;
        fesetenv(&saved);
    }
    return answer;
}

#endif
