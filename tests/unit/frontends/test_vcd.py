"""--vcd (emulator/frontends/vcd.py): the pins over virtual time as a Value Change Dump, read back
with a small parser of our own (tests/support/vcd_reader.py) and checked against what the programs do."""
from __future__ import annotations

import json

from suite import run_emulator
from vcd_reader import parse_vcd, read_vcd
from emulator.vtime import PS_PER_MS, PS_PER_S


def test_leds_blink_on_their_pads_at_the_timer_s_pace(c_firmware, tmp_path):
    out = tmp_path / "out"
    run = run_emulator("run", str(c_firmware / "blink.elf"), "--until", "0.6", "--quiet", "--out", str(out),
                       "--vcd", str(tmp_path / "blink.vcd"))
    assert run.returncode == 0, run.stderr
    timescale, changes = read_vcd((tmp_path / "blink.vcd").read_text())
    assert timescale == "1ps"
    blue = [t for t, v in changes["pad12"]]
    gaps = {round((b - a) / PS_PER_MS, 3) for a, b in zip(blue[1:], blue[2:])}
    assert gaps == {50.0}                                       # ms between the blue LED's edges
    summary = json.loads((out / "run.json").read_text())
    logged = [(round(c["virtual_time_s"] * PS_PER_S), str(c["level"])) for c in summary["pad_changes"] if c["pad"] == 12]
    assert changes["pad12"] == logged
    assert summary["vcd"]["value_changes"] == sum(len(v) for v in changes.values())


def test_the_lcd_s_select_clock_bursts_and_pins(c_firmware, tmp_path):
    run = run_emulator("run", str(c_firmware / "lcd_demo.elf"), "--frames", "4", "--quiet", "--out",
                       str(tmp_path / "out"), "--vcd", str(tmp_path / "lcd.vcd"))
    assert run.returncode == 0, run.stderr
    _, changes = read_vcd((tmp_path / "lcd.vcd").read_text())
    reset = [v for _, v in changes["pad37"]]
    assert reset[:3] == ["1", "0", "1"]                         # the reset pulse on its GPIO line
    assert len(changes["pad38"]) > 10                           # D/C between commands and data
    _, initial, _ = parse_vcd((tmp_path / "lcd.vcd").read_text())
    assert initial["spi0_ss_n"] == "1" and initial["spi0_sclk"] == "0"
    selects = [(0, "1")] + changes["spi0_ss_n"]
    assert any(v == "0" for _, v in selects)
    lows = [(t, next(t2 for t2, v2 in selects if t2 > t and v2 == "1")) for t, v in selects if v == "0"
            if any(t2 > t and v2 == "1" for t2, v2 in selects)]
    bursts = changes["spi0_sclk"]
    starts = [t for t, v in bursts if v == "1"]
    assert starts and all(any(lo <= t <= hi for lo, hi in lows) for t in starts)   # clocks only while selected
    ends = [t for t, v in bursts[1:] if v == "0"]
    assert all(e > s for s, e in zip(starts, ends, strict=True))


def test_a_vcd_that_cannot_be_written_is_bad_input(c_firmware, tmp_path):
    run = run_emulator("run", str(c_firmware / "hello.elf"), "--until", "0.01", "--out", str(tmp_path / "o"),
                       "--vcd", "/nonexistent-folder/x.vcd")
    assert run.returncode == 6 and "--vcd /nonexistent-folder/x.vcd: cannot write it" in run.stderr


def test_every_signal_starts_with_its_level_at_time_0(c_firmware, tmp_path):
    """issue 32, item 10: a $dumpvars at #0 gives every signal its value (IEEE 1364-2005, 18.2):
    the pads the program drives later are undriven (z) until then, not unknown (x) to a viewer."""
    run = run_emulator("run", str(c_firmware / "blink.elf"), "--until", "0.2", "--quiet", "--out",
                       str(tmp_path / "out"), "--vcd", str(tmp_path / "blink.vcd"))
    assert run.returncode == 0, run.stderr
    text = (tmp_path / "blink.vcd").read_text()
    body = text.partition("$enddefinitions $end\n")[2]
    assert body.startswith("#0\n$dumpvars\n")
    _, initial, changes = parse_vcd(text)
    assert set(initial) == set(changes)                      # every signal declared has its value at 0
    assert initial["pad12"] == initial["pad13"] == "z"        # the LEDs, before blink.c routes lines to them
    assert initial["spi0_ss_n"] == initial["spi1_ss_n"] == "1"
    assert changes["pad12"][0][0] > 0 and changes["pad12"][0][1] in "01"
    for name, values in changes.items():                      # no change repeats the value before it
        levels = [initial[name]] + [v for _, v in values]
        assert all(a != b for a, b in zip(levels, levels[1:])), name
