"""The GDB remote stub (`run --gdb PORT [--gdb-wait]`, emulator/frontends/gdbstub.py): a real
gdb-multiarch session in batch mode against the default card, and the protocol's edges through
a small client of our own (Ctrl-C, a firmware trap shown as a signal, bad packets, a GDB that
goes away)."""
from __future__ import annotations

import os
import re
import shutil
import socket
import subprocess
import sys
import time

import pytest

from suite import GOLDEN_FRAMES, ROOT, run_emulator
from unicorn import riscv_const as rv

from emulator.frontends.gdbstub import checksum

GDB = shutil.which("gdb-multiarch")
needs_gdb = pytest.mark.skipif(GDB is None, reason="gdb-multiarch is not installed (tools/ensure-toolchain.sh)")


def start_board(*args: str) -> tuple[subprocess.Popen, int]:
    """The board model waiting for GDB on a free port; returns the process and the port."""
    process = subprocess.Popen([sys.executable, "-m", "emulator", "run", *args, "--gdb", "0", "--gdb-wait"],
                               cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = process.stderr.readline()
    match = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
    assert match, line + process.stderr.read()
    return process, int(match.group(1))


def finish(process: subprocess.Popen) -> tuple[int, str]:
    _, errors = process.communicate(timeout=300)
    return process.returncode, errors


class Client:
    """A minimal GDB: packets with checksums, acknowledgements on."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=60)
        self.buffer = b""

    def _read(self) -> None:
        data = self.sock.recv(65536)
        if not data:
            raise EOFError("the stub closed the connection")
        self.buffer += data

    def send_raw(self, data: bytes) -> None:
        self.sock.sendall(data)

    def send(self, payload: str) -> None:
        data = payload.encode()
        self.sock.sendall(b"$" + data + b"#" + checksum(data))

    def ack(self) -> bytes:
        while not self.buffer:
            self._read()
        byte, self.buffer = self.buffer[:1], self.buffer[1:]
        return byte

    def reply(self) -> str:
        while True:
            start = self.buffer.find(b"$")
            end = self.buffer.find(b"#", start)
            if start >= 0 and end >= 0 and len(self.buffer) >= end + 3:
                payload = self.buffer[start + 1:end]
                self.buffer = self.buffer[end + 3:]
                self.sock.sendall(b"+")
                return payload.decode()
            self._read()

    def ask(self, payload: str) -> str:
        self.send(payload)
        assert self.ack() == b"+"
        return self.reply()


@needs_gdb
def test_a_gdb_multiarch_session(firmware, card, tmp_path):
    """The issue's session: break at render_band, step, registers and memory, a watchpoint on a
    variable, continue to the next frame; then detach, and the run goes on to its end."""
    process, port = start_board(str(firmware), "--sd", str(card), "--frames", "3", "--out", str(tmp_path / "out"))
    script = tmp_path / "session.gdb"
    script.write_text(f"""set pagination off
set confirm off
target remote 127.0.0.1:{port}
info threads
break *render_band
continue
stepi
info registers pc ra sp
print/x $mstatus
print $mhartid
x/2xw 0x80000000
watch *(unsigned int *)&fb_state
continue
delete 2
continue
print $pc == render_band
thread 2
print $mhartid
detach
""")
    session = subprocess.run([GDB, "-batch", "-nx", "-x", str(script), str(firmware)], capture_output=True, text=True,
                             timeout=300)
    status, errors = finish(process)
    out = session.stdout
    assert session.returncode == 0, session.stderr + out
    assert re.search(r"\* 1 +Thread 1 \(hart 0: running\)", out) and "Thread 2 (hart 1: running)" in out
    assert out.count("hit Breakpoint 1, ") == 2 and "in render_band ()" in out
    words = subprocess.run(["riscv64-unknown-elf-objdump", "-d", "--start-address=0x80000000",
                            "--stop-address=0x80000008", str(firmware)], capture_output=True, text=True).stdout
    first = re.findall(r"^\s*80000000:\s+([0-9a-f]{8})", words, re.M)
    assert first and f"0x80000000 <_start>:\t0x{first[0]}" in out
    assert "Hardware watchpoint 2: *(unsigned int *)&fb_state" in out
    assert "Old value = 0\nNew value = 1" in out
    assert "$1 = 0x" in out and "$2 = 0" in out and "$3 = 1" in out and "$4 = 1" in out
    assert status == 0, errors
    assert "[gdb] GDB detached; the run goes on to its end" in errors and "3 frames shown" in errors


@needs_gdb
def test_a_breakpoint_session_leaves_the_run_as_without_gdb(firmware, card, firmware_run, tmp_path):
    """Stopped at a breakpoint, continued and detached, the run shows the same frames at the same
    virtual times with the same instruction and cycle counts as without GDB, and its console ends
    with the same line (issue 32, item 5: the board used to run under GDB with a frame count of 0,
    which ended every turn early, and the console's last line was cut after a detach)."""
    import json
    out = tmp_path / "out"
    process, port = start_board(str(firmware), "--sd", str(card), "--frames", str(GOLDEN_FRAMES), "--out", str(out),
                                "--quiet")
    script = tmp_path / "session.gdb"
    script.write_text(f"""set pagination off
set confirm off
target remote 127.0.0.1:{port}
break *render_band
continue
delete
detach
""")
    session = subprocess.run([GDB, "-batch", "-nx", "-x", str(script), str(firmware)], capture_output=True, text=True,
                             timeout=300)
    status, errors = finish(process)
    assert session.returncode == 0 and "hit Breakpoint 1, " in session.stdout, session.stderr + session.stdout
    assert status == 0, errors
    with_gdb = json.loads((out / "run.json").read_text())
    _, _, plain = firmware_run

    def frames(summary: dict) -> list:
        return [(f["virtual_time_s"], f["instructions"], f["cycles"]) for f in summary["frames"]]
    assert frames(with_gdb) == frames(plain)
    assert with_gdb["console"] == plain["console"]



def test_ctrl_c_stops_a_running_board_and_time_stands_still(firmware, card, tmp_path):
    process, port = start_board(str(firmware), "--sd", str(card), "--out", str(tmp_path / "out"))
    client = Client(port)
    assert client.ask("?") == "T05thread:1;"
    client.send("c")
    assert client.ack() == b"+"
    time.sleep(0.5)
    client.send_raw(b"\x03")
    assert client.reply().startswith("T02thread:")
    cycles = client.ask(f"p{65 + 0xB00:x}")      # mcycle: CSR n is register 65 + n
    time.sleep(0.3)
    assert client.ask(f"p{65 + 0xB00:x}") == cycles and int.from_bytes(bytes.fromhex(cycles), "little") > 0
    assert client.ask("m80000000,4") != "E14" and client.ask("m60000000,4") == "E14"
    assert client.ask("qfThreadInfo") == "m1,2" and client.ask("Hg2") == "OK" and client.ask("Hg3") == "E02"
    client.send("$Hg1#00")                      # a bad checksum is refused
    assert client.ack() == b"-"
    client.send("vKill;1")
    assert client.ack() == b"+" and client.reply() == "OK"
    client.sock.close()
    status, errors = finish(process)
    assert status == 0 and "ended by GDB (kill)" in errors


TRAP_PROGRAM = """
    .globl _start
_start:
    csrr    t0, mhartid
    bnez    t0, park
    la      t0, handler
    csrw    mtvec, t0
bad:
    .word   0                         # an illegal instruction
park:
    wfi
    j       park
    .balign 4
handler:
    j       handler
"""


def test_a_firmware_trap_is_a_stop_with_its_signal(assemble, tmp_path):
    process, port = start_board(str(assemble(TRAP_PROGRAM)), "--until", "0.01", "--out", str(tmp_path / "out"))
    client = Client(port)
    assert client.ask("c").startswith("O")          # the board's words on GDB's console first
    assert client.reply() == "T04thread:1;"          # SIGILL, at the trap handler
    mcause = int.from_bytes(bytes.fromhex(client.ask(f"p{65 + 0x342:x}")), "little")
    assert mcause == 2
    client.send("vKill;1")
    assert client.ack() == b"+" and client.reply() == "OK"
    client.sock.close()
    status, errors = finish(process)
    assert status == 0 and "ended by GDB (kill)" in errors


def test_a_gdb_that_goes_away_mid_packet_leaves_the_run_going(c_firmware, tmp_path):
    process, port = start_board(str(c_firmware / "hello.elf"), "--until", "0.02", "--out", str(tmp_path / "out"))
    client = Client(port)
    client.send_raw(b"$qSupp")                        # half a packet, then gone
    client.sock.close()
    status, errors = finish(process)
    assert status == 0, errors
    assert "GDB closed the connection; the run goes on without it" in errors and "ran until 20.000 ms" in errors


def test_a_busy_port_and_bad_options(firmware, tmp_path):
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen(1)
    port = busy.getsockname()[1]
    run = run_emulator("run", str(firmware), "--gdb", str(port), "--out", str(tmp_path / "a"))
    busy.close()
    assert run.returncode == 6 and f"--gdb {port}: cannot listen on 127.0.0.1:{port}" in run.stderr
    run = run_emulator("run", str(firmware), "--gdb-wait", "--out", str(tmp_path / "b"))
    assert run.returncode == 2 and "--gdb-wait needs --gdb" in run.stderr
    run = run_emulator("run", str(firmware), "--gdb", "70000", "--out", str(tmp_path / "c"))
    assert run.returncode == 2 and "must be a TCP port 0..65535" in run.stderr


def test_a_breakpoint_stops_before_its_instruction_and_counts_stay_exact():
    from emulator.frontends.gdbstub import Debugger
    from k210_fixtures import make_board, program, symbol
    board = make_board(program("""
    first:
        addi    a0, a0, 1
        addi    a0, a0, 1
        addi    a0, a0, 1
        addi    a0, a0, 1
        addi    a0, a0, 1
    second:
        addi    a0, a0, 1
    """))
    debugger = Debugger(board)
    hart = board.harts[0]
    for name in ("first", "second"):
        debugger.set_breakpoint(symbol(board, name), "swbreak")
    debugger.resume(None)
    event = debugger.run_until_stop(lambda: False)
    assert (event.hart, event.extra, hart.pc) == (0, "swbreak:;", symbol(board, "first"))
    at_first, a0 = hart.instret, hart.reg(rv.UC_RISCV_REG_A0)
    debugger.resume(None)
    debugger.run_until_stop(lambda: False)
    assert hart.pc == symbol(board, "second")
    assert hart.instret - at_first == 5 and hart.reg(rv.UC_RISCV_REG_A0) - a0 == 5
    debugger.resume(0)                     # one step
    debugger.run_until_stop(lambda: False)
    assert hart.pc == symbol(board, "second") + 2 and hart.instret - at_first == 6    # c.addi


def test_read_and_access_watchpoints_stop_after_the_access():
    from emulator.frontends.gdbstub import Debugger
    from k210_fixtures import make_board, program, symbol
    board = make_board(program("""
        la      t0, cell
    load:
        ld      a0, 0(t0)
        addi    a0, a0, 1
    store:
        sd      a0, 0(t0)
        nop
    """, data="cell: .dword 41\n"))
    debugger = Debugger(board)
    hart = board.harts[0]
    cell = symbol(board, "cell")
    debugger.set_watchpoint(3, cell, 8)                 # rwatch: the load
    debugger.resume(None)
    event = debugger.run_until_stop(lambda: False)
    assert event.extra == f"rwatch:{cell:x};" and hart.pc == symbol(board, "load") + 4
    assert hart.reg(rv.UC_RISCV_REG_A0) == 41            # the load has happened
    debugger.clear_watchpoint(3, cell, 8)
    debugger.set_watchpoint(4, cell, 8)                 # awatch: the store is the next access
    debugger.resume(None)
    event = debugger.run_until_stop(lambda: False)
    assert event.extra == f"awatch:{cell:x};" and hart.pc == symbol(board, "store") + 4
    assert int.from_bytes(board.memory.read(cell, 8), "little") == 42


def test_malformed_packets_get_an_error_reply_and_the_run_goes_on(c_firmware, tmp_path):
    """Issue 35's packets, which ended the run with a traceback or set the board running: each
    gets E01 (or the empty reply of an unknown packet), nothing runs, and the stub goes on."""
    process, port = start_board(str(c_firmware / "hello.elf"), "--until", "0.02", "--out", str(tmp_path / "out"))
    client = Client(port)
    pc = client.ask("p20")
    for payload in ["m", "m80000000", "mzz,4", "Hgzz", "H", "vCont;s:9", "vCont;x", "vCont;", "vCont;c:zz", "Z0",
                    "Z0,zz,4", "p", "pzz", "P20", "Gzz", "T", "qThreadExtraInfo,9", "qXfer:features:read:target.xml:",
                    "M80000000,4", "X80000000"]:
        assert client.ask(payload) == "E01", payload
    assert client.ask("") == ""                                    # the empty packet: no command
    assert client.ask("p20") == pc                                 # nothing ran meanwhile
    client.send_raw(b"$" + b"m" * 70_000)                          # longer than PacketSize, no end yet
    assert client.ack() == b"-"                                    # refused at once
    client.send_raw(b"m\x03m" * 100 + b"#00")                      # its tail: a 0x03 in it is data, not Ctrl-C
    assert client.ask("p20") == pc
    client.send("vKill;1")
    assert client.ack() == b"+" and client.reply() == "OK"
    client.sock.close()
    status, errors = finish(process)
    assert status == 0 and "Traceback" not in errors, errors


def test_any_packet_gets_a_reply_without_running_the_board():
    """Hypothesis: whatever bytes a packet holds (but the commands that run, kill or detach), the
    stub answers it (a reply, E.., or the empty reply) and the board has not moved."""
    from hypothesis import given, settings
    from hypothesis import strategies as st

    from emulator.frontends.gdbstub import GdbServer, StopEvent
    from k210_fixtures import make_board

    board = make_board()
    server = GdbServer(board, 0, lambda text: None)
    verbs = st.sampled_from(["m", "M", "X", "g", "G", "p", "P", "H", "T", "z", "Z", "q", "qXfer:features:read:",
                             "qThreadExtraInfo,", "vCont;", "?", ""])
    try:
        @settings(max_examples=int(os.environ.get("FUZZ_EXAMPLES", "400")), deadline=None, derandomize=True)
        @given(verbs, st.binary(max_size=40))
        def check(verb: str, rest: bytes) -> None:
            packet = verb.encode() + rest
            if verb == "vCont;" and any(v in rest for v in (b"c", b"s", b"C", b"S")):
                return                                   # a well-formed one would run the board
            if packet[:1] in (b"c", b"s", b"C", b"S", b"k", b"D", b"R", b"r", b"i", b"I"):
                return                                   # continue, step, kill, detach, restart
            before = (board.time, [h.executed for h in board.harts])
            reply = server.handle(packet)
            assert isinstance(reply, (str, bytes, StopEvent)), packet   # '?' answers with the stop
            assert (board.time, [h.executed for h in board.harts]) == before, packet
        check()
    finally:
        server.close()
