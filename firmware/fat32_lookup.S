# fat32_lookup.S: finding a file by its path, and fat32_load, which reads a
# file found so whole into the heap (fat32_read.S).
#
# Paths are '/'-separated, relative to the root (leading '/' allowed). In
# each directory (any cluster chain) an entry matches by its long name when
# it has a valid one: long-name entries in sequence (first stored entry
# carries 0x40 | n, then n - 1 .. 1, each with the checksum of the short
# entry that follows them, which is verified), compared with the path
# component decoded from UTF-8 to UTF-16, ASCII letters case-folded and
# every other character exact (fat32_names.S). An entry without a valid long
# name matches by its 8.3 name, case-insensitively. Deleted entries and
# volume labels are skipped; a 0x00 name ends the directory. Not found is
# error 6. A directory's chain may hold at most FAT_DIR_MAX_ENTRIES entries
# (the FAT limit, 2 MiB): it is measured on the FAT before the search
# (fat32_chain.S), and a longer one is error 8, "corrupt directory:
# <folder> has more than 65536 entries", so no search reads more than 2 MiB
# (a chain of deleted entries could otherwise fill the volume and take
# longer than any boot should).

    .option norelax
    .include "k210.inc"
    .include "fat32.inc"
    .include "errors.inc"
    .include "frame.inc"

    .text
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
    FRAME_SAVE 64, ra, s0, s1, s2, s3
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
    FRAME_RESTORE 64, ra, s0, s1, s2, s3
    ret

    .globl fat32_open
# fat32_open
#   What: fat32_lookup, with "not found" a fatal error.
#   Arguments: a0 = path (NUL-terminated).
#   Results: a0 = the file's first cluster (0 for an empty file), a1 = size.
#   Errors: 6 not found, 8 corrupt chain or directory.
#   Clobbers: only ABI temporaries.
fat32_open:
    FRAME_SAVE 16, ra
    call    fat32_lookup
    beqz    a2, 1f
    FRAME_RESTORE 16, ra
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
    FRAME_SAVE 48, ra, s0, s1, s2, s3
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
10: FRAME_RESTORE 48, ra, s0, s1, s2, s3
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
    FRAME_SAVE 112, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11
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
31: FRAME_RESTORE 112, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11
    ret

