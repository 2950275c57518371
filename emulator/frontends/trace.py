"""--trace-insn: an instruction trace of a window of virtual time, one line per instruction:

    hart  virtual time (s)  pc          instruction          registers it wrote
    0     0.000123456       0x80000124  addi a0, a0, 1       a0=0x5

The virtual time is the hart's after the instruction (its instructions so far, as `mcycle` and
the frame figures count them). A Python hook on every instruction runs only inside the window,
so a run costs nothing extra before and after it; inside, the model runs at roughly 1 % of its
speed, and a trace takes about 60 bytes per instruction.
"""
from __future__ import annotations

from pathlib import Path
from typing import IO, TYPE_CHECKING

import unicorn
from unicorn import riscv_const as rv

from ..cpu.riscv import FPR_NAMES, GPR_NAMES
from ..errors import BadInput, write_failed
from ..vtime import Time, to_seconds

if TYPE_CHECKING:
    from ..board import Board
    from ..cpu.hart import Hart

GPRS = [rv.UC_RISCV_REG_X0 + n for n in range(1, 32)]
FPRS = [rv.UC_RISCV_REG_F0 + n for n in range(32)]
HEADER = "# hart  virtual_time_s  pc  instruction  ;  registers written\n"


def open_trace(path: Path) -> IO[str]:
    """The trace file, opened before the run: a path that cannot be written is bad input."""
    try:
        return path.open("w")
    except OSError as error:
        raise BadInput(f"--trace-insn {path}: cannot write it ({error.strerror or error})") from None


class _Pending:
    """An instruction started but not yet seen finished: what its registers held before."""
    __slots__ = ("pc", "text", "time", "gprs", "fprs")

    def __init__(self, pc: int, text: str, time: Time, gprs: list[int], fprs: list[int] | None) -> None:
        self.pc, self.text, self.time, self.gprs, self.fprs = pc, text, time, gprs, fprs


class InstructionTrace:
    """Writes the trace of [t_from, t_to) of virtual time (t_to None: to the end of the run)."""

    def __init__(self, board: "Board", out: IO[str], t_from: Time = 0, t_to: Time | None = None) -> None:
        self.board = board
        self.out = out
        self.lines = 0
        self._handles: dict[int, int] = {}
        self._pending: dict[int, _Pending] = {}
        self._texts: dict[int, str] = {}
        out.write(HEADER)
        if t_from <= 0:
            self._start(board)
        else:
            board.grab_at(t_from, self._start)
        if t_to is not None:
            board.grab_at(t_to, self._stop)

    def _start(self, board: "Board") -> None:
        for hart in board.harts:
            self._handles[hart.hart_id] = hart.add_hook(unicorn.UC_HOOK_CODE, self._hook, hart)
            # the CSR instructions the board carries out itself stop the engine before the hook above
            hart.csr_listeners.append(self._on_csr_site)

    def _stop(self, board: "Board") -> None:
        for hart in board.harts:
            handle = self._handles.pop(hart.hart_id, None)
            if handle is not None:
                hart.delete_hook(handle)
                hart.csr_listeners.remove(self._on_csr_site)
            self._finish(hart)

    def close(self) -> None:
        """At the end of the run: the last instructions' register writes, and the file closed."""
        self._stop(self.board)
        self.out.close()

    def _hook(self, uc: unicorn.Uc | None, address: int, size: int, hart: "Hart") -> None:
        self._finish(hart)
        text = self._texts.get(address)
        if text is None:
            text = self._texts[address] = self.board.disassemble_at(address)
        floating = text.startswith(("f", "c.f"))
        # the native counter has already counted this instruction: the hart's time is after it
        now = self.board.scheduler.hart_now(hart)
        self._pending[hart.hart_id] = _Pending(address, text, now, [hart.reg(r) for r in GPRS],
                                                [hart.reg(r) for r in FPRS] if floating else None)

    def _on_csr_site(self, hart: "Hart", address: int) -> None:
        self._hook(None, address, 4, hart)

    def _finish(self, hart: "Hart") -> None:
        """Writes the line of the hart's previous instruction, now that it has run."""
        pending = self._pending.pop(hart.hart_id, None)
        if pending is None:
            return
        written = [f"{GPR_NAMES[n + 1]}=0x{value:x}" for n, (old, value)
                   in enumerate(zip(pending.gprs, (hart.reg(r) for r in GPRS))) if value != old]
        if pending.fprs is not None:
            written += [f"{FPR_NAMES[n]}=0x{value:x}" for n, (old, value)
                        in enumerate(zip(pending.fprs, (hart.reg(r) for r in FPRS))) if value != old]
        try:
            self.out.write(f"{hart.hart_id} {to_seconds(pending.time):.12f} 0x{pending.pc:08x} {pending.text}"
                           f"{'  ; ' + ' '.join(written) if written else ''}\n")
        except OSError as error:
            raise write_failed(getattr(self.out, "name", "--trace-insn"), error) from None
        self.lines += 1
