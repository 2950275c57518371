"""SPI0, SPI1 and SPI3: the DesignWare SSI controllers as configured on the K210 (SPI3, the flash's,
is the newer DWC_ssi: its ctrlr0 fields sit elsewhere, Ctrlr0Layout).

Frames written to the data register go through a 32-entry transmit FIFO and
out on the wire at the serial clock the firmware programmed: a frame of `dfs`
bits takes dfs / lanes serial clock periods (lanes: 1 standard, 2 dual, 4 quad,
8 octal), each baudr cycles of the controller's source clock; frames sent back to
back are timed from the first one's start, in whole picoseconds (spi_frames.py). A frame
reaches the selected device when its last bit is out, so the device sees pins such
as the LCD's D/C as they are at that moment. In transmit-and-receive mode the
device's answer goes into the 32-entry receive FIFO; in receive-only mode writing one
dummy frame clocks ctrlr1 + 1 frames in. In EEPROM-read mode (tmod 3) the frames
written (a command and an address) go out with their replies dropped, and once the
transmit FIFO has run empty the controller clocks ctrlr1 + 1 frames in, sending 0xFF:
the SDK's spi_receive_data_standard reads a flash's ID or status this way whenever it
has a command.

DMA: with dmacr.tdmae set and a DMAC channel handshaking to this controller's
TX request, the channel keeps the FIFO full, so a DMA transfer is one unbroken
train of frames on the wire; each word is read from memory when a FIFO slot
frees (at most 32 frames ahead of the wire). Each DMA item (8, 16 or 32 bits) is one
FIFO entry, of which a frame takes the low bits. A channel started before any slave is
selected fills the FIFO and waits; a block that fits in the FIFO is then done, as far as
the DMA goes, before anything is sent (the SDK enables the channel, then writes ser).
With rdmae set, received frames go to memory as they arrive.

Configuration registers can only be written while the controller is disabled
(ssienr = 0); the real controller ignores such writes, and so does the model
(with a warning in the run log).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Protocol

import numpy as np

from ..errors import UnmodelledAccess
from ..memory_map import K210_BLOCKS
from ..vtime import NEVER, Time, cycles_time
from .mmio import Peripheral, Register
from .ports import Ports
from .spi_frames import FrameClock, FrameTrain

if TYPE_CHECKING:
    from .dmac import DmaChannel

CTRLR0, CTRLR1, SSIENR, MWCR, SER, BAUDR = 0x00, 0x04, 0x08, 0x0C, 0x10, 0x14
TXFTLR, RXFTLR, TXFLR, RXFLR, SR, IMR, ISR, RISR = 0x18, 0x1C, 0x20, 0x24, 0x28, 0x2C, 0x30, 0x34
TXOICR, RXOICR, RXUICR, MSTICR, ICR = 0x38, 0x3C, 0x40, 0x44, 0x48
DMACR, DMATDLR, DMARDLR, IDR, VERSION = 0x4C, 0x50, 0x54, 0x58, 0x5C
DR_FIRST, DR_LAST = 0x60, 0xEC
RX_SAMPLE_DELAY, SPI_CTRLR0, XIP_MODE_BITS, ENDIAN = 0xF0, 0xF4, 0xFC, 0x118
# SPI3's (DWC_ssi's) execute-in-place registers (the FreeRTOS SDK's spi_t)
XIP_INCR_INST, XIP_WRAP_INST, XIP_CTRL, XIP_SER, XRXOICR, XIP_CNT_TIME_OUT = 0x100, 0x104, 0x108, 0x10C, 0x110, 0x114

FIFO_DEPTH = 32
TMOD_TX_RX, TMOD_TX, TMOD_RX, TMOD_EEPROM = 0, 1, 2, 3
FORMAT_LANES = {0: 1, 1: 2, 2: 4, 3: 8}
FORMAT_NAMES = {0: "standard", 1: "dual", 2: "quad", 3: "octal"}

SR_BUSY, SR_TFNF, SR_TFE, SR_RFNE, SR_RFF = 1, 2, 4, 8, 16
# interrupt bits (isr/risr/imr)
INT_TXE, INT_TXO, INT_RXU, INT_RXO, INT_RXF = 1, 2, 4, 8, 16
DMACR_RDMAE, DMACR_TDMAE = 1, 2

CONFIG_REGISTERS = {CTRLR0, CTRLR1, BAUDR, SPI_CTRLR0, ENDIAN}
# Registers whose reads have no side effect and whose values only frames on the wire change
STATUS_REGISTERS = {TXFLR, RXFLR, SR, RISR, ISR}


@dataclass(frozen=True)
class Ctrlr0Layout:
    """Where ctrlr0's fields sit. The K210 has two versions of the SSI: SPI0-2 are DW_apb_ssi,
    SPI3 is DWC_ssi, whose ctrlr0 moves every field (the SDK's spi.c: dfs_offset, tmod_offset,
    frf_offset and work_mode_offset per controller)."""

    dfs: int            # data frame size - 1, 5 bits
    frf: int            # frame format (standard, dual, quad, octal), 2 bits
    tmod: int           # transfer mode, 2 bits
    work_mode: int      # SCPH/SCPOL, 2 bits
    reset: int          # ctrlr0's reset value: 8-bit frames


APB_SSI = Ctrlr0Layout(dfs=16, frf=21, tmod=8, work_mode=6, reset=0x0007_0000)
DWC_SSI = Ctrlr0Layout(dfs=0, frf=22, tmod=10, work_mode=8, reset=0x0000_0007)
# spi_ctrlr0's trans_type: which phases go out on the frame format's lanes (the others on one)
TRANS_ALL_STANDARD, TRANS_ADDRESS_WIDE, TRANS_ALL_WIDE = 0, 1, 2


class SpiDevice(Protocol):
    """A device on an SPI bus: what the board wires behind a chip select."""

    def spi_select(self, selected: bool, now: Time) -> None: ...

    def spi_transfer(self, data: np.ndarray, lanes: int, now: Time) -> np.ndarray: ...

    def spi_dummy(self, clocks: int, now: Time) -> None:
        """Clock cycles with no data (the wait cycles of a dual/quad/octal read)."""


class SpiController(Peripheral):
    """One DW SSI controller (index 0 = SPI0, 1 = SPI1)."""

    REGISTERS = {
        CTRLR0: Register("ctrlr0", reset=0x0007_0000), CTRLR1: Register("ctrlr1"),
        SSIENR: Register("ssienr"), MWCR: Register("mwcr"), SER: Register("ser"),
        BAUDR: Register("baudr"), TXFTLR: Register("txftlr"), RXFTLR: Register("rxftlr"),
        TXFLR: Register("txflr", writable=False), RXFLR: Register("rxflr", writable=False),
        SR: Register("sr", writable=False), IMR: Register("imr", reset=0x3F),
        ISR: Register("isr", writable=False), RISR: Register("risr", writable=False),
        TXOICR: Register("txoicr", writable=False), RXOICR: Register("rxoicr", writable=False),
        RXUICR: Register("rxuicr", writable=False), MSTICR: Register("msticr", writable=False),
        ICR: Register("icr", writable=False), DMACR: Register("dmacr"),
        DMATDLR: Register("dmatdlr"), DMARDLR: Register("dmardlr"),
        IDR: Register("idr", writable=False, reset=0xFFFF_FFFF),
        VERSION: Register("ssic_version_id", writable=False, reset=0x3430_312A),
        **{off: Register(f"dr{(off - DR_FIRST) // 4}") for off in range(DR_FIRST, DR_LAST + 4, 4)},
        RX_SAMPLE_DELAY: Register("rx_sample_delay"), SPI_CTRLR0: Register("spi_ctrlr0"),
        XIP_MODE_BITS: Register("xip_mode_bits"), ENDIAN: Register("endian"),
    }

    def __init__(self, index: int, ports: Ports, source_hz: Callable[[], int],
                 layout: Ctrlr0Layout = APB_SSI) -> None:
        """source_hz: the clock SYSCTL gives the controller, in whole hertz (its baud rate is that / baudr).
        layout: APB_SSI for SPI0/1, DWC_SSI for SPI3 (which also has the XIP registers)."""
        self.index = index
        self.source_hz = source_hz
        self.NAME = f"SPI{index}"
        block = K210_BLOCKS[self.NAME]
        self.GATE, self.BASE, self.SIZE = block.gate, block.base, block.size
        self.layout = layout
        self._dfs_shift, self._frf_shift, self._tmod_shift = layout.dfs, layout.frf, layout.tmod
        self.REGISTERS = {**SpiController.REGISTERS, CTRLR0: Register("ctrlr0", reset=layout.reset)}
        if layout is DWC_SSI:
            self.REGISTERS.update({
                XIP_INCR_INST: Register("xip_incr_inst"), XIP_WRAP_INST: Register("xip_wrap_inst"),
                XIP_CTRL: Register("xip_ctrl"), XIP_SER: Register("xip_ser"),
                XRXOICR: Register("xrxoicr", writable=False), XIP_CNT_TIME_OUT: Register("xip_cnt_time_out")})
        super().__init__(ports)
        self.device_for_ss = lambda ss: None   # set by the board's wiring
        self._train: FrameTrain | None = None
        # while received frames are handed to the device: their train, the first one's index, bytes a frame
        self._delivering: tuple[FrameTrain, int, int] | None = None
        self._held: list[int] = []               # frames written while no slave is selected
        self._rx: list[int] = []
        self._raw_int = 0
        self._selected: SpiDevice | None = None
        self._ss_low = False                    # the slave select as the pins show it (--vcd)
        self.tx_dma: "DmaChannel | None" = None
        self.rx_dma: "DmaChannel | None" = None
        self._dma_started: Time = 0
        # EEPROM-read mode: frames at the train's end that clock the reply in (not transmit data);
        # the frames before them are the command, whose replies are dropped
        self._eeprom_fill = 0
        # a dual/quad/octal transfer whose instruction and address are phases of their own
        # (_push_phased): the FIFO entries taken so far as its instruction and address, and
        # whether they have gone out (the transfer is open: what follows is data)
        self._phase_entries: list[int] = []
        self._phases_sent = False
        self._phased_since_select = False     # the selected device has seen a phased transfer

    def reset(self, now: Time) -> None:
        """peri_reset: FIFOs, transfers and registers back to reset; devices deselected."""
        if self._selected is not None:
            self._selected.spi_select(False, now)
            self._selected = None
        for channel in (self.tx_dma, self.rx_dma):
            if channel is not None:
                channel.peripheral_gone()
        self._end_train(now)
        super().reset(now)
        if self._ss_low:
            self._ss_low = False
            self.ports.signal(now, f"spi{self.index}_ss_n", 1)
        self._held.clear()
        self._rx.clear()
        self._raw_int = 0
        self._eeprom_fill = 0
        self._phase_entries.clear()
        self.tx_dma = self.rx_dma = None

    # --- configuration decoded -----------------------------------------------------------

    # (bit fields spelled out: these are read on every register access)
    @property
    def frame_bits(self) -> int:
        return ((self.values[CTRLR0] >> self._dfs_shift) & 0x1F) + 1

    @property
    def tmod(self) -> int:
        """The transfer mode. In a dual, quad or octal format EEPROM-read mode acts as receive-only:
        the instruction and address go out as phases and ctrlr1 + 1 frames come in. The SDK's
        spi_receive_data_multiple[_dma] reads the Dock's flash this way (tmod 3, quad); the
        FreeRTOS SDK's spi.cpp reads the same flash with tmod 2."""
        ctrlr0 = self.values[CTRLR0]
        mode = (ctrlr0 >> self._tmod_shift) & 3
        if mode == TMOD_EEPROM and (ctrlr0 >> self._frf_shift) & 3:
            return TMOD_RX
        return mode

    @property
    def frame_format(self) -> int:
        return (self.values[CTRLR0] >> self._frf_shift) & 3

    @property
    def enabled(self) -> bool:
        return bool(self.values[SSIENR] & 1)

    def _divider(self) -> int:
        """SCKDV: source clock cycles per serial clock cycle (0: no serial clock)."""
        return self.values[BAUDR] & 0xFFFE   # SCKDV is even; bit 0 reads as written but is ignored

    def sclk_hz(self) -> int:
        """The serial clock in whole hertz, rounded down (0: none), for checks and messages: the
        wire's times come from the source clock and the divider exactly (frame_clock, _sclk_time)."""
        divider = self._divider()
        if divider == 0:
            return 0
        return self.source_hz() // divider

    def frame_clock(self) -> FrameClock | None:
        """How long a frame takes in the frame format now (None: no serial clock, nothing moves)."""
        divider, source = self._divider(), self.source_hz()
        if divider == 0 or source == 0:
            return None
        return FrameClock(self.frame_bits * divider, FORMAT_LANES[self.frame_format] * source)

    def frame_period(self) -> Time:
        """One frame's time on the wire, rounded up to a whole picosecond (NEVER: no serial clock).
        For reports: a train times its frames from its start (FrameTrain.edge), not by adding this."""
        clock = self.frame_clock()
        if clock is None:
            return NEVER
        return cycles_time(clock.ticks, clock.hz)

    def _sclk_time(self, clocks: int) -> Time:
        """How long `clocks` serial clock cycles take (a clock is running: frame_clock is not None)."""
        return cycles_time(clocks * self._divider(), self.source_hz())

    def _phases(self) -> tuple[int, int, int, int, int]:
        """spi_ctrlr0 decoded: (instruction bits, its lanes, address bits, its lanes, wait cycles)."""
        spi_ctrlr0 = self.values[SPI_CTRLR0]
        trans_type = spi_ctrlr0 & 3
        lanes = FORMAT_LANES[self.frame_format]
        inst_bits = (0, 4, 8, 16)[(spi_ctrlr0 >> 8) & 3]
        addr_bits = ((spi_ctrlr0 >> 2) & 0xF) * 4
        inst_lanes = lanes if trans_type == TRANS_ALL_WIDE else 1
        addr_lanes = 1 if trans_type == TRANS_ALL_STANDARD else lanes
        return inst_bits, inst_lanes, addr_bits, addr_lanes, (spi_ctrlr0 >> 11) & 0x1F

    def _phased(self) -> bool:
        """Whether a dual/quad/octal transfer sends its instruction and address as phases of their
        own (_push_phased): always when receiving; when transmitting, unless each phase is absent or
        exactly a frame on the format's lanes, in which case it goes out as one (wait cycles only
        come before received data)."""
        if self.tmod == TMOD_RX:
            return True
        inst_bits, inst_lanes, addr_bits, addr_lanes, _ = self._phases()
        bits, lanes = self.frame_bits, FORMAT_LANES[self.frame_format]
        return not all(n == 0 or (n == bits and on == lanes) for n, on in ((inst_bits, inst_lanes),
                                                                           (addr_bits, addr_lanes)))

    def _check_wire_format(self) -> None:
        """The model passes whole bytes to devices; say so clearly for anything else."""
        bits = self.frame_bits
        if bits % 8:
            raise UnmodelledAccess(f"{self.NAME}: {bits}-bit frames (only whole bytes reach devices in the model)")
        if self.values[ENDIAN]:
            raise UnmodelledAccess(f"{self.NAME}.endian = 0x{self.values[ENDIAN]:x}: byte-order conversion is not modelled")
        if self.frame_format and self.tmod == TMOD_RX and self.layout is APB_SSI:
            # the devices on SPI0 and SPI1 (the LCD, the SD card) neither answer nor take wait cycles
            raise UnmodelledAccess(f"{self.NAME}: receiving in {FORMAT_NAMES[self.frame_format]} format is not "
                                   f"modelled (SPI3 receives so)")
        if self.frame_format and self.tmod == TMOD_TX_RX:
            raise UnmodelledAccess(f"{self.NAME}: transmit-and-receive mode in {FORMAT_NAMES[self.frame_format]} "
                                   f"format (the SSI transmits or receives there, not both)")
        if self.frame_format:
            trans_type = self.values[SPI_CTRLR0] & 3
            inst_bits, _, addr_bits, _, _ = self._phases()
            if trans_type == 3 or inst_bits % 8 or addr_bits % 8:
                raise UnmodelledAccess(
                    f"{self.NAME}: {FORMAT_NAMES[self.frame_format]} format with a {inst_bits}-bit instruction, "
                    f"a {addr_bits}-bit address and transfer type {trans_type}: the model passes instruction "
                    f"and address phases of whole bytes, transfer types 0-2")

    # --- chip select and device wiring -------------------------------------------------------

    def _slave(self) -> SpiDevice | None:
        ser = self.values[SER]
        for ss in range(4):
            if ser >> ss & 1:
                device = self.device_for_ss(ss)
                if device is not None:
                    return device
        return None

    def _end_train(self, at: Time) -> None:
        if self._train is not None:
            self.ports.signal(min(at, self._train.end()), f"spi{self.index}_sclk", 0)
        self._train = None
        self._eeprom_fill = 0
        self._phases_sent = False

    def _update_selection(self, now: Time) -> None:
        low = bool(self.enabled and self.values[SER])
        if low != self._ss_low:
            self._ss_low = low
            self.ports.signal(now, f"spi{self.index}_ss_n", 0 if low else 1)
        device = self._slave() if self.enabled and self.values[SER] else None
        if device is not self._selected:
            self._phased_since_select = False
            if self._selected is not None:
                self._selected.spi_select(False, now)
            self._selected = device
            if device is not None:
                device.spi_select(True, now)

    def byte_clocked_at(self, i: int, now: Time) -> Time:
        """While frames are handed to the selected device (its spi_transfer): when byte i of them had
        been clocked (its frame's last edge), which can be before `now`, the moment they are handed
        over; `now` outside a hand-over. A device whose answer depends on time (the SD card's read
        access time) reckons it from this."""
        if self._delivering is None:
            return now
        train, first, nbytes = self._delivering
        frame, byte = first + i // nbytes, i % nbytes
        if byte == nbytes - 1:
            return train.edge(frame + 1)
        start = train.edge(frame)     # a frame of several bytes sends its first byte first (its top bits)
        return start + (train.edge(frame + 1) - start) * (byte + 1) // nbytes

    def is_data_register(self, address: int) -> bool:
        return self.BASE + DR_FIRST <= address <= self.BASE + DR_LAST

    def wiring_changed(self, now: Time) -> None:
        self.advance(now)
        self._update_selection(now)

    # --- time -------------------------------------------------------------------------

    def advance(self, now: Time) -> None:
        """Moves frames along the wire up to `now`: DMA refills, deliveries, received frames.
        (Called on every register access and every scheduler turn: the idle cases return early.)"""
        if self.tx_dma is not None:
            self._dma_refill(now)
        train = self._train
        if train is None:
            return
        done = train.finished(now)
        if done > train.delivered:
            self._deliver(train.take(done - train.delivered), now)
        if train.delivered == train.count and now >= train.end():
            self._end_train(now)
            if self._phase_entries and self.frame_format and self.tmod == TMOD_RX and self.values[SER]:
                # instruction and address written during the receive that ended begin the next
                # (unless the source clock has stopped meanwhile: then they wait in the FIFO)
                clock = self.frame_clock()
                if clock is not None:
                    self._start_phased(clock, train.end())
                if self._train is not None:
                    self.advance(now)

    def _deliver(self, frames: np.ndarray, now: Time) -> None:
        nbytes = self.frame_bits // 8
        if nbytes == 1:
            data = frames.astype(np.uint8)     # an 8-bit frame is its low byte
        else:
            data = frames.astype(">u4").view(np.uint8).reshape(-1, 4)[:, 4 - nbytes:].reshape(-1)
        device = self._selected
        if device is not None:
            train = self._train
            self._delivering = (train, train.delivered - len(frames), nbytes) if train is not None else None
            try:
                reply = device.spi_transfer(data, FORMAT_LANES[self.frame_format], now)
            finally:
                self._delivering = None
        else:
            reply = np.full(len(data), 0xFF, dtype=np.uint8)  # MISO pulled up: nothing answers
        train = self._train
        if self.tmod == TMOD_EEPROM and train is not None:
            # these frames are train.delivered - len(frames) onwards; the command ends at count - fill
            dropped = min(len(frames), max(0, train.count - self._eeprom_fill - (train.delivered - len(frames))))
            reply = reply[dropped * nbytes:]
            if not len(reply):
                return
        if self.tmod in (TMOD_TX_RX, TMOD_RX, TMOD_EEPROM):
            if nbytes == 1:
                self._receive(reply.astype(np.uint32), now)
                return
            words = reply.reshape(-1, nbytes)
            values = np.zeros(len(words), dtype=np.uint32)
            for i in range(nbytes):
                values = (values << 8) | words[:, i]
            self._receive(values, now)

    def _receive(self, values: np.ndarray, now: Time) -> None:
        if self.rx_dma is not None and self.values[DMACR] & DMACR_RDMAE:
            self.rx_dma.accept_from_peripheral(values, now)
            return
        room = FIFO_DEPTH - len(self._rx)
        self._rx.extend(values[:room].tolist())
        if len(values) > room:
            self._raw_int |= INT_RXO
            # no frame count in the text: repeated overflows are counted as one warning
            self.ports.warn(f"{self.NAME}: receive FIFO overflow: received frames lost "
                            f"(the {FIFO_DEPTH}-frame FIFO was full)", now)

    def _push(self, values: np.ndarray, now: Time) -> None:
        """Queues frames for the wire as written at `now` (by the CPU or the DMA)."""
        if not self.enabled:
            return
        clock = self.frame_clock() if self.values[SER] else None
        if clock is None:
            self._held.extend(int(v) for v in values)
            return
        if self.frame_format and self._phased():
            self._push_phased(values, clock, now)
            return
        train = self._train
        if train is None or train.end() < now:
            if train is not None:
                self.advance(now)
            self._check_wire_format()
            train = self._train = FrameTrain(start=now, clock=clock, bits=self.frame_bits)
            self.ports.signal(now, f"spi{self.index}_sclk", 1)
        train.frames.append(values.astype(np.uint32))
        train.count += len(values)

    def _push_phased(self, values: np.ndarray, clock: FrameClock, now: Time) -> None:
        """A dual/quad/octal transfer with instruction and address phases (_phased). Its first FIFO
        entries are the instruction (when spi_ctrlr0's inst_l is not 0) and the address (when addr_l
        is not 0); once they are in, both go out (each on one lane or on the format's, as trans_type
        says), then: receiving, wait_cycles clocks with no data and ctrlr1 + 1 frames clocked in;
        transmitting, the entries after them as frames, for as long as the FIFO does not run empty.
        Entries written during a receive wait in the FIFO and begin the next transfer."""
        train = self._train
        if self._phases_sent and train is not None:
            if self.tmod == TMOD_RX:
                self._phase_entries.extend(int(v) for v in values)
            else:
                train.frames.append(values.astype(np.uint32))
                train.count += len(values)
            return
        self._phase_entries.extend(int(v) for v in values)
        self._start_phased(clock, now)

    def _start_phased(self, clock: FrameClock, now: Time) -> None:
        """Sends the phases of a transfer once its entries are in, and puts its frames on the wire."""
        inst_bits, inst_lanes, addr_bits, addr_lanes, wait = self._phases()
        phases = [(bits, lanes) for bits, lanes in ((inst_bits, inst_lanes), (addr_bits, addr_lanes)) if bits]
        receiving = self.tmod == TMOD_RX
        entries = self._phase_entries
        # receive-only with neither phase: a write starts the transfer, as in the standard format
        if len(entries) < max(len(phases), 1 if receiving else 0):
            return
        self._check_wire_format()
        device = self._selected
        if device is not None and self._phased_since_select:
            # a transfer after one that ended: the controller raised its slave select between them
            device.spi_select(False, now)
            device.spi_select(True, now)
        self._phased_since_select = True
        clocks = 0
        for (bits, lanes), value in zip(phases, entries):
            if device is not None:
                device.spi_transfer(np.frombuffer((value & ((1 << bits) - 1)).to_bytes(bits // 8, "big"),
                                                  dtype=np.uint8), lanes, now)
            clocks += bits // lanes
        if receiving and wait:
            if device is not None:
                device.spi_dummy(wait, now)
            clocks += wait
        train = self._train = FrameTrain(start=now + self._sclk_time(clocks), clock=clock, bits=self.frame_bits)
        self.ports.signal(now, f"spi{self.index}_sclk", 1)
        self._phases_sent = True
        rest = entries[max(len(phases), 1 if receiving else 0):]
        if receiving:
            count = (self.values[CTRLR1] & 0xFFFF) + 1
            train.frames.append(np.full(count, (1 << self.frame_bits) - 1, dtype=np.uint32))
            train.count = count
            self._phase_entries = rest
        else:
            self._phase_entries = []
            if rest:
                train.frames.append(np.array(rest, dtype=np.uint32))
                train.count = len(rest)

    def tx_level(self, now: Time) -> int:
        """txflr: frames in the FIFO that have not started shifting out."""
        held = len(self._held) + len(self._phase_entries)
        if self.tmod == TMOD_RX and self.frame_format:
            return min(FIFO_DEPTH, held)      # phase entries waiting for the next transfer
        if self.tmod == TMOD_RX:
            # receive-only: the frames on the wire are clocks, not transmit data; the dummy
            # word that starts them leaves the FIFO at once (it waits there only while no
            # slave is selected)
            return 1 if held else 0
        train = self._train
        if train is None:
            return min(held, FIFO_DEPTH)
        # (EEPROM-read mode: the frames clocking the reply in are not in the FIFO)
        return min(FIFO_DEPTH, max(0, train.count - self._eeprom_fill - train.started(now)) + held)

    def busy(self, now: Time) -> bool:
        train = self._train
        return train is not None and now < train.end()

    def next_event_time(self, now: Time) -> Time | None:
        """The next moment software can see a change: the TX DMA block completing, a slot
        freeing in a full FIFO, a received frame changing the receive FIFO's status, the
        wire going idle."""
        train = self._train
        if train is None:
            return None
        dma_left = self.tx_dma.remaining() if self.tx_dma is not None else 0
        # under DMA the train runs on until the block's last frame is out
        times = [train.edge(train.count + dma_left)]
        if self.tx_dma is None and self.tmod != TMOD_RX and train.count - train.started(now) >= FIFO_DEPTH:
            # a CPU waiting for room in a full FIFO can go on when the next frame starts
            # (under DMA the slots are the DMA's business and nobody waits on them)
            times.append(train.edge(train.count - FIFO_DEPTH))
        if self.tx_dma is not None and self.tx_dma.remaining():
            times.append(self._dma_push_time(train.count + self.tx_dma.remaining() - 1))
        if self.tmod in (TMOD_TX_RX, TMOD_RX, TMOD_EEPROM) and not (
                self.rx_dma is not None and self.values[DMACR] & DMACR_RDMAE):
            # a CPU reading the receive FIFO sees it change when frames arrive: the first one
            # into an empty FIFO (RFNE), the one that lifts the level above rxftlr (RXF), the
            # one that fills it (RFF) and the one that overflows it (RXO)
            done = train.finished(now)
            level = len(self._rx)
            threshold = self.values[RXFTLR] & 0x1F
            wanted = [FIFO_DEPTH - level if level < FIFO_DEPTH else 1]
            if level == 0:
                wanted.append(1)
            if level <= threshold:
                wanted.append(threshold + 1 - level)
            arrival = done + min(wanted)
            if arrival <= train.count:
                times.append(train.edge(arrival))
        later = [t for t in times if t > now]
        return min(later) if later else None

    def earliest_delivery(self, frames: int, now: Time) -> Time:
        """The earliest time by which `frames` more frames than delivered so far can have reached the
        selected device (a frame early, for safety); NEVER when the frames on the wire and those the
        TX DMA still has to give are fewer (the train's end is a device event, next_event_time).
        Without a train: now, unless nothing could start one but a register access."""
        train = self._train
        if train is None:
            return now if self.tx_dma is not None and self.tx_dma.remaining() else NEVER
        index = train.delivered + frames
        available = train.count + (self.tx_dma.remaining() if self.tx_dma is not None else 0)
        if index > available:
            return NEVER
        return train.edge(index - 1)

    def stable_until(self, offset: int, now: Time) -> Time:
        """Not declared `steady` (mmio.Register): the FIFO levels change at every frame edge, of which
        only some are device events (next_event_time), so the controller works the bound out.
        The status registers (sr, txflr, rxflr, risr, isr: reading them changes nothing) stay
        as they are until the next frame starts or ends on the wire, which is also when advance()
        next has something to do; sr until the next frame edge that changes one of its bits
        (_next_sr_change). Without a DMA transmit channel only (it refills the FIFO as time
        goes). The bound is that edge itself: the frame counts are exact, and at one picosecond
        before the edge the frame before it has not yet arrived."""
        if offset not in STATUS_REGISTERS or self.tx_dma is not None or self.tmod == TMOD_EEPROM:
            return now
        train = self._train
        if train is None:
            return NEVER                # nothing on the wire: only an access changes anything
        if now < train.start:
            return now
        frames = train.edges_passed(now)
        if frames >= train.count:
            return now                  # the train is over but not yet ended
        edge = self._next_sr_change(train, frames) if offset == SR else frames + 1
        return train.edge(edge)

    def _next_sr_change(self, train: FrameTrain, frames: int) -> int:
        """The first frame edge after edge `frames` at which sr can read otherwise (edge i: frame i
        starts, frame i - 1 has arrived; the FIFOs as they are at edge `frames`): the wire going idle,
        the last frame leaving the transmit FIFO (TFE), a slot freeing in a full one (TFNF), a
        frame reaching an empty receive FIFO (RFNE), the receive FIFO filling (RFF). A CPU that
        sent a burst and waits for the wire to be idle is answered once a burst, not once a frame."""
        if self._held:
            return frames + 1
        edges = [train.count]
        if self.tmod != TMOD_RX:
            edges += [train.count - 1, train.count - FIFO_DEPTH]
        if self.tmod in (TMOD_TX_RX, TMOD_RX) and not (self.rx_dma is not None and self.values[DMACR] & DMACR_RDMAE):
            level = len(self._rx)
            edges += [frames + FIFO_DEPTH - level] + ([frames + 1] if level == 0 else [])
        return min(edge for edge in edges if edge > frames)

    # --- DMA handshakes -------------------------------------------------------------------

    def attach_tx_dma(self, channel: "DmaChannel", now: Time) -> None:
        self.advance(now)
        self.tx_dma = channel
        item_bits = 8 * channel.transfer.dst_width
        if item_bits < self.frame_bits:
            # each item is one FIFO entry; the DW SSI takes a frame's bits from the entry's low bits
            self.ports.warn(f"DMAC channel {channel.index} writes {item_bits}-bit items into {self.NAME}'s "
                            f"{self.frame_bits}-bit frames: AXI leaves the byte lanes a narrow write does not "
                            f"use undefined; the model sends their bits as 0", now)
        self._dma_started = now
        self._dma_refill(now)

    def attach_rx_dma(self, channel: "DmaChannel", now: Time) -> None:
        self.advance(now)
        self.rx_dma = channel
        if self._rx and self.values[DMACR] & DMACR_RDMAE:
            values = np.array(self._rx, dtype=np.uint32)
            self._rx.clear()
            channel.accept_from_peripheral(values, now)

    def detach_dma(self, channel: "DmaChannel") -> None:
        if self.tx_dma is channel:
            self.tx_dma = None
        if self.rx_dma is channel:
            self.rx_dma = None

    def _dma_push_time(self, index: int) -> Time:
        """When train frame `index` enters the FIFO under DMA: as soon as frame index - 32
        has started shifting and freed a slot (never before the channel was enabled)."""
        return max(self._dma_started, self._train.edge(index - FIFO_DEPTH))

    def _dma_refill(self, now: Time) -> None:
        """The TX DMA keeps the FIFO full: push every word whose slot has freed by `now`."""
        channel = self.tx_dma
        if channel is None or not channel.remaining():
            return
        if not (self.values[DMACR] & DMACR_TDMAE) or not self.enabled:
            return   # no request reaches the DMAC: the channel waits (a hang report says why)
        if self._phases_sent and self.tmod == TMOD_RX:
            return   # entries for the transfer after this receive: written when it ends (none of the SDKs do)
        if self._train is None:
            room = FIFO_DEPTH - len(self._held) - len(self._phase_entries)
            if room <= 0:
                return
            self._push(channel.read_for_peripheral(min(room, channel.remaining())), now)
            if self._train is None:
                # nothing on the wire yet (no slave selected): the FIFO holds what the DMA
                # wrote, and a block that fitted in it is done now, as far as the DMA goes
                if not channel.remaining():
                    channel.peripheral_done(now)
                return
            if not channel.remaining():
                channel.peripheral_done(now)
                return
        train = self._train
        # frames started by now if the train had never run dry (the DMA keeps it going)
        started = train.edges_passed(now) + 1 if now >= train.start else 0
        n = min(channel.remaining(), started + FIFO_DEPTH - train.count)
        if n > 0:
            last_index = train.count + n - 1
            train.frames.append(channel.read_for_peripheral(n).astype(np.uint32))
            train.count += n
            if not channel.remaining():
                channel.peripheral_done(self._dma_push_time(last_index))

    # --- registers --------------------------------------------------------------------------

    def irq_line(self) -> bool:
        if not self.values[IMR]:
            return False        # every source masked (the PLIC samples this on every wake check)
        return bool(self._interrupts(self.ports.clock.now()) & self.values[IMR])

    def _interrupts(self, now: Time) -> int:
        raw = self._raw_int
        if self.tx_level(now) <= (self.values[TXFTLR] & 0x1F):
            raw |= INT_TXE
        if len(self._rx) > (self.values[RXFTLR] & 0x1F):
            raw |= INT_RXF
        return raw

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        self.advance(now)
        if DR_FIRST <= offset <= DR_LAST:
            if not self._rx:
                self._raw_int |= INT_RXU
                return 0
            self.took_on_read = True
            return self._rx.pop(0)
        if offset == TXFLR:
            return self.tx_level(now)
        if offset == RXFLR:
            return len(self._rx)
        if offset == SR:
            level = self.tx_level(now)
            value = 0
            if self.busy(now):
                value |= SR_BUSY
            if level < FIFO_DEPTH:
                value |= SR_TFNF
            if level == 0:
                value |= SR_TFE
            if self._rx:
                value |= SR_RFNE
            if len(self._rx) >= FIFO_DEPTH:
                value |= SR_RFF
            return value
        if offset == RISR:
            return self._interrupts(now)
        if offset == ISR:
            return self._interrupts(now) & self.values[IMR]
        if offset in (TXOICR, RXOICR, RXUICR, MSTICR, ICR):
            bits = {TXOICR: INT_TXO, RXOICR: INT_RXO, RXUICR: INT_RXU, MSTICR: 0,
                    ICR: INT_TXO | INT_RXO | INT_RXU}[offset]
            self._raw_int &= ~bits
            return 0
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        self.advance(now)
        if DR_FIRST <= offset <= DR_LAST:
            self._write_data(value, now)
            return
        if offset in CONFIG_REGISTERS and self.enabled:
            self.ports.warn(f"{self.NAME}.{reg.name} written while the controller is enabled: ignored, "
                            f"as the DW SSI ignores it")
            return
        if offset == SSIENR:
            was = self.enabled
            self.values[SSIENR] = value & 1
            if was and not self.enabled:
                # disabling halts any transfer and clears both FIFOs
                self._end_train(now)
                self._held.clear()
                self._phase_entries.clear()
                self._rx.clear()
                self._raw_int = 0
            self._update_selection(now)
            return
        self.values[offset] = value
        if offset == SER:
            self._update_selection(now)
            if value and self._held:
                held = np.array(self._held, dtype=np.uint32)
                self._held.clear()
                if self.tmod == TMOD_EEPROM:
                    self._push_eeprom(held, now)
                else:
                    self._push(held, now)
        if offset == DMACR:
            self._dma_refill(now)

    def _write_data(self, value: int, now: Time) -> None:
        if not self.enabled:
            return
        if self.tx_level(now) >= FIFO_DEPTH:
            self._raw_int |= INT_TXO
            # no value in the text: repeated losses are counted as one warning
            self.ports.warn(f"{self.NAME}: a frame written to a full transmit FIFO was lost", now)
            return
        if self.tmod == TMOD_RX and not self.frame_format:
            # receive-only: one write starts clocking ctrlr1 + 1 frames in (sending 0xFF filler,
            # the idle level of the data-out line)
            self._check_wire_format()
            count = (self.values[CTRLR1] & 0xFFFF) + 1
            filler = (1 << self.frame_bits) - 1
            self._push(np.full(count, filler, dtype=np.uint32), now)
            return
        if self.frame_format and self._phased():
            # instruction and address entries are wider than a frame may be: kept whole
            self._push(np.array([value & 0xFFFF_FFFF], dtype=np.uint32), now)
            return
        frame = np.array([value & ((1 << self.frame_bits) - 1)], dtype=np.uint32)
        if self.tmod == TMOD_EEPROM:
            self._push_eeprom(frame, now)
            return
        self._push(frame, now)

    def _push_eeprom(self, frames: np.ndarray, now: Time) -> None:
        """EEPROM-read mode: the command frames go out, and behind them, once the transmit FIFO runs
        empty, ctrlr1 + 1 frames clock the reply in. A frame written before the filler has started
        joins the command (the FIFO had not run empty yet); the filler moves behind it."""
        self._check_wire_format()
        train = self._train
        if train is not None and self._eeprom_fill and now < train.end():
            if train.started(now) > train.count - self._eeprom_fill:
                raise UnmodelledAccess(f"{self.NAME}: a frame written in EEPROM-read mode while the reply is "
                                       f"being clocked in (what the controller does with it is not modelled)")
            train.frames.pop()                           # the filler, always its own chunk
            train.count -= self._eeprom_fill
            self._eeprom_fill = 0
        self._push(frames, now)
        if self._train is None:
            return                                       # held until a slave is selected (write_register)
        if not self._eeprom_fill:
            count = (self.values[CTRLR1] & 0xFFFF) + 1
            self._push(np.full(count, (1 << self.frame_bits) - 1, dtype=np.uint32), now)
            self._eeprom_fill = count
