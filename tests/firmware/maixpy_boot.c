/* maixpy_boot.c: the paths MicroPython's FreeRTOS port (LoBo's MaixPy) takes on both cores at
 * boot, in one program of ours:
 * - hart 1 started by hart 0's software interrupt; each hart yielding through an ecall its own
 *   trap handler run serves; a spinlock (amoswap, then a spin on the lock word) the two take turns
 *   at around a shared counter, each read-modify-write inside it slowed by a few instructions;
 * - the file system's first block read from the SPI3 flash in quad output (6Bh) by DMA, 32-bit
 *   frames whose bytes LoBo's driver swaps back, the channel's completion taken as its PLIC
 *   interrupt (the DMAC's intsignal_en never written, as the SDKs leave it);
 * - the BOOT key read on its pulled-up pad (GPIOHS line 5 on pad 16): released, it reads 1. */
#include <stdio.h>
#include <string.h>

#include "drivers.h"
#include "k210.h"

#define CONSOLE_BAUD   115200u
#define ROUNDS         200
#define SYSCALL_YIELD  1000u                /* a7 of the yield ecall */
#define MCAUSE_ECALL_M 11u
#define FS_ADDRESS     0x500000u            /* where LoBo's kfpkg puts the LittleFS image (5 MiB) */
#define FS_WORDS       8
#define DMA_CHANNEL    1
#define IRQ_DMA0       27                   /* DMAC channel n is PLIC source 27 + n */
#define PAD_KEY        16
#define KEY_LINE       5

static volatile int lock;
static volatile unsigned shared, hart1_done, dma_done;
static volatile unsigned rounds[2], yields[2];
static uint32_t fs_block[FS_WORDS];

static void take(void)
{
    while (__atomic_exchange_n(&lock, 1, __ATOMIC_ACQUIRE))
        while (lock)
            ;
}

static void give(void) { __atomic_store_n(&lock, 0, __ATOMIC_RELEASE); }

static void yield(void)
{
    register uintptr_t a7 __asm__("a7") = SYSCALL_YIELD;
    __asm__ volatile("ecall" : "+r"(a7) : : "memory");
}

uintptr_t trap_handler(uintptr_t mcause, uintptr_t mepc, uintptr_t mtval, struct trap_frame *frame)
{
    if (mcause == MCAUSE_ECALL_M && frame->a[7] == SYSCALL_YIELD) {
        yields[read_csr(mhartid)]++;
        return mepc + 4;
    }
    if (mcause == (MCAUSE_INTERRUPT | IRQ_M_EXTERNAL)) {
        int source = plic_claim();
        if (source == IRQ_DMA0 + DMA_CHANNEL) {
            mmio_write64(DMAC_BASE + DMAC_CH(DMA_CHANNEL) + DMAC_CH_INTCLEAR, 0xFFFFFFFFu);
            dma_done = 1;
        }
        plic_complete(source);
        return mepc;
    }
    printf("trap on hart %lu: mcause 0x%lx mepc 0x%lx mtval 0x%lx\n", read_csr(mhartid), (unsigned long)mcause,
           (unsigned long)mepc, (unsigned long)mtval);
    for (;;)
        __asm__ volatile("wfi");
}

/* ROUNDS times: the counter incremented inside the lock (read, a few instructions, write), then
 * a yield. */
static void work(unsigned hart)
{
    for (int i = 0; i < ROUNDS; i++) {
        take();
        unsigned value = shared;
        for (volatile unsigned delay = 0; delay < 2 + 3 * hart; delay++)
            ;
        shared = value + 1;
        rounds[hart]++;
        give();
        yield();
    }
}

void hart1_main(void)
{
    work(1);
    hart1_done = 1;
}

/* The file system's first FS_WORDS words: fast read quad output (instruction and 24-bit address
 * on one line, 8 wait cycles), 32-bit frames by DMA, waiting in wfi for the channel's interrupt. */
static void read_fs_block(void)
{
    mmio_write64(DMAC_BASE + DMAC_CH(DMA_CHANNEL) + DMAC_CH_INTSTATUS_EN, DMAC_INT_DMA_TFR_DONE);
    plic_enable(IRQ_DMA0 + DMA_CHANNEL, 1);
    set_csr(mie, MIE_MEIE);
    spi3_init(SPI_FF_QUAD, 32);
    spi3_init_non_standard(8, 24, 8, SPI_AITM_STANDARD);
    clear_csr(mstatus, MSTATUS_MIE);
    spi3_receive_dma_start(DMA_CHANNEL, 0x6B, FS_ADDRESS, fs_block, FS_WORDS);
    while (!dma_done) {
        __asm__ volatile("wfi");                    /* wakes on the pending interrupt */
        set_csr(mstatus, MSTATUS_MIE);
        clear_csr(mstatus, MSTATUS_MIE);
    }
    spi3_receive_end();
    for (int i = 0; i < FS_WORDS; i++)              /* LoBo's w25qxx_swap_dat */
        fs_block[i] = __builtin_bswap32(fs_block[i]);
}

static int key_level(void)
{
    mmio_write32(FPIOA_BASE + 4u * PAD_KEY, (FUNC_GPIOHS0 + KEY_LINE) | FPIOA_IE_EN | FPIOA_PU);
    mmio_write32(GPIOHS_BASE + GPIOHS_INPUT_EN, mmio_read32(GPIOHS_BASE + GPIOHS_INPUT_EN) | 1u << KEY_LINE);
    return (int)(mmio_read32(GPIOHS_BASE + GPIOHS_INPUT_VAL) >> KEY_LINE & 1);
}

int main(void)
{
    clock_enable(CLOCK_FPIOA);
    clock_enable(CLOCK_GPIO);
    fpioa_set_function(PAD_UARTHS_RX, FUNC_UARTHS_RX);
    fpioa_set_function(PAD_UARTHS_TX, FUNC_UARTHS_TX);
    uarths_init(CONSOLE_BAUD);
    dmac_init();
    printf("hart 0 starts hart 1\n");
    mmio_write32(CLINT_BASE + CLINT_MSIP1_OFFSET, 1);
    work(0);
    while (!hart1_done)
        ;
    printf("shared %u (hart 0 %u, hart 1 %u), yields %u and %u\n", shared, rounds[0], rounds[1], yields[0], yields[1]);
    read_fs_block();
    char magic[9] = {0};
    memcpy(magic, (const char *)fs_block + 8, 8);
    printf("file system block: %s, by the DMA interrupt\n", magic);
    printf("BOOT key reads %d\n", key_level());
    return 0;
}
