# crc.S: the three table-driven CRCs the SD card path needs.
#
#   CRC7   x^7 + x^3 + 1, MSB first, initial 0: SD command frames. The table
#          holds each byte's CRC left-aligned in 8 bits (crc7 << 1), so a
#          byte is one lookup and the frame's last byte is (crc << 1) | 1.
#   CRC16  x^16 + x^12 + x^5 + 1 (CCITT / XMODEM), MSB first, initial 0: every
#          512-byte data block the card sends.
#   CRC32  reflected 0xEDB88320, initial and final xor 0xFFFFFFFF: exactly
#          zlib.crc32, reported for every loaded file.
#
# The tables are built at boot into .bss by crc_init (256 entries each:
# 256 + 512 + 1024 bytes), which must run before any of the CRC functions.

    .option norelax
    .include "k210.inc"

    .equ CRC7_POLY_ALIGNED,     0x09 << 1   # x^3 + 1 (x^7 implied), left-aligned in a byte
    .equ CRC16_POLY,            0x1021
    .equ CRC32_POLY_REFLECTED,  0xEDB88320
    .equ CRC_TABLE_ENTRIES,     256
    .equ CRC7_TOP_BIT,          0x80        # bit 7 of the left-aligned register
    .equ CRC16_TOP_SHIFT,       15          # bit 15 of the register
    .equ CRC16_ENTRY_SHIFT,     1           # 2-byte table entries
    .equ CRC32_ENTRY_SHIFT,     2           # 4-byte table entries
    .equ CRC_BITS_PER_BYTE,     8
    .equ BYTE_MASK,             0xFF
    .equ HALFWORD_MASK,         0xFFFF
    .equ WORD_MASK,             0xFFFFFFFF

    .text
    .globl crc_init
# crc_init
#   What: builds the CRC7, CRC16 and CRC32 lookup tables.
#   Arguments: none. Results: none.
#   Clobbers: only ABI temporaries.
crc_init:
    la      a0, crc7_table
    la      a1, crc16_table
    la      a2, crc32_table
    li      a3, CRC16_POLY
    li      a4, CRC32_POLY_REFLECTED
    li      a5, HALFWORD_MASK
    li      t0, 0                       # t0 = table index i
1:
    # CRC7: shift left 8 times, feeding back x^3 + 1 when bit 7 falls out.
    mv      t1, t0
    li      t2, CRC_BITS_PER_BYTE
2:  andi    t3, t1, CRC7_TOP_BIT
    slli    t1, t1, 1
    beqz    t3, 3f
    xori    t1, t1, CRC7_POLY_ALIGNED
3:  addi    t2, t2, -1
    bnez    t2, 2b
    add     t3, a0, t0
    sb      t1, 0(t3)

    # CRC16: i in the top byte, shift left 8 times.
    slli    t1, t0, CRC_BITS_PER_BYTE
    li      t2, CRC_BITS_PER_BYTE
2:  srli    t3, t1, CRC16_TOP_SHIFT
    andi    t3, t3, 1
    slli    t1, t1, 1
    beqz    t3, 3f
    xor     t1, t1, a3
3:  addi    t2, t2, -1
    bnez    t2, 2b
    and     t1, t1, a5
    slli    t3, t0, CRC16_ENTRY_SHIFT
    add     t3, a1, t3
    sh      t1, 0(t3)

    # CRC32: reflected, shift right 8 times.
    mv      t1, t0
    li      t2, CRC_BITS_PER_BYTE
2:  andi    t3, t1, 1
    srli    t1, t1, 1
    beqz    t3, 3f
    xor     t1, t1, a4
3:  addi    t2, t2, -1
    bnez    t2, 2b
    slli    t3, t0, CRC32_ENTRY_SHIFT
    add     t3, a2, t3
    sw      t1, 0(t3)

    addi    t0, t0, 1
    li      t1, CRC_TABLE_ENTRIES
    bltu    t0, t1, 1b
    ret

    .globl crc7_sd
# crc7_sd
#   What: the CRC7 of a1 bytes at a0, as the last byte of an SD command
#         frame: (crc7 << 1) | 1 (end bit).
#   Arguments: a0 = address, a1 = byte count (> 0).
#   Results: a0 = the frame's CRC byte.
#   Clobbers: only ABI temporaries.
crc7_sd:
    la      t0, crc7_table
    add     a1, a1, a0                  # a1 = end
    li      t1, 0                       # t1 = crc7 << 1
1:  lbu     t2, 0(a0)
    xor     t2, t2, t1
    add     t2, t2, t0
    lbu     t1, 0(t2)
    addi    a0, a0, 1
    bltu    a0, a1, 1b
    ori     a0, t1, 1
    ret

    .globl crc16_ccitt
# crc16_ccitt
#   What: the CRC16-CCITT (initial 0, as the SD card computes it for a data
#         block) of a1 bytes at a0.
#   Arguments: a0 = address, a1 = byte count (0 gives 0).
#   Results: a0 = CRC (16 bits).
#   Clobbers: only ABI temporaries.
crc16_ccitt:
    la      t0, crc16_table
    li      t4, HALFWORD_MASK
    add     a1, a1, a0                  # a1 = end
    li      t1, 0                       # t1 = crc
    bgeu    a0, a1, 2f
1:  lbu     t2, 0(a0)
    srli    t3, t1, CRC_BITS_PER_BYTE
    xor     t3, t3, t2
    slli    t3, t3, CRC16_ENTRY_SHIFT
    add     t3, t3, t0
    lhu     t3, 0(t3)
    slli    t1, t1, CRC_BITS_PER_BYTE
    xor     t1, t1, t3
    and     t1, t1, t4
    addi    a0, a0, 1
    bltu    a0, a1, 1b
2:  mv      a0, t1
    ret

    .globl crc32
# crc32
#   What: the CRC-32 of a1 bytes at a0, exactly as zlib.crc32(data) gives it.
#   Arguments: a0 = address, a1 = byte count (0 gives 0).
#   Results: a0 = CRC (32 bits, zero-extended).
#   Clobbers: only ABI temporaries.
crc32:
    mv      a2, a1
    mv      a1, a0
    li      a0, 0
    # fall through

    .globl crc32_update
# crc32_update
#   What: extends a CRC-32 over more bytes, as zlib.crc32(data, crc) does:
#         crc32_update(crc32_update(0, A), B) = CRC-32 of A followed by B.
#   Arguments: a0 = CRC so far (0 to start), a1 = address, a2 = byte count.
#   Results: a0 = CRC (32 bits, zero-extended).
#   Clobbers: only ABI temporaries.
crc32_update:
    la      t0, crc32_table
    li      t4, WORD_MASK
    add     a2, a2, a1                  # a2 = end
    xor     t1, a0, t4                  # t1 = register (the CRC before its final xor)
    and     t1, t1, t4
    bgeu    a1, a2, 2f
1:  lbu     t2, 0(a1)
    xor     t3, t1, t2
    andi    t3, t3, BYTE_MASK
    slli    t3, t3, CRC32_ENTRY_SHIFT
    add     t3, t3, t0
    lwu     t3, 0(t3)
    srli    t1, t1, CRC_BITS_PER_BYTE
    xor     t1, t1, t3
    addi    a1, a1, 1
    bltu    a1, a2, 1b
2:  xor     a0, t1, t4
    ret

# ---------------------------------------------------------------------------
    .bss
    .balign 8
crc32_table:
    .space  4 * CRC_TABLE_ENTRIES
crc16_table:
    .space  2 * CRC_TABLE_ENTRIES
crc7_table:
    .space  CRC_TABLE_ENTRIES
