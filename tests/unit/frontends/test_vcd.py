"""--vcd (emulator/frontends/vcd.py): the pins over virtual time as a Value Change Dump, read back
with a small parser of our own (tests/support/vcd_reader.py) and checked against what the programs do."""
from __future__ import annotations

import json

from suite import run_emulator
from vcd_reader import read_vcd
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
    selects = changes["spi0_ss_n"]
    assert selects[0] == (0, "1") and any(v == "0" for _, v in selects)
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
