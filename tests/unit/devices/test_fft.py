"""The FFT accelerator's registers (devices/fft.py): what opening the block does, as the FreeRTOS
SDK's fft driver (MicroPython's start-up) does it, and a clear stop at a calculation."""
import pytest

from emulator.devices import fft as f
from emulator.errors import UnmodelledAccess
from k210_fixtures import board, idle_elf  # noqa: F401 (fixtures)


def test_opening_the_fft_as_the_freertos_sdk_does(board):  # noqa: F811
    fft = board.fft
    fft.write(f.INTR_CLEAR, 8, fft.read(f.INTR_CLEAR, 8, 0) | 1, 0)     # fft_done_clear = 1
    fft.write(f.INTR_MASK, 8, fft.read(f.INTR_MASK, 8, 0) & ~1, 0)     # fft_done_mask = 0
    ctrl = 3 | 1 << 3 | 0x1FF << 4 | 1 << 13                                # 64 points, shift all, enable
    fft.write(f.CTRL, 8, ctrl, 0)
    assert fft.read(f.CTRL, 8, 0) == ctrl
    assert fft.read(f.STATUS, 8, 0) == 0 and fft.read(f.STATUS_RAW, 8, 0) == 0
    assert not fft.irq_line()


def test_a_calculation_stops_the_run_naming_the_fft(board):  # noqa: F811
    with pytest.raises(UnmodelledAccess, match="FFT calculation is not modelled"):
        board.fft.write(f.INPUT_FIFO, 8, 1, 0)
    with pytest.raises(UnmodelledAccess, match="FFT calculation is not modelled"):
        board.fft.read(f.OUTPUT_FIFO, 8, 0)
