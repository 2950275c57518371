"""Command line: `python -m emulator run FIRMWARE.elf [--frames N] [--out DIR] ...`."""
from __future__ import annotations

import argparse
import gc
import math
import os
import signal
import sys
import time
from pathlib import Path
from typing import TextIO

from k210_common.exit_status import (BY_CODE, EXIT_BAD_INPUT, EXIT_EXPECT_UNMET, EXIT_FAIL_ON, EXIT_FIRMWARE_ERROR,
                                     EXIT_GOLDEN_MISMATCH, EXIT_HANG, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_MISUSE,
                                     EXIT_OK, EXIT_STRAY_WRITE, EXIT_TERMINATED, EXIT_TRAP, EXIT_UNMODELLED,
                                     EXIT_USAGE, EXIT_WRITE_FAILED, help_epilog)
from ..errors import BadInput, BoardStop, Interrupted
from ..devices.sdcard import FAULTS
from ..cpu.timing import TIMING_MODELS, TIMING_ROCKET
from ..cpu.hart import ENGINE_FAST, ENGINES
from ..board.wiring import LCD_8080, LCD_INTERFACES

PROG = "python -m emulator"
MAX_QUANTUM = 1_000_000_000    # instructions per turn; the native counter's limit is 64-bit, runs need far less
MAX_TOLERANCE = 255            # a channel of an RGB888 pixel differs by at most 255
DEFAULT_FRAMES = 8
MAX_PAD_CHANGES_IN_RUN_JSON = 10_000    # a pin toggled for ever must not bloat run.json

# When this command returns each status (k210_common/exit_status.py holds the numbers and
# names); --help and the README's table are made from it (tests/test_exit_status.py)
EXIT_STATUS_DETAILS: dict[int, str] = {
    EXIT_OK: "the requested frames were shown, or `--until`'s time was reached, or (with `--expect`) the console "
             "printed every expected text (with `--golden`: all match; every `--grab` was taken)",
    EXIT_INTERNAL: "an internal error of the board model",
    EXIT_USAGE: f"bad command line: an unknown option or a value out of range (`--frames`, `--quantum` 1..{MAX_QUANTUM}, "
                f"`--budget` and `--until` above 0 and finite, `--tolerance` 0..{MAX_TOLERANCE}, `--sd-fault`, "
                "`--lcd-interface`, `--timing`, a `--grab`'s syntax or time, a `--pin` that is not `PAD=LEVEL@SECONDS` "
                "with a pad 0..47), `--out` equal to or inside `--golden` or the folder of the `--sd` image, "
                "an option without the one it needs (`--tolerance` without `--golden`, "
                "`--sd-writable` or `--sd-fault` without `--sd`), `--until` or `--expect` with `--frames`, "
                "`--gdb-wait` without `--gdb`, `--gdb` with `--expect`/`--fail-on`, a `--gdb` port above 65535, "
                "`--trace-from`/`--trace-to` without `--trace-insn` or in the wrong order, a `--grab` of a symbol "
                "the firmware does not define or of a buffer outside SRAM, an empty `--expect`/`--fail-on` text or "
                "a regular expression that does not compile; or, after a run that ended well, a `--grab` whose "
                "time the run ended before",
    EXIT_TRAP: "the firmware trapped: an exception whose handler never returned, after which no hart could go on "
               "(the handler parked the harts) or no frame came within `--budget`; an exception with `mtvec` "
               "pointing at no memory; a jump into a block the model lacks; with `--stop-on-trap`, any exception "
               "(after its handler's 0.5 s of virtual time to report it)",
    EXIT_HANG: "no frame within `--budget` virtual seconds, or every hart waits forever (neither with `--until`), "
               "or a trap storm (the same exception at the same pc with the same registers 1,000 times in a row, "
               "no device store in between)",
    EXIT_UNMODELLED: "the firmware touched an address or register the model does not implement; with `--strict` "
                     "also an access the K210's bus answers in a way of its own (see `--strict`)",
    EXIT_BAD_INPUT: "a file or folder the command line names cannot be used: the firmware image (missing, "
                    "unreadable, not a RISC-V ELF, a raw `.bin` that is empty or larger than SRAM), the "
                    "`--uart-input` or `--pin-file` file (missing or unreadable; a `--pin-file` line that is not "
                    "`SECONDS PAD LEVEL`), the `--trace-insn` or `--vcd` file (cannot be written), the `--gdb` "
                    "port (in use), the card image (missing, empty, or not a whole number of 512-byte blocks), "
                    "the `--golden` folder (missing or a file) or one of its frames (not a readable PNG), the "
                    "`--out` folder (a file of that name exists, or it cannot be created or written in)",
    EXIT_MISUSE: "something the real K210 does not do, such as running the CPU from PLL0 "
                 "before it locked, or using a peripheral whose clock is gated",
    EXIT_FIRMWARE_ERROR: "the firmware reported a fatal error on its console (`error <code> <words>`)",
    EXIT_GOLDEN_MISMATCH: "`--golden`: a shown frame differs from its golden PNG (diff images are in the output "
                          "folder)",
    EXIT_STRAY_WRITE: "`--check-writes`: a store (a hart's or a DMA channel's) landed in SRAM outside the "
                      "firmware's buffers",
    EXIT_FAIL_ON: "the console printed a `--fail-on`/`--fail-on-re` text",
    EXIT_EXPECT_UNMET: "`--expect`: the run ended (`--until`'s time, or `--budget` virtual seconds without the "
                       "next expected text) before the console printed every expected text",
    EXIT_WRITE_FAILED: "an output could not be written during or after the run (a frame, console.log, the "
                       "animation, `--trace-insn`, `--vcd`: a full disk, a file size limit): the run stops there, "
                       "and run.json (with `output_failed`) and what else can be written are written",
    EXIT_INTERRUPTED: "Ctrl-C (SIGINT) stopped the run: it ends after the instruction under way and writes "
                      "run.json, console.log, the frames shown so far and the animation as any end does; a second "
                      "Ctrl-C ends the process at once",
    EXIT_TERMINATED: "SIGTERM stopped the run, as Ctrl-C does",
}

EXIT_STATUS_HELP = help_epilog(EXIT_STATUS_DETAILS) + """
The command line, then the --golden frames, the --grab buffers and the --out folder are checked
before the run: a refusal there (2 or 6) writes nothing. Every run that starts writes run.json in
the output folder, whatever its status. After the run the first that applies decides: how the run
stopped (3-8, 10-12), --golden (9), a --grab not taken (2).
"""


def _whole_number(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None


def frames_count(text: str) -> int:
    value = _whole_number(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, not {value}")
    return value


def quantum_count(text: str) -> int:
    value = _whole_number(text)
    if not 1 <= value <= MAX_QUANTUM:
        raise argparse.ArgumentTypeError(f"must be 1..{MAX_QUANTUM} CPU cycles, not {value}")
    return value


def budget_seconds(text: str) -> float:
    """A finite number of virtual seconds above 0: 0 or less would call every run hung at once,
    nan and inf would turn hang detection off without saying so."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"must be a finite number of seconds above 0, not {text}")
    return value


def port_number(text: str) -> int:
    value = _whole_number(text)
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"must be a TCP port 0..65535 (0: any free one), not {value}")
    return value


def time_seconds(text: str) -> float:
    """A finite virtual time of 0 or more."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"must be a finite number of seconds, 0 or more, not {text}")
    return value


def pin_change(text: str):
    from ..board.pins import parse_pin
    try:
        return parse_pin(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def tolerance_value(text: str) -> int:
    value = _whole_number(text)
    if not 0 <= value <= MAX_TOLERANCE:
        raise argparse.ArgumentTypeError(f"must be 0..{MAX_TOLERANCE} (a channel differs by at most "
                                         f"{MAX_TOLERANCE}), not {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=PROG, description="Sipeed Maix Dock (Kendryte K210) board model",
                                     epilog=EXIT_STATUS_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a firmware ELF and capture the LCD's frames",
                         epilog=EXIT_STATUS_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    run.add_argument("firmware", nargs="?", default=None,
                     help="firmware ELF (linked for SRAM at 0x80000000), or a raw image ending in .bin "
                          "(firmware.bin, as kflash writes it and the ROM copies it to 0x80000000); left out "
                          "with --flash: boot the program at the flash's address 0 as the mask ROM does")
    run.add_argument("--flash", metavar="IMAGE", default=None,
                     help="the content of the Dock's 16 MiB SPI flash: a .kfpkg (each file at its address, "
                          "as kflash writes it), a program .bin (written at 0 with the ROM's boot header, as "
                          "`make flash` writes it) or any other file as a dump of the flash from address 0")
    run.add_argument("--flash-writable", action="store_true",
                     help="with --flash: write the flash's content back to IMAGE when the run ends (IMAGE must "
                          "be a dump; without this the firmware's programs and erases last for the run only)")
    run.add_argument("--flash-save", metavar="DUMP", default=None,
                     help="when the run ends, write the flash's 16 MiB to DUMP (a dump later runs can give to "
                          "--flash), whatever --flash was")
    run.add_argument("--otp", metavar="FILE", default=None,
                     help="the K210's 16 KiB OTP content (a dump; shorter files are padded with 0), which "
                          "firmware reads through the OTP block; without it the OTP reads as blank (all 0)")
    run.add_argument("--sd", metavar="IMAGE", help="SD card image in the Dock's slot (opened read-only: the "
                     "firmware's writes are kept in memory for the run)")
    run.add_argument("--sd-writable", action="store_true", help="with --sd: let the firmware's writes reach the "
                     "image file")
    run.add_argument("--sd-fault", action="append", default=[], metavar="FAULT", choices=list(FAULTS),
                     help="with --sd: make the card misbehave, to test firmware error paths: "
                          "no-init (never leaves idle), bad-crc (every block's CRC16 wrong), "
                          "flaky-crc (each block's first CRC16 wrong); repeatable")
    run.add_argument("--frames", type=frames_count, default=None,
                     help="stop after this many frames reach the LCD (default 8; at least 1)")
    run.add_argument("--until", type=budget_seconds, default=None, metavar="SECONDS",
                     help="instead of counting frames, run until this virtual time (finite, above 0), for "
                          "firmware whose output is its console or its pins: frames shown are kept, no frame "
                          "budget applies, and a board whose harts all sleep for good skips ahead to it")
    run.add_argument("--expect", dest="expected", action="append", default=[], metavar="TEXT",
                     type=literal_pattern,
                     help="end the run with success (status 0) once the console has printed TEXT and every "
                          "--expect/--expect-re before it, in order; found wherever it is printed, within a "
                          "line or across lines; frames then end nothing; without --until the run fails "
                          "(status 12) after --budget seconds of virtual time without the next one; repeatable")
    run.add_argument("--expect-re", dest="expected", action="append", metavar="REGEX", type=regex_pattern,
                     help="as --expect, a Python regular expression matched against each whole console line")
    run.add_argument("--fail-on", dest="failures", action="append", default=[], metavar="TEXT",
                     type=literal_pattern,
                     help="end the run with failure (status 11) when the console prints TEXT; repeatable")
    run.add_argument("--fail-on-re", dest="failures", action="append", metavar="REGEX", type=regex_pattern,
                     help="as --fail-on, a regular expression matched against each whole console line")
    run.add_argument("--uart-input", metavar="FILE", default=None,
                     help="send FILE's bytes to pad 4 (the Dock's USB serial bridge), to the receiver of the UART "
                          "FPIOA routes from it (UARTHS at reset, UART3 after the SDK's start-up), at the baud "
                          "the firmware set (each when the receiver is on and has room); '-' reads "
                          "standard input: piped, all of it; from a terminal, each key as it is typed, with "
                          "virtual time held to the host's clock")
    run.add_argument("--uart-script", metavar="FILE", default=None,
                     help="hold a conversation with the console: FILE's lines 'expect TEXT', 'expect-re REGEX', "
                          "'send TEXT' (\\r, \\n, \\xNN escapes), 'sleep SECONDS' and 'timeout SECONDS' (how long "
                          "each later expect may wait; 10 s), in order; sends go where --uart-input's would. The "
                          "run ends when the last step is done, or fails (status 12) at an expect not met in time")
    run.add_argument("--pin", dest="pins", action="append", default=[], metavar="PAD=LEVEL@SECONDS", type=pin_change,
                     help="drive a pad from outside from SECONDS of virtual time on: LEVEL 0 or 1, or z to let "
                          "go of it (a key: the Dock's BOOT key is pad 16, pressed = 0); repeatable. GPIOHS and "
                          "GPIO lines routed to the pad read it, with their edge and level interrupts; a line "
                          "the chip drives reads its own output")
    run.add_argument("--pin-file", metavar="FILE", type=Path, default=None,
                     help="more such changes from FILE, a line each: SECONDS PAD LEVEL ('#' starts a comment)")
    run.add_argument("--trace-insn", metavar="FILE", type=Path, default=None,
                     help="write an instruction trace to FILE: per instruction the hart, virtual time, pc, "
                          "disassembly and the registers it wrote (about 60 bytes per instruction; the model runs "
                          "at about 1 %% of its speed inside the window)")
    run.add_argument("--trace-from", metavar="SECONDS", type=time_seconds, default=None,
                     help="with --trace-insn: start the trace at this virtual time (default 0)")
    run.add_argument("--trace-to", metavar="SECONDS", type=time_seconds, default=None,
                     help="with --trace-insn: end the trace at this virtual time (default: the end of the run)")
    run.add_argument("--vcd", metavar="FILE", type=Path, default=None,
                     help="write the pins over virtual time as a Value Change Dump (GTKWave, sigrok): every pad a "
                          "GPIOHS or GPIO line drives (LEDs, the LCD's reset and D/C), SPI0's and SPI1's slave "
                          "selects, and their clocks as bursts (high while frames are on the wire)")
    run.add_argument("--profile", action="store_true",
                     help="write profile.txt (per hart, instructions and cycles per function, exclusive and "
                          "inclusive, with calls; per frame the top functions) and profile.folded (call stacks "
                          "weighted by cycles, for flame graphs and speedscope) into the output folder; the "
                          "model runs several times slower with it")
    run.add_argument("--gdb", metavar="PORT", type=port_number, default=None,
                     help="serve GDB's remote protocol on 127.0.0.1:PORT (0: any free port, printed): attach "
                          "with gdb-multiarch FIRMWARE.elf -ex 'target remote :PORT'; while GDB is attached it "
                          "drives the run (frames and --until end nothing); after it detaches the run goes on "
                          "to its end, a kill ends it (status 0)")
    run.add_argument("--gdb-wait", action="store_true",
                     help="with --gdb: wait for GDB before the first instruction (else the board runs until it "
                          "attaches)")
    run.add_argument("--out", default="build/frames", type=Path, help="output folder (default build/frames)")
    run.add_argument("--budget", type=budget_seconds, default=5.0,
                     help="virtual seconds allowed between frames before the run counts as hung "
                          "(default 5; finite, above 0)")
    run.add_argument("--quantum", type=quantum_count, default=20_000,
                     help=f"CPU cycles per hart per turn (default 20000; 1..{MAX_QUANTUM})")
    run.add_argument("--timing", choices=TIMING_MODELS, default=TIMING_ROCKET,
                     help="what an instruction costs: rocket (the default), the cycles the K210's Rocket core "
                          "takes (result latencies, the iterative multiplier and divider, branch prediction; "
                          "mcycle and virtual time follow them); ipc1, one cycle per instruction, the model "
                          "before cycle timing")
    run.add_argument("--engine", choices=ENGINES, default=ENGINE_FAST,
                     help="fast (the default): the harts' code in SRAM runs on the model's own interpreter, "
                          "the rest on Unicorn; precise: everything on Unicorn, each instruction counted by a "
                          "hook (slower; what runs, every count and every time are the same)")
    run.add_argument("--golden", metavar="DIR", type=Path,
                     help="compare every shown frame with DIR/frame_NNNN.png of the same index; write "
                          "diff_NNNN.png for frames that differ and exit with status 9 on any mismatch")
    run.add_argument("--tolerance", type=tolerance_value, default=None, metavar="N",
                     help="with --golden: a pixel matches when no channel differs by more than N "
                          f"(0..{MAX_TOLERANCE}; default 0: exact)")
    run.add_argument("--grab", action="append", default=[], metavar="WHAT@SECONDS",
                     help="write a PNG of a framebuffer at a virtual time, whether or not a frame is complete: "
                          "WHAT is 'gram' (the LCD's memory), a firmware symbol or a 0x address of a 320x240 "
                          "RGB565 buffer in SRAM; add ':pairs' for the project's pixel-pair order or "
                          ":WxH for another size, e.g. --grab framebuffers@0.45:pairs; repeatable. "
                          "A time the run ends before fails the run (status 2)")
    run.add_argument("--check-writes", action="store_true",
                     help="stop with exit status 10 at the first store into SRAM outside the firmware's buffers "
                          "(.data/.bss, the heap handed out so far, the storing hart's own stack): a checker "
                          "of the board model, like a watchpoint; the real K210 lets such stores through")
    run.add_argument("--lcd-interface", choices=LCD_INTERFACES, default=LCD_8080,
                     help="the LCD's bus: 8080, the Dock's panel, an 8-bit parallel bus on SPI0's eight data "
                          "lines (octal frames; the default), or spi, a 4-line serial ST7789V module on SPI0's "
                          "data line 0 (standard frames)")
    run.add_argument("--quiet", action="store_true", help="do not echo the console or show progress")
    run.add_argument("--permissive", action="store_true",
                     help="an access to a register a modelled device does not implement warns (loads read 0, "
                          "stores are ignored) instead of stopping the run; addresses no device claims still stop it")
    run.add_argument("--cold", action="store_true",
                     help="start from the reset value of every register (CPU on the 26 MHz oscillator, clocks "
                          "gated, pads unrouted) instead of the state the K210's mask ROM hands a program "
                          "(CPU at 390 MHz from PLL0, the clocks the ROM and Dock firmware use on, UARTHS at "
                          "115200 baud on pads 4 and 5)")
    run.add_argument("--stop-on-trap", action="store_true",
                     help="end the run (status 3) at the first synchronous exception, after its handler's 0.5 s "
                          "of virtual time to report it, instead of letting the firmware's trap handler deal "
                          "with it as the chip does (ecall system calls, misaligned accesses it emulates)")
    run.add_argument("--strict", action="store_true",
                     help="stop (status 5) at the first access the K210's bus answers in a way of its own instead "
                          "of answering it as the chip does with a warning: an 8/16-bit or 64-bit access to "
                          "32-bit registers, a 32-bit access to half of a 64-bit DMAC register, a store to a "
                          "read-only or load from a write-only register, an offset of a TileLink device without "
                          "a register, an address no device answers, the debug region at address 0; and have the "
                          "LCD and the SD card enforce their datasheets' waits (a command too soon after a reset "
                          "or SLPIN/SLPOUT is ignored, a RESX pulse under 10 us does not reset, CMD0 before 74 "
                          "clocks is ignored) instead of carrying them out with a warning")
    return parser


def literal_pattern(text: str):
    from .console_watch import ConsolePattern
    try:
        return ConsolePattern.literal(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def regex_pattern(text: str):
    from .console_watch import ConsolePattern
    try:
        return ConsolePattern.expression(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def option_problem(args: argparse.Namespace) -> str | None:
    """What is wrong with the combination of options (argparse checked each value)."""
    if args.trace_insn is None and (args.trace_from is not None or args.trace_to is not None):
        return "--trace-from and --trace-to need --trace-insn (the file the trace goes to)"
    if args.trace_from is not None and args.trace_to is not None and args.trace_to <= args.trace_from:
        return f"--trace-to ({args.trace_to:g} s) must come after --trace-from ({args.trace_from:g} s)"
    if args.gdb_wait and args.gdb is None:
        return "--gdb-wait needs --gdb (the port GDB attaches to)"
    if args.gdb is not None and (args.expected or args.failures):
        return "--gdb excludes --expect and --fail-on (under GDB, GDB decides when the run stops)"
    if args.uart_script is not None and (args.uart_input is not None or args.expected or args.frames is not None
                                         or args.gdb is not None):
        return ("--uart-script excludes --uart-input, --expect, --frames and --gdb (the script sends to the "
                "console, waits for it and ends the run; add --until to bound it in virtual time)")
    if args.expected and args.frames is not None:
        return ("--expect and --frames exclude each other (with --expect the run ends when the console has "
                "printed the texts; add --until to bound it in virtual time)")
    if args.until is not None and args.frames is not None:
        return "--until and --frames exclude each other (a run ends at a virtual time or after frames)"
    if args.tolerance is not None and args.golden is None:
        return "--tolerance needs --golden (it says how far a pixel may differ from its golden frame)"
    if args.firmware is None and args.flash is None:
        return "give a firmware file, or --flash IMAGE to boot the program in the flash as the mask ROM does"
    if args.firmware is None and args.profile:
        return "--profile needs the firmware's ELF for its symbols (give it as well as --flash)"
    if args.flash is None and args.flash_writable:
        return "--flash-writable needs --flash (the dump the flash's changes would go back to)"
    if args.flash_save is not None:
        target = Path(args.flash_save).resolve()
        if args.flash is not None and target == Path(args.flash).resolve() and not args.flash_writable:
            return (f"--flash-save {args.flash_save} names the --flash image, which stays read-only unless "
                    f"--flash-writable is given (for a dump)")
        if not target.parent.is_dir() or not os.access(target.parent, os.W_OK):
            return f"--flash-save {args.flash_save}: its folder does not exist or cannot be written"
    if args.sd is None and args.sd_writable:
        return "--sd-writable needs --sd (the card image the firmware's writes would reach)"
    if args.sd is None and args.sd_fault:
        return "--sd-fault needs --sd (a card in the slot to misbehave)"
    return output_overwrites_input(args)


def output_overwrites_input(args: argparse.Namespace) -> str | None:
    """The run writes frame_NNNN.png, run.json and more into --out: refused where that would
    replace what the run compares with (the golden frames) or mix with a card's files."""
    out = Path(args.out).resolve()
    if args.golden is not None:
        golden = Path(args.golden).resolve()
        if out == golden or golden in out.parents:
            return (f"--out {args.out} is the --golden folder {args.golden} (or inside it): the run's frames "
                    f"would replace the goldens; give another output folder")
    if args.sd is not None and out == Path(args.sd).resolve().parent:
        return (f"--out {args.out} is the folder the --sd card image {args.sd} is in: the run's output would be "
                f"written beside the card; give another output folder")
    return None


def pad_changes_summary(board) -> dict:
    """run.json's record of the pads GPIOHS and GPIO lines drove: every change (the first
    MAX_PAD_CHANGES_IN_RUN_JSON) with its virtual time, and how many there were."""
    if board is None:
        return {"pad_changes": [], "pad_changes_total": 0}
    changes = [{"virtual_time_s": at, "pad": pad, "level": level}
               for at, pad, level in board.pad_changes[:MAX_PAD_CHANGES_IN_RUN_JSON]]
    return {"pad_changes": changes, "pad_changes_total": board.wiring.pad_change_count}


def golden_count(args: argparse.Namespace) -> int:
    """How many golden frames to load before the run: --frames, or with --until as many as the
    folder holds (a folder that is missing is reported by load_golden_frames)."""
    if args.frames is not None:
        return args.frames
    return max(1, len(list(args.golden.glob("frame_*.png")))) if args.golden.is_dir() else 1


def grab_problem(grabs: list, firmware: str | None) -> str | None:
    """Before the run: every --grab of a symbol or address names a buffer in SRAM. A firmware
    that cannot be read is left for the run to report (status 6)."""
    from ..board.elf import read_symbol_values
    from .grab import check_grab_buffer
    symbols: dict[str, int] = {}
    if any(g.what != "gram" and not g.what.lower().startswith("0x") for g in grabs):
        if firmware is None:
            return "--grab of a symbol needs the firmware's ELF (booted from --flash there are no symbols)"
        try:
            symbols = read_symbol_values(firmware)
        except BadInput:
            return None
    for request in grabs:
        try:
            check_grab_buffer(request, symbols)
        except ValueError as error:
            return f"--grab {error}"
    return None


# --expect without --until: how far the run may go in virtual time at most (the --budget
# deadline after each expected text ends it long before)
EXPECT_HORIZON_S = 1e6


def read_otp(source: str) -> bytes:
    """--otp FILE's bytes: at most the OTP's 16 KiB. BadInput naming the file otherwise."""
    from ..devices.otp import SIZE_BYTES
    path = Path(source)
    try:
        data = path.read_bytes()
    except OSError as error:
        raise BadInput(f"--otp {source}: cannot read it ({error.strerror or error})") from None
    if len(data) > SIZE_BYTES:
        raise BadInput(f"--otp {source}: {len(data)} bytes, more than the OTP's {SIZE_BYTES}")
    return data


def run_script(board, script, until_s: float | None, progress):
    """--uart-script: runs until the script ends the run (done: ConsoleExpectationsMet; an expect not
    met in its time: ConsoleExpectationUnmet), or fails at --until's time."""
    from ..errors import ConsoleExpectationUnmet
    result = board.run_until(until_s if until_s is not None else EXPECT_HORIZON_S, progress=progress)
    if board.scheduler.pending_stop is not None:
        raise board.scheduler.pending_stop          # the script ended (or failed) as the run did
    step = script.step
    if step is None:
        return result
    bound = "--until" if until_s is not None else "the longest run"
    raise ConsoleExpectationUnmet(f"--uart-script {script.path}:{step.line}: {step.describe()}: not done by "
                                  f"{board.time:g} s of virtual time ({bound})")


def run_expecting(board, watch, until_s: float | None, budget_s: float, progress):
    """--expect: runs until the console has printed every expected text (the watch ends the run
    with ConsoleExpectationsMet), or fails at --until's time, or without --until after
    budget_s of virtual time without the next expected text."""
    from ..errors import ConsoleExpectationUnmet
    if until_s is not None:
        board.run_until(until_s, progress=progress)
        raise ConsoleExpectationUnmet(watch.unmet_message(f"by --until's {until_s:g} s of virtual time"))

    def arm(at_s: float) -> None:
        count = len(watch.matches)

        def deadline(board) -> None:
            if len(watch.matches) != count:          # an expected text came meanwhile
                arm(watch.matches[-1].virtual_time_s + budget_s)
                return
            since = "the previous expected text" if count else "reset"
            raise ConsoleExpectationUnmet(watch.unmet_message(
                f"in {budget_s:g} s of virtual time after {since} (--budget)"))
        board.grab_at(at_s, deadline)

    arm(budget_s)
    board.run_until(EXPECT_HORIZON_S, progress=progress)
    raise ConsoleExpectationUnmet(watch.unmet_message(f"by {EXPECT_HORIZON_S:g} s of virtual time"))


def run_under_gdb(board, args: argparse.Namespace, terminal):
    """--gdb: serves GDB on the board (gdbstub.py). Without --gdb-wait the board runs until GDB
    attaches (or until the run's own end); after GDB detaches the run goes on to its end."""
    import select as select_module
    from .gdbstub import GdbServer
    from ..board.scheduler import RunResult
    server = GdbServer(board, args.gdb, terminal.message)
    scheduler = board.scheduler
    terminal.message(f"[gdb] listening on 127.0.0.1:{server.port}; attach with: gdb-multiarch {args.firmware or ''} "
                     f"-ex 'target remote 127.0.0.1:{server.port}'")
    try:
        if not args.gdb_wait:
            scheduler.frames_wanted = args.frames if args.frames is not None else 1 << 62
            while not select_module.select([server.listener], [], [], 0)[0]:
                if args.until is not None and scheduler.time >= args.until:
                    return board.run_until(args.until)
                if args.frames is not None and len(board.frames) >= args.frames:
                    return board.run(args.frames)
                scheduler.step()
        server.accept()
        budget, scheduler.hang_budget_s = scheduler.hang_budget_s, math.inf   # GDB decides when it is stuck
        outcome = server.serve()
        scheduler.hang_budget_s = budget
    finally:
        server.close()
    if outcome == "killed":
        terminal.message("[gdb] GDB killed the run")
        return RunResult("ok", f"ended by GDB (kill) at {board.time * 1e3:.3f} ms of virtual time; "
                               f"{len(board.frames)} frames shown", board.frames, board.time,
                         [h.instret for h in board.harts], 0.0, board.warnings)
    terminal.message(f"[gdb] GDB {outcome}; the run goes on to its end")
    scheduler._last_frame_time = board.time       # the frame budget counts from here, not from before GDB
    if args.until is not None:
        return board.run_until(max(args.until, board.time))
    return board.run(max(args.frames, len(board.frames)))


class Terminal:
    """What the user sees: the firmware's console on stdout and, when stderr is a terminal, a
    progress line on stderr that is rewritten in place. Console lines are written whole, each
    after clearing the progress line, so that neither is written into the other."""

    CLEAR_LINE = "\r\033[K"

    def __init__(self, quiet: bool, out: TextIO | None = None, err: TextIO | None = None,
                 immediate: bool = False) -> None:
        """immediate: write each console byte at once (an interactive run, whose prompts end
        no line), with no progress line to keep apart."""
        self.out = out or sys.stdout
        self.err = err or sys.stderr
        self.quiet = quiet
        self.immediate = immediate
        self.shows_progress = not quiet and self.err.isatty() and not immediate
        self._line = bytearray()
        self._progress_shown = False

    def _clear_progress(self) -> None:
        if self._progress_shown:
            self.err.write(self.CLEAR_LINE)
            self.err.flush()
            self._progress_shown = False

    def console_byte(self, byte: int) -> None:
        if self.quiet:
            return
        self._line.append(byte)
        if byte == 10 or self.immediate:
            self._write_console_line()

    def _write_console_line(self) -> None:
        self._clear_progress()
        self.out.flush()
        self.out.buffer.write(bytes(self._line))
        self.out.flush()
        self._line.clear()

    def progress(self, board) -> None:
        frames = len(board.frames)
        total = sum(h.instret for h in board.harts)
        self.out.flush()
        self.err.write(f"{self.CLEAR_LINE}[board] frame {frames}/{board._frames_wanted}  virtual "
                       f"{board.time * 1e3:9.2f} ms  {total / 1e6:9.2f} M instructions")
        self.err.flush()
        self._progress_shown = True

    def message(self, text: str) -> None:
        """A line of the board model's own (warnings, results) on stderr."""
        self._clear_progress()
        self.out.flush()
        self.err.write(text + "\n")
        self.err.flush()

    def warning(self, text: str) -> None:
        if not self.quiet:
            self.message(f"[board] warning: {text}")

    def finish(self) -> None:
        """The end of the run: a console line the firmware did not end is shown as it is."""
        if self._line:
            self._line.append(10)
            self._write_console_line()
        self._clear_progress()


def usage_error(message: str) -> int:
    print(f"{PROG} run: error: {message}", file=sys.stderr)
    return EXIT_USAGE


def stop_on_signals(board) -> dict:
    """SIGINT and SIGTERM end the run after the instruction under way, so that everything it has is
    written (Interrupted); a second one while that stop is under way ends the process at once, as
    it would have without this. Returns the handlers replaced, to put back after the run."""
    def stop(number: int, _frame) -> None:
        if isinstance(board.scheduler.pending_stop, Interrupted):
            signal.signal(number, signal.SIG_DFL)
            os.kill(os.getpid(), number)
            return
        board.stop_run(Interrupted(number, signal.Signals(number).name))
    return {number: signal.signal(number, stop) for number in (signal.SIGINT, signal.SIGTERM)}


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    problem = option_problem(args)
    if problem:
        return usage_error(problem)
    if args.until is None and args.frames is None and not args.expected and args.uart_script is None:
        args.frames = DEFAULT_FRAMES
    from ..board import Board
    from .console_watch import ConsoleWatch
    from .trace import InstructionTrace, open_trace
    from .vcd import attach as attach_signal_log, open_vcd
    from .uart_input import UartInput
    from .golden import compare_run, load_golden_frames
    from .grab import GrabRequest, parse_grab
    from .output import RunOutput, prepare_output_folder, summary_dict
    try:
        grabs: list[GrabRequest] = [parse_grab(text) for text in args.grab]
    except ValueError as error:
        return usage_error(f"--grab {error}")
    try:
        goldens = load_golden_frames(args.golden, golden_count(args)) if args.golden is not None else None
        problem = grab_problem(grabs, args.firmware)
        if problem:
            return usage_error(problem)
        flash = None
        if args.flash is not None:
            from ..board.flash_image import FlashImage
            flash = FlashImage.open(args.flash, writable=args.flash_writable)
        uart_input = UartInput.open(args.uart_input) if args.uart_input is not None else None
        otp = read_otp(args.otp) if args.otp is not None else None
        script = None
        if args.uart_script is not None:
            from .uart_script import UartScript
            script = UartScript.open(args.uart_script)
        pins = list(args.pins)
        if args.pin_file is not None:
            from ..board.pins import load_schedule
            pins.extend(load_schedule(args.pin_file))
        prepare_output_folder(args.out)
        trace_file = open_trace(args.trace_insn) if args.trace_insn is not None else None
        vcd_file = open_vcd(args.vcd) if args.vcd is not None else None
    except BadInput as error:
        print(f"[board] stopped (bad-input): {error}", file=sys.stderr)
        return EXIT_BAD_INPUT

    output = RunOutput(args.out)
    terminal = Terminal(args.quiet, immediate=uart_input is not None and uart_input.interactive)
    watch = ConsoleWatch(args.expected, args.failures)
    board = None
    flash_saved = None                 # where --flash-save wrote the flash, once it has

    def console(byte: int) -> None:
        output.console_byte(byte)
        terminal.console_byte(byte)
        watch.byte(byte, board.console_byte_time)
        if script is not None:
            script.console_byte(byte, board.console_byte_time)

    taken: set[int] = set()

    def grab_action(index: int, request: GrabRequest):
        def action(board) -> None:
            output.grab(request, board)
            taken.add(index)
        return action

    started = time.perf_counter()
    trace = None
    profiler = None
    signal_log = None
    previous_handlers: dict = {}

    def on_frame(record, image) -> None:
        output.frame(record, image)
        if profiler is not None:
            profiler.frame(record)

    try:
        board = Board(None if args.firmware is None else str(args.firmware), flash=flash, quantum=args.quantum, hang_budget_s=args.budget, console=console,
                      on_frame=on_frame, on_warning=terminal.warning, permissive=args.permissive,
                      sd_image=args.sd, sd_writable=args.sd_writable, sd_faults=frozenset(args.sd_fault),
                      check_writes=args.check_writes, strict=args.strict, lcd_interface=args.lcd_interface,
                      cold=args.cold, timing=args.timing, engine=args.engine, pins=pins,
                      otp=otp, otp_source=f"--otp {args.otp}" if args.otp is not None else "")
        if uart_input is not None:
            board.connect_serial_input(uart_input)
        board.scheduler.traps.stop_on_trap = args.stop_on_trap
        if vcd_file is not None:
            signal_log = attach_signal_log(board)
        if args.profile:
            from .profile import Profiler
            profiler = Profiler(board, args.firmware)
        if trace_file is not None:
            trace = InstructionTrace(board, trace_file, args.trace_from or 0.0, args.trace_to)
        watch.attach(board.stop_run)
        # it may end the run (or answer) the moment a byte is out
        board.uarths.every_byte_heard = watch.active or script is not None
        if script is not None:
            board.connect_serial_input(script)
            script.attach(board)
        # One board a process, and what exists now lives until the run ends: frozen, it is no
        # longer scanned by every full collection, which the scheduler's allocations set off
        # every few virtual ms (each took milliseconds of host time).
        gc.freeze()
        for index, request in enumerate(grabs):
            board.grab_at(request.at_s, grab_action(index, request))
        progress = terminal.progress if terminal.shows_progress else None
        previous_handlers = stop_on_signals(board)
        if args.gdb is not None:
            result = run_under_gdb(board, args, terminal)
        elif args.expected:
            result = run_expecting(board, watch, args.until, args.budget, progress)
        elif script is not None:
            result = run_script(board, script, args.until, progress)
        elif args.until is not None:
            result = board.run_until(args.until, progress=progress)
        else:
            result = board.run(args.frames, progress=progress)
            board.finish_console_line()
        if board.scheduler.pending_stop is not None:
            raise board.scheduler.pending_stop     # recorded as the run's last turn ended
        status, kind, message = EXIT_OK, BY_CODE[EXIT_OK].name, result.message
    except BoardStop as stop:
        status, kind, message = stop.exit_status, stop.kind, str(stop)
    except Exception as error:  # an internal bug must still leave a run.json behind
        status, kind, message = EXIT_INTERNAL, BY_CODE[EXIT_INTERNAL].name, f"{type(error).__name__}: {error}"
        import traceback
        traceback.print_exc()
    for number, handler in previous_handlers.items():
        signal.signal(number, handler)
    terminal.finish()
    output_problems = []
    try:
        if trace is not None:
            trace.close()
        elif trace_file is not None:
            trace_file.close()
    except OSError as error:
        output_problems.append(f"{args.trace_insn}: {error.strerror or error}")
    if uart_input is not None:
        uart_input.close()
    if board is not None:
        board.close()
        try:
            if board.flash.writable and board.flash_chip.changed:
                board.flash.save()
            if args.flash_save is not None:
                board.flash.save(args.flash_save)
                flash_saved = args.flash_save
        except BoardStop as stop:
            terminal.message(f"[board] {stop}")
            if status == EXIT_OK:
                status, kind, message = stop.exit_status, stop.kind, str(stop)
        for text in board.repeated_warnings:
            terminal.warning(f"repeated: {text}")
    frames = board.frames if board is not None else []
    summary = summary_dict(kind, message, frames, board.time if board else 0.0,
                           [h.instret for h in board.harts] if board else [0, 0],
                           time.perf_counter() - started, board.warnings if board else [],
                           str(args.firmware) if args.firmware is not None else f"{args.flash} (booted from flash)",
                           board.device_writes if board else {}, board.console_lines if board else [])
    if args.golden is not None and board is not None:
        tolerance = args.tolerance or 0
        comparisons = compare_run(output.frame_paths, args.golden, output.folder, tolerance, goldens)
        summary["golden"] = {"folder": str(args.golden), "tolerance": tolerance,
                             "frames": [c.as_dict() for c in comparisons]}
        mismatches = [c for c in comparisons if not c.matches]
        for comparison in mismatches:
            terminal.message(f"[golden] {comparison.describe()}")
        if status == EXIT_OK and mismatches:
            status, kind = EXIT_GOLDEN_MISMATCH, BY_CODE[EXIT_GOLDEN_MISMATCH].name
            message = f"{len(mismatches)} of {len(comparisons)} frames differ from {args.golden}"
        elif status == EXIT_OK:
            terminal.message(f"[golden] all {len(comparisons)} frames match {args.golden}")
    if board is not None:
        missed = [request for index, request in enumerate(grabs) if index not in taken]
        for request in missed:
            output.missed_grab(request, board.time)
        if missed and status == EXIT_OK:
            status, kind = EXIT_USAGE, "grab-missed"
            message = (f"--grab {', '.join(r.label for r in missed)}: the run ended at {board.time:.6f} s of "
                       f"virtual time, before the grab's time, so nothing was written (ask for more --frames "
                       f"or an earlier time)")
    summary["exit"], summary["message"] = kind, message
    summary["grabs"] = output.grabs
    summary["writes_checked"] = args.check_writes
    summary["strict"] = args.strict
    summary["stop_on_trap"] = args.stop_on_trap
    summary["resets"] = ([{"virtual_time_s": at, "cause": cause} for at, cause in board.scheduler.resets]
                         if board is not None else [])
    summary["pins"] = [change.describe() for change in board.pins.played] if board is not None else []
    summary["exceptions"] = dict(board.scheduler.traps.taken) if board is not None else {}
    # every UART's output, wherever FPIOA routed it (the console is pad 5's only)
    summary["uart_output"] = ({name: bytes(sent).decode("utf-8", "replace") for name, sent in board.uart_output.items()}
                              if board is not None else {})
    summary["lcd_interface"] = args.lcd_interface
    summary["flash"] = ({"image": str(board.flash.path), "kind": board.flash.kind, "writable": board.flash.writable,
                         "changed": board.flash_chip.changed, "saved_to": flash_saved}
                        if board is not None else {})
    summary["bus_warnings"] = dict(board.bus.questionable) if board is not None else {}
    summary["until_s"] = args.until
    summary.update(pad_changes_summary(board))
    summary["cold"] = args.cold
    summary["timing"] = args.timing
    summary["cycles"] = [h.cycles for h in board.harts] if board is not None else [0, 0]
    summary["timing_warnings"] = dict(board.timing_warnings) if board is not None else {}
    summary.update(watch.summary())
    if vcd_file is not None:
        try:
            if signal_log is not None:
                changes = signal_log.write(vcd_file, board.time)
                summary["vcd"] = {"file": str(args.vcd), "value_changes": changes}
            else:
                vcd_file.close()
        except OSError as error:
            output_problems.append(f"{args.vcd}: {error.strerror or error}")
    if profiler is not None:
        try:
            summary["profile"] = profiler.write(args.out)
        except BadInput as error:
            terminal.message(f"[board] {error}")
            summary["profile"] = None
    summary["trace_insn"] = None if trace is None else {
        "file": str(args.trace_insn), "from_s": args.trace_from or 0.0, "to_s": args.trace_to, "lines": trace.lines}
    summary["uart_script"] = None if script is None else script.summary()
    summary["uart_input"] = None if uart_input is None else {
        "source": args.uart_input, "interactive": uart_input.interactive, "bytes": uart_input.total,
        # what each UART's receiver took of it (the one FPIOA routed from pad 4 at the time)
        "received": sum(uart.bytes_received for uart in (board.uarths, *board.uarts)) if board is not None else 0,
        "received_by": ({uart.NAME: uart.bytes_received for uart in (board.uarths, *board.uarts) if uart.bytes_received}
                        if board is not None else {})}
    if output_problems and status == EXIT_OK:
        status, kind = EXIT_WRITE_FAILED, BY_CODE[EXIT_WRITE_FAILED].name
        message = f"cannot write {'; '.join(output_problems)}"
        summary["exit"], summary["message"] = kind, message
    unwritten = output.finish(summary)
    if unwritten is not None:
        terminal.message(f"[board] cannot write {unwritten}")
        if status == EXIT_OK:
            status, kind, message = EXIT_WRITE_FAILED, BY_CODE[EXIT_WRITE_FAILED].name, f"cannot write {unwritten}"
    if status == EXIT_OK:
        terminal.message(f"[board] {message}; {board.time * 1e3:.2f} ms virtual; output in {args.out}")
    else:
        terminal.message(f"[board] stopped ({kind}): {message}")
    return status
