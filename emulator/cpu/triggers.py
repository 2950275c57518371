"""The hardware breakpoint of the K210's Rocket: one trigger per hart (tselect, tdata1, tdata2), as
rocket-chip of 2017-03-14 (commit 1322a026, the last before privileged spec 1.10) has it in
rocket/Breakpoint.scala, rocket/CSR.scala and rocket/Rocket.scala. Its one count is the default
(`RocketCoreParams.nBreakpoints = 1`): the K210's is not documented.

tdata1 (Rocket's BPControl, most significant field first):

| bits  | field   | here |
|-------|---------|------|
| 63:60 | type    | 2 (address match), fixed |
| 59    | dmode   | 0: writable only from debug mode, which the model has not |
| 58:53 | maskmax | 4, fixed: a NAPOT match covers up to 2^4 bytes |
| 52:13 | -       | 0 |
| 12    | action  | 0: 1 (enter debug mode) only with dmode |
| 11    | chain   | 0: the last (only) trigger |
| 10:9  | -       | 0 |
| 8:7   | match   | 0 exact, 1 NAPOT (the address's trailing ones, up to 3, widen the match), 2 at or above, 3 below |
| 6     | m       | fires in M-mode |
| 5     | h       | 0 |
| 4     | s       | fires in S-mode |
| 3     | u       | fires in U-mode |
| 2     | x       | before an instruction at the address is executed |
| 1     | w       | before a store (SC and AMOs too) to it |
| 0     | r       | before a load (LR, SC and AMOs too) from it |

tdata2 holds the address, 39 bits (vaddrBits), read back sign-extended. A match raises the
breakpoint exception (mcause 3) before the instruction has any effect; mtval (mbadaddr) is the pc
for an execute match, the access's address for a load or store. An execute match ranks below an
interrupt and above an illegal instruction; a load or store match above misalignment and access
faults. A chip reset clears action, dmode, r, w and x and keeps the rest."""
from __future__ import annotations

from dataclasses import dataclass

from .decode import READS, WRITES, memory_access_kind
from .riscv import bits

CSR_TSELECT, CSR_TDATA1, CSR_TDATA2 = 0x7A0, 0x7A1, 0x7A2
TRIGGER_CSRS = (CSR_TSELECT, CSR_TDATA1, CSR_TDATA2)

TYPE_ADDRESS_MATCH = 2
MASK_MAX = 4
VADDR_BITS = 39
VADDR_MASK = (1 << VADDR_BITS) - 1
# the bits a write keeps outside debug mode: match, m, s, u, x, w, r
WRITABLE = (3 << 7) | (1 << 6) | (1 << 4) | (1 << 3) | 7
R, W, X = READS, WRITES, 4     # tdata1's r, w, x bits (decode.py's access kinds are r and w)
MODE_BITS = {0: 1 << 3, 1: 1 << 4, 3: 1 << 6}    # privilege level -> its enable bit (U, S, M)


@dataclass
class Trigger:
    control: int = 0     # the writable bits of tdata1
    address: int = 0     # tdata2, VADDR_BITS wide

    def tdata1(self) -> int:
        return TYPE_ADDRESS_MATCH << 60 | MASK_MAX << 53 | self.control

    def tdata2(self) -> int:
        value = self.address
        return value - (1 << VADDR_BITS) if value >> (VADDR_BITS - 1) else value

    def fires(self, kind: int, privilege: int, address: int) -> bool:
        """Whether an access of `kind` (R, W, X, or R | W for an AMO) at `address` in mode
        `privilege` matches (BreakpointUnit)."""
        return bool(self.control & kind) and bool(self.control & MODE_BITS.get(privilege, 0)) \
            and self._matches(address & VADDR_MASK)

    def _matches(self, x: int) -> bool:
        match = bits(self.control, 8, 7)
        if match & 2:
            return (x >= self.address) != bool(match & 1)
        # BP.mask: bit 0 from match's low bit, each further bit while the address's bits below are ones
        mask, bit = 0, match & 1
        for i in range(MASK_MAX):
            if not bit:
                break
            mask |= 1 << i
            bit = (self.address >> i) & 1
        return (x | mask) == (self.address | mask)


class TriggerUnit:
    """A hart's trigger registers and what they watch."""

    def __init__(self) -> None:
        self.trigger = Trigger()

    @property
    def armed(self) -> bool:
        """Whether anything can fire (a hook watches the hart only then)."""
        control = self.trigger.control
        return bool(control & (R | W | X)) and bool(control & ((1 << 6) | (1 << 4) | (1 << 3)))

    def read(self, csr: int) -> int:
        if csr == CSR_TSELECT:
            return 0              # one trigger: tselect has no bits
        if csr == CSR_TDATA1:
            return self.trigger.tdata1()
        return self.trigger.tdata2() & (2**64 - 1)

    def write(self, csr: int, value: int) -> None:
        if csr == CSR_TDATA1:
            self.trigger.control = value & WRITABLE
        elif csr == CSR_TDATA2:
            self.trigger.address = value & VADDR_MASK

    def reset(self) -> None:
        self.trigger.control &= ~(R | W | X)

    def check(self, word: int, pc: int, privilege: int, effective_address: int | None) -> int | None:
        """mtval of the breakpoint exception the instruction `word` at `pc` raises before it runs,
        or None. `effective_address` is its load/store address, if it has one."""
        if self.trigger.fires(X, privilege, pc):
            return pc
        if effective_address is not None:
            kind = memory_access_kind(word)
            if kind and any(self.trigger.fires(k, privilege, effective_address) for k in (R, W) if kind & k):
                return effective_address & (2**64 - 1)
        return None
