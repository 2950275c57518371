"""The live view's parts that need no browser (emulator/frontends/view.py): the server binds
127.0.0.1 only and answers only to that name; its event stream carries the console, each changed
frame once and the run's end; commands are checked; the run loop pauses, steps one frame, holds
virtual time to the host's clock at real time (and on a board waiting for a key), and a BOOT key
clicked between two slices stays down long enough to be seen. tests/test_view_browser.py drives the
page itself in Chromium."""
from __future__ import annotations

import http.client
import json
import socket
import threading
import time

import numpy as np
import pytest
from PIL import Image

from suite import ROOT
from emulator.board import Board
from emulator.errors import Interrupted
from emulator.frontends.view import (BOOT_PAD, KEY_MIN_HOLD, Cursor, LiveRun, ViewServer, ViewState, page_info,
                                     parse_command)
from emulator.vtime import PS_PER_MS, from_seconds, to_seconds

C_LCD_GOLDEN = ROOT / "tests" / "golden" / "c-lcd-demo"


@pytest.fixture
def server():
    state = ViewState(page_info("test.elf"))
    view = ViewServer(0, state)
    yield view
    view.close(wait_s=0.2)


def request(view: ViewServer, method: str, path: str, body: bytes | None = None, headers: dict | None = None):
    connection = http.client.HTTPConnection("127.0.0.1", view.port, timeout=10)
    connection.request(method, path, body=body, headers=headers or {})
    response = connection.getresponse()
    data = response.read()
    connection.close()
    return response, data


def read_events(view: ViewServer, until_name: str, limit_s: float = 10.0) -> list[tuple[str, object]]:
    """The stream's events up to and with the first named `until_name`."""
    sock = socket.create_connection(("127.0.0.1", view.port), timeout=limit_s)
    sock.sendall(f"GET /events HTTP/1.1\r\nHost: 127.0.0.1:{view.port}\r\n\r\n".encode())
    stream = sock.makefile("rb")
    while stream.readline() not in (b"\r\n", b""):        # the response's headers
        pass
    events, name = [], None
    try:
        for line in stream:
            line = line.decode().rstrip("\n")
            if line.startswith("event: "):
                name = line[7:]
            elif line.startswith("data: "):
                events.append((name, json.loads(line[6:])))
                if name == until_name:
                    break
    finally:
        sock.close()
    return events


def test_the_server_listens_on_127_0_0_1_only(server):
    assert server.httpd.server_address == ("127.0.0.1", server.port)
    assert server.url == f"http://127.0.0.1:{server.port}/"
    response, page = request(server, "GET", "/")
    assert response.status == 200 and b"<canvas id=\"lcd\"" in page and b"://" not in page   # nothing from elsewhere
    # another loopback address reaches a server bound to every interface, not this one
    with pytest.raises(ConnectionRefusedError):
        socket.create_connection(("127.0.0.2", server.port), timeout=5).close()
    if socket.has_ipv6:
        with pytest.raises(OSError):
            socket.create_connection(("::1", server.port), timeout=5).close()
    # a name of another site resolving here (DNS rebinding) is not answered
    response, _ = request(server, "GET", "/", headers={"Host": f"example.com:{server.port}"})
    assert response.status == 403
    response, _ = request(server, "GET", "/", headers={"Host": f"localhost:{server.port}"})
    assert response.status == 200


def test_commands_are_checked_and_queued(server):
    json_type = {"Content-Type": "application/json"}
    for path, body, status in (("/control", {"action": "step"}, 204), ("/control", {"action": "jump"}, 400),
                               ("/pad", {"pad": 16, "level": None}, 204), ("/pad", {"pad": 48, "level": 0}, 400),
                               ("/pad", {"pad": 3, "level": 2}, 400), ("/pad", {"pad": 3}, 400),
                               ("/key", {"down": True}, 204), ("/key", {"down": 1}, 400), ("/nothing", {}, 400)):
        response, _ = request(server, "POST", path, json.dumps(body).encode(), json_type)
        assert response.status == status, (path, body)
    # a form another site's page could post without asking first is refused
    response, _ = request(server, "POST", "/control", b"action=pause", {"Content-Type": "text/plain"})
    assert response.status == 415
    assert server.state.take_commands() == [("control", "step"), ("pad", 16, None), ("key", True)]
    assert server.state.take_commands() == []
    assert parse_command("/pad", {"pad": 5, "level": 1}) == ("pad", 5, 1)
    with pytest.raises(ValueError, match="level"):
        parse_command("/pad", {"pad": 5, "level": True})


def test_the_stream_carries_the_console_each_changed_frame_once_and_the_end(server):
    state = server.state
    for byte in "hé".encode():                 # a character split between two sends
        state.console_byte(byte)
    image = np.zeros((240, 320, 3), dtype=np.uint8)
    image[10, 20] = (1, 2, 3)
    assert state.frame(0, image)
    assert not state.frame(1, image.copy())    # the same picture again: not sent
    state.publish({"frames": 2})
    events = read_events(server, "status")
    names = [name for name, _ in events]
    assert names[0] == "hello" and events[0][1]["boot_pad"] == 16
    assert {"name": "green", "pad": 13} in events[0][1]["leds"]
    assert ("console", {"text": "hé"}) in events
    assert ("frame", {"seq": 1, "index": 0}) in events and names.count("frame") == 1
    response, data = request(server, "GET", "/frame")
    assert response.status == 200 and response.getheader("X-Frame-Seq") == "1"
    assert (response.getheader("X-Frame-Width"), response.getheader("X-Frame-Height")) == ("320", "240")
    assert data == image.tobytes()
    image[0, 0] = (9, 9, 9)
    assert state.frame(2, image)
    cursor = Cursor(console=3, frame=1, status=1)
    assert state.news(cursor, 0.0) == [("frame", {"seq": 2, "index": 2})]
    state.end("3 frames shown")
    assert read_events(server, "end")[-1] == ("end", "3 frames shown")


def test_the_console_kept_for_a_late_page_is_bounded():
    from emulator.frontends import view
    state = ViewState({})
    for _ in range(2 * view.CONSOLE_KEPT + 10):
        state.console_byte(ord("x"))
    (name, data), = state.news(Cursor(), 0.0)[:1]
    assert name == "console" and view.CONSOLE_KEPT <= len(data) <= 2 * view.CONSOLE_KEPT


def test_a_closed_stream_leaves_the_server_serving(server):
    sock = socket.create_connection(("127.0.0.1", server.port), timeout=5)
    sock.sendall(f"GET /events HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\n\r\n".encode())
    assert sock.recv(100).startswith(b"HTTP/1.1 200")
    sock.close()                               # the page closed
    server.state.publish({"frames": 1})
    assert read_events(server, "status")[-1] == ("status", {"frames": 1})


def test_a_page_gone_in_the_middle_of_a_frame_is_no_error(server, capfd):
    """A page closed (or navigated away) while its frame was on the way: no traceback on the
    terminal, whose lines are the console's."""
    server.state.frame(0, np.random.default_rng(1).integers(0, 255, (240, 320, 3), dtype=np.uint8))
    for _ in range(10):
        sock = socket.create_connection(("127.0.0.1", server.port), timeout=5)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")  # reset
        sock.sendall(f"GET /frame HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\n\r\n".encode())
        sock.recv(10)
        sock.close()
    response, data = request(server, "GET", "/frame")      # and the server goes on
    assert response.status == 200 and len(data) == 240 * 320 * 3
    time.sleep(0.2)
    assert "Traceback" not in capfd.readouterr().err


# --- the run loop on real boards ----------------------------------------------------------------

def live_board(elf, frames: list | None = None, console: bytearray | None = None) -> tuple[Board, ViewState]:
    state = ViewState(page_info(str(elf)))

    def on_frame(record, image):
        state.frame(record.index, image)
        if frames is not None:
            frames.append(image.copy())

    def on_byte(byte):
        state.console_byte(byte)
        if console is not None:
            console.append(byte)
    return Board(str(elf), on_frame=on_frame, console=on_byte), state


def wait_for_status(state: ViewState, check, limit_s: float = 60.0) -> dict:
    cursor = Cursor()
    deadline = time.monotonic() + limit_s
    while time.monotonic() < deadline:
        for name, value in state.news(cursor, 0.2):
            if name == "status" and check(value):
                return value
    raise AssertionError("the status never came")


def test_paused_step_one_frame_continue_and_the_frames_are_the_goldens(c_firmware):
    """Started paused, nothing runs; each step runs to the next frame and pauses; continue runs to
    --frames' end. The frames, run in slices, are lcd_demo's goldens."""
    images: list[np.ndarray] = []
    board, state = live_board(c_firmware / "lcd_demo.elf", images)
    live = LiveRun(board, state, frames=4, paused=True, realtime=False)
    result = {}
    thread = threading.Thread(target=lambda: result.setdefault("run", live.run()))
    thread.start()
    try:
        status = wait_for_status(state, lambda s: s["state"] == "paused")
        assert status["virtual_time_s"] == 0 and status["frames"] == 0
        time.sleep(0.2)
        assert board.time == 0
        for shown in (1, 2):
            state.command(("control", "step"))
            status = wait_for_status(state, lambda s: s["state"] == "paused" and s["frames"] == shown)
            time.sleep(0.1)
            assert len(board.frames) == shown                 # and no further
        state.command(("control", "continue"))
        thread.join(60)
    finally:
        if thread.is_alive():
            board.stop_run(Interrupted(2, "SIGINT"))
            thread.join(10)
    assert result["run"].message == "4 frames shown" and len(images) == 4
    for index, image in enumerate(images):
        golden = np.asarray(Image.open(C_LCD_GOLDEN / f"frame_{index:04d}.png").convert("RGB"))
        assert np.array_equal(image, golden), f"frame {index}"


def test_real_time_never_runs_ahead_of_the_host_clock_and_fast_does_not_wait(c_firmware):
    """blink.c ticks every 50 ms of virtual time: at real time 0.2 s of it takes 0.2 s, and at no
    moment is the board ahead of the host's clock by more than a slice; as fast as possible it
    never waits."""
    board, state = live_board(c_firmware / "blink.elf")
    live = LiveRun(board, state, until=from_seconds(0.2))
    ahead = []
    publish = live._publish

    def watch(now, ended=False):
        if live._anchor is not None:
            host, virtual = live._anchor
            ahead.append(to_seconds(board.time - virtual) - (now - host))
        publish(now, ended)
    live._publish = watch
    began = time.perf_counter()
    assert live.run().message == "ran until 200.000 ms of virtual time; 0 frames shown"
    real = time.perf_counter() - began
    assert real >= 0.19 and max(ahead) < 0.01
    board, state = live_board(c_firmware / "blink.elf")
    waits = []
    state.wait_for_command = waits.append
    LiveRun(board, state, until=from_seconds(0.2), realtime=False).run()
    assert board.time == from_seconds(0.2) and waits == []


def test_a_board_waiting_for_a_key_waits_at_real_time_even_as_fast_as_possible(c_firmware):
    board, state = live_board(c_firmware / "boot_key.elf")
    began = time.perf_counter()
    LiveRun(board, state, until=from_seconds(0.15), realtime=False).run()
    assert time.perf_counter() - began >= 0.14
    assert board.scheduler.waits_for_outside()


def test_a_click_between_two_slices_holds_the_boot_key_down_long_enough(c_firmware):
    """The page's press and release arrive together: the key goes down at the board's time and
    comes up KEY_MIN_HOLD later, and the firmware sees both."""
    console = bytearray()
    board, state = live_board(c_firmware / "boot_key.elf", console=console)
    LiveRun(board, state, until=from_seconds(0.02), realtime=False).run()
    state.command(("key", True))
    state.command(("key", False))
    state.command(("pad", 20, 1))
    LiveRun(board, state, until=from_seconds(0.2), realtime=False).run()
    pressed, pad20, released = board.pins.played
    assert (pressed.pad, pressed.level, released.pad, released.level) == (BOOT_PAD, 0, BOOT_PAD, None)
    assert 0.02 <= to_seconds(pressed.at) < 0.021 and released.at == pressed.at + KEY_MIN_HOLD
    assert (pad20.pad, pad20.level, pad20.at) == (20, 1, pressed.at)
    lines = console.decode().splitlines()
    assert lines == ["boot_key: press the BOOT key", "BOOT key pressed (1)", "BOOT key released (1)"]
    assert released.at - pressed.at == 50 * PS_PER_MS
