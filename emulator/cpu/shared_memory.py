"""The harts side by side: what one hart stores, the other sees as soon as it would on the chip.

The harts run in turns (scheduler.py), thousands of instructions each, which is what keeps
the model fast. Turns alone would hide a value one hart stores and soon overwrites from the
other, which on the chip polls the location the whole time: firmware that hands frames
between the harts through a flag set for a few instructions shows no second frame. What
the model does about it:

- Poll loops. At load time every short loop in the code that can only be polling memory is
  found (`find_poll_loops`): a straight run of loads, register arithmetic and branches out of
  the loop, closed by a backward branch, in which no register carries a value from one
  iteration to the next, so that every iteration is the same as long as the memory it reads
  is the same. The native instruction counter (_insn_counter.c) notices when a hart comes round
  one a second time in a row (a table look-up per instruction: a Unicorn hook per loop would
  cost every instruction far more, since Unicorn walks its list of code hooks on each).
- Waiting on SRAM. If every address such a loop reads is SRAM, the hart waits (HartState.WAITING)
  instead of spinning: it costs no host time, its time stands still, and a native store watch
  on the other harts covers exactly the bytes it reads. It wakes, and runs before the storer
  goes on, at the first store by another hart to those bytes; when a DMA write or anything
  else changes them (checked whenever devices advance); or when an interrupt it has enabled
  with mstatus.MIE set is pending. Loops that poll a device are left to the bus's own poll
  detection (Bus.note_poll).
- Races. After a hart is woken by a store, at reset, and while a hart comes round a poll loop on
  SRAM that is not yet proven to wait (its last iteration began in an earlier turn, and the
  memory it reads has changed since), the harts run in lockstep for RACE_WINDOW_CYCLES (turns of
  RACE_TURN cycles while both run; each cycle is run by the lowest hart first), so that a
  reply stored for only a few instructions meets the other hart's loop as it would on the chip.
  The window is short: its cost is a few hundred turns per hand-over.

What is left: a value stored and overwritten again while the other hart was not yet polling
it, but would have started to within one turn of the storer on the chip, is missed as
before; in practice a poller is waiting long before the hand-over.
"""
from __future__ import annotations

import ctypes
import functools
from dataclasses import dataclass, field

import numpy as np

from . import _poll_watch
from .decode import decode_memory_access
from .riscv import bits, code_parcels, instruction_at, signed
from ..memory_map import SRAM_BASE, SRAM_SIZE, SRAM_UNCACHED_BASE

MAX_LOOP_BYTES = 64            # longer loops are not taken for poll loops
RACE_WINDOW_CYCLES = 512       # lockstep after a hand-over (and at reset), in CPU cycles
RACE_TURN = 2                  # CPU cycles per hart per turn in lockstep (at least one instruction)

_watch_lib = ctypes.CDLL(_poll_watch.__file__)
STORE_WATCH_HOOK = ctypes.cast(_watch_lib.store_watch, ctypes.c_void_p)


class LoopSlot(ctypes.Structure):
    """_insn_counter.c's poll_loop_t: one slot of a hart's table of poll loops."""
    _fields_ = [("head", ctypes.c_uint64), ("body", ctypes.c_uint64), ("last", ctypes.c_uint64),
                ("ignore", ctypes.c_uint64)]


class StoreWatch(ctypes.Structure):
    """_poll_watch.c's store_watch_t."""
    _fields_ = [("counter", ctypes.c_void_p), ("hits", ctypes.c_uint64), ("address", ctypes.c_uint64)]


@dataclass(frozen=True)
class PollLoop:
    """A loop that can only poll memory: [head, branch] holds `body` instructions."""

    head: int
    branch: int                                    # address of the backward branch closing it
    body: int
    loads: tuple[tuple[int, int, int], ...]        # (width, base register, offset) of each load


@dataclass
class Wait:
    """What a waiting hart polls: SRAM offsets and the bytes it last read there."""

    loop: PollLoop
    spans: list[tuple[int, int]]                   # (SRAM offset, width)
    seen: list[bytes]
    watches: list[tuple[object, StoreWatch, list[int]]] = field(default_factory=list)  # (hart, watch, handles)

    def describe(self) -> str:
        """What the hart waits for, for hang reports."""
        spans = ", ".join(f"0x{SRAM_BASE + offset:08x} ({width} bytes, {seen[::-1].hex()})"
                          for (offset, width), seen in zip(self.spans, self.seen))
        return f"waits for another hart or a DMA write to change {spans}"


# --- static analysis: which loops can only be polling ---------------------------------------------

@dataclass(frozen=True)
class _Insn:
    size: int
    reads: tuple[int, ...]          # integer registers read
    writes: int                     # integer register written (0: none)
    load: bool = False
    target: int | None = None       # branch or jump target (absolute)
    conditional: bool = False


def _decode_32(word: int, pc: int) -> _Insn | None:
    opcode, rd, rs1, rs2 = word & 0x7F, bits(word, 11, 7), bits(word, 19, 15), bits(word, 24, 20)
    if opcode == 0x03:                                           # integer loads
        return _Insn(4, (rs1,), rd, load=True)
    if opcode in (0x13, 0x1B):                                   # OP-IMM, OP-IMM-32
        return _Insn(4, (rs1,), rd)
    if opcode in (0x33, 0x3B):                                   # OP, OP-32 (M included)
        return _Insn(4, (rs1, rs2), rd)
    if opcode in (0x17, 0x37):                                   # AUIPC, LUI
        return _Insn(4, (), rd)
    if opcode == 0x0F:                                           # FENCE
        return _Insn(4, (), 0)
    if opcode == 0x63:                                           # branches
        imm = (bits(word, 31, 31) << 12 | bits(word, 7, 7) << 11 | bits(word, 30, 25) << 5
               | bits(word, 11, 8) << 1)
        return _Insn(4, (rs1, rs2), 0, target=pc + signed(imm, 13), conditional=True)
    if opcode == 0x6F and rd == 0:                               # j
        imm = (bits(word, 31, 31) << 20 | bits(word, 19, 12) << 12 | bits(word, 20, 20) << 11
               | bits(word, 30, 21) << 1)
        return _Insn(4, (), 0, target=pc + signed(imm, 21))
    return None                                                  # stores, AMOs, CSRs, calls, FP, wfi...


def _decode_16(word: int, pc: int) -> _Insn | None:
    op, funct3 = word & 3, bits(word, 15, 13)
    rd, rs2 = bits(word, 11, 7), bits(word, 6, 2)
    rdp, rs2p = 8 + bits(word, 4, 2), 8 + bits(word, 9, 7)    # rd' (Q0), rs1'/rd' (Q1)
    if op == 0:
        if funct3 == 0 and word != 0:                            # c.addi4spn
            return _Insn(2, (2,), rdp)
        if funct3 in (2, 3):                                     # c.lw, c.ld
            return _Insn(2, (rs2p,), rdp, load=True)
        return None
    if op == 1:
        if funct3 in (0, 1):                                     # c.addi / c.nop, c.addiw
            return _Insn(2, (rd,), rd)
        if funct3 in (2, 3):                                     # c.li, c.lui / c.addi16sp
            return _Insn(2, (rd,) if funct3 == 3 and rd == 2 else (), rd)
        if funct3 == 4:
            if bits(word, 11, 10) != 3:                         # c.srli, c.srai, c.andi
                return _Insn(2, (rs2p,), rs2p)
            return _Insn(2, (rs2p, 8 + bits(word, 4, 2)), rs2p)  # c.sub c.xor c.or c.and c.subw c.addw
        if funct3 == 5:                                          # c.j
            imm = (bits(word, 12, 12) << 11 | bits(word, 8, 8) << 10 | bits(word, 10, 9) << 8
                   | bits(word, 6, 6) << 7 | bits(word, 7, 7) << 6 | bits(word, 2, 2) << 5
                   | bits(word, 11, 11) << 4 | bits(word, 5, 3) << 1)
            return _Insn(2, (), 0, target=pc + signed(imm, 12))
        imm = (bits(word, 12, 12) << 8 | bits(word, 6, 5) << 6 | bits(word, 2, 2) << 5
               | bits(word, 11, 10) << 3 | bits(word, 4, 3) << 1)
        return _Insn(2, (rs2p,), 0, target=pc + signed(imm, 9), conditional=True)   # c.beqz, c.bnez
    if op == 2:
        if funct3 == 0:                                          # c.slli
            return _Insn(2, (rd,), rd)
        if funct3 in (2, 3) and rd:                              # c.lwsp, c.ldsp
            return _Insn(2, (2,), rd, load=True)
        if funct3 == 4 and rs2:                                  # c.mv, c.add
            return _Insn(2, (rs2,) if not bits(word, 12, 12) else (rd, rs2), rd)
    return None


def _decode(code: bytes, offset: int, pc: int) -> _Insn | None:
    found = instruction_at(code, offset)
    if found is None:
        return None
    word, size = found
    return _decode_16(word, pc) if size == 2 else _decode_32(word, pc)


def _poll_loop_at(code: bytes, base: int, branch_offset: int) -> PollLoop | None:
    """The poll loop closed by a backward branch at code[branch_offset], if it is one."""
    branch_pc = base + branch_offset
    closing = _decode(code, branch_offset, branch_pc)
    if closing is None or closing.target is None or not branch_pc - MAX_LOOP_BYTES <= closing.target < branch_pc:
        return None
    head = closing.target
    insns: list[tuple[int, _Insn]] = []
    pc = head
    while pc < branch_pc:
        insn = _decode(code, pc - base, pc)
        if insn is None:
            return None
        if insn.target is not None and head <= insn.target <= branch_pc:
            return None                                          # a branch within the loop
        insns.append((pc, insn))
        pc += insn.size
    if pc != branch_pc or not any(insn.load for _, insn in insns):
        return None
    insns.append((branch_pc, closing))
    written = {insn.writes for _, insn in insns} - {0}
    defined: set[int] = set()
    for _, insn in insns:
        if any(r in written and r not in defined for r in insn.reads):
            return None                                          # a value carried between iterations
        if insn.writes:
            defined.add(insn.writes)
    loads = []
    for pc, insn in insns:
        if insn.load:
            word = int.from_bytes(code[pc - base:pc - base + insn.size].ljust(4, b"\0"), "little")
            loads.append(decode_memory_access(word))
    return PollLoop(head, branch_pc, len(insns), tuple(loads))


@functools.lru_cache(maxsize=8)
def _backward_branches(code: bytes) -> tuple[int, ...]:
    """Offsets of every 2-byte-aligned position holding a branch or jump with a negative offset
    (a sign bit set), the only places a loop can close; once a process for the same code (the poll,
    time and idle loops are looked for from them, in both views of SRAM)."""
    halves, words = code_parcels(code)
    found = ((halves & 3) == 1) & ((halves >> 13) >= 5) & ((halves >> 12 & 1) == 1)     # compressed
    found[:-1] |= ((words & 3) == 3) & np.isin(words & 0x7F, (0x63, 0x6F)) & ((words >> 31) == 1)
    return tuple(2 * int(i) for i in np.flatnonzero(found))


def table_key(address: int) -> int:
    """An instruction address as a native counter's tables hold it (_counter.h's table_key: the two
    must agree): in SRAM's uncached view (0x4000_0000), the same bytes' address in the cached one
    (0x8000_0000), so that code runs alike in both views, whichever it was linked for, with one
    entry for both (a poll loop's state is the code's, whichever view the hart runs it in)."""
    if SRAM_UNCACHED_BASE <= address < SRAM_UNCACHED_BASE + SRAM_SIZE:
        return address - SRAM_UNCACHED_BASE + SRAM_BASE
    return address


def collision_free_size(addresses: list[int]) -> int:
    """The size of a native counter's table of instruction addresses (poll-loop heads, CSR sites,
    as table_key gives them) indexed by (address >> 1) & (size - 1): the smallest power of two at
    least twice their number in which no two share a slot, so that a look-up is one compare."""
    addresses = list(set(addresses))
    size = 1
    while size < 2 * len(addresses):
        size *= 2
    while len({(a >> 1) & (size - 1) for a in addresses}) < len(addresses):
        size *= 2
    return size


def loop_table(loops: list[PollLoop]) -> tuple[ctypes.Array, int]:
    """The native counter's table of poll loops (collision_free_size), by table_key (a loop found in
    both views of SRAM has one slot). Returns (slots, mask)."""
    size = collision_free_size([table_key(loop.head) for loop in loops])
    slots = (LoopSlot * size)()
    for loop in loops:
        head = table_key(loop.head)
        slot = slots[(head >> 1) & (size - 1)]
        slot.head, slot.body = head, loop.body
    return slots, size - 1


def find_poll_loops(code: bytes, base: int) -> list[PollLoop]:
    """Every loop in `code` (loaded at `base`) that can only be polling memory (module comment).
    Every 2-byte-aligned position is tried: one that is really the middle of an instruction never
    executes, so a loop found there costs nothing."""
    return list(_poll_loops(code, base))


@functools.lru_cache(maxsize=8)
def _poll_loops(code: bytes, base: int) -> tuple[PollLoop, ...]:
    """find_poll_loops, once a process for the same code (every board of a firmware scans it)."""
    loops = {}
    for offset in _backward_branches(code):
        loop = _poll_loop_at(code, base, offset)
        if loop is not None and loop.head not in loops:
            loops[loop.head] = loop
    return tuple(loops.values())


# --- at run time ---------------------------------------------------------------------------------

def sram_span(address: int, width: int) -> int | None:
    """The SRAM offset of an access of `width` bytes at `address`, in either view (None: not SRAM)."""
    for view in (SRAM_BASE, SRAM_UNCACHED_BASE):
        if view <= address and address + width <= view + SRAM_SIZE:
            return address - view
    return None


def polled_spans(loop: PollLoop, register: "callable") -> list[tuple[int, int]] | None:
    """The SRAM spans a loop reads, from the hart's registers as the loop leaves them (every
    iteration computes the same addresses while memory is unchanged); None when any load reads
    something other than SRAM (a device: the bus's poll detection is for those)."""
    spans = []
    for width, base, offset in loop.loads:
        address = ((register(base) if base else 0) + offset) & (2**64 - 1)
        span = sram_span(address, width)
        if span is None:
            return None
        spans.append((span, width))
    return spans
