"""Command line: `python -m emulator run FIRMWARE.elf [--frames N] [--out DIR] ...`."""
from __future__ import annotations

import argparse
import dataclasses
import gc
import os
import signal
import sys
import time
from pathlib import Path
from typing import TextIO

from k210_common.exit_status import (BY_CODE, EXIT_BAD_INPUT, EXIT_GOLDEN_MISMATCH, EXIT_INTERNAL, EXIT_OK,
                                     EXIT_USAGE, EXIT_WRITE_FAILED)
from ..errors import BadInput, BoardStop, Interrupted
from ..vtime import NEVER, PS_PER_MS, PS_PER_S, PS_PER_US, Time, from_seconds, ms, to_seconds
from ..board.scheduler import UNLIMITED_FRAMES
from ..devices.sdcard import READ_ACCESS_TIME
from .options import (DEFAULT_FRAMES, MAX_PAD_CHANGES_IN_RUN_JSON, PROG, build_parser, golden_count, grab_problem,
                      option_problem)

def pad_changes_summary(board) -> dict:
    """run.json's record of the pads GPIOHS and GPIO lines drove: every change (the first
    MAX_PAD_CHANGES_IN_RUN_JSON) with its virtual time, and how many there were."""
    if board is None:
        return {"pad_changes": [], "pad_changes_total": 0}
    changes = [{"virtual_time_s": to_seconds(at), "pad": pad, "level": level}
               for at, pad, level in board.pad_changes[:MAX_PAD_CHANGES_IN_RUN_JSON]]
    return {"pad_changes": changes, "pad_changes_total": board.wiring.pad_change_count}


# --expect without --until: how far the run may go in virtual time at most (the --budget
# deadline after each expected text ends it long before)
EXPECT_HORIZON = 10 ** 6 * PS_PER_S


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
    result = board.run_until(from_seconds(until_s) if until_s is not None else EXPECT_HORIZON, progress=progress)
    if board.scheduler.pending_stop is not None:
        raise board.scheduler.pending_stop          # the script ended (or failed) as the run did
    step = script.step
    if step is None:
        return result
    bound = "--until" if until_s is not None else "the longest run"
    raise ConsoleExpectationUnmet(f"--uart-script {script.path}:{step.line}: {step.describe()}: not done by "
                                  f"{to_seconds(board.time):g} s of virtual time ({bound})")


def run_expecting(board, watch, until_s: float | None, budget_s: float, progress):
    """--expect: runs until the console has printed every expected text (the watch ends the run
    with ConsoleExpectationsMet), or fails at --until's time, or without --until after
    budget_s of virtual time without the next expected text."""
    from ..errors import ConsoleExpectationUnmet
    if until_s is not None:
        board.run_until(from_seconds(until_s), progress=progress)
        raise ConsoleExpectationUnmet(watch.unmet_message(f"by --until's {until_s:g} s of virtual time"))

    budget = from_seconds(budget_s)

    def arm(at: Time) -> None:
        count = len(watch.matches)

        def deadline(board) -> None:
            if len(watch.matches) != count:          # an expected text came meanwhile
                arm(watch.matches[-1].virtual_time + budget)
                return
            since = "the previous expected text" if count else "reset"
            raise ConsoleExpectationUnmet(watch.unmet_message(
                f"in {budget_s:g} s of virtual time after {since} (--budget)"))
        board.grab_at(at, deadline)

    arm(budget)
    board.run_until(EXPECT_HORIZON, progress=progress)
    raise ConsoleExpectationUnmet(watch.unmet_message(f"by {to_seconds(EXPECT_HORIZON):g} s of virtual time"))


def run_under_gdb(board, args: argparse.Namespace, terminal):
    """--gdb: serves GDB on the board (gdbstub.py). Without --gdb-wait the board runs until GDB
    attaches (or until the run's own end); after GDB detaches the run goes on to its end."""
    import select as select_module
    from .gdbstub import GdbServer
    from ..board.scheduler import RunResult
    server = GdbServer(board, args.gdb, terminal.message)
    scheduler = board.scheduler
    until = None if args.until is None else from_seconds(args.until)
    terminal.message(f"[gdb] listening on 127.0.0.1:{server.port}; attach with: gdb-multiarch {args.firmware or ''} "
                     f"-ex 'target remote 127.0.0.1:{server.port}'")
    try:
        if not args.gdb_wait:
            scheduler.frames_wanted = args.frames if args.frames is not None else UNLIMITED_FRAMES
            while not select_module.select([server.listener], [], [], 0)[0]:
                if until is not None and scheduler.time >= until:
                    return board.run_until(until)
                if args.frames is not None and len(board.frames) >= args.frames:
                    return finish_frames(board, args.frames)
                scheduler.step()
        server.accept()
        # GDB decides when the board stops: no frame count ends a turn early and no hang budget runs
        # out meanwhile, as a run without GDB goes on until its own end (counts stay those of a run
        # without GDB)
        scheduler.frames_wanted = UNLIMITED_FRAMES
        budget, scheduler.hang_budget = scheduler.hang_budget, NEVER
        outcome = server.serve()
        scheduler.hang_budget = budget
    finally:
        server.close()
    if outcome == "killed":
        terminal.message("[gdb] GDB killed the run")
        return RunResult("ok", f"ended by GDB (kill) at {ms(board.time)} of virtual time; "
                               f"{len(board.frames)} frames shown", board.frames, to_seconds(board.time),
                         [h.instret for h in board.harts], 0.0, board.warnings)
    terminal.message(f"[gdb] GDB {outcome}; the run goes on to its end")
    scheduler._last_frame_time = board.time       # the frame budget counts from here, not from before GDB
    if until is not None:
        return board.run_until(max(until, board.time))
    return finish_frames(board, max(args.frames, len(board.frames)))


def finish_frames(board, frames: int):
    """Runs until `frames` frames have been shown and lets the console line begun after the last one
    end, as a run of frames does (Board.finish_console_line)."""
    result = board.run(frames)
    board.finish_console_line()
    return result


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
                       f"{board.time / PS_PER_MS:9.2f} ms  {total / 1e6:9.2f} M instructions")
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


class SignalStop:
    """SIGINT (Ctrl-C) and SIGTERM while the command runs. Before the board exists a signal raises
    Interrupted at once; afterwards it asks the board to stop after the instruction under way (the
    waits that could block for ever, for GDB or for a pipe's writer, look at `asked` a few times a
    second and raise it), and a second one before that stop is taken ends the process at once.
    Once the run has ended and its outputs are being written, a signal is ignored: they are
    finished first. The handlers replaced are put back by restore()."""

    def __init__(self) -> None:
        self.board = None
        self.writing = False
        self.asked: Interrupted | None = None
        self._previous = {number: signal.signal(number, self._on_signal) for number in (signal.SIGINT, signal.SIGTERM)}

    def _on_signal(self, number: int, _frame) -> None:
        if self.writing:
            return
        stop = Interrupted(number, signal.Signals(number).name)
        if self.board is None:
            raise stop
        if self.asked is not None:
            signal.signal(number, signal.SIG_DFL)
            os.kill(os.getpid(), number)
            return
        self.asked = stop
        self.board.stop_run(stop)

    def check(self) -> None:
        """For a wait that may block: raises the stop a signal asked for, if one did."""
        if self.asked is not None and not self.writing:
            raise self.asked

    def restore(self) -> None:
        for number, handler in self._previous.items():
            signal.signal(number, handler)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    problem = option_problem(args)
    if problem:
        return usage_error(problem)
    signals = SignalStop()
    opened: list = []                  # what must be given back however the command ends (a terminal)
    try:
        return run_command(args, signals, opened)
    except Interrupted as stop:        # before the run began, or while no hart ran
        print(f"[board] stopped ({stop.kind}): {stop}", file=sys.stderr)
        return stop.exit_status
    finally:
        signals.writing = True         # a signal now would cut short what is being given back
        for thing in opened:
            thing.close()
        signals.restore()


def run_command(args: argparse.Namespace, signals: SignalStop, opened: list) -> int:
    if args.until is None and args.frames is None and not args.expected and args.uart_script is None and \
            args.view is None:
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
        if uart_input is not None:
            opened.append(uart_input)
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
        view = None
        if args.view is not None:
            from .view import ViewServer, ViewState, page_info
            view = ViewServer(args.view, ViewState(page_info(
                str(args.firmware) if args.firmware is not None else f"{args.flash} (booted from flash)")))
            opened.append(view)
    except BadInput as error:
        print(f"[board] stopped (bad-input): {error}", file=sys.stderr)
        return EXIT_BAD_INPUT

    output = RunOutput(args.out)
    terminal = Terminal(args.quiet, immediate=uart_input is not None and uart_input.interactive)
    watch = ConsoleWatch(args.expected, args.failures)
    if view is not None:
        terminal.message(f"[view] the live view is at {view.url} (Ctrl-C ends the run)")
    board = None
    flash_saved = None                 # where --flash-save wrote the flash, once it has

    def console(byte: int) -> None:
        output.console_byte(byte)
        terminal.console_byte(byte)
        watch.byte(byte, board.console_byte_time)
        if view is not None:
            view.state.console_byte(byte)
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

    def on_frame(record, image) -> None:
        output.frame(record, image)
        if view is not None:
            view.state.frame(record.index, image)
        if profiler is not None:
            profiler.frame(record)

    try:
        board = Board(None if args.firmware is None else str(args.firmware), flash=flash, quantum=args.quantum, hang_budget=from_seconds(args.budget), console=console,
                      on_frame=on_frame, on_warning=terminal.warning, permissive=args.permissive,
                      sd_image=args.sd, sd_writable=args.sd_writable, sd_faults=frozenset(args.sd_fault),
                      sd_access_time=(READ_ACCESS_TIME if args.sd_access_time is None
                                      else round(args.sd_access_time * PS_PER_US)),
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
            trace = InstructionTrace(board, trace_file, from_seconds(args.trace_from or 0.0),
                                     None if args.trace_to is None else from_seconds(args.trace_to))
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
            board.grab_at(from_seconds(request.at_s), grab_action(index, request))
        progress = terminal.progress if terminal.shows_progress else None
        signals.board = board
        if uart_input is not None:
            uart_input.stop_check = signals.check
        if args.gdb is not None:
            result = run_under_gdb(board, args, terminal)
        elif view is not None:
            from .view import LiveRun
            result = LiveRun(board, view.state, frames=args.frames, paused=args.view_paused, progress=progress,
                             until=None if args.until is None else from_seconds(args.until)).run()
            if args.frames is not None:
                board.finish_console_line()
        elif args.expected:
            result = run_expecting(board, watch, args.until, args.budget, progress)
        elif script is not None:
            result = run_script(board, script, args.until, progress)
        elif args.until is not None:
            result = board.run_until(from_seconds(args.until), progress=progress)
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
    signals.writing = True             # the run is over: what it has is written whatever comes
    terminal.finish()
    output_problems = []
    try:
        if trace is not None:
            trace.close()
        elif trace_file is not None:
            trace_file.close()
    except OSError as error:
        output_problems.append(f"{args.trace_insn}: {error.strerror or error}")
    if board is not None:
        try:
            board.close()
        except OSError as error:           # an SD card image's writes could not be made durable
            output_problems.append(f"{args.sd}: {error.strerror or error}")
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
    summary = summary_dict(kind, message, frames, to_seconds(board.time) if board else 0.0,
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
            output.missed_grab(request, to_seconds(board.time))
        if missed and status == EXIT_OK:
            status, kind = EXIT_USAGE, "grab-missed"
            message = (f"--grab {', '.join(r.label for r in missed)}: the run ended at {to_seconds(board.time):.6f} s of "
                       f"virtual time, before the grab's time, so nothing was written (ask for more --frames "
                       f"or an earlier time)")
    summary["exit"], summary["message"] = kind, message
    summary["grabs"] = output.grabs
    summary["writes_checked"] = args.check_writes
    summary["strict"] = args.strict
    summary["stop_on_trap"] = args.stop_on_trap
    summary["resets"] = ([{"virtual_time_s": to_seconds(at), "cause": cause} for at, cause in board.scheduler.resets]
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
    summary["caches"] = ([dataclasses.asdict(caches.statistics()) for caches in board.caches]
                         if board is not None and board.caches is not None else None)
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
        except OSError as error:
            output_problems.append(f"the --profile files in {args.out}: {error.strerror or error}")
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
        terminal.message(f"[board] {message}; {board.time / PS_PER_MS:.2f} ms virtual; output in {args.out}")
    else:
        terminal.message(f"[board] stopped ({kind}): {message}")
    if view is not None:
        view.state.end(message if status == EXIT_OK else f"stopped ({kind}): {message}")
    return status
