"""A GDB remote stub for the board model (`run --gdb PORT [--gdb-wait]`).

It speaks the GDB remote serial protocol (GDB's manual, "Remote Protocol") on 127.0.0.1 well
enough for gdb-multiarch with the firmware's ELF: both harts as threads 1 and 2, registers
(integer, floating point and the machine CSRs that matter, described by target XML for
riscv:rv64), memory (SRAM, and device registers with the device's own semantics: a read of a
FIFO register pops it, as through a JTAG probe), software and hardware breakpoints, write,
read and access watchpoints, single step, continue, Ctrl-C, detach and kill.

While GDB has the board stopped, nothing runs: virtual time, and every device with it, stands
still. A firmware exception is reported as a stop with its signal (SIGSEGV for an access
fault, SIGILL, SIGBUS for a misaligned access, SIGTRAP for ebreak and ecall) once the hart has
entered its trap handler; a board stop (a hang, an access the model refuses, the firmware's
error report) as a stop with the board's message on GDB's console, instead of ending the run.

Breakpoints and the single step are Python code hooks on the harts' engines, and watchpoints
memory hooks: they cost time only while they are set. A stop hook runs before the native
counter, so the instruction it stops before is neither counted nor timed until it runs.
"""
from __future__ import annotations

import re
import select
import socket
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

import unicorn
from unicorn import riscv_const as rv

from ..errors import (BadInput, BoardStop, ConsoleExpectationsMet, FirmwareReportedError, FirmwareTrap, HangDetected,
                      Interrupted)
from ..cpu import riscv
from ..cpu.hart import HartState
from ..cpu.riscv import CAUSE_INTERRUPT, CSR_MCYCLE, CSR_MHARTID, CSR_MINSTRET

if TYPE_CHECKING:
    from ..board import Board
    from ..cpu.hart import Hart

HOST = "127.0.0.1"
SIGINT, SIGILL, SIGTRAP, SIGABRT, SIGBUS, SIGSEGV, SIGKILL = 2, 4, 5, 6, 7, 11, 9
# mcause -> the signal GDB shows (what a Linux kernel would send for the same exception)
CAUSE_SIGNALS = {0: SIGBUS, 1: SIGSEGV, 2: SIGILL, 3: SIGTRAP, 4: SIGBUS, 5: SIGSEGV, 6: SIGBUS, 7: SIGSEGV,
                 8: SIGTRAP, 9: SIGTRAP, 11: SIGTRAP}
INTERRUPT_BYTE = 0x03
PACKET_SIZE = 0x4000
STOP_LOOK_S = 0.25      # how often a wait for GDB looks whether the board model was asked to stop
# the most a packet may take on the wire: PACKET_SIZE of payload, every byte escaped, and $, #, checksum
MAX_PACKET_BYTES = 2 * PACKET_SIZE + 4
# GDB's numbering for RISC-V (gdb/riscv-tdep.h): x0..x31, pc, f0..f31, then CSR n at 65 + n
PC_REGNUM, FIRST_FPR_REGNUM, FIRST_CSR_REGNUM = 32, 33, 65
# GDB's own names (gdb/features/riscv/64bit-cpu.xml) are the psABI's, but x8 is "fp"
GPR_NAMES = [*riscv.GPR_NAMES[:8], "fp", *riscv.GPR_NAMES[9:]]
FPR_NAMES = list(riscv.FPR_NAMES)
# the CSRs shown: (name, number, Unicorn register or None where the board answers)
CSRS = [("fflags", riscv.CSR_FFLAGS, rv.UC_RISCV_REG_FFLAGS), ("frm", riscv.CSR_FRM, rv.UC_RISCV_REG_FRM),
        ("fcsr", riscv.CSR_FCSR, rv.UC_RISCV_REG_FCSR), ("mstatus", riscv.CSR_MSTATUS, rv.UC_RISCV_REG_MSTATUS),
        ("misa", riscv.CSR_MISA, rv.UC_RISCV_REG_MISA), ("mie", riscv.CSR_MIE, rv.UC_RISCV_REG_MIE),
        ("mtvec", riscv.CSR_MTVEC, rv.UC_RISCV_REG_MTVEC), ("mscratch", riscv.CSR_MSCRATCH, rv.UC_RISCV_REG_MSCRATCH),
        ("mepc", riscv.CSR_MEPC, rv.UC_RISCV_REG_MEPC), ("mcause", riscv.CSR_MCAUSE, rv.UC_RISCV_REG_MCAUSE),
        ("mtval", riscv.CSR_MTVAL, rv.UC_RISCV_REG_MTVAL), ("mip", riscv.CSR_MIP, None),
        ("mcycle", CSR_MCYCLE, None), ("minstret", CSR_MINSTRET, None), ("mhartid", CSR_MHARTID, None)]
CSR_BY_REGNUM = {FIRST_CSR_REGNUM + number: (name, number, reg) for name, number, reg in CSRS}
WATCH_KINDS = {2: "watch", 3: "rwatch", 4: "awatch"}


def target_xml() -> str:
    """The target description: RV64 integer registers, doubles, the CSRs above."""
    gprs = "".join(f'<reg name="{name}" bitsize="64" regnum="{n}" type="{"code_ptr" if n == 1 else "int"}"/>'
                   for n, name in enumerate(GPR_NAMES))
    fprs = "".join(f'<reg name="{name}" bitsize="64" regnum="{FIRST_FPR_REGNUM + n}" type="ieee_double"/>'
                   for n, name in enumerate(FPR_NAMES))
    fp_csrs = "".join(f'<reg name="{name}" bitsize="64" regnum="{FIRST_CSR_REGNUM + number}" type="int"/>'
                      for name, number, _ in CSRS if number < 0x100)
    csrs = "".join(f'<reg name="{name}" bitsize="64" regnum="{FIRST_CSR_REGNUM + number}" type="int"/>'
                   for name, number, _ in CSRS if number >= 0x100)
    return ('<?xml version="1.0"?><!DOCTYPE target SYSTEM "gdb-target.dtd"><target version="1.0">'
            '<architecture>riscv:rv64</architecture>'
            f'<feature name="org.gnu.gdb.riscv.cpu">{gprs}'
            f'<reg name="pc" bitsize="64" regnum="{PC_REGNUM}" type="code_ptr"/></feature>'
            f'<feature name="org.gnu.gdb.riscv.fpu">{fprs}{fp_csrs}</feature>'
            f'<feature name="org.gnu.gdb.riscv.csr">{csrs}</feature></target>')


def _hex(text: str) -> int:
    """A number of the remote protocol: hex digits only (int() would take a sign or spaces too)."""
    if not re.fullmatch(r"[0-9a-fA-F]+", text):
        raise ValueError(f"not a hex number: {text!r}")
    return int(text, 16)


def checksum(payload: bytes) -> bytes:
    return f"{sum(payload) & 0xFF:02x}".encode()


def escape(payload: bytes) -> bytes:
    """Binary data in a packet: '#', '$', '}' and '*' escaped as '}' then the byte ^ 0x20."""
    out = bytearray()
    for byte in payload:
        if byte in b"#$}*":
            out += bytes((0x7D, byte ^ 0x20))
        else:
            out.append(byte)
    return bytes(out)


def unescape(payload: bytes) -> bytes:
    out, i = bytearray(), 0
    while i < len(payload):
        if payload[i] == 0x7D and i + 1 < len(payload):
            out.append(payload[i + 1] ^ 0x20)
            i += 2
        else:
            out.append(payload[i])
            i += 1
    return bytes(out)


class ProtocolError(Exception):
    """GDB went away, or sent something that is not a packet."""


class Connection:
    """One GDB connection: packets in and out, acknowledgements, the interrupt byte."""

    def __init__(self, sock: socket.socket, stop_check: Callable[[], None] = lambda: None) -> None:
        self.sock = sock
        self.stop_check = stop_check     # raises when the board model was asked to stop (a signal)
        self.acks = True
        self._buffer = bytearray()
        self.interrupted = False
        # a packet refused for its length whose end has not come yet: every byte up to its '#' and
        # checksum is the packet's (a 0x03 in it is data, not Ctrl-C)
        self._refusing = False

    def _fill(self, timeout: float | None) -> bool:
        ready, _, _ = select.select([self.sock], [], [], timeout)
        if not ready:
            return False
        try:
            data = self.sock.recv(65536)
        except OSError as error:
            raise ProtocolError(f"connection lost ({error.strerror or error})") from None
        if not data:
            raise ProtocolError("GDB closed the connection")
        self._buffer += data
        return True

    def poll_interrupt(self) -> bool:
        """While the board runs: has GDB sent Ctrl-C (since the last look)? Other bytes wait."""
        if not self.interrupted and self._fill(0) and INTERRUPT_BYTE in self._buffer:
            self._buffer = self._buffer.replace(bytes((INTERRUPT_BYTE,)), b"")
            self.interrupted = True
        interrupted, self.interrupted = self.interrupted, False
        return interrupted

    def receive(self) -> bytes:
        """The next packet's payload (acknowledged); a bare Ctrl-C comes back as b'\\x03'. A packet
        longer than the PacketSize the stub advertises (a payload of PACKET_SIZE bytes, its
        escapes counted) is refused whole: its bytes are dropped and GDB is told to send again."""
        scanned = 0                          # how far the search for the packet's end has looked
        while True:
            if self._refusing:
                end = self._buffer.find(b"#")
                if end < 0:
                    del self._buffer[:]
                    self._wait()
                    continue
                if len(self._buffer) < end + 3:
                    del self._buffer[:end]       # the checksum's digits are still to come
                    self._wait()
                    continue
                del self._buffer[:end + 3]
                self._refusing = False
            start = self._buffer.find(b"$")
            if self.interrupted or (start < 0 and INTERRUPT_BYTE in self._buffer):
                self.interrupted = False
                self._buffer = self._buffer.replace(bytes((INTERRUPT_BYTE,)), b"", 1)
                return bytes((INTERRUPT_BYTE,))
            if start >= 0:
                end = self._buffer.find(b"#", max(start, scanned))
                if end >= 0 and len(self._buffer) >= end + 3:
                    payload = bytes(self._buffer[start + 1:end])
                    sent_sum = bytes(self._buffer[end + 1:end + 3]).lower()
                    del self._buffer[:end + 3]
                    scanned = 0
                    if self.acks:
                        good = sent_sum == checksum(payload)
                        self.sock.sendall(b"+" if good else b"-")
                        if not good:
                            continue
                    return payload
                if end < 0:
                    scanned = len(self._buffer)
                    if scanned - start > MAX_PACKET_BYTES:
                        del self._buffer[:]          # too long: refused, and the rest of it as it comes
                        self._refusing = True
                        scanned = 0
                        if self.acks:
                            self.sock.sendall(b"-")
                        continue
            elif self._buffer:
                del self._buffer[:]          # acknowledgements and noise between packets
            self._wait()

    def _wait(self) -> None:
        """Waits for GDB's next bytes, looking a few times a second whether a signal asked the
        board model to stop (the wait would otherwise outlast it)."""
        while not self._fill(STOP_LOOK_S):
            self.stop_check()

    def wait_for_close(self, timeout: float = 2.0) -> None:
        """After a kill: GDB closes the connection itself (closing first would be an error to it)."""
        try:
            while self._fill(timeout):
                pass
        except ProtocolError:
            pass

    def send(self, payload: bytes | str) -> None:
        data = payload.encode() if isinstance(payload, str) else payload
        frame = b"$" + data + b"#" + checksum(data)
        for _ in range(5):
            self.sock.sendall(frame)
            if not self.acks:
                return
            while True:
                while not self._buffer:
                    self._wait()
                byte = self._buffer[0]
                if byte in b"+-":
                    del self._buffer[:1]
                    break
                if byte == INTERRUPT_BYTE:
                    del self._buffer[:1]
                    self.interrupted = True
                    continue
                return      # GDB went on with a packet: take the reply as received
            if byte == ord("+"):
                return
        raise ProtocolError("GDB refused a reply five times")


@dataclass
class StopEvent:
    signal: int
    hart: int
    extra: str = ""          # e.g. "swbreak:;" or "watch:80001234;"
    message: str = ""        # shown on GDB's console first


class Debugger:
    """The board under GDB's control: breakpoints, watchpoints, stepping, registers, memory."""

    def __init__(self, board: "Board") -> None:
        self.board = board
        self.breakpoints: dict[int, str] = {}                   # address -> "swbreak" / "hwbreak"
        self._bp_hooks: dict[int, list[int]] = {}
        self.watchpoints: dict[tuple[int, int, int], list[int]] = {}   # (kind, address, length) -> hooks
        self.event: StopEvent | None = None
        self._skip: dict[int, int] = {}                         # hart -> breakpoint address to pass once
        self._step_hook: tuple["Hart", int] | None = None
        self._step_started = False
        self.ended: str | None = None
        for hart in board.harts:
            self._wrap_traps(hart)

    # --- stop conditions ------------------------------------------------------------------

    def _wrap_traps(self, hart: "Hart") -> None:
        enter = hart.enter_trap

        def enter_trap(cause: int, epc: int, tval: int) -> None:
            enter(cause, epc, tval)
            if not cause & CAUSE_INTERRUPT and self.event is None:
                name = riscv.EXCEPTION_NAMES.get(cause, f"exception {cause}")
                self.event = StopEvent(CAUSE_SIGNALS.get(cause, SIGTRAP), hart.hart_id,
                                       message=f"hart {hart.hart_id}: {name} at pc 0x{epc:x}, mtval 0x{tval:x}; "
                                               f"stopped at its trap handler (mepc, mcause, mtval say where)\n")
        hart.enter_trap = enter_trap

    def _stop_before(self, uc: unicorn.Uc, hart: "Hart") -> None:
        """Stops the hart before the instruction whose hook is running (a stop hook runs before
        the native counter, which then never sees the instruction: Hart.add_stop_hook)."""
        uc.emu_stop()

    def _on_breakpoint(self, uc: unicorn.Uc, address: int, size: int, hart: "Hart") -> None:
        if self._skip.get(hart.hart_id) == address:
            del self._skip[hart.hart_id]
            return
        if address in self.breakpoints and self.event is None:
            self._stop_before(uc, hart)
            self.event = StopEvent(SIGTRAP, hart.hart_id, f"{self.breakpoints[address]}:;")

    def set_breakpoint(self, address: int, kind: str) -> None:
        if address in self.breakpoints:
            self.breakpoints[address] = kind
            return
        self.breakpoints[address] = kind
        self._bp_hooks[address] = [hart.add_stop_hook(self._on_breakpoint, hart, address, address)
                                   for hart in self.board.harts]

    def clear_breakpoint(self, address: int) -> None:
        self.breakpoints.pop(address, None)
        for hart, handle in zip(self.board.harts, self._bp_hooks.pop(address, [])):
            hart.delete_hook(handle)

    def _on_access(self, kind: int):
        def hook(uc, access, address, size, value, hart):
            if self.event is None:
                hart.request_stop()           # after this instruction: GDB reports a watchpoint after the access
                self.event = StopEvent(SIGTRAP, hart.hart_id, f"{WATCH_KINDS[kind]}:{address:x};")
        return hook

    def set_watchpoint(self, kind: int, address: int, length: int) -> None:
        key = (kind, address, length)
        if key in self.watchpoints:
            return
        types = {2: unicorn.UC_HOOK_MEM_WRITE, 3: unicorn.UC_HOOK_MEM_READ,
                 4: unicorn.UC_HOOK_MEM_WRITE | unicorn.UC_HOOK_MEM_READ}[kind]
        self.watchpoints[key] = [hart.add_hook(types, self._on_access(kind), hart, address, address + length - 1)
                                 for hart in self.board.harts]

    def clear_watchpoint(self, kind: int, address: int, length: int) -> None:
        for hart, handle in zip(self.board.harts, self.watchpoints.pop((kind, address, length), [])):
            hart.delete_hook(handle)

    def clear_all(self) -> None:
        for address in list(self.breakpoints):
            self.clear_breakpoint(address)
        for key in list(self.watchpoints):
            self.clear_watchpoint(*key)

    # --- running ------------------------------------------------------------------------------

    def _on_step(self, uc: unicorn.Uc, address: int, size: int, hart: "Hart") -> None:
        if not self._step_started:
            self._step_started = True      # the instruction being stepped
            return
        if self.event is None:
            self._stop_before(uc, hart)
            self.event = StopEvent(SIGTRAP, hart.hart_id)

    def resume(self, step_hart: int | None) -> None:
        """Lets the board run on: every hart, and with step_hart set, until that hart has run one
        instruction. A hart standing on a breakpoint passes it once."""
        self.event = None
        for hart in self.board.harts:
            if hart.pc in self.breakpoints:
                self._skip[hart.hart_id] = hart.pc
        if step_hart is not None:
            hart = self.board.harts[step_hart]
            self._step_started = False
            self._step_hook = (hart, hart.add_stop_hook(self._on_step, hart, 1, 0))

    def _end_step(self) -> None:
        if self._step_hook is not None:
            hart, handle = self._step_hook
            hart.delete_hook(handle)
            self._step_hook = None

    def run_until_stop(self, interrupted: Callable[[], bool]) -> StopEvent:
        """Runs turns until a breakpoint, watchpoint, step, trap, board stop or Ctrl-C."""
        scheduler = self.board.scheduler
        try:
            while self.event is None:
                if interrupted():
                    self.event = StopEvent(SIGINT, self._current_hart())
                    break
                if self._stuck():
                    self.event = StopEvent(SIGTRAP, self._current_hart(),
                                           message="[board] every hart sleeps in wfi and no device will ever raise "
                                                   "an interrupt: nothing more will happen\n")
                    break
                try:
                    scheduler.step()
                except Interrupted:
                    raise                  # Ctrl-C or SIGTERM to the board model itself ends the run
                except BoardStop as stop:
                    self.event = self._board_stopped(stop)
            return self.event
        finally:
            self._end_step()
            self._skip.clear()

    def _stuck(self) -> bool:
        scheduler = self.board.scheduler
        return (all(h.state is not HartState.RUNNING for h in self.board.harts)
                and self.board.next_device_event(scheduler.time) is None and scheduler._trap_deadline is None)

    def _current_hart(self) -> int:
        running = [h.hart_id for h in self.board.harts if h.state is HartState.RUNNING]
        return running[0] if running else 0

    def _board_stopped(self, stop: BoardStop) -> StopEvent:
        """A stop that would end a run: shown in GDB as a signal; continuing goes on from there."""
        scheduler = self.board.scheduler
        scheduler.pending_stop = None
        scheduler.traps.report = None
        scheduler._trap_deadline = None
        scheduler._error_report = None
        if isinstance(stop, ConsoleExpectationsMet):
            signal = SIGTRAP
        elif isinstance(stop, FirmwareTrap):
            signal = SIGSEGV
        elif isinstance(stop, FirmwareReportedError):
            signal = SIGABRT
        elif isinstance(stop, HangDetected):
            signal = SIGTRAP
        else:
            signal = SIGBUS
        return StopEvent(signal, self._current_hart(), message=f"[board] stopped ({stop.kind}): {stop}\n")

    # --- registers ------------------------------------------------------------------------------

    def read_register(self, hart: "Hart", regnum: int) -> int | None:
        if regnum < 32:
            return hart.reg(rv.UC_RISCV_REG_X0 + regnum) if regnum else 0
        if regnum == PC_REGNUM:
            return hart.pc
        if FIRST_FPR_REGNUM <= regnum < FIRST_FPR_REGNUM + 32:
            return hart.reg(rv.UC_RISCV_REG_F0 + regnum - FIRST_FPR_REGNUM)
        csr = CSR_BY_REGNUM.get(regnum)
        if csr is None:
            return None
        _, number, register = csr
        if register is not None:
            return hart.csr(register)
        if number == CSR_MINSTRET:
            return (hart.instret + hart.minstret_offset) & (2**64 - 1)
        return hart._csr_value(number)

    def write_register(self, hart: "Hart", regnum: int, value: int) -> bool:
        if 0 < regnum < 32:
            hart.set_reg(rv.UC_RISCV_REG_X0 + regnum, value)
        elif regnum == 0:
            pass
        elif regnum == PC_REGNUM:
            hart.set_reg(rv.UC_RISCV_REG_PC, value)
        elif FIRST_FPR_REGNUM <= regnum < FIRST_FPR_REGNUM + 32:
            hart.set_reg(rv.UC_RISCV_REG_F0 + regnum - FIRST_FPR_REGNUM, value)
        elif regnum in CSR_BY_REGNUM and CSR_BY_REGNUM[regnum][2] is not None:
            hart.set_csr(CSR_BY_REGNUM[regnum][2], value)
        else:
            return False
        return True

    # --- memory -------------------------------------------------------------------------------------

    def _device_at(self, address: int):
        return next((p for p in self.board.peripherals if p.BASE <= address < p.BASE + p.SIZE), None)

    def read_memory(self, address: int, length: int) -> bytes | None:
        """SRAM as it is; device registers read as the harts would (32-bit words, with the
        device's side effects). None where nothing answers or a device refuses."""
        bus = self.board.bus
        if bus.is_sram(address) and bus.is_sram(address + length - 1):
            return self.board.memory.read(address, length)
        out = bytearray()
        for word in range(address & ~3, address + length, 4):
            peripheral = self._device_at(word)
            if peripheral is None:
                return bytes(out[address - (address & ~3):]) if out else None
            try:
                bus._gate_check(peripheral)
                value = peripheral.read(word - peripheral.BASE, 4, self.board.time)
            except BoardStop:
                return None
            out += value.to_bytes(4, "little")
        start = address - (address & ~3)
        return bytes(out[start:start + length])

    def write_memory(self, address: int, data: bytes) -> bool:
        bus = self.board.bus
        if bus.is_sram(address) and bus.is_sram(address + len(data) - 1):
            self.board.memory.load(address, data)
            for hart in self.board.harts:       # code may have changed: drop what was translated
                hart.code_written(address, address + len(data))
            return True
        if address % 4 or len(data) % 4:
            return False
        for offset in range(0, len(data), 4):
            peripheral = self._device_at(address + offset)
            if peripheral is None:
                return False
            try:
                bus._gate_check(peripheral)
                peripheral.write(address + offset - peripheral.BASE, 4,
                                 int.from_bytes(data[offset:offset + 4], "little"), self.board.time)
            except BoardStop:
                return False
        return True


class GdbServer:
    """Serves one GDB at a time on 127.0.0.1:port for a board."""

    def __init__(self, board: "Board", port: int, log: Callable[[str], None]) -> None:
        self.board = board
        self.log = log
        self.debugger = Debugger(board)
        self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self.listener.bind((HOST, port))
        except OSError as error:
            self.listener.close()
            raise BadInput(f"--gdb {port}: cannot listen on {HOST}:{port} ({error.strerror or error})") from None
        self.listener.listen(1)
        self.port = self.listener.getsockname()[1]
        self.conn: Connection | None = None
        self.general = 0           # the hart Hg selected (registers, memory)
        self.outcome = "detached"

    def close(self) -> None:
        if self.conn is not None:
            self.conn.sock.close()
        self.listener.close()

    def accept(self) -> None:
        while not select.select([self.listener], [], [], STOP_LOOK_S)[0]:
            self._stop_check()
        sock, _ = self.listener.accept()
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.conn = Connection(sock, self._stop_check)
        self.log(f"[gdb] connected on {HOST}:{self.port}")

    def _stop_check(self) -> None:
        """A signal to the board model (SIGINT, SIGTERM) ends the run, even while GDB is quiet."""
        stop = self.board.scheduler.pending_stop
        if isinstance(stop, Interrupted):
            raise stop

    def serve(self) -> str:
        """Answers GDB until it detaches or kills the run; returns which ('detached', 'killed',
        'disconnected')."""
        conn = self.conn
        debugger = self.debugger
        try:
            while True:
                packet = conn.receive()
                reply = self.handle(packet)
                if isinstance(reply, StopEvent):
                    self.stop_reply(reply)
                elif reply is not None:
                    conn.send(reply)
                if self.outcome == "killed":
                    conn.wait_for_close()
                    break
                if self.outcome == "detached-now":
                    break
        except ProtocolError as error:
            self.log(f"[gdb] {error}; the run goes on without it")
            self.outcome = "disconnected"
        debugger.clear_all()
        return "detached" if self.outcome == "detached-now" else self.outcome

    def stop_reply(self, event: StopEvent) -> None:
        if event.message:
            self.conn.send("O" + event.message.encode().hex())
        self.general = event.hart
        self.conn.send(f"T{event.signal:02x}thread:{event.hart + 1:x};{event.extra}")

    def _hart(self):
        return self.board.harts[self.general]

    def _run(self, step_hart: int | None) -> StopEvent:
        self.debugger.resume(step_hart)
        return self.debugger.run_until_stop(self.conn.poll_interrupt)

    def handle(self, packet: bytes):
        """The reply to one packet: bytes/str to send, a StopEvent, or None for no reply. A packet
        that does not parse (a missing field, a number that is not hex, a thread that does not
        exist) gets an error reply, E01, as the remote protocol has it, and the run goes on."""
        try:
            return self._handle(packet)
        except (ValueError, IndexError) as error:
            self.log(f"[gdb] malformed packet {packet[:40]!r}: {error}")
            return "E01"

    def _handle(self, packet: bytes):
        if not packet:
            return ""                        # the empty packet: not a command
        if packet == bytes((INTERRUPT_BYTE,)):
            return StopEvent(SIGINT, self.general)
        text = packet.decode("latin-1")
        command = text[:1]
        if text.startswith("qSupported"):
            return (f"PacketSize={PACKET_SIZE:x};qXfer:features:read+;QStartNoAckMode+;vContSupported+;"
                    f"swbreak+;hwbreak+")
        if text == "QStartNoAckMode":
            self.conn.send("OK")
            self.conn.acks = False
            return None
        if text.startswith("qXfer:features:read:target.xml:"):
            offset, length = (int(x, 16) for x in text.rsplit(":", 1)[1].split(","))
            document = target_xml().encode()
            chunk = document[offset:offset + length]
            return (b"l" if offset + length >= len(document) else b"m") + escape(chunk)
        if text in ("qfThreadInfo",):
            return "m" + ",".join(f"{h.hart_id + 1:x}" for h in self.board.harts)
        if text == "qsThreadInfo":
            return "l"
        if text == "qC":
            return f"QC{self.general + 1:x}"
        if text == "qAttached":
            return "1"
        if text.startswith("qThreadExtraInfo,"):
            hart = self.board.harts[self._thread_index(text.split(",")[1])]
            return f"hart {hart.hart_id}: {hart.state.value}".encode().hex()
        if text == "?":
            return StopEvent(SIGTRAP, self.general)
        if command == "H":
            if text[1:2] not in ("g", "c"):
                raise ValueError("H without g or c")
            thread = int(text[2:], 16) if text[2:] not in ("", "-1") else 0
            if thread > 0:
                if thread > len(self.board.harts):
                    return "E02"
                if text[1] == "g":
                    self.general = thread - 1
            return "OK"
        if command == "T":
            return "OK" if 0 < int(text[1:], 16) <= len(self.board.harts) else "E01"
        if command == "g":
            return "".join(self._register_hex(n) for n in range(33))
        if command == "G":
            data = bytes.fromhex(text[1:])
            for n in range(min(33, len(data) // 8)):
                self.debugger.write_register(self._hart(), n, int.from_bytes(data[8 * n:8 * n + 8], "little"))
            return "OK"
        if command == "p":
            value = self.debugger.read_register(self._hart(), int(text[1:], 16))
            return "E45" if value is None else self._hex64(value)
        if command == "P":
            number, value = text[1:].split("=")
            ok = self.debugger.write_register(self._hart(), int(number, 16),
                                              int.from_bytes(bytes.fromhex(value), "little"))
            return "OK" if ok else "E45"
        if command == "m":
            address, length = (_hex(x) for x in text[1:].split(","))
            data = self.debugger.read_memory(address, min(length, PACKET_SIZE // 2))
            return "E14" if data is None else data.hex()
        if command == "M":
            where, data = text[1:].split(":")
            address, length = (_hex(x) for x in where.split(","))
            if len(data) != 2 * length:
                raise ValueError("M's length is not its data's")
            return "OK" if self.debugger.write_memory(address, bytes.fromhex(data)) else "E14"
        if command == "X":
            head, colon, data = packet[1:].partition(b":")
            where, length = head.split(b",")
            address, data = int(where, 16), unescape(data)
            if not colon or len(data) != int(length, 16):
                raise ValueError("X's length is not its data's")
            return "OK" if not data or self.debugger.write_memory(address, data) else "E14"
        if command in ("z", "Z"):
            kind, address, length = text[1:].split(";")[0].split(",")
            kind, address, length = int(kind), int(address, 16), int(length, 16)
            if kind in (0, 1):
                if command == "Z":
                    self.debugger.set_breakpoint(address, "swbreak" if kind == 0 else "hwbreak")
                else:
                    self.debugger.clear_breakpoint(address)
                return "OK"
            if kind in WATCH_KINDS:
                if command == "Z":
                    self.debugger.set_watchpoint(kind, address, max(1, length))
                else:
                    self.debugger.clear_watchpoint(kind, address, max(1, length))
                return "OK"
            return ""
        if text == "vCont?":
            return "vCont;c;C;s;S"
        if text.startswith("vCont;"):
            return self._vcont(text[6:])
        if command in ("c", "C"):
            return self._run(None)
        if command in ("s", "S"):
            return self._run(self.general)
        if command == "D":
            self.outcome = "detached-now"
            return "OK"
        if command == "k" or text.startswith("vKill"):
            self.outcome = "killed"
            self.debugger.ended = "killed"
            return "OK" if text.startswith("vKill") else None
        return ""            # not supported: GDB falls back or says so

    def _vcont(self, actions: str):
        """vCont;ACTION[:THREAD]...: continue (c, Cxx) or step (s, Sxx) a hart; anything else, or
        no action, is an error and nothing runs."""
        step_hart = None
        if not actions:
            raise ValueError("vCont without an action")
        for action in actions.split(";"):
            verb, _, thread = action.partition(":")
            if not re.fullmatch(r"[cs]|[CS][0-9a-fA-F]{2}", verb):
                raise ValueError(f"vCont action {verb!r}")
            hart = self._thread_index(thread) if thread not in ("", "-1") else self.general
            if verb[0] in "sS":
                step_hart = hart
        return self._run(step_hart)

    def _thread_index(self, thread: str) -> int:
        """A hart's index from GDB's thread id (1, 2: hart 0, 1; 0: any, the selected one)."""
        if not re.fullmatch(r"[0-9a-fA-F]+", thread):
            raise ValueError(f"thread id {thread!r}")
        if int(thread, 16) == 0:
            return self.general
        index = int(thread, 16) - 1
        if not 0 <= index < len(self.board.harts):
            raise ValueError(f"no thread {thread}")
        return index

    def _hex64(self, value: int) -> str:
        return (value & (2**64 - 1)).to_bytes(8, "little").hex()

    def _register_hex(self, regnum: int) -> str:
        return self._hex64(self.debugger.read_register(self._hart(), regnum) or 0)
