# fat32.S: a read-only FAT32 volume on the SD card: its mount (the MBR's
# partition, the BPB's checks, the volume's layout); the file system's
# messages and state.
#
# Mount: the first MBR partition of type 0x0B or 0x0C, which must lie on
# the card (below sd_capacity, the CSD's capacity: a partition table that
# claims more than the card holds is checked here rather than left to a
# read the card refuses); its BPB must have 512 bytes per sector, a
# power-of-two cluster size, reserved sectors, 1 or 2 FATs, a FAT size, a
# root cluster >= 2 inside the volume, a total sector count that fits its
# partition and the card and leaves a data region, a FAT big enough for
# every cluster, and the 0x55AA signature. Anything else is error 5. Every
# block the fat32*.S files read is then inside the volume, so on the card.
#
# The file system's messages and variables (.rodata, .bss, below) live here
# for all the fat32*.S files, in the order the image has always had them
# (the Makefile's FW_ORDER keeps code and data where the cycle counts were
# measured); each says who uses it.
#
# The file system's files, in link order:
#   fat32.S          fat32_mount: the MBR's partition, the BPB; messages,
#                    state
#   fat32_lookup.S   files by path: fat32_lookup, fat32_open, fat32_load
#                    (a whole file into the heap), one directory's search
#   fat32_names.S    names: a path component against a long name or an 8.3
#                    name, the long name's checksum, UTF-8 to UTF-16
#   fat32_read.S     file reads: fat32_read, streams (fat32_stream_open,
#                    fat32_stream_read), the file's CRC-32 as it arrives
#   fat32_chain.S    cluster chains: the FAT through its one-sector cache,
#                    each chain checked as it is followed; the reports of
#                    a corrupt chain or directory

    .option norelax
    .include "k210.inc"
    .include "fat32.inc"
    .include "errors.inc"
    .include "frame.inc"

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


    .section .rodata
# Offsets of the 13 UTF-16 characters inside a long-name entry
# (fat32_lookup.S fat32_find collects them).
    .globl lfn_char_offsets
lfn_char_offsets:
    .byte   1, 3, 5, 7, 9, 14, 16, 18, 20, 22, 24, 28, 30
    .if (. - lfn_char_offsets) != LFN_CHARS
    .error "lfn_char_offsets needs LFN_CHARS entries"
    .endif

# The reports' words: the mount's, fat32_lookup.S's (not found, too large
# for the heap), fat32_chain.S's (a corrupt chain or directory; fat32_read.S
# names the chain's ends), then the mount's console line, in the order the
# image has them.
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
    .globl msg_not_found
msg_not_found:      .asciz "file not found: "
    .globl msg_chain
msg_chain:          .asciz "corrupt FAT chain: "
    .globl msg_chain_open
msg_chain_open:     .asciz " ("
    .globl msg_chain_close
msg_chain_close:    .asciz ")"
    .globl msg_chain_range
msg_chain_range:    .asciz "cluster out of range"
    .globl msg_chain_bad
msg_chain_bad:      .asciz "bad cluster"
    .globl msg_chain_loop
msg_chain_loop:     .asciz "loop"
    .globl msg_chain_volume
msg_chain_volume:   .asciz "chain longer than the volume"
    .globl msg_chain_short
msg_chain_short:    .asciz "chain ends before the file's size"
    .globl msg_chain_long
msg_chain_long:     .asciz "chain does not end at the file's size"
    .globl msg_dir_corrupt
msg_dir_corrupt:    .asciz "corrupt directory: "
    .globl msg_dir_entries
msg_dir_entries:    .asciz " has more than "
    .globl msg_dir_entries_tail
msg_dir_entries_tail: .asciz " entries"
    .globl msg_too_large
msg_too_large:      .asciz "file too large for memory: "
    .globl msg_too_large_size
msg_too_large_size: .asciz " ("
    .globl msg_too_large_sectors
msg_too_large_sectors: .asciz " bytes, "
    .globl msg_too_large_free
msg_too_large_free: .asciz " in whole sectors, "
    .globl msg_too_large_tail
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
    FRAME_SAVE 96, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10
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

    FRAME_RESTORE 96, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10
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

# ---------------------------------------------------------------------------
    .bss
    .balign 64
    .globl fat_sector
# fat_sector: MBR, BPB (fat32_mount) and directory sectors (fat32_lookup.S)
# as they are read.
fat_sector:
    .space  FAT_SECTOR_BYTES
    .globl fat_cache
# fat_cache: the FAT sector VOL_CACHE_LBA names (fat32_chain.S).
fat_cache:
    .space  FAT_SECTOR_BYTES
    .balign 8
    .globl fat_volume
# fat_volume: the mounted volume's layout (VOL_* offsets).
fat_volume:
    .space  VOL_BYTES
    .globl fat_path
# fat_path: the path being opened (fat32_lookup.S, fat32_read.S's streams),
# for error reports.
fat_path:
    .space  8
    .globl fat_dir_end
# fat_dir_end: where in fat_path the folder being searched ends (the start
# of the component looked up in it), for error reports (fat32_lookup.S sets
# it, fat32_chain.S fat_dir_error names the folder).
fat_dir_end:
    .space  8
    .globl fat_walk
# fat_walk: the chain being followed (WALK_* offsets, fat32_chain.S).
fat_walk:
    .space  WALK_BYTES
    .balign 2
    .globl lfn_buffer
# lfn_buffer: the long name being collected, 13 UTF-16 units per entry
# (fat32_lookup.S fat32_find; fat32_names.S compares it).
lfn_buffer:
    .space  2 * LFN_BUFFER_UNITS
    .globl fat_name16
# fat_name16: the path component being looked up, as UTF-16 units
# (fat32_names.S).
fat_name16:
    .space  2 * LFN_BUFFER_UNITS
