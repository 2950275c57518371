"""RISC-V names and numbers the model speaks in, in one place: register names (the psABI's), the
CSRs the board carries out or shows, trap causes and their names, interrupt numbers, privilege
levels, the few whole-instruction encodings the harts look for, and the field helpers every decoder
here uses (the privileged and unprivileged specifications, version 20191213 / 1.11)."""
from __future__ import annotations

import numpy as np

# Integer and floating-point registers by ABI name (RISC-V psABI, "Integer Register Convention")
GPR_NAMES = ("zero", "ra", "sp", "gp", "tp", "t0", "t1", "t2", "s0", "s1", "a0", "a1", "a2", "a3", "a4", "a5",
             "a6", "a7", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "t3", "t4", "t5", "t6")
FPR_NAMES = ("ft0", "ft1", "ft2", "ft3", "ft4", "ft5", "ft6", "ft7", "fs0", "fs1", "fa0", "fa1", "fa2", "fa3",
             "fa4", "fa5", "fa6", "fa7", "fs2", "fs3", "fs4", "fs5", "fs6", "fs7", "fs8", "fs9", "fs10", "fs11",
             "ft8", "ft9", "ft10", "ft11")

# CSR numbers
CSR_FFLAGS, CSR_FRM, CSR_FCSR = 0x001, 0x002, 0x003
CSR_SSTATUS, CSR_SIE, CSR_STVEC, CSR_SIP = 0x100, 0x104, 0x105, 0x144
CSR_MEDELEG, CSR_MIDELEG = 0x302, 0x303
CSR_SPTBR = 0x180                                     # 1.9.1's name; satp in 1.10
CSR_MUCOUNTEREN, CSR_MSCOUNTEREN = 0x320, 0x321       # 1.9.1's counter enables
CSR_MSTATUS, CSR_MISA, CSR_MIE, CSR_MTVEC = 0x300, 0x301, 0x304, 0x305
CSR_MSCRATCH, CSR_MEPC, CSR_MCAUSE, CSR_MTVAL, CSR_MIP = 0x340, 0x341, 0x342, 0x343, 0x344
CSR_MCYCLE, CSR_MINSTRET = 0xB00, 0xB02
CSR_CYCLE, CSR_INSTRET = 0xC00, 0xC02
CSR_MHARTID = 0xF14

MSTATUS_SIE = 1 << 1
MSTATUS_MIE = 1 << 3
MSTATUS_SPIE = 1 << 5
MSTATUS_MPIE = 1 << 7
MSTATUS_SPP = 1 << 8
MSTATUS_MPP = 3 << 11

# mcause
CAUSE_INTERRUPT = 1 << 63
CAUSE_FETCH_FAULT = 1
CAUSE_ILLEGAL_INSTRUCTION = 2
CAUSE_BREAKPOINT = 3
CAUSE_LOAD_MISALIGNED, CAUSE_STORE_MISALIGNED = 4, 6
CAUSE_LOAD_FAULT, CAUSE_STORE_FAULT = 5, 7
CAUSE_ECALL_U, CAUSE_ECALL_S, CAUSE_ECALL_M = 8, 9, 11
ECALL_CAUSES = (CAUSE_ECALL_U, CAUSE_ECALL_S, CAUSE_ECALL_M)
EXCEPTION_NAMES = {
    0: "instruction address misaligned", 1: "instruction access fault",
    2: "illegal instruction", 3: "breakpoint", 4: "load address misaligned",
    5: "load access fault", 6: "store address misaligned", 7: "store access fault",
    8: "environment call from U-mode", 9: "environment call from S-mode",
    11: "environment call from M-mode",
}

# interrupts (mip/mie bits, and mcause's code with CAUSE_INTERRUPT); of those pending and takeable
# the K210's Rocket takes the lowest-numbered first (privileged.py)
IRQ_SSI, IRQ_MSI, IRQ_STI, IRQ_MTI, IRQ_SEI, IRQ_MEI = 1, 3, 5, 7, 9, 11

PRIV_U, PRIV_S, PRIV_M = 0, 1, 3

INSN_WFI = 0x10500073
INSN_MRET = 0x30200073
INSN_SRET = 0x10200073
# sfence.vm rs1 of privileged spec 1.9.1 (1.10 replaced it with sfence.vma): match and mask
INSN_SFENCE_VM, MASK_SFENCE_VM = 0x10400073, 0xFFF07FFF
# sfence.vma rs1, rs2 of 1.10, which the K210 (1.9.1) does not have
INSN_SFENCE_VMA, MASK_SFENCE_VMA = 0x12000073, 0xFE007FFF


def bits(word: int, high: int, low: int) -> int:
    """The field word[high:low], as the specifications write instruction fields."""
    return (word >> low) & ((1 << (high - low + 1)) - 1)


def signed(value: int, width: int) -> int:
    """A `width`-bit field read as two's complement (an immediate's sign extension)."""
    return value - (1 << width) if value >> (width - 1) & 1 else value


def instruction_at(code: bytes, offset: int) -> tuple[int, int] | None:
    """(word, length in bytes) of the instruction at code[offset]: 2 for a compressed one (its low
    bits are not 11), else 4; None where the code ends first."""
    if offset + 2 > len(code):
        return None
    low = int.from_bytes(code[offset:offset + 2], "little")
    if low & 3 != 3:
        return low, 2
    if offset + 4 > len(code):
        return None
    return int.from_bytes(code[offset:offset + 4], "little"), 4


def code_parcels(code: bytes) -> tuple[np.ndarray, np.ndarray]:
    """For the scans of whole code (every 2-byte-aligned position tried as an instruction's start):
    the 16-bit parcel at each position, and the 32-bit word that begins there at every position but
    the last (the parcel and the next), as uint32 arrays (little-endian code)."""
    halves = np.frombuffer(code[:len(code) & ~1], dtype="<u2").astype(np.uint32)
    return halves, halves[:-1] | halves[1:] << 16
