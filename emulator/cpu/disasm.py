"""Disassembly of single instructions for fault reports (capstone, RV64GC)."""
from __future__ import annotations

import capstone

_engine = capstone.Cs(capstone.CS_ARCH_RISCV, capstone.CS_MODE_RISCV64 | capstone.CS_MODE_RISCVC)


def disassemble_one(code: bytes, address: int) -> str:
    """The instruction at the start of `code`, as text ('?' if it does not decode)."""
    for insn in _engine.disasm(code, address, 1):
        return f"{insn.mnemonic} {insn.op_str}".strip()
    return "?"
