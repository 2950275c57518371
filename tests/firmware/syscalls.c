/* syscalls.c: the Kendryte SDK's way of running C, with our own code: the console on UART3
 * through pads 4 and 5 (the SDK's start-up), write() as an `ecall` its trap handler serves
 * (newlib's system calls on the SDK), and a misaligned load the trap handler carries out
 * byte by byte (the SDK's handle_misaligned_load): the K210's Rocket traps on both. */
#include <stdio.h>
#include <string.h>

#include "drivers.h"
#include "k210.h"

#define CONSOLE_UART 3
#define CONSOLE_BAUD 115200u
#define PAD_CONSOLE_RX 4
#define PAD_CONSOLE_TX 5

static unsigned ecalls, misaligned_loads;

/* write(fd, buffer, length) as newlib on the SDK makes it: a7 = SYS_write, ecall. */
static long sys_write(int fd, const void *buffer, size_t length)
{
    register long a0 __asm__("a0") = fd;
    register long a1 __asm__("a1") = (long)buffer;
    register long a2 __asm__("a2") = (long)length;
    register long a7 __asm__("a7") = SYS_WRITE;
    __asm__ volatile("ecall" : "+r"(a0) : "r"(a1), "r"(a2), "r"(a7) : "memory");
    return a0;
}

/* The byte-by-byte load a misaligned lw/lwu/lh/lhu/ld stands for; its destination register is
 * taken from the instruction (funct3: width and sign), as the SDK's handler decodes it. */
static uintptr_t emulate_load(uintptr_t mepc, uintptr_t address, struct trap_frame *frame)
{
    uint32_t insn = *(volatile uint16_t *)mepc | (uint32_t)*(volatile uint16_t *)(mepc + 2) << 16;
    if ((insn & 3) != 3 || (insn & 0x7F) != 0x03)
        return 0;                                /* only uncompressed integer loads here */
    uint32_t funct3 = (insn >> 12) & 7, bytes = 1u << (funct3 & 3);
    uint64_t value = 0;
    for (uint32_t n = 0; n < bytes; n++)
        value |= (uint64_t)*(volatile uint8_t *)(address + n) << (8 * n);
    if (!(funct3 & 4) && bytes < 8 && value >> (8 * bytes - 1) & 1)
        value |= ~0ull << (8 * bytes);           /* lh, lw: sign-extended */
    uint64_t *rd = trap_frame_register(frame, (int)((insn >> 7) & 31));
    if (rd == NULL)
        return 0;
    *rd = value;
    misaligned_loads++;
    return mepc + 4;
}

uintptr_t trap_handler(uintptr_t mcause, uintptr_t mepc, uintptr_t mtval, struct trap_frame *frame)
{
    uintptr_t resume = 0;
    if (mcause == CAUSE_ECALL_M && frame->a[7] == SYS_WRITE) {
        const char *text = (const char *)frame->a[1];
        for (uint64_t n = 0; n < frame->a[2]; n++)
            uart_putc(CONSOLE_UART, text[n]);
        frame->a[0] = frame->a[2];
        ecalls++;
        resume = mepc + 4;
    } else if (mcause == CAUSE_LOAD_MISALIGNED) {
        resume = emulate_load(mepc, mtval, frame);
    }
    if (resume)
        return resume;
    char report[96];
    int length = snprintf(report, sizeof report, "unhandled trap: mcause 0x%lx mepc 0x%lx mtval 0x%lx\n",
                          (unsigned long)mcause, (unsigned long)mepc, (unsigned long)mtval);
    for (int n = 0; n < length; n++)
        uart_putc(CONSOLE_UART, report[n]);
    for (;;)
        __asm__ volatile("wfi");
}

static int console_put(char c, FILE *file)
{
    (void)file;
    if (c == '\n')
        sys_write(1, "\r", 1);
    sys_write(1, &c, 1);
    return (unsigned char)c;
}

static FILE console = FDEV_SETUP_STREAM(console_put, NULL, NULL, _FDEV_SETUP_WRITE);

static const uint8_t bytes[8] __attribute__((aligned(8))) = {0x10, 0x21, 0x32, 0x43, 0x54, 0x65, 0x76, 0x87};

int main(void)
{
    clock_enable(CLOCK_FPIOA);
    fpioa_set_function(PAD_CONSOLE_RX, FUNC_UART1_RX + 2 * (CONSOLE_UART - 1));
    fpioa_set_function(PAD_CONSOLE_TX, FUNC_UART1_TX + 2 * (CONSOLE_UART - 1));
    uart_init(CONSOLE_UART, CONSOLE_BAUD);

    const char *hello = "hello from UART3, through an ecall\n";
    long written = sys_write(1, hello, strlen(hello));
    /* a misaligned 32-bit load, into a register the trap frame holds */
    register uint64_t loaded __asm__("a5");
    __asm__ volatile("lw %0, 1(%1)" : "=r"(loaded) : "r"(bytes) : "memory");
    fprintf(&console, "write returned %ld; misaligned lw read 0x%08lx\n", written, (unsigned long)loaded);
    fprintf(&console, "%u ecalls served, %u misaligned loads carried out\n", ecalls, misaligned_loads);
    uart_flush(CONSOLE_UART);
    return 0;
}
