"""The command line of `python -m emulator run`: its options, what each takes, the checks made of
them before a run (a refusal there is status 2 and writes nothing), and when each exit status is
returned (--help's epilog and docs/reference/options.md's table are made from EXIT_STATUS_DETAILS). cli.py runs
what this accepts."""
from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

from k210_common.exit_status import (EXIT_BAD_INPUT, EXIT_EXPECT_UNMET, EXIT_FAIL_ON, EXIT_FIRMWARE_ERROR,
                                     EXIT_GOLDEN_MISMATCH, EXIT_HANG, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_MISUSE,
                                     EXIT_OK, EXIT_STRAY_WRITE, EXIT_TERMINATED, EXIT_TRAP, EXIT_UNMODELLED,
                                     EXIT_USAGE, EXIT_WRITE_FAILED, help_epilog)
from ..errors import BadInput
from ..devices.sdcard import FAULTS, READ_ACCESS_TIME
from ..vtime import PS_PER_US
from ..cpu.timing import TIMING_MODELS, TIMING_ROCKET
from ..cpu.hart import ENGINE_FAST, ENGINES
from ..board.wiring import LCD_8080, LCD_INTERFACES

PROG = "python -m emulator"
MAX_QUANTUM = 1_000_000_000    # instructions per turn; the native counter's limit is 64-bit, runs need far less
MAX_TOLERANCE = 255            # a channel of an RGB888 pixel differs by at most 255
MAX_SD_ACCESS_US = 100_000     # the SD specification's read timeout for SDHC cards: 100 ms
DEFAULT_FRAMES = 8
VIEW_PORT = 8210               # --view without a port
MAX_PAD_CHANGES_IN_RUN_JSON = 10_000    # a pin toggled for ever must not bloat run.json

# When this command returns each status (k210_common/exit_status.py holds the numbers and
# names); --help and docs/reference/options.md's table are made from it (tests/unit/shared/test_exit_status.py)
EXIT_STATUS_DETAILS: dict[int, str] = {
    EXIT_OK: "the requested frames were shown, or `--until`'s time was reached, or (with `--expect`) the console "
             "printed every expected text (with `--golden`: all match; every `--grab` was taken)",
    EXIT_INTERNAL: "an internal error of the board model",
    EXIT_USAGE: f"bad command line: an unknown option or a value out of range (`--frames`, `--quantum` 1..{MAX_QUANTUM}, "
                f"`--budget` and `--until` above 0 and finite, `--tolerance` 0..{MAX_TOLERANCE}, `--sd-fault`, "
                f"`--sd-access-time` 0..{MAX_SD_ACCESS_US:,} microseconds, "
                "`--lcd-interface`, `--timing`, a `--grab`'s syntax or time, a `--pin` that is not `PAD=LEVEL@SECONDS` "
                "with a pad 0..47), `--out` equal to or inside `--golden` or the folder of the `--sd` image, "
                "an option without the one it needs (`--tolerance` without `--golden`, "
                "`--sd-writable`, `--sd-fault` or `--sd-access-time` without `--sd`), `--until` or `--expect` with `--frames`, "
                "`--gdb-wait` without `--gdb`, `--gdb` with `--expect`/`--fail-on`, a `--gdb` or `--view` port above "
                "65535, `--view-paused` without `--view`, `--view` with `--gdb`, `--expect` or `--uart-script`, "
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
                    "or `--view` port (in use), the card image (missing, empty, or not a whole number of 512-byte blocks), "
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


def access_microseconds(text: str) -> float:
    """A finite number of microseconds, 0 to 100,000 (the SD specification's longest read access time
    for SDHC cards)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of microseconds") from None
    if not math.isfinite(value) or not 0 <= value <= MAX_SD_ACCESS_US:
        raise argparse.ArgumentTypeError(f"must be 0 to {MAX_SD_ACCESS_US:,} microseconds, not {text}")
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
    run.add_argument("--sd-access-time", type=access_microseconds, default=None, metavar="MICROSECONDS",
                     help=f"with --sd: the card's read access time, from a read command to its first block "
                          f"(default {READ_ACCESS_TIME // PS_PER_US}, the card measured on a Dock; real cards "
                          f"take about 100 to 1,000; 0: at once)")
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
    run.add_argument("--view", metavar="PORT", nargs="?", const=VIEW_PORT, type=port_number, default=None,
                     help=f"serve a live view of the run on http://127.0.0.1:PORT/ (default {VIEW_PORT}; 0: any free "
                          "port; printed), on 127.0.0.1 only: the LCD, the console, the LEDs and the pads the "
                          "firmware drives, virtual time, frame rates and the real-time factor; a BOOT key and "
                          "buttons for the input pads; pause, continue, step one frame, real time (the default: "
                          "virtual time never runs ahead of the host's clock) or as fast as possible. Without "
                          "--frames or --until the run goes on until it is stopped (Ctrl-C); no run is ended as "
                          "hung while viewed. Give it after the firmware (else PORT would take its name)")
    run.add_argument("--view-paused", action="store_true",
                     help="with --view: start paused, before the first instruction (the page's continue or step "
                          "starts the run)")
    run.add_argument("--out", default="build/frames", type=Path, help="output folder (default build/frames)")
    run.add_argument("--budget", type=budget_seconds, default=5.0,
                     help="virtual seconds allowed between frames before the run counts as hung "
                          "(default 5; finite, above 0)")
    run.add_argument("--quantum", type=quantum_count, default=20_000,
                     help=f"CPU cycles per hart per turn (default 20000; 1..{MAX_QUANTUM})")
    run.add_argument("--timing", choices=TIMING_MODELS, default=TIMING_ROCKET,
                     help="what an instruction costs: rocket (the default), the cycles the K210's Rocket core "
                          "takes (result latencies, the iterative multiplier and divider, branch prediction, "
                          "the L1 caches' misses, device registers' round trips; mcycle and virtual time follow "
                          "them); rocket-nocache, the same with every access a cache hit (the model before the "
                          "caches); ipc1, one cycle per instruction, the model before cycle timing. A card's read "
                          "access time applies under each (--sd-access-time 0: as before it)")
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
    if args.view_paused and args.view is None:
        return "--view-paused needs --view (the page whose continue starts the run)"
    if args.view is not None and (args.gdb is not None or args.expected or args.uart_script is not None):
        return ("--view excludes --gdb, --expect and --uart-script (each of them runs the board its own way; "
                "the view's page pauses and steps it)")
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
    if args.sd is None and args.sd_access_time is not None:
        return "--sd-access-time needs --sd (a card in the slot)"
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
