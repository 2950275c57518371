"""DMAC (0x5000_0000): the DesignWare AXI DMA controller, six channels, 64-bit registers.

Modelled: single-block transfers memory-to-memory, memory-to-peripheral and
peripheral-to-memory, with the peripheral side handshaking through the request
SYSCTL dma_sel routes to the channel's handshake interface (dst_per / src_per).
A channel's chen bit drops when its block is done; the channel's intstatus
then has BLOCK_TFR_DONE (bit 0) and DMA_TFR_DONE (bit 1) set as far as
intstatus_en allows, and its interrupt line (PLIC source 27 + n) is high while
intstatus & intsignal_en is non-zero and cfg.int_en is set.
Linked-list and multi-block transfers are not modelled and stop the run.
Registers are 64 bits wide; the SDK accesses them with ld/sd. The DMAC's register port is a
32-bit AHB slave (the SDK's platform.h), so a 32-bit access reaches one half of a register and a
narrower one the bytes it addresses: the bus models those with a warning (bus.py).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np

from ..errors import HardwareMisuse, UnmodelledAccess
from ..memory_map import K210_BLOCKS
from ..vtime import Time, cycles_time
from .mmio import BUS_AHB, Peripheral, Register, field
from .ports import DmaMemory, Ports

CHANNELS = 6
ID, COMPVER, CFG, CHEN, INTSTATUS, COM_INTCLEAR = 0x00, 0x08, 0x10, 0x18, 0x30, 0x38
COM_INTSTATUS_EN, COM_INTSIGNAL_EN, COM_INTSTATUS, RESET = 0x40, 0x48, 0x50, 0x58
CH_BASE, CH_STRIDE = 0x100, 0x100
SAR, DAR, BLOCK_TS, CTL, CH_CFG, LLP, STATUS = 0x00, 0x08, 0x10, 0x18, 0x20, 0x28, 0x30
SWHSSRC, SWHSDST, BLK_TFR_RESUMEREQ, AXI_ID, AXI_QOS = 0x38, 0x40, 0x48, 0x50, 0x58
INTSTATUS_EN, CH_INTSTATUS, INTSIGNAL_EN, INTCLEAR = 0x80, 0x88, 0x90, 0x98

CFG_ENABLE, CFG_INT_EN = 1, 2
TT_MEM2MEM, TT_MEM2PER, TT_PER2MEM = 0, 1, 2
INT_BLOCK_TFR_DONE, INT_DMA_TFR_DONE = 1, 2
WIDTH_BYTES = {0: 1, 1: 2, 2: 4, 3: 8}
# memory-to-memory copies move one 64-bit AXI beat per bus clock (ACLK = CPU clock)
MEM2MEM_BYTES_PER_CYCLE = 8
# a channel's set-up registers: they take effect when the channel starts
# A channel's intsignal_en lets every interrupt through at reset: the Kendryte SDK's dmac.c never
# writes it, and its dmac_irq_register relies on the channel's interrupt (intstatus_en chooses)
INTSIGNAL_RESET = 0xFFFF_FFFF
_SETUP_REGISTERS = frozenset({SAR, DAR, BLOCK_TS, CTL, CH_CFG, LLP})
# each channel's (intstatus, intsignal_en) offsets: its interrupt line is high when they share a bit
_IRQ_REGISTERS = [(CH_BASE + CH_STRIDE * n + CH_INTSTATUS, CH_BASE + CH_STRIDE * n + INTSIGNAL_EN)
                  for n in range(CHANNELS)]


def _channel_registers() -> dict[int, Register]:
    names = {SAR: "sar", DAR: "dar", BLOCK_TS: "block_ts", CTL: "ctl", CH_CFG: "cfg", LLP: "llp",
             STATUS: "status", SWHSSRC: "swhssrc", SWHSDST: "swhsdst", BLK_TFR_RESUMEREQ: "blk_tfr_resumereq",
             AXI_ID: "axi_id", AXI_QOS: "axi_qos", INTSTATUS_EN: "intstatus_en", CH_INTSTATUS: "intstatus",
             INTSIGNAL_EN: "intsignal_en", INTCLEAR: "intclear"}
    table = {}
    for n in range(CHANNELS):
        for off, name in names.items():
            table[CH_BASE + CH_STRIDE * n + off] = Register(
                f"ch{n}_{name}", width=8,
                writable=off not in (STATUS, CH_INTSTATUS),
                readable=off != INTCLEAR,
                reset=INTSIGNAL_RESET if off == INTSIGNAL_EN else 0,
            )
    return table


@dataclass
class Transfer:
    """A channel's block in flight."""

    kind: int
    items: int
    src_width: int
    dst_width: int
    src: int
    dst: int
    src_fixed: bool
    dst_fixed: bool
    done_items: int = 0
    done_at: Time | None = None
    peripheral: object = None


class DmaChannel:
    """One channel; the SPI controllers talk to it through the handshake methods."""

    def __init__(self, dmac: "Dmac", index: int) -> None:
        self.dmac = dmac
        self.index = index
        self.transfer: Transfer | None = None

    def _reg(self, off: int) -> int:
        return self.dmac.values[CH_BASE + CH_STRIDE * self.index + off]

    def remaining(self) -> int:
        t = self.transfer
        return 0 if t is None else t.items - t.done_items

    def read_for_peripheral(self, n: int) -> np.ndarray:
        """The next n items from memory, for a peripheral's transmit FIFO."""
        t = self.transfer
        values = self.dmac.memory.read_items(t.src, t.src_width, n, t.src_fixed)
        if not t.src_fixed:
            t.src += n * t.src_width
        t.done_items += n
        return values

    def accept_from_peripheral(self, values: np.ndarray, now: Time) -> None:
        """Received items from a peripheral's receive FIFO, written to memory."""
        t = self.transfer
        if t is None:
            return
        take = values[: self.remaining()]
        self.dmac.memory.write_items(t.dst, t.dst_width, take, t.dst_fixed, f"DMAC channel {self.index}")
        if not t.dst_fixed:
            t.dst += len(take) * t.dst_width
        t.done_items += len(take)
        if not self.remaining():
            self.peripheral_done(now)

    def peripheral_gone(self) -> None:
        """The peripheral was reset under the channel: no more requests will come."""
        if self.transfer is not None:
            self.transfer.peripheral = None

    def peripheral_done(self, at: Time) -> None:
        if self.transfer is not None:
            self.transfer.done_at = at


class HandshakePeripheral(Protocol):
    """A block a channel hands items to or takes them from, paced by its handshake (SPI0, SPI1,
    UART1-3)."""

    NAME: str

    def is_data_register(self, address: int) -> bool: ...

    def attach_tx_dma(self, channel: DmaChannel, now: Time) -> None: ...

    def attach_rx_dma(self, channel: DmaChannel, now: Time) -> None: ...

    def detach_dma(self, channel: DmaChannel) -> None: ...


class Dmac(Peripheral):
    NAME = "DMAC"
    BASE = K210_BLOCKS["DMAC"].base
    SIZE = K210_BLOCKS["DMAC"].size
    GATE = K210_BLOCKS["DMAC"].gate
    BUS = BUS_AHB
    REGISTERS = {
        ID: Register("id", width=8, writable=False), COMPVER: Register("compver", width=8, writable=False,
                                                                        reset=0x3130_302A),
        CFG: Register("cfg", width=8), CHEN: Register("chen", width=8),
        INTSTATUS: Register("intstatus", width=8, writable=False),
        COM_INTCLEAR: Register("com_intclear", width=8, readable=False),
        COM_INTSTATUS_EN: Register("com_intstatus_en", width=8),
        COM_INTSIGNAL_EN: Register("com_intsignal_en", width=8),
        COM_INTSTATUS: Register("com_intstatus", width=8, writable=False),
        RESET: Register("reset", width=8),
        **_channel_registers(),
    }

    def __init__(self, ports: Ports, memory: DmaMemory, requests: Callable[[int], tuple[str, str] | None],
                 peripherals: dict[str, "HandshakePeripheral"]) -> None:
        """memory: what the channels read and write. requests: the peripheral request SYSCTL's dma_sel
        routes to a handshake interface, as (peripheral name, "tx" or "rx"), None: none. peripherals:
        the blocks a channel can handshake with, by those names."""
        super().__init__(ports)
        self.memory = memory
        self.requests = requests
        self.peripherals = peripherals
        self.channels = [DmaChannel(self, n) for n in range(CHANNELS)]

    def reset(self, now: Time) -> None:
        for channel in self.channels:
            if channel.transfer is not None and channel.transfer.peripheral is not None:
                channel.transfer.peripheral.detach_dma(channel)
            channel.transfer = None
        super().reset(now)

    def _ch(self, n: int, off: int) -> int:
        return CH_BASE + CH_STRIDE * n + off

    # --- time ------------------------------------------------------------------------

    def advance(self, now: Time) -> None:
        for channel in self.channels:
            t = channel.transfer
            if t is not None and t.done_at is not None and t.done_at <= now:
                self._complete(channel)

    def next_event_time(self, now: Time) -> Time | None:
        times = [c.transfer.done_at for c in self.channels
                 if c.transfer is not None and c.transfer.done_at is not None and c.transfer.done_at > now]
        return min(times) if times else None

    def _complete(self, channel: DmaChannel) -> None:
        n = channel.index
        t = channel.transfer
        if t.peripheral is not None:
            t.peripheral.detach_dma(channel)
        channel.transfer = None
        self.values[CHEN] &= ~(1 << n)
        self.values[self._ch(n, STATUS)] = t.items
        enabled = self.values[self._ch(n, INTSTATUS_EN)]
        self.values[self._ch(n, CH_INTSTATUS)] |= (INT_BLOCK_TFR_DONE | INT_DMA_TFR_DONE) & enabled
        self.ports.irq_changed(t.done_at)

    def irq_line(self, n: int) -> bool:
        return bool(self.irq_lines() >> n & 1)

    def irq_lines(self) -> int:
        """Every channel's interrupt line, channel n in bit n (the PLIC samples them all at once)."""
        values = self.values
        if not values[CFG] & CFG_INT_EN:
            return 0
        lines = 0
        for n, (status, signal) in enumerate(_IRQ_REGISTERS):
            if values[status] & values[signal]:
                lines |= 1 << n
        return lines

    def describe_wait(self) -> str | None:
        for channel in self.channels:
            t = channel.transfer
            if t is not None and t.done_at is None and t.peripheral is not None:
                return (f"DMA channel {channel.index} waits for {t.peripheral.NAME} "
                        f"({'TX' if t.kind == TT_MEM2PER else 'RX'} requests; {channel.remaining()} of "
                        f"{t.items} items left; check {t.peripheral.NAME}.dmacr, ssienr and ser)")
        return None

    # --- registers ------------------------------------------------------------------------

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        self.ports.catch_up(now)
        if offset == INTSTATUS:
            return sum(1 << n for n in range(CHANNELS) if self.values[self._ch(n, CH_INTSTATUS)])
        if offset == RESET:
            return 0   # reset completes at once
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        if offset >= CH_BASE and (offset - CH_BASE) % CH_STRIDE in _SETUP_REGISTERS and \
                self.channels[(offset - CH_BASE) // CH_STRIDE].transfer is None:
            # an idle channel's set-up: nothing the devices do until now depends on it (its start, at
            # chen, does), so they need not catch up first (the firmware writes these for every block)
            self.values[offset] = value
            return
        self.ports.catch_up(now)
        if offset == RESET:
            if value & 1:
                self.reset(now)
            return
        if offset == CHEN:
            self._write_chen(value, now)
            return
        if offset == COM_INTCLEAR:
            return
        if offset >= CH_BASE and (offset - CH_BASE) % CH_STRIDE == INTCLEAR:
            status = offset - INTCLEAR + CH_INTSTATUS
            self.values[status] &= ~value
            self.ports.irq_changed(now)
            return
        self.values[offset] = value
        if offset == CFG:
            self.ports.irq_changed(now)

    def _write_chen(self, value: int, now: Time) -> None:
        old = self.values[CHEN]
        write_enable = (value >> 8) & 0x3F
        new = (old & ~write_enable) | (value & write_enable)
        for n in range(CHANNELS):
            bit = 1 << n
            if write_enable & bit and new & bit and not old & bit:
                if not self.values[CFG] & CFG_ENABLE:
                    self.ports.warn(f"DMAC: channel {n} enabled while the DMAC is disabled (cfg bit 0): ignored", now)
                    new &= ~bit
                    continue
                self.values[CHEN] = (self.values[CHEN] & ~bit) | bit
                self._start(n, now)
            elif write_enable & bit and not new & bit and old & bit:
                raise UnmodelledAccess(f"DMAC: disabling channel {n} in the middle of a transfer is not modelled")
        self.values[CHEN] = (self.values[CHEN] & ~0x3F) | (new & 0x3F)

    def _start(self, n: int, now: Time) -> None:
        ctl = self.values[self._ch(n, CTL)]
        cfg = self.values[self._ch(n, CH_CFG)]
        if field(cfg, 0, 4) or self.values[self._ch(n, LLP)]:
            raise UnmodelledAccess(f"DMAC channel {n}: multi-block / linked-list transfers are not modelled")
        kind = field(cfg, 32, 3)
        src_width = WIDTH_BYTES[field(ctl, 8, 3) if field(ctl, 8, 3) < 4 else 3]
        dst_width = WIDTH_BYTES[field(ctl, 11, 3) if field(ctl, 11, 3) < 4 else 3]
        items = field(self.values[self._ch(n, BLOCK_TS)], 0, 22) + 1
        transfer = Transfer(kind, items, src_width, dst_width,
                            self.values[self._ch(n, SAR)], self.values[self._ch(n, DAR)],
                            bool(ctl >> 4 & 1), bool(ctl >> 6 & 1))
        channel = self.channels[n]
        channel.transfer = transfer
        memory = self.memory
        if kind == TT_MEM2MEM:
            if src_width != dst_width:
                raise UnmodelledAccess(f"DMAC channel {n}: memory-to-memory with different widths is not modelled")
            values = memory.read_items(transfer.src, src_width, items, transfer.src_fixed)
            memory.write_items(transfer.dst, dst_width, values, transfer.dst_fixed, f"DMAC channel {n}")
            transfer.done_items = items
            # items x width bytes at 8 bytes a cycle, as bytes at 8 x the clock rate: a copy that ends
            # within a beat is not rounded to whole cycles (only to a whole picosecond, up)
            bytes_per_second = MEM2MEM_BYTES_PER_CYCLE * self.ports.clock.cpu_hz()
            transfer.done_at = now + cycles_time(items * src_width, bytes_per_second)
            return
        if kind not in (TT_MEM2PER, TT_PER2MEM):
            raise UnmodelledAccess(f"DMAC channel {n}: transfer type {kind} is not modelled")
        to_peripheral = kind == TT_MEM2PER
        hs_software = bool(cfg >> (36 if to_peripheral else 35) & 1)
        if hs_software:
            raise UnmodelledAccess(f"DMAC channel {n}: software handshake on the peripheral side is not modelled")
        handshake = field(cfg, 44, 4) if to_peripheral else field(cfg, 39, 4)
        request = self.requests(handshake)
        if request is None:
            raise HardwareMisuse(f"DMAC channel {n}: handshake interface {handshake} has no peripheral request "
                                 f"selected in SYSCTL dma_sel")
        device_name, direction = request
        if device_name not in self.peripherals:
            raise UnmodelledAccess(f"DMAC channel {n}: transfers handshaking with {device_name.upper()} "
                                   f"{direction.upper()} are not modelled")
        if direction != ("tx" if to_peripheral else "rx"):
            raise HardwareMisuse(f"DMAC channel {n}: {'memory-to-peripheral' if to_peripheral else 'peripheral-to-memory'} "
                                 f"transfer handshakes with {device_name.upper()} {direction.upper()}")
        spi = self.peripherals[device_name]
        address = transfer.dst if to_peripheral else transfer.src
        if not spi.is_data_register(address):
            raise HardwareMisuse(f"DMAC channel {n}: {'dar' if to_peripheral else 'sar'} = 0x{address:x} is not "
                                 f"{spi.NAME}'s data register, yet the channel handshakes with {spi.NAME}")
        if src_width != dst_width:
            raise UnmodelledAccess(f"DMAC channel {n}: {src_width * 8}-bit source items into {dst_width * 8}-bit "
                                   f"destination items (the DMAC packing them) to or from a peripheral are not "
                                   f"modelled")
        if src_width not in (1, 2, 4):
            raise UnmodelledAccess(f"DMAC channel {n}: 64-bit items to or from an SPI FIFO are not modelled")
        transfer.peripheral = spi
        if to_peripheral:
            spi.attach_tx_dma(channel, now)
        else:
            spi.attach_rx_dma(channel, now)
