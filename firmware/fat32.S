# fat32.S: a read-only FAT32 volume on the SD card: mount, path lookup,
# file reads.
#
# Mount: the first MBR partition of type 0x0B or 0x0C, which must lie on
# the card (below sd_capacity, the CSD's capacity: a partition table that
# claims more than the card holds is checked here rather than left to a
# read the card refuses); its BPB must have 512 bytes per sector, a
# power-of-two cluster size, reserved sectors, 1 or 2 FATs, a FAT size, a
# root cluster >= 2 inside the volume, a total sector count that fits its
# partition and the card and leaves a data region, a FAT big enough for
# every cluster, and the 0x55AA signature. Anything else is error 5. Every
# block fat32.S reads is then inside the volume, so on the card.
#
# FAT entries are read through a one-sector cache (fat_cache). Chains are
# checked as they are followed: an entry < 2 or >= cluster count + 2, the
# bad-cluster marker, a chain longer than the volume's cluster count, a
# loop (Brent's cycle detection: found long before that bound), or a file
# chain that ends before or goes on after the file's size (a loop never
# ends) is error 8.
#
# Lookup: paths are '/'-separated, relative to the root (leading '/'
# allowed). In each directory (any cluster chain) an entry matches by its
# long name when it has a valid one: long-name entries in sequence (first
# stored entry carries 0x40 | n, then n - 1 .. 1, each with the checksum of
# the short entry that follows them, which is verified), compared with the
# path component decoded from UTF-8 to UTF-16, ASCII letters case-folded and
# every other character exact. An entry without a valid long name matches by
# its 8.3 name, case-insensitively. Deleted entries and volume labels are
# skipped; a 0x00 name ends the directory. Not found is error 6. A
# directory's chain may hold at most FAT_DIR_MAX_ENTRIES entries (the FAT
# limit, 2 MiB): it is measured on the FAT before the search, and a longer
# one is error 8, "corrupt directory: <folder> has more than 65536 entries",
# so no search reads more than 2 MiB (a chain of deleted entries could
# otherwise fill the volume and take longer than any boot should).
#
# Reads: a file's contiguous clusters are read with one multi-block command
# each (sd_read_blocks), only the sectors the file's size needs; the file's
# CRC-32 is computed sector by sector while the next sector arrives. A file
# is read whole into the heap (fat32_load) or a few sectors at a time into
# the reader's buffer (fat32_stream_open, fat32_stream_read: obj.S reads the
# model so, without keeping its text).

    .option norelax
    .include "k210.inc"
    .include "fat32.inc"
    .include "errors.inc"

# Little-endian loads at any alignment (BPB and MBR fields are unaligned).
.macro LE16 rd, off, base, tmp
    lbu     \rd, \off(\base)
    lbu     \tmp, \off+1(\base)
    slli    \tmp, \tmp, BYTE_BITS
    or      \rd, \rd, \tmp
.endm
.macro LE32 rd, off, base, tmp
    LE16    \rd, \off, \base, \tmp
    lbu     \tmp, \off+2(\base)
    slli    \tmp, \tmp, 2 * BYTE_BITS
    or      \rd, \rd, \tmp
    lbu     \tmp, \off+3(\base)
    slli    \tmp, \tmp, 3 * BYTE_BITS
    or      \rd, \rd, \tmp
.endm

# A fatal error whose report is one fixed string.
.macro FAIL code, message
    li      a0, \code
    la      a1, \message
    li      a2, 0
    call    error_fatal
.endm

    .equ BYTE_BITS,             8
    .equ BYTE_MASK,             0xFF
    .equ UTF16_UNIT_BYTES,      2
    .equ UTF16_UNIT_SHIFT,      1
    .equ CLUSTER_HI_SHIFT,      16          # DIR_CLUSTER_HI holds bits 31:16
    .equ CHECKSUM_ROTATE,       7           # rotate right by 1 in 8 bits = << 7 | >> 1
    .equ ASCII_LOWER_A,         'a'
    .equ ASCII_LOWER_Z,         'z'
    .equ ASCII_CASE_BIT,        0x20
    .equ ASCII_CASE_SHIFT,      5           # ASCII_CASE_BIT = 1 << 5
    .equ ASCII_LIMIT,           0x80        # case folding stops here
    .equ PATH_SEPARATOR,        '/'
    .equ EXT_SEPARATOR,         '.'
    .equ SPACE,                 ' '
    .equ UTF8_CONT_MASK,        0xC0
    .equ UTF8_CONT_TAG,         0x80
    .equ UTF8_CONT_BITS,        0x3F
    .equ UTF8_CONT_SHIFT,       6
    .equ UTF8_LEAD2_MASK,       0xE0
    .equ UTF8_LEAD2_TAG,        0xC0
    .equ UTF8_LEAD3_MASK,       0xF0
    .equ UTF8_LEAD3_TAG,        0xE0
    .equ UTF8_LEAD4_MASK,       0xF8
    .equ UTF8_LEAD4_TAG,        0xF0
    .equ UTF8_LEAD2_CONTS,      1           # continuation bytes after each lead
    .equ UTF8_LEAD3_CONTS,      2
    .equ UTF8_LEAD4_CONTS,      3
    .equ UTF16_SUPPLEMENTARY,   0x10000
    .equ UTF16_HIGH_SURROGATE,  0xD800
    .equ UTF16_LOW_SURROGATE,   0xDC00
    .equ UTF16_SURROGATE_SHIFT, 10
    .equ UTF16_SURROGATE_BITS,  0x3FF
# fat_walk: the loop detector of the chain being followed
    .equ WALK_SAVED,            0           # cluster to watch for
    .equ WALK_POWER,            8           # steps until the next one is watched
    .equ WALK_COUNT,            16          # steps since
    .equ WALK_STEPS,            24          # clusters visited
    .equ WALK_BYTES,            32
# fat32_load's CRC context (on its stack), handed to fat_crc_sector
    .equ CRC_CTX_CRC,           0           # CRC-32 so far
    .equ CRC_CTX_LEFT,          8           # file bytes not yet counted
    .equ CRC_CTX_BYTES,         16

    .section .rodata
# Offsets of the 13 UTF-16 characters inside a long-name entry.
lfn_char_offsets:
    .byte   1, 3, 5, 7, 9, 14, 16, 18, 20, 22, 24, 28, 30
    .if (. - lfn_char_offsets) != LFN_CHARS
    .error "lfn_char_offsets needs LFN_CHARS entries"
    .endif

msg_no_mbr:         .asciz "no FAT32 partition: no MBR signature in block 0"
msg_no_partition:   .asciz "no FAT32 partition: no MBR entry of type 0x0B or 0x0C"
msg_part_at_zero:   .asciz "no FAT32 partition: partition entry starts at block 0"
msg_bpb_signature:  .asciz "invalid BPB: no 0x55AA signature"
msg_bpb_sector:     .asciz "invalid BPB: bytes per sector is not 512"
msg_bpb_spc:        .asciz "invalid BPB: sectors per cluster is not a power of two"
msg_bpb_reserved:   .asciz "invalid BPB: no reserved sectors"
msg_bpb_fats:       .asciz "invalid BPB: number of FATs is not 1 or 2"
msg_bpb_fat_size:   .asciz "invalid BPB: FAT size is 0"
msg_bpb_fat_small:  .asciz "invalid BPB: FAT too small for the clusters"
msg_bpb_root:       .asciz "invalid BPB: root cluster out of range"
msg_bpb_total:      .asciz "invalid BPB: no sectors"
msg_bpb_partition:  .asciz "invalid BPB: volume larger than its partition"
msg_bpb_data:       .asciz "invalid BPB: no data region"
msg_part_past_card: .asciz "no FAT32 partition: the partition ends at block "
msg_bpb_past_card:  .asciz "invalid BPB: the volume ends at block "
msg_past_card_last: .asciz ", past the card's last block "
msg_not_found:      .asciz "file not found: "
msg_chain:          .asciz "corrupt FAT chain: "
msg_chain_open:     .asciz " ("
msg_chain_close:    .asciz ")"
msg_chain_range:    .asciz "cluster out of range"
msg_chain_bad:      .asciz "bad cluster"
msg_chain_loop:     .asciz "loop"
msg_chain_volume:   .asciz "chain longer than the volume"
msg_chain_short:    .asciz "chain ends before the file's size"
msg_chain_long:     .asciz "chain does not end at the file's size"
msg_dir_corrupt:    .asciz "corrupt directory: "
msg_dir_entries:    .asciz " has more than "
msg_dir_entries_tail: .asciz " entries"
msg_too_large:      .asciz "file too large for memory: "
msg_too_large_size: .asciz " ("
msg_too_large_sectors: .asciz " bytes, "
msg_too_large_free: .asciz " in whole sectors, "
msg_too_large_tail: .asciz " bytes free)"
msg_mount:          .asciz "fat32: partition at block "
msg_mount_cluster:  .asciz ", "
msg_mount_clusters: .asciz "-byte clusters, "
msg_mount_tail:     .asciz " clusters\n"
msg_root_path:      .asciz "/"

    .text
    .globl fat32_mount
# fat32_mount
#   What: finds the FAT32 partition, validates its BPB (see the file
#         comment), records the volume's layout in fat_volume and prints
#         one console line. Needs sd_init.
#   Arguments: none. Results: none (returns only with a usable volume).
#   Clobbers: only ABI temporaries.
fat32_mount:
    addi    sp, sp, -96
    sd      ra, 88(sp)
    sd      s0, 80(sp)
    sd      s1, 72(sp)
    sd      s2, 64(sp)
    sd      s3, 56(sp)
    sd      s4, 48(sp)
    sd      s5, 40(sp)
    sd      s6, 32(sp)
    sd      s7, 24(sp)
    sd      s8, 16(sp)
    sd      s9, 8(sp)
    sd      s10, 0(sp)
    la      s0, fat_volume
    la      s1, fat_sector
    li      t0, -1
    sd      t0, VOL_CACHE_LBA(s0)
    la      t0, fat_path
    la      t1, msg_root_path
    sd      t1, 0(t0)

    # MBR
    li      a0, 0
    li      a1, 1
    mv      a2, s1
    li      a3, 0
    call    sd_read_blocks
    mv      a0, s1
    call    has_boot_signature
    bnez    a0, 1f
    FAIL    ERR_NO_FAT32, msg_no_mbr
1:  addi    t2, s1, MBR_PART_TABLE
    li      t3, MBR_PART_COUNT
2:  lbu     t0, MBR_PART_TYPE(t2)
    li      t1, PART_TYPE_FAT32_CHS
    beq     t0, t1, 3f
    li      t1, PART_TYPE_FAT32_LBA
    beq     t0, t1, 3f
    addi    t2, t2, MBR_PART_ENTRY_BYTES
    addi    t3, t3, -1
    bnez    t3, 2b
    FAIL    ERR_NO_FAT32, msg_no_partition
3:  LE32    s2, MBR_PART_FIRST_LBA, t2, t0  # s2 = partition's first block
    LE32    s3, MBR_PART_SECTORS, t2, t0    # s3 = partition's length
    bnez    s2, 4f
    FAIL    ERR_NO_FAT32, msg_part_at_zero
4:  mv      a0, s2
    mv      a1, s3
    bnez    a1, 41f
    li      a1, 1                       # no length: at least its BPB
41: la      a2, msg_part_past_card
    call    fat_check_on_card
    sd      s2, VOL_PART_LBA(s0)

    # BPB
    mv      a0, s2
    li      a1, 1
    mv      a2, s1
    li      a3, 0
    call    sd_read_blocks
    mv      a0, s1
    call    has_boot_signature
    bnez    a0, 5f
    FAIL    ERR_NO_FAT32, msg_bpb_signature
5:  LE16    t0, BPB_BYTES_PER_SECTOR, s1, t1
    li      t1, FAT_SECTOR_BYTES
    beq     t0, t1, 6f
    FAIL    ERR_NO_FAT32, msg_bpb_sector
6:  lbu     t0, BPB_SECTORS_PER_CLUSTER(s1)
    beqz    t0, 7f
    addi    t1, t0, -1
    and     t1, t1, t0
    beqz    t1, 8f
7:  FAIL    ERR_NO_FAT32, msg_bpb_spc
8:  li      s4, 0                       # s4 = log2(sectors per cluster)
9:  srli    t0, t0, 1
    beqz    t0, 10f
    addi    s4, s4, 1
    j       9b
10: sd      s4, VOL_SPC_SHIFT(s0)
    LE16    s5, BPB_RESERVED_SECTORS, s1, t1    # s5 = reserved sectors
    bnez    s5, 11f
    FAIL    ERR_NO_FAT32, msg_bpb_reserved
11: lbu     s6, BPB_NUM_FATS(s1)        # s6 = FATs
    beqz    s6, 12f
    li      t0, BPB_MAX_FATS
    bleu    s6, t0, 13f
12: FAIL    ERR_NO_FAT32, msg_bpb_fats
13: LE32    s7, BPB_FAT_SIZE_32, s1, t1 # s7 = sectors per FAT
    bnez    s7, 14f
    FAIL    ERR_NO_FAT32, msg_bpb_fat_size
14: LE32    s8, BPB_ROOT_CLUSTER, s1, t1    # s8 = root cluster
    li      t0, FAT_FIRST_CLUSTER
    bgeu    s8, t0, 15f
    FAIL    ERR_NO_FAT32, msg_bpb_root
15: LE16    s9, BPB_TOTAL_SECTORS_16, s1, t1    # s9 = sectors in the volume
    bnez    s9, 16f
    LE32    s9, BPB_TOTAL_SECTORS_32, s1, t1
    bnez    s9, 16f
    FAIL    ERR_NO_FAT32, msg_bpb_total
16: beqz    s3, 161f                    # (a partition entry without a length)
    bleu    s9, s3, 161f
    FAIL    ERR_NO_FAT32, msg_bpb_partition
161: mv     a0, s2
    mv      a1, s9
    la      a2, msg_bpb_past_card
    call    fat_check_on_card
17: mul     t0, s6, s7
    add     t0, t0, s5                  # t0 = data region's first sector
    bltu    t0, s9, 18f
    FAIL    ERR_NO_FAT32, msg_bpb_data
18: sub     s10, s9, t0
    srl     s10, s10, s4                # s10 = clusters
    bnez    s10, 19f
    FAIL    ERR_NO_FAT32, msg_bpb_data
19: add     t1, s2, t0
    sd      t1, VOL_DATA_LBA(s0)
    add     t1, s2, s5
    sd      t1, VOL_FAT_LBA(s0)
    sd      s10, VOL_CLUSTERS(s0)
    slli    t1, s7, FAT_ENTRIES_PER_SECTOR_SHIFT    # entries the FAT holds
    addi    t2, s10, FAT_FIRST_CLUSTER
    bgeu    t1, t2, 20f
    FAIL    ERR_NO_FAT32, msg_bpb_fat_small
20: li      t3, FAT_BAD_CLUSTER         # cluster numbers must stay below the markers
    bleu    t2, t3, 21f
    FAIL    ERR_NO_FAT32, msg_bpb_fat_small
21: bltu    s8, t2, 22f
    FAIL    ERR_NO_FAT32, msg_bpb_root
22: sd      s8, VOL_ROOT_CLUSTER(s0)

    call    console_lock
    la      a0, msg_mount
    call    console_puts
    mv      a0, s2
    call    console_put_dec
    la      a0, msg_mount_cluster
    call    console_puts
    li      a0, FAT_SECTOR_BYTES
    sll     a0, a0, s4
    call    console_put_dec
    la      a0, msg_mount_clusters
    call    console_puts
    mv      a0, s10
    call    console_put_dec
    la      a0, msg_mount_tail
    call    console_puts
    call    console_unlock

    ld      s10, 0(sp)
    ld      s9, 8(sp)
    ld      s8, 16(sp)
    ld      s7, 24(sp)
    ld      s6, 32(sp)
    ld      s5, 40(sp)
    ld      s4, 48(sp)
    ld      s3, 56(sp)
    ld      s2, 64(sp)
    ld      s1, 72(sp)
    ld      s0, 80(sp)
    ld      ra, 88(sp)
    addi    sp, sp, 96
    ret

# fat_check_on_card (file-local)
#   What: error 5 unless blocks a0 .. a0 + a1 - 1 all exist on the card
#         (below sd_capacity): "<words><last block>, past the card's last
#         block <sd_capacity - 1>".
#   Arguments: a0 = first block, a1 = block count (>= 1; both below 2^32),
#         a2 = words (msg_part_past_card, msg_bpb_past_card).
#   Results: none (the error path does not return).
#   Clobbers: only ABI temporaries when it returns.
fat_check_on_card:
    add     t0, a0, a1
    la      t1, sd_capacity
    ld      t1, 0(t1)
    bgtu    t0, t1, 1f
    ret
1:  addi    s0, t0, -1                  # (fatal: the caller's s registers are not needed)
    addi    s1, t1, -1
    mv      s2, a2
    li      a0, ERR_NO_FAT32
    call    error_begin
    mv      a0, s2
    call    console_puts
    mv      a0, s0
    call    console_put_dec
    la      a0, msg_past_card_last
    call    console_puts
    mv      a0, s1
    call    console_put_dec
    j       error_end

# has_boot_signature (file-local)
#   What: whether a sector ends in 0x55 0xAA.
#   Arguments: a0 = sector buffer.
#   Results: a0 = 1 yes, 0 no.
#   Clobbers: only ABI temporaries.
has_boot_signature:
    lbu     t0, BOOT_SIGNATURE_OFF(a0)
    lbu     t1, BOOT_SIGNATURE_OFF + 1(a0)
    li      a0, 0
    li      t2, BOOT_SIGNATURE_0
    bne     t0, t2, 1f
    li      t2, BOOT_SIGNATURE_1
    bne     t1, t2, 1f
    li      a0, 1
1:  ret

    .globl fat32_load
# fat32_load
#   What: reads a whole file into a heap block sized from its length
#         (rounded up to whole sectors for the reads), computing its CRC-32
#         (zlib's) as the sectors arrive.
#   Arguments: a0 = path (NUL-terminated, '/'-separated, from the root).
#   Results: a0 = address of the file's bytes, a1 = its size in bytes,
#         a2 = its CRC-32.
#   Errors: 6 not found, 7 does not fit in the heap, 8 corrupt chain.
#   Clobbers: only ABI temporaries.
fat32_load:
    addi    sp, sp, -64
    sd      ra, 56(sp)
    sd      s0, 48(sp)
    sd      s1, 40(sp)
    sd      s2, 32(sp)
    sd      s3, 24(sp)
    # 0(sp): the CRC context (CRC_CTX_BYTES)
    mv      s0, a0
    call    fat32_open
    mv      s1, a0                      # s1 = first cluster
    mv      s2, a1                      # s2 = size
    addi    a0, s2, FAT_SECTOR_BYTES - 1
    andi    a0, a0, -FAT_SECTOR_BYTES
    call    heap_alloc
    mv      s3, a0                      # s3 = buffer
    bnez    s3, 1f
    li      a0, ERR_TOO_LARGE
    call    error_begin
    la      a0, msg_too_large
    call    console_puts
    mv      a0, s0
    call    console_puts
    la      a0, msg_too_large_size
    call    console_puts
    mv      a0, s2
    call    console_put_dec
    la      a0, msg_too_large_sectors
    call    console_puts
    addi    a0, s2, FAT_SECTOR_BYTES - 1  # what the heap was asked for
    andi    a0, a0, -FAT_SECTOR_BYTES
    call    console_put_dec
    la      a0, msg_too_large_free
    call    console_puts
    call    heap_free_bytes
    call    console_put_dec
    la      a0, msg_too_large_tail
    call    console_puts
    j       error_end
1:  sd      zero, CRC_CTX_CRC(sp)
    sd      s2, CRC_CTX_LEFT(sp)
    mv      a0, s1
    mv      a1, s2
    mv      a2, s3
    la      a3, fat_crc_sector
    mv      a4, sp
    call    fat32_read
    mv      a0, s3
    mv      a1, s2
    ld      a2, CRC_CTX_CRC(sp)
    ld      s3, 24(sp)
    ld      s2, 32(sp)
    ld      s1, 40(sp)
    ld      s0, 48(sp)
    ld      ra, 56(sp)
    addi    sp, sp, 64
    ret

    .globl fat32_open
# fat32_open
#   What: fat32_lookup, with "not found" a fatal error.
#   Arguments: a0 = path (NUL-terminated).
#   Results: a0 = the file's first cluster (0 for an empty file), a1 = size.
#   Errors: 6 not found, 8 corrupt chain or directory.
#   Clobbers: only ABI temporaries.
fat32_open:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    call    fat32_lookup
    beqz    a2, 1f
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret
1:  la      t0, fat_path
    ld      a2, 0(t0)
    li      a0, ERR_NOT_FOUND
    la      a1, msg_not_found
    call    error_fatal

    .globl fat32_lookup
# fat32_lookup
#   What: looks a file up by path: each component in turn, from the root
#         directory; every component but the last must be a directory, the
#         last must not be. Remembers the path for error reports.
#   Arguments: a0 = path (NUL-terminated).
#   Results: a2 = 1 found, then a0 = the file's first cluster (0 for an
#         empty file), a1 = size; a2 = 0 not found (no such file, or a
#         folder where a file is wanted or the other way round).
#   Errors: 8 corrupt chain in a directory, or a directory longer than
#         FAT_DIR_MAX_ENTRIES entries.
#   Clobbers: only ABI temporaries.
fat32_lookup:
    addi    sp, sp, -48
    sd      ra, 40(sp)
    sd      s0, 32(sp)
    sd      s1, 24(sp)
    sd      s2, 16(sp)
    sd      s3, 8(sp)
    la      t0, fat_path
    sd      a0, 0(t0)
    mv      s0, a0                      # s0 = next component
    la      t0, fat_volume
    ld      s1, VOL_ROOT_CLUSTER(t0)    # s1 = directory searched
1:  lbu     t0, 0(s0)
    li      t1, PATH_SEPARATOR
    bne     t0, t1, 2f
    addi    s0, s0, 1
    j       1b
2:  beqz    t0, 9f                      # empty component: nothing to find
    mv      s2, s0                      # s2 = end of the component
3:  lbu     t0, 0(s2)
    beqz    t0, 4f
    li      t1, PATH_SEPARATOR
    beq     t0, t1, 4f
    addi    s2, s2, 1
    j       3b
4:  la      t0, fat_dir_end
    sd      s0, 0(t0)                   # the folder searched is the path before s0
    mv      a0, s1
    mv      a1, s0
    sub     a2, s2, s0
    call    fat32_find
    beqz    a0, 9f
    andi    s3, a3, ATTR_DIRECTORY      # s3 = is a directory
    lbu     t0, 0(s2)
    beqz    t0, 6f                      # last component
    beqz    s3, 9f                      # a file where a folder is wanted
    mv      s1, a1
    bnez    s1, 5f
    la      t0, fat_volume              # ".." of a first-level folder: cluster 0 = root
    ld      s1, VOL_ROOT_CLUSTER(t0)
5:  mv      s0, s2
    j       1b
6:  bnez    s3, 9f                      # a folder where a file is wanted
    mv      a0, a1
    mv      a1, a2
    li      a2, 1
    j       10f
9:  li      a2, 0
10: ld      s3, 8(sp)
    ld      s2, 16(sp)
    ld      s1, 24(sp)
    ld      s0, 32(sp)
    ld      ra, 40(sp)
    addi    sp, sp, 48
    ret

# fat32_find (file-local)
#   What: searches one directory (its whole cluster chain) for an entry
#         named like the given path component (see the file comment for the
#         matching rules).
#   Arguments: a0 = directory's first cluster, a1 = name, a2 = name length
#         in bytes (no NUL needed).
#   Results: a0 = 1 found, 0 not found; when found a1 = first cluster,
#         a2 = size, a3 = attribute byte.
#   Errors: 8 corrupt chain, or a chain longer than FAT_DIR_MAX_ENTRIES
#         entries (the folder is named from fat_path up to fat_dir_end).
#   Clobbers: only ABI temporaries.
fat32_find:
    addi    sp, sp, -112
    sd      ra, 104(sp)
    sd      s0, 96(sp)
    sd      s1, 88(sp)
    sd      s2, 80(sp)
    sd      s3, 72(sp)
    sd      s4, 64(sp)
    sd      s5, 56(sp)
    sd      s6, 48(sp)
    sd      s7, 40(sp)
    sd      s8, 32(sp)
    sd      s9, 24(sp)
    sd      s10, 16(sp)
    sd      s11, 8(sp)
    mv      s0, a0                      # s0 = cluster being read
    mv      s8, a1                      # s8 = name
    mv      s9, a2                      # s9 = name length (bytes)
    mv      a0, s8
    mv      a1, s9
    call    utf8_to_utf16
    mv      s10, a0                     # s10 = name length (UTF-16 units)
    mv      a0, s0
    call    fat_dir_check_length
    mv      a0, s0
    call    fat_walk_start
    li      s4, -1                      # s4 = long name state: -1 none, n > 0 next
                                        #      ordinal expected, 0 complete
    la      t0, fat_volume
    ld      s11, VOL_SPC_SHIFT(t0)
    li      t1, 1
    sll     s11, t1, s11                # s11 = sectors per cluster

1:  li      s1, 0                       # s1 = sector within the cluster
2:  mv      a0, s0
    call    fat_cluster_lba
    add     a0, a0, s1
    li      a1, 1
    la      a2, fat_sector
    li      a3, 0
    call    sd_read_blocks
    la      s2, fat_sector              # s2 = entry
    addi    s3, s2, FAT_SECTOR_BYTES    # s3 = end of the sector

3:  lbu     t0, DIR_NAME(s2)
    beqz    t0, 20f                     # DIR_MARK_END: no more entries
    li      t1, DIR_MARK_DELETED
    beq     t0, t1, 10f
    lbu     t1, DIR_ATTR(s2)
    andi    t2, t1, ATTR_LONG_NAME_MASK
    li      t3, ATTR_LONG_NAME
    beq     t2, t3, 5f
    andi    t2, t1, ATTR_VOLUME_ID
    bnez    t2, 10f

    # A short entry: by its long name if a complete one with its checksum
    # came right before it, else by its 8.3 name.
    bnez    s4, 4f
    mv      a0, s2
    call    short_name_checksum
    bne     a0, s5, 4f
    mv      a0, s6
    mv      a1, s10
    call    long_name_matches
    j       41f
4:  mv      a0, s2
    mv      a1, s8
    mv      a2, s9
    call    short_name_matches
41: li      s4, -1
    bnez    a0, 30f
    j       11f

    # A long-name entry: ordinal t0 (bit 6 = first stored).
5:  andi    t2, t0, LFN_LAST
    andi    t0, t0, ~LFN_LAST & BYTE_MASK
    beqz    t2, 6f
    beqz    t0, 10f                     # ordinal 0 or > 20: not a valid sequence
    li      t3, LFN_MAX_ORDINAL
    bgtu    t0, t3, 10f
    mv      s6, t0                      # s6 = entries in this long name
    mv      s4, t0
    lbu     s5, LFN_CHECKSUM(s2)        # s5 = checksum they all carry
    j       7f
6:  blez    s4, 10f                     # no sequence open (or already complete)
    bne     t0, s4, 10f                 # out of order
    lbu     t3, LFN_CHECKSUM(s2)
    bne     t3, s5, 10f
7:  # Copy its 13 characters to lfn_buffer[(ordinal - 1) * 13 ..].
    addi    t0, t0, -1
    li      t1, LFN_CHARS * UTF16_UNIT_BYTES
    mul     t0, t0, t1
    la      t1, lfn_buffer
    add     t0, t0, t1                  # t0 = destination
    la      t1, lfn_char_offsets
    addi    t2, t1, LFN_CHARS           # t2 = end of the offsets
8:  lbu     t3, 0(t1)
    add     t3, t3, s2
    lbu     t4, 0(t3)
    lbu     t5, 1(t3)
    slli    t5, t5, 8
    or      t4, t4, t5
    sh      t4, 0(t0)
    addi    t0, t0, UTF16_UNIT_BYTES
    addi    t1, t1, 1
    bltu    t1, t2, 8b
    addi    s4, s4, -1
    j       11f

10: li      s4, -1                      # anything breaking a long-name sequence
11: addi    s2, s2, DIR_ENTRY_BYTES
    bltu    s2, s3, 3b
    addi    s1, s1, 1
    bltu    s1, s11, 2b

    # Next cluster of the directory.
    mv      a0, s0
    call    fat_walk_next
    beqz    a0, 20f
    mv      s0, a0
    j       1b

20: li      a0, 0
    j       31f
30: lhu     a1, DIR_CLUSTER_HI(s2)
    slli    a1, a1, CLUSTER_HI_SHIFT
    lhu     t0, DIR_CLUSTER_LO(s2)
    or      a1, a1, t0
    lwu     a2, DIR_FILE_SIZE(s2)
    lbu     a3, DIR_ATTR(s2)
    li      a0, 1
31: ld      s11, 8(sp)
    ld      s10, 16(sp)
    ld      s9, 24(sp)
    ld      s8, 32(sp)
    ld      s7, 40(sp)
    ld      s6, 48(sp)
    ld      s5, 56(sp)
    ld      s4, 64(sp)
    ld      s3, 72(sp)
    ld      s2, 80(sp)
    ld      s1, 88(sp)
    ld      s0, 96(sp)
    ld      ra, 104(sp)
    addi    sp, sp, 112
    ret

# short_name_checksum (file-local)
#   What: the long-name checksum of a short entry's 11 name bytes
#         (rotate right by one, add the next byte, modulo 256).
#   Arguments: a0 = directory entry.
#   Results: a0 = checksum (0 .. 255).
#   Clobbers: only ABI temporaries.
short_name_checksum:
    addi    t2, a0, DIR_NAME_BYTES
    li      t0, 0
1:  srli    t1, t0, 1
    slli    t0, t0, CHECKSUM_ROTATE
    or      t0, t0, t1
    andi    t0, t0, BYTE_MASK
    lbu     t1, 0(a0)
    add     t0, t0, t1
    andi    t0, t0, BYTE_MASK
    addi    a0, a0, 1
    bltu    a0, t2, 1b
    mv      a0, t0
    ret

# ascii_fold (file-local macro): upper-cases \reg if it is 'a' .. 'z'.
.macro ASCII_FOLD reg, tmp
    addi    \tmp, \reg, -ASCII_LOWER_A
    sltiu   \tmp, \tmp, ASCII_LOWER_Z - ASCII_LOWER_A + 1
    slli    \tmp, \tmp, ASCII_CASE_SHIFT              # ASCII_CASE_BIT when a lower-case letter
    sub     \reg, \reg, \tmp
.endm
    .if ASCII_CASE_BIT != (1 << ASCII_CASE_SHIFT)
    .error "ASCII_CASE_SHIFT does not match ASCII_CASE_BIT"
    .endif

# long_name_matches (file-local)
#   What: compares the long name in lfn_buffer (a0 entries' worth, ending
#         at its first NUL or after them all) with the path component in
#         fat_name16: same length; ASCII letters compared case-folded, every
#         other UTF-16 unit exactly.
#   Arguments: a0 = long-name entries (1 .. 20), a1 = component length in
#         UTF-16 units.
#   Results: a0 = 1 match, 0 not.
#   Clobbers: only ABI temporaries.
long_name_matches:
    li      t0, LFN_CHARS
    mul     t0, t0, a0
    la      t1, lfn_buffer
    slli    t0, t0, UTF16_UNIT_SHIFT
    add     t0, t0, t1                  # t0 = end of the stored units
    mv      t2, t1
1:  bgeu    t2, t0, 2f                  # t2 = scan for the terminating NUL
    lhu     t3, 0(t2)
    beqz    t3, 2f
    addi    t2, t2, UTF16_UNIT_BYTES
    j       1b
2:  sub     t2, t2, t1
    srli    t2, t2, UTF16_UNIT_SHIFT    # t2 = long name length
    bne     t2, a1, 9f
    la      t3, fat_name16
3:  beqz    t2, 8f
    lhu     t4, 0(t1)
    lhu     t5, 0(t3)
    beq     t4, t5, 4f
    li      t6, ASCII_LIMIT
    bgeu    t4, t6, 9f
    bgeu    t5, t6, 9f
    ASCII_FOLD t4, t6
    ASCII_FOLD t5, t6
    bne     t4, t5, 9f
4:  addi    t1, t1, UTF16_UNIT_BYTES
    addi    t3, t3, UTF16_UNIT_BYTES
    addi    t2, t2, -1
    j       3b
8:  li      a0, 1
    ret
9:  li      a0, 0
    ret

# short_name_matches (file-local)
#   What: compares a short entry's 8.3 name, written as text ("BASE.EXT"
#         without padding, no dot without an extension, a leading 0x05 read
#         as 0xE5), with a path component, ASCII letters case-folded.
#   Arguments: a0 = directory entry, a1 = component, a2 = its length.
#   Results: a0 = 1 match, 0 not.
#   Clobbers: only ABI temporaries.
short_name_matches:
    addi    sp, sp, -16                 # the text, at most 12 bytes
    mv      t0, sp                      # t0 = write pointer
    # base: up to its last non-space byte
    li      t1, DIR_BASE_BYTES
1:  add     t2, a0, t1
    lbu     t2, -1(t2)
    li      t3, SPACE
    bne     t2, t3, 2f
    addi    t1, t1, -1
    bnez    t1, 1b
2:  li      t2, 0                       # t2 = index; t1 = base length
3:  bgeu    t2, t1, 5f
    add     t3, a0, t2
    lbu     t3, 0(t3)
    bnez    t2, 4f
    li      t4, DIR_MARK_KANJI_E5
    bne     t3, t4, 4f
    li      t3, DIR_MARK_DELETED
4:  sb      t3, 0(t0)
    addi    t0, t0, 1
    addi    t2, t2, 1
    j       3b
5:  # extension: up to its last non-space byte, after a dot
    li      t1, DIR_EXT_BYTES
6:  add     t2, a0, t1
    lbu     t2, DIR_BASE_BYTES - 1(t2)
    li      t3, SPACE
    bne     t2, t3, 7f
    addi    t1, t1, -1
    bnez    t1, 6b
    j       9f
7:  li      t3, EXT_SEPARATOR
    sb      t3, 0(t0)
    addi    t0, t0, 1
    addi    t4, a0, DIR_BASE_BYTES
    add     t5, t4, t1
8:  lbu     t3, 0(t4)
    sb      t3, 0(t0)
    addi    t0, t0, 1
    addi    t4, t4, 1
    bltu    t4, t5, 8b
9:  sub     t1, t0, sp                  # t1 = text length
    bne     t1, a2, 12f
    mv      t0, sp
10: beqz    t1, 11f
    lbu     t2, 0(t0)
    lbu     t3, 0(a1)
    ASCII_FOLD t2, t4
    ASCII_FOLD t3, t4
    bne     t2, t3, 12f
    addi    t0, t0, 1
    addi    a1, a1, 1
    addi    t1, t1, -1
    j       10b
11: li      a0, 1
    addi    sp, sp, 16
    ret
12: li      a0, 0
    addi    sp, sp, 16
    ret

# utf8_to_utf16 (file-local)
#   What: decodes a path component from UTF-8 into UTF-16 units in
#         fat_name16 (characters above U+FFFF as surrogate pairs). A byte
#         that does not start a valid sequence stands for itself. Units past
#         the buffer are counted but not stored (such a name matches no
#         long name anyway).
#   Arguments: a0 = bytes, a1 = byte count.
#   Results: a0 = number of UTF-16 units.
#   Clobbers: only ABI temporaries.
utf8_to_utf16:
    add     a1, a1, a0                  # a1 = end
    la      a2, fat_name16
    li      a3, 0                       # a3 = units
1:  bgeu    a0, a1, 9f
    lbu     t0, 0(a0)
    addi    a0, a0, 1
    li      t1, ASCII_LIMIT
    bltu    t0, t1, 7f                  # ASCII
    andi    t1, t0, UTF8_LEAD2_MASK
    li      t2, UTF8_LEAD2_TAG
    li      t3, UTF8_LEAD2_CONTS                     # t3 = continuation bytes
    andi    t4, t0, ~UTF8_LEAD2_MASK & BYTE_MASK
    beq     t1, t2, 2f
    andi    t1, t0, UTF8_LEAD3_MASK
    li      t2, UTF8_LEAD3_TAG
    li      t3, UTF8_LEAD3_CONTS
    andi    t4, t0, ~UTF8_LEAD3_MASK & BYTE_MASK
    beq     t1, t2, 2f
    andi    t1, t0, UTF8_LEAD4_MASK
    li      t2, UTF8_LEAD4_TAG
    li      t3, UTF8_LEAD4_CONTS
    andi    t4, t0, ~UTF8_LEAD4_MASK & BYTE_MASK
    beq     t1, t2, 2f
    j       7f                          # not a lead byte: itself
2:  mv      t5, a0                      # t5 = scan; t4 = code point so far
3:  bgeu    t5, a1, 7f                  # truncated: the lead byte stands for itself
    lbu     t1, 0(t5)
    andi    t2, t1, UTF8_CONT_MASK
    li      t6, UTF8_CONT_TAG
    bne     t2, t6, 7f
    andi    t1, t1, UTF8_CONT_BITS
    slli    t4, t4, UTF8_CONT_SHIFT
    or      t4, t4, t1
    addi    t5, t5, 1
    addi    t3, t3, -1
    bnez    t3, 3b
    mv      a0, t5
    mv      t0, t4
    li      t1, UTF16_SUPPLEMENTARY
    bltu    t0, t1, 7f
    sub     t0, t0, t1                  # a surrogate pair
    srli    t1, t0, UTF16_SURROGATE_SHIFT
    li      t2, UTF16_HIGH_SURROGATE
    add     t1, t1, t2
    li      t2, LFN_BUFFER_UNITS
    bgeu    a3, t2, 4f
    slli    t2, a3, UTF16_UNIT_SHIFT
    add     t2, t2, a2
    sh      t1, 0(t2)
4:  addi    a3, a3, 1
    andi    t0, t0, UTF16_SURROGATE_BITS
    li      t2, UTF16_LOW_SURROGATE
    add     t0, t0, t2
7:  li      t2, LFN_BUFFER_UNITS        # store unit t0
    bgeu    a3, t2, 8f
    slli    t2, a3, UTF16_UNIT_SHIFT
    add     t2, t2, a2
    sh      t0, 0(t2)
8:  addi    a3, a3, 1
    j       1b
9:  mv      a0, a3
    ret

    .globl fat32_read
# fat32_read
#   What: reads the first ceil(a1 / 512) sectors of the cluster chain that
#         starts at a0 into memory at a2, one multi-block read per run of
#         contiguous clusters. The chain is checked as it is followed. Each
#         sector is handed to the hook as it arrives (see sd_read_blocks).
#   Arguments: a0 = first cluster, a1 = size in bytes (0 reads nothing),
#         a2 = destination (size rounded up to whole sectors), a3 = hook
#         or 0, a4 = hook context.
#   Results: none.
#   Errors: 8 corrupt chain (out of range, bad cluster, loop, longer than
#         the volume, ending before or after the file's size).
#   Clobbers: only ABI temporaries.
fat32_read:
    beqz    a1, 9f
    addi    sp, sp, -96
    sd      ra, 88(sp)
    sd      s0, 80(sp)
    sd      s1, 72(sp)
    sd      s2, 64(sp)
    sd      s3, 56(sp)
    sd      s4, 48(sp)
    sd      s5, 40(sp)
    sd      s6, 32(sp)
    sd      s7, 24(sp)
    sd      s8, 16(sp)
    sd      s9, 8(sp)
    mv      s0, a0                      # s0 = current cluster
    addi    s1, a1, FAT_SECTOR_BYTES - 1
    srli    s1, s1, FAT_SECTOR_SHIFT    # s1 = sectors still to read
    mv      s2, a2                      # s2 = destination
    mv      s8, a3                      # s8 = hook
    mv      s9, a4                      # s9 = hook context
    call    fat_walk_start
    la      t0, fat_volume
    ld      s6, VOL_SPC_SHIFT(t0)       # s6 = log2(sectors per cluster)

1:  mv      s3, s0                      # s3 = first cluster of the run
    li      s4, 1                       # s4 = clusters in the run
2:  sll     t0, s4, s6
    bgeu    t0, s1, 5f                  # the run covers the rest of the file
    mv      a0, s0
    call    fat_walk_next
    bnez    a0, 4f
    la      a0, msg_chain_short
    call    fat_chain_error
4:  addi    t0, s0, 1
    mv      s7, a0                      # s7 = next cluster
    mv      s0, a0
    bne     s7, t0, 6f                  # not contiguous: read this run
    addi    s4, s4, 1
    j       2b

5:  # Last run: only the sectors the size needs. The chain must end with
    # the file's last cluster (a loop never ends; it would repeat data).
    mv      a0, s0
    call    fat_chain_next
    beqz    a0, 51f
    la      a0, msg_chain_long
    call    fat_chain_error
51: mv      a0, s3
    call    fat_cluster_lba
    mv      a1, s1
    mv      a2, s2
    mv      a3, s8
    mv      a4, s9
    call    sd_read_blocks
    j       8f

6:  mv      a0, s3
    call    fat_cluster_lba
    sll     a1, s4, s6
    mv      a2, s2
    mv      a3, s8
    mv      a4, s9
    sub     s1, s1, a1
    slli    t0, a1, FAT_SECTOR_SHIFT
    add     s2, s2, t0
    call    sd_read_blocks
    j       1b                          # s0 = the next run's first cluster

8:  ld      s9, 8(sp)
    ld      s8, 16(sp)
    ld      s7, 24(sp)
    ld      s6, 32(sp)
    ld      s5, 40(sp)
    ld      s4, 48(sp)
    ld      s3, 56(sp)
    ld      s2, 64(sp)
    ld      s1, 72(sp)
    ld      s0, 80(sp)
    ld      ra, 88(sp)
    addi    sp, sp, 96
9:  ret

    .if STREAM_CRC != CRC_CTX_CRC || STREAM_CRC_LEFT != CRC_CTX_LEFT
    .error "a stream record must start with a CRC context"
    .endif

    .globl fat32_stream_open
# fat32_stream_open
#   What: opens a file to be read a few sectors at a time (fat32_stream_read),
#         for a reader that does not keep the whole file: fills the stream
#         record (STREAM_*, fat32.inc) and starts following the file's chain.
#   Arguments: a0 = stream record (STREAM_BYTES), a1 = path (NUL-terminated;
#         must stay in place while the stream is read).
#   Results: a0 = the file's size in bytes.
#   Errors: 6 not found, 8 corrupt chain (a first cluster out of range).
#   Clobbers: only ABI temporaries.
fat32_stream_open:
    addi    sp, sp, -32
    sd      ra, 24(sp)
    sd      s0, 16(sp)
    sd      s1, 8(sp)
    mv      s0, a0                      # s0 = stream
    sd      a1, STREAM_PATH(s0)
    mv      a0, a1
    call    fat32_open
    mv      s1, a1                      # s1 = size
    sd      a0, STREAM_CLUSTER(s0)
    sd      zero, STREAM_SECTOR(s0)
    addi    t0, s1, FAT_SECTOR_BYTES - 1
    srli    t0, t0, FAT_SECTOR_SHIFT
    sd      t0, STREAM_LEFT(s0)
    sd      zero, STREAM_CRC(s0)
    sd      s1, STREAM_CRC_LEFT(s0)
    beqz    s1, 1f                      # an empty file: no chain to follow
    call    fat_walk_start
1:  mv      a0, s1
    ld      s1, 8(sp)
    ld      s0, 16(sp)
    ld      ra, 24(sp)
    addi    sp, sp, 32
    ret

    .globl fat32_stream_read
# fat32_stream_read
#   What: reads the next sectors of a stream's file (at most a2, fewer at the
#         file's end) to a1, one multi-block read per run of contiguous
#         clusters, checking the chain as fat32_read does (it must not end
#         before the file's size, and must end with the file's last sector).
#         With a3 = 1 the sectors extend the stream's CRC-32 (STREAM_CRC, over
#         the file's bytes only) while the next ones arrive. No other chain
#         may be followed between fat32_stream_open and the last read.
#   Arguments: a0 = stream record, a1 = destination (a2 * 512 bytes, any
#         alignment), a2 = most sectors to read, a3 = 1 to extend the CRC.
#   Results: a0 = sectors read (0 once the file is read).
#   Errors: 8 corrupt chain (out of range, bad cluster, loop, longer than
#         the volume, ending before or after the file's size).
#   Clobbers: only ABI temporaries.
fat32_stream_read:
    addi    sp, sp, -80
    sd      ra, 72(sp)
    sd      s0, 64(sp)
    sd      s1, 56(sp)
    sd      s2, 48(sp)
    sd      s3, 40(sp)
    sd      s4, 32(sp)
    sd      s5, 24(sp)
    sd      s6, 16(sp)
    sd      s7, 8(sp)
    mv      s0, a0                      # s0 = stream
    mv      s1, a1                      # s1 = destination
    ld      t0, STREAM_LEFT(s0)
    bleu    a2, t0, 1f
    mv      a2, t0
1:  mv      s2, a2                      # s2 = sectors still to read in this call
    mv      s7, a2                      # s7 = sectors this call reads
    li      s6, 0                       # s6 = hook
    beqz    a3, 2f
    la      s6, fat_crc_sector
2:  ld      t0, STREAM_PATH(s0)         # errors name this file
    la      t1, fat_path
    sd      t0, 0(t1)
    la      t0, fat_volume
    ld      t0, VOL_SPC_SHIFT(t0)
    li      s5, 1
    sll     s5, s5, t0                  # s5 = sectors per cluster

10: beqz    s2, 90f
    ld      t0, STREAM_SECTOR(s0)
    bne     t0, s5, 11f
    ld      a0, STREAM_CLUSTER(s0)      # this cluster is read: on to the next
    call    fat_walk_next
    beqz    a0, 80f
    sd      a0, STREAM_CLUSTER(s0)
    sd      zero, STREAM_SECTOR(s0)
11: ld      a0, STREAM_CLUSTER(s0)
    call    fat_cluster_lba
    ld      t0, STREAM_SECTOR(s0)
    add     s3, a0, t0                  # s3 = first block of the run
    sub     s4, s5, t0                  # s4 = sectors in the run
    bleu    s4, s2, 12f
    mv      s4, s2
12: add     t0, t0, s4
    sd      t0, STREAM_SECTOR(s0)
    # The run goes on while the next cluster is the one after this.
13: bgeu    s4, s2, 20f
    ld      a0, STREAM_CLUSTER(s0)
    call    fat_walk_next
    beqz    a0, 80f
    ld      t0, STREAM_CLUSTER(s0)
    sd      a0, STREAM_CLUSTER(s0)
    sd      zero, STREAM_SECTOR(s0)
    addi    t0, t0, 1
    bne     a0, t0, 20f                 # not contiguous: read what the run has
    sub     t1, s2, s4                  # take min(sectors per cluster, still wanted)
    bleu    t1, s5, 14f
    mv      t1, s5
14: add     s4, s4, t1
    sd      t1, STREAM_SECTOR(s0)
    j       13b

20: ld      t0, STREAM_LEFT(s0)
    sub     t0, t0, s4
    sd      t0, STREAM_LEFT(s0)
    bnez    t0, 21f
    # The file's last sector: its chain must end with this cluster (a loop
    # never ends; it would repeat data).
    ld      a0, STREAM_CLUSTER(s0)
    call    fat_chain_next
    beqz    a0, 21f
    la      a0, msg_chain_long
    call    fat_chain_error
21: mv      a0, s3
    mv      a1, s4
    mv      a2, s1
    mv      a3, s6
    mv      a4, s0
    call    sd_read_blocks
    slli    t0, s4, FAT_SECTOR_SHIFT
    add     s1, s1, t0
    sub     s2, s2, s4
    j       10b

80: la      a0, msg_chain_short
    call    fat_chain_error

90: mv      a0, s7
    ld      s7, 8(sp)
    ld      s6, 16(sp)
    ld      s5, 24(sp)
    ld      s4, 32(sp)
    ld      s3, 40(sp)
    ld      s2, 48(sp)
    ld      s1, 56(sp)
    ld      s0, 64(sp)
    ld      ra, 72(sp)
    addi    sp, sp, 80
    ret

# fat_crc_sector (file-local)
#   What: fat32_load's hook: extends the file's CRC-32 over one arrived
#         sector, counting only the bytes inside the file's size.
#   Arguments: a0 = sector in memory, a1 = context: CRC_CTX_CRC (CRC so
#         far), CRC_CTX_LEFT (file bytes not yet counted).
#   Results: none.
#   Clobbers: only ABI temporaries.
fat_crc_sector:
    ld      a2, CRC_CTX_LEFT(a1)
    beqz    a2, 2f
    li      t0, FAT_SECTOR_BYTES
    bleu    a2, t0, 1f
    mv      a2, t0                      # a2 = bytes of this sector in the file
1:  ld      t1, CRC_CTX_LEFT(a1)
    sub     t1, t1, a2
    sd      t1, CRC_CTX_LEFT(a1)
    addi    sp, sp, -16
    sd      ra, 8(sp)
    sd      a1, 0(sp)                   # the context
    mv      t0, a1
    mv      a1, a0
    ld      a0, CRC_CTX_CRC(t0)
    call    crc32_update                # (CRC so far, sector, bytes)
    ld      t0, 0(sp)
    sd      a0, CRC_CTX_CRC(t0)
    ld      ra, 8(sp)
    addi    sp, sp, 16
2:  ret

# fat_cluster_lba (file-local)
#   What: the card block where cluster a0 starts.
#   Arguments: a0 = cluster (>= 2).
#   Results: a0 = block number.
#   Clobbers: only ABI temporaries.
fat_cluster_lba:
    la      t0, fat_volume
    ld      t1, VOL_SPC_SHIFT(t0)
    ld      t2, VOL_DATA_LBA(t0)
    addi    a0, a0, -FAT_FIRST_CLUSTER
    sll     a0, a0, t1
    add     a0, a0, t2
    ret

# fat_check_cluster (file-local)
#   What: error 8 unless 2 <= a0 < cluster count + 2.
#   Arguments: a0 = cluster.
#   Results: none.
#   Clobbers: only ABI temporaries.
fat_check_cluster:
    li      t0, FAT_FIRST_CLUSTER
    bltu    a0, t0, 1f
    la      t1, fat_volume
    ld      t1, VOL_CLUSTERS(t1)
    add     t1, t1, t0
    bgeu    a0, t1, 1f
    ret
1:  la      a0, msg_chain_range
    j       fat_chain_error

# fat_chain_next (file-local)
#   What: the cluster after a0 in its chain, through the one-sector FAT
#         cache, checked: end-of-chain gives 0; the bad-cluster marker or a
#         number < 2 or >= cluster count + 2 is error 8.
#   Arguments: a0 = cluster (valid).
#   Results: a0 = next cluster, or 0 at the end of the chain.
#   Clobbers: only ABI temporaries.
fat_chain_next:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    sd      s0, 0(sp)
    mv      s0, a0
    la      t0, fat_volume
    srli    a0, s0, FAT_ENTRIES_PER_SECTOR_SHIFT
    ld      t1, VOL_FAT_LBA(t0)
    add     a0, a0, t1                  # a0 = FAT sector holding the entry
    ld      t1, VOL_CACHE_LBA(t0)
    beq     a0, t1, 1f
    sd      a0, VOL_CACHE_LBA(t0)
    li      a1, 1
    la      a2, fat_cache
    li      a3, 0
    call    sd_read_blocks
1:  andi    t0, s0, FAT_ENTRY_INDEX_MASK
    slli    t0, t0, FAT_ENTRY_SHIFT
    la      t1, fat_cache
    add     t0, t0, t1
    lwu     a0, 0(t0)
    li      t1, FAT_ENTRY_MASK
    and     a0, a0, t1
    li      t1, FAT_END_OF_CHAIN
    bltu    a0, t1, 2f
    li      a0, 0
    j       3f
2:  li      t1, FAT_BAD_CLUSTER
    bne     a0, t1, 21f
    la      a0, msg_chain_bad
    call    fat_chain_error
21: call    fat_check_cluster
3:  ld      s0, 0(sp)
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

# fat_walk_start (file-local)
#   What: starts following a cluster chain (a directory's or a file's) with
#         fat_walk_next: checks the first cluster, resets the loop detector.
#   Arguments: a0 = first cluster.
#   Results: none.
#   Errors: 8 if the cluster is out of range.
#   Clobbers: only ABI temporaries.
fat_walk_start:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    sd      a0, 0(sp)
    call    fat_check_cluster
    ld      a0, 0(sp)
    la      t0, fat_walk
    sd      a0, WALK_SAVED(t0)
    li      t1, 1
    sd      t1, WALK_POWER(t0)
    sd      zero, WALK_COUNT(t0)
    sd      t1, WALK_STEPS(t0)
    ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

# fat_walk_next (file-local)
#   What: the next cluster of the chain fat_walk_start began (see
#         fat_chain_next), with two guards: Brent's cycle detection (the
#         walk remembers one cluster, replaced after 1, 2, 4, 8 ... steps;
#         meeting it again means a loop, found within about twice the
#         chain's length before the loop plus the loop's length) and a
#         bound: a chain longer than the volume's cluster count.
#   Arguments: a0 = current cluster.
#   Results: a0 = next cluster, or 0 at the end of the chain.
#   Errors: 8 out of range, bad cluster, loop, longer than the volume.
#   Clobbers: only ABI temporaries.
fat_walk_next:
    addi    sp, sp, -16
    sd      ra, 8(sp)
    call    fat_chain_next
    beqz    a0, 2f
    la      t0, fat_walk
    ld      t1, WALK_SAVED(t0)
    bne     a0, t1, 1f
    la      a0, msg_chain_loop
    call    fat_chain_error
1:  ld      t1, WALK_STEPS(t0)
    addi    t1, t1, 1
    sd      t1, WALK_STEPS(t0)
    la      t2, fat_volume
    ld      t2, VOL_CLUSTERS(t2)
    bleu    t1, t2, 11f
    la      a0, msg_chain_volume
    call    fat_chain_error
11: ld      t1, WALK_COUNT(t0)
    addi    t1, t1, 1
    ld      t2, WALK_POWER(t0)
    bne     t1, t2, 12f
    sd      a0, WALK_SAVED(t0)          # a new cluster to watch for
    slli    t2, t2, 1
    sd      t2, WALK_POWER(t0)
    li      t1, 0
12: sd      t1, WALK_COUNT(t0)
2:  ld      ra, 8(sp)
    addi    sp, sp, 16
    ret

# fat_dir_check_length (file-local)
#   What: follows a directory's cluster chain through the FAT (fat_walk_*:
#         its range, loop and volume checks) before any of its entries is
#         read, and reports error 8 (fat_dir_error) when the chain is longer
#         than FAT_DIR_MAX_ENTRIES entries. Checking the chain rather than
#         counting entries as they are read gives the same answer wherever
#         the wanted entry lies, and costs one FAT sector per 128 clusters
#         instead of reading 2 MiB of entries before the error.
#   Arguments: a0 = the directory's first cluster.
#   Results: none.
#   Errors: 8 corrupt chain, or a directory longer than the limit.
#   Clobbers: only ABI temporaries.
fat_dir_check_length:
    addi    sp, sp, -32
    sd      ra, 24(sp)
    sd      s0, 16(sp)
    sd      s1, 8(sp)
    mv      s0, a0                      # s0 = cluster reached
    call    fat_walk_start
    la      t0, fat_volume
    ld      t0, VOL_SPC_SHIFT(t0)
    li      s1, FAT_DIR_MAX_SECTORS
    srl     s1, s1, t0                  # s1 = clusters the directory may have (>= 1)
1:  addi    s1, s1, -1                  # cluster s0 counted
    mv      a0, s0
    call    fat_walk_next
    beqz    a0, 2f
    mv      s0, a0
    bnez    s1, 1b
    call    fat_dir_error
2:  ld      s1, 8(sp)
    ld      s0, 16(sp)
    ld      ra, 24(sp)
    addi    sp, sp, 32
    ret

# fat_dir_error (file-local)
#   What: error 8, "corrupt directory: <folder> has more than 65536
#         entries", the folder being fat_path up to fat_dir_end without its
#         separators at either end ("/" for the root).
#   Arguments: none.
#   Results: never returns.
#   Clobbers: everything.
fat_dir_error:
    li      a0, ERR_BAD_CHAIN
    call    error_begin
    la      a0, msg_dir_corrupt
    call    console_puts
    la      t0, fat_path
    ld      s0, 0(t0)                   # s0 = folder's first character
    la      t0, fat_dir_end
    ld      s1, 0(t0)                   # s1 = its end
    li      t1, PATH_SEPARATOR
1:  bgeu    s0, s1, 2f
    lbu     t0, 0(s0)
    bne     t0, t1, 2f
    addi    s0, s0, 1
    j       1b
2:  bgeu    s0, s1, 3f
    lbu     t0, -1(s1)
    bne     t0, t1, 3f
    addi    s1, s1, -1
    j       2b
3:  li      a0, PATH_SEPARATOR
    call    console_putc
4:  bgeu    s0, s1, 5f
    lbu     a0, 0(s0)
    call    console_putc
    addi    s0, s0, 1
    j       4b
5:  la      a0, msg_dir_entries
    call    console_puts
    li      a0, FAT_DIR_MAX_ENTRIES
    call    console_put_dec
    la      a0, msg_dir_entries_tail
    call    console_puts
    j       error_end

# fat_chain_error (file-local)
#   What: error 8, "corrupt FAT chain: <path> (<reason>)".
#   Arguments: a0 = reason (string).
#   Results: never returns.
#   Clobbers: everything.
fat_chain_error:
    mv      s0, a0
    li      a0, ERR_BAD_CHAIN
    call    error_begin
    la      a0, msg_chain
    call    console_puts
    la      t0, fat_path
    ld      a0, 0(t0)
    call    console_puts
    la      a0, msg_chain_open
    call    console_puts
    mv      a0, s0
    call    console_puts
    la      a0, msg_chain_close
    call    console_puts
    j       error_end

# ---------------------------------------------------------------------------
    .bss
    .balign 64
# fat_sector: MBR, BPB and directory sectors as they are read.
fat_sector:
    .space  FAT_SECTOR_BYTES
# fat_cache: the FAT sector VOL_CACHE_LBA names.
fat_cache:
    .space  FAT_SECTOR_BYTES
    .balign 8
# fat_volume: the mounted volume's layout (VOL_* offsets).
fat_volume:
    .space  VOL_BYTES
# fat_path: the path being opened, for error reports.
fat_path:
    .space  8
# fat_dir_end: where in fat_path the folder being searched ends (the start
# of the component looked up in it), for error reports.
fat_dir_end:
    .space  8
# fat_walk: the chain being followed (WALK_* offsets).
fat_walk:
    .space  WALK_BYTES
    .balign 2
# lfn_buffer: the long name being collected, 13 UTF-16 units per entry.
lfn_buffer:
    .space  2 * LFN_BUFFER_UNITS
# fat_name16: the path component being looked up, as UTF-16 units.
fat_name16:
    .space  2 * LFN_BUFFER_UNITS
