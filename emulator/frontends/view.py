"""The live view: `python -m emulator run FIRMWARE --view [PORT]` serves a page on 127.0.0.1 that
shows the board as it runs and drives it: the LCD as the Dock shows it (each frame that reaches the
panel and differs from the one before), the console, the LEDs and every pad the firmware drives,
virtual time, frames per virtual and per host second and the real-time factor; a BOOT key and
buttons for every pad the firmware reads as an input; pause, continue, step one frame, and real time
or as fast as possible.

Three parts. ViewState is what the run and the server share, under one lock: the console's bytes
(the last CONSOLE_KEPT of them, for a page opened later), the last frame, the run's figures, the
page's commands. ViewServer serves the page (view.html beside this module: one file, its script
and style inline, nothing fetched from anywhere else) and, in threads of its own, a Server-Sent
Events stream (`/events`: the console as it comes, "a new frame", the figures at most
STATUS_INTERVAL_S apart, the run's end), the frame's raw RGB bytes (`/frame`) and the commands
(POST `/control`, `/pad`, `/key`). The page fetches a frame when the stream says there is a new one
and it has drawn the last, so frames go out at the rate the page takes them and never queue up.
LiveRun is the run loop, in the main thread: the board runs in slices (Scheduler.run_slice) of
about SLICE_HOST_S of host time each, and between slices the loop carries out the page's commands,
publishes the figures and holds virtual time to the host's clock when asked to.

The server is the standard library's (http.server's ThreadingHTTPServer, one thread a request, the
stream one long response). The project's main thread is the board model's, which runs between
looks at the page's commands; a server in threads beside it needs no event loop, and what it
carries is small (a browser or two on the loopback: a frame of 225 KiB and a few short messages
some 30 times a second, a POST per click). aiohttp, starlette with an ASGI server, or websockets
would each bring an asyncio loop to run in a thread of its own and a tree of dependencies to
install and keep up, for nothing the page needs: Server-Sent Events (EventSource) carry the
server's side, and the page's few commands are plain POSTs.

The server binds 127.0.0.1 only, never another interface. It answers only requests whose Host is
127.0.0.1 or localhost with its port (a page elsewhere cannot reach it through a name of its own,
DNS rebinding), and takes commands only as application/json, which a page of another origin
cannot send without a preflight the server does not answer.

Pacing: at real time (the default) the run never goes ahead of the host's clock since it last
started or was switched to real time; when the model is slower than that, it runs as fast as it
can and does not catch up on more than MAX_LAG later. As fast as possible, it runs without waiting,
except on a board on which nothing can happen until something comes from outside (every hart
asleep, no device with anything to do): that waits at real time, for a key. A page's key press or
pad change takes effect at the board's virtual time when it arrives (Board.drive_pad); the BOOT
key, once pressed, stays down at least KEY_MIN_HOLD of virtual time, so that a click between two
slices is seen. Closing the page does not stop the run; Ctrl-C ends it as always (paused too). With
no --frames or --until the run goes on until it is stopped; no run is ended as hung while viewed.
"""
from __future__ import annotations

import codecs
import json
import sys
import threading
import time
from collections import deque
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Callable

import numpy as np

from ..board.maix_dock import DOCK_PADS
from ..board.scheduler import UNLIMITED_FRAMES, RunResult
from ..devices.fpioa import PAD_COUNT
from ..errors import BadInput
from ..vtime import NEVER, PS_PER_MS, PS_PER_US, Time, from_seconds, ms, to_seconds

HOST = "127.0.0.1"
DEFAULT_PORT = 8210
PAGE = Path(__file__).with_name("view.html")

STATUS_INTERVAL_S = 1 / 30          # the run's figures are published at most this often
EVENT_INTERVAL_S = 1 / 60           # an event stream sends at most this often (what came meanwhile goes together)
KEEPALIVE_S = 10.0                  # a quiet stream sends a comment this often (a page gone is noticed)
CONSOLE_KEPT = 256 * 1024           # console bytes a page opened later is sent
MAX_REQUEST_BYTES = 4096            # a command's body at most
KEY_MIN_HOLD = 50 * PS_PER_MS       # virtual time the BOOT key stays down at least once pressed
BOOT_PAD = DOCK_PADS["BOOT"].number
SLICE_HOST_S = 1 / 60               # host time a slice of the run aims at (how soon a command is taken)
MIN_SLICE = 10 * PS_PER_US          # virtual time of a slice, at least and at most
MAX_SLICE = 50 * PS_PER_MS
FIRST_SLICE = PS_PER_MS
MAX_LAG = 100 * PS_PER_MS           # real time: how far behind the host's clock the run catches up
WAIT_LOOK_S = 0.1                   # a paused or waiting run looks this often for a signal (Ctrl-C)
RATE_WINDOW_S = 1.0                 # the rates shown are over about this much host time

CONTROLS = ("pause", "continue", "step", "realtime", "fast")


def page_info(firmware: str) -> dict:
    """What the page is told once: the Dock's pads by name, its LEDs (lit when the pad is low), the BOOT key."""
    return {"firmware": firmware, "pad_count": PAD_COUNT, "boot_pad": BOOT_PAD,
            "pads": {str(pad.number): f"{name}: {pad.part}" for name, pad in DOCK_PADS.items()},
            "leds": [{"name": name[4:].lower(), "pad": pad.number} for name, pad in DOCK_PADS.items()
                     if name.startswith("LED_")]}


@dataclass
class Cursor:
    """How far one event stream has sent what the state holds."""
    console: int = 0          # console bytes sent (counted from the run's first)
    frame: int = -1           # the frame sequence number last announced
    status: int = -1
    ended: bool = False


class ViewState:
    """What the run (the main thread) and the server's threads share, under one lock: the run
    writes the console, frames and figures and takes the commands; the server reads the former
    and queues the latter."""

    def __init__(self, info: dict) -> None:
        self.info = info
        self._changed = threading.Condition(threading.Lock())
        self._console = bytearray()
        self._console_base = 0            # how many console bytes were dropped from the front
        self._frame: tuple[int, int, int, int, bytes] | None = None   # (seq, index, width, height, RGB)
        self._frame_seq = 0
        self._status: dict = {}
        self._status_seq = 0
        self._ended: str | None = None
        self._commands: deque = deque()
        self._command_arrived = threading.Event()
        self._streams = 0                 # event streams open now

    # --- the run's side ------------------------------------------------------------------

    def console_byte(self, byte: int) -> None:
        with self._changed:
            self._console.append(byte)
            if len(self._console) > 2 * CONSOLE_KEPT:
                drop = len(self._console) - CONSOLE_KEPT
                del self._console[:drop]
                self._console_base += drop
            self._changed.notify_all()

    def frame(self, index: int, image: np.ndarray) -> bool:
        """A frame reached the panel (an upright (height, width, 3) RGB picture): kept, and announced,
        when it differs from the last. Returns whether it did."""
        data = np.ascontiguousarray(image, dtype=np.uint8).tobytes()
        with self._changed:
            if self._frame is not None and self._frame[4] == data:
                return False
            self._frame_seq += 1
            self._frame = (self._frame_seq, index, image.shape[1], image.shape[0], data)
            self._changed.notify_all()
        return True

    def publish(self, status: dict) -> None:
        with self._changed:
            self._status = status
            self._status_seq += 1
            self._changed.notify_all()

    def end(self, message: str) -> None:
        """The run has ended: every stream says so and closes."""
        with self._changed:
            if self._ended is None:
                self._ended = message
            self._changed.notify_all()

    @property
    def ended(self) -> str | None:
        return self._ended

    def take_commands(self) -> list[tuple]:
        with self._changed:
            commands = list(self._commands)
            self._commands.clear()
            self._command_arrived.clear()
        return commands

    def wait_for_command(self, timeout: float) -> None:
        """Waits up to `timeout` seconds, less when the page sends a command."""
        self._command_arrived.wait(max(0.0, timeout))

    # --- the server's side -----------------------------------------------------------------

    def command(self, command: tuple) -> None:
        with self._changed:
            self._commands.append(command)
            self._command_arrived.set()

    def stream_opened(self) -> None:
        with self._changed:
            self._streams += 1

    def stream_closed(self) -> None:
        with self._changed:
            self._streams -= 1
            self._changed.notify_all()

    def wait_for_streams(self, timeout: float) -> None:
        """Waits up to `timeout` seconds for every event stream to have closed."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while self._streams and time.monotonic() < deadline:
                self._changed.wait(deadline - time.monotonic())

    def frame_data(self) -> tuple[int, int, int, int, bytes] | None:
        with self._changed:
            return self._frame

    def news(self, cursor: Cursor, timeout: float) -> list[tuple[str, object]]:
        """What the stream at `cursor` has not sent yet, waiting up to `timeout` seconds for
        something: ("console", bytes), ("frame", {seq, index}), ("status", dict), ("end", text)."""
        with self._changed:
            if not self._has_news(cursor):
                self._changed.wait(timeout)
            events: list[tuple[str, object]] = []
            end = self._console_base + len(self._console)
            if cursor.console < end:
                start = max(cursor.console, self._console_base)
                events.append(("console", bytes(self._console[start - self._console_base:])))
                cursor.console = end
            if self._frame is not None and self._frame[0] != cursor.frame:
                cursor.frame = self._frame[0]
                events.append(("frame", {"seq": self._frame[0], "index": self._frame[1]}))
            if self._status_seq != cursor.status:
                cursor.status = self._status_seq
                events.append(("status", self._status))
            if self._ended is not None and not cursor.ended:
                cursor.ended = True
                events.append(("end", self._ended))
            return events

    def _has_news(self, cursor: Cursor) -> bool:
        return (cursor.console < self._console_base + len(self._console)
                or (self._frame is not None and self._frame[0] != cursor.frame)
                or self._status_seq != cursor.status or (self._ended is not None and not cursor.ended))


# --- the server ----------------------------------------------------------------------------------

class _HttpServer(ThreadingHTTPServer):
    daemon_threads = True              # a stream still open does not hold the command's end
    allow_reuse_address = True
    state: ViewState
    page: bytes

    def handle_error(self, request, client_address) -> None:
        if isinstance(sys.exc_info()[1], (ConnectionError, TimeoutError)):
            return                     # a page closed in the middle of an answer: nothing to tell
        super().handle_error(request, client_address)


class _Handler(BaseHTTPRequestHandler):
    server: _HttpServer
    server_version = "k210-view"
    protocol_version = "HTTP/1.1"      # a page's frames come one after another on one connection

    def log_message(self, format: str, *args) -> None:     # noqa: A002 (the base class's name)
        pass                                               # the terminal is the console's

    def _host_allowed(self) -> bool:
        port = self.server.server_address[1]
        if self.headers.get("Host", "") in (f"{HOST}:{port}", f"localhost:{port}"):
            return True
        self._reply(403, b"this server answers to 127.0.0.1 only\n", "text/plain")
        return False

    def _reply(self, status: int, body: bytes = b"", content_type: str = "text/plain",
               headers: dict[str, str] | None = None) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        for name, value in (headers or {}).items():
            self.send_header(name, value)
        if status >= 400:              # a request refused may have left its body unread
            self.send_header("Connection", "close")
            self.close_connection = True
        self.end_headers()
        if body and self.command != "HEAD":
            self.wfile.write(body)

    def do_GET(self) -> None:          # noqa: N802 (http.server's name)
        if not self._host_allowed():
            return
        path = self.path.split("?", 1)[0]
        if path == "/":
            self._reply(200, self.server.page, "text/html; charset=utf-8")
        elif path == "/events":
            self._events()
        elif path == "/frame":
            frame = self.server.state.frame_data()
            if frame is None:
                self._reply(204)
                return
            seq, index, width, height, data = frame
            self._reply(200, data, "application/octet-stream",
                        {"X-Frame-Seq": str(seq), "X-Frame-Index": str(index), "X-Frame-Width": str(width),
                         "X-Frame-Height": str(height)})
        else:
            self._reply(404, b"not found\n")

    def do_POST(self) -> None:         # noqa: N802
        if not self._host_allowed():
            return
        if self.headers.get("Content-Type", "").split(";")[0].strip() != "application/json":
            self._reply(415, b"commands are application/json\n")
            return
        try:
            length = int(self.headers.get("Content-Length", "0"))
        except ValueError:
            length = -1
        if not 0 < length <= MAX_REQUEST_BYTES:
            self._reply(400, b"a command is a short JSON body\n")
            return
        try:
            body = json.loads(self.rfile.read(length))
            command = parse_command(self.path, body)
        except (ValueError, TypeError) as error:
            self._reply(400, f"{error}\n".encode())
            return
        self.server.state.command(command)
        self._reply(204)

    def _events(self) -> None:
        state = self.server.state
        self.send_response(200)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-store")
        self.send_header("Connection", "close")     # the stream lasts until either end closes it
        self.close_connection = True
        self.end_headers()
        decoder = codecs.getincrementaldecoder("utf-8")("replace")
        cursor = Cursor()
        state.stream_opened()
        try:
            self._send("hello", state.info)
            while True:
                events = state.news(cursor, KEEPALIVE_S)
                if not events:
                    self.wfile.write(b": still here\n\n")
                for name, value in events:
                    if name == "console":
                        text = decoder.decode(value).replace("\r", "")
                        if text:
                            self._send("console", {"text": text})
                    else:
                        self._send(name, value)
                if cursor.ended:
                    return
                time.sleep(EVENT_INTERVAL_S)
        except (BrokenPipeError, ConnectionResetError, TimeoutError):
            return                       # the page went away: the run goes on
        finally:
            state.stream_closed()

    def _send(self, name: str, value: object) -> None:
        self.wfile.write(f"event: {name}\ndata: {json.dumps(value)}\n\n".encode())


def parse_command(path: str, body: object) -> tuple:
    """A page's command, checked: ("control", action), ("pad", pad, level 0/1/None), ("key", down).
    ValueError saying what is wrong otherwise."""
    if not isinstance(body, dict):
        raise ValueError("a command is a JSON object")
    if path == "/control":
        action = body.get("action")
        if action not in CONTROLS:
            raise ValueError(f"action: one of {', '.join(CONTROLS)}")
        return ("control", action)
    if path == "/pad":
        pad, level = body.get("pad"), body.get("level", "missing")
        if type(pad) is not int or not 0 <= pad < PAD_COUNT:
            raise ValueError(f"pad: a number 0..{PAD_COUNT - 1}")
        if level not in (0, 1, None) or type(level) is bool:
            raise ValueError("level: 0, 1 or null (let go)")
        return ("pad", pad, level)
    if path == "/key":
        down = body.get("down")
        if type(down) is not bool:
            raise ValueError("down: true or false")
        return ("key", down)
    raise ValueError(f"no command {path}")


class ViewServer:
    """The page's server on 127.0.0.1:port (0: a free port), in threads of its own."""

    def __init__(self, port: int, state: ViewState) -> None:
        self.state = state
        try:
            self.httpd = _HttpServer((HOST, port), _Handler)
        except OSError as error:
            raise BadInput(f"--view {port}: cannot listen on {HOST}:{port} ({error.strerror or error})") from None
        self.httpd.state = state
        self.httpd.page = PAGE.read_bytes()
        self.port = self.httpd.server_address[1]
        self.url = f"http://{HOST}:{self.port}/"
        self._thread = threading.Thread(target=self.httpd.serve_forever, kwargs={"poll_interval": 0.1},
                                        name="view-server", daemon=True)
        self._thread.start()

    def close(self, wait_s: float = 1.0) -> None:
        """Tells the pages the run has ended (if nobody did), lets their streams say so for up to
        `wait_s` seconds, and stops serving."""
        self.state.end("the run has ended")
        self.state.wait_for_streams(wait_s)
        self.httpd.shutdown()
        self.httpd.server_close()
        self._thread.join()


# --- the run ------------------------------------------------------------------------------------

class LiveRun:
    """Runs the board for the view: in slices, with the page's commands carried out, and the
    figures published, between them (the module's doc)."""

    def __init__(self, board, state: ViewState, *, frames: int | None = None, until: Time | None = None,
                 paused: bool = False, realtime: bool = True,
                 progress: Callable[[object], None] | None = None) -> None:
        """frames, until: the run ends once that many frames have been shown, or at that virtual
        time (neither: when it is stopped). paused: waits for the page's continue or step first."""
        self.board = board
        self.scheduler = board.scheduler
        self.state = state
        self.frames = frames
        self.until = until
        self.paused = paused
        self.realtime = realtime
        self.progress = progress
        self.step_to: int | None = None            # a step ends when this many frames have been shown
        self.slice = FIRST_SLICE
        self._anchor: tuple[float, Time] | None = None   # (host, virtual) time real-time pacing counts from
        self._pad_free: dict[int, Time] = {}       # per pad: the time of its last change driven from the page
        self._pressed_at: Time | None = None       # when the BOOT key went down (None: up)
        self._samples: deque[tuple[float, Time, int]] = deque()    # (host, virtual, frames) for the rates
        self._last_publish = -1.0
        self._last_progress = time.perf_counter()

    # --- commands -----------------------------------------------------------------------

    def _carry_out(self, commands: list[tuple]) -> None:
        for command in commands:
            if command[0] == "control":
                action = command[1]
                if action == "pause":
                    self.paused, self.step_to = True, None
                elif action == "continue":
                    self.paused, self.step_to = False, None
                elif action == "step":
                    self.paused, self.step_to = False, len(self.board.frames) + 1
                else:
                    self.realtime = action == "realtime"
                self._anchor = None
                self._samples.clear()
            elif command[0] == "pad":
                self._drive(command[1], command[2])
            elif command[0] == "key":
                self._key(command[1])

    def _drive(self, pad: int, level: int | None, at: Time | None = None) -> None:
        earliest = self._pad_free.get(pad, 0)
        change = self.board.drive_pad(pad, level, max(earliest, at or 0))
        self._pad_free[pad] = change.at

    def _key(self, down: bool) -> None:
        """The BOOT key: down pulls its pad low; up lets go of it (the pad's pull-up), no sooner than
        KEY_MIN_HOLD after it went down."""
        if down:
            if self._pressed_at is None:
                self._drive(BOOT_PAD, 0)
                self._pressed_at = self._pad_free[BOOT_PAD]
        elif self._pressed_at is not None:
            self._drive(BOOT_PAD, None, self._pressed_at + KEY_MIN_HOLD)
            self._pressed_at = None

    # --- the loop ----------------------------------------------------------------------

    def run(self) -> RunResult:
        board, scheduler = self.board, self.scheduler
        started = time.perf_counter()
        try:
            while True:
                self._carry_out(self.state.take_commands())
                if scheduler.pending_stop is not None:
                    raise scheduler.pending_stop          # a signal (Ctrl-C), --fail-on: paused or not
                now = time.perf_counter()
                if now - self._last_publish >= STATUS_INTERVAL_S:
                    self._publish(now)
                if self.paused:
                    self.state.wait_for_command(WAIT_LOOK_S)
                    continue
                end = NEVER if self.until is None else self.until
                last = self.until is not None
                if self.realtime or scheduler.waits_for_outside():
                    target = self._paced_until(now)
                    if target <= scheduler.time:
                        self.state.wait_for_command(min(WAIT_LOOK_S, to_seconds(scheduler.time - target) + 0.001))
                        continue
                    if target < end:
                        end, last = target, False
                else:
                    self._anchor = None
                sliced = scheduler.time + self.slice < end
                if sliced:
                    end, last = scheduler.time + self.slice, False
                frames = min(self.frames or UNLIMITED_FRAMES, self.step_to or UNLIMITED_FRAMES)
                began = time.perf_counter()
                done = scheduler.run_slice(end, frames, last)
                took = time.perf_counter() - began
                if sliced and scheduler.time >= end and took > 0:
                    factor = min(2.0, max(0.25, SLICE_HOST_S / took))
                    self.slice = min(MAX_SLICE, max(MIN_SLICE, int(self.slice * factor)))
                if self.step_to is not None and len(board.frames) >= self.step_to:
                    self.paused, self.step_to, self._anchor = True, None, None
                    self._samples.clear()
                    self._publish(time.perf_counter())
                if done and (last or (self.frames is not None and len(board.frames) >= self.frames)):
                    break
                if self.progress is not None and time.perf_counter() - self._last_progress > 0.5:
                    self._last_progress = time.perf_counter()
                    self.progress(board)
        finally:
            self._publish(time.perf_counter(), ended=True)
        if self.until is not None and self.frames is None:
            message = f"ran until {ms(self.until)} of virtual time; {len(board.frames)} frames shown"
        else:
            message = f"{len(board.frames)} frames shown"
        return RunResult("ok", message, board.frames, to_seconds(board.time), [h.instret for h in board.harts],
                         time.perf_counter() - started, board.warnings, [h.cycles for h in board.harts])

    def _paced_until(self, now: float) -> Time:
        """Real time: the virtual time the run may have reached by host time `now`, counted from
        when the pacing began; a run that fell further behind than MAX_LAG catches up that much only."""
        scheduler = self.scheduler
        if self._anchor is None:
            self._anchor = (now, scheduler.time)
        host, virtual = self._anchor
        target = virtual + from_seconds(now - host)
        if target - scheduler.time > MAX_LAG:
            self._anchor = (now - to_seconds(MAX_LAG), scheduler.time)
            target = scheduler.time + MAX_LAG
        return target

    # --- the figures ----------------------------------------------------------------------

    def _publish(self, now: float, ended: bool = False) -> None:
        self._last_publish = now
        board = self.board
        frames = len(board.frames)
        rates = {"fps_virtual": None, "fps_host": None, "real_time_factor": None}
        if not self.paused and not ended:
            self._samples.append((now, board.time, frames))
            while len(self._samples) > 2 and now - self._samples[1][0] >= RATE_WINDOW_S:
                self._samples.popleft()
            host0, virtual0, frames0 = self._samples[0]
            if now - host0 > 0.1:
                dv = to_seconds(board.time - virtual0)
                rates = {"fps_virtual": (frames - frames0) / dv if dv > 0 else None,
                         "fps_host": (frames - frames0) / (now - host0),
                         "real_time_factor": dv / (now - host0)}
        if ended:
            state = "ended"
        elif self.paused:
            state = "paused"
        else:
            state = "stepping" if self.step_to is not None else "running"
        wiring = board.wiring
        self.state.publish({
            "state": state, "pacing": "realtime" if self.realtime else "fast",
            "virtual_time_s": to_seconds(board.time), "frames": frames,
            "instructions": sum(h.instret for h in board.harts), **rates,
            "waits_for_outside": self.scheduler.waits_for_outside(),
            "driven": {str(pad): level for pad, level in wiring.driven_levels().items()},
            "outside": {str(pad): level for pad, level in sorted(board.pins.levels.items())},
            "inputs": wiring.input_pads(),
            "boot_down": self._pressed_at is not None,
        })
