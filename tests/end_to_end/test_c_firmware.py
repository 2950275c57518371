"""C firmware in the Kendryte SDK's manner (tests/firmware/), run on the board model with no
flag: hello on UARTHS through picolibc's printf, LEDs blinking on the CLINT timer interrupt
(one slow-GPIO line, one GPIOHS line), and the LCD driven over SPI0 in octal mode by DMA.
`make c-firmware` builds them (with Debian's gcc-riscv64-unknown-elf and picolibc), once per
session here (conftest's c_firmware fixture). Their output is checked against what the
programs and the datasheets say: console text, pin changes at their virtual times, and golden
frames computed here."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from suite import ROOT, run_emulator
from vcd_reader import read_vcd
from emulator.board import Board
from emulator.errors import UnmodelledAccess
from emulator.vtime import PS_PER_MS, PS_PER_US

LCD_GOLDEN = ROOT / "tests" / "golden" / "c-lcd-demo"
LCD_FRAMES = 4
PAD_LED_BLUE, PAD_LED_GREEN, PAD_LCD_RST = 12, 13, 37
TICK_S, TICKS = 0.050, 10


def console_of(summary: dict) -> list[str]:
    return [entry["line"] for entry in summary["console"]]


# --- hello ------------------------------------------------------------------------------------

def test_hello_prints_through_picolibc_with_the_clocks_as_handed_over(c_firmware):
    board = Board(str(c_firmware / "hello.elf"))
    reset_status = board.sysctl.values[0x60]          # as the firmware finds it
    result = board.run_until(50 * PS_PER_MS)
    pin_reset = "the reset pin" if reset_status & 2 else "power-on"
    cpu, pll0 = int(board.sysctl.cpu_hz()), int(board.sysctl.pll_hz(0x08))
    assert [line for _, line in board.console_lines] == [
        "hello from C on the K210",
        f"cpu {cpu} Hz, pll0 {pll0} Hz, reset by {pin_reset}",
        "malloc works; sqrt(2) = 1.414214; hart 0",
    ]
    assert "every hart slept in wfi" in result.message
    # of the two accesses firmware built without -fstrict-volatile-bitfields makes, the 64-bit load
    # of two SYSCTL registers is answered as the K210's buses do, warned about once and counted; the
    # byte stores to UARTHS txdata's data field are what TileLink's register map declares (no warning)
    assert board.bus.questionable == {"64-bit access to 32-bit registers": 1}
    assert len(board.warnings) == 1


def test_hello_stops_a_strict_run_at_its_64_bit_sysctl_load(c_firmware):
    board = Board(str(c_firmware / "hello.elf"), strict=True)
    with pytest.raises(UnmodelledAccess, match=r"<reset_status\+0x[0-9a-f]+> \(c\.ld .*load of 8 bytes at "
                                               r"0x50440060"):
        board.run_until(50 * PS_PER_MS)


# --- blink ------------------------------------------------------------------------------------

@pytest.fixture(scope="session")
def blink_run(c_firmware, tmp_path_factory):
    out = tmp_path_factory.mktemp("blink")
    result = run_emulator("run", str(c_firmware / "blink.elf"), "--until", "0.6", "--out", str(out), "--quiet")
    return result, json.loads((out / "run.json").read_text())


def test_blink_console(blink_run):
    result, summary = blink_run
    assert result.returncode == 0, result.stderr
    lines = console_of(summary)
    assert re.fullmatch(r"blink: 50 ms ticks, \d+ mtime counts each", lines[0])
    expected = [f"tick {n}: blue {'on' if n % 2 else 'off'}, green {'on' if n // 2 % 2 else 'off'}"
                for n in range(1, TICKS + 1)]
    assert lines[1:] == expected + ["blink: done"]
    assert summary["until_s"] == 0.6 and summary["virtual_time_s"] == pytest.approx(0.6)


def test_blink_pins_change_on_the_timer_ticks(blink_run):
    """The blue LED's pad (slow GPIO) toggles on every tick, the green one's (GPIOHS) on every
    second: exactly one tick apart, since each mtimecmp is one period after the last."""
    _, summary = blink_run
    changes = [(c["virtual_time_s"], c["pad"], c["level"]) for c in summary["pad_changes"]]
    blue = [(t, level) for t, pad, level in changes if pad == PAD_LED_BLUE]
    green = [(t, level) for t, pad, level in changes if pad == PAD_LED_GREEN]
    assert [level for _, level in blue] == [1] + [n % 2 == 0 for n in range(1, TICKS + 1)]
    assert [level for _, level in green] == [1] + [n // 2 % 2 == 0 for n in range(2, TICKS + 1, 2)]
    ticks = [t for t, _ in blue[1:]]
    assert TICK_S < ticks[0] < TICK_S + 0.01                        # after the first 50 ms, set-up included
    assert np.allclose(np.diff(ticks), TICK_S, rtol=0, atol=1e-6)
    for (t_green, _), t_blue in zip(green[1:], ticks[1::2], strict=True):
        assert 0 <= t_green - t_blue < 5e-6                       # the same interrupt, a few instructions on
    assert summary["pad_changes_total"] == len(changes)


def test_blink_runs_clean_under_strict(c_firmware, tmp_path):
    """issue 32, item 11: the C driver layer's uarths_putc stores each byte with a `sb` to txdata's
    8-bit data field, a store TileLink's register router takes as it is (bus.py,
    _whole_fields_store): --strict no longer stops there, and no run warns about it."""
    for strict in (("--strict",), ()):
        out = tmp_path / f"out{len(strict)}"
        result = run_emulator("run", str(c_firmware / "blink.elf"), "--until", "0.3", "--out", str(out), "--quiet",
                              *strict)
        assert result.returncode == 0, result.stderr
        summary = json.loads((out / "run.json").read_text())
        assert console_of(summary)[0].startswith("blink: 50 ms ticks")
        assert summary["bus_warnings"] == {} and summary["warnings"] == [], summary["warnings"]


# --- the LCD --------------------------------------------------------------------------------

def rgb565(r5: int, g6: int, b5: int) -> int:
    return r5 << 11 | g6 << 5 | b5


def landscape_pixel(x: int, y: int) -> int:
    """lcd_demo.c's landscape picture, 320 x 240."""
    if 20 <= x < 60 and 20 <= y < 60:
        return 0xFFFF
    if 250 <= x < 300 and 170 <= y < 220:
        return 0xF800
    return rgb565(x * 32 // 320, y * 64 // 240, 31 if (x // 20 + y // 20) % 2 else 0)


def portrait_pixel(x: int, y: int) -> int:
    """lcd_demo.c's portrait picture, 240 x 320."""
    if 10 <= x < 50 and 10 <= y < 50:
        return 0x07E0
    if 180 <= x < 230 and 260 <= y < 310:
        return 0x001F
    return rgb565(31 - y * 32 // 320, x * 64 // 240, 16)


def to_rgb888(colours: np.ndarray, bgr: bool = False) -> np.ndarray:
    """RGB565 as the ST7789V stores it (5 bits to 6 by repeating the top bit; MADCTL BGR
    exchanges red and blue) and as the frame shows it (6 bits to 8 the same way)."""
    r5, g6, b5 = colours >> 11 & 0x1F, colours >> 5 & 0x3F, colours & 0x1F
    r6, b6 = r5 << 1 | r5 >> 4, b5 << 1 | b5 >> 4
    if bgr:
        r6, b6 = b6, r6
    return np.stack([(c << 2 | c >> 4) for c in (r6, g6, b6)], axis=-1).astype(np.uint8)


def expected_lcd_frames() -> list[np.ndarray]:
    """What the Dock shows (320 x 240 PNGs) for lcd_demo.c's four frames, from the datasheet's
    MADCTL rules and the Dock's panel mounting (PNG pixel (x, y) = GRAM row 319 - x, column y):
    MY|MV shows logical (x, y) upright; MX|MV turns it 180 degrees; no MV puts the 240-wide
    logical picture's (x, y) at PNG (319 - y, x)."""
    landscape = np.array([[landscape_pixel(x, y) for x in range(320)] for y in range(240)])
    portrait = np.array([[portrait_pixel(x, y) for x in range(240)] for y in range(320)])
    fill = np.full((240, 320), 0x2945)
    turned = landscape[::-1, ::-1]
    shown_portrait = portrait[::-1, :].T            # PNG (x', y') = portrait (x = y', y = 319 - x')
    return [to_rgb888(fill), to_rgb888(landscape), to_rgb888(turned), to_rgb888(shown_portrait, bgr=True)]


def test_the_lcd_goldens_are_what_the_program_and_the_datasheet_say():
    """tests/golden/c-lcd-demo holds expected_lcd_frames(), not frames the model made."""
    for index, frame in enumerate(expected_lcd_frames()):
        golden = np.asarray(Image.open(LCD_GOLDEN / f"frame_{index:04d}.png").convert("RGB"))
        assert np.array_equal(golden, frame), index


@pytest.fixture(scope="session")
def lcd_run(c_firmware, tmp_path_factory):
    out = tmp_path_factory.mktemp("lcd")
    result = run_emulator("run", str(c_firmware / "lcd_demo.elf"), "--frames", str(LCD_FRAMES), "--out", str(out),
                          "--quiet", "--golden", str(LCD_GOLDEN))
    return result, json.loads((out / "run.json").read_text())


def test_lcd_demo_matches_its_golden_frames(lcd_run):
    result, summary = lcd_run
    assert result.returncode == 0, result.stderr
    assert all(frame["matches"] for frame in summary["golden"]["frames"])
    assert len(summary["golden"]["frames"]) == LCD_FRAMES
    assert console_of(summary) == ["lcd: ready", "lcd: frame 0 sent (fill)", "lcd: frame 1 sent (32-bit pairs)",
                                   "lcd: frame 2 sent (16-bit, turned)", "lcd: frame 3 sent (bytes, portrait, BGR)"]
    # nothing is answered with a warning: the LCD took every command, the console's byte stores
    # are whole-field stores to txdata
    assert summary["bus_warnings"] == {} and summary["warnings"] == []


def test_lcd_demo_resets_the_lcd_through_a_gpio_pin(lcd_run):
    """RESX on pad 37 is a slow-GPIO line: driven high, pulled low for 1 ms, released."""
    _, summary = lcd_run
    reset = [(c["virtual_time_s"], c["level"]) for c in summary["pad_changes"] if c["pad"] == PAD_LCD_RST]
    assert [level for _, level in reset] == [1, 0, 1]
    assert reset[2][0] - reset[1][0] == pytest.approx(1e-3, abs=1e-5)


def test_a_serial_lcd_module_in_standard_spi_gets_the_same_frames(c_firmware, tmp_path):
    """lcd_demo built for a 4-line serial ST7789V (standard SPI frames of 8, 16 and 32 bits on
    SPI0's data line 0, D/C on a slow-GPIO line, reset on a GPIOHS line) shows the same four
    frames on a board whose LCD is such a module."""
    result = run_emulator("run", str(c_firmware / "lcd_demo_serial.elf"), "--lcd-interface", "spi", "--frames",
                          str(LCD_FRAMES), "--out", str(tmp_path), "--quiet", "--golden", str(LCD_GOLDEN))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "run.json").read_text())
    assert summary["lcd_interface"] == "spi"
    assert summary["warnings"] == []
    levels = [c["level"] for c in summary["pad_changes"] if c["pad"] == PAD_LCD_RST]
    assert levels == [1, 0, 1]


def test_standard_spi_frames_do_not_reach_the_docks_parallel_lcd(c_firmware, tmp_path):
    result = run_emulator("run", str(c_firmware / "lcd_demo_serial.elf"), "--frames", "1", "--out", str(tmp_path),
                          "--quiet")
    assert result.returncode == 7, result.stderr
    assert "SPI0 sends to the LCD in the 1-line format; the Dock's LCD has an 8-bit parallel bus" in result.stderr
    assert "--lcd-interface spi" in result.stderr


# --- the SDK's way: UART3 console, ecall system calls, a misaligned load -----------------------

@pytest.mark.parametrize("engine", ["fast", "precise"])
def test_syscalls_ecall_and_misaligned_load_served_by_the_trap_handler(c_firmware, engine):
    """syscalls.c prints on UART3 routed to pads 4/5 through write() ecalls its trap handler
    serves, and reads a misaligned word the handler puts together byte by byte: the K210 traps
    on both, the run goes on (before 2026-11-28 the model ended it at the second exception,
    and let the misaligned load through)."""
    board = Board(str(c_firmware / "syscalls.elf"), engine=engine)
    board.run_until(50 * PS_PER_MS)
    assert [line for _, line in board.console_lines] == [
        "hello from UART3, through an ecall",
        "write returned 35; misaligned lw read 0x54433221",
        "51 ecalls served, 1 misaligned loads carried out",
    ]
    assert board.scheduler.traps.taken == {"environment call from M-mode": 101, "load address misaligned": 1}
    assert set(board.uart_output) == {"UART3"}


def test_an_expected_text_on_a_uart3_console_is_timed_by_uart3(c_firmware, tmp_path):
    """--expect times each match by the byte's end on the UART that drives pad 5 (here UART3; the
    time was UARTHS's, 0 ms, before 2026-11-28)."""
    run = run_emulator("run", str(c_firmware / "syscalls.elf"), "--expect", "misaligned lw read", "--quiet",
                       "--out", str(tmp_path / "out"))
    assert run.returncode == 0, run.stderr
    (match,) = json.loads((tmp_path / "out" / "run.json").read_text())["expect_matched"]
    printed = json.loads((tmp_path / "out" / "run.json").read_text())["console"]
    assert 0.0005 < match["virtual_time_s"] < 0.05
    assert match["virtual_time_s"] > printed[0]["virtual_time_s"]      # after the first line ended


def test_stop_on_trap_fails_the_syscalls_program_at_its_first_ecall(c_firmware, tmp_path):
    result = run_emulator("run", str(c_firmware / "syscalls.elf"), "--out", str(tmp_path), "--quiet",
                          "--until", "0.05", "--stop-on-trap")
    assert result.returncode == 3, result.stderr
    assert re.search(r"^\[board\] stopped \(trap\): hart 0: environment call from M-mode at pc 0x[0-9a-f]+ <main", result.stderr), \
        result.stderr
    summary = json.loads((tmp_path / "run.json").read_text())
    assert summary["exceptions"] == {"environment call from M-mode": 1} and summary["stop_on_trap"]


# --- the time blocks and the watchdog, in the SDK's manner -----------------------------------------

def test_timers_tick_pwm_alarm_and_a_key_through_the_plic(c_firmware, tmp_path):
    """timers.c: TIMER0 every 10 ms (five ticks), TIMER1's PWM on pad 24 (1 kHz, a quarter high,
    read back from the VCD), an RTC alarm two seconds after it was set, the BOOT key (pad 16,
    pulled up) pressed at 2.5 s by --pin: each through the PLIC to hart 0's handler."""
    out = tmp_path / "out"
    run = run_emulator("run", str(c_firmware / "timers.elf"), "--until", "3", "--quiet", "--out", str(out),
                       "--pin", "16=0@2.5", "--vcd", str(tmp_path / "t.vcd"))
    assert run.returncode == 0, run.stderr
    summary = json.loads((out / "run.json").read_text())
    lines = console_of(summary)
    assert lines[0] == "timers started: 13000000 Hz timer clock"
    ticks = [int(re.fullmatch(r"tick (\d) at (\d+) us", line).group(2)) for line in lines[1:6]]
    # each handler reads mtime some cycles after its tick, fewer once its code is in the instruction
    # cache (the first handler fetches it from SRAM): 10 ms apart, to the microsecond
    assert all(abs(b - a - 10000) <= 1 for a, b in zip(ticks, ticks[1:])), ticks
    assert lines[6:] == ["alarm at 12:34:58", "key pressed", "done: 5 ticks, 1 alarm, 1 key"]
    alarm = next(c["virtual_time_s"] for c in summary["console"] if c["line"] == "alarm at 12:34:58")
    assert 2.0 < alarm < 2.01                               # set at 12:34:56 just after start
    key = next(c["virtual_time_s"] for c in summary["console"] if c["line"] == "key pressed")
    assert 2.5 < key < 2.51
    _, changes = read_vcd((tmp_path / "t.vcd").read_text())
    edges = [t for t, v in changes["pad24"]]                # low from the start, then high, ...
    assert [v for t, v in changes["pad24"][:3]] == ["0", "1", "0"]
    lows = [round((b - a) / PS_PER_US) for a, b in zip(edges[0::2], edges[1::2])]
    highs = {round((b - a) / PS_PER_US) for a, b in zip(edges[1::2], edges[2::2])}
    # (the first low begins when the pad is routed to the timer, some instructions before the PWM
    # starts: a little longer, by as many cycles as those instructions take)
    assert set(lows[1:]) == {750} and 750 <= lows[0] <= 751 and highs == {250}     # microseconds


def test_boot_key_tells_each_press_and_release_and_lights_the_green_led(c_firmware, tmp_path):
    """boot_key.c (the live view's browser test presses its key from the page): both edges of the
    BOOT key through the PLIC, the green LED (pad 13) low while the key is down."""
    out = tmp_path / "out"
    run = run_emulator("run", str(c_firmware / "boot_key.elf"), "--until", "0.1", "--quiet", "--out", str(out),
                       "--pin", "16=0@0.03", "--pin", "16=z@0.05", "--pin", "16=0@0.06", "--pin", "16=z@0.07")
    assert run.returncode == 0, run.stderr
    summary = json.loads((out / "run.json").read_text())
    assert console_of(summary) == ["boot_key: press the BOOT key", "BOOT key pressed (1)", "BOOT key released (1)",
                                   "BOOT key pressed (2)", "BOOT key released (2)"]
    led = [(round(change["virtual_time_s"], 3), change["level"]) for change in summary["pad_changes"]
           if change["pad"] == 13]
    assert led == [(0.0, 1), (0.03, 0), (0.05, 1), (0.06, 0), (0.07, 1)]


def test_an_unfed_watchdog_interrupts_then_resets_and_the_program_finds_out(c_firmware, tmp_path):
    out = tmp_path / "out"
    run = run_emulator("run", str(c_firmware / "watchdog.elf"), "--until", "0.1", "--quiet", "--out", str(out))
    assert run.returncode == 0, run.stderr
    summary = json.loads((out / "run.json").read_text())
    assert console_of(summary) == ["watchdog started: 5 ms a timeout", "watchdog interrupt: not fed, not cleared",
                                   "restarted by the watchdog"]
    (reset,) = summary["resets"]
    assert reset["cause"] == "WDT0" and 0.0100 < reset["virtual_time_s"] < 0.0102   # two timeouts of 2^16 / 13 MHz


# --- the flash on SPI3 ------------------------------------------------------------------------

FLASH_TEST_DATA = 0x100000


def flash_dump(tmp_path) -> Path:
    """A dump of the flash's first MiB and 16 bytes: erased, but 16 known bytes at 0x100000."""
    dump = bytearray(b"\xFF") * (FLASH_TEST_DATA + 16)
    dump[FLASH_TEST_DATA:] = bytes(range(0x10, 0x20))
    path = tmp_path / "flash.img"
    path.write_bytes(dump)
    return path


def flash_run(c_firmware, out, *flags) -> list[str]:
    run = run_emulator("run", str(c_firmware / "flash.elf"), "--until", "1", "--expect", "flash done", "--quiet",
                       "--out", str(out), *flags)
    assert run.returncode == 0, run.stderr
    return console_of(json.loads((out / "run.json").read_text()))


def test_flash_id_erase_quad_program_and_reads_on_spi3(c_firmware, tmp_path):
    """flash.c through SPI3 (the DWC_ssi layout): the W25Q128's JEDEC ID, a sector erase, a quad
    page program by DMA read back in quad I/O by DMA (8-bit frames) and with the standard read,
    programming that only clears bits; the test's bytes read as 32-bit quad frames come first byte
    in the top bits (as MicroPython's w25qxx driver expects: it swaps each word's bytes back)."""
    dump = flash_dump(tmp_path)
    before = dump.read_bytes()
    lines = flash_run(c_firmware, tmp_path / "out", "--flash", str(dump))
    assert lines[1:] == ["jedec id ef 40 18, quad on", "erased: all ff",
                         "programmed: quad read matches, standard read matches", "f0 then 0f: all 00",
                         "erased again: all ff", "test data 10111213 14151617 18191a1b 1c1d1e1f",
                         "runs before this one: 0"]
    assert dump.read_bytes() == before                 # read-only unless asked


def test_flash_writes_reach_the_dump_only_when_asked(c_firmware, tmp_path):
    dump = flash_dump(tmp_path)
    saved = tmp_path / "saved.img"
    assert flash_run(c_firmware, tmp_path / "a", "--flash", str(dump), "--flash-save", str(saved))[-1] == \
        "runs before this one: 0"
    assert len(saved.read_bytes()) == 16 * 1024 * 1024 and saved.read_bytes()[0x300000] == 0
    assert flash_run(c_firmware, tmp_path / "b", "--flash", str(saved), "--flash-writable")[-1] == "runs before this one: 1"
    assert flash_run(c_firmware, tmp_path / "c", "--flash", str(saved))[-1] == "runs before this one: 2"
    assert saved.read_bytes()[0x300000:0x300003] == b"\x00\x00\xFF"


def test_flash_writable_refuses_a_kfpkg_or_a_program(c_firmware, tmp_path):
    program = tmp_path / "firmware.bin"
    program.write_bytes((c_firmware / "hello.elf").read_bytes()[:64])
    run = run_emulator("run", str(c_firmware / "flash.elf"), "--flash", str(program), "--flash-writable", "--quiet",
                       "--out", str(tmp_path / "out"))
    assert run.returncode == 6 and "cannot take the flash's changes back" in run.stderr


def test_the_paths_maixpy_boots_through(c_firmware, tmp_path):
    """maixpy_boot.c, the paths LoBo's MaixPy (FreeRTOS on both cores) takes at boot: hart 1 started
    by hart 0's software interrupt, each hart's yields served by its own trap handler run, a spinlock
    the two take turns at around a read-modify-write of a shared counter (no increment lost); the
    file system's first block read from the flash in quad output by DMA, the channel's completion
    taken as its PLIC interrupt with intsignal_en as at reset; the BOOT key on its pulled-up pad."""
    dump = bytearray(b"\xFF") * (0x500000 + 64)
    dump[0x500000:0x500010] = bytes([1, 0, 0, 0, 0xF0, 0x0F, 0xFF, 0xF7]) + b"littlefs"   # a LittleFS superblock's start
    (tmp_path / "flash.img").write_bytes(dump)
    out = tmp_path / "out"
    run = run_emulator("run", str(c_firmware / "maixpy_boot.elf"), "--flash", str(tmp_path / "flash.img"),
                       "--until", "0.05", "--quiet", "--out", str(out))
    assert run.returncode == 0, run.stderr
    summary = json.loads((out / "run.json").read_text())
    assert console_of(summary) == ["hart 0 starts hart 1",
                                   "shared 400 (hart 0 200, hart 1 200), yields 200 and 200",
                                   "file system block: littlefs, by the DMA interrupt",
                                   "BOOT key reads 1"]
    assert summary["exceptions"] == {"environment call from M-mode": 400}
    assert min(summary["instructions"]) > 10_000          # both harts ran their rounds
