"""The K210's bus as the harts see it: address decoding and the rules of an access.

SRAM is mapped straight into each hart's Unicorn engine (both views, one buffer).
Every device window becomes an MMIO range whose callbacks come here: the access is
decoded from the instruction (Unicorn splits 64-bit and misaligned MMIO accesses into
pieces; the instruction says what the hart really did), checked against the rules
(a misaligned device access traps, a peripheral whose clock is gated or held in reset
cannot be used), and handed to the device's register table. An address no device
answers stops the run with a message naming hart, pc, instruction and address.
With --check-writes the stray-write checker watches stores into SRAM here too.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import unicorn
from unicorn import riscv_const as rv

from . import hart as hartmod
from .disasm import disassemble_one
from .elf import symbolize
from .errors import BoardStop, FirmwareTrap, HardwareMisuse, StrayWrite, UnmodelledAccess
from .hart import Hart
from .memory import SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE
from .mmio import Peripheral
from .write_watch import describe as describe_stray

if TYPE_CHECKING:
    from .board import Board

# Blocks of the K210 the model knows by name but does not implement (for clear messages)
KNOWN_UNMODELLED = [
    (0x5020_0000, 0x1000, "GPIO (the slow GPIO block)"), (0x5021_0000, 0x1_0000, "UART1"),
    (0x5022_0000, 0x1_0000, "UART2"), (0x5023_0000, 0x1_0000, "UART3"), (0x5024_0000, 0x1_0000, "SPI slave"),
    (0x5025_0000, 0x3_0000, "I2S"), (0x5028_0000, 0x3_0000, "I2C"), (0x502C_0000, 0x1_0000, "SHA256"),
    (0x502D_0000, 0x3_0000, "timers"), (0x5040_0000, 0x2_0000, "WDT"), (0x5042_0000, 0x1_0000, "OTP"),
    (0x5043_0000, 0x1_0000, "DVP"), (0x5045_0000, 0x1_0000, "AES"), (0x5046_0000, 0x1_0000, "RTC"),
    (0x5400_0000, 0x100_0000, "SPI3 (on-board flash)"), (0x5000_0000 + 0x1000, 0xF000, "DMAC (past its registers)"),
    (0x5100_0000, 0x100_0000, "SPI2"), (0x4080_0000, 0x100_0000, "KPU"), (0x4200_0000, 0x100_0000, "FFT"),
    (0x8800_0000, 0x2_0000, "boot ROM"),
]
CAUSE_LOAD_MISALIGNED, CAUSE_STORE_MISALIGNED = 4, 6


def _bits(word: int, high: int, low: int) -> int:
    return (word >> low) & ((1 << (high - low + 1)) - 1)


def _signed(value: int, bits: int) -> int:
    return value - (1 << bits) if value >> (bits - 1) & 1 else value


def decode_memory_access(word: int) -> tuple[int, int, int] | None:
    """(bytes moved, base register, offset) of an RV64GC load/store/AMO, or None."""
    if word & 3 != 3:                         # compressed
        op, funct3 = word & 3, _bits(word, 15, 13)
        if op == 0 and funct3 in (1, 2, 3, 5, 6, 7):          # c.fld c.lw c.ld c.fsd c.sw c.sd
            rs1 = 8 + _bits(word, 9, 7)
            if funct3 in (2, 6):
                imm = _bits(word, 12, 10) << 3 | _bits(word, 6, 6) << 2 | _bits(word, 5, 5) << 6
                return 4, rs1, imm
            return 8, rs1, _bits(word, 12, 10) << 3 | _bits(word, 6, 5) << 6
        if op == 2 and funct3 in (1, 2, 3):                    # c.fldsp c.lwsp c.ldsp
            if funct3 == 2:
                return 4, 2, _bits(word, 12, 12) << 5 | _bits(word, 6, 4) << 2 | _bits(word, 3, 2) << 6
            return 8, 2, _bits(word, 12, 12) << 5 | _bits(word, 6, 5) << 3 | _bits(word, 4, 2) << 6
        if op == 2 and funct3 in (5, 6, 7):                    # c.fsdsp c.swsp c.sdsp
            if funct3 == 6:
                return 4, 2, _bits(word, 12, 9) << 2 | _bits(word, 8, 7) << 6
            return 8, 2, _bits(word, 12, 10) << 3 | _bits(word, 9, 7) << 6
        return None
    opcode, funct3, rs1 = word & 0x7F, _bits(word, 14, 12), _bits(word, 19, 15)
    if opcode in (0x03, 0x07):                                 # loads
        return 1 << (funct3 & 3), rs1, _signed(word >> 20, 12)
    if opcode in (0x23, 0x27):                                 # stores
        return 1 << (funct3 & 3), rs1, _signed(_bits(word, 31, 25) << 5 | _bits(word, 11, 7), 12)
    if opcode == 0x2F:                                         # AMOs and LR/SC
        return (8 if funct3 == 3 else 4), rs1, 0
    return None


def is_sram(address: int) -> bool:
    return SRAM_BASE <= address < SRAM_BASE + SRAM_SIZE or SRAM_UNCACHED_BASE <= address < SRAM_UNCACHED_BASE + SRAM_SIZE


class Bus:
    """Decodes every hart access outside SRAM and applies the K210's rules to it."""

    def __init__(self, board: "Board") -> None:
        self.board = board
        self.scheduler = board.scheduler
        self.peripherals: list[Peripheral] = board.peripherals
        self._timed_set = set(board.timed_devices)
        harts = len(board.scheduler.harts)
        self._split: list[tuple[int, int, int] | None] = [None] * harts
        self._accesses: dict[int, tuple[int, int, int]] = {}
        self._faulting_pc: list[int | None] = [None] * harts
        self.device_writes: dict[str, list[int]] = {}     # stores per device, per hart

    # --- mapping ----------------------------------------------------------------------

    def attach(self, hart: Hart) -> None:
        """Maps SRAM (both views) and every device window into a hart's engine."""
        uc = hart.uc
        memory = self.board.memory
        uc.mem_map_ptr(SRAM_BASE, SRAM_SIZE, unicorn.UC_PROT_ALL, memory.address)
        uc.mem_map_ptr(SRAM_UNCACHED_BASE, SRAM_SIZE, unicorn.UC_PROT_ALL, memory.address)
        for peripheral in self.peripherals:
            uc.mmio_map(peripheral.BASE, peripheral.SIZE,
                        self._mmio_reader(hart, peripheral), None, self._mmio_writer(hart, peripheral), None)
        uc.hook_add(unicorn.UC_HOOK_MEM_UNMAPPED | unicorn.UC_HOOK_MEM_FETCH_PROT | unicorn.UC_HOOK_MEM_READ_PROT
                    | unicorn.UC_HOOK_MEM_WRITE_PROT, self._unmapped(hart))

    @staticmethod
    def is_sram(address: int) -> bool:
        return is_sram(address)

    def is_device(self, address: int) -> bool:
        return any(p.BASE <= address < p.BASE + p.SIZE for p in self.peripherals)

    # --- turns ------------------------------------------------------------------------------

    def turn_begins(self, hart: Hart) -> None:
        self._faulting_pc[hart.hart_id] = None

    def turn_ended(self, hart: Hart) -> BoardStop | None:
        """After a hart's turn: with --check-writes, the stray store that ended it, if any."""
        watch = self.board.write_watch
        stray = watch.stray_store(hart) if watch is not None else None
        if stray is None:
            return None
        # the hart stopped right after the stray store, so nothing it did later this turn
        # can have been recorded: the store is what ends the run
        access = self.describe_access(hart, stray.address, stray.size, "store", stray.pc)
        return StrayWrite(f"{access}: {describe_stray(stray)}")

    # --- describing and refusing accesses ------------------------------------------------

    def describe_access(self, hart: Hart, address: int, size: int, direction: str, pc: int | None = None) -> str:
        """'hart H at pc P <symbol> (instruction): <direction> of N bytes at A'; the pc is the
        hart's current one unless given (a store the run has already gone past)."""
        if pc is None:
            pc = hart.uc.reg_read(rv.UC_RISCV_REG_PC)
        where = symbolize(self.board.image.symbols, pc)
        where = f" <{where}>" if where else ""
        return (f"hart {hart.hart_id} at pc 0x{pc:08x}{where} ({self.board.disassemble_at(pc)}): "
                f"{direction} of {size} bytes at 0x{address:08x}")

    def _fail(self, hart: Hart, error: BoardStop, address: int, size: int, direction: str) -> None:
        if self.board.permissive and isinstance(error, UnmodelledAccess) and self.is_device(address):
            self.board.warn(f"{self.describe_access(hart, address, size, direction)}: {error.args[0]} "
                            f"(permissive: loads read 0, stores are ignored)")
            return
        if self.scheduler.pending_stop is None:
            error.args = (f"{self.describe_access(hart, address, size, direction)}: {error.args[0]}",)
            self.scheduler.stop(error)
        hart.request_stop()

    def check_dma_write(self, address: int, length: int, writer: str) -> None:
        """--check-writes for the DMAC: a write outside the firmware's buffers ends the run (the
        current hart's turn ends after its instruction; between turns, step() raises)."""
        stray = self.board.write_watch.check_dma(address, length)
        if stray is None or self.scheduler.pending_stop is not None:
            return
        self.scheduler.stop(StrayWrite(f"{writer}: write of {length} bytes at "
                                       f"0x{address:08x}..0x{address + length - 1:08x}: {describe_stray(stray)}"))
        if self.scheduler.current is not None:
            self.scheduler.current.request_stop()

    def _unmapped(self, hart: Hart):
        def hook(uc, access, address, size, value, user_data):
            fetch = access in (unicorn.UC_MEM_FETCH_UNMAPPED, unicorn.UC_MEM_FETCH_PROT)
            write = access in (unicorn.UC_MEM_WRITE_UNMAPPED, unicorn.UC_MEM_WRITE_PROT)
            name = next((n for base, length, n in KNOWN_UNMODELLED if base <= address < base + length), None)
            if fetch:
                self.scheduler.stop(FirmwareTrap(
                    f"hart {hart.hart_id}: instruction fetch from 0x{address:08x}, which is not memory "
                    f"(jumped from around pc 0x{uc.reg_read(rv.UC_RISCV_REG_PC):08x})"))
                return False
            reason = (f"{name}, which the board model does not implement" if name
                      else "no device or memory answers at this address")
            self._fail(hart, UnmodelledAccess(reason), address, size, "store" if write else "load")
            return False
        return hook

    # --- the rules of a device access ---------------------------------------------------------

    def _gate_check(self, peripheral: Peripheral) -> None:
        gate = getattr(peripheral, "GATE", None)
        sysctl = self.board.sysctl
        if gate is None or gate in sysctl.usable:
            return
        if not sysctl.gate_open(gate):
            raise HardwareMisuse(f"{peripheral.NAME} accessed while its clock is gated "
                                 f"(SYSCTL clk_en_peri / clk_en_cent): enable its clock first")
        if sysctl.in_reset(gate):
            raise HardwareMisuse(f"{peripheral.NAME} accessed while held in reset (SYSCTL peri_reset)")

    def _access(self, hart: Hart, pc: int) -> tuple[int, int, int]:
        """(width, base register, offset) of the load/store at pc, decoded once per pc.
        Unicorn splits a 64-bit or misaligned MMIO access into several callbacks; the
        instruction says what the hart really did."""
        access = self._accesses.get(pc)
        if access is None:
            access = decode_memory_access(hart.read_u32(pc)) or (4, 0, 0)
            self._accesses[pc] = access
        return access

    def _misaligned(self, hart: Hart, pc: int, width: int, rs1: int, imm: int, is_store: bool) -> bool:
        """A misaligned device access raises the misaligned-access exception, as on the K210;
        the rest of the instruction's callbacks are ignored."""
        if self._faulting_pc[hart.hart_id] == pc:
            return True
        base = hart.reg(rv.UC_RISCV_REG_X0 + rs1) if rs1 else 0
        address = (base + imm) & (2**64 - 1)
        if address % width == 0:
            return False
        cause = CAUSE_STORE_MISALIGNED if is_store else CAUSE_LOAD_MISALIGNED
        hart.pending_exception = hartmod.PendingException(cause, pc, address)
        hart.retired_adjust += 1
        hart.request_stop()
        self._faulting_pc[hart.hart_id] = pc
        return True

    def _mmio_reader(self, hart: Hart, peripheral: Peripheral):
        scheduler = self.scheduler

        def read(uc, offset, size, user_data):
            if scheduler.pending_stop is not None:
                return 0
            pc = hart.reg(rv.UC_RISCV_REG_PC)
            pending = self._split[hart.hart_id]
            if pending is not None and pending[:2] == (pc, offset):
                self._split[hart.hart_id] = None
                return pending[2]
            now = scheduler.hart_now(hart)
            width, rs1, imm = self._access(hart, pc)
            if self._misaligned(hart, pc, width, rs1, imm, False):
                return 0
            try:
                self._gate_check(peripheral)
                value = peripheral.read(offset, width, now)
            except BoardStop as error:
                self._fail(hart, error, peripheral.BASE + offset, width, "load")
                return 0
            if width == 8 and size == 4:
                self._split[hart.hart_id] = (pc, offset + 4, value >> 32)
                value &= 0xFFFF_FFFF
            scheduler.note_poll(hart, pc, offset + peripheral.BASE, value)
            return value
        return read

    def _mmio_writer(self, hart: Hart, peripheral: Peripheral):
        scheduler = self.scheduler
        timed = peripheral in self._timed_set

        def write(uc, offset, size, value, user_data):
            if scheduler.pending_stop is not None:
                return
            pc = hart.reg(rv.UC_RISCV_REG_PC)
            width, rs1, imm = self._access(hart, pc)
            if self._misaligned(hart, pc, width, rs1, imm, True):
                return
            if width == 8 and size == 4:
                pending = self._split[hart.hart_id]
                if pending is None or pending[:2] != (pc, offset):
                    self._split[hart.hart_id] = (pc, offset + 4, value & 0xFFFF_FFFF)
                    return
                self._split[hart.hart_id] = None
                offset, value = offset - 4, pending[2] | (value & 0xFFFF_FFFF) << 32
            now = scheduler.hart_now(hart)
            scheduler.forget_poll(hart)
            self.device_writes.setdefault(peripheral.NAME, [0] * len(self._split))[hart.hart_id] += 1
            try:
                self._gate_check(peripheral)
                peripheral.write(offset, width, value, now)
            except BoardStop as error:
                self._fail(hart, error, peripheral.BASE + offset, width, "store")
                return
            # A hart with interrupts enabled must take an interrupt the moment its device raises
            # it: a store that schedules something before this turn's planned end ends the turn.
            # (Without mstatus.MIE nothing can preempt the hart; status reads are exact in any
            # case, and sleeping harts wake at the event's own time.)
            if timed and hart.reg(rv.UC_RISCV_REG_MSTATUS) & hartmod.MSTATUS_MIE:
                event = self.board.next_device_event(now)
                if event is not None and event < scheduler.turn_horizon:
                    hart.request_stop()
        return write
