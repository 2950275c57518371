"""The privileged architecture of the K210's harts, where the model carries it out instead of
Unicorn: the CSRs the board answers, trap entry and return, delegation to S-mode, and which
interrupts a hart would take. The K210 implements privileged spec 1.9.1, so its Rocket predates
rocket-chip's merge of 1.10 (2017-03-14); "Rocket" below is rocket-chip commit 1322a026
(rocket/CSR.scala), the last before it. Unicorn follows 1.11, so every place they differ is here:

- a trap saves the interrupt enable of the mode it came from (`pie = read_mstatus(prv)`: UIE, always
  0, from U-mode; SIE from S; MIE from M) in MPIE or SPIE, and writes mbadaddr (mtval) only for
  breakpoints, misaligned accesses and access faults (`write_badaddr`); an illegal instruction or an
  ecall leaves it as it was;
- mret sets MIE from MPIE only when returning to M-mode, SIE when returning to S-mode; sret sets
  SIE from SPIE only when returning to S-mode;
- a trap from below M-mode whose bit is set in medeleg (exceptions) or mideleg (interrupts) enters
  S-mode at stvec, with sepc, scause, sbadaddr; mideleg takes only SSIP, STIP and SEIP;
- interrupts: M-level ones (not delegated) are taken below M-mode or with MIE set, delegated ones
  below S-mode or in S-mode with SIE set; of those pending, the lowest-numbered is taken first
  (`PriorityEncoder`): SSI 1, MSI 3, STI 5, MTI 7, SEI 9, MEI 11;
- mip's SSIP and STIP are written by software (sip's SSIP too); mie takes the six supported bits;
- mtvec and stvec keep their two low bits at zero (no vectored mode);
- `sfence.vm` is 1.9.1's (a no-op here: paging, `mstatus.VM`, is not modelled and stops the run);
  1.10's `sfence.vma` is an illegal instruction.

Hart (hart.py) inherits these methods; they use its Unicorn instance and state (uc, privilege,
pending_exception, the counters' offsets, the trigger unit), and importing nothing of it."""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import unicorn
from unicorn import riscv_const as rv

from .decode import decode_memory_access
from .riscv import (CAUSE_BREAKPOINT, CAUSE_FETCH_FAULT, CAUSE_ILLEGAL_INSTRUCTION, CAUSE_INTERRUPT,
                    CAUSE_LOAD_FAULT, CAUSE_LOAD_MISALIGNED, CAUSE_STORE_FAULT, CAUSE_STORE_MISALIGNED,
                    CSR_CYCLE, CSR_INSTRET, CSR_MCYCLE, CSR_MEDELEG, CSR_MHARTID, CSR_MIDELEG, CSR_MIE,
                    CSR_MINSTRET, CSR_MIP, CSR_MSCOUNTEREN, CSR_MSTATUS, CSR_MTVEC, CSR_MUCOUNTEREN, CSR_SIE,
                    CSR_SIP, CSR_SPTBR, CSR_SSTATUS, CSR_STVEC,
                    INSN_MRET, INSN_SFENCE_VM, INSN_SFENCE_VMA, INSN_SRET, MASK_SFENCE_VM, MASK_SFENCE_VMA, MSTATUS_MIE, MSTATUS_MPIE,
                    MSTATUS_MPP, MSTATUS_SIE, MSTATUS_SPIE, MSTATUS_SPP, PRIV_M, PRIV_S, PRIV_U, code_parcels)
from .triggers import TRIGGER_CSRS
from ..errors import UnmodelledAccess

@dataclass
class PendingException:
    """A synchronous exception an instruction raised, waiting for the board to take it."""
    cause: int
    epc: int
    tval: int

# mstatus and mie are real Unicorn CSRs; they are intercepted so that a write that may unmask a
# pending interrupt ends the hart's turn, and the interrupt is taken right there
INTERRUPT_ENABLE_CSRS = {CSR_MSTATUS: rv.UC_RISCV_REG_MSTATUS, CSR_MIE: rv.UC_RISCV_REG_MIE}
INTERCEPTED_CSRS = {CSR_MHARTID, CSR_MCYCLE, CSR_MINSTRET, CSR_CYCLE, CSR_INSTRET, CSR_MIP, CSR_MTVEC,
                    CSR_MIDELEG, CSR_MEDELEG, CSR_SSTATUS, CSR_SIE, CSR_SIP, CSR_STVEC, CSR_SPTBR,
                    CSR_MUCOUNTEREN, CSR_MSCOUNTEREN,
                    *INTERRUPT_ENABLE_CSRS, *TRIGGER_CSRS}
READ_ONLY_CSRS = {CSR_MHARTID, CSR_CYCLE, CSR_INSTRET}
# mstatus.VM (bits 28:24) of 1.9.1: 0 (bare) or 9 (Sv39) are taken, others ignored; the model has no
# paging, so 9 stops the run
MSTATUS_VM_1_9_1, VM_SV39 = 0x1F00_0000, 9
# what a write to mstatus changes (Rocket: SIE, MIE, SPIE, MPIE, SPP, MPP, FS, MPRV, PUM, MXR; SD
# follows FS, and the rest reads 0); FS written non-zero reads 3 (`Fill(2, fs.orR)`); MPP keeps even
# 2 (`trimPrivilege` with VM: an mret then restores MIE and enters U-mode)
MSTATUS_WRITABLE = 0x000E_79AA
MSTATUS_FS = 3 << 13
MSTATUS_RESET = MSTATUS_MPP        # Rocket's `reset_mstatus.mpp := PRV.M`, the rest 0
# sstatus's view of mstatus (1.9.1: SD, MXR, PUM, XS, FS, SPP, SPIE, SIE) and what a write changes
# (SIE, SPIE, SPP, PUM, FS)
SSTATUS_READ = 0x8000_0000_000D_E122
SSTATUS_WRITABLE = 0x0000_0000_0004_6122
SUPPORTED_INTERRUPTS = 0xAAA                  # SSIP, MSIP, STIP, MTIP, SEIP, MEIP
DELEGABLE_INTERRUPTS = 0x222                  # SSIP, STIP, SEIP
SOFTWARE_PENDING = 0x22                       # mip.SSIP and mip.STIP: written by software
SIP_WRITABLE = 0x2                            # sip.SSIP
# Rocket's delegable exceptions: misaligned and faulting fetches, breakpoints, load and store
# faults, U-mode ecalls (not misaligned loads and stores, nor illegal instructions)
DELEGABLE_EXCEPTIONS = (1 << 0) | (1 << 1) | (1 << 3) | (1 << 5) | (1 << 7) | (1 << 8)
# 1.9.1's counter enables: which of cycle (bit 0) and instret (bit 2) U-mode (mucounteren) and
# S-mode (mscounteren) may read (Rocket's delegable_counters with no performance counters; time is
# not implemented). Rocket gives them no reset value: chosen both enabled, as the model always let
# the counters through
COUNTER_BITS = 0b101
# sptbr keeps the root page number only (`reg_sptbr.ppn := wdata(ppnBits-1,0)`: 32-bit physical
# addresses, 4 KiB pages), so Unicorn's satp never selects a paging mode
SPTBR_PPN = (1 << 20) - 1
WRITES_BADADDR = {CAUSE_BREAKPOINT, 0, CAUSE_LOAD_MISALIGNED, CAUSE_STORE_MISALIGNED, CAUSE_FETCH_FAULT,
                  CAUSE_LOAD_FAULT, CAUSE_STORE_FAULT}


def legal_mstatus(value: int) -> int:
    """The mstatus a write of `value` leaves (MSTATUS_WRITABLE's rules)."""
    value &= MSTATUS_WRITABLE
    if value & MSTATUS_FS:
        value |= MSTATUS_FS
    return value


def lowest_interrupt(pending: int) -> int | None:
    """The interrupt Rocket takes of those pending: the lowest-numbered."""
    return (pending & -pending).bit_length() - 1 if pending else None


class PrivilegedArchitecture:
    """Trap entry and return, the CSRs the board answers and the interrupt rules, for Hart."""

    # --- which interrupts would be taken --------------------------------------------------------

    def takeable_interrupts(self) -> int:
        """The mie bits of the interrupts the hart would take now if pending: those not delegated
        while below M-mode or MIE is set, the delegated ones while below S-mode or SIE is set."""
        mstatus = self.reg(rv.UC_RISCV_REG_MSTATUS)
        mie = self.reg(rv.UC_RISCV_REG_MIE)
        mideleg = self.reg(rv.UC_RISCV_REG_MIDELEG)
        takeable = 0
        if self.privilege < PRIV_M or mstatus & MSTATUS_MIE:
            takeable |= mie & ~mideleg
        if self.privilege < PRIV_S or (self.privilege == PRIV_S and mstatus & MSTATUS_SIE):
            takeable |= mie & mideleg
        return takeable

    def interrupts_enabled(self) -> bool:
        """Whether some enabled interrupt would be taken now if it were pending."""
        return bool(self.takeable_interrupts())

    # --- trap entry and return ------------------------------------------------------------------

    def delegated(self, cause: int) -> bool:
        """Whether a trap of `cause` taken now goes to S-mode (medeleg or mideleg, from below M)."""
        if self.privilege == PRIV_M:
            return False
        register = rv.UC_RISCV_REG_MIDELEG if cause & CAUSE_INTERRUPT else rv.UC_RISCV_REG_MEDELEG
        return bool(self.reg(register) >> (cause & 0x3F) & 1)

    def trap_vector(self, cause: int) -> tuple[str, int]:
        """(name, value) of the vector register a trap of `cause` taken now enters at."""
        if self.delegated(cause):
            return "stvec", self.reg(rv.UC_RISCV_REG_STVEC)
        return "mtvec", self.reg(rv.UC_RISCV_REG_MTVEC)

    def enter_trap(self, cause: int, epc: int, tval: int) -> None:
        """Takes a trap as Rocket does (the module's notes): into S-mode when delegated, else
        M-mode, at the vector's base."""
        self.forget_pending_transfer()
        uc = self.uc
        privilege = self.privilege
        if privilege != PRIV_M:
            uc.reg_write(rv.UC_RISCV_REG_PRIV, PRIV_M)     # the CSRs are written as M-mode
        mstatus = uc.reg_read(rv.UC_RISCV_REG_MSTATUS)
        pie = (mstatus >> privilege) & 1
        interrupt = bool(cause & CAUSE_INTERRUPT)
        code = cause & 0x3F
        delegation = uc.reg_read(rv.UC_RISCV_REG_MIDELEG if interrupt else rv.UC_RISCV_REG_MEDELEG)
        writes_badaddr = not interrupt and code in WRITES_BADADDR
        if privilege < PRIV_M and delegation >> code & 1:
            uc.reg_write(rv.UC_RISCV_REG_SEPC, epc)
            uc.reg_write(rv.UC_RISCV_REG_SCAUSE, cause)
            if writes_badaddr:
                uc.reg_write(rv.UC_RISCV_REG_SBADADDR, tval)
            mstatus = (mstatus & ~(MSTATUS_SIE | MSTATUS_SPIE | MSTATUS_SPP)) | (pie << 5) | ((privilege & 1) << 8)
            uc.reg_write(rv.UC_RISCV_REG_MSTATUS, mstatus)
            self.pc = uc.reg_read(rv.UC_RISCV_REG_STVEC) & ~3
            new_privilege = PRIV_S
        else:
            uc.reg_write(rv.UC_RISCV_REG_MEPC, epc)
            uc.reg_write(rv.UC_RISCV_REG_MCAUSE, cause)
            if writes_badaddr:
                uc.reg_write(rv.UC_RISCV_REG_MTVAL, tval)
            mstatus = (mstatus & ~(MSTATUS_MIE | MSTATUS_MPIE | MSTATUS_MPP)) | (pie << 7) | (privilege << 11)
            uc.reg_write(rv.UC_RISCV_REG_MSTATUS, mstatus)
            self.pc = uc.reg_read(rv.UC_RISCV_REG_MTVEC) & ~3
            new_privilege = PRIV_M
        self._set_privilege(new_privilege)
        self.wake()

    def _set_privilege(self, privilege: int) -> None:
        self.uc.reg_write(rv.UC_RISCV_REG_PRIV, privilege)
        self.privilege = privilege

    def _carry_out_mret(self) -> int:
        """mret: MIE = MPIE when MPP's high bit is set (M, or the H that MPP can hold), SIE = MPIE when
        MPP is S; MPIE = 1, MPP = U; to mode MPP (H becomes U) at mepc. Carried out here so that the
        board knows the trap handler has returned (open_trap)."""
        uc = self.uc
        mstatus = uc.reg_read(rv.UC_RISCV_REG_MSTATUS)
        mpp = (mstatus & MSTATUS_MPP) >> 11
        mpie = 1 if mstatus & MSTATUS_MPIE else 0
        if mpp & 2:
            mstatus = (mstatus & ~MSTATUS_MIE) | (mpie << 3)
        elif mpp == PRIV_S:
            mstatus = (mstatus & ~MSTATUS_SIE) | (mpie << 1)
        mstatus = (mstatus & ~MSTATUS_MPP) | MSTATUS_MPIE | (PRIV_U << 11)
        self._write_status(rv.UC_RISCV_REG_MSTATUS, mstatus)    # may unmask a pending interrupt
        pc = uc.reg_read(rv.UC_RISCV_REG_MEPC) & ~1
        self._return_to(PRIV_U if mpp == 2 else mpp)
        return pc

    def _carry_out_sret(self, address: int, word: int) -> int:
        """sret (S-mode and above): to mode SPP at sepc; SIE = SPIE when that mode is S; SPIE = 1,
        SPP = U."""
        if self.privilege < PRIV_S:
            return self._illegal(address, word)
        uc = self.uc
        mstatus = uc.reg_read(rv.UC_RISCV_REG_MSTATUS)
        privilege = PRIV_S if mstatus & MSTATUS_SPP else PRIV_U
        if privilege == PRIV_S:
            mstatus = (mstatus & ~MSTATUS_SIE) | (MSTATUS_SIE if mstatus & MSTATUS_SPIE else 0)
        mstatus = (mstatus & ~MSTATUS_SPP) | MSTATUS_SPIE
        self._write_status(rv.UC_RISCV_REG_MSTATUS, mstatus)
        pc = uc.reg_read(rv.UC_RISCV_REG_SEPC) & ~1
        self._return_to(privilege)
        return pc

    def _return_to(self, privilege: int) -> None:
        """After mret or sret: the hart in `privilege`, its trap handled. Interrupts of a higher
        level are enabled whatever the enable bits below it, so a lower mode ends the turn: a
        pending one is taken before the first instruction there."""
        if privilege < self.privilege:
            self.request_stop()
        self._set_privilege(privilege)
        self.open_trap = None

    def _illegal(self, address: int, word: int) -> int:
        """The instruction `word` at `address` (counted, not retired) raises an illegal-instruction
        exception; returns the pc the hart stays at."""
        self.pending_exception = PendingException(CAUSE_ILLEGAL_INSTRUCTION, address, word)
        self.retired_adjust += 1
        return address

    # --- the CSRs the board answers ---------------------------------------------------------------

    def _carry_out_csr(self, address: int, word: int) -> int:
        """Executes the CSR instruction, mret, sret, sfence.vm or sfence.vma `word` at `address` (already
        counted); returns the pc the hart goes on from: the next instruction, or the site itself
        when it traps. Unicorn gives its CSRs only to M-mode, so it runs as M-mode meanwhile."""
        if self.privilege == PRIV_M:
            return self._carry_out(address, word)
        self.uc.reg_write(rv.UC_RISCV_REG_PRIV, PRIV_M)
        try:
            return self._carry_out(address, word)
        finally:
            self.uc.reg_write(rv.UC_RISCV_REG_PRIV, self.privilege)

    def _carry_out(self, address: int, word: int) -> int:
        if word == INSN_MRET:
            if self.privilege != PRIV_M:
                return self._illegal(address, word)
            return self._carry_out_mret()
        if word == INSN_SRET:
            return self._carry_out_sret(address, word)
        if word & MASK_SFENCE_VM == INSN_SFENCE_VM:
            # 1.9.1's TLB flush, legal in S- and M-mode; without paging there is nothing to flush
            return self._illegal(address, word) if self.privilege == PRIV_U else address + 4
        if word & MASK_SFENCE_VMA == INSN_SFENCE_VMA:
            return self._illegal(address, word)      # 1.10's, which Unicorn would carry out
        csr = word >> 20
        loop = self.time_loops.get(address)
        if loop is not None and not self.triggers.armed:      # skipped iterations would not be watched
            self.skipper.at_time_read(loop, lambda: self._csr_value(csr),
                                      lambda r: self.reg(rv.UC_RISCV_REG_X0 + r), self._turn_limit,
                                      self.time_skip_limit)
        if self.privilege < (csr >> 8) & 3:
            # a CSR of a more privileged mode (bits 9:8 of its number): an illegal instruction
            return self._illegal(address, word)
        if csr in (CSR_CYCLE, CSR_INSTRET) and self.privilege < PRIV_M:
            enables = self.counter_enables[self.privilege]
            if not enables >> (csr & 0x1F) & 1:
                return self._illegal(address, word)
        rd = (word >> 7) & 31
        rs1 = (word >> 15) & 31
        funct3 = (word >> 12) & 7
        operand = rs1 if funct3 & 4 else (self.reg(rv.UC_RISCV_REG_X0 + rs1) if rs1 else 0)
        writes = (funct3 & 3) == 1 or rs1 != 0
        if writes and csr in READ_ONLY_CSRS:
            return self._illegal(address, word)     # a write to a read-only CSR, as on the real hart
        old = self._csr_value(csr)
        if writes:
            op = funct3 & 3
            new = operand if op == 1 else (old | operand if op == 2 else old & ~operand)
            self._csr_write(csr, new & (2**64 - 1))
        if rd:
            self.uc.reg_write(rv.UC_RISCV_REG_X0 + rd, old)
        return address + 4

    def _csr_value(self, csr: int) -> int:
        uc = self.uc
        if csr in INTERRUPT_ENABLE_CSRS:
            return uc.reg_read(INTERRUPT_ENABLE_CSRS[csr])
        if csr == CSR_MHARTID:
            return self.hart_id
        if csr in (CSR_MTVEC, CSR_STVEC, CSR_MIDELEG, CSR_MEDELEG):
            return uc.reg_read(_UNICORN_CSR[csr])
        if csr == CSR_SSTATUS:
            return uc.reg_read(rv.UC_RISCV_REG_MSTATUS) & SSTATUS_READ
        if csr == CSR_SIE:
            return uc.reg_read(rv.UC_RISCV_REG_MIE) & uc.reg_read(rv.UC_RISCV_REG_MIDELEG)
        if csr in TRIGGER_CSRS:
            return self.triggers.read(csr)
        if csr == CSR_MUCOUNTEREN:
            return self.counter_enables[PRIV_U]
        if csr == CSR_MSCOUNTEREN:
            return self.counter_enables[PRIV_S]
        if csr == CSR_SPTBR:
            return uc.reg_read(rv.UC_RISCV_REG_SATP) & SPTBR_PPN
        if csr in (CSR_MCYCLE, CSR_CYCLE):
            return (self.csr_context.mcycle() + self.mcycle_offset) & (2**64 - 1)
        if csr in (CSR_MINSTRET, CSR_INSTRET):
            # the counting hook has already counted the CSR instruction itself, which has
            # not retired yet: a read returns the instructions retired before it
            return (self.instret - 1 + self.minstret_offset) & (2**64 - 1)
        mip = self.csr_context.mip() & SUPPORTED_INTERRUPTS
        if csr == CSR_SIP:
            return mip & uc.reg_read(rv.UC_RISCV_REG_MIDELEG)
        return mip

    def _csr_write(self, csr: int, value: int) -> None:
        uc = self.uc
        if csr == CSR_MSTATUS:
            if (value & MSTATUS_VM_1_9_1) >> 24 == VM_SV39:
                raise UnmodelledAccess(
                    f"hart {self.hart_id}: mstatus.VM = {VM_SV39} (Sv39) turns on the paged virtual memory of "
                    f"privileged spec 1.9.1 (the K210's MMU), which the model does not have")
            self._write_status(rv.UC_RISCV_REG_MSTATUS, legal_mstatus(value))
        elif csr == CSR_SSTATUS:
            mstatus = uc.reg_read(rv.UC_RISCV_REG_MSTATUS)
            value = (mstatus & ~SSTATUS_WRITABLE) | (value & SSTATUS_WRITABLE)
            self._write_status(rv.UC_RISCV_REG_MSTATUS, legal_mstatus(value))
        elif csr == CSR_MIE:
            self._write_status(rv.UC_RISCV_REG_MIE, value & SUPPORTED_INTERRUPTS)
        elif csr == CSR_SIE:
            mideleg = uc.reg_read(rv.UC_RISCV_REG_MIDELEG)
            mie = uc.reg_read(rv.UC_RISCV_REG_MIE)
            self._write_status(rv.UC_RISCV_REG_MIE, (mie & ~mideleg) | (value & mideleg))
        elif csr == CSR_MIDELEG:
            uc.reg_write(rv.UC_RISCV_REG_MIDELEG, value & DELEGABLE_INTERRUPTS)
            self.request_stop()                       # which interrupts are takeable may change
        elif csr == CSR_MEDELEG:
            uc.reg_write(rv.UC_RISCV_REG_MEDELEG, value & DELEGABLE_EXCEPTIONS)
        elif csr in (CSR_MIP, CSR_SIP):
            writable = SOFTWARE_PENDING if csr == CSR_MIP else SIP_WRITABLE
            raised = value & writable & ~self.soft_mip
            self.soft_mip = (self.soft_mip & ~writable) | (value & writable)
            if raised:
                self.request_stop()                   # the hart's own bits: taken after this instruction
        elif csr in TRIGGER_CSRS:
            self.triggers.write(csr, value)
            self._watch_triggers()
        elif csr in (CSR_MUCOUNTEREN, CSR_MSCOUNTEREN):
            self.counter_enables[PRIV_U if csr == CSR_MUCOUNTEREN else PRIV_S] = value & COUNTER_BITS
        elif csr == CSR_SPTBR:
            uc.reg_write(rv.UC_RISCV_REG_SATP, value & SPTBR_PPN)
        elif csr in (CSR_MTVEC, CSR_STVEC):
            # `reg_mtvec := wdata >> 2 << 2`, and stvec alike: no vectored mode before 1.10
            uc.reg_write(_UNICORN_CSR[csr], value & ~3)
        elif csr == CSR_MCYCLE:
            self.mcycle_offset = value - self.csr_context.mcycle()
        elif csr == CSR_MINSTRET:
            # the write replaces the CSR instruction's own increment: the next instruction
            # reads exactly `value` (privileged spec, "CSR side effects")
            self.minstret_offset = value - self.instret

    def _write_status(self, register: int, value: int) -> None:
        """Writes mstatus or mie; a write that may let an interrupt in ends the turn, so that the
        scheduler takes it right after this instruction."""
        unmasks = value & ~self.uc.reg_read(register)
        self.uc.reg_write(register, value)
        if unmasks:
            self.request_stop()

    # --- the hardware breakpoint ------------------------------------------------------------------

    def _watch_triggers(self) -> None:
        """While a trigger is armed, a hook looks at every instruction before it runs (on the
        precise engine: the fast one does not carry hooks); otherwise nothing is paid."""
        armed = self.triggers.armed
        if armed and self._trigger_hook is None:
            self._trigger_hook = self.add_stop_hook(self._on_trigger_watch, None, 1, 0)
        elif not armed and self._trigger_hook is not None:
            self.delete_hook(self._trigger_hook)
            self._trigger_hook = None

    def _on_trigger_watch(self, uc: unicorn.Uc, address: int, size: int, _: object) -> None:
        """Before an instruction: the breakpoint exception if the trigger matches its pc or its
        load/store address. The instruction is neither counted nor retired."""
        word = self.read_u16(address)
        if word & 3 == 3:
            word = self.read_u32(address)
        access = decode_memory_access(word)
        effective = None
        if access is not None:
            _, rs1, imm = access
            effective = ((uc.reg_read(rv.UC_RISCV_REG_X0 + rs1) if rs1 else 0) + imm) & (2**64 - 1)
        tval = self.triggers.check(word, address, self.privilege, effective)
        if tval is not None:
            self.pending_exception = PendingException(CAUSE_BREAKPOINT, address, tval)
            uc.emu_stop()


_UNICORN_CSR = {CSR_MTVEC: rv.UC_RISCV_REG_MTVEC, CSR_STVEC: rv.UC_RISCV_REG_STVEC,
                CSR_MIDELEG: rv.UC_RISCV_REG_MIDELEG, CSR_MEDELEG: rv.UC_RISCV_REG_MEDELEG}


def find_csr_sites(code: bytes, base: int) -> list[tuple[int, int]]:
    """Every 2-byte-aligned address in `code` holding an instruction the board carries out (an
    intercepted CSR, mret, sret, sfence.vm, sfence.vma). Sites that are really the middle of another
    instruction never execute, so extra candidates are harmless."""
    return list(_csr_sites(code, base))


@functools.lru_cache(maxsize=8)
def _csr_sites(code: bytes, base: int) -> tuple[tuple[int, int], ...]:
    """find_csr_sites, once a process for the same code (every board of a firmware scans it)."""
    _, words = code_parcels(code)
    found = ((words & 0x7F) == 0x73) & ((words >> 12 & 3) != 0) & np.isin(words >> 20, sorted(INTERCEPTED_CSRS))
    found |= np.isin(words, (INSN_MRET, INSN_SRET))
    found |= (words & MASK_SFENCE_VM) == INSN_SFENCE_VM
    found |= (words & MASK_SFENCE_VMA) == INSN_SFENCE_VMA
    return tuple((base + 2 * int(i), int(words[i])) for i in np.flatnonzero(found))
