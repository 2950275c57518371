"""UART1-3 (0x5021_0000, 0x5022_0000, 0x5023_0000): Synopsys DesignWare APB UARTs, 16550-compatible.

The register map and its use are the Kendryte SDK's (uart.h `uart_t`, uart.c): 32-bit registers
4 bytes apart, the divisor latch (DLL, DLH) at RBR/THR and IER while LCR.DLAB is set, a
fractional divisor DLF (the SDK's uart_configure: divisor = APB0 clock / baud, DLH:DLL =
divisor / 16, DLF = divisor % 16, so a bit lasts 16 x (DLH:DLL + DLF / 16) APB0 clocks), the
FIFOs through FCR and the shadow registers SRT/STET, and the "programmable THRE interrupt" mode
(IER bit 7) the SDK switches on: then LSR bit 5 means "transmit FIFO full" (the SDK's putchar
waits while it is set) and the THRE interrupt follows the FIFO's level against its threshold.
What the SDK does not say is the DesignWare DW_apb_uart databook's 16550 behaviour, as Linux's
8250 and 8250_dw drivers rely on it: IIR's priorities (line status, received data or
character timeout, THR empty, modem status), LSR's error bits cleared by reading it, USR, TFL,
RFL, SRR's resets.

The FIFOs hold 16 bytes: the SDK's trigger names (uart.h: receive 1, 4, 8, 14 for "1 byte,
1/4, 1/2, 2 less than full"; transmit 0, 2, 4, 8 for "empty, 2 bytes, 1/4, 1/2") are those
of a 16-byte FIFO. Each byte takes start + data + parity + stop bits; what leaves the
transmitter goes to the pin FPIOA routes UARTn_TX to (the Dock's wiring hears it), or back
to the receiver in loopback (MCR bit 4). The receiver takes what the host sends (--uart-input)
as UARTHS does. DMA handshakes (SYSCTL dma_sel's UARTn requests) keep the transmit FIFO full
from memory, one 32-bit item a byte, and hand each received byte to the channel. The parameter
registers say what the databook says they say when the encoded
parameters are not configured (CPR 0), UCV 0; CTR is the DesignWare peripheral id 0x44570110.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

import numpy as np

from ..memory_map import K210_BLOCKS
from ..vtime import PS_PER_MS, Time, cycles_time
from .mmio import Peripheral, Register
from .ports import Ports, SerialInput

if TYPE_CHECKING:
    from .dmac import DmaChannel

RBR, IER, IIR, LCR, MCR, LSR, MSR, SCR = 0x00, 0x04, 0x08, 0x0C, 0x10, 0x14, 0x18, 0x1C
LPDLL, LPDLH = 0x20, 0x24
SHADOW_FIRST, SHADOW_LAST = 0x30, 0x6C          # SRBR/STHR: RBR/THR again, 16 times
FAR, USR, TFL, RFL, SRR, SRTS, SBCR, SDMAM = 0x70, 0x7C, 0x80, 0x84, 0x88, 0x8C, 0x90, 0x94
SFE, SRT, STET, HTX, DMASA = 0x98, 0x9C, 0xA0, 0xA4, 0xA8
TCR, DE_EN, RE_EN, DET, TAT, DLF, RAR, TAR, LCR_EXT = 0xAC, 0xB0, 0xB4, 0xB8, 0xBC, 0xC0, 0xC4, 0xC8, 0xCC
CPR, UCV, CTR = 0xF4, 0xF8, 0xFC
FIFO_DEPTH = 16
PERIPHERAL_ID = 0x4457_0110                      # "DW", the databook's CTR

IER_ERBFI, IER_ETBEI, IER_ELSI, IER_EDSSI, IER_PTIME = 1, 2, 4, 8, 0x80
IID_NONE, IID_MODEM, IID_THRE, IID_RDA, IID_LINE, IID_TIMEOUT = 0x1, 0x0, 0x2, 0x4, 0x6, 0xC
FCR_FIFOE, FCR_RFIFOR, FCR_XFIFOR = 1, 2, 4
LCR_STOP, LCR_PEN, LCR_DLAB = 4, 8, 0x80
MCR_LOOPBACK = 0x10
LSR_DR, LSR_OE, LSR_THRE, LSR_TEMT = 1, 2, 0x20, 0x40
LSR_ERRORS = 0x1E                                 # OE, PE, FE, BI: cleared by reading LSR
USR_BUSY, USR_TFNF, USR_TFE, USR_RFNE, USR_RFF = 1, 2, 4, 8, 0x10
SRR_UR, SRR_RFR, SRR_XFR = 1, 2, 4
RX_TRIGGER = (1, FIFO_DEPTH // 4, FIFO_DEPTH // 2, FIFO_DEPTH - 2)     # FCR[7:6], SRT
TX_THRESHOLD = (0, 2, FIFO_DEPTH // 4, FIFO_DEPTH // 2)                # FCR[5:4], STET
TIMEOUT_CHARACTERS = 4          # a character timeout: no byte in or out of the FIFO for 4 byte times
INTERACTIVE_POLL: Time = 50 * PS_PER_MS   # virtual time between looks at a terminal while nothing was typed


@dataclass
class ByteTrain:
    """Bytes on a serial line back to back at one rate, each `cycles` cycles of a clock at `hz`:
    the k-th ends at start + cycles_time(k x cycles, hz), counted from the train's start, so that
    no byte's end depends on the rounding of those before it (nor on how often the line was
    advanced meanwhile)."""

    start: Time
    cycles: int
    hz: int
    count: int = 0                                # bytes begun

    def end(self, k: int) -> Time:
        """When the k-th byte ends."""
        return self.start + cycles_time(k * self.cycles, self.hz)


def next_byte(train: ByteTrain | None, start: Time, cycles: int, hz: int) -> ByteTrain:
    """A byte begins at `start`, `cycles` cycles of a clock at `hz` long: the train it belongs to
    (`train`, if it follows that train's last byte at its rate; else a new one), with it counted.
    Its end is the train's end(count)."""
    if train is None or (train.cycles, train.hz) != (cycles, hz) or train.end(train.count) != start:
        train = ByteTrain(start, cycles, hz)
    train.count += 1
    return train


class DwUart(Peripheral):
    """One of UART1-3."""

    REGISTERS = {
        RBR: Register("rbr_thr_dll"), IER: Register("ier_dlh"), IIR: Register("iir_fcr"),
        LCR: Register("lcr"), MCR: Register("mcr"), LSR: Register("lsr", writable=False, reset=LSR_THRE | LSR_TEMT, steady=True),
        MSR: Register("msr", writable=False), SCR: Register("scr"), LPDLL: Register("lpdll"), LPDLH: Register("lpdlh"),
        **{offset: Register(f"srbr_sthr{(offset - SHADOW_FIRST) // 4}")
           for offset in range(SHADOW_FIRST, SHADOW_LAST + 4, 4)},
        FAR: Register("far"), USR: Register("usr", writable=False, reset=USR_TFNF | USR_TFE, steady=True),
        TFL: Register("tfl", writable=False, steady=True), RFL: Register("rfl", writable=False, steady=True),
        SRR: Register("srr", readable=False), SRTS: Register("srts"), SBCR: Register("sbcr"), SDMAM: Register("sdmam"),
        SFE: Register("sfe"), SRT: Register("srt"), STET: Register("stet"), HTX: Register("htx"),
        DMASA: Register("dmasa", readable=False), TCR: Register("tcr"), DE_EN: Register("de_en"),
        RE_EN: Register("re_en"), DET: Register("det"), TAT: Register("tat"), DLF: Register("dlf"),
        RAR: Register("rar"), TAR: Register("tar"), LCR_EXT: Register("lcr_ext"),
        CPR: Register("cpr", writable=False), UCV: Register("ucv", writable=False),
        CTR: Register("ctr", writable=False, reset=PERIPHERAL_ID),
    }

    def __init__(self, index: int, ports: Ports, source_hz: Callable[[], int], on_byte: Callable[[int], None]) -> None:
        """index: 1, 2 or 3. source_hz: the APB0 clock the UART counts its bit times in.
        on_byte: hears each byte as its stop bit leaves the TX pin."""
        self.index = index
        self.NAME = f"UART{index}"
        block = K210_BLOCKS[self.NAME]
        self.GATE, self.BASE, self.SIZE = block.gate, block.base, block.size
        self.source_hz = source_hz
        self.on_byte = on_byte
        self.input: SerialInput | None = None     # what the host sends this UART's RX pin
        super().__init__(ports)
        self._clear()
        self.bytes_sent = 0                       # the run's counts (run.json), kept across resets
        self.bytes_received = 0

    def _clear(self) -> None:
        self._divisor_latch = 0                   # DLH:DLL
        self._fcr = 0                             # FCR is write-only: its fields live here
        self._tx: deque[int] = deque()
        self._rx: deque[int] = deque()
        self._shifting_until: Time | None = None
        self._tx_train: ByteTrain | None = None   # the bytes sent back to back, the one shifting the last
        self._pending_byte = 0
        self._receiving_until: Time | None = None
        self._rx_train: ByteTrain | None = None   # the bytes received back to back, likewise
        self._receiving_byte = 0
        self._thre_pending = False                # the 16550 THR-empty interrupt, until IIR reads it
        self._errors = 0                          # LSR's error bits since it was last read
        self._rx_activity: Time = 0               # when a byte last went into or out of the receive FIFO
        self.last_byte_time: Time = 0
        self.tx_dma: DmaChannel | None = None      # a DMAC channel feeding THR (its handshake)
        self.rx_dma: DmaChannel | None = None      # a DMAC channel taking what is received

    def reset(self, now: Time) -> None:
        """peri_reset or a chip reset: registers and FIFOs as at power-on. A byte coming in is cut
        off, and the host's bridge sends it again (it hands a receiver a byte only when it can take
        one: the SDK's start-up sets UART3 up and its uart_init resets it again, and a test's input
        should not depend on where in that window its first byte fell)."""
        self.advance(now)
        if self._receiving_until is not None and self.input is not None:
            self.input.put_back(self._receiving_byte)
        for channel in (self.tx_dma, self.rx_dma):
            if channel is not None:
                channel.peripheral_gone()
        super().reset(now)
        self._clear()

    # --- DMA handshakes (sysctl dma_sel: UARTn RX/TX requests) --------------------------------------

    def is_data_register(self, address: int) -> bool:
        return address == self.BASE + RBR

    def attach_tx_dma(self, channel: DmaChannel, now: Time) -> None:
        """The channel answers the transmitter's requests: the FIFO is kept full from memory, each
        32-bit item one byte (its low 8 bits, as the SDK's uart_send_data_dma writes them)."""
        self.advance(now)
        self.tx_dma = channel
        self._dma_refill(now)
        self.advance(now)

    def attach_rx_dma(self, channel: DmaChannel, now: Time) -> None:
        """The channel takes each received byte as an item, the FIFO's first."""
        self.advance(now)
        self.rx_dma = channel
        if self._rx:
            received = np.array(self._rx, dtype=np.uint32)
            self._rx.clear()
            channel.accept_from_peripheral(received, now)

    def detach_dma(self, channel: DmaChannel) -> None:
        if self.tx_dma is channel:
            self.tx_dma = None
        if self.rx_dma is channel:
            self.rx_dma = None

    def _dma_refill(self, at: Time) -> None:
        channel = self.tx_dma
        if channel is None or not channel.remaining():
            return
        room = self._depth() - len(self._tx)
        if room <= 0:
            return
        items = channel.read_for_peripheral(min(room, channel.remaining()))
        self._tx.extend(int(item) & 0xFF for item in items)
        self._thre_pending = False
        if not channel.remaining():
            channel.peripheral_done(at)

    # --- the line ----------------------------------------------------------------------------------

    def _fifo_enabled(self) -> bool:
        return bool(self._fcr & FCR_FIFOE)

    def _depth(self) -> int:
        return FIFO_DEPTH if self._fifo_enabled() else 1

    def _bit_clocks(self) -> int:
        """APB0 clocks a bit lasts: 16 x (DLH:DLL + DLF / 16); 0 while the divisor is 0."""
        return 16 * self._divisor_latch + (self.values[DLF] & 0xF)

    def bit_time(self) -> Time | None:
        """How long a bit lasts (rounded up to a picosecond); None while the divisor is 0 (the baud
        clock stopped)."""
        clocks, hz = self._bit_clocks(), self.source_hz()
        if clocks == 0 or hz <= 0:
            return None
        return cycles_time(clocks, hz)

    def _frame(self) -> tuple[int, int] | None:
        """A byte's length on the line as (cycles, hz): start, data, parity and stop bits, counted
        in half cycles of APB0 (cycles of a clock at twice its rate) so that 1.5 stop bits are
        whole. None while the divisor is 0."""
        clocks, hz = self._bit_clocks(), self.source_hz()
        if clocks == 0 or hz <= 0:
            return None
        lcr = self.values[LCR]
        data_bits = 5 + (lcr & 3)
        half_stop_bits = 2 if not lcr & LCR_STOP else (3 if data_bits == 5 else 4)
        half_bits = 2 * (1 + data_bits + (1 if lcr & LCR_PEN else 0)) + half_stop_bits
        return half_bits * clocks, 2 * hz

    def _idle(self) -> bool:
        """Nothing on the wire, nothing to send or to be sent: time changes nothing here (the board
        advances every device often; most UARTs are idle)."""
        return self._shifting_until is None and not self._tx and self._receiving_until is None and \
            self.input is None and not self._rx

    def advance(self, now: Time) -> None:
        if self._idle():
            return
        self._advance_tx(now)
        self._advance_rx(now)

    def _advance_tx(self, now: Time) -> None:
        while True:
            if self._shifting_until is not None:
                if self._shifting_until > now:
                    return
                end = self._shifting_until
                self._shifting_until = None
                self.last_byte_time = end
                self._sent(self._pending_byte, end)
                start = end
            else:
                start = now
            frame = self._frame()
            if not self._tx or frame is None or self.values[HTX] & 1:
                return
            self._pending_byte = self._tx.popleft()
            self._tx_train = next_byte(self._tx_train, start, *frame)
            self._shifting_until = self._tx_train.end(self._tx_train.count)
            self._dma_refill(start)
            if not self._tx:
                self._thre_pending = True         # THR (the FIFO) empty: the 16550's THRE interrupt

    def _sent(self, byte: int, at: Time) -> None:
        if self.values[MCR] & MCR_LOOPBACK:
            self._take(byte, at)
            return
        self.bytes_sent += 1
        self.on_byte(byte)

    def _take(self, byte: int, at: Time) -> None:
        """A byte has come in whole: to the DMA channel taking them, into the receive FIFO, or lost
        (overrun) when it is full."""
        self._rx_activity = at
        if self.rx_dma is not None and self.rx_dma.remaining():
            self.bytes_received += 1
            self.rx_dma.accept_from_peripheral(np.array([byte], dtype=np.uint32), at)
            return
        if len(self._rx) < self._depth():
            self._rx.append(byte)
            self.bytes_received += 1
        else:
            self._errors |= LSR_OE
        self._rx_activity = at

    def _advance_rx(self, now: Time) -> None:
        source = self.input
        while True:
            if self._receiving_until is not None:
                if self._receiving_until > now:
                    return
                start = self._receiving_until
                self._receiving_until = None
                self._take(self._receiving_byte, start)
            else:
                start = now
            if source is None or self.values[MCR] & MCR_LOOPBACK or len(self._rx) >= self._depth():
                return
            frame = self._frame()
            if frame is None or not source.has_byte(start):
                return
            self._receiving_byte = source.pop()
            self._rx_train = next_byte(self._rx_train, start, *frame)
            self._receiving_until = self._rx_train.end(self._rx_train.count)

    def next_event_time(self, now: Time) -> Time | None:
        if self._idle():
            return None
        events = [t for t in (self._shifting_until, self._receiving_until, self._timeout_time()) if t is not None
                  and t > now]
        source = self.input
        if self._receiving_until is None and source is not None and len(self._rx) < self._depth() and \
                not self.values[MCR] & MCR_LOOPBACK and self.bit_time() is not None:
            if source.has_byte(now):
                events.append(now)
            elif source.may_grow:
                events.append(now + INTERACTIVE_POLL)
        return min(events) if events else None

    def _timeout_time(self) -> Time | None:
        """When the character timeout interrupt comes, for bytes waiting in the receive FIFO."""
        if not self._rx or not self._fifo_enabled():
            return None
        frame = self._frame()
        if frame is None:
            return None
        cycles, hz = frame
        return self._rx_activity + cycles_time(TIMEOUT_CHARACTERS * cycles, hz)

    # --- interrupts -------------------------------------------------------------------------------

    def _rx_trigger(self) -> int:
        return RX_TRIGGER[self._fcr >> 6 & 3] if self._fifo_enabled() else 1

    def _tx_threshold_reached(self) -> bool:
        """Programmable THRE mode: the transmit FIFO is at or below its threshold."""
        return len(self._tx) <= TX_THRESHOLD[self._fcr >> 4 & 3]

    def _ptime(self) -> bool:
        return bool(self.values[IER] & IER_PTIME) and self._fifo_enabled()

    def interrupt_id(self, now: Time) -> int:
        """IIR[3:0]: the highest-priority pending interrupt (databook: line status, received data
        or character timeout, THR empty, modem status), or 1: none."""
        ier = self.values[IER]
        if ier & IER_ELSI and self._errors:
            return IID_LINE
        if ier & IER_ERBFI and self._rx:
            if len(self._rx) >= self._rx_trigger():
                return IID_RDA
            timeout = self._timeout_time()
            if timeout is not None and now >= timeout:
                return IID_TIMEOUT
        if ier & IER_ETBEI:
            if self._tx_threshold_reached() if self._ptime() else (self._thre_pending and not self._tx):
                return IID_THRE
        return IID_NONE

    def irq_line(self) -> bool:
        return self.interrupt_id(self.ports.clock.now()) != IID_NONE

    # --- registers ---------------------------------------------------------------------------------

    def _lsr(self) -> int:
        value = self._errors
        if self._rx:
            value |= LSR_DR
        if self._ptime():
            if len(self._tx) >= FIFO_DEPTH:
                value |= LSR_THRE                 # the SDK's putchar waits while this is set
        elif not self._tx:
            value |= LSR_THRE
        if not self._tx and self._shifting_until is None:
            value |= LSR_TEMT
        return value

    def _usr(self) -> int:
        value = USR_BUSY if self._shifting_until is not None or self._receiving_until is not None else 0
        if len(self._tx) < self._depth():
            value |= USR_TFNF
        if not self._tx:
            value |= USR_TFE
        if self._rx:
            value |= USR_RFNE
        if len(self._rx) >= self._depth():
            value |= USR_RFF
        return value

    def _pop(self, now: Time) -> int:
        if not self._rx:
            return 0
        self.took_on_read = True
        byte = self._rx.popleft()
        self._rx_activity = now
        self.advance(now)                         # room in the FIFO: the host's next byte may start
        return byte

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        self.advance(now)
        dlab = self.values[LCR] & LCR_DLAB
        if offset == RBR:
            return self._divisor_latch & 0xFF if dlab else self._pop(now)
        if SHADOW_FIRST <= offset <= SHADOW_LAST:
            return self._pop(now)
        if offset == IER:
            return self._divisor_latch >> 8 if dlab else self.values[IER]
        if offset == IIR:
            iid = self.interrupt_id(now)
            if iid == IID_THRE and not self._ptime():
                self._thre_pending = False        # reading IIR with THRE its source clears it
                self.ports.irq_changed(now)
            return iid | (0xC0 if self._fifo_enabled() else 0)
        if offset == LSR:
            value = self._lsr()
            if self._errors:
                self._errors = 0
                self.took_on_read = True          # the errors: the next read is not the same
                self.ports.irq_changed(now)
            return value
        if offset == USR:
            return self._usr()
        if offset == TFL:
            return len(self._tx)
        if offset == RFL:
            return len(self._rx)
        if offset == SFE:
            return self._fcr & FCR_FIFOE
        if offset == SRT:
            return self._fcr >> 6 & 3
        if offset == STET:
            return self._fcr >> 4 & 3
        if offset == SRTS:
            return self.values[MCR] >> 1 & 1
        if offset == SDMAM:
            return self._fcr >> 3 & 1
        if offset == SBCR:
            return self.values[LCR] >> 6 & 1
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        self.advance(now)
        dlab = self.values[LCR] & LCR_DLAB
        if offset == RBR and dlab:
            self._divisor_latch = (self._divisor_latch & 0xFF00) | (value & 0xFF)
        elif offset == IER and dlab:
            self._divisor_latch = (self._divisor_latch & 0x00FF) | (value & 0xFF) << 8
        elif offset == RBR or SHADOW_FIRST <= offset <= SHADOW_LAST:
            self._transmit(value & 0xFF, now)
        elif offset == IER:
            enabling = value & ~self.values[IER] & IER_ETBEI
            self.values[IER] = value & 0x8F
            if enabling and not self._tx:
                self._thre_pending = True         # 16550: enabling ETBEI with THR empty interrupts at once
        elif offset == IIR:
            self._write_fcr(value)
        elif offset == SRR:
            if value & SRR_UR:
                self.reset(now)
            if value & SRR_RFR:
                self._rx.clear()
            if value & SRR_XFR:
                self._tx.clear()
        elif offset == SFE:
            self._write_fcr((self._fcr & ~FCR_FIFOE) | (value & 1))
        elif offset == SRT:
            self._fcr = (self._fcr & ~0xC0) | (value & 3) << 6
        elif offset == STET:
            self._fcr = (self._fcr & ~0x30) | (value & 3) << 4
        elif offset == SDMAM:
            self._fcr = (self._fcr & ~0x08) | (value & 1) << 3
        elif offset == SRTS:
            self.values[MCR] = (self.values[MCR] & ~2) | (value & 1) << 1
        elif offset == SBCR:
            self.values[LCR] = (self.values[LCR] & ~0x40) | (value & 1) << 6
        else:
            self.values[offset] = value
        self.advance(now)
        self.ports.irq_changed(now)

    def _write_fcr(self, value: int) -> None:
        if (value ^ self._fcr) & FCR_FIFOE:
            self._rx.clear()                      # changing FIFO mode empties both FIFOs
            self._tx.clear()
        if value & FCR_RFIFOR:
            self._rx.clear()
        if value & FCR_XFIFOR:
            self._tx.clear()
        self._fcr = value & 0xF9                  # the reset bits clear themselves

    def _transmit(self, byte: int, now: Time) -> None:
        if len(self._tx) >= self._depth():
            # one counted warning for a firmware that never waits, not one per byte
            self.ports.warn(f"{self.NAME}: a byte written to THR while the transmit FIFO was full was lost: "
                            f"a writer waits while LSR bit 5 is set (with IER bit 7, the SDK's mode) or USR bit 1 "
                            f"(TFNF) is clear", now)
            return
        self._tx.append(byte)
        self._thre_pending = False

    def describe_wait(self) -> str | None:
        if self._tx and self.bit_time() is None:
            return f"{self.NAME}: {len(self._tx)} bytes wait to be sent, but the divisor latch is 0 (no baud clock)"
        return None
