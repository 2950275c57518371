"""The K210's bus as the harts see it: address decoding and the rules of an access.

SRAM is mapped straight into each hart's Unicorn engine (both views, one buffer).
Every device window becomes an MMIO range whose callbacks come here: the access is
decoded from the instruction (Unicorn splits 64-bit and misaligned MMIO accesses into
pieces; the instruction says what the hart really did), checked against the rules
(a peripheral whose clock is gated or held in reset cannot be used) and handed to the
device's register table. With --check-writes the stray-write checker watches stores
into SRAM here too.

Accesses a register table does not take as they are get what the K210's buses do with
them (docs/design/board-model.md, "What the bus does"), with a warning naming hart, pc, instruction and
address, or, with --strict, stop the run (exit status 5):

- TileLink devices (CLINT, PLIC, UARTHS, GPIOHS: Rocket's register router) answer any
  width: a load returns the addressed bytes of the register; a store writes each field
  of the register whose bytes it covers entirely and leaves the others; an offset
  without a register reads 0 and ignores stores. A narrow store that covers every field
  it touches entirely (a `sb` to UARTHS txdata's data byte, to eight PLIC enable bits) is
  what the register map declares: carried out without a warning, under --strict too.
- APB devices (SYSCTL, FPIOA, SPI0, SPI1) are 32 bits wide with no byte strobes: a load
  reads the whole register (side effects included) and returns the addressed bytes; a
  narrower store writes the whole register with the stored byte or halfword repeated in
  every lane, as Rocket puts it on the bus.
- The DMAC's 32-bit AHB port takes each half of its 64-bit registers as a register of
  its own and narrower accesses by their bytes.
- A 64-bit access to two 32-bit registers is two 32-bit accesses, the lower one first.
- A store to a read-only register is ignored; a load from a write-only one reads 0.
- A misaligned access to a device raises the misaligned-address exception (mcause 4, 6).
- An address where nothing answers raises an access fault too, except in the debug
  module's region at the bottom of the address space, which answers outside debug mode:
  loads read 0 and stores are ignored. A jump to where nothing answers raises the
  instruction access fault (mcause 1).
- Physical addresses are 32 bits: an address with any of its upper 32 bits set reaches
  what its low 32 bits name (machine mode translates nothing, and Rocket's TLB passes the
  low bits through), so a hart returning through a saved address whose upper half was
  overwritten runs on at the low half. The model maps the same memory or device there
  on first use.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Callable, Protocol

import unicorn
from unicorn import riscv_const as rv

from ..cpu import hart as hartmod
from ..cpu import riscv
from .elf import symbolize
from ..errors import BoardStop, FirmwareTrap, HardwareMisuse, RegisterRuleViolation, StrayWrite, UnmodelledAccess
from ..cpu.decode import decode_memory_access
from ..cpu.hart import Hart
from .scheduler import POLL_REPEATS
from ..memory_map import K210_UNMODELLED, SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE, is_sram
from ..vtime import Time
from ..devices.mmio import BUS_AHB, BUS_APB, BUS_TILELINK, Peripheral, Register
from .write_watch import describe as describe_stray

if TYPE_CHECKING:
    from ..devices.sysctl import Sysctl
    from .elf import LoadedImage
    from .memory import Sram
    from .scheduler import Scheduler
    from .write_watch import WriteWatch

# Rocket's physical addresses (rocket-chip coreplex/Configs.scala, PAddrBits = 32; in machine
# mode its TLB passes the address's low bits through unchanged, rocket/TLB.scala)
PHYSICAL_ADDRESS_BITS = 32
PHYSICAL_ADDRESS_MASK = (1 << PHYSICAL_ADDRESS_BITS) - 1
# distinct upper halves one hart may use before the run stops: each costs a set of mappings
MAX_ADDRESS_ALIASES = 16
# Rocket's debug module answers at the bottom of the address space, in and out of debug mode
# (rocket-chip denied M-mode access to it only in August 2019, long after the K210's design)
DEBUG_BASE, DEBUG_SIZE = 0x0000_0000, 0x1000
NO_DEVICE = "no device or memory answers at this address"
# What a store of 1 or 2 bytes puts on a 32-bit bus: Rocket repeats it in every byte lane
LANE_REPEAT = {1: 0x0101_0101, 2: 0x0001_0001}


def _mask(width_bytes: int) -> int:
    return (1 << (8 * width_bytes)) - 1


class Board(Protocol):
    """What the bus asks of the board it serves (dock.py's Board): the parts an access reaches or
    depends on, and its warnings."""

    scheduler: "Scheduler"
    peripherals: list[Peripheral]
    timed_devices: list[Peripheral]
    memory: "Sram"
    sysctl: "Sysctl"
    image: "LoadedImage"
    write_watch: "WriteWatch | None"
    permissive: bool

    def warn(self, text: str, now: Time | None = None) -> None: ...

    def disassemble_at(self, pc: int) -> str: ...

    def next_device_event(self, now: Time, past_quiet_console: bool = False) -> Time | None: ...


class Bus:
    """Decodes every hart access outside SRAM and applies the K210's rules to it."""

    def __init__(self, board: Board, strict: bool = False) -> None:
        self.board = board
        self.strict = strict     # stop at the first access the register tables do not take as it is
        self.scheduler = board.scheduler
        self.peripherals: list[Peripheral] = board.peripherals
        self._timed_set = set(board.timed_devices)
        harts = len(board.scheduler.harts)
        self._split: list[tuple[int, int, int] | None] = [None] * harts
        self._accesses: dict[int, tuple[int, int, int]] = {}
        self._faulting_pc: list[int | None] = [None] * harts
        # per hart, the last load if reading it again is known to give the same value with no side
        # effect until some virtual time (Peripheral.stable_until): (pc, offset, peripheral, value,
        # until). Only the same load again, with no other device access between, in the same turn,
        # is answered from it; a hart polling a status register does that several times a byte.
        self._stable: list[tuple[int, int, Peripheral, int, Time] | None] = [None] * harts
        self._aliases: list[set[int]] = [set() for _ in range(harts)]    # upper halves mapped, per hart
        self.device_writes: dict[str, list[int]] = {}     # stores per device, per hart
        self.questionable: dict[str, int] = {}            # accesses the bus answered with a warning, per kind

    # --- mapping ----------------------------------------------------------------------

    def attach(self, hart: Hart) -> None:
        """Maps SRAM (both views) and every device window into a hart's engine."""
        self._map_windows(hart, 0)
        hart.trap_misaligned(self.board.memory.address)
        hart.on_unmapped(self._unmapped(hart))
        hart.attach_devices([(p.BASE, p.BASE + p.SIZE) for p in self.peripherals], self._direct_access(),
                            self.scheduler.repeats_answered)

    def _map_windows(self, hart: Hart, upper: int) -> None:
        """Maps SRAM's two views and every device window at `upper` (0, or an upper half of the
        address space that aliases the 32-bit physical one) into a hart's engine."""
        memory = self.board.memory
        hart.map_memory(upper + SRAM_BASE, SRAM_SIZE, memory.address)
        hart.map_memory(upper + SRAM_UNCACHED_BASE, SRAM_SIZE, memory.address)
        for peripheral in self.peripherals:
            hart.map_device(upper + peripheral.BASE, peripheral.SIZE, self._mmio_reader(hart, peripheral),
                            self._mmio_writer(hart, peripheral))

    def answers(self, address: int) -> bool:
        """Whether memory or a modelled device answers at a 32-bit physical address."""
        return self.is_sram(address) or self.is_device(address)

    @staticmethod
    def is_sram(address: int) -> bool:
        return is_sram(address)

    def is_device(self, address: int) -> bool:
        return any(p.BASE <= address < p.BASE + p.SIZE for p in self.peripherals)

    # --- turns ------------------------------------------------------------------------------

    def turn_begins(self, hart: Hart) -> None:
        self._faulting_pc[hart.hart_id] = None
        self._stable[hart.hart_id] = None      # the other hart and the scheduler may have changed devices

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
            pc = hart.reg(rv.UC_RISCV_REG_PC)
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
            if address >> PHYSICAL_ADDRESS_BITS:
                return self._upper_bits_set(hart, address, size, fetch, write)
            name = next((n for base, length, n in K210_UNMODELLED if base <= address < base + length), None)
            if not fetch and not self.strict and DEBUG_BASE <= address < DEBUG_BASE + DEBUG_SIZE:
                # mapped on first use: a mapping at address 0 slows every hart down by several per cent
                hart.map_device(DEBUG_BASE, DEBUG_SIZE, self._debug_reader(hart), self._debug_writer(hart))
                return True     # Unicorn retries the access, which now reaches the debug region
            if fetch:
                self._fetch_fault(hart, address, name)
                return False
            if name is not None or self.strict:
                reason = f"{name}, which the board model does not implement" if name else NO_DEVICE
                self._fail(hart, UnmodelledAccess(reason), address, size, "store" if write else "load")
                return False
            self._access_fault(hart, address, write, "no device answers at this address")
            return False
        return hook

    def _fetch_fault(self, hart: Hart, address: int, name: str | None) -> None:
        """A jump to where no memory answers: Rocket's instruction access fault (mcause 1,
        mepc and mtval = the address; rocket/TLB.scala xcpt_if, rocket/CSR.scala). A device the
        model lacks, the debug region (its ROM is not modelled) and --strict stop the run."""
        jumped_from = hart.reg(rv.UC_RISCV_REG_PC)
        if name is not None or self.strict or DEBUG_BASE <= address < DEBUG_BASE + DEBUG_SIZE:
            what = f"{name}, which the board model does not implement" if name else "not memory"
            self.scheduler.stop(FirmwareTrap(
                f"hart {hart.hart_id}: instruction fetch from 0x{address:08x}, which is {what} "
                f"(jumped from around pc 0x{jumped_from:08x})"))
            return
        self._questionable(hart, "access fault", address, 4, "instruction fetch",
                           f"no memory answers at this address: the K210 raises an instruction access "
                           f"fault (mcause {riscv.CAUSE_FETCH_FAULT}, mtval 0x{address:x}) into the firmware's "
                           f"trap handler", pc=address)
        # the jump retired; the instruction at the target was never fetched, so nothing to take back
        hart.pending_exception = hartmod.PendingException(riscv.CAUSE_FETCH_FAULT, address, address)

    def _upper_bits_set(self, hart: Hart, address: int, size: int, fetch: bool, write: bool) -> bool:
        """An address above 4 GiB: the K210 reaches what its low 32 bits name. The same memory
        or device windows are mapped at the address's upper half (on first use, per hart) and
        the access retried; --strict stops instead. Returns whether Unicorn is to retry."""
        physical = address & PHYSICAL_ADDRESS_MASK
        upper = address - physical
        direction = "instruction fetch" if fetch else ("store" if write else "load")
        if not self.answers(physical):
            # nothing answers at the low half either: the access faults as it would there
            if fetch:
                self._fetch_fault(hart, address, None)
            elif self.strict:
                self._fail(hart, UnmodelledAccess(NO_DEVICE), address, size, direction)
            else:
                self._access_fault(hart, address, write, f"nothing answers at its low 32 bits (0x{physical:08x})")
            return False
        pc = address if fetch else None
        if self.strict:
            error = UnmodelledAccess(f"upper 32 bits set; the K210 would reach 0x{physical:08x} "
                                     f"(its physical addresses are 32 bits), --strict stops here")
            if fetch:
                self.scheduler.stop(FirmwareTrap(f"hart {hart.hart_id}: instruction fetch from "
                                                 f"0x{address:x}: {error.args[0]}"))
            else:
                self._fail(hart, error, address, size, direction)
            return False
        aliases = self._aliases[hart.hart_id]
        if upper not in aliases and len(aliases) >= MAX_ADDRESS_ALIASES:
            self._fail(hart, UnmodelledAccess(
                f"upper 32 bits set, and this hart has already used {MAX_ADDRESS_ALIASES} other upper "
                f"halves; the board model maps no more of them"), address, size, direction)
            return False
        self._questionable(hart, "upper address bits", address, size, direction,
                           f"the upper 32 bits are not 0: the K210's physical addresses are 32 bits, so "
                           f"the {direction} reaches 0x{physical:08x} (reported once per upper half and hart: "
                           f"the model maps memory and devices there and runs on at full speed)", pc=pc)
        if upper not in aliases:
            aliases.add(upper)
            self._map_windows(hart, upper)
        return True

    def _access_fault(self, hart: Hart, address: int, is_store: bool, why: str) -> None:
        """Rocket's answer to an access its physical memory attributes do not allow: a precise
        load or store access fault with mtval = the address, into the firmware's trap handler."""
        pc = hart.reg(rv.UC_RISCV_REG_PC)
        cause = riscv.CAUSE_STORE_FAULT if is_store else riscv.CAUSE_LOAD_FAULT
        width = self._access(hart, pc)[0]
        self._questionable(hart, "access fault", address, width, "store" if is_store else "load",
                           f"{why}: the K210 raises a {'store' if is_store else 'load'} access fault "
                           f"(mcause {cause}, mtval 0x{address:x}) into the firmware's trap handler")
        hart.pending_exception = hartmod.PendingException(cause, pc, address)
        hart.retired_adjust += 1
        hart.request_stop()
        self._faulting_pc[hart.hart_id] = pc

    def _questionable(self, hart: Hart, kind: str, address: int, width: int, direction: str,
                      what_happens: str, pc: int | None = None) -> None:
        """An access the bus answered the way the K210 does, though a register table would not
        take it as it is: a warning naming the access, counted per kind for run.json."""
        self.questionable[kind] = self.questionable.get(kind, 0) + 1
        self.board.warn(f"{self.describe_access(hart, address, width, direction, pc)}: {what_happens}",
                        self.scheduler.hart_now(hart))

    # --- the debug module's region ------------------------------------------------------------

    def _debug_reader(self, hart: Hart):
        def read(uc, offset, size, user_data):
            if self.scheduler.pending_stop is None:
                self._debug_access(hart, offset, False)
            return 0
        return read

    def _debug_writer(self, hart: Hart):
        def write(uc, offset, size, value, user_data):
            if self.scheduler.pending_stop is None:
                self._debug_access(hart, offset, True)
        return write

    def _debug_access(self, hart: Hart, offset: int, is_store: bool) -> None:
        """An access to the debug module's window outside debug mode: it answers (loads 0,
        stores ignored; the model has no debug ROM image or debug state to change). Not mapped
        with --strict, where such an access stops the run as any address nothing answers."""
        pc = hart.reg(rv.UC_RISCV_REG_PC)
        width, rs1, imm = self._access(hart, pc)
        direction = "store" if is_store else "load"
        if self._misaligned(hart, pc, width, rs1, imm, is_store):
            return
        base = hart.reg(rv.UC_RISCV_REG_X0 + rs1) if rs1 else 0
        if DEBUG_BASE + offset != (base + imm) & (2**64 - 1):
            return     # the second half of a 64-bit access: the first one warned
        self._questionable(hart, "debug region", DEBUG_BASE + offset, width, direction,
                           "the debug module's region (0x0..0xfff) answers outside debug mode too: "
                           + ("the store is ignored" if is_store else "the load reads 0"))

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
        """A misaligned device access raises the misaligned-access exception, as on the K210
        (its Rocket's data cache raises it for every address); the rest of the instruction's
        callbacks are ignored."""
        if self._faulting_pc[hart.hart_id] == pc:
            return True
        base = hart.reg(rv.UC_RISCV_REG_X0 + rs1) if rs1 else 0
        address = (base + imm) & (2**64 - 1)
        if address % width == 0:
            return False
        cause = riscv.CAUSE_STORE_MISALIGNED if is_store else riscv.CAUSE_LOAD_MISALIGNED
        hart.pending_exception = hartmod.PendingException(cause, pc, address)
        hart.retired_adjust += 1
        hart.request_stop()
        self._faulting_pc[hart.hart_id] = pc
        return True

    def _mmio_reader(self, hart: Hart, peripheral: Peripheral):
        """Unicorn's read callback for a device window: what Unicorn adds to an access (its pc, the
        pieces it splits a 64-bit load into, misaligned loads) before device_load."""
        scheduler = self.scheduler
        h = hart.hart_id
        accesses, split, stable = self._accesses, self._split, self._stable
        load = self._device_loader(hart, peripheral)

        def read(uc, offset, size, user_data):
            if scheduler.pending_stop is not None:
                return 0
            pc = hart.reg(rv.UC_RISCV_REG_PC)
            pending = split[h]
            if pending is not None and pending[:2] == (pc, offset):
                split[h] = None
                return pending[2]
            access = accesses.get(pc)
            width, rs1, imm = access if access is not None else self._access(hart, pc)
            # Unicorn splits a misaligned load into aligned pieces, the first of which can look like
            # an aligned load: the load traps before it reaches the device or counts as a poll
            if self._misaligned(hart, pc, width, rs1, imm, False):
                stable[h] = None
                return 0
            value = load(pc, offset, width, size == width)
            if width == 8 and size == 4:
                split[h] = (pc, offset + 4, value >> 32)
                value &= 0xFFFF_FFFF
            return value
        return read

    def _device_loader(self, hart: Hart, peripheral: Peripheral):
        """A load of `width` bytes at `offset` of the device by the instruction at pc, aligned (the
        callers have checked): its value. Every device load of the firmware comes through here (a
        poll of a status register many times per byte on the SD card's bus), so the common case
        takes the shortest way to the register table. `whole`: the caller hands over the value whole
        (Unicorn, splitting a 64-bit load, does not), so a stable answer may be kept."""
        scheduler = self.scheduler
        h = hart.hart_id
        gate = getattr(peripheral, "GATE", None)
        sysctl = self.board.sysctl
        stable = self._stable
        base_address = peripheral.BASE

        def load(pc: int, offset: int, width: int, whole: bool) -> int:
            now = scheduler.hart_now(hart)
            # a device access can set off an event the turn's long-skip limit did not know of
            hart.time_skip_limit = None
            again = stable[h]
            if again is not None:
                if again[0] == pc and again[1] == offset and again[2] is peripheral and now < again[4]:
                    # the same load as the last one, whose register cannot have changed: what the
                    # device would answer, without asking it (the poll is still noted)
                    scheduler.note_poll(hart, pc, offset + base_address, again[3])
                    return again[3]
                stable[h] = None
            try:
                if gate is not None and gate not in sysctl.usable:
                    self._gate_check(peripheral)
                value = self._load(hart, peripheral, offset, width, now)
            except BoardStop as error:
                self._fail(hart, error, peripheral.BASE + offset, width, "load")
                return 0
            if peripheral.took_on_read:
                # a loop emptying a FIFO reads alike values from one pc without waiting for anything
                peripheral.took_on_read = False
                scheduler.forget_poll(hart)
                return value
            if whole and scheduler.pending_stop is None:
                until = peripheral.stable_until(offset, now)
                if until > now:
                    stable[h] = (pc, offset, peripheral, value, until)
            scheduler.note_poll(hart, pc, offset + base_address, value)
            return value
        return load

    def _mmio_writer(self, hart: Hart, peripheral: Peripheral):
        """Unicorn's write callback for a device window: what Unicorn adds to an access (its pc, the
        pieces it splits a 64-bit store into, misaligned stores) before device_store."""
        scheduler = self.scheduler
        h = hart.hart_id
        accesses, stable, split = self._accesses, self._stable, self._split
        store = self._device_storer(hart, peripheral)

        def write(uc, offset, size, value, user_data):
            stable[h] = None
            if scheduler.pending_stop is not None:
                return
            pc = hart.reg(rv.UC_RISCV_REG_PC)
            access = accesses.get(pc)
            width, rs1, imm = access if access is not None else self._access(hart, pc)
            if self._misaligned(hart, pc, width, rs1, imm, True):
                return
            if width == 8 and size == 4:
                pending = split[h]
                if pending is None or pending[:2] != (pc, offset):
                    split[h] = (pc, offset + 4, value & 0xFFFF_FFFF)
                    return
                split[h] = None
                offset, value = offset - 4, pending[2] | (value & 0xFFFF_FFFF) << 32
            store(offset, width, value)
        return write

    def _device_storer(self, hart: Hart, peripheral: Peripheral):
        """A store of `width` bytes of `value` at `offset` of the device, aligned (the callers have
        checked)."""
        scheduler = self.scheduler
        timed = peripheral in self._timed_set
        moved = self.board.devices_a_store_moves(peripheral) if timed else None
        gate = getattr(peripheral, "GATE", None)
        sysctl = self.board.sysctl
        device_writes, harts = self.device_writes, len(self._split)

        def store(offset: int, width: int, value: int) -> None:
            now = scheduler.hart_now(hart)
            hart.time_skip_limit = None     # (as in load)
            scheduler.forget_poll(hart)
            device_writes.setdefault(peripheral.NAME, [0] * harts)[hart.hart_id] += 1
            try:
                if gate is not None and gate not in sysctl.usable:
                    self._gate_check(peripheral)
                self._store(hart, peripheral, offset, width, value, now)
            except BoardStop as error:
                self._fail(hart, error, peripheral.BASE + offset, width, "store")
                return
            # A hart with interrupts enabled must take an interrupt the moment its device raises
            # it: a store that schedules something before this turn's planned end ends the turn.
            # (Without mstatus.MIE nothing can preempt the hart; status reads are exact in any
            # case, and sleeping harts wake at the event's own time.)
            if timed and hart.interrupts_enabled():
                if moved is None:
                    event = self.board.next_device_event(now)
                else:
                    times = [t for t in (device.next_event_time(now) for device in moved) if t is not None and t > now]
                    event = min(times) if times else None
                if event is not None and event < scheduler.turn_horizon:
                    hart.request_stop()
        return store

    def _direct_access(self):
        """The device accesses the fast engine leaves to the bus (Hart.attach_devices): aligned,
        whole, in the window of self.peripherals[window]; the hart's registers are the fast engine's
        meanwhile (Hart.reg reads them)."""
        scheduler = self.scheduler
        stable = self._stable
        loaders: dict[tuple[int, int], Callable] = {}
        storers: dict[tuple[int, int], Callable] = {}

        def access(hart: Hart, window: int, address: int, width: int, is_store: bool, value: int, pc: int) -> int:
            peripheral = self.peripherals[window]
            key = (hart.hart_id, window)
            if is_store:
                stable[hart.hart_id] = None
                if scheduler.pending_stop is not None:
                    return 0
                storer = storers.get(key)
                if storer is None:
                    storer = storers[key] = self._device_storer(hart, peripheral)
                storer(address - peripheral.BASE, width, value)
                return 0
            if scheduler.pending_stop is not None:
                return 0
            loader = loaders.get(key)
            if loader is None:
                loader = loaders[key] = self._device_loader(hart, peripheral)
            offset = address - peripheral.BASE
            # (Unicorn hands a 64-bit device load over in two 32-bit halves, so the bus keeps no stable
            # answer for one: nor here, or its warnings would be counted differently)
            value = loader(pc, offset, width, width != 8)
            again = stable[hart.hart_id]
            if again is not None and again[0] == pc and again[1] == offset and again[2] is peripheral and \
                    not hart.stop_requested and scheduler.pending_stop is None:
                # the same load again would be answered from `again` (the loader's first case): the
                # fast engine does that itself, no call per poll
                repeats = scheduler.poll_count(hart, pc, address, value)
                if repeats:
                    hart.arm_repeats(pc, address, width, value, again[4], scheduler.turn_clock(hart), repeats,
                                     POLL_REPEATS)
            return value
        return access

    # --- what the buses do with accesses a register table does not take as they are -----------

    def _load(self, hart: Hart, peripheral: Peripheral, offset: int, width: int, now: Time) -> int:
        try:
            return peripheral.read(offset, width, now)
        except RegisterRuleViolation:
            if self.strict:
                raise
            located = peripheral.register_containing(offset)
            if located is None and peripheral.BUS != BUS_TILELINK:
                raise     # an APB or AHB register the model may lack: --permissive decides
        return self._answer_load(hart, peripheral, offset, width, now, located)

    def _answer_load(self, hart: Hart, peripheral: Peripheral, offset: int, width: int, now: Time,
                     located: tuple[int, Register] | None) -> int:
        address = peripheral.BASE + offset
        if located is None:
            self._questionable(hart, "no register", address, width, "load",
                               f"{peripheral.NAME} has no register at offset 0x{offset:x}; its TileLink "
                               f"register router answers 0")
            return 0
        base, reg = located
        name = f"{peripheral.NAME}.{reg.name}"
        if width == 8 and reg.width == 4:
            self._warn_pair(hart, peripheral, offset, "load")
            low = self._load(hart, peripheral, offset, 4, now)
            return low | self._load(hart, peripheral, offset + 4, 4, now) << 32
        if not reg.readable:
            self._questionable(hart, "write-only register", address, width, "load",
                               f"{name} is write-only: the load reads 0")
            return 0
        value = peripheral.read_register(base, reg, now)
        part = (value >> (8 * (offset - base))) & _mask(width)
        self._questionable(hart, "narrow load", address, width, "load",
                           f"{width * 8}-bit load from the {reg.width * 8}-bit register {name}: "
                           f"the register is read whole (with any side effect of reading it) and the "
                           f"addressed bytes returned")
        return part

    def _store(self, hart: Hart, peripheral: Peripheral, offset: int, width: int, value: int, now: Time) -> None:
        try:
            peripheral.write(offset, width, value, now)
            return
        except RegisterRuleViolation:
            located = peripheral.register_containing(offset)
            if self._whole_fields_store(peripheral, offset, width, value, now, located):
                return
            if self.strict:
                raise
            if located is None and peripheral.BUS != BUS_TILELINK:
                raise
        self._answer_store(hart, peripheral, offset, width, value, now, located)

    def _whole_fields_store(self, peripheral: Peripheral, offset: int, width: int, value: int, now: Time,
                            located: tuple[int, Register] | None) -> bool:
        """Carries out a store narrower than a TileLink register that covers every field of it the
        store touches entirely (at least one): an access the register map declares, made as the
        chip makes it, with no warning and under --strict too. The register router writes a field
        when the store's byte mask covers all of its bits (rocket-chip regmapper/RegMapper.scala:
        `wimask = frontMask(high, low).andR`) and leaves the rest; UARTHS's txdata is an 8-bit data
        field at [7:0] (sifive-blocks devices/uart/UART.scala, txdata: util/RegMapFIFO.scala's
        NonBlockingEnqueue, the data field 7:0 and `full` at bit 31), so a `sb` to it queues the
        byte, what the SDK's uarths_putchar (`txdata.data = c`) compiles to without
        -fstrict-volatile-bitfields. A store that covers a
        field only in part (that field keeps its value) or no field at all is legal on the chip too,
        but drops what it stores there: the bus answers it with a warning (_answer_store). False:
        not such a store."""
        if peripheral.BUS != BUS_TILELINK or located is None:
            return False
        base, reg = located
        if not reg.writable or width >= reg.width or offset + width > base + reg.width:
            return False
        lanes = _mask(width) << (8 * (offset - base))
        fields = reg.fields or ((0, 8 * reg.width),)
        touched = [((1 << bits) - 1) << low for low, bits in fields if ((1 << bits) - 1) << low & lanes]
        if not touched or any(field_mask & ~lanes for field_mask in touched):
            return False
        new, _ = self._narrow_store_result(peripheral, base, reg, offset, width, value, now)
        peripheral.write_register(base, reg, new, now)
        return True

    def _answer_store(self, hart: Hart, peripheral: Peripheral, offset: int, width: int, value: int,
                      now: Time, located: tuple[int, Register] | None) -> None:
        address = peripheral.BASE + offset
        if located is None:
            self._questionable(hart, "no register", address, width, "store",
                               f"{peripheral.NAME} has no register at offset 0x{offset:x}; its TileLink "
                               f"register router ignores the store")
            return
        base, reg = located
        name = f"{peripheral.NAME}.{reg.name}"
        if width == 8 and reg.width == 4:
            self._warn_pair(hart, peripheral, offset, "store")
            self._store(hart, peripheral, offset, 4, value & 0xFFFF_FFFF, now)
            self._store(hart, peripheral, offset + 4, 4, value >> 32, now)
            return
        if not reg.writable:
            self._questionable(hart, "read-only register", address, width, "store",
                               f"{name} is read-only: the store is ignored")
            return
        new, what = self._narrow_store_result(peripheral, base, reg, offset, width, value, now)
        self._questionable(hart, "narrow store", address, width, "store",
                           f"{width * 8}-bit store to the {reg.width * 8}-bit register {name}: {what}")
        if new is not None:
            peripheral.write_register(base, reg, new, now)

    def _narrow_store_result(self, peripheral: Peripheral, base: int, reg: Register, offset: int, width: int,
                             value: int, now: Time) -> tuple[int | None, str]:
        """The register's value after a store narrower than the register (None: unchanged), and
        how the bus came to it, for the warning. The text names no value: a firmware that keeps
        storing bytes from one instruction (a console's putc) gives one warning, counted."""
        shift = 8 * (offset - base)
        lanes = _mask(width) << shift
        data = (value & _mask(width)) << shift
        if peripheral.BUS == BUS_APB and reg.width == 4:
            new = (value & _mask(width)) * LANE_REPEAT[width]
            return new, (f"{peripheral.BUS} has no byte strobes, so the whole register is written with the "
                         f"stored value repeated in every byte lane")
        old = peripheral.merge_base(base, reg, now)
        if peripheral.BUS == BUS_AHB:
            new = (old & ~lanes) | data
            return new, f"the {peripheral.BUS} port writes the addressed bytes only"
        fields = reg.fields or ((0, 8 * reg.width),)
        new, covered = old, 0
        for low, bits in fields:
            field_mask = ((1 << bits) - 1) << low
            if field_mask & ~lanes == 0:
                new = (new & ~field_mask) | (data & field_mask)
                covered += 1
        if not covered:
            return None, (f"it covers no whole field of the register, so the {BUS_TILELINK} register router "
                          f"ignores it")
        return new, f"the {BUS_TILELINK} register router writes the fields whose bytes it covers"

    def _warn_pair(self, hart: Hart, peripheral: Peripheral, offset: int, direction: str) -> None:
        names = []
        for part in (offset, offset + 4):
            located = peripheral.register_containing(part)
            names.append(f"{peripheral.NAME}.{located[1].name}" if located else f"offset 0x{part:x}")
        self._questionable(hart, "64-bit access to 32-bit registers", peripheral.BASE + offset, 8, direction,
                           f"{names[0]} and {names[1]} are 32-bit registers: the bus makes the 64-bit "
                           f"{direction} two 32-bit ones, the lower address first")
