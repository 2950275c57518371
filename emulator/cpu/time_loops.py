"""Loops that wait for time by reading it: the Kendryte SDK's usleep and msleep, `while
(read_cycle() - start < n);`. Each iteration reads mcycle (or cycle), does register arithmetic on
it and branches back until the value is far enough on; nothing else happens in it. Run
instruction by instruction, a one-second wait at 400 MHz is tens of millions of CSR reads, each
answered by the board; here the hart skips the iterations that cannot end the loop, with exact
counts.

At load time every such loop is found (`find_time_loops`): a straight run of register arithmetic,
exactly one read of mcycle/cycle and branches out of the loop, closed by a backward branch, in
which no register carries a value from one iteration to the next (so every iteration is the
same but for the time it reads), and whose instructions this module can evaluate. At run time
(LoopSkipper.at_time_read) the hart, stopped at the loop's time read, has seen the last two iterations
take the same instructions, cycles, branch mispredictions and stalls, with the branch predictor
in the same state and the time advancing by the same cycles: from here every iteration is the
same. `exits` evaluates the rest of an iteration (from the time read to the closing branch) for a
time value; the first iteration whose value ends the loop is found by bisection (the loops wait
for a value to grow past a bound), and the ones before it are skipped: their instructions,
cycles, mispredictions and stalls are counted, time moves on by their cycles, and the hart reads
the time of the iteration that ends the loop, which it then runs. The skip stays within the
hart's turn, whose end is where running would have stopped as well: a one-second wait costs a
turn's overhead per 20,000 cycles instead of a CSR read per iteration; while the hart runs alone
with nothing due, the scheduler lets it skip past its turn's end (Scheduler._alone_until).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Iterable, TypeVar

import numpy as np

from .riscv import CSR_CYCLE, CSR_MCYCLE, bits, code_parcels, instruction_at, signed
from .shared_memory import MAX_LOOP_BYTES, PollLoop, _backward_branches

MASK = (1 << 64) - 1
_L = TypeVar("_L", PollLoop, "TimeLoop")


def _sx32(value: int) -> int:
    value &= 0xFFFF_FFFF
    return (value - (1 << 32) if value >> 31 else value) & MASK


@dataclass(frozen=True)
class Op:
    """One instruction the evaluator carries out: `kind` alu (rd = op(rs1, rs2 or imm)), branch
    (to `target` when op(rs1, rs2) holds), jump (to `target`), time (rd = the time read)."""
    pc: int
    size: int
    kind: str
    op: str = ""
    rd: int = 0
    rs1: int = 0
    rs2: int | None = None          # None: the immediate is the second operand
    imm: int = 0
    target: int | None = None

    @property
    def reads(self) -> tuple[int, ...]:
        return tuple(r for r in (self.rs1, self.rs2) if r)


_OP = {(0, 0): "add", (0, 0x20): "sub", (1, 0): "sll", (2, 0): "slt", (3, 0): "sltu", (4, 0): "xor",
       (5, 0): "srl", (5, 0x20): "sra", (6, 0): "or", (7, 0): "and"}
_OP_IMM = {0: "add", 2: "slt", 3: "sltu", 4: "xor", 6: "or", 7: "and"}
_BRANCH = {0: "eq", 1: "ne", 4: "lt", 5: "ge", 6: "ltu", 7: "geu"}


def _decode_32(word: int, pc: int) -> Op | None:
    opcode, rd, funct3 = word & 0x7F, bits(word, 11, 7), bits(word, 14, 12)
    rs1, rs2, funct7 = bits(word, 19, 15), bits(word, 24, 20), bits(word, 31, 25)
    i_imm = signed(word >> 20, 12)
    if opcode in (0x13, 0x1B):                                   # OP-IMM, OP-IMM-32
        w = "w" if opcode == 0x1B else ""
        if funct3 in (1, 5):
            shamt = bits(word, 25, 20) if not w else bits(word, 24, 20)
            op = "sll" if funct3 == 1 else ("sra" if word >> 30 & 1 else "srl")
            return Op(pc, 4, "alu", op + w, rd, rs1, None, shamt)
        if w and funct3 != 0:
            return None
        return Op(pc, 4, "alu", _OP_IMM[funct3] + w, rd, rs1, None, i_imm) if funct3 in _OP_IMM else None
    if opcode in (0x33, 0x3B):                                   # OP, OP-32 (no M extension)
        name = _OP.get((funct3, funct7))
        w = "w" if opcode == 0x3B else ""
        if name is None or (w and name not in ("add", "sub", "sll", "srl", "sra")):
            return None
        return Op(pc, 4, "alu", name + w, rd, rs1, rs2)
    if opcode == 0x37:                                           # LUI
        return Op(pc, 4, "alu", "add", rd, 0, None, signed(word & 0xFFFF_F000, 32))
    if opcode == 0x17:                                           # AUIPC
        return Op(pc, 4, "alu", "add", rd, 0, None, (pc + signed(word & 0xFFFF_F000, 32)) & MASK)
    if opcode == 0x63 and funct3 in _BRANCH:
        imm = (bits(word, 31, 31) << 12 | bits(word, 7, 7) << 11 | bits(word, 30, 25) << 5
               | bits(word, 11, 8) << 1)
        return Op(pc, 4, "branch", _BRANCH[funct3], 0, rs1, rs2, target=pc + signed(imm, 13))
    if opcode == 0x6F and rd == 0:                               # j
        imm = (bits(word, 31, 31) << 20 | bits(word, 19, 12) << 12 | bits(word, 20, 20) << 11
               | bits(word, 30, 21) << 1)
        return Op(pc, 4, "jump", target=pc + signed(imm, 21))
    if opcode == 0x73 and funct3 == 2 and rs1 == 0 and word >> 20 in (CSR_MCYCLE, CSR_CYCLE) and rd:
        return Op(pc, 4, "time", rd=rd)                          # csrr rd, mcycle / cycle
    return None


def _decode_16(half: int, pc: int) -> Op | None:
    op, funct3 = half & 3, bits(half, 15, 13)
    rd = bits(half, 11, 7)
    rdp, rs2p = 8 + bits(half, 9, 7), 8 + bits(half, 4, 2)
    imm6 = signed(bits(half, 12, 12) << 5 | bits(half, 6, 2), 6)
    if op == 1:
        if funct3 == 0:
            return Op(pc, 2, "alu", "add", rd, rd, None, imm6)             # c.addi (c.nop)
        if funct3 == 1 and rd:
            return Op(pc, 2, "alu", "addw", rd, rd, None, imm6)            # c.addiw
        if funct3 == 2:
            return Op(pc, 2, "alu", "add", rd, 0, None, imm6)              # c.li
        if funct3 == 3 and rd not in (0, 2) and imm6:
            return Op(pc, 2, "alu", "add", rd, 0, None, (imm6 << 12) & MASK)   # c.lui
        if funct3 == 4:
            kind = bits(half, 11, 10)
            if kind in (0, 1):
                shamt = bits(half, 12, 12) << 5 | bits(half, 6, 2)
                return Op(pc, 2, "alu", "srl" if kind == 0 else "sra", rdp, rdp, None, shamt)
            if kind == 2:
                return Op(pc, 2, "alu", "and", rdp, rdp, None, imm6)
            name = {(0, 0): "sub", (0, 1): "xor", (0, 2): "or", (0, 3): "and", (1, 0): "subw",
                    (1, 1): "addw"}.get((bits(half, 12, 12), bits(half, 6, 5)))
            return Op(pc, 2, "alu", name, rdp, rdp, rs2p) if name else None
        if funct3 == 5:
            imm = (bits(half, 12, 12) << 11 | bits(half, 8, 8) << 10 | bits(half, 10, 9) << 8
                   | bits(half, 6, 6) << 7 | bits(half, 7, 7) << 6 | bits(half, 2, 2) << 5
                   | bits(half, 11, 11) << 4 | bits(half, 5, 3) << 1)
            return Op(pc, 2, "jump", target=pc + signed(imm, 12))       # c.j
        imm = (bits(half, 12, 12) << 8 | bits(half, 6, 5) << 6 | bits(half, 2, 2) << 5
               | bits(half, 11, 10) << 3 | bits(half, 4, 3) << 1)
        return Op(pc, 2, "branch", "eq" if funct3 == 6 else "ne", 0, rdp, 0, target=pc + signed(imm, 9))
    if op == 2:
        if funct3 == 0 and rd:
            return Op(pc, 2, "alu", "sll", rd, rd, None, bits(half, 12, 12) << 5 | bits(half, 6, 2))
        rs2 = bits(half, 6, 2)
        if funct3 == 4 and rd and rs2:
            if not bits(half, 12, 12):
                return Op(pc, 2, "alu", "add", rd, 0, rs2)                     # c.mv
            return Op(pc, 2, "alu", "add", rd, rd, rs2)                        # c.add
    return None


def decode(code: bytes, offset: int, pc: int) -> Op | None:
    """The instruction at code[offset], if it is one the evaluator carries out."""
    found = instruction_at(code, offset)
    if found is None:
        return None
    word, size = found
    return _decode_16(word, pc) if size == 2 else _decode_32(word, pc)


def _alu(op: str, a: int, b: int) -> int:
    word = op.endswith("w")
    name = op[:-1] if word else op
    shift = b & (31 if word else 63)
    if name == "add":
        value = a + b
    elif name == "sub":
        value = a - b
    elif name == "sll":
        value = a << shift
    elif name == "srl":
        value = (a & (0xFFFF_FFFF if word else MASK)) >> shift
    elif name == "sra":
        value = signed(a & (0xFFFF_FFFF if word else MASK), 32 if word else 64) >> shift
    elif name == "slt":
        value = int(signed(a & MASK, 64) < signed(b & MASK, 64))
    elif name == "sltu":
        value = int((a & MASK) < (b & MASK))
    elif name == "xor":
        value = a ^ b
    elif name == "or":
        value = a | b
    else:
        value = a & b
    return _sx32(value) if word else value & MASK


def _taken(op: str, a: int, b: int) -> bool:
    sa, sb = signed(a, 64), signed(b, 64)
    return {"eq": a == b, "ne": a != b, "lt": sa < sb, "ge": sa >= sb, "ltu": a < b, "geu": a >= b}[op]


@dataclass(frozen=True)
class TimeLoop:
    """A loop waiting for time (module comment): [head, branch] holds `body` instructions; `rest`
    is what follows the time read up to the closing branch, the part of an iteration that decides
    whether the loop ends."""
    head: int
    branch: int
    body: int
    site: int                                   # the time read's address
    rest: tuple[Op, ...]

    def exits(self, time: int, register) -> bool:
        """Whether the iteration whose time read returns `time` leaves the loop; `register(n)`
        gives the others' values (what the loop does not write is the same in every iteration)."""
        values: dict[int, int] = {}

        def get(r: int) -> int:
            return 0 if r == 0 else values[r] if r in values else register(r)

        time_read = next(op for op in self.rest if op.kind == "time")
        values[time_read.rd] = time & MASK
        for op in self.rest[1:]:
            if op.kind == "alu":
                b = get(op.rs2) if op.rs2 is not None else op.imm & MASK
                if op.rd:
                    values[op.rd] = _alu(op.op, get(op.rs1), b)
            elif op.kind == "branch":
                if _taken(op.op, get(op.rs1), get(op.rs2)):
                    return op.target != self.head
            elif op.kind == "jump":
                return op.target != self.head
        return True                             # fell through the closing branch


JAL_TO_ITSELF, C_J_TO_ITSELF = 0x0000_006F, 0xA001     # jal x0, 0 and c.j 0: `j .`


def find_idle_loops(code: bytes, base: int) -> list[PollLoop]:
    """Every loop that does nothing but spin: `j .` (a jump to itself; the SDK's sys_exit ends in
    one, and many programs' last words are one) or a straight run of register arithmetic closed by a
    backward jump, carrying no value between iterations and reading no memory and no time. The
    native counter reports them as it reports poll loops (a PollLoop without loads); the hart counts
    their iterations without running them (Hart.skip_idle)."""
    return list(_idle_loops(code, base))


def _first_at_each_head(found: Iterable[_L | None]) -> tuple[_L, ...]:
    """The loops found, the first one for each head address (several closing jumps may share one)."""
    loops: dict[int, _L] = {}
    for loop in found:
        if loop is not None and loop.head not in loops:
            loops[loop.head] = loop
    return tuple(loops.values())


@functools.lru_cache(maxsize=8)
def _idle_loops(code: bytes, base: int) -> tuple[PollLoop, ...]:
    """find_idle_loops, once a process for the same code (every board of a firmware scans it)."""
    return _first_at_each_head(_idle_loop_at(code, base, offset) for offset in [*_backward_branches(code), *_jumps_to_themselves(code)])


def _jumps_to_themselves(code: bytes) -> list[int]:
    """Offsets of every 2-byte-aligned `j .` (JAL_TO_ITSELF or C_J_TO_ITSELF)."""
    halves, words = code_parcels(code)
    found = halves == C_J_TO_ITSELF
    found[:-1] |= words == JAL_TO_ITSELF
    return [2 * int(i) for i in np.flatnonzero(found)]


def _idle_loop_at(code: bytes, base: int, branch_offset: int) -> PollLoop | None:
    branch_pc = base + branch_offset
    closing = decode(code, branch_offset, branch_pc)
    if closing is None or closing.kind != "jump" or not branch_pc - MAX_LOOP_BYTES <= closing.target <= branch_pc:
        return None
    head = closing.target
    ops: list[Op] = []
    pc = head
    while pc < branch_pc:
        op = decode(code, pc - base, pc)
        if op is None or op.kind != "alu":
            return None
        ops.append(op)
        pc += op.size
    if pc != branch_pc:
        return None
    written = {op.rd for op in ops if op.rd}
    defined: set[int] = set()
    for op in ops:
        if any(r in written and r not in defined for r in op.reads):
            return None
        if op.rd:
            defined.add(op.rd)
    return PollLoop(head, branch_pc, len(ops) + 1, ())


def find_time_loops(code: bytes, base: int) -> list[TimeLoop]:
    """Every loop in `code` (loaded at `base`) that can only be waiting for time (module comment)."""
    return list(_time_loops(code, base))


@functools.lru_cache(maxsize=8)
def _time_loops(code: bytes, base: int) -> tuple[TimeLoop, ...]:
    return _first_at_each_head(_time_loop_at(code, base, offset) for offset in _backward_branches(code))


def _time_loop_at(code: bytes, base: int, branch_offset: int) -> TimeLoop | None:
    branch_pc = base + branch_offset
    closing = decode(code, branch_offset, branch_pc)
    if closing is None or closing.kind not in ("branch", "jump") or closing.target is None or \
            not branch_pc - MAX_LOOP_BYTES <= closing.target < branch_pc:
        return None
    head = closing.target
    ops: list[Op] = []
    pc = head
    while pc < branch_pc:
        op = decode(code, pc - base, pc)
        if op is None or (op.kind == "jump") or (op.kind == "branch" and head <= op.target <= branch_pc):
            return None                          # not evaluable, or a branch within the loop
        ops.append(op)
        pc += op.size
    if pc != branch_pc:
        return None
    ops.append(closing)
    times = [index for index, op in enumerate(ops) if op.kind == "time"]
    if len(times) != 1:
        return None
    written = {op.rd for op in ops if op.kind in ("alu", "time") and op.rd}
    defined: set[int] = set()
    for op in ops:
        if any(r in written and r not in defined for r in op.reads):
            return None                          # a value carried between iterations
        if op.kind in ("alu", "time") and op.rd:
            defined.add(op.rd)
    start = times[0]
    return TimeLoop(head, branch_pc, len(ops), ops[start].pc, tuple(ops[start:]))


class LoopSkipper:
    """One hart's skipping of the loops above: what its native counter (native.py's Counter) was at
    the last two visits of each loop, and the iterations counted without being run."""

    def __init__(self, counter) -> None:
        self.counter = counter
        self.seen: dict[int, tuple] = {}
        self.iterations = 0

    def forget(self) -> None:
        """A chip reset: every loop is seen afresh."""
        self.seen.clear()

    def _state(self) -> tuple:
        counter = self.counter
        return (counter.executed, counter.cycles, counter.mispredicts, counter.stall_cycles,
                bytes(counter.predictor), counter.pending_kind, counter.pending_pc, counter.pending_entry,
                counter.pending_penalty)

    def _steady(self, key: int, now: tuple, body: int) -> tuple[tuple, tuple[int, ...]] | None:
        """Records this visit; (the last visit, the counts one iteration adds) when the last two
        iterations were alike in instructions (`body`), cycles, mispredictions, stalls and
        predictor state, else None."""
        seen = self.seen.get(key)
        self.seen[key] = (seen[1] if seen else None, now)
        if seen is None or seen[0] is None:
            return None
        older, last = seen
        step = tuple(b - a for a, b in zip(last[:4], now[:4]))
        if step != tuple(b - a for a, b in zip(older[:4], last[:4])) or step[0] != body or step[1] <= 0 or \
                last[4:9] != now[4:9] or older[4:9] != last[4:9]:
            return None
        return last, step

    def _room(self, body: int, cycles_per: int, turn_limit: int, beyond_turn: int | None = None) -> int:
        """Iterations that fit in the rest of the hart's turn: where running would stop too (beyond
        it, the scheduler's to allow).
        `beyond_turn`: the cycle count up to which the scheduler lets the hart go past its turn's end
        (Scheduler._alone_until: it runs alone and nothing happens before then)."""
        counter = self.counter
        if beyond_turn is not None and beyond_turn > counter.cycle_limit:
            return (beyond_turn - counter.cycles) // cycles_per
        return min((counter.cycle_limit - counter.cycles) // cycles_per,
                   (max(counter.limit, turn_limit) - counter.executed) // body)

    def _count(self, iterations: int, step: tuple[int, ...]) -> None:
        counter = self.counter
        counter.executed += iterations * step[0]
        counter.cycles += iterations * step[1]
        counter.mispredicts += iterations * step[2]
        counter.stall_cycles += iterations * step[3]

    def at_time_read(self, loop: TimeLoop, time_now, register, turn_limit: int, beyond_turn: int | None = None) -> None:
        """At a time loop's read (counted, not carried out; `time_now()` the value it would read,
        `register(n)` the hart's registers): the iterations before the first that ends the loop are
        counted, and the read then returns the time of the iteration it now is. `beyond_turn`: as
        _room's (a skip past the turn's end ends the turn right after it)."""
        time = time_now()
        steady = self._steady(loop.site, self._state() + (time,), loop.body)
        if steady is None:
            return
        last, step = steady
        cycles_per = step[1]
        if time - last[9] != cycles_per:
            return                               # the clock changed, or mcycle was written
        limit = self._room(loop.body, cycles_per, turn_limit, beyond_turn)
        if limit <= 0 or loop.exits(time, register):
            return
        if not loop.exits(time + limit * cycles_per, register):
            skip = limit
        else:
            low, high = 0, limit                 # exits(low) false, exits(high) true
            while high - low > 1:
                middle = (low + high) // 2
                if loop.exits(time + middle * cycles_per, register):
                    high = middle
                else:
                    low = middle
            skip = high
        self._count(skip, step)
        if time_now() != time + skip * cycles_per:
            self._count(-skip, step)             # the clock does not map cycles one to one here
            return
        self.iterations += skip
        self.seen[loop.site] = (last, self._state() + (time + skip * cycles_per,))

    def at_idle(self, loop: PollLoop, turn_limit: int, beyond_turn: int | None = None) -> None:
        """At a spinning loop's head, come round again: its iterations up to the end of the turn are
        counted without being run. `beyond_turn`: as _room's, the cycle count up to which the
        scheduler lets the hart go past its turn's end (Scheduler._alone_until: it runs alone and
        nothing can happen before then, no interrupt either, so nothing can take it out of the loop;
        a `j .` at the end of a program then costs a turn per device event, not one per quantum)."""
        steady = self._steady(loop.head, self._state(), loop.body)
        if steady is None:
            return
        last, step = steady
        skip = self._room(loop.body, step[1], turn_limit, beyond_turn)
        if skip <= 0:
            return
        self._count(skip, step)
        self.iterations += skip
        self.seen[loop.head] = (last, self._state())
