/* core_seeds.h: the seeds CoreMark's run types read (its porting guide's core_portme.c template asks every
 * port to define them), shared by our two ports (core_portme.c on the K210, virt/core_portme.c on
 * QEMU's virt), so that both run the very same program. Included once, by each port's core_portme.c,
 * after coremark.h (which has no include guard, so it is not included again here). */
#ifndef CORE_SEEDS_H
#define CORE_SEEDS_H

#if VALIDATION_RUN
volatile ee_s32 seed1_volatile = 0x3415;
volatile ee_s32 seed2_volatile = 0x3415;
volatile ee_s32 seed3_volatile = 0x66;
#endif
#if PERFORMANCE_RUN
volatile ee_s32 seed1_volatile = 0x0;
volatile ee_s32 seed2_volatile = 0x0;
volatile ee_s32 seed3_volatile = 0x66;
#endif
#if PROFILE_RUN
volatile ee_s32 seed1_volatile = 0x8;
volatile ee_s32 seed2_volatile = 0x8;
volatile ee_s32 seed3_volatile = 0x8;
#endif
volatile ee_s32 seed4_volatile = ITERATIONS;
volatile ee_s32 seed5_volatile = 0;

ee_u32 default_num_contexts = 1;
#endif
