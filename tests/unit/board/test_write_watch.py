"""--check-writes (emulator/board/write_watch.py): stores outside the firmware's buffers stop the run
with StrayWrite (exit status 10) naming the pc, the address and the region; stores inside them,
and the real firmware, run as without the check.

The small programs are linked with the firmware's own k210.ld, so they have its segments and
its heap and stack symbols; hart 0 hands out HEAP_GIVEN bytes of heap (heap.S's heap_next)
before its body runs, and each hart runs on its own stack."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest
from PIL import Image

from suite import GOLDEN_FRAMES, ROOT, run_emulator
from emulator.devices import dmac as d
from emulator.cpu.hart import ENGINE_FAST, ENGINE_PRECISE
from emulator.errors import FirmwareTrap, StrayWrite
from k210_common.exit_status import EXIT_STRAY_WRITE
from emulator.cpu.hart import HartState
from emulator.memory_map import SRAM_BASE, SRAM_SIZE
from emulator.board.write_watch import CODE, DATA, HEAP, UNOWNED, Rule, plan_layout, stack_name
from k210_fixtures import at_done, build_elf, make_board, program, reg, run_until

K210_LD = ROOT / "firmware" / "k210.ld"
HEAP_GIVEN = 256
AI_SRAM = 0x8060_0000

TEMPLATE = """
    .option norelax
    .globl _start
_start:
    csrr    a0, mhartid
    # hart h's stack ends at __stack_top - h * (__stack_hart0_top - __stack_hart1_top)
    la      t0, __stack_hart0_top
    la      t1, __stack_hart1_top
    sub     t1, t0, t1
    mul     t1, t1, a0
    la      sp, __stack_top
    sub     sp, sp, t1
    bnez    a0, hart1
{heap_init}
{body0}
    li      s0, 1                       # the instruction after the body's last
done:
    j       done
hart1:
{body1}
    li      s0, 1
park:
    csrw    mie, zero
1:  wfi
    j       1b

    .data
    .balign 8
buffer:
    .dword  0x1111111111111111, 0x2222222222222222
    .bss
    .balign 8
{heap_next}
counter:
    .space  8
"""


HEAP_INIT = f"""
    la      t0, heap_next               # heap.S's heap_init, then a block of HEAP_GIVEN bytes
    la      t1, __heap_start
    addi    t1, t1, {HEAP_GIVEN}
    sd      t1, 0(t0)
"""


def watched(body0: str = "", body1: str = "", heap_next: bool = True) -> str:
    """A program linked with k210.ld; without heap_next it lacks one of the heap symbols."""
    return build_elf(TEMPLATE.format(body0=body0, body1=body1, heap_init=HEAP_INIT if heap_next else "",
                                     heap_next="heap_next:\n    .space  8" if heap_next else ""), K210_LD)


def finished(board) -> bool:
    return at_done(board) and board.harts[1].state is HartState.ASLEEP


def run_checked(elf: str):
    board = make_board(elf, check_writes=True)
    run_until(board, finished)
    return board


def sym(board, name: str) -> int:
    return board.image.symbol_values[name]


def code_end(board) -> int:
    (segment,) = [s for s in board.image.segments if not s.writable]
    return segment.address + segment.size


# (hart, body, address of the store, bytes, region text) per stray store; the store is at `store`
STRAYS = {
    "into code": (0, "la t0, _start\nstore: sw t0, 8(t0)", lambda b: sym(b, "_start") + 8, 4,
                  lambda b: f"{CODE} [0x80000000, 0x{code_end(b):08x})"),
    "into code through the uncached alias": (
        0, "la t0, _start\nli t1, 0x40000000\nsub t0, t0, t1\nstore: sh t0, 16(t0)",
        lambda b: sym(b, "_start") - 0x4000_0000 + 16, 2,
        lambda b: f"{CODE} [0x80000000, 0x{code_end(b):08x}); 0x{sym(b, '_start') - 0x4000_0000 + 16:08x} is the "
                  f"uncached alias of 0x{sym(b, '_start') + 16:08x}"),
    "into AI SRAM": (0, "li t0, 0x80700000\nli t1, 0x5a5a\nstore: sd t1, 0(t0)", lambda b: 0x8070_0000, 8,
                     lambda b: f"{UNOWNED} [0x{AI_SRAM:08x}, 0x{SRAM_BASE + SRAM_SIZE:08x})"),
    "into the heap not handed out": (
        0, f"la t0, __heap_start\nstore: sb t0, {HEAP_GIVEN}(t0)", lambda b: sym(b, "__heap_start") + HEAP_GIVEN, 1,
        lambda b: f"heap not allocated [0x{sym(b, '__heap_start') + HEAP_GIVEN:08x}, 0x{sym(b, '__heap_end'):08x}) "
                  f"(heap_next = 0x{sym(b, '__heap_start') + HEAP_GIVEN:x})"),
    # heap.S's heap_release lowers heap_next: a block given back is no longer the firmware's
    "into a block given back": (
        0, f"la t0, heap_next\nla t1, __heap_start\naddi t1, t1, {HEAP_GIVEN // 2}\nsd t1, 0(t0)\n"
           f"la t0, __heap_start\nstore: sw t0, {HEAP_GIVEN // 2}(t0)",
        lambda b: sym(b, "__heap_start") + HEAP_GIVEN // 2, 4,
        lambda b: f"heap not allocated [0x{sym(b, '__heap_start') + HEAP_GIVEN // 2:08x}, "
                  f"0x{sym(b, '__heap_end'):08x}) (heap_next = 0x{sym(b, '__heap_start') + HEAP_GIVEN // 2:x})"),
    "by hart 0 into hart 1's stack": (
        0, "la t0, __stack_hart1_top\nstore: sd t0, -8(t0)", lambda b: sym(b, "__stack_hart1_top") - 8, 8,
        lambda b: f"{stack_name(1)} [0x{sym(b, '__stack_bottom'):08x}, 0x{sym(b, '__stack_hart1_top'):08x})"),
    "by hart 1 into hart 0's stack": (
        1, "la t0, __stack_hart0_top\nstore: sd t0, -16(t0)", lambda b: sym(b, "__stack_hart0_top") - 16, 8,
        lambda b: f"{stack_name(0)} [0x{sym(b, '__stack_hart1_top'):08x}, 0x{sym(b, '__stack_hart0_top'):08x})"),
}


@pytest.mark.parametrize("name", STRAYS)
def test_a_stray_store_stops_the_run_naming_pc_address_and_region(name):
    """On the fast engine (the default), which checks its own stores; the precise engine, whose
    Unicorn hook checks them, stops at the same store with the same message and counts."""
    hart, body, address, size, region = STRAYS[name]
    elf = watched(*((body, "") if hart == 0 else ("", body)))
    stops = {}
    for engine in (ENGINE_PRECISE, ENGINE_FAST):
        board = make_board(elf, check_writes=True, engine=engine)
        with pytest.raises(StrayWrite) as stop:
            run_until(board, finished)
        stops[engine] = (str(stop.value), [h.executed for h in board.harts], [h.cycles for h in board.harts])
    assert stops[ENGINE_FAST] == stops[ENGINE_PRECISE]
    assert board.harts[hart].fast_statistics()["instructions"] > 0     # the store was the fast engine's
    store = sym(board, "store")
    message = str(stop.value)
    access = re.match(rf"hart {hart} at pc 0x{store:08x} <store> \(s[bhwd] [^:]*\): store of {size} bytes at "
                      rf"0x{address(board):08x}: ", message)
    assert access and message[access.end():].startswith(region(board)), message
    assert stop.value.exit_status == EXIT_STRAY_WRITE == 10
    # a watchpoint, not protection: the store landed, and the hart stopped right after it
    assert reg(board, "s0", hart) == 0
    if name == "into AI SRAM":
        assert board.memory.read(0x8070_0000, 8) == (0x5a5a).to_bytes(8, "little")


CLEAN = {
    "own stack and its trap save area": ("sd t0, -8(sp)\nla t0, __stack_hart0_top\nsd t0, -8(t0)",
                                         "sd t0, -8(sp)\nla t0, __stack_hart1_top\nsd t0, -8(t0)"),
    ".data and .bss, also uncached": ("la t0, buffer\nsd t0, 8(t0)\nla t0, counter\nsd t0, 0(t0)\n"
                                      "li t1, 0x40000000\nla t0, buffer\nsub t0, t0, t1\nsw t0, 12(t0)", ""),
    "the last byte of the heap handed out": (f"la t0, __heap_start\nsb t0, {HEAP_GIVEN - 1}(t0)", ""),
    # heap_next is read at each store: once the next block is handed out, it may be written
    "a block handed out later": (f"la t0, heap_next\nla t1, __heap_start\naddi t1, t1, {2 * HEAP_GIVEN}\n"
                                 f"sd t1, 0(t0)\nla t0, __heap_start\nsd t0, {HEAP_GIVEN}(t0)\n"
                                 f"sd t0, {2 * HEAP_GIVEN - 8}(t0)", ""),
}


@pytest.mark.parametrize("name", CLEAN)
def test_stores_inside_the_firmwares_buffers_run_clean(name):
    body0, body1 = CLEAN[name]
    board = run_checked(watched(body0, body1))
    assert reg(board, "s0", 0) == 1 and reg(board, "s0", 1) == 1
    assert board.warnings == []


def test_the_firmwares_regions_come_from_its_elf(firmware):
    from emulator.board import Board
    board = Board(str(firmware))
    s = board.image.symbol_values
    offset = lambda name: s[name] - SRAM_BASE   # noqa: E731
    (data,) = [seg for seg in board.image.segments if seg.writable]
    expected_hart0 = [(0, code_end(board) - SRAM_BASE, Rule.FORBID, CODE)]
    if code_end(board) < data.address:   # alignment padding before .data
        expected_hart0.append((code_end(board) - SRAM_BASE, data.address - SRAM_BASE, Rule.FORBID, UNOWNED))
    expected_hart0 += [(data.address - SRAM_BASE, data.address + data.size - SRAM_BASE, Rule.ALLOW, DATA),
                       (offset("__heap_start"), offset("__heap_end"), Rule.HEAP, HEAP),
                       (offset("__stack_bottom"), offset("__stack_hart1_top"), Rule.FORBID, stack_name(1)),
                       (offset("__stack_hart1_top"), offset("__stack_top"), Rule.ALLOW, stack_name(0)),
                       (offset("__stack_top"), SRAM_SIZE, Rule.FORBID, UNOWNED)]
    assert data.address + data.size == s["__bss_end"] == s["__heap_start"]   # no gap in this layout
    layout = plan_layout(board.image, 2)
    assert [(r.lo, r.hi, r.rule, r.name) for r in layout.harts[0]] == expected_hart0
    hart1 = [(r.lo, r.hi, r.rule, r.name) for r in layout.harts[1]]
    assert (offset("__stack_bottom"), offset("__stack_hart1_top"), Rule.ALLOW, stack_name(1)) in hart1
    assert (offset("__stack_hart1_top"), offset("__stack_top"), Rule.FORBID, stack_name(0)) in hart1
    assert [r.rule for r in layout.dma if r.name.endswith("stack")] == [Rule.FORBID, Rule.FORBID]
    assert layout.heap_next_offset == offset("heap_next") and not layout.missing


# --- without the heap and stack symbols: only code and constants ----------------------------------

def test_without_heap_symbols_only_code_is_checked_with_a_warning():
    body = "li t0, 0x80700000\nsd t0, 0(t0)\nla t0, __stack_hart1_top\nsd t0, -8(t0)\n" \
           "la t0, _start\nstore: sw t0, 8(t0)"
    board = make_board(watched(body, heap_next=False), check_writes=True)
    assert [w for w in board.warnings if "only stores into code and constants" in w and "heap_next" in w]
    with pytest.raises(StrayWrite, match=rf"pc 0x{sym(board, 'store'):08x} <store> .*: {CODE} \[0x80000000, "):
        run_until(board, finished)


def test_a_store_across_the_end_of_the_heap_traps_before_it_lands():
    """A store can cross the end of the heap handed out (an aligned boundary) only misaligned, and
    the K210's Rocket traps on that before the store: no stray write, a misaligned-store exception
    (here into no trap handler), on either engine."""
    elf = watched(f"la t0, __heap_start\nstore: sd t0, {HEAP_GIVEN - 4}(t0)", "")
    for engine in (ENGINE_PRECISE, ENGINE_FAST):
        board = make_board(elf, check_writes=True, engine=engine)
        with pytest.raises(FirmwareTrap, match=r"store address misaligned at pc 0x[0-9a-f]+ <store>.*mtval "
                                               rf"0x{sym(board, '__heap_start') + HEAP_GIVEN - 4:x}"):
            run_until(board, finished)


def test_a_program_in_one_writable_segment_runs_clean():
    """The tests' usual programs (one read-write-execute segment, no symbols): nothing is out of
    bounds, not even their own code."""
    board = make_board(program("li t0, 0x80700000\nsd t0, 0(t0)\nla t0, done\nandi t0, t0, -4\nsw zero, 64(t0)\n"
                               "li s0, 1"),
                       check_writes=True)
    run_until(board, at_done)
    assert reg(board, "s0") == 1
    assert len([w for w in board.warnings if "--check-writes" in w]) == 1


# --- DMA -----------------------------------------------------------------------------------------

def dma_copy(destination: str) -> str:
    """Hart 0 copies `buffer` (16 bytes) to the address `destination` leaves in t0, with a
    memory-to-memory transfer on DMAC channel 0."""
    channel = d.CH_BASE
    return f"""
    li      s2, 0x50440000              # SYSCTL clk_en_peri: the DMA clock
    lw      t0, 0x2c(s2)
    ori     t0, t0, 1 << 1
    sw      t0, 0x2c(s2)
    li      s1, {d.Dmac.BASE:#x}
    li      t0, {d.CFG_ENABLE}
    sd      t0, {d.CFG:#x}(s1)
    la      t0, buffer
    sd      t0, {channel + d.SAR:#x}(s1)
    {destination}
    sd      t0, {channel + d.DAR:#x}(s1)
    li      t0, 3
    sd      t0, {channel + d.BLOCK_TS:#x}(s1)    # 4 items
    li      t0, (2 << 8) | (2 << 11)
    sd      t0, {channel + d.CTL:#x}(s1)         # 32-bit items, both sides incrementing
    li      t0, (1 << 35) | (1 << 36)
    sd      t0, {channel + d.CH_CFG:#x}(s1)      # memory to memory, software handshakes
    li      t0, 0x0101
    sd      t0, {d.CHEN:#x}(s1)                  # channel 0 on: the copy happens now
"""


DMA_STRAYS = {
    "into the heap not handed out": (f"la t0, __heap_start\naddi t0, t0, {HEAP_GIVEN - 8}",
                                     lambda b: sym(b, "__heap_start") + HEAP_GIVEN - 8,
                                     lambda b: f"heap not allocated [0x{sym(b, '__heap_start') + HEAP_GIVEN:08x}, "),
    "into the stack of the hart that started it": ("addi t0, sp, -64", lambda b: sym(b, "__stack_top") - 64,
                                                   lambda b: f"{stack_name(0)} [0x{sym(b, '__stack_hart1_top'):08x}, "),
    "into code": ("la t0, _start", lambda b: sym(b, "_start"), lambda b: f"{CODE} [0x80000000, "),
}


@pytest.mark.parametrize("name", DMA_STRAYS)
def test_a_stray_dma_write_names_the_channel(name):
    destination, address, region = DMA_STRAYS[name]
    board = make_board(watched(dma_copy(destination)), check_writes=True)
    with pytest.raises(StrayWrite) as stop:
        run_until(board, finished)
    assert str(stop.value).startswith(f"DMAC channel 0: write of 16 bytes at 0x{address(board):08x}.."
                                      f"0x{address(board) + 15:08x}: {region(board)}"), str(stop.value)


def test_a_dma_write_into_the_heap_handed_out_runs_clean():
    board = run_checked(watched(dma_copy(f"la t0, __heap_start\naddi t0, t0, {HEAP_GIVEN - 16}")))
    start = sym(board, "__heap_start") + HEAP_GIVEN - 16
    assert board.memory.read(start, 16) == board.memory.read(sym(board, "buffer"), 16)


# --- through the command line, and the real firmware ---------------------------------------------

def test_the_command_line_exits_with_status_10(tmp_path):
    elf = watched("la t0, _start\nstore: sw t0, 8(t0)")
    out = tmp_path / "out"
    result = run_emulator("run", elf, "--check-writes", "--frames", "1", "--budget", "0.01", "--out", str(out),
                          "--quiet")
    assert result.returncode == 10, result.stderr
    assert "stopped (stray-write): hart 0 at pc 0x" in result.stderr and f"{CODE} [0x80000000, " in result.stderr
    summary = json.loads((out / "run.json").read_text())
    assert summary["exit"] == "stray-write" and summary["writes_checked"] is True
    # without the option the store goes through, as on the K210; hart 1 ran the instruction it
    # overwrote long before (the harts start side by side), so nothing traps and no frame comes
    plain = run_emulator("run", elf, "--frames", "1", "--budget", "0.01", "--out", str(tmp_path / "plain"), "--quiet")
    assert plain.returncode == 4 and "no frame reached the LCD" in plain.stderr, plain.stderr
    assert "hart 0: running at pc" in plain.stderr and "<done>" in plain.stderr


def test_the_firmware_writes_only_its_buffers_and_draws_the_same_frames(firmware, card, firmware_run, tmp_path):
    """The default scene with --check-writes: no stray store, no warning (the heap and the stacks
    are checked), and the same frames, instruction counts and virtual times as without."""
    _, plain_out, plain = firmware_run
    out = tmp_path / "checked"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", str(GOLDEN_FRAMES), "--out", str(out),
                          "--quiet", "--check-writes")
    assert result.returncode == 0, result.stderr
    checked = json.loads((out / "run.json").read_text())
    assert checked["writes_checked"] is True and plain["writes_checked"] is False
    assert checked["warnings"] == plain["warnings"]
    for n in range(GOLDEN_FRAMES):
        name = f"frame_{n:04d}.png"
        assert np.array_equal(np.asarray(Image.open(out / name)), np.asarray(Image.open(plain_out / name))), name
    for key in ("instructions", "instructions_total", "virtual_time_s"):
        assert [f[key] for f in checked["frames"]] == [f[key] for f in plain["frames"]], key
