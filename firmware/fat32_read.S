# fat32_read.S: reading a file's sectors. A file's contiguous clusters are
# read with one multi-block command each (sd_read_blocks), only the sectors
# the file's size needs; the file's CRC-32 is computed sector by sector while
# the next sector arrives (fat_crc_sector, sd_read_blocks' hook). A file is
# read whole (fat32_read; fat32_lookup.S fat32_load puts it in the heap) or
# a few sectors at a time into the reader's buffer (fat32_stream_open,
# fat32_stream_read: obj.S reads the model so, without keeping its text).
# Each chain is followed and checked by fat32_chain.S.

    .option norelax
    .include "k210.inc"
    .include "fat32.inc"
    .include "errors.inc"
    .include "frame.inc"

    .text
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
    FRAME_SAVE 96, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9
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

8:  FRAME_RESTORE 96, ra, s0, s1, s2, s3, s4, s5, s6, s7, s8, s9
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
    FRAME_SAVE 32, ra, s0, s1
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
    FRAME_RESTORE 32, ra, s0, s1
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
    FRAME_SAVE 80, ra, s0, s1, s2, s3, s4, s5, s6, s7
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
    FRAME_RESTORE 80, ra, s0, s1, s2, s3, s4, s5, s6, s7
    ret

    .globl fat_crc_sector
# fat_crc_sector
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
    FRAME_SAVE 16, ra
    sd      a1, 0(sp)                   # the context
    mv      t0, a1
    mv      a1, a0
    ld      a0, CRC_CTX_CRC(t0)
    call    crc32_update                # (CRC so far, sector, bytes)
    ld      t0, 0(sp)
    sd      a0, CRC_CTX_CRC(t0)
    FRAME_RESTORE 16, ra
2:  ret

