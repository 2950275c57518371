"""Cycle-approximate timing: what each instruction costs on the K210's Rocket cores.

The K210's two cores are Rocket cores of early 2017 (the chip implements the privileged spec
1.9.1, which rocket-chip left for 1.10 in spring 2017). Kendryte publishes no pipeline figures
beyond "RV64IMAFDC, FPU, 32 KiB instruction and 32 KiB data cache per core", so the figures
below come from rocket-chip's own sources at commit e8c8d2af7 (February 2017) and from SiFive's
manuals for its Rocket-derived cores, with measurements on Rocket where there are some:

  [R]  rocket-chip e8c8d2af7, src/main/scala/rocket/Rocket.scala (5-stage pipeline, hazards and
       bypasses), Multiplier.scala (MulDiv), BTB.scala (BTB, BHT, RAS), tile/FPU.scala (FPU
       pipes: sfmaLatency 3, dfmaLatency 4; the iterative divide/square-root unit), and
       coreplex/Configs.scala (the "big core": MulDivParams(mulUnroll = 8, mulEarlyOut = true,
       divEarlyOut = true), BTBParams(nEntries = 40, nRAS = 2), fastLoadWord = true,
       fastLoadByte = false, fastJAL = false);
  [H]  berkeley-hardfloat DivSqrtRecF64_mulAddZ31.scala (the FPU's divide/square-root unit of
       that time: stages A, B, C, E of 4+6+5+4 cycles for a division, 7+10+6+4 for a root);
  [S]  SiFive FE310-G000 manual (E31, a Rocket of early 2017): 40-entry BTB, 128-entry BHT,
       2-entry RAS (the same sizes as [R]); "correctly predicted control-flow instructions
       result in no penalty. Mispredicted control-flow instructions incur a three-cycle
       penalty"; "LW has a two-cycle result latency, LH, LHU, LB and LBU three, CSR reads
       three"; MUL 5 cycles with an 8-bit-per-cycle multiplier on 32 bits. SiFive FU540 manual
       (U54/E51, 2018): the same pipeline, "DIV ... between a 2-cycle and 65-cycle result
       latency, depending on the operand values";
  [B]  GaloisInc/BESSPIN-riscv-timing-tests (measured on a Rocket in Verilator): a loop of
       DIV, ADDI, BLEU costs about 8 cycles plus one per quotient bit, 72 when dividing by 0.

What the model charges (the table `LATENCY` and the C code in _insn_counter.c):

- Every instruction takes one cycle; Rocket issues one instruction per cycle when nothing
  stalls [R][S].
- Result latencies ([R] hazard logic; [S]): an instruction that reads (or writes) a register
  still being produced stalls until the producer's result latency has passed. The stall is
  worked out once, at load, from the straight run of instructions after each producer (up to
  the first control transfer; the instruction after a transfer counts as using the value, which
  holds for the long latencies of division, where the waiting instruction is rarely far) and
  charged to the producer: max(0, latency - distance to the first instruction that waits).
- Multiply and divide: the iterative unit's cycles from the operands, as Multiplier.scala
  counts them (an early out once the multiplier's remaining bits are zero, 8 bits a cycle; a
  divide skips the quotient's leading zeros, one bit a cycle; 65 iterations when dividing by
  zero); the native counter reads the operands before the instruction executes. A second
  multiply or divide waits for the first one (the unit takes one at a time).
- Floating point ([R] FPU.scala): results of the single-precision FMA, the FP-to-FP and the
  int-to-FP pipes are ready for a dependent FP instruction 4 cycles after issue, the
  double-precision FMA's (4-cycle pipe, scoreboarded) 6; FP results an integer instruction
  reads (compares, moves, conversions) 3; division 22 and square root 30 (either precision:
  one double-precision unit [H], entered from the memory stage and written back a cycle after it
  is done); a second division or root waits for the first.
- Control transfers: Rocket's predictor [R] as it is, per hart: a 40-entry fully associative
  BTB (round-robin replacement, written when a taken transfer was mispredicted), a 128-entry
  BHT of 2-bit entries indexed by pc xor 7 bits of global history (for branches that hit in the
  BTB), a 2-entry return-address stack. A correctly predicted transfer costs nothing more; a
  mispredicted one (direction or target, or a taken one the BTB does not know) 3 cycles [R][S].
  Rocket compares the pc it fetched next with the one computed (mem_wrong_npc [R]), so with the
  caches (--timing rocket) a transfer to the very next instruction is no misprediction;
  --timing rocket-nocache keeps charging it, as before issue 31.
- Fetch after a redirect (with the caches, --timing rocket; the frontend's fetch is modelled with
  the instruction cache): the frontend fetches 4 bytes a cycle (RocketCoreParams: fetchWidth, two
  16-bit parcels with RVC) and the IBuf issues a 4-byte instruction only with both halves
  (IBuf.scala), so a 4-byte instruction at an address 2 mod 4 that a transfer taken (or any
  mispredicted one) leads to waits a cycle for the next fetch packet [R]; so does one that a CSR
  write's, mret's or fence.i's flush refetches from.
- CSR writes flush the pipeline (3 cycles: Rocket of 2017 redirects from the memory stage;
  SiFive's later cores state 5), mret and fence.i too (4 and 3).

Not in the table: cache misses, the uncached alias and device registers being slower than SRAM
(caches.py charges those under --timing rocket). Not modelled (choices, written down): the FPU's
write-port conflicts, special FP operands finishing division early, interrupt entry. The K210's
multiplier configuration is not published: Rocket's default big core is taken.

`--timing ipc1` keeps the earlier model, one cycle per instruction, exactly.
"""
from __future__ import annotations

import enum
import hashlib
import os
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from .riscv import bits, code_parcels

TIMING_ROCKET = "rocket"                    # Rocket's pipeline and its L1 caches (caches.py)
TIMING_ROCKET_NOCACHE = "rocket-nocache"    # Rocket's pipeline, every access a cache hit
TIMING_IPC1 = "ipc1"
TIMING_MODELS = (TIMING_ROCKET, TIMING_ROCKET_NOCACHE, TIMING_IPC1)

WINDOW = 31                  # instructions looked at after a producer (the entry's 5-bit distance)
MISPREDICT_PENALTY = 3       # _insn_counter.c's MISPREDICT_PENALTY
REDIRECT_BUBBLE = 1          # _counter.h's: a 4-byte instruction 2 mod 4 after a redirect (with the caches)
CSR_WRITE_FLUSH = 3          # a CSR write flushes the pipeline from the memory stage [R]
MRET_FLUSH = 4               # mret redirects from write-back [R] (take_pc_wb)
FENCE_I_FLUSH = 3

FP = 32                      # registers 32..63 are f0..f31 in the decoder's register numbers


class Kind(enum.IntEnum):
    """What the native counter does beyond the static extra cycles (_insn_counter.c KIND_*)."""
    PLAIN = 0
    BRANCH = 1
    JAL = 2
    JALR = 3
    MUL = 4
    DIV = 5
    FLUSH = 6      # a CSR write, mret or fence.i: the pipeline refetches from the next pc (no prediction)


# Result latencies in cycles from issue to the issue of an instruction that waits for it
# (1: bypassed, no stall). Sources in the module comment.
LATENCY = {
    "alu": 1,
    "load_word": 2,        # LW, LWU, LD: fastLoadWord bypass from the memory stage [R]; [S] 2
    "load_subword": 3,     # LB, LBU, LH, LHU, SC: slow bypass [R]; [S] 3
    "load_fp": 4,          # FLW, FLD: FP hazards in execute, memory and write-back [R]
    "csr_read": 3,         # [R] CSRs bypass neither from execute nor memory; [S] 3
    "jalr_link": 2,        # [R] ex_cannot_bypass includes jalr
    "fp_single": 4,        # sfma (3-cycle pipe) and the FP-to-FP / int-to-FP pipes [R]
    "fp_double": 6,        # dfma (4-cycle pipe) through the FP scoreboard [R]
    "fp_to_int": 3,        # compares, moves and conversions to integer registers [R]
    "fp_div": 22,          # DivSqrtRecF64 division, 19 cycles in the unit [H] + entry and write-back
    "fp_sqrt": 30,         # square root, 27 cycles in the unit [H] + entry and write-back
}


@dataclass(frozen=True)
class Insn:
    """One decoded instruction, as the timing model sees it."""
    size: int
    kind: Kind = Kind.PLAIN
    writes: int = -1                 # register written (0..31 integer, 32..63 FP), -1 none
    reads: tuple[int, ...] = ()
    latency: int = 1                 # of the value it writes
    unit: str = ""                   # "muldiv" or "fdiv": one operation at a time
    extra: int = 0                   # cycles beyond the first, known statically (flushes)
    ends_run: bool = False           # a control transfer or trap: the straight run ends after it
    rs1: int = 0
    rs2: int = 0
    word: bool = False               # mul/div: the *W form
    lhs_signed: bool = False
    rhs_signed: bool = False
    hi: bool = False                 # mulh*, rem*
    call: bool = False               # jal/jalr writing x1 or x5
    ret: bool = False                # jalr through x1 or x5 that writes neither


def _regs(*numbers: int) -> tuple[int, ...]:
    """Registers read, without x0 (always ready)."""
    return tuple(n for n in numbers if n != 0)


def _written(rd: int) -> int:
    return rd if rd != 0 else -1


def _is_link(register: int) -> bool:
    return register in (1, 5)


def _jump(size: int, kind: Kind, rd: int, rs1: int = 0) -> Insn:
    return Insn(size, kind, writes=_written(rd), reads=_regs(rs1),
                latency=LATENCY["jalr_link"] if kind is Kind.JALR else 1, ends_run=True,
                call=_is_link(rd), ret=kind is Kind.JALR and _is_link(rs1) and not _is_link(rd))


# funct3 of OP / OP-32 with funct7 = 1: (unit kind, lhs signed, rhs signed, hi)
_MULDIV = {0: (Kind.MUL, False, False, False), 1: (Kind.MUL, True, True, True),
           2: (Kind.MUL, True, False, True), 3: (Kind.MUL, False, False, True),
           4: (Kind.DIV, True, True, False), 5: (Kind.DIV, False, False, False),
           6: (Kind.DIV, True, True, True), 7: (Kind.DIV, False, False, True)}


def _decode32(w: int) -> Insn:
    opcode, rd, f3 = w & 0x7F, bits(w, 11, 7), bits(w, 14, 12)
    rs1, rs2, f7 = bits(w, 19, 15), bits(w, 24, 20), bits(w, 31, 25)
    if opcode in (0x37, 0x17):                                   # lui, auipc
        return Insn(4, writes=_written(rd))
    if opcode == 0x6F:
        return _jump(4, Kind.JAL, rd)
    if opcode == 0x67:
        return _jump(4, Kind.JALR, rd, rs1)
    if opcode == 0x63:
        return Insn(4, Kind.BRANCH, reads=_regs(rs1, rs2), ends_run=True)
    if opcode == 0x03:
        subword = f3 in (0, 1, 4, 5)
        return Insn(4, writes=_written(rd), reads=_regs(rs1),
                    latency=LATENCY["load_subword" if subword else "load_word"])
    if opcode == 0x07:
        return Insn(4, writes=FP + rd, reads=_regs(rs1), latency=LATENCY["load_fp"])
    if opcode == 0x23:
        return Insn(4, reads=_regs(rs1, rs2))
    if opcode == 0x27:
        return Insn(4, reads=_regs(rs1) + (FP + rs2,))
    if opcode in (0x13, 0x1B):
        return Insn(4, writes=_written(rd), reads=_regs(rs1))
    if opcode in (0x33, 0x3B):
        if f7 == 1:
            kind, lhs, rhs, hi = _MULDIV[f3]
            return Insn(4, kind, writes=_written(rd), reads=_regs(rs1, rs2), unit="muldiv", rs1=rs1, rs2=rs2,
                        word=opcode == 0x3B, lhs_signed=lhs, rhs_signed=rhs, hi=hi)
        return Insn(4, writes=_written(rd), reads=_regs(rs1, rs2))
    if opcode == 0x2F:                                           # LR, SC, AMOs
        funct5 = f7 >> 2
        reads = _regs(rs1) if funct5 == 0x02 else _regs(rs1, rs2)
        return Insn(4, writes=_written(rd), reads=reads,
                    latency=LATENCY["load_subword" if funct5 == 0x03 else "load_word"])
    if opcode == 0x0F:
        if f3 == 1:
            return Insn(4, Kind.FLUSH, extra=FENCE_I_FLUSH)
        return Insn(4)
    if opcode == 0x73:
        if f3 == 0:                                              # ecall, ebreak, mret, wfi
            if w == 0x30200073:
                return Insn(4, Kind.FLUSH, extra=MRET_FLUSH, ends_run=True)
            return Insn(4, ends_run=True)
        reads = _regs(rs1) if f3 < 4 else ()
        writes_csr = (f3 & 3) == 1 or rs1 != 0
        return Insn(4, Kind.FLUSH if writes_csr else Kind.PLAIN, writes=_written(rd), reads=reads,
                    latency=LATENCY["csr_read"], extra=CSR_WRITE_FLUSH if writes_csr else 0)
    if opcode in (0x43, 0x47, 0x4B, 0x4F):                       # fmadd, fmsub, fnmsub, fnmadd
        double = bits(w, 26, 25) == 1
        return Insn(4, writes=FP + rd, reads=(FP + rs1, FP + rs2, FP + bits(w, 31, 27)),
                    latency=LATENCY["fp_double" if double else "fp_single"])
    if opcode == 0x53:
        return _decode_op_fp(rd, rs1, rs2, f3, f7)
    return Insn(4)


def _decode_op_fp(rd: int, rs1: int, rs2: int, f3: int, f7: int) -> Insn:
    group, double = f7 >> 2, (f7 & 3) == 1
    arithmetic = LATENCY["fp_double" if double else "fp_single"]
    if group in (0x00, 0x01, 0x02):                              # fadd, fsub, fmul
        return Insn(4, writes=FP + rd, reads=(FP + rs1, FP + rs2), latency=arithmetic)
    if group == 0x03:                                            # fdiv
        return Insn(4, writes=FP + rd, reads=(FP + rs1, FP + rs2), latency=LATENCY["fp_div"], unit="fdiv")
    if group == 0x0B:                                            # fsqrt
        return Insn(4, writes=FP + rd, reads=(FP + rs1,), latency=LATENCY["fp_sqrt"], unit="fdiv")
    if group in (0x04, 0x05):                                    # fsgnj*, fmin, fmax
        return Insn(4, writes=FP + rd, reads=(FP + rs1, FP + rs2), latency=LATENCY["fp_single"])
    if group == 0x08:                                            # fcvt.s.d, fcvt.d.s
        return Insn(4, writes=FP + rd, reads=(FP + rs1,), latency=LATENCY["fp_single"])
    if group == 0x14:                                            # feq, flt, fle
        return Insn(4, writes=_written(rd), reads=(FP + rs1, FP + rs2), latency=LATENCY["fp_to_int"])
    if group in (0x18, 0x1C):                                    # fcvt.w*.fmt, fmv.x.*, fclass
        return Insn(4, writes=_written(rd), reads=(FP + rs1,), latency=LATENCY["fp_to_int"])
    if group in (0x1A, 0x1E):                                    # fcvt.fmt.w*, fmv.*.x
        return Insn(4, writes=FP + rd, reads=_regs(rs1), latency=LATENCY["fp_single"])
    return Insn(4)


def _decode16(h: int) -> Insn:
    quadrant, f3 = h & 3, bits(h, 15, 13)
    rd = bits(h, 11, 7)
    rs2 = bits(h, 6, 2)
    rdp, rs2p = 8 + bits(h, 9, 7), 8 + bits(h, 4, 2)     # the 3-bit register fields (x8..x15)
    if quadrant == 0:
        if f3 == 0:                                              # c.addi4spn
            return Insn(2, writes=rs2p, reads=(2,))
        if f3 == 1:                                              # c.fld
            return Insn(2, writes=FP + rs2p, reads=(rdp,), latency=LATENCY["load_fp"])
        if f3 in (2, 3):                                         # c.lw, c.ld
            return Insn(2, writes=rs2p, reads=(rdp,), latency=LATENCY["load_word"])
        if f3 == 5:                                              # c.fsd
            return Insn(2, reads=(rdp, FP + rs2p))
        if f3 in (6, 7):                                         # c.sw, c.sd
            return Insn(2, reads=(rdp, rs2p))
        return Insn(2)
    if quadrant == 1:
        if f3 in (0, 1):                                         # c.addi, c.addiw
            return Insn(2, writes=_written(rd), reads=_regs(rd))
        if f3 in (2, 3):                                         # c.li, c.lui, c.addi16sp
            return Insn(2, writes=_written(rd), reads=_regs(rd) if f3 == 3 and rd == 2 else ())
        if f3 == 4:
            if bits(h, 11, 10) == 3:                             # c.sub ... c.addw
                return Insn(2, writes=rdp, reads=(rdp, rs2p))
            return Insn(2, writes=rdp, reads=(rdp,))             # c.srli, c.srai, c.andi
        if f3 == 5:                                              # c.j
            return _jump(2, Kind.JAL, 0)
        return Insn(2, Kind.BRANCH, reads=(rdp,), ends_run=True)  # c.beqz, c.bnez
    if quadrant == 2:
        if f3 == 0:                                              # c.slli
            return Insn(2, writes=_written(rd), reads=_regs(rd))
        if f3 == 1:                                              # c.fldsp
            return Insn(2, writes=FP + rd, reads=(2,), latency=LATENCY["load_fp"])
        if f3 in (2, 3):                                         # c.lwsp, c.ldsp
            return Insn(2, writes=_written(rd), reads=(2,), latency=LATENCY["load_word"])
        if f3 == 4:
            if not bits(h, 12, 12):
                if rs2 == 0:                                     # c.jr
                    return _jump(2, Kind.JALR, 0, rd)
                return Insn(2, writes=_written(rd), reads=_regs(rs2))   # c.mv
            if rs2 == 0:
                if rd == 0:                                      # c.ebreak
                    return Insn(2, ends_run=True)
                return _jump(2, Kind.JALR, 1, rd)                # c.jalr
            return Insn(2, writes=_written(rd), reads=_regs(rd, rs2))   # c.add
        if f3 == 5:                                              # c.fsdsp
            return Insn(2, reads=(2, FP + rs2))
        return Insn(2, reads=_regs(2, rs2))                      # c.swsp, c.sdsp
    return Insn(2)


@lru_cache(maxsize=65536)
def decode(word: int) -> Insn:
    """The instruction whose first bytes are `word` (little-endian; 16 bits matter for a
    compressed one)."""
    if word & 3 != 3:
        return _decode16(word & 0xFFFF)
    return _decode32(word & 0xFFFF_FFFF)


def _waits_for(producer: Insn, insn: Insn) -> bool:
    """Whether `insn` must wait for `producer`'s result or unit (Rocket stalls in decode on a
    read-after-write or write-after-write hazard, and on a busy iterative unit)."""
    if producer.writes >= 0 and (producer.writes in insn.reads or producer.writes == insn.writes):
        return True
    return bool(producer.unit) and producer.unit == insn.unit


def _distance(insns: list[Insn], slot: int, producer: Insn) -> int:
    """Instructions from the producer at `slot` (of `insns`, one per 2-byte slot of a code
    range) to the first one that waits for it, in the straight run after it (the instruction
    after the run's control transfer counts as waiting)."""
    position = slot + producer.size // 2
    for distance in range(1, WINDOW):
        if position >= len(insns):
            return distance
        insn = insns[position]
        if _waits_for(producer, insn):
            return distance
        if insn.ends_run:
            return distance + 1
        position += insn.size // 2
    return WINDOW


def entry(insn: Insn, distance: int) -> int:
    """The native counter's table entry for an instruction (_insn_counter.c E_* macros)."""
    extra = insn.extra
    if insn.kind not in (Kind.MUL, Kind.DIV):
        extra += max(0, insn.latency - distance)
    value = min(extra, 0xFF) | (int(insn.kind) << 8) | ((insn.size == 4) << 11)
    if insn.kind in (Kind.MUL, Kind.DIV):
        value |= (insn.rs1 << 12) | (insn.rs2 << 17) | (insn.word << 22) | (insn.lhs_signed << 23)
        value |= (insn.hi << 24) | (min(distance, 31) << 25) | (insn.rhs_signed << 30)
    else:
        value |= (insn.call << 30) | (insn.ret << 31)
    return value


@dataclass
class CycleTable:
    """Entries for every 2-byte slot of [base, base + 2 * len(entries)) (the firmware's code)."""
    base: int
    entries: np.ndarray      # uint32, kept alive while a hart's counter points at it

    @property
    def end(self) -> int:
        return self.base + 2 * len(self.entries)


_TABLES: dict[tuple, CycleTable] = {}     # by code: boards of one firmware share its table (read only)
_TABLES_KEPT = 8

# Built tables are also kept on disk, so that each new process (every `python -m emulator run`)
# does not decode the firmware again: a fifth of a second for ours, more than many short runs
# take. A file is named by a digest of this module's source (the decoding and the figures) and
# of the code, so a changed model or firmware never reads a stale table. A cache that cannot be
# read or written is passed over: the table is then built as without one.
CACHE_ENVIRONMENT = "K210_MODEL_CACHE"     # a folder to use instead of the user's cache folder
_CACHE_FILES_KEPT = 32
# Code this short is decoded in about as long as a file takes to write (some 2 ms for 4 KiB, 1 ms to
# write and prune): a test's or a demo's small program is not kept, and does not push a firmware's
# table out of the files kept
_CACHE_MIN_BYTES = 4096


def table_cache_folder() -> Path:
    """Where tables are kept: $K210_MODEL_CACHE, else $XDG_CACHE_HOME/k210-board-model, else
    ~/.cache/k210-board-model."""
    chosen = os.environ.get(CACHE_ENVIRONMENT)
    if chosen:
        return Path(chosen)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "k210-board-model"


def build_table(code_ranges: list[tuple[int, bytes]]) -> CycleTable | None:
    """The cycle table of the firmware's code: every 2-byte-aligned position is decoded as if an
    instruction began there (a position that is really the middle of one never executes)."""
    if not code_ranges:
        return None
    key = tuple((address, bytes(code)) for address, code in code_ranges)
    table = _TABLES.get(key)
    if table is None:
        if sum(len(code) for _, code in code_ranges) < _CACHE_MIN_BYTES:
            table = _build_table(code_ranges)
        else:
            digest = _digest(key)
            table = _read_cached(digest, code_ranges)
            if table is None:
                table = _build_table(code_ranges)
                _write_cached(digest, table)
        if len(_TABLES) >= _TABLES_KEPT:
            _TABLES.pop(next(iter(_TABLES)))
        _TABLES[key] = table
    return table


def _digest(key: tuple) -> str:
    digest = hashlib.sha256(Path(__file__).read_bytes())
    for address, code in key:
        digest.update(address.to_bytes(8, "little") + len(code).to_bytes(8, "little") + code)
    return digest.hexdigest()


def _table_bounds(code_ranges: list[tuple[int, bytes]]) -> tuple[int, int]:
    base = min(address for address, _ in code_ranges) & ~1
    end = max(address + len(code) for address, code in code_ranges)
    return base, (end - base + 1) // 2


def _read_cached(digest: str, code_ranges: list[tuple[int, bytes]]) -> CycleTable | None:
    """The table kept under `digest`, or None when there is none of the right length."""
    base, slots = _table_bounds(code_ranges)
    path = table_cache_folder() / f"{digest}.u32"
    try:
        entries = np.fromfile(path, dtype="<u4")
    except (OSError, ValueError):
        return None
    if len(entries) != slots:
        return None
    try:
        os.utime(path)              # the tables kept are the ones used last, not written last
    except OSError:
        pass
    return CycleTable(base, entries.astype(np.uint32))


def _write_cached(digest: str, table: CycleTable) -> None:
    """Writes the table under its digest (whole or not at all: another process may be reading)
    and keeps only the _CACHE_FILES_KEPT tables used last."""
    folder = table_cache_folder()
    part = None
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, suffix=".part", delete=False) as handle:
            part = Path(handle.name)
            handle.write(table.entries.astype("<u4").tobytes())
        os.replace(part, folder / f"{digest}.u32")
        part = None
        with os.scandir(folder) as found:     # (a fifth of pathlib's glob's time)
            tables = [(file.stat().st_mtime, file.path) for file in found if file.name.endswith(".u32")]
        for _, stale in sorted(tables)[:-_CACHE_FILES_KEPT]:
            Path(stale).unlink(missing_ok=True)
    except OSError:
        if part is not None:
            part.unlink(missing_ok=True)


def _build_table(code_ranges: list[tuple[int, bytes]]) -> CycleTable:
    base, slots = _table_bounds(code_ranges)
    entries = np.zeros(slots, dtype=np.uint32)
    for address, code in code_ranges:
        first = (address - base + 1) // 2
        start = 2 * first - (address - base)
        # the 4 bytes at each 2-byte position (zeros past the code's end), as words
        words = code_parcels(code[start:] + bytes(4))[1][:len(range(start, len(code) - 1, 2))].tolist()
        insns = [decode(word) for word in words]
        row = []
        for index, (word, insn) in enumerate(zip(words, insns)):
            # a call's link register is read by the return, far later: no stall is charged for it
            needs_distance = (insn.latency > 1 and not insn.ends_run) or insn.kind in (Kind.MUL, Kind.DIV)
            row.append(_entry_of_word(word, _distance(insns, index, insn) if needs_distance else WINDOW))
        entries[first:first + len(row)] = row
    return CycleTable(base, entries)


@lru_cache(maxsize=65536)
def _entry_of_word(word: int, distance: int) -> int:
    """entry(decode(word), distance), looked up by the word: hashing an Insn (a dataclass of a dozen
    fields) for entry's own cache took most of a table's building."""
    return entry(decode(word), distance)
