"""UARTHS (0x3800_0000): the SiFive UART wired to the Dock's USB serial bridge.

Bytes written to txdata go through an 8-entry transmit FIFO that drains at the
programmed baud rate (core clock / (div + 1), 10 bits per byte with one stop
bit); each byte reaches the console when its stop bit is out. With txen = 0
bytes wait in the FIFO, as on the real UART. A byte written while the FIFO is
full is lost, as on the chip, with a warning (the firmware should wait while
txdata reads FULL).

The receiver takes what --uart-input sends (uart_input.py) into an 8-entry
receive FIFO, one byte per 10 bit times at the programmed baud. rxdata reads
the oldest byte (bit 31 set: empty); ip.rxwm is raised while the FIFO holds more
than rxctrl.rxcnt bytes (SiFive FE310-G000 manual, UART chapter, whose UART is
the block UARTHS is). The host side waits while the receiver is off or its FIFO
is full, as QEMU's and Renode's serial back-ends hand a device a byte only when
it can take one: on the chip those bytes would be lost, but a test's input
should not depend on how fast a firmware boots.
"""
from __future__ import annotations

import itertools
from collections import deque
from typing import Callable, Iterator

from ..memory_map import K210_BLOCKS
from ..vtime import PS_PER_MS, Time
from .mmio import BUS_TILELINK, Peripheral, Register
from .ports import Ports, SerialInput
from .uart import ByteTrain, next_byte

TXDATA, RXDATA, TXCTRL, RXCTRL, IE, IP, DIV = 0x00, 0x04, 0x08, 0x0C, 0x10, 0x14, 0x18
TX_FIFO_DEPTH = 8
RX_FIFO_DEPTH = 8
FULL = 1 << 31
EMPTY = 1 << 31
IP_TXWM, IP_RXWM = 1, 2
NEWLINE = 0x0A
RXCTRL_RXEN = 1
INTERACTIVE_POLL: Time = 50 * PS_PER_MS   # virtual time between looks at a terminal while nothing was typed


class Uarths(Peripheral):
    NAME = "UARTHS"
    BASE = K210_BLOCKS["UARTHS"].base
    SIZE = K210_BLOCKS["UARTHS"].size
    BUS = BUS_TILELINK
    # fields as sifive-blocks' UART declares them: an 8-bit txdata byte (a store that covers it
    # queues it), txen and nstop, the 3-bit watermarks at bit 16, a 16-bit divisor
    REGISTERS = {
        TXDATA: Register("txdata", fields=((0, 8),), steady=True), RXDATA: Register("rxdata", writable=False),
        TXCTRL: Register("txctrl", fields=((0, 1), (1, 1), (16, 3))), RXCTRL: Register("rxctrl", fields=((0, 1), (16, 3))),
        IE: Register("ie", fields=((0, 1), (1, 1))), IP: Register("ip", writable=False),
        DIV: Register("div", reset=0x0D8D, fields=((0, 16),)),  # 115200 baud from the 26 MHz oscillator... about
    }

    def __init__(self, ports: Ports, on_byte: Callable[[int], None]) -> None:
        """on_byte: hears each byte as its stop bit goes out (the Dock's USB-serial bridge)."""
        super().__init__(ports)
        self.on_byte = on_byte
        self._fifo: deque[int] = deque()
        self._shifting_until: Time | None = None    # end time of the byte on the wire
        self._tx_train: ByteTrain | None = None      # the bytes sent back to back, that one the last
        self.last_byte_time: Time = 0                # when the last byte's stop bit went out
        self.input: SerialInput | None = None          # what the host sends (--uart-input)
        self._rx_fifo: deque[int] = deque()
        self._receiving_until: Time | None = None   # end time of the byte coming in
        self._rx_train: ByteTrain | None = None      # the bytes received back to back, likewise
        self._receiving_byte = 0
        self.bytes_received = 0
        # whoever hears the console acts on each byte the moment it is out (a console watch that
        # ends the run): then no byte's end is quiet (quiet_byte_ends)
        self.every_byte_heard = False

    def reset(self, now: Time) -> None:
        """A chip reset: registers and FIFOs as at power-on; a byte on the wire is cut off (one
        coming in is sent again by the host's bridge, as DwUart.reset says)."""
        self.advance(now)
        if self._receiving_until is not None and self.input is not None:
            self.input.put_back(self._receiving_byte)
        super().reset(now)
        self._fifo.clear()
        self._rx_fifo.clear()
        self._shifting_until = None
        self._receiving_until = None
        self._tx_train = self._rx_train = None

    def _frame(self) -> tuple[int, int]:
        """A byte's length on the line: (cycles, hz), bits x (div + 1) cycles of the core clock."""
        bits = 10 + (1 if self.values[TXCTRL] >> 1 & 1 else 0)
        return bits * (self.values[DIV] + 1), self.ports.clock.cpu_hz()

    def advance(self, now: Time) -> None:
        self._advance_tx(now)
        if self.input is not None:
            self._advance_rx(now)

    def _advance_rx(self, now: Time) -> None:
        while True:
            if self._receiving_until is not None:
                if self._receiving_until > now:
                    return
                self._rx_fifo.append(self._receiving_byte)
                self.bytes_received += 1
                start = self._receiving_until
                self._receiving_until = None
            else:
                start = now
            if not self._receiver_ready() or not self.input.has_byte(start):
                return
            self._receiving_byte = self.input.pop()
            self._rx_train = next_byte(self._rx_train, start, *self._frame())
            self._receiving_until = self._rx_train.end(self._rx_train.count)

    def _receiver_ready(self) -> bool:
        return bool(self.values[RXCTRL] & RXCTRL_RXEN) and len(self._rx_fifo) < RX_FIFO_DEPTH

    def _advance_tx(self, now: Time) -> None:
        while True:
            if self._shifting_until is not None:
                if self._shifting_until > now:
                    return
                self.last_byte_time = self._shifting_until
                self.on_byte(self._pending_byte)
                start = self._shifting_until
                self._shifting_until = None
            else:
                start = now
            if not self._fifo or not self.values[TXCTRL] & 1:
                return
            self._pending_byte = self._fifo.popleft()
            self._tx_train = next_byte(self._tx_train, start, *self._frame())
            self._shifting_until = self._tx_train.end(self._tx_train.count)

    def next_event_time(self, now: Time) -> Time | None:
        events = [t for t in (self._shifting_until, self._receiver_event(now)) if t is not None]
        return min(events) if events else None

    def _receiver_event(self, now: Time) -> Time | None:
        if self._receiving_until is not None:
            return self._receiving_until
        source = self.input
        if source is not None and self._receiver_ready():
            if source.has_byte(now):
                return now                              # the next byte starts coming in now
            if source.may_grow:
                return now + INTERACTIVE_POLL           # look at the terminal again then
        return None

    def quiet_byte_ends(self) -> tuple[Time, ...]:
        """The ends of the bytes about to leave that change nothing but the FIFO's level and the
        console's record of them (each is heard with its own time, last_byte_time, whenever the
        UART is advanced past it): not a line's end (the board reads each whole line, and an error
        report, at its end), no transmit-watermark interrupt enabled, nobody acting on each byte
        (every_byte_heard), no terminal typed into meanwhile (whose next look depends on when it is
        asked). The ends in a row, as advance works them out, up to the first byte that is not
        quiet; the board's turns may run past them without stopping (Scheduler._go_on_alone). At most
        the FIFO's bytes and the one on the wire."""
        return self._quiet_chain()[0]

    def next_loud_event_time(self, now: Time) -> Time | None:
        """next_event_time, with the quiet byte ends (quiet_byte_ends) left out."""
        _, loud = self._quiet_chain()
        events = [t for t in (loud, self._receiver_event(now)) if t is not None]
        return min(events) if events else None

    def _quiet_chain(self) -> tuple[tuple[Time, ...], Time | None]:
        """(quiet_byte_ends, the end of the first byte about to leave that is not quiet (None: none
        is)), in one walk along the bytes."""
        if self._shifting_until is None:
            return (), None
        if self.every_byte_heard or self.values[IE] & IP_TXWM or (self.input is not None and self.input.may_grow):
            return (), self._shifting_until
        ends: list[Time] = []
        for end, byte in zip(self._leaving_ends(), self._leaving()):
            if byte == NEWLINE:
                return tuple(ends), end
            ends.append(end)
        return tuple(ends), None

    def _leaving_ends(self) -> Iterator[Time]:
        """The ends of the bytes that leave back to back from now on (_leaving), as advance will work
        them out: the one on the wire's, then those of the train the next bytes join (the running
        one, or a new one from that end if the byte's length has changed since it began)."""
        end = self._shifting_until
        yield end
        cycles, hz = self._frame()
        train = self._tx_train
        if train is None or (train.cycles, train.hz) != (cycles, hz):
            train = ByteTrain(end, cycles, hz)
        for k in itertools.count(train.count + 1):
            yield train.end(k)

    def _leaving(self) -> tuple[int, ...]:
        """The bytes that leave back to back from now on: the one on the wire, and the FIFO's while
        the transmitter is on (txen = 0 lets the byte on the wire end and no other start)."""
        if self._shifting_until is None:
            return ()
        if not self.values[TXCTRL] & 1:
            return (self._pending_byte,)
        return (self._pending_byte, *self._fifo)

    def tx_level(self) -> int:
        return len(self._fifo)

    def irq_line(self) -> bool:
        return bool(self.read_ip() & self.values[IE])

    def read_ip(self) -> int:
        tx_watermark = (self.values[TXCTRL] >> 16) & 7
        rx_watermark = (self.values[RXCTRL] >> 16) & 7
        return (IP_TXWM if len(self._fifo) < tx_watermark else 0) | \
            (IP_RXWM if len(self._rx_fifo) > rx_watermark else 0)

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        self.advance(now)
        if offset == TXDATA:
            return FULL if len(self._fifo) >= TX_FIFO_DEPTH else 0
        if offset == RXDATA:
            if not self._rx_fifo:
                return EMPTY
            byte = self._rx_fifo.popleft()
            self.took_on_read = True
            self.advance(now)          # room in the FIFO: the host's next byte may start
            return byte
        if offset == IP:
            return self.read_ip()
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        self.advance(now)
        if offset == TXDATA:
            if len(self._fifo) < TX_FIFO_DEPTH:
                self._fifo.append(value & 0xFF)
            else:
                # the text names no byte, so that a firmware that never waits gets one
                # counted warning rather than one per lost character
                self.ports.warn(f"{self.NAME}: a byte written to txdata while the {TX_FIFO_DEPTH}-byte transmit "
                                f"FIFO was full was lost: a writer must wait while txdata reads bit 31 (full)", now)
        else:
            self.values[offset] = value
        self.advance(now)
