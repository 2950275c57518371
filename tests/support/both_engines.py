"""Running one program on both engines of a hart, the precise one (Unicorn) and the fast one
(_fast_engine.c), and what they must agree on; the operand values and instruction lists the random
programs are made of. For unit/cpu/test_fast_engine.py's seeded walks and slow/test_engines_agree.py's
Hypothesis programs."""
from __future__ import annotations

from unicorn import riscv_const as rv

from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE
from emulator.cpu.timing import TIMING_ROCKET
from k210_fixtures import make_board, program, reg, run_to_done

GPRS = ["ra", "sp", "gp", "tp", "t0", "t1", "t2", "s0", "s1", "a0", "a1", "a2", "a3", "a4", "a5", "a6", "a7",
        "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "t3", "t4", "t5", "t6"]

# The FPU on, its flags clear, before each program: fflags must stay what the program's own
# instructions make them (Unicorn reads them only with the FPU on)
FPU_ON = """
    li      t0, 3 << 13
    csrs    mstatus, t0
    fsflags zero
"""


def run_on(engine: str, source: str, data: str = "", timing: str = TIMING_ROCKET, max_time_s: float = 0.05):
    board = make_board(program(FPU_ON + source, data=data), timing=timing, engine=engine)
    run_to_done(board, max_time_s=max_time_s)
    return board


def run_on_both(source: str, data: str = "", timing: str = TIMING_ROCKET):
    """The program run on the precise engine, then on the fast one: (precise board, fast board)."""
    return run_on(ENGINE_PRECISE, source, data, timing), run_on(ENGINE_FAST, source, data, timing)


def state(board) -> dict:
    """What both engines must agree on (fflags too: the board's own float arithmetic between a hart's
    instructions must not raise the guest's flags)."""
    hart = board.harts[0]
    return {"registers": [reg(board, name) for name in GPRS], "fflags": reg(board, "fflags") & 0x1F,
            "executed": hart.executed, "cycles": hart.cycles, "stall_cycles": hart.stall_cycles,
            "mispredicts": hart.mispredicts, "pc": hart.pc}


def fp_state(board) -> dict:
    hart = board.harts[0]
    return {**state(board), "f": [hart.uc.reg_read(getattr(rv, f"UC_RISCV_REG_F{n}")) for n in range(32)],
            "fcsr": hart.uc.reg_read(rv.UC_RISCV_REG_FCSR), "mstatus": hart.uc.reg_read(rv.UC_RISCV_REG_MSTATUS)}


# The operands where IEEE arithmetic and the RISC-V rules have their corner cases, and the
# instructions the random programs draw from.
SINGLE_VALUES = [0x00000000, 0x80000000, 0x3F800000, 0xBF800000, 0x3FC00000, 0x3DCCCCCD, 0x7F7FFFFF, 0xFF7FFFFF,
                 0x00800000, 0x80800000, 0x00000001, 0x807FFFFF, 0x7F800000, 0xFF800000, 0x7FC00000, 0x7F800001,
                 0x4F000000, 0xCF000000, 0x4F800000, 0x5F000000, 0x5F800000, 0xDF000000, 0x3F000000, 0xBF000000,
                 0x40200000, 0x3EAAAAAB, 0x00400000, 0x33800000]
DOUBLE_VALUES = [0x0000000000000000, 0x8000000000000000, 0x3FF0000000000000, 0xBFF0000000000000,
                 0x3FF8000000000000, 0x3FB999999999999A, 0x7FEFFFFFFFFFFFFF, 0xFFEFFFFFFFFFFFFF,
                 0x0010000000000000, 0x0000000000000001, 0x800FFFFFFFFFFFFF, 0x7FF0000000000000,
                 0xFFF0000000000000, 0x7FF8000000000000, 0x7FF0000000000001, 0x41E0000000000000,
                 0xC1E0000000000000, 0xC1E0000000200000, 0x41F0000000000000, 0x43E0000000000000,
                 0x43F0000000000000, 0xC3E0000000000000, 0x3FE0000000000000, 0xBFE0000000000000,
                 0x3FE8000000000000, 0x4004000000000000, 0x36A0000000000000, 0x47EFFFFFE0000000,
                 0x380FFFFFC0000000]
INTEGER_VALUES = [0, 1, -1, 7, 0x7FFFFFFF, -0x80000000, 0xFFFFFFFF, 0x7FFFFFFFFFFFFFFF, -0x8000000000000000,
                  0x1000001, 0x20000001, 0x123456789ABCDEF1, -3]

THREE = ["fmadd", "fmsub", "fnmsub", "fnmadd"]
TWO = ["fadd", "fsub", "fmul", "fdiv", "fsgnj", "fsgnjn", "fsgnjx", "fmin", "fmax"]
ROUNDED = {"fadd", "fsub", "fmul", "fdiv", "fsqrt", *THREE}
COMPARE = ["feq", "flt", "fle"]
ROUNDING = ["rne", "rtz", "rdn", "rup", "rmm", "dyn"]

INTEGER_OPS = ["add", "sub", "sll", "slt", "sltu", "xor", "srl", "sra", "or", "and", "addw", "subw", "sllw", "srlw",
               "sraw", "mul", "mulh", "mulhsu", "mulhu", "div", "divu", "rem", "remu", "mulw", "divw", "divuw", "remw",
               "remuw"]
IMMEDIATE_OPS = ["addi", "slti", "sltiu", "xori", "ori", "andi", "addiw"]
SHIFT_OPS = [("slli", 64), ("srli", 64), ("srai", 64), ("slliw", 32), ("srliw", 32), ("sraiw", 32)]
LOADS = [("lb", 1), ("lh", 2), ("lw", 4), ("ld", 8), ("lbu", 1), ("lhu", 2), ("lwu", 4)]
STORES = [("sb", 1), ("sh", 2), ("sw", 4), ("sd", 8)]
