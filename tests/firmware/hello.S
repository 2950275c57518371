    .section .text
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, sleep               # hart 1 has nothing to do
    li      t1, 0x38000000          # UARTHS
    la      t2, message
next:
    lbu     t3, 0(t2)
    beqz    t3, sleep
wait:
    lw      t4, 0(t1)               # txdata: bit 31 set while the FIFO is full
    bltz    t4, wait
    sw      t3, 0(t1)
    addi    t2, t2, 1
    j       next
sleep:
    wfi
    j       sleep
message:
    .asciz  "hello from my own firmware\r\n"
