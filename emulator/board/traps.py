"""Traps as the board takes them: a hart's synchronous exception entering the firmware's handler at
mtvec, and a pending enabled interrupt entering it before a turn; what ends a run there (mtvec at
no memory, a trap storm, --stop-on-trap) and what run.json counts (exceptions by kind)."""
from __future__ import annotations

from typing import TYPE_CHECKING, Callable, Protocol

from unicorn import riscv_const as rv

from ..cpu import riscv
from ..cpu.hart import Hart
from ..cpu.privileged import PendingException, lowest_interrupt
from ..errors import FirmwareTrap, HangDetected
from .elf import symbolize

if TYPE_CHECKING:
    from .elf import LoadedImage

# A hart that takes the same exception at the same pc with the same registers this many times in a
# row, storing to no device in between, can make no progress: a trap storm, which ends the run
TRAP_STORM_REPEATS = 1000


class TrapBus(Protocol):
    device_writes: dict[str, list[int]]            # stores per device, per hart

    def is_sram(self, address: int) -> bool: ...


class TrapBoard(Protocol):
    """What taking a trap needs of the board: its program (for symbols), a disassembler, the bus
    (whether mtvec is in SRAM; the harts' device stores so far) and the pending interrupts."""

    image: "LoadedImage"
    bus: TrapBus

    def disassemble_at(self, pc: int) -> str: ...

    def mip(self, h: int, now: float, mask: int = ~0) -> int: ...


class Traps:
    """The board's side of the harts' traps."""

    def __init__(self, board: TrapBoard) -> None:
        self.board = board
        self.stop_on_trap = False                         # --stop-on-trap: any exception ends the run
        self.report: str | None = None                    # --stop-on-trap: the exception that ends it
        self.taken: dict[str, int] = {}                   # exceptions per kind, for run.json
        self.last: str | None = None                      # the last exception taken, for a hang report
        self._storm: dict[int, tuple[tuple, int, int]] = {}   # per hart: (what, device stores, repeats)

    def chip_reset(self) -> None:
        self.report = None
        self._storm.clear()

    def take_interrupt(self, hart: Hart) -> None:
        """Before a turn: of the pending interrupts the hart would take (privileged.py), the
        lowest-numbered enters its trap vector."""
        takeable = hart.takeable_interrupts()
        if not takeable:
            return
        irq = lowest_interrupt(self.board.mip(hart.hart_id, hart.time, takeable) & takeable)
        if irq is not None:
            hart.enter_trap(riscv.CAUSE_INTERRUPT | irq, hart.pc, 0)

    def deliver_exception(self, hart: Hart, open_grace: Callable[[], None]) -> None:
        """A synchronous exception enters the firmware's trap handler, as on the chip, and the run
        goes on. The run ends only where the hart can make no progress: mtvec pointing at no
        memory, or a trap storm; with --stop-on-trap, after the handler's grace period, which
        open_grace starts (as it does for a fault whose handler may never return)."""
        exc = hart.pending_exception
        hart.pending_exception = None
        name = riscv.EXCEPTION_NAMES.get(exc.cause, f"exception {exc.cause}")
        where = symbolize(self.board.image.symbols, exc.epc)
        report = (f"hart {hart.hart_id}: {name} at pc 0x{exc.epc:08x}{f' <{where}>' if where else ''} "
                  f"({self.board.disassemble_at(exc.epc)}), mtval 0x{exc.tval:x}")
        vector_name, vector = hart.trap_vector(exc.cause)
        if self.report is not None:
            where = "in the trap handler" if hart.open_trap is not None else "after the trap handler returned"
            raise FirmwareTrap(f"{self.report}; then, {where}, {report}")
        if vector & ~3 == 0 or not self.board.bus.is_sram(vector & ~3):
            raise FirmwareTrap(f"{report}; {vector_name} = 0x{vector:x} points at no trap handler")
        self.taken[name] = self.taken.get(name, 0) + 1
        self.last = report
        if self.stop_on_trap:
            self.report = report
        else:
            self._watch_for_storm(hart, exc, report)
        if exc.cause not in riscv.ECALL_CAUSES or self.stop_on_trap:
            # a fault its handler may not return from; an ecall is a request, and a handler that
            # never returns from one ends the program as asked (the SDK's exit spins in sys_exit)
            hart.open_trap = report
            open_grace()
        hart.enter_trap(exc.cause, exc.epc, exc.tval)

    def _watch_for_storm(self, hart: Hart, exc: PendingException, report: str) -> None:
        """Ends the run when the hart takes the same exception at the same pc with the same registers
        TRAP_STORM_REPEATS times in a row, storing to no device in between (its handler returns to
        the faulting instruction and nothing changes): reported like a hang, naming the trap."""
        what = (exc.cause, exc.epc, exc.tval, tuple(hart.reg(rv.UC_RISCV_REG_X1 + n) for n in range(31)))
        stores = sum(counts[hart.hart_id] for counts in self.board.bus.device_writes.values())
        last = self._storm.get(hart.hart_id)
        repeats = last[2] + 1 if last is not None and last[0] == what and last[1] == stores else 1
        self._storm[hart.hart_id] = (what, stores, repeats)
        if repeats >= TRAP_STORM_REPEATS:
            raise HangDetected(f"trap storm: {report}, {repeats} times in a row with the same registers and no "
                               f"device store in between: the trap handler returns to the faulting instruction "
                               f"and nothing changes")
