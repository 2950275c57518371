"""Pads driven from outside (--pin, --pin-file; board/pins.py): GPIOHS and GPIO lines read them
through FPIOA, with their interrupts; an undriven pad reads its pull, FPIOA's or GPIOHS's own."""
from __future__ import annotations

import json

import pytest

from suite import run_emulator
from emulator.board.pins import PinChange, load_schedule, parse_pin
from emulator.devices import gpio as g
from emulator.devices import gpiohs as h
from emulator.devices.fpioa import FUNC_GPIO0, FUNC_GPIOHS0
from emulator.errors import BadInput
from emulator.vtime import PS_PER_MS, PS_PER_US
from k210_fixtures import make_board, program, reg, run_to_done

PAD_BOOT = 16                    # the Dock's BOOT key: pressed pulls the pad low
FPIOA_IE, FPIOA_PU = 1 << 20, 1 << 16


def test_parse_pin_and_its_refusals(tmp_path):
    assert parse_pin("16=0@0.5") == PinChange(500 * PS_PER_MS, 16, 0)
    assert parse_pin("3=z@0") == PinChange(0, 3, None)
    for bad, what in (("16=0", "PAD=LEVEL@SECONDS"), ("48=1@0", "pad 48 does not exist"), ("x=1@0", "not a number"),
                      ("1=2@0", "not 0, 1 or z"), ("1=1@-1", "0 or more"), ("1=1@inf", "finite")):
        with pytest.raises(ValueError, match=what):
            parse_pin(bad)
    schedule = tmp_path / "pins.txt"
    schedule.write_text("# the BOOT key\n0.001 16 0   # pressed\n0.002 16 z\n")
    assert load_schedule(schedule) == [PinChange(PS_PER_MS, 16, 0), PinChange(2 * PS_PER_MS, 16, None)]
    schedule.write_text("0.001 16\n")
    with pytest.raises(BadInput, match=r"pins.txt:1: expected SECONDS PAD LEVEL"):
        load_schedule(schedule)


def test_a_key_on_a_gpiohs_line_with_the_pads_pull_up_interrupts_on_its_edges():
    """The SDK's gpiohs_set_drive_mode(GPIO_DM_INPUT_PULL_UP) sets the pad's pull-up in FPIOA: the
    line reads 1 until the key pulls the pad low at 1 ms (a falling edge, interrupt), 0 until it is
    let go at 2 ms."""
    board = make_board(program(f"""
        li      s0, 0x50440000
        lw      t0, 0x28(s0)
        ori     t0, t0, 1 << 3
        sw      t0, 0x28(s0)
        lw      t0, 0x2C(s0)
        li      t1, 1 << 20
        or      t0, t0, t1
        sw      t0, 0x2C(s0)                 # FPIOA's clock
        li      s1, 0x502B0000
        li      t0, {FUNC_GPIOHS0 + 5} | {FPIOA_IE} | {FPIOA_PU}
        sw      t0, {4 * PAD_BOOT}(s1)       # pad 16: GPIOHS5, input, pulled up
        li      s2, 0x38001000
        li      t0, 1 << 5
        sw      t0, {h.INPUT_EN}(s2)
        sw      t0, {h.FALL_IE}(s2)
        lw      s3, {h.INPUT_VAL}(s2)        # released: 1
        la      t0, handler
        csrw    mtvec, t0
        li      t1, 0x0C000000
        li      t0, 1
        sw      t0, {4 * (34 + 5)}(t1)       # priority of GPIOHS5 (source 39)
        li      t1, 0x0C002004
        li      t0, 1 << (39 - 32)
        sw      t0, 0(t1)
        li      t0, 1 << 11
        csrw    mie, t0
        csrsi   mstatus, 8
    1:  beqz    s5, 1b                       # wait for the interrupt
        csrr    s6, mcycle
        j       done
        .balign 4
    handler:
        lw      s4, {h.INPUT_VAL}(s2)        # pressed: 0
        li      t0, 1 << 5
        sw      t0, {h.FALL_IP}(s2)          # acknowledge the edge
        li      t1, 0x0C200004
        lw      t2, 0(t1)
        sw      t2, 0(t1)
        li      s5, 1
        mret
    """), pins=[PinChange(PS_PER_MS, PAD_BOOT, 0), PinChange(2 * PS_PER_MS, PAD_BOOT, None)], quantum=500)
    run_to_done(board, max_time_s=0.01)
    assert reg(board, "s3") >> 5 & 1 == 1
    assert reg(board, "s4") >> 5 & 1 == 0
    assert 1e-3 <= reg(board, "s6") / 26e6 < 1.05e-3
    board.advance_devices(2500 * PS_PER_US)
    assert board.gpiohs.read(h.INPUT_VAL, 4, 2500 * PS_PER_US) >> 5 & 1 == 1     # let go: the pull-up again
    assert [c.describe() for c in board.pins.played] == ["16=0@0.001", "16=z@0.002"]


def test_a_slow_gpio_line_reads_the_outside_and_its_own_output_wins():
    board = make_board(program(""), pins=[PinChange(PS_PER_US, 20, 1)])
    board.fpioa.write(4 * 20, 4, FUNC_GPIO0 + 2 | FPIOA_IE, 0.0)
    assert board.gpio.read(g.DATA_INPUT, 4, 0.0) >> 2 & 1 == 0
    board.advance_devices(PS_PER_US)
    assert board.gpio.read(g.DATA_INPUT, 4, PS_PER_US) >> 2 & 1 == 1
    board.gpio.write(g.DIRECTION, 4, 1 << 2, 2 * PS_PER_US)            # the chip drives it low
    assert board.gpio.read(g.DATA_INPUT, 4, 2 * PS_PER_US) >> 2 & 1 == 0


def test_pins_from_the_command_line_and_a_file(tmp_path, assemble):
    elf = assemble("""
    .globl _start
_start:
1:  wfi
    j 1b
""")
    schedule = tmp_path / "pins.txt"
    schedule.write_text("0.002 17 1\n")
    result = run_emulator("run", str(elf), "--out", str(tmp_path / "out"), "--quiet", "--until", "0.01",
                          "--pin", "16=0@0.001", "--pin-file", str(schedule))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "out" / "run.json").read_text())
    assert summary["pins"] == ["16=0@0.001", "17=1@0.002"]
    result = run_emulator("run", str(elf), "--out", str(tmp_path / "bad"), "--quiet", "--pin", "99=1@0")
    assert result.returncode == 2 and "pad 99 does not exist" in result.stderr
    schedule.write_text("soon 17 1\n")
    result = run_emulator("run", str(elf), "--out", str(tmp_path / "bad"), "--quiet", "--pin-file", str(schedule))
    assert result.returncode == 6 and "pins.txt:1:" in result.stderr


def test_a_pad_driven_from_outside_while_the_board_runs(c_firmware):
    """Board.drive_pad (the live view's keys): at the board's time, at once when every hart is
    there; a later time waits for it; never before the board's time."""
    from emulator.board import Board
    from emulator.vtime import from_seconds
    console = bytearray()
    board = Board(str(c_firmware / "boot_key.elf"), console=console.append)
    board.run_until(from_seconds(0.01))
    pressed = board.drive_pad(PAD_BOOT, 0)
    assert pressed.at == board.time and board.pins.levels == {PAD_BOOT: 0}       # at once
    released = board.drive_pad(PAD_BOOT, None, at=board.time + 5 * PS_PER_MS)
    early = board.drive_pad(20, 1, at=0)
    assert early.at == board.time and board.pins.levels == {PAD_BOOT: 0, 20: 1}
    board.run_until(from_seconds(0.02))
    assert board.pins.levels == {20: 1} and board.pins.played == [pressed, early, released]
    assert console.decode().splitlines()[1:] == ["BOOT key pressed (1)", "BOOT key released (1)"]
    with pytest.raises(ValueError, match="pad 48"):
        board.drive_pad(48, 0)
