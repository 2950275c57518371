"""What the K210's buses do with accesses a register table does not take as they are (bus.py,
docs/design/board-model.md "What the bus does"): by default the model answers them as the chip does and warns,
naming hart, pc, instruction and address; with --strict the run stops at the first one.

Each idiom has a small program; the facts and their sources are in its table there."""
from __future__ import annotations

import json

import pytest

from suite import GOLDEN, GOLDEN_FRAMES, run_emulator
from emulator.devices import plic as p
from emulator.devices import sysctl as sc
from unicorn import riscv_const as rv

from emulator.errors import UnmodelledAccess
from emulator.cpu.riscv import IRQ_MSI
from k210_fixtures import make_board, program, reg, route_uarths_to_the_console, run_to_done, run_until, symbol

PLIC = 0x0C00_0000
SYSCTL = 0x5044_0000
HANDLER = """
    j       done
    .balign 4
handler:
    csrr    s8, mcause
    csrr    s9, mepc
    csrr    s10, mtval
    j       done
"""
SET_MTVEC = """
    la      t0, handler
    csrw    mtvec, t0
"""


def warning_about(board, address: int, instruction: str = "") -> str:
    """The one warning naming an access at `address` (by the instruction whose text starts so)."""
    found = [w for w in board.warnings if f"at 0x{address:08x}:" in w and f"({instruction}" in w]
    assert len(found) == 1, board.warnings
    return found[0]


# --- TileLink devices (CLINT, PLIC, UARTHS, GPIOHS): fields written when a store covers them ---------

PLIC_PRIORITY_BYTE = """
    li      t0, 0x0C000000
    li      t1, 5
    sw      t1, 4(t0)                 # source 1's priority = 5
    li      t1, 7
bad:
    sb      t1, 4(t0)                 # issue 10: firmware that ran on real Docks does this
    lw      s1, 4(t0)
"""


def test_byte_store_to_a_plic_priority_is_ignored():
    """A priority is one 32-bit field in the K210's PLIC: a byte store does not cover it."""
    board = make_board(program(PLIC_PRIORITY_BYTE))
    run_to_done(board)
    assert reg(board, "s1") == 5
    text = warning_about(board, PLIC + 4)
    assert f"hart 0 at pc 0x{symbol(board, 'bad'):08x} <bad> (sb t1, 4(t0)): store of 1 bytes" in text
    assert "8-bit store to the 32-bit register PLIC.priority1: it covers no whole field" in text
    assert board.bus.questionable == {"narrow store": 1}


def test_byte_stores_write_the_plic_enable_bits_they_cover():
    """Enables are one field per bit: a byte store sets the eight sources it covers."""
    board = make_board(program("""
        li      t0, 0x0C002000            # enables of context 0, sources 0-31
        li      t1, 0xFF
        sb      t1, 1(t0)                 # sources 8-15
        li      t1, 0x0101
        sh      t1, 6(t0)                 # sources 48 and 56
        lw      s1, 0(t0)
        lw      s2, 4(t0)
    """))
    run_to_done(board)
    assert reg(board, "s1") == 0xFF00 and reg(board, "s2") == 0x0101_0000
    # each store covers every field it touches: what the register map declares, no warning
    assert board.warnings == [] and board.bus.questionable == {}


def test_byte_store_to_a_plic_priority_stops_a_strict_run():
    board = make_board(program(PLIC_PRIORITY_BYTE), strict=True)
    with pytest.raises(UnmodelledAccess) as info:
        run_to_done(board)
    assert "(sb t1, 4(t0)): store of 1 bytes at 0x0c000004" in str(info.value)
    assert "PLIC.priority1 is a 32-bit register; a 8-bit access is not supported by the model" in str(info.value)


def test_narrow_stores_that_cover_no_whole_field_are_ignored():
    """msip and the halves of mtimecmp are 32-bit fields in the K210's CLINT, every GPIOHS
    register one 32-bit field: a byte or halfword store leaves them as they were."""
    board = make_board(program("""
        li      t0, 0x02004000
        li      t1, 5
        sw      t1, 0(t0)                 # mtimecmp0, low half (a 32-bit field: taken)
        sw      zero, 4(t0)
        li      t1, 0x7F
        sb      t1, 1(t0)
        ld      s1, 0(t0)
        li      t0, 0x02000000
        li      t1, 1
        sb      t1, 0(t0)                 # msip0
        lw      s2, 0(t0)
        li      t0, 0x38001000
        sh      t1, 0x08(t0)              # GPIOHS output_en
        lw      s3, 0x08(t0)
    """))
    run_to_done(board)
    assert (reg(board, "s1"), reg(board, "s2"), reg(board, "s3")) == (5, 0, 0)
    assert not board.mip(0, board.time) >> IRQ_MSI & 1
    assert "no whole field of the register" in warning_about(board, 0x0200_0000)
    assert "GPIOHS.output_en" in warning_about(board, 0x3800_1008)
    assert board.bus.questionable == {"narrow store": 3}


UARTHS_BYTE_STORES = """
    li      t0, 0x38000000
    li      t1, 1
    sw      t1, 0x08(t0)              # txctrl.txen
    li      t1, 'K'
first:
    sb      t1, 0(t0)                 # txdata's 8-bit data field
    li      t1, 10
    sb      t1, 0(t0)
    li      t1, 0x7F
    sh      t1, 0x18(t0)              # div: one 16-bit field, covered whole
    lw      s1, 0x18(t0)
    li      t1, 0x55
half:
    sb      t1, 0x18(t0)              # half of div's field: the router leaves div as it is
    lw      s2, 0x18(t0)
"""


@pytest.mark.parametrize("strict", [False, True])
def test_byte_store_to_uarths_txdata_sends_the_byte(strict):
    """issue 32, item 11: txdata's data is an 8-bit field at [7:0] (sifive-blocks' UART): a `sb` to
    it is a store the register map declares, carried out without a warning, and --strict takes it;
    so does a `sh` covering div's 16-bit field. A byte of div is still answered with a warning
    (the router writes no field it covers only in part), or stops a strict run."""
    sent = bytearray()
    board = make_board(program(UARTHS_BYTE_STORES), console=sent.append, strict=strict)
    route_uarths_to_the_console(board)
    if strict:
        with pytest.raises(UnmodelledAccess, match=r"<half> \(sb t1, 0x18\(t0\)\): store of 1 bytes at 0x38000018"):
            run_to_done(board)
        assert reg(board, "s1") == 0x7F          # the byte stores to txdata and the sh to div went through
        return
    run_until(board, lambda b: len(sent) == 2, max_time_s=0.01)
    run_to_done(board)
    assert bytes(sent) == b"K\n"
    assert (reg(board, "s1"), reg(board, "s2")) == (0x7F, 0x7F)
    assert [w for w in board.warnings if "UARTHS.txdata" in w] == []
    assert "8-bit store to the 32-bit register UARTHS.div: it covers no whole field" in \
        warning_about(board, 0x3800_0018)
    assert board.bus.questionable == {"narrow store": 1}


def test_a_putc_loop_of_byte_stores_is_one_warning_counted():
    """A loop storing every character with the same questionable `sb` (here to a PLIC priority,
    whose 32-bit field a byte does not cover): one warning, counted, not one per character value
    (the text names no value; it used to, 150 for one C hello)."""
    board = make_board(program("""
        li      t0, 0x0C000000
        la      t2, text
    next:
        lbu     t1, 0(t2)
        beqz    t1, done
    putc:
        sb      t1, 4(t0)
        addi    t2, t2, 1
        j       next
    """, data="text: .byte 97, 98, 99, 10, 0"))
    run_to_done(board)
    putc = [w for w in board.warnings if f"pc 0x{symbol(board, 'putc'):08x} <putc>" in w]
    assert len(putc) == 1 and "(4 times in all" in putc[0], board.warnings
    assert board.bus.questionable == {"narrow store": 4}


def test_a_byte_load_of_the_claim_register_claims():
    """A load is the whole register read with its side effect, whatever its width."""
    board = make_board(program("""
        li      t0, 0x0C200004            # claim/complete, context 0
        lbu     s1, 0(t0)
        lbu     s2, 0(t0)
    """))
    board.plic.write(p.PRIORITY + 4 * 5, 4, 1, 0.0)
    board.plic.write(p.ENABLE, 4, 1 << 5, 0.0)
    board.plic.pending.add(5)
    run_to_done(board)
    assert (reg(board, "s1"), reg(board, "s2")) == (5, 0)   # claimed by the first load
    assert 5 in board.plic.in_service


def test_an_offset_without_a_register_reads_0_on_tilelink():
    """The SDK's plic_init writes priority[0]: the K210's PLIC has that register (it reads 0),
    so no warning. UARTHS has nothing at 0x20: its register router answers 0."""
    source = """
        li      t0, 0x0C000000
        li      t1, 3
        sw      t1, 0(t0)
        lw      s1, 0(t0)
        li      t0, 0x38000000
        sw      t1, 0x20(t0)
        lw      s2, 0x20(t0)
    """
    board = make_board(program(source))
    run_to_done(board)
    assert (reg(board, "s1"), reg(board, "s2")) == (0, 0)
    assert "UARTHS has no register at offset 0x20; its TileLink register router ignores the store" in \
        warning_about(board, 0x3800_0020, "sw")
    assert board.bus.questionable == {"no register": 2}
    with pytest.raises(UnmodelledAccess, match="UARTHS has no register at offset 0x20"):
        run_to_done(make_board(program(source), strict=True))


# --- APB devices (SYSCTL, FPIOA, SPI0, SPI1): no byte strobes ---------------------------------------

def test_apb_narrow_store_writes_the_whole_register_with_the_value_repeated():
    board = make_board(program("""
        li      t0, 0x50440000
        li      t1, 0xAB
        sb      t1, 0x3D(t0)              # clk_th1, byte 1
        lw      s1, 0x3C(t0)
        lbu     s2, 0x3E(t0)
        li      t1, 0x1234
        sh      t1, 0x3E(t0)
        lwu     s3, 0x3C(t0)
    """))
    run_to_done(board)
    assert reg(board, "s1") == 0xFFFF_FFFF_ABAB_ABAB          # lw sign-extends
    assert reg(board, "s2") == 0xAB
    assert reg(board, "s3") == 0x1234_1234
    assert "APB has no byte strobes" in warning_about(board, SYSCTL + 0x3D)
    assert "8-bit load from the 32-bit register SYSCTL.clk_th1" in warning_about(board, SYSCTL + 0x3E, "lbu")
    assert "repeated in every byte lane" in warning_about(board, SYSCTL + 0x3E, "sh")


# --- 64-bit accesses to two 32-bit registers ---------------------------------------------------------

def test_64_bit_access_to_two_32_bit_registers_is_two_32_bit_accesses():
    """SYSCTL 0x60 holds reset_status, 0x64 dma_sel0 (issue 10: firmware that ran on real Docks
    does this); the PLIC's priorities 2 and 3 share a doubleword too."""
    board = make_board(program("""
        li      t0, 0x50440000
    load:
        ld      s1, 0x60(t0)
        li      t1, 0x0000000500000001
    store:
        sd      t1, 0x60(t0)
        lw      s2, 0x64(t0)
        li      t0, 0x0C000000
        li      t1, 0x0000000600000003
        sd      t1, 8(t0)
        lw      s3, 8(t0)
        lw      s4, 12(t0)
    """))
    board.sysctl.values[sc.DMA_SEL0] = 0x2A
    run_to_done(board)
    assert reg(board, "s1") == 0x2A << 32 | 1                  # reset_status (1 after reset) | dma_sel0 << 32
    assert reg(board, "s2") == 5 and board.sysctl.values[0x60] == 1
    assert (reg(board, "s3"), reg(board, "s4")) == (3, 6)
    pair = "SYSCTL.reset_status and SYSCTL.dma_sel0 are 32-bit registers: the bus makes the 64-bit"
    assert [w.split("] ", 1)[1] for w in board.warnings if pair in w] == [
        f"hart 0 at pc 0x{symbol(board, 'load'):08x} <load> (ld s1, 0x60(t0)): load of 8 bytes at 0x50440060: "
        f"{pair} load two 32-bit ones, the lower address first",
        f"hart 0 at pc 0x{symbol(board, 'store'):08x} <store> (sd t1, 0x60(t0)): store of 8 bytes at 0x50440060: "
        f"{pair} store two 32-bit ones, the lower address first"]
    assert board.bus.questionable == {"64-bit access to 32-bit registers": 3}


# --- read-only and write-only registers ----------------------------------------------------------------

def test_a_store_to_a_read_only_register_is_ignored_and_a_write_only_one_reads_0():
    board = make_board(program("""
        li      t0, 0x0C001000            # PLIC pending0
        lw      s3, 0(t0)
        li      t1, -1
        sw      t1, 0(t0)
        lw      s1, 0(t0)
        li      s0, 0x50440000
        lw      t0, 0x2c(s0)
        ori     t0, t0, 1 << 1            # DMA clock
        sw      t0, 0x2c(s0)
        li      t0, 0x50000000
        ld      s2, 0x198(t0)             # channel 0 intclear, write-only
    """))
    run_to_done(board)
    assert reg(board, "s1") == reg(board, "s3") != 0xFFFF_FFFF_FFFF_FFFF   # whatever was pending before
    assert reg(board, "s2") == 0
    assert "PLIC.pending0 is read-only: the store is ignored" in warning_about(board, PLIC + 0x1000)
    assert "DMAC.ch0_intclear is write-only: the load reads 0" in warning_about(board, 0x5000_0198)


# --- the DMAC's 32-bit AHB port --------------------------------------------------------------------------

def test_32_bit_accesses_reach_halves_of_the_dmac_registers():
    board = make_board(program("""
        li      s0, 0x50440000
        lw      t0, 0x2c(s0)
        ori     t0, t0, 1 << 1
        sw      t0, 0x2c(s0)
        li      s1, 0x50000000
        lwu     s2, 0x08(s1)              # compver, low half
        lw      s3, 0x0C(s1)              # compver, high half
        li      t0, 3
        sw      t0, 0x10(s1)              # cfg, low half
        li      t0, 0x55
        sb      t0, 0x104(s1)             # ch0 sar, byte 4
    """))
    run_to_done(board)
    assert (reg(board, "s2"), reg(board, "s3")) == (0x3130_302A, 0)
    assert board.dmac.values[0x10] == 3
    assert board.dmac.values[0x100] == 0x55 << 32
    assert "the AHB port writes the addressed bytes only" in warning_about(board, 0x5000_0104)


# --- addresses no device answers ------------------------------------------------------------------------

@pytest.mark.parametrize("instruction, cause", [("lw t1, 8(t0)", 5), ("sw t1, 8(t0)", 7)])
def test_an_access_nothing_answers_is_an_access_fault(instruction, cause):
    board = make_board(program(SET_MTVEC + f"""
        li      t0, 0x60000000
    bad:
        {instruction}
    """ + HANDLER))
    run_to_done(board)
    assert reg(board, "s8") == cause
    assert reg(board, "s9") == symbol(board, "bad")
    assert reg(board, "s10") == 0x6000_0008
    assert f"access fault (mcause {cause}, mtval 0x60000008)" in warning_about(board, 0x6000_0008)


def test_the_debug_region_answers_outside_debug_mode():
    """A `sb` to address 9 (a jump into the middle of a loop) did not stop the real chip."""
    source = """
        li      t1, 0x5A
        sb      t1, 9(zero)
        li      t0, 0x100
        lw      s1, 0(t0)
    """
    board = make_board(program(SET_MTVEC + source + HANDLER))
    run_to_done(board)
    assert reg(board, "s1") == 0 and reg(board, "s8") == 0             # no trap
    assert "the store is ignored" in warning_about(board, 0x9)
    assert board.bus.questionable == {"debug region": 2}
    with pytest.raises(UnmodelledAccess, match="store of 1 bytes at 0x00000009: no device or memory answers"):
        run_to_done(make_board(program(source), strict=True))


# --- addresses with upper bits set: the K210's physical addresses are 32 bits -------------------------

UPPER_HALF = 0x1234_5678_0000_0000


def test_a_return_through_an_address_with_a_clobbered_upper_half_runs_on_at_its_low_half():
    """Issue 10: a saved return address whose upper 32 bits a later store overwrote; the real chip
    fetched from its low 32 bits and went on."""
    board = make_board(program(SET_MTVEC + """
        la      t0, saved
        la      t1, back
        sd      t1, 0(t0)
        li      t1, 0x12345678
        sw      t1, 4(t0)                 # the later store over the upper half
        ld      ra, 0(t0)
        li      s1, 0
        ret
    back:
        li      s1, 1
        auipc   s2, 0                     # where the hart runs now
        la      t0, done                  # pc-relative, so in the upper half too: clear it
        slli    t0, t0, 32
        srli    t0, t0, 32
        jr      t0
    """ + HANDLER, data="saved: .dword 0\n"))
    run_to_done(board)
    assert reg(board, "s1") == 1 and reg(board, "s8") == 0        # back reached, no trap
    target = UPPER_HALF | symbol(board, "back")
    assert reg(board, "s2") == target + 2          # the model keeps the pc's upper half (docs/design/board-model.md)
    assert board.bus.questionable == {"upper address bits": 1}
    assert f"reaches 0x{symbol(board, 'back'):08x}" in warning_about(board, target)


def test_loads_and_stores_with_upper_bits_reach_sram_and_devices_at_their_low_half():
    board = make_board(program(SET_MTVEC + f"""
        la      t0, cell
        li      t2, {UPPER_HALF:#x}
        or      t0, t0, t2
        li      t1, 0x5A5A
        sd      t1, 0(t0)                 # SRAM through the upper half
        la      t3, cell
        ld      s1, 0(t3)                 # ... is the cell
        li      t4, 0x0C000004
        or      t4, t4, t2
        li      t1, 6
        sw      t1, 0(t4)                 # PLIC source 1's priority through the upper half
        li      t4, 0x0C000004
        lw      s2, 0(t4)
    """ + HANDLER, data="cell: .dword 0\n"))
    run_to_done(board)
    assert reg(board, "s8") == 0
    assert reg(board, "s1") == 0x5A5A and reg(board, "s2") == 6
    assert board.bus.questionable == {"upper address bits": 1}     # once per upper half and hart


def test_upper_bits_over_a_hole_fault_and_strict_stops_at_upper_bits():
    board = make_board(program(SET_MTVEC + """
        li      t0, 0x60000000
        li      t2, 0x100000000
        or      t0, t0, t2
    bad:
        lw      t1, 0(t0)
    """ + HANDLER))
    run_to_done(board)
    assert reg(board, "s8") == 5 and reg(board, "s9") == symbol(board, "bad")
    assert reg(board, "s10") == 0x1_6000_0000
    strict = make_board(program("""
        la      t0, cell
        li      t2, 0x100000000
        or      t0, t0, t2
        ld      t1, 0(t0)
    """, data="cell: .dword 0\n"), strict=True)
    with pytest.raises(UnmodelledAccess, match="upper 32 bits set; the K210 would reach 0x8"):
        run_to_done(strict)


def test_a_jump_where_nothing_answers_is_an_instruction_access_fault():
    board = make_board(program(SET_MTVEC + """
        li      t0, 0x60000000
    bad:
        jalr    ra, 0(t0)
    """ + HANDLER))
    run_to_done(board)
    assert reg(board, "s8") == 1                                   # instruction access fault
    assert reg(board, "s9") == 0x6000_0000 and reg(board, "s10") == 0x6000_0000
    assert board.harts[0].uc.reg_read(rv.UC_RISCV_REG_RA) == symbol(board, "bad") + 4   # the jump retired
    assert board.bus.questionable == {"access fault": 1}


# --- the command line ------------------------------------------------------------------------------------

CLI_PROGRAM = """
    .globl _start
_start:
    li t0, 0x0C000000
    li t1, 1
    sb t1, 4(t0)
1:  j 1b
"""


def test_the_run_counts_bus_warnings_and_strict_stops(assemble, tmp_path):
    elf = str(assemble(CLI_PROGRAM))
    result = run_emulator("run", elf, "--out", str(tmp_path / "a"), "--budget", "0.01")
    assert result.returncode == 4, result.stderr                 # went on; never drew a frame
    summary = json.loads((tmp_path / "a" / "run.json").read_text())
    assert summary["bus_warnings"] == {"narrow store": 2} and summary["strict"] is False   # both harts
    assert "[board] warning:" in result.stderr and "PLIC.priority1" in result.stderr
    result = run_emulator("run", elf, "--out", str(tmp_path / "b"), "--budget", "0.01", "--strict")
    assert result.returncode == 5, result.stderr
    assert "[board] stopped (unmodelled): hart 0 at pc 0x80000006 <_start+0x6> (sb t1, 4(t0)): store of 1 bytes at " \
           "0x0c000004" in result.stderr
    assert "a 8-bit access is not supported by the model" in result.stderr


def test_the_firmware_runs_clean_under_strict(firmware, card, tmp_path):
    """Our own firmware makes no access the bus would have to warn about: --strict changes
    nothing, the frames match the goldens."""
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", str(GOLDEN_FRAMES), "--strict",
                          "--out", str(tmp_path), "--quiet", "--golden", str(GOLDEN / "default"))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "run.json").read_text())
    assert summary["bus_warnings"] == {} and summary["warnings"] == []
