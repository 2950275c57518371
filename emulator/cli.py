"""Command line: `python -m emulator run FIRMWARE.elf [--frames N] [--out DIR] ...`."""
from __future__ import annotations

import argparse
import sys
import time

from pathlib import Path

from .errors import EXIT_GOLDEN_MISMATCH, EXIT_INTERNAL, EXIT_OK, EXIT_USAGE, BoardStop

EXIT_STATUS_HELP = """exit status:
  0  the requested frames were shown
  1  internal error of the board model
  2  bad command line
  3  the firmware trapped (exception), or jumped outside memory
  4  hang: no frame within the virtual-time budget, or every hart waits forever
  5  the firmware touched an address or register the model does not implement
  6  bad input: the firmware image is missing or not a RISC-V ELF
  7  hardware misuse: something the real K210 would not do (e.g. CPU on an unlocked PLL)
  8  the firmware reported a fatal error on its console ("error <code> <words>")
  9  --golden: a shown frame differs from its golden PNG (diff images are in the output folder)
 10  --check-writes: a store (a hart's or a DMA channel's) landed in SRAM outside the firmware's buffers
"""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m emulator", description="Sipeed Maix Dock (Kendryte K210) board model",
                                     epilog=EXIT_STATUS_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a firmware ELF and capture the LCD's frames",
                         epilog=EXIT_STATUS_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    run.add_argument("firmware", help="firmware ELF (linked for SRAM at 0x80000000)")
    run.add_argument("--sd", metavar="IMAGE", help="SD card image in the Dock's slot (opened read-only: the "
                     "firmware's writes are kept in memory for the run)")
    run.add_argument("--sd-writable", action="store_true", help="let the firmware's writes reach the image file")
    run.add_argument("--sd-fault", action="append", default=[], metavar="FAULT",
                     help="make the card misbehave, to test firmware error paths: "
                          "no-init (never leaves idle), bad-crc (every block's CRC16 wrong), "
                          "flaky-crc (each block's first CRC16 wrong); repeatable")
    run.add_argument("--frames", type=int, default=8, help="stop after this many frames reach the LCD (default 8)")
    run.add_argument("--out", default="build/frames", help="output folder (default build/frames)")
    run.add_argument("--budget", type=float, default=5.0,
                     help="virtual seconds allowed between frames before the run counts as hung (default 5)")
    run.add_argument("--quantum", type=int, default=20_000, help="instructions per hart per turn (default 20000)")
    run.add_argument("--golden", metavar="DIR", type=Path,
                     help="compare every shown frame with DIR/frame_NNNN.png of the same index; write "
                          "diff_NNNN.png for frames that differ and exit with status 9 on any mismatch")
    run.add_argument("--tolerance", type=int, default=0, metavar="N",
                     help="with --golden: a pixel matches when no channel differs by more than N (default 0: exact)")
    run.add_argument("--grab", action="append", default=[], metavar="WHAT@SECONDS",
                     help="write a PNG of a framebuffer at a virtual time, whether or not a frame is complete: "
                          "WHAT is 'gram' (the LCD's memory), a firmware symbol or a 0x address of a 320x240 "
                          "RGB565 buffer in SRAM; add ':pairs' for the project's pixel-pair order or "
                          ":WxH for another size, e.g. --grab framebuffers@0.45:pairs; repeatable")
    run.add_argument("--check-writes", action="store_true",
                     help="stop with exit status 10 at the first store into SRAM outside the firmware's buffers "
                          "(.data/.bss, the heap handed out so far, the storing hart's own stack): a checker "
                          "of the board model, like a watchpoint; the real K210 lets such stores through")
    run.add_argument("--quiet", action="store_true", help="do not echo the console or show progress")
    run.add_argument("--permissive", action="store_true",
                     help="an access to a register a modelled device does not implement warns (loads read 0, "
                          "stores are ignored) instead of stopping the run; addresses no device claims still stop it")
    return parser


def _progress(board) -> None:
    frames = len(board.frames)
    total = sum(h.instret for h in board.harts)
    sys.stderr.write(f"\r[board] frame {frames}/{board._frames_wanted}  virtual {board.time * 1e3:9.2f} ms  "
                     f"{total / 1e6:9.2f} M instructions ")
    sys.stderr.flush()


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.frames < 1:
        print("--frames must be at least 1", file=sys.stderr)
        return EXIT_USAGE
    from .board import Board
    from .grab import GrabRequest, parse_grab
    from .golden import compare_run
    from .output import RunOutput, summary_dict
    try:
        grabs: list[GrabRequest] = [parse_grab(text) for text in args.grab]
    except ValueError as error:
        print(f"--grab: {error}", file=sys.stderr)
        return EXIT_USAGE
    if args.golden is not None and not args.golden.is_dir():
        print(f"--golden: {args.golden} is not a folder", file=sys.stderr)
        return EXIT_USAGE

    output = RunOutput(args.out)

    def console(byte: int) -> None:
        output.console_byte(byte)
        if not args.quiet:
            sys.stdout.buffer.write(bytes((byte,)))
            if byte == 10:
                sys.stdout.flush()

    def warning(text: str) -> None:
        if not args.quiet:
            sys.stderr.write(f"\n[board] warning: {text}\n")

    started = time.perf_counter()
    board = None
    try:
        board = Board(args.firmware, quantum=args.quantum, hang_budget_s=args.budget, console=console,
                      on_frame=output.frame, on_warning=warning, permissive=args.permissive,
                      sd_image=args.sd, sd_writable=args.sd_writable, sd_faults=frozenset(args.sd_fault),
                      check_writes=args.check_writes)
        for request in grabs:
            board.grab_at(request.at_s, lambda b, request=request: output.grab(request, b))
        result = board.run(args.frames, progress=None if args.quiet or not sys.stderr.isatty() else _progress)
        status, kind, message = EXIT_OK, "ok", result.message
    except BoardStop as stop:
        status, kind, message = stop.exit_status, stop.kind, str(stop)
    except Exception as error:  # an internal bug must still leave a run.json behind
        status, kind, message = EXIT_INTERNAL, "internal", f"{type(error).__name__}: {error}"
        import traceback
        traceback.print_exc()
    sys.stdout.flush()
    if board is not None:
        board.close()
    frames = board.frames if board is not None else []
    summary = summary_dict(kind, message, frames, board.time if board else 0.0,
                           [h.instret for h in board.harts] if board else [0, 0],
                           time.perf_counter() - started, board.warnings if board else [], args.firmware,
                           board.device_writes if board else {}, board.console_lines if board else [])
    if args.golden is not None and board is not None:
        comparisons = compare_run(output.frame_paths, args.golden, output.folder, args.tolerance)
        summary["golden"] = {"folder": str(args.golden), "tolerance": args.tolerance,
                             "frames": [c.as_dict() for c in comparisons]}
        mismatches = [c for c in comparisons if not c.matches]
        for comparison in mismatches:
            print(f"[golden] {comparison.describe()}", file=sys.stderr)
        if status == EXIT_OK and mismatches:
            status, kind = EXIT_GOLDEN_MISMATCH, "golden-mismatch"
            message = f"{len(mismatches)} of {len(comparisons)} frames differ from {args.golden}"
            summary["exit"], summary["message"] = kind, message
        elif status == EXIT_OK:
            print(f"[golden] all {len(comparisons)} frames match {args.golden}", file=sys.stderr)
    summary["grabs"] = output.grabs
    summary["writes_checked"] = args.check_writes
    output.finish(summary)
    if not args.quiet and sys.stderr.isatty():
        sys.stderr.write("\n")
    if status == EXIT_OK:
        print(f"[board] {message}; {board.time * 1e3:.2f} ms virtual; output in {args.out}", file=sys.stderr)
    else:
        print(f"[board] stopped ({kind}): {message}", file=sys.stderr)
    return status
