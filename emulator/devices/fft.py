"""FFT: the K210's FFT accelerator, its registers without the calculation.

| offset | register        | in the model                                               |
|--------|-----------------|------------------------------------------------------------|
| 0x00   | fft_input_fifo  | a write would start feeding a calculation: stops the run    |
| 0x08   | fft_ctrl        | point count, direction, shift, enable, dma_send, modes: kept |
| 0x10   | fifo_ctrl       | the three FIFO flush bits: kept                             |
| 0x18   | intr_mask       | fft_done_mask: kept                                         |
| 0x20   | intr_clear      | fft_done_clear: clears the done status; reads 0             |
| 0x28   | fft_status      | fft_done_status: 0 (no calculation has run)                 |
| 0x30   | fft_status_raw  | done and work bits: 0                                       |
| 0x38   | fft_output_fifo | a read would take a result: stops the run                   |

Every register is 64 bits wide (the SDK's `fft_t`, bit fields of uint64_t). Firmware that only
opens the block (the FreeRTOS SDK's fft driver clears and unmasks the done interrupt when the
device is first opened, which MicroPython does at start-up) runs on; the calculation itself (its
fixed-point scaling and rounding are not documented) is not modelled and says so, whether the data
comes from the CPU or from a DMA channel (dma_sel requests 23 and 24 stop the run when a channel
starts on them). Sources: the
SDK's `fft.h` (register table and fields), `plic.h` (IRQN_FFT_INTERRUPT 26), the FreeRTOS SDK's
`fft.cpp` (`on_first_open`).
"""
from __future__ import annotations

from ..errors import UnmodelledAccess
from ..memory_map import K210_BLOCKS
from ..vtime import Time
from .mmio import Peripheral, Register

INPUT_FIFO, CTRL, FIFO_CTRL, INTR_MASK, INTR_CLEAR, STATUS, STATUS_RAW, OUTPUT_FIFO = range(0, 0x40, 8)
_BLOCK = K210_BLOCKS["FFT"]


class Fft(Peripheral):
    NAME = "FFT"
    BASE, SIZE, GATE = _BLOCK.base, _BLOCK.size, _BLOCK.gate
    REGISTERS = {
        INPUT_FIFO: Register("fft_input_fifo", width=8, narrow_ok=True, readable=False),
        CTRL: Register("fft_ctrl", width=8, narrow_ok=True),
        FIFO_CTRL: Register("fifo_ctrl", width=8, narrow_ok=True),
        INTR_MASK: Register("intr_mask", width=8, narrow_ok=True),
        INTR_CLEAR: Register("intr_clear", width=8, narrow_ok=True),
        STATUS: Register("fft_status", width=8, narrow_ok=True, writable=False),
        STATUS_RAW: Register("fft_status_raw", width=8, narrow_ok=True, writable=False),
        OUTPUT_FIFO: Register("fft_output_fifo", width=8, narrow_ok=True, writable=False),
    }

    def irq_line(self) -> bool:
        return False                    # no calculation ever completes

    def read_register(self, offset: int, reg: Register, now: Time) -> int:
        if offset == OUTPUT_FIFO:
            raise UnmodelledAccess("FFT: reading a result from fft_output_fifo: the FFT calculation is not modelled")
        if offset in (INTR_CLEAR, STATUS, STATUS_RAW):
            return 0
        return self.values[offset]

    def write_register(self, offset: int, reg: Register, value: int, now: Time) -> None:
        if offset == INPUT_FIFO:
            raise UnmodelledAccess("FFT: data written to fft_input_fifo: the FFT calculation is not modelled")
        if offset == INTR_CLEAR:
            return                      # nothing is latched to clear
        self.values[offset] = value
