"""The Dock's W25Q128 flash (devices/w25q128.py) driven byte by byte as an SPI controller would,
against the W25Q128FV datasheet's instruction descriptions and AC characteristics."""
import numpy as np
import pytest

from emulator.devices import w25q128 as w
from emulator.errors import UnmodelledAccess
from emulator.vtime import PS_PER_MS, PS_PER_US


class Chip:
    def __init__(self, content: bytes = b"") -> None:
        self.data = bytearray(b"\xFF") * w.SIZE
        self.data[:len(content)] = content
        self.warnings: list[str] = []
        self.flash = w.W25Q128(self.data, warn=lambda text, now: self.warnings.append(text))
        self.now = 0

    def transaction(self, *phases, now: float | None = None) -> bytes:
        """One /CS low-high: phases are (bytes, lines) or an int of dummy clocks; returns the
        replies to every byte."""
        if now is not None:
            self.now = now
        self.flash.spi_select(True, self.now)
        reply = b""
        for phase in phases:
            if isinstance(phase, int):
                self.flash.spi_dummy(phase, self.now)
                continue
            data, lines = phase
            reply += bytes(self.flash.spi_transfer(np.frombuffer(data, dtype=np.uint8), lines, self.now))
        self.flash.spi_select(False, self.now)
        return reply

    def one_line(self, data: bytes) -> bytes:
        return self.transaction((data, 1))

    def status1(self) -> int:
        return self.one_line(b"\x05\x00")[1]

    def write_enable(self) -> None:
        self.one_line(b"\x06")


def test_ids():
    chip = Chip()
    assert chip.one_line(b"\x9F" + b"\x00" * 3)[1:] == bytes([0xEF, 0x40, 0x18])
    assert chip.one_line(b"\x90\x00\x00\x00" + b"\x00" * 4)[4:] == bytes([0xEF, 0x17, 0xEF, 0x17])
    assert chip.one_line(b"\x90\x00\x00\x01" + b"\x00" * 2)[4:] == bytes([0x17, 0xEF])
    assert chip.one_line(b"\xAB\x00\x00\x00\x00")[4] == 0x17
    assert len(chip.one_line(b"\x4B" + b"\x00" * 4 + b"\x00" * 8)[5:]) == 8


def test_reads_on_one_two_and_four_lines():
    content = bytes(range(256)) * 16
    chip = Chip(content)
    assert chip.one_line(b"\x03\x00\x01\x00" + b"\x00" * 4)[4:] == content[0x100:0x104]
    assert chip.one_line(b"\x0B\x00\x00\x10" + b"\x00" + b"\x00" * 3)[5:] == content[0x10:0x13]
    assert chip.transaction((b"\x3B\x00\x00\x20", 1), 8, (b"\x00" * 4, 2))[4:] == content[0x20:0x24]
    assert chip.transaction((b"\x6B\x00\x00\x30", 1), 8, (b"\x00" * 4, 4))[4:] == content[0x30:0x34]
    assert chip.transaction((b"\xEB", 1), (b"\x00\x00\x40\x00", 4), 4, (b"\x00" * 4, 4))[5:] == content[0x40:0x44]
    assert chip.transaction((b"\xBB", 1), (b"\x00\x00\x50\x00", 2), (b"\x00" * 4, 2))[5:] == content[0x50:0x54]
    assert chip.warnings == []


def test_a_read_runs_on_past_the_end_to_address_zero():
    chip = Chip(b"\x5A")
    assert chip.one_line(b"\x03\xFF\xFF\xFF\x00\x00")[4:] == b"\xFF\x5A"


def test_a_phase_on_the_wrong_lines_makes_the_command_do_nothing():
    chip = Chip(b"\x12\x34")
    assert chip.transaction((b"\xEB", 1), (b"\x00\x00\x00\x00", 1), 4, (b"\x00\x00", 4))[5:] == b"\xFF\xFF"
    assert "expected 4" in chip.warnings[0]
    # 4 of its 8 dummy clocks: the next byte's two clocks are still dummy ones
    assert chip.transaction((b"\x6B\x00\x00\x00", 1), 4, (b"\x00", 4))[4:] == b"\xFF"


def test_page_program_needs_write_enable_and_only_clears_bits():
    chip = Chip()
    chip.one_line(b"\x02\x00\x00\x00\xF0")
    assert chip.data[0] == 0xFF and "without write enable" in chip.warnings[0]
    chip.write_enable()
    chip.one_line(b"\x02\x00\x00\x00\xF0\xAA")
    assert chip.data[:2] == b"\xF0\xAA" and chip.flash.changed
    chip.now += PS_PER_MS
    chip.write_enable()
    chip.one_line(b"\x02\x00\x00\x00\x0F")
    assert chip.data[0] == 0x00


def test_page_program_wraps_within_the_page_and_keeps_the_last_256_bytes():
    chip = Chip()
    chip.write_enable()
    chip.one_line(b"\x02\x00\x01\xFE" + bytes([1, 2, 3]))
    assert chip.data[0x1FE:0x200] == b"\x01\x02" and chip.data[0x100] == 3 and chip.data[0x200] == 0xFF
    chip.now += PS_PER_MS
    chip.write_enable()
    chip.transaction((b"\x32\x00\x02\x00", 1), (bytes(range(256)) + b"\x00\x00", 4))
    assert chip.data[0x200:0x202] == b"\x00\x00" and chip.data[0x202:0x300] == bytes(range(2, 256))


def test_busy_times_status_and_write_enable_latch():
    chip = Chip()
    chip.write_enable()
    assert chip.status1() == w.SR1_WEL
    chip.one_line(b"\x20\x00\x10\x00")                 # sector erase: 45 ms typical
    assert chip.status1() == w.SR1_BUSY | w.SR1_WEL
    chip.now = 44 * PS_PER_MS
    assert chip.one_line(b"\x9F\x00")[1] == 0xFF and "under way" in chip.warnings[-1]
    chip.now = 45_100 * PS_PER_US
    assert chip.status1() == 0
    chip.one_line(b"\x02\x00\x00\x00\x00")             # the latch cleared: ignored
    assert chip.data[0] == 0xFF


@pytest.mark.parametrize("code, size, busy", [(0x20, 4096, 45 * PS_PER_MS), (0x52, 32768, 120 * PS_PER_MS), (0xD8, 65536, 150 * PS_PER_MS)])
def test_erase_sizes(code, size, busy):
    chip = Chip(b"\x00" * (3 * 65536))
    chip.write_enable()
    chip.one_line(bytes([code, 0x01, 0x00, 0x10]))      # an address inside the block
    first = 0x10000
    assert chip.data[first - 1] == 0 and chip.data[first:first + size] == b"\xFF" * size
    assert chip.data[first + size] == 0
    assert chip.flash.busy_until == busy


def test_an_erase_with_a_byte_after_its_address_does_not_happen():
    chip = Chip(b"\x00" * 4096)
    chip.write_enable()
    chip.one_line(b"\x20\x00\x00\x00\x00")
    assert chip.data[0] == 0 and "after the command" in chip.warnings[-1]


def test_quad_commands_need_the_quad_enable_bit():
    chip = Chip(b"\x42")
    chip.write_enable()
    chip.one_line(b"\x01\x00\x00")                     # status 1 and 2 written: QE cleared
    chip.now = 11 * PS_PER_MS
    assert chip.one_line(b"\x35\x00")[1] & w.SR2_QE == 0
    assert chip.transaction((b"\x6B\x00\x00\x00", 1), 8, (b"\x00", 4))[4:] == b"\xFF"
    assert "QE" in chip.warnings[-1]
    chip.one_line(b"\x50")                             # volatile: no busy time
    chip.one_line(b"\x31\x02")
    assert chip.status1() == 0 and chip.transaction((b"\x6B\x00\x00\x00", 1), 8, (b"\x00", 4))[4:] == b"\x42"


def test_power_down_and_release():
    chip = Chip(b"\x42")
    chip.one_line(b"\xB9")
    assert chip.one_line(b"\x03\x00\x00\x00\x00")[4] == 0xFF and "powered down" in chip.warnings[-1]
    chip.one_line(b"\xAB")
    assert chip.one_line(b"\x03\x00\x00\x00\x00")[4] == 0x42


def test_what_the_model_does_not_have_is_said():
    chip = Chip()
    with pytest.raises(UnmodelledAccess, match="continuous read mode"):
        chip.transaction((b"\xEB", 1), (b"\x00\x00\x00\x20", 4))
    chip = Chip()
    chip.write_enable()
    chip.one_line(b"\x01\x04")                         # BP0
    chip.now = 11 * PS_PER_MS
    chip.write_enable()
    with pytest.raises(UnmodelledAccess, match="block protection"):
        chip.one_line(b"\x20\x00\x00\x00")
    chip = Chip()
    chip.one_line(b"\x5A\x00\x00\x00\x00\x00")
    assert "not one the model knows" in chip.warnings[0]


def test_mode_bits_clocked_as_wait_cycles_read_high_and_the_read_works():
    """A controller set up with a 24-bit address and 6 wait cycles for EBh clocks the mode byte as
    wait cycles: the lines are undriven and read high (not the continuous read mode)."""
    chip = Chip(b"\x00\x00\x00\x00\x5A\xA5")
    assert chip.transaction((b"\xEB", 1), (b"\x00\x00\x04", 4), 6, (b"\x00\x00", 4))[4:] == b"\x5A\xA5"
    assert chip.transaction((b"\xBB", 1), (b"\x00\x00\x05", 2), 4, (b"\x00", 2))[4:] == b"\xA5"
    assert chip.warnings == []


def test_reset_needs_99h_right_after_66h_and_lock_bits_stay_set():
    chip = Chip()
    chip.write_enable()
    chip.one_line(b"\x66")
    chip.status1()
    chip.one_line(b"\x99")                             # not right after 66h: nothing
    assert chip.status1() & w.SR1_WEL
    chip.one_line(b"\x66")
    chip.one_line(b"\x99")
    assert not chip.status1() & w.SR1_WEL
    chip.one_line(b"\x50")
    chip.one_line(b"\x31\x0A")                         # QE and LB1
    chip.one_line(b"\x50")
    chip.one_line(b"\x31\x02")                         # LB1 cannot be cleared
    assert chip.one_line(b"\x35\x00")[1] == 0x0A
