"""What the board needs to know of an instruction word without executing it: the memory access a
load, store or AMO makes (the bus reports a faulting access by it; the poll-loop finder reads
what a loop loads; the hardware breakpoint matches its address) and whether it reads or writes."""
from __future__ import annotations

from .riscv import bits, signed


def decode_memory_access(word: int) -> tuple[int, int, int] | None:
    """(bytes moved, base register, offset) of an RV64GC load/store/AMO, or None."""
    if word & 3 != 3:                         # compressed
        op, funct3 = word & 3, bits(word, 15, 13)
        if op == 0 and funct3 in (1, 2, 3, 5, 6, 7):          # c.fld c.lw c.ld c.fsd c.sw c.sd
            rs1 = 8 + bits(word, 9, 7)
            if funct3 in (2, 6):
                imm = bits(word, 12, 10) << 3 | bits(word, 6, 6) << 2 | bits(word, 5, 5) << 6
                return 4, rs1, imm
            return 8, rs1, bits(word, 12, 10) << 3 | bits(word, 6, 5) << 6
        if op == 2 and funct3 in (1, 2, 3):                    # c.fldsp c.lwsp c.ldsp
            if funct3 == 2:
                return 4, 2, bits(word, 12, 12) << 5 | bits(word, 6, 4) << 2 | bits(word, 3, 2) << 6
            return 8, 2, bits(word, 12, 12) << 5 | bits(word, 6, 5) << 3 | bits(word, 4, 2) << 6
        if op == 2 and funct3 in (5, 6, 7):                    # c.fsdsp c.swsp c.sdsp
            if funct3 == 6:
                return 4, 2, bits(word, 12, 9) << 2 | bits(word, 8, 7) << 6
            return 8, 2, bits(word, 12, 10) << 3 | bits(word, 9, 7) << 6
        return None
    opcode, funct3, rs1 = word & 0x7F, bits(word, 14, 12), bits(word, 19, 15)
    if opcode in (0x03, 0x07):                                 # loads
        return 1 << (funct3 & 3), rs1, signed(word >> 20, 12)
    if opcode in (0x23, 0x27):                                 # stores
        return 1 << (funct3 & 3), rs1, signed(bits(word, 31, 25) << 5 | bits(word, 11, 7), 12)
    if opcode == 0x2F:                                         # AMOs and LR/SC
        return (8 if funct3 == 3 else 4), rs1, 0
    return None


READS, WRITES = 1, 2


def memory_access_kind(word: int) -> int:
    """READS, WRITES or both for a load, store or AMO, else 0: as Rocket's isRead and isWrite see
    them (rocket-chip uncore/Consts.scala: isRead covers M_XSC and the AMOs, isWrite M_XSC and the
    AMOs)."""
    if word & 3 != 3:
        op, funct3 = word & 3, bits(word, 15, 13)
        if op in (0, 2) and funct3 in (1, 2, 3):
            return READS                                # c.fld c.lw c.ld, c.fldsp c.lwsp c.ldsp
        if op in (0, 2) and funct3 in (5, 6, 7):
            return WRITES                               # c.fsd c.sw c.sd, c.fsdsp c.swsp c.sdsp
        return 0
    opcode = word & 0x7F
    if opcode in (0x03, 0x07):
        return READS
    if opcode in (0x23, 0x27):
        return WRITES
    if opcode == 0x2F:
        return READS if word >> 27 == 0b00010 else READS | WRITES   # LR reads; SC and the AMOs both
    return 0
