"""--profile: instructions and cycles per function, per hart, over the whole run and per frame.

A Python block hook on each hart sees every translated block the hart enters. Between two
blocks, what the hart's native counter counted (instructions, and the cycles the timing model
charged) belongs to the function the earlier block lies in, under the calls that led there:

- functions are the firmware's code symbols that are global or the target of a call (`jal`,
  or `auipc` + `jalr`, writing ra or t0); other code labels (loop heads, local branches)
  belong to the function around them;
- a block that ends in a call (`jal`/`jalr`/`c.jalr` writing ra or t0) pushes its function and
  return address; a block entered at a return address on the stack (a `ret`, an `mret` back,
  a long jump) pops down to it; a trap handler runs on top of what it interrupted.

Exclusive figures count a function's own instructions; inclusive ones those of everything it
called too (each function once per stack, so recursion is not counted twice). `profile.txt`
has the table, sorted by cycles, per hart, then each frame's top functions; `profile.folded`
has one line per call stack, "hart0;main_hart0;render_frame;raster_triangle 12345" weighted by
cycles, which flamegraph.pl, speedscope and inferno read. A run without --profile installs
nothing and costs nothing; with it, the model runs many times slower: 13.7 times the host CPU
time over the default card's first 12 frames in one run (2026-11-28), and `make bench` measures
it per steady frame (its profile figures' `cost`).
"""
from __future__ import annotations

import bisect
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import unicorn
from elftools.elf.constants import SH_FLAGS
from elftools.elf.elffile import ELFFile

from ..errors import BadInput

if TYPE_CHECKING:
    from ..board import Board, FrameRecord
    from ..cpu.hart import Hart

LINK_REGISTERS = (1, 5)           # ra, t0: the RISC-V calling convention's link registers
UNKNOWN = "?"
TOP_PER_FRAME = 8
CALL, OTHER = 1, 0


def decode_call(word: int) -> tuple[bool, int, int | None]:
    """(is a call, length in bytes, static target offset or None) of the instruction `word`;
    a `jalr` call's target is the caller's to work out (function_starts pairs it with its auipc)."""
    if word & 3 != 3:
        # c.jalr rs1 (writes ra): funct4 1001, rs1 != 0, rs2 = 0
        if word & 0xF003 == 0x9002 and (word >> 7) & 31 and not (word >> 2) & 31:
            return True, 2, None
        return False, 2, None
    opcode, rd = word & 0x7F, (word >> 7) & 31
    if opcode == 0x6F and rd in LINK_REGISTERS:                     # jal
        imm = ((word >> 31) & 1) << 20 | ((word >> 12) & 0xFF) << 12 | ((word >> 20) & 1) << 11 | \
            ((word >> 21) & 0x3FF) << 1
        return True, 4, imm - (1 << 21) if imm & (1 << 20) else imm
    if opcode == 0x67 and rd in LINK_REGISTERS:                     # jalr
        return True, 4, None
    return False, 4, None


def function_starts(path: str | Path) -> list[tuple[int, str]]:
    """(address, name) of every function of the ELF, sorted: its global code symbols and the
    local ones some `jal` calls."""
    try:
        with open(path, "rb") as handle:
            elf = ELFFile(handle)
            code = [(s["sh_addr"], s.data(), n) for n, s in enumerate(elf.iter_sections())
                    if s["sh_flags"] & SH_FLAGS.SHF_EXECINSTR and s["sh_type"] == "SHT_PROGBITS"]
            symtab = elf.get_section_by_name(".symtab")
            symbols = [] if symtab is None else [
                (s["st_value"], s.name, s["st_info"]["bind"]) for s in symtab.iter_symbols()
                if s.name and not s.name.startswith((".L", "$")) and any(s["st_shndx"] == n for _, _, n in code)]
    except (OSError, ValueError) as error:
        raise BadInput(f"--profile: cannot read the symbols of {path} ({error})") from None
    targets: set[int] = set()
    for base, data, _ in code:
        offset, upper = 0, None       # upper: (register, pc + its upper immediate) after an auipc
        while offset + 2 <= len(data):
            word = int.from_bytes(data[offset:offset + 4].ljust(4, b"\0"), "little")
            is_call, length, target = decode_call(word)
            if is_call and target is not None:
                targets.add(base + offset + target)
            elif is_call and length == 4 and upper is not None and upper[0] == (word >> 15) & 31:
                # `call` without relaxation: auipc ra, %hi(f); jalr ra, %lo(f)(ra)
                low = word >> 20
                targets.add(upper[1] + (low - (1 << 12) if low & 0x800 else low))
            if length == 4 and word & 0x7F == 0x17:           # auipc
                imm = word & 0xFFFFF000
                upper = ((word >> 7) & 31, base + offset + (imm - (1 << 32) if imm & 0x80000000 else imm))
            else:
                upper = None
            offset += length
    named = {address: name for address, name, bind in symbols if bind == "STB_GLOBAL" or address in targets}
    return sorted(named.items())


@dataclass
class FunctionFigures:
    instructions: int = 0            # exclusive
    cycles: int = 0
    inclusive_instructions: int = 0
    inclusive_cycles: int = 0
    calls: int = 0


@dataclass
class _HartState:
    executed: int = 0
    cycles: int = 0
    function: str = UNKNOWN
    stack: list[tuple[str, int]] = field(default_factory=list)     # callers: (function, return address)
    last_block: tuple[int, int, int] = (0, 0, 0)                    # (kind, fall-through, instructions)
    block_entered: int = 0                                          # `executed` when it was entered


class Profiler:
    """Collects the profile of a run; `write(folder)` writes profile.txt and profile.folded."""

    def __init__(self, board: "Board", firmware: str | Path) -> None:
        self.board = board
        starts = function_starts(firmware)
        self._addresses = [address for address, _ in starts]
        self._names = [name for _, name in starts]
        self._block_kinds: dict[int, tuple[int, int]] = {}
        self.figures: list[dict[str, FunctionFigures]] = [defaultdict(FunctionFigures) for _ in board.harts]
        self.folded: list[dict[str, int]] = [defaultdict(int) for _ in board.harts]
        self._states = [_HartState() for _ in board.harts]
        self._frame_marks: list[list[dict[str, tuple[int, int]]]] = []      # per frame, per hart: exclusive so far
        for hart in board.harts:
            hart.add_hook(unicorn.UC_HOOK_BLOCK, self._on_block, hart)

    def function_of(self, address: int) -> str:
        index = bisect.bisect_right(self._addresses, address) - 1
        return self._names[index] if index >= 0 else UNKNOWN

    def _block_kind(self, hart: "Hart", start: int, size: int) -> tuple[int, int, int]:
        """(CALL or OTHER, the address after the block, its instructions), decoded once."""
        known = self._block_kinds.get((start, size))
        if known is None:
            offset, kind, count = 0, OTHER, 0
            while offset < size:
                is_call, length, _ = decode_call(hart.read_u32(start + offset))
                kind = CALL if is_call and offset + length >= size else OTHER
                offset += length
                count += 1
            known = self._block_kinds[(start, size)] = (kind, start + size, count)
        return known

    def _account(self, hart: "Hart") -> None:
        """What the hart ran since it was last looked at goes to its current call stack."""
        state = self._states[hart.hart_id]
        executed, cycles = hart.executed, hart.cycles
        instructions, spent = executed - state.executed, cycles - state.cycles
        state.executed, state.cycles = executed, cycles
        if not instructions:
            return
        figures = self.figures[hart.hart_id]
        own = figures[state.function]
        own.instructions += instructions
        own.cycles += spent
        for name in {name for name, _ in state.stack} | {state.function}:
            figures[name].inclusive_instructions += instructions
            figures[name].inclusive_cycles += spent
        names = [f"hart{hart.hart_id}"]
        for name in [name for name, _ in state.stack] + [state.function]:
            if name != names[-1]:       # a call to code without a symbol of its own shows as its caller
                names.append(name)
        path = ";".join(names)
        self.folded[hart.hart_id][path] += spent

    def _on_block(self, uc: unicorn.Uc, address: int, size: int, hart: "Hart") -> None:
        self._account(hart)
        state = self._states[hart.hart_id]
        kind, after, count = state.last_block
        function = self.function_of(address)
        # a block cut short (the turn ended in it, or an exception) did not reach its call
        completed = hart.executed - state.block_entered >= count
        if kind == CALL and completed and address != after:
            state.stack.append((state.function, after))
            self.figures[hart.hart_id][function].calls += 1
        else:
            for depth in range(len(state.stack) - 1, -1, -1):
                if state.stack[depth][1] == address:
                    del state.stack[depth:]
                    break
        state.function = function
        state.last_block = self._block_kind(hart, address, size)
        state.block_entered = hart.executed

    def frame(self, record: "FrameRecord") -> None:
        """A frame was shown: its share of the profile starts from here."""
        for hart in self.board.harts:
            self._account(hart)
        self._frame_marks.append([{name: (f.instructions, f.cycles) for name, f in figures.items()}
                                  for figures in self.figures])

    def write(self, folder: Path) -> dict:
        """Writes profile.txt and profile.folded; returns run.json's summary of them."""
        for hart in self.board.harts:
            self._account(hart)
        lines = ["# per hart, functions by cycles (exclusive: own instructions; inclusive: with what they called)",
                 f"# cycles: the timing model's ({self.board.timing})"]
        for hart_id, figures in enumerate(self.figures):
            total_cycles = sum(f.cycles for f in figures.values()) or 1
            lines += ["", f"hart {hart_id}",
                      f"{'function':32} {'cycles':>14} {'%':>6} {'instructions':>14} {'incl. cycles':>14} "
                      f"{'incl. instr.':>14} {'calls':>9}"]
            for name, f in sorted(figures.items(), key=lambda item: -item[1].cycles):
                if not f.cycles and not f.inclusive_cycles:
                    continue
                lines.append(f"{name[:32]:32} {f.cycles:14,} {100 * f.cycles / total_cycles:6.2f} {f.instructions:14,} "
                             f"{f.inclusive_cycles:14,} {f.inclusive_instructions:14,} {f.calls:9,}")
        previous = [{} for _ in self.figures]
        for index, marks in enumerate(self._frame_marks):
            lines += ["", f"frame {index}: top functions by cycles since the frame before"]
            for hart_id, mark in enumerate(marks):
                deltas = sorted(((cycles - previous[hart_id].get(name, (0, 0))[1],
                                  instructions - previous[hart_id].get(name, (0, 0))[0], name)
                                 for name, (instructions, cycles) in mark.items()), reverse=True)
                shown = ", ".join(f"{name} {cycles:,} ({instructions:,} instr.)"
                                  for cycles, instructions, name in deltas[:TOP_PER_FRAME] if cycles)
                lines.append(f"  hart {hart_id}: {shown or 'nothing'}")
            previous = marks
        try:
            (folder / "profile.txt").write_text("\n".join(lines) + "\n")
            with (folder / "profile.folded").open("w") as out:
                for figures in self.folded:
                    for path, cycles in sorted(figures.items()):
                        if cycles:
                            out.write(f"{path} {cycles}\n")
        except OSError as error:
            raise BadInput(f"--profile: cannot write into {folder} ({error.strerror or error})") from None
        return {"files": ["profile.txt", "profile.folded"],
                "functions": {f"hart{h}": {name: vars(f) for name, f in figures.items() if f.inclusive_cycles}
                              for h, figures in enumerate(self.figures)}}
