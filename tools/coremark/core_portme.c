/* core_portme.c: CoreMark's port to a bare K210 hart (see core_portme.h). Hart 0 runs it; the C test
 * firmware's start.S parks hart 1. The seconds CoreMark reports are mcycle's cycles over the CPU
 * clock SYSCTL says (cpu_hz), so that the score per MHz is the cycle model's. */
#include "coremark.h"
#include "drivers.h"
#include "k210.h"

#define CONSOLE_BAUD 115200u

#include "core_seeds.h"   /* the run types' seeds, shared by both ports */

static CORE_TICKS started, stopped;

static CORE_TICKS cycles_now(void)
{
    return read_csr(mcycle);
}

void start_time(void) { started = cycles_now(); }
void stop_time(void) { stopped = cycles_now(); }
CORE_TICKS get_time(void) { return stopped - started; }
secs_ret time_in_secs(CORE_TICKS ticks) { return (secs_ret)ticks / (secs_ret)cpu_hz(); }

void portable_init(core_portable *p, int *argc, char *argv[])
{
    (void)argc;
    (void)argv;
    clock_enable(CLOCK_FPIOA);
    fpioa_set_function(PAD_UARTHS_RX, FUNC_UARTHS_RX);
    fpioa_set_function(PAD_UARTHS_TX, FUNC_UARTHS_TX);
    uarths_init(CONSOLE_BAUD);
    printf("CoreMark on hart 0: CPU %lu Hz\n", (unsigned long)cpu_hz());
    p->portable_id = 1;
}

void portable_fini(core_portable *p)
{
    p->portable_id = 0;
}
