"""SHA256 (0x502C_0000): the K210's SHA-256 accelerator, as the Kendryte SDK's sha256.c drives it.

Registers (sha256.h `sha256_t`): sha_result[8] (0x00-0x1C), sha_data_in1 (0x20: the message, a
32-bit word at a time, already padded by software), sha_num_reg (0x28: bits 15:0 the number of
512-bit blocks to hash, bits 31:16 the block being hashed), sha_function_reg_0 (0x2C: writing bit
0 starts; reading it says the hash is complete; bit 8 overflow, more words than blocks; bit 16 the
words' byte order, 1 big-endian), sha_function_reg_1 (0x34: bit 0 DMA handshake, bit 8 the input
FIFO full).

With bit 16 set (the SDK's SHA256_BIG_ENDIAN) each word written is the message's next four bytes
as a little-endian load reads them, and the accelerator takes them in message order; with it
clear the word itself is the big-endian message word. Each block is hashed as it fills (the
FIFO is never full here) and after the last the result reads back as the SDK's sha256_final takes
it: the digest's word i (as a little-endian store writes it) is sha_result[7 - i].

DMA (the FreeRTOS SDK's sha256.cpp, as MicroPython builds it): a DMAC channel with dma_sel's
SHA request (21) writes 32-bit items to sha_data_in1 while sha_function_reg_1 bit 0 is set; the
SDK starts the channel, then sets the bit. Each item is taken as a CPU write would be, all at
once: the accelerator's throughput is not documented, and the model hashes as the words come.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..errors import UnmodelledAccess
from ..memory_map import K210_BLOCKS
from ..vtime import Time
from .mmio import Peripheral, Register
from .ports import Ports

if TYPE_CHECKING:
    from .dmac import DmaChannel

RESULT, DATA_IN, NUM, FUNCTION0, FUNCTION1 = 0x00, 0x20, 0x28, 0x2C, 0x34
ENABLE, OVERFLOW, BIG_ENDIAN = 1, 1 << 8, 1 << 16
DMA_ENABLE, FIFO_FULL = 1, 1 << 8

_K = (0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
      0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
      0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
      0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
      0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
      0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
      0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
      0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2)
_H0 = (0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a, 0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19)
_M = 0xFFFF_FFFF


def _rotr(x: int, n: int) -> int:
    return (x >> n | x << (32 - n)) & _M


def compress(state: tuple[int, ...], block: list[int]) -> tuple[int, ...]:
    """One SHA-256 compression (FIPS 180-4, 6.2.2) of sixteen big-endian message words."""
    w = list(block)
    for t in range(16, 64):
        s0 = _rotr(w[t - 15], 7) ^ _rotr(w[t - 15], 18) ^ (w[t - 15] >> 3)
        s1 = _rotr(w[t - 2], 17) ^ _rotr(w[t - 2], 19) ^ (w[t - 2] >> 10)
        w.append((w[t - 16] + s0 + w[t - 7] + s1) & _M)
    a, b, c, d, e, f, g, h = state
    for t in range(64):
        t1 = (h + (_rotr(e, 6) ^ _rotr(e, 11) ^ _rotr(e, 25)) + ((e & f) ^ (~e & g)) + _K[t] + w[t]) & _M
        t2 = ((_rotr(a, 2) ^ _rotr(a, 13) ^ _rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c))) & _M
        a, b, c, d, e, f, g, h = (t1 + t2) & _M, a, b, c, (d + t1) & _M, e, f, g
    return tuple((x + y) & _M for x, y in zip(state, (a, b, c, d, e, f, g, h)))


class Sha256(Peripheral):
    NAME = "SHA256"
    BASE = K210_BLOCKS["SHA256"].base
    SIZE = K210_BLOCKS["SHA256"].size
    GATE = K210_BLOCKS["SHA256"].gate
    REGISTERS = {
        **{RESULT + 4 * n: Register(f"sha_result{n}", writable=False) for n in range(8)},
        DATA_IN: Register("sha_data_in1", readable=False), 0x24: Register("reserved0"),
        NUM: Register("sha_num_reg"), FUNCTION0: Register("sha_function_reg_0"), 0x30: Register("reserved1"),
        FUNCTION1: Register("sha_function_reg_1"),
    }

    def __init__(self, ports: Ports) -> None:
        super().__init__(ports)
        self.tx_dma: "DmaChannel | None" = None
        self._clear()

    def _clear(self) -> None:
        self._state = _H0
        self._words: list[int] = []
        self._blocks = 0
        self._started = False             # sha_en written: the blocks sha_num_reg counts are taken
        self._overflow = False

    def reset(self, now: Time) -> None:
        if self.tx_dma is not None:
            self.tx_dma.peripheral_gone()
            self.tx_dma = None
        super().reset(now)
        self._clear()

    # --- the DMA handshake (dmac.HandshakePeripheral) ---------------------------------------------

    def is_data_register(self, address: int) -> bool:
        return address == self.BASE + DATA_IN

    def attach_tx_dma(self, channel: "DmaChannel", now: Time) -> None:
        if channel.transfer.dst_width != 4:
            raise UnmodelledAccess(f"SHA256: DMAC channel {channel.index} writes {8 * channel.transfer.dst_width}-bit "
                                   f"items to sha_data_in1 (the SDK writes 32-bit items, one message word each)")
        self.tx_dma = channel
        self._dma_take(now)

    def attach_rx_dma(self, channel: "DmaChannel", now: Time) -> None:
        raise AssertionError("the SHA request is a transmit request: the DMAC checks the direction first")

    def detach_dma(self, channel: "DmaChannel") -> None:
        if self.tx_dma is channel:
            self.tx_dma = None

    def _dma_take(self, now: Time) -> None:
        """While the DMA handshake is on, the channel's items are the message's words."""
        channel = self.tx_dma
        if channel is None or not self.values[FUNCTION1] & DMA_ENABLE or not channel.remaining():
            return
        for item in channel.read_for_peripheral(channel.remaining()):
            self._take_word(int(item))
        channel.peripheral_done(now)
        # the channel's completion (its interrupt) is due now: the DMAC catches up at once, as a
        # block it serves through a FIFO would have it when its own event came
        self.ports.catch_up(now)
        self.ports.irq_changed(now)

    def _running(self) -> bool:
        return self._started and self._blocks < self.values[NUM] & 0xFFFF

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        if offset < DATA_IN:
            if self._running():
                return 0
            # the SDK stores sha_result[7 - i] little-endian as the digest's bytes 4i..4i+3
            return int.from_bytes(self._state[7 - offset // 4].to_bytes(4, "big"), "little")
        if offset == NUM:
            return (self.values[NUM] & 0xFFFF) | self._blocks << 16
        if offset == FUNCTION0:
            done = 0 if self._running() else ENABLE
            return done | (OVERFLOW if self._overflow else 0) | (self.values[FUNCTION0] & BIG_ENDIAN)
        if offset == FUNCTION1:
            return self.values[FUNCTION1] & 1              # the FIFO is never full
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        if offset == FUNCTION0:
            self.values[offset] = value & (BIG_ENDIAN | ENABLE)
            if value & ENABLE:
                # (the FreeRTOS SDK writes sha_num_reg after sha_en, the standalone SDK before)
                self._state, self._words, self._blocks, self._overflow = _H0, [], 0, False
                self._started = True
            return
        if offset == DATA_IN:
            self._take_word(value)
            return
        self.values[offset] = value
        if offset == FUNCTION1:
            self._dma_take(now)

    def _take_word(self, value: int) -> None:
        """The message's next word (from the CPU or a DMA channel)."""
        if not self._running():
            self._overflow = True
            return
        word = value & _M
        if self.values[FUNCTION0] & BIG_ENDIAN:
            word = int.from_bytes(word.to_bytes(4, "little"), "big")
        self._words.append(word)
        if len(self._words) == 16:
            self._state = compress(self._state, self._words)
            self._words = []
            self._blocks += 1

