"""The K210's two Rocket harts: Unicorn engines with the parts Unicorn leaves out (hart.py), the
fast interpreter beside them (_fast_engine.c), the native instruction counter and cycle model
(_insn_counter.c, timing.py), the poll-loop finder (shared_memory.py), instruction decoding, and
the RISC-V names and numbers (riscv.py: registers, CSRs, causes, interrupts); native.py mirrors
the C extension's structures for ctypes.

May import: emulator.errors, emulator.memory_map, emulator.vtime, and this package. Never the board, the devices
or the front-ends: the board hands a hart what it needs (CsrContext, device windows, hooks)."""
