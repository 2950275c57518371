# fat32_chain.S: following cluster chains. FAT entries are read through a
# one-sector cache (fat32.S fat_cache). Chains are checked as they are
# followed: an entry < 2 or >= cluster count + 2, the bad-cluster marker, a
# chain longer than the volume's cluster count, a loop (Brent's cycle
# detection: found long before that bound), or a file chain that ends
# before or goes on after the file's size (a loop never ends; fat32_read.S
# checks the ends) is error 8. A directory's chain is measured before it is
# searched (fat_dir_check_length). The reports of a corrupt chain or
# directory are here too.

    .option norelax
    .include "k210.inc"
    .include "fat32.inc"
    .include "errors.inc"
    .include "frame.inc"

    .text
    .globl fat_cluster_lba
# fat_cluster_lba
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

    .globl fat_chain_next
# fat_chain_next
#   What: the cluster after a0 in its chain, through the one-sector FAT
#         cache, checked: end-of-chain gives 0; the bad-cluster marker or a
#         number < 2 or >= cluster count + 2 is error 8.
#   Arguments: a0 = cluster (valid).
#   Results: a0 = next cluster, or 0 at the end of the chain.
#   Clobbers: only ABI temporaries.
fat_chain_next:
    FRAME_SAVE 16, ra, s0
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
3:  FRAME_RESTORE 16, ra, s0
    ret

    .globl fat_walk_start
# fat_walk_start
#   What: starts following a cluster chain (a directory's or a file's) with
#         fat_walk_next: checks the first cluster, resets the loop detector.
#   Arguments: a0 = first cluster.
#   Results: none.
#   Errors: 8 if the cluster is out of range.
#   Clobbers: only ABI temporaries.
fat_walk_start:
    FRAME_SAVE 16, ra
    sd      a0, 0(sp)
    call    fat_check_cluster
    ld      a0, 0(sp)
    la      t0, fat_walk
    sd      a0, WALK_SAVED(t0)
    li      t1, 1
    sd      t1, WALK_POWER(t0)
    sd      zero, WALK_COUNT(t0)
    sd      t1, WALK_STEPS(t0)
    FRAME_RESTORE 16, ra
    ret

    .globl fat_walk_next
# fat_walk_next
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
    FRAME_SAVE 16, ra
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
2:  FRAME_RESTORE 16, ra
    ret

    .globl fat_dir_check_length
# fat_dir_check_length
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
    FRAME_SAVE 32, ra, s0, s1
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
2:  FRAME_RESTORE 32, ra, s0, s1
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

    .globl fat_chain_error
# fat_chain_error
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

