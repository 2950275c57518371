"""SPI0/SPI1 (DesignWare SSI as on the K210, facts sheet section 7): FIFO level and
status over time, frame timing, configuration locking, receive paths, refusals."""
from __future__ import annotations

import pytest

from emulator.cpu.caches import ROCKET_L1
from emulator.devices import spi as s
from emulator.memory_map import K210_BLOCKS
from emulator.errors import UnmodelledAccess
from emulator.vtime import PS_PER_MS, PS_PER_NS, PS_PER_S, PS_PER_US, Time, cycles_time, to_seconds
from spi_programs import RECEIVE_100, SEND_AND_WAIT, SPI1_CLOCKS_ON
from k210_fixtures import (RecordingDevice, at_done, board, idle_elf, make_board, program, reg,  # noqa: F401
                           run_to_done, run_until, symbol)

# Reset clocks: PLL0 = 26 MHz, clk_th1 = 0 -> SPI source 13 MHz; baudr 26 -> 500 kHz.
SRC_HZ = 13_000_000
CPU_HZ = 26_000_000
BAUDR = 26
BIT = cycles_time(BAUDR, SRC_HZ)     # 2 us, exactly
FRAME8 = 8 * BIT                     # 16 us
SPI1_ACCESS = ROCKET_L1.device(K210_BLOCKS["SPI1"].bus, (1, 1, 1))   # cycles a register access adds


def ctrlr0(dfs=8, tmod=s.TMOD_TX, fmt=0) -> int:
    return (dfs - 1) << 16 | tmod << 8 | fmt << 21


@pytest.fixture
def bus(board):
    dev = RecordingDevice()
    board.spi1.device_for_ss = lambda ss: dev if ss == 0 else None
    return board, board.spi1, dev


def setup(spi, cr0, now=0, baudr=BAUDR, ser=1, ctrlr1=None, spi_ctrlr0=None):
    spi.write(s.SSIENR, 4, 0, now)
    spi.write(s.CTRLR0, 4, cr0, now)
    spi.write(s.BAUDR, 4, baudr, now)
    if ctrlr1 is not None:
        spi.write(s.CTRLR1, 4, ctrlr1, now)
    if spi_ctrlr0 is not None:
        spi.write(s.SPI_CTRLR0, 4, spi_ctrlr0, now)
    spi.write(s.SSIENR, 4, 1, now)
    spi.write(s.SER, 4, ser, now)


def sr(spi, now) -> int:
    return spi.read(s.SR, 4, now)


def txflr(spi, now) -> int:
    return spi.read(s.TXFLR, 4, now)


# --- transmit timing ---------------------------------------------------------------------

def test_fifo_level_and_status_over_time(bus):
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_TX))
    assert sr(spi, 0) == s.SR_TFNF | s.SR_TFE            # idle
    t0 = 10 * PS_PER_US
    for byte in (0x11, 0x22, 0x33):
        spi.write(s.DR_FIRST, 4, byte, t0)
    # the first frame went straight into the shifter
    assert txflr(spi, t0) == 2
    assert sr(spi, t0) == s.SR_BUSY | s.SR_TFNF
    assert txflr(spi, t0 + FRAME8 - 1) == 2
    assert bytes(dev.received) == b""
    assert txflr(spi, t0 + FRAME8) == 1
    assert bytes(dev.received) == b"\x11"              # delivered when its last bit is out
    assert txflr(spi, t0 + 2 * FRAME8) == 0
    assert sr(spi, t0 + 2 * FRAME8) == s.SR_BUSY | s.SR_TFNF | s.SR_TFE
    assert bytes(dev.received) == b"\x11\x22"
    assert sr(spi, t0 + 3 * FRAME8 - 1) & s.SR_BUSY
    assert sr(spi, t0 + 3 * FRAME8) == s.SR_TFNF | s.SR_TFE   # (sr & 5) == 4: done
    assert bytes(dev.received) == b"\x11\x22\x33"
    assert dev.transfers[0][2] == 1                    # one data line
    assert spi.next_event_time(t0 + 3 * FRAME8) is None


def test_next_event_is_the_end_of_the_train(bus):
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_TX))
    for byte in range(5):
        spi.write(s.DR_FIRST, 4, byte, 0)
    assert spi.next_event_time(0) == 5 * FRAME8


def test_frames_written_later_queue_behind_the_wire(bus):
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_TX))
    spi.write(s.DR_FIRST, 4, 1, 0)
    spi.write(s.DR_FIRST, 4, 2, FRAME8 // 2)           # while frame 1 is shifting
    assert sr(spi, 2 * FRAME8 - 1) & s.SR_BUSY
    assert not sr(spi, 2 * FRAME8) & s.SR_BUSY
    spi.write(s.DR_FIRST, 4, 3, 5 * FRAME8)            # after an idle gap: starts at once
    assert sr(spi, 6 * FRAME8 - 1) & s.SR_BUSY
    assert not sr(spi, 6 * FRAME8) & s.SR_BUSY
    assert bytes(dev.received) == b"\x01\x02\x03"


@pytest.mark.parametrize("dfs, fmt, lanes", [
    (8, 0, 1), (16, 0, 1), (32, 0, 1), (16, 1, 2), (32, 2, 4), (8, 3, 8), (32, 3, 8),
])
def test_frame_period_is_bits_over_lanes_over_sclk(bus, dfs, fmt, lanes):
    board, spi, dev = bus
    setup(spi, ctrlr0(dfs, s.TMOD_TX, fmt))
    period = dfs // lanes * BIT
    assert spi.frame_period() == period
    n = 4
    for i in range(n):
        spi.write(s.DR_FIRST, 4, 0x0102_0304 + i, 0)
    assert sr(spi, n * period - 1) & s.SR_BUSY
    assert not sr(spi, n * period) & s.SR_BUSY
    assert len(dev.received) == n * dfs // 8
    assert {lanes_seen for _, _, lanes_seen in dev.transfers} == {lanes}
    nbytes = dfs // 8
    first = (0x0102_0304).to_bytes(4, "big")[4 - nbytes:]
    assert bytes(dev.received[:nbytes]) == first          # most significant byte first


def test_sclk_follows_clk_th1_and_baudr(bus):
    board, spi, dev = bus
    board.sysctl.write(0x3C, 4, 3 << 8, 0)               # spi1 threshold 3: 26 MHz / 8
    setup(spi, ctrlr0(8, s.TMOD_TX), baudr=4)
    assert spi.sclk_hz() == 26_000_000 // 8 // 4
    assert spi.frame_period() == cycles_time(8 * 4 * 8, 26_000_000)   # 8 bits of 4 cycles of 26 MHz / 8
    board.spi0.write(s.BAUDR, 4, 2, 0)
    assert board.spi0.sclk_hz() == 13_000_000 // 2      # spi0 threshold untouched


def test_fifo_holds_32_plus_the_shifter_and_overflow_is_lost(bus):
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_TX))
    for i in range(33):
        assert sr(spi, 0) & s.SR_TFNF, i
        spi.write(s.DR_FIRST, 4, i, 0)
    assert txflr(spi, 0) == 32
    assert not sr(spi, 0) & s.SR_TFNF
    spi.write(s.DR_FIRST, 4, 0xEE, 0)                    # lost
    assert spi.read(s.RISR, 4, 0) & s.INT_TXO
    assert any("full transmit FIFO" in w for w in board.warnings)
    assert not sr(spi, FRAME8 - 1) & s.SR_TFNF
    assert sr(spi, FRAME8) & s.SR_TFNF                 # one slot freed
    spi.read(s.TXOICR, 4, FRAME8)
    assert not spi.read(s.RISR, 4, FRAME8) & s.INT_TXO
    spi.advance(PS_PER_S)
    assert bytes(dev.received) == bytes(range(33))


def test_frames_wait_for_a_slave_select(bus):
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_TX), ser=0)
    spi.write(s.DR_FIRST, 4, 0xA5, 0)
    assert txflr(spi, PS_PER_MS) == 1
    assert not sr(spi, PS_PER_MS) & s.SR_BUSY
    spi.write(s.SER, 4, 1, PS_PER_MS)                   # writing ser starts the transfer
    assert dev.selects == [(True, PS_PER_MS)]
    assert sr(spi, PS_PER_MS) & s.SR_BUSY
    spi.advance(PS_PER_MS + FRAME8)
    assert bytes(dev.received) == b"\xA5"
    spi.write(s.SER, 4, 0, 2 * PS_PER_MS)
    assert dev.selects[-1] == (False, 2 * PS_PER_MS)


# --- configuration ------------------------------------------------------------------------

@pytest.mark.parametrize("offset", [s.CTRLR0, s.CTRLR1, s.BAUDR, s.SPI_CTRLR0])
def test_configuration_writes_are_ignored_while_enabled(bus, offset):
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_TX))
    before = spi.read(offset, 4, 0)
    spi.write(offset, 4, 0x0001_0002, PS_PER_US)
    assert spi.read(offset, 4, PS_PER_US) == before
    assert any("written while the controller is enabled" in w for w in board.warnings)
    spi.write(s.SSIENR, 4, 0, 2 * PS_PER_US)
    spi.write(offset, 4, 0x0001_0002, 2 * PS_PER_US)
    assert spi.read(offset, 4, 2 * PS_PER_US) == 0x0001_0002


def test_disabling_clears_the_fifos_and_stops_the_wire(bus):
    board, spi, dev = bus
    dev.replies = bytearray(b"\x10\x20\x30")
    setup(spi, ctrlr0(8, s.TMOD_TX_RX))
    for i in range(5):
        spi.write(s.DR_FIRST, 4, i, 0)
    t = 3 * FRAME8 // 2
    assert spi.read(s.RXFLR, 4, t) == 1
    spi.write(s.SSIENR, 4, 0, t)
    assert txflr(spi, t) == 0
    assert spi.read(s.RXFLR, 4, t) == 0
    assert sr(spi, t) == s.SR_TFNF | s.SR_TFE
    assert dev.selects[-1] == (False, t)                 # the slave select drops
    spi.advance(PS_PER_S)
    assert bytes(dev.received) == b"\x00"              # nothing more reached the wire
    spi.write(s.DR_FIRST, 4, 9, PS_PER_S)                # writes while disabled are dropped
    assert txflr(spi, PS_PER_S) == 0


# --- receive -------------------------------------------------------------------------------

def test_transmit_and_receive_fills_the_rx_fifo_with_the_reply(bus):
    board, spi, dev = bus
    dev.replies = bytearray(b"\xA1\xA2\xA3")
    setup(spi, ctrlr0(8, s.TMOD_TX_RX))
    for byte in (0x40, 0x00, 0x95):
        spi.write(s.DR_FIRST, 4, byte, 0)
    assert spi.read(s.RXFLR, 4, FRAME8 - 1) == 0
    assert spi.read(s.RXFLR, 4, FRAME8) == 1
    assert sr(spi, FRAME8) & s.SR_RFNE
    t = 3 * FRAME8
    assert spi.read(s.RXFLR, 4, t) == 3
    assert [spi.read(s.DR_FIRST, 4, t) for _ in range(3)] == [0xA1, 0xA2, 0xA3]
    assert bytes(dev.received) == b"\x40\x00\x95"
    assert spi.read(s.RXFLR, 4, t) == 0
    assert not sr(spi, t) & s.SR_RFNE
    spi.read(s.DR_FIRST, 4, t)                          # underflow
    assert spi.read(s.RISR, 4, t) & s.INT_RXU


@pytest.mark.parametrize("tmod, frames", [(s.TMOD_TX_RX, 1), (s.TMOD_TX_RX, 15), (s.TMOD_TX_RX, 33),
                                          (s.TMOD_TX, 33)])
def test_sr_is_stable_until_the_next_edge_that_changes_it(bus, tmod, frames):
    """A CPU that writes a burst and polls sr is told, at every moment, a time up to which sr reads
    the same; the bound is the frame edge at which it next reads otherwise (it skips the edges
    that change nothing), so a poll is answered once for each change, not once a frame."""
    board, spi, dev = bus
    setup(spi, ctrlr0(8, tmod))
    for i in range(frames):
        spi.write(s.DR_FIRST, 4, i, 0)
    # every quarter frame, the frame edges included, and a picosecond before each edge
    samples = sorted({k * FRAME8 // 4 + d for k in range(4 * frames + 6) for d in (0, -1)} - {-1})
    reads = [(t, sr(spi, t), spi.stable_until(s.SR, t)) for t in samples]
    changes = 0
    for i, (t, value, until) in enumerate(reads):
        assert until >= t
        later = [v for t2, v, _ in reads[i + 1:] if t2 < until]
        assert all(v == value for v in later), f"sr changed before {until / FRAME8:.3f} frames (at {t / FRAME8:.3f})"
        after = [v for t2, v, _ in reads[i + 1:] if until <= t2 < until + FRAME8 // 2]
        if until != t and after:
            assert after[0] != value, f"sr at {until / FRAME8:.3f} frames reads as before: not an edge that changes it"
        changes += i > 0 and value != reads[i - 1][1]
    # one frame: RFNE as BUSY clears; a burst: RFNE (TFNF too when it filled the FIFO), TFE (with RFF
    # when 32 frames have come in), BUSY
    assert changes == {(s.TMOD_TX_RX, 1): 1, (s.TMOD_TX_RX, 15): 3, (s.TMOD_TX_RX, 33): 3,
                       (s.TMOD_TX, 33): 3}[(tmod, frames)]


def test_rx_fifo_threshold_interrupt(bus):
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_TX_RX))
    spi.write(s.SSIENR, 4, 0, 0)
    spi.write(s.RXFTLR, 4, 1, 0)
    spi.write(s.IMR, 4, s.INT_RXF, 0)
    spi.write(s.SSIENR, 4, 1, 0)
    spi.write(s.DR_FIRST, 4, 1, 0)
    spi.write(s.DR_FIRST, 4, 2, 0)
    assert not spi.read(s.ISR, 4, FRAME8) & s.INT_RXF          # 1 entry: not above 1
    assert not spi.read(s.ISR, 4, 2 * FRAME8 - 1) & s.INT_RXF
    assert spi.read(s.ISR, 4, 2 * FRAME8) & s.INT_RXF
    board.time = 2 * FRAME8
    assert spi.irq_line()


def test_receive_fifo_overflow_loses_frames(bus):
    board, spi, dev = bus
    dev.replies = bytearray(range(40))
    setup(spi, ctrlr0(8, s.TMOD_TX_RX))
    for i in range(33):
        spi.write(s.DR_FIRST, 4, i, 0)
    spi.write(s.DR_FIRST, 4, 33, FRAME8)
    t = 34 * FRAME8
    assert spi.read(s.RXFLR, 4, t) == 32
    assert sr(spi, t) & s.SR_RFF
    assert spi.read(s.RISR, 4, t) & s.INT_RXO
    assert [spi.read(s.DR_FIRST, 4, t) for _ in range(32)] == list(range(32))


def test_receive_only_clocks_ctrlr1_plus_one_frames(bus):
    board, spi, dev = bus
    dev.replies = bytearray(b"\x01\x02\x03\x04\x05\x06")
    setup(spi, ctrlr0(8, s.TMOD_RX), ctrlr1=4)
    spi.write(s.DR_FIRST, 4, 0xFFFF_FFFF, 0)             # dummy word starts the clocks
    # the dummy word is not transmitted data: the transmit FIFO is empty at once
    assert txflr(spi, 0) == 0
    assert sr(spi, 0) == s.SR_BUSY | s.SR_TFNF | s.SR_TFE
    assert spi.read(s.RXFLR, 4, 2 * FRAME8) == 2
    assert sr(spi, 5 * FRAME8 - 1) & s.SR_BUSY
    t = 5 * FRAME8
    assert sr(spi, t) == s.SR_TFNF | s.SR_TFE | s.SR_RFNE
    assert spi.read(s.RXFLR, 4, t) == 5
    assert [spi.read(s.DR_FIRST, 4, t) for _ in range(5)] == [1, 2, 3, 4, 5]
    assert bytes(dev.received) == b"\xFF" * 5             # the data line idles high


def record_clock_times(spi, dev) -> list[list[Time]]:
    """Each hand-over to the device, as the times its bytes were clocked (byte_clocked_at)."""
    seen: list[list[Time]] = []
    record = dev.spi_transfer

    def transfer(data, lanes, now):
        seen.append([spi.byte_clocked_at(i, now) for i in range(len(data))])
        return record(data, lanes, now)
    dev.spi_transfer = transfer
    return seen


def test_a_device_knows_when_each_byte_of_a_late_batch_was_clocked(bus):
    """Frames handed to the device in one batch, later than they were clocked (the controller moves
    on lazily), each keep the time their last edge had: a device answering by time (the SD card's
    read access time) reckons from it, not from the hand-over."""
    board, spi, dev = bus
    seen = record_clock_times(spi, dev)
    setup(spi, ctrlr0(8, s.TMOD_RX), ctrlr1=4)
    spi.write(s.DR_FIRST, 4, 0xFFFF_FFFF, 0)
    assert spi.read(s.RXFLR, 4, 10 * FRAME8) == 5         # handed over at once, long after
    assert seen == [[FRAME8 * (n + 1) for n in range(5)]]
    assert spi.byte_clocked_at(0, 123) == 123             # outside a hand-over: the time given


def test_the_bytes_of_a_16_bit_frame_are_clocked_one_after_the_other(bus):
    board, spi, dev = bus
    seen = record_clock_times(spi, dev)
    setup(spi, ctrlr0(16, s.TMOD_RX), ctrlr1=1)
    spi.write(s.DR_FIRST, 4, 0, 0)
    assert spi.read(s.RXFLR, 4, 10 * 16 * BIT) == 2
    assert seen == [[8 * BIT, 16 * BIT, 24 * BIT, 32 * BIT]]


def test_receive_only_16_bit_frames(bus):
    board, spi, dev = bus
    dev.replies = bytearray(b"\x12\x34\x56\x78")
    setup(spi, ctrlr0(16, s.TMOD_RX), ctrlr1=1)
    spi.write(s.DR_FIRST, 4, 0, 0)
    t = 2 * 16 * BIT
    assert [spi.read(s.DR_FIRST, 4, t) for _ in range(2)] == [0x1234, 0x5678]


def test_transmit_only_ignores_the_reply(bus):
    board, spi, dev = bus
    dev.replies = bytearray(b"\x99")
    setup(spi, ctrlr0(8, s.TMOD_TX))
    spi.write(s.DR_FIRST, 4, 1, 0)
    assert spi.read(s.RXFLR, 4, PS_PER_S) == 0


def send_and_wait(quantum):
    board = make_board(program(SEND_AND_WAIT), quantum=quantum)
    dev = RecordingDevice()
    board.spi1.device_for_ss = lambda ss: dev if ss == 0 else None
    run_to_done(board)
    assert bytes(dev.received) == b"\xC1\xC2\xC3\xC4"
    waited = cycles_time(reg(board, "s11") - reg(board, "s10"), CPU_HZ)
    # four frames on the wire, plus the few instructions of the loop, the first store's round trip
    # before the wire starts and the last poll's after it ends (caches.py)
    assert 4 * FRAME8 <= waited <= 4 * FRAME8 + cycles_time(40 + 2 * SPI1_ACCESS, CPU_HZ)


def test_spi_transfer_through_a_program():
    """Firmware opens SPI1's clock gates, sends four bytes and waits for (sr & 5) == 4:
    the wait costs the wire time."""
    send_and_wait(quantum=200)


def test_spi_wait_is_the_wire_time_with_the_default_quantum():
    send_and_wait(quantum=20_000)


# SPI1's clock gates open, 8-bit frames in transmit-and-receive mode at 500 kHz, enabled, slave 0
SPI1_TX_RX = SPI1_CLOCKS_ON + """
    li      t0, (7 << 16)              # 8-bit frames, transmit and receive
    sw      t0, 0x00(s1)
    li      t0, 26
    sw      t0, 0x14(s1)
    li      t0, 1
    sw      t0, 0x08(s1)
    sw      t0, 0x10(s1)
"""

BURST_THEN_DRAIN = SPI1_TX_RX + """
    li      t3, 16
    li      t0, 0xFF
1:  sw      t0, 0x60(s1)
    addi    t3, t3, -1
    bnez    t3, 1b
    li      t2, 4
2:  lw      t1, 0x28(s1)               # wait for the wire to be idle: (sr & 5) == 4
    andi    t1, t1, 5
    bne     t1, t2, 2b
    csrr    s10, mcycle
    la      s2, buffer
    li      t3, 16
3:  lw      t1, 0x60(s1)               # sixteen 0xFF from one pc: a FIFO emptied, not a poll
    sb      t1, 0(s2)
    addi    s2, s2, 1
    addi    t3, t3, -1
    bnez    t3, 3b
    csrr    s11, mcycle
"""


@pytest.mark.parametrize("quantum", [200, 20_000])
def test_emptying_the_receive_fifo_is_not_polling(quantum):
    """Reads that take entries from the receive FIFO are not a poll, however alike the entries:
    the hart reading sixteen 0xFF bytes in a loop runs on, it does not wait for the next
    device event as a hart polling a status register does."""
    board = make_board(program(BURST_THEN_DRAIN, data="buffer: .space 16\n"), quantum=quantum)
    dev = RecordingDevice()          # answers 0xFF to every byte
    board.spi1.device_for_ss = lambda ss: dev if ss == 0 else None
    run_to_done(board)
    assert board.memory.read(symbol(board, "buffer"), 16) == b"\xff" * 16
    # cycles: sixteen loads, each a round trip to SPI1 (caches.py), and sixteen stores
    assert reg(board, "s11") - reg(board, "s10") < 200 + 16 * SPI1_ACCESS
    assert not any("underflow" in w or "overflow" in w for w in board.warnings)


def receive_100(quantum):
    board = make_board(program(RECEIVE_100, data="buffer: .space 128\n"), quantum=quantum)
    dev = RecordingDevice(bytes(range(100)))
    board.spi1.device_for_ss = lambda ss: dev if ss == 0 else None
    run_until(board, at_done, max_time_s=to_seconds(150 * FRAME8))      # 1.5 times the wire time
    assert board.memory.read(symbol(board, "buffer"), 100) == bytes(range(100))
    assert not any("overflow" in w for w in board.warnings)


def test_cpu_polled_receive_only_transfer():
    receive_100(quantum=2000)


def test_cpu_polled_receive_only_transfer_with_the_default_quantum():
    receive_100(quantum=20_000)


def test_receive_fifo_changes_are_device_events(bus):
    """A CPU polling rxflr is woken when frames arrive: the next event while receiving is
    the next frame into an empty FIFO, the RXF threshold, or the FIFO filling up."""
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_RX), ctrlr1=99)
    spi.write(s.DR_FIRST, 4, 0, 0)
    assert spi.next_event_time(0) == FRAME8
    t = 3 * FRAME8                                        # three frames waiting
    spi.read(s.RXFLR, 4, t)
    assert spi.next_event_time(t) == (3 + 29) * FRAME8    # would fill the FIFO
    spi.write(s.SSIENR, 4, 0, t)
    spi.write(s.RXFTLR, 4, 7, t)
    setup(spi, ctrlr0(8, s.TMOD_RX), now=t, ctrlr1=99)
    spi.write(s.DR_FIRST, 4, 0, t)
    t2 = t + 2 * FRAME8
    spi.read(s.RXFLR, 4, t2)
    assert spi.next_event_time(t2) == t + 8 * FRAME8      # level 8 > rxftlr 7


# --- refusals --------------------------------------------------------------------------------

@pytest.mark.parametrize("dfs", [4, 7, 12, 31])
def test_frame_sizes_that_are_not_whole_bytes_are_unmodelled(bus, dfs):
    board, spi, dev = bus
    setup(spi, ctrlr0(dfs, s.TMOD_TX))
    with pytest.raises(UnmodelledAccess, match=f"{dfs}-bit frames"):
        spi.write(s.DR_FIRST, 4, 1, 0)


def test_eeprom_read_sends_the_command_then_clocks_ctrlr1_plus_one_frames_in(bus):
    # as the SDK's spi_receive_data_standard reads a W25Q's ID: the command and address written
    # before the slave is selected, then 2 bytes read (DW SSI databook, EEPROM read)
    board, spi, dev = bus
    dev.replies = bytearray(b"\x11\x22\x33\x44\xEF\x17")
    setup(spi, ctrlr0(8, s.TMOD_EEPROM), ctrlr1=1, ser=0)
    for byte in (0x90, 0, 0, 0):
        spi.write(s.DR_FIRST, 4, byte, 0)
    assert txflr(spi, 0) == 4
    spi.write(s.SER, 4, 1, 0)
    assert txflr(spi, FRAME8 // 2) == 3 and sr(spi, FRAME8 // 2) & s.SR_BUSY
    assert spi.read(s.RXFLR, 4, 5 * FRAME8 - 1) == 0
    assert spi.read(s.RXFLR, 4, 5 * FRAME8) == 1                  # the command's replies are dropped
    assert txflr(spi, 5 * FRAME8) == 0
    t = 6 * FRAME8
    assert sr(spi, t) == s.SR_TFNF | s.SR_TFE | s.SR_RFNE
    assert [spi.read(s.DR_FIRST, 4, t) for _ in range(2)] == [0xEF, 0x17]
    assert bytes(dev.received) == b"\x90\x00\x00\x00\xFF\xFF"


def test_eeprom_read_with_the_command_written_after_the_select(bus):
    # a frame written while the earlier ones are still going out joins the command
    board, spi, dev = bus
    dev.replies = bytearray(b"\x00\x00\x5A\xA5\x01")
    setup(spi, ctrlr0(8, s.TMOD_EEPROM), ctrlr1=2)
    spi.write(s.DR_FIRST, 4, 0x05, 0)
    spi.write(s.DR_FIRST, 4, 0x35, FRAME8 // 2)
    t = 5 * FRAME8
    assert spi.read(s.RXFLR, 4, t) == 3
    assert [spi.read(s.DR_FIRST, 4, t) for _ in range(3)] == [0x5A, 0xA5, 0x01]
    assert bytes(dev.received) == b"\x05\x35\xFF\xFF\xFF"
    # a second read after the first has ended starts a command of its own
    dev.replies = bytearray(b"\x00\x42")
    spi.write(s.SSIENR, 4, 0, t)
    spi.write(s.CTRLR1, 4, 0, t)
    spi.write(s.SSIENR, 4, 1, t)
    spi.write(s.SER, 4, 1, t)
    spi.write(s.DR_FIRST, 4, 0x05, t)
    assert spi.read(s.DR_FIRST, 4, t + 2 * FRAME8) == 0x42


def test_a_frame_written_while_an_eeprom_reply_comes_in_is_unmodelled(bus):
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_EEPROM), ctrlr1=3)
    spi.write(s.DR_FIRST, 4, 0x05, 0)
    with pytest.raises(UnmodelledAccess, match="while the reply is being clocked in"):
        spi.write(s.DR_FIRST, 4, 0x06, 2 * FRAME8)


def spi_ctrlr0(trans=0, addr_bits=0, inst_bits=0, wait=0) -> int:
    inst = {0: 0, 4: 1, 8: 2, 16: 3}[inst_bits]
    return trans | (addr_bits // 4) << 2 | inst << 8 | wait << 11


@pytest.mark.parametrize("dfs, phases", [
    (8, dict(trans=2, inst_bits=8)),                   # the SDK's LCD set-up for 8-bit frames
    (32, dict(trans=2, addr_bits=32)),                 # and for 32-bit frames
    (16, dict(trans=2, inst_bits=16)),
    (32, dict()),
])
def test_enhanced_phases_sent_like_frames_are_accepted(bus, dfs, phases):
    board, spi, dev = bus
    setup(spi, ctrlr0(dfs, s.TMOD_TX, 3), spi_ctrlr0=spi_ctrlr0(**phases))
    spi.write(s.DR_FIRST, 4, 0xA1B2C3D4, 0)
    spi.advance(PS_PER_S)
    assert bytes(dev.received) == (0xA1B2C3D4).to_bytes(4, "big")[4 - dfs // 8:]
    assert dev.transfers[0][2] == 8


def sclk_time(spi, clocks: int, lanes: int = 1) -> Time:
    """How long `clocks` serial clock cycles take, or as many bits on `lanes` lines, from the
    controller's source clock and divider (rounded up to a picosecond, as the model rounds)."""
    return cycles_time(clocks * (spi.values[s.BAUDR] & 0xFFFE), lanes * spi.source_hz())


def ctrlr0_dwc(dfs=8, tmod=s.TMOD_TX, fmt=0) -> int:
    """SPI3's ctrlr0 (DWC_ssi): frame size [4:0], tmod [11:10], frame format [23:22]."""
    return (dfs - 1) | tmod << 10 | fmt << 22


@pytest.fixture
def bus3(board):  # noqa: F811
    dev = RecordingDevice()
    board.spi3.device_for_ss = lambda ss: dev if ss == 0 else None
    board.sysctl.values[0x3C] &= 0x00FF_FFFF          # SPI3's clock threshold 0, as spi_init sets it
    return board, board.spi3, dev


def test_quad_transmit_with_instruction_and_address_on_one_line(bus):
    """The W25Q's quad page program as the SDK sends it (spi_init_non_standard(8, 24, 0, standard)):
    the instruction and the address go out on one line, then the 32-bit frames on four."""
    board, spi, dev = bus
    setup(spi, ctrlr0(32, s.TMOD_TX, 2), ser=0, spi_ctrlr0=spi_ctrlr0(trans=0, inst_bits=8, addr_bits=24))
    for value in (0x32, 0x012345, 0xA1B2C3D4, 0x01020304):
        spi.write(s.DR_FIRST, 4, value, 0)
    spi.write(s.SER, 4, 1, 0)
    assert dev.transfers[:2] == [(0, b"\x32", 1), (0, b"\x01\x23\x45", 1)]
    header = sclk_time(spi, 8 + 24)
    assert header == (8 + 24) * BIT
    end = header + sclk_time(spi, 2 * 32, lanes=4)
    assert spi.busy(end - 1) and not spi.busy(end)
    spi.advance(PS_PER_S)
    assert bytes(dev.received[4:]) == bytes.fromhex("A1B2C3D4 01020304")
    assert {lanes for _, _, lanes in dev.transfers[2:]} == {4}
    assert dev.dummies == []                           # wait cycles come only before received data


@pytest.mark.parametrize("tmod", [s.TMOD_RX, s.TMOD_EEPROM])
def test_quad_receive_with_phases_and_wait_cycles(bus3, tmod):
    """The W25Q's fast read quad I/O as the SDK reads it (8-bit instruction on one line, 32-bit
    address on four, 4 wait cycles; tmod 3, as spi_receive_data_multiple sets it, or 2, as the
    FreeRTOS SDK does): the replies to the phases are dropped, ctrlr1 + 1 frames come in."""
    board, spi, dev = bus3
    dev.replies = bytearray(b"\xEE" * 5 + b"\x11\x22\x33")
    setup(spi, ctrlr0_dwc(8, tmod, 2), ser=0, ctrlr1=2, spi_ctrlr0=spi_ctrlr0(trans=1, inst_bits=8, addr_bits=32, wait=4))
    spi.write(s.DR_FIRST, 4, 0xEB, 0)
    spi.write(s.DR_FIRST, 4, 0x12345600, 0)
    assert spi.read(s.TXFLR, 4, 0) == 2                # waiting in the FIFO for a slave
    spi.write(s.SER, 4, 1, 0)
    assert dev.transfers[:2] == [(0, b"\xEB", 1), (0, b"\x12\x34\x56\x00", 4)]
    assert dev.dummies == [(0, 4)]
    # the instruction's 8 clocks, the address's 32 / 4, 4 wait cycles, then three frames on 4 lines
    done = sclk_time(spi, 8 + 32 // 4 + 4) + sclk_time(spi, 3 * 8, lanes=4)
    assert spi.read(s.RXFLR, 4, done - 1) == 2
    assert spi.read(s.RXFLR, 4, done) == 3
    assert [spi.read(s.DR_FIRST, 4, done) for _ in range(3)] == [0x11, 0x22, 0x33]
    assert spi.read(s.TXFLR, 4, done) == 0


def test_a_second_quad_receive_starts_after_the_first(bus3):
    # the instruction and address written during a receive wait in the FIFO for the next one
    board, spi, dev = bus3
    setup(spi, ctrlr0_dwc(8, s.TMOD_RX, 2), ctrlr1=0, spi_ctrlr0=spi_ctrlr0(trans=1, inst_bits=8, addr_bits=24))
    spi.write(s.DR_FIRST, 4, 0x6B, 0)
    spi.write(s.DR_FIRST, 4, 0x000100, 0)
    spi.write(s.DR_FIRST, 4, 0x6B, 0)
    spi.write(s.DR_FIRST, 4, 0x000200, 0)
    assert spi.read(s.TXFLR, 4, 0) == 2
    spi.advance(PS_PER_S)
    assert [data for _, data, _ in dev.transfers] == [b"\x6B", b"\x00\x01\x00", b"\xFF", b"\x6B",
                                                      b"\x00\x02\x00", b"\xFF"]
    assert spi.read(s.RXFLR, 4, PS_PER_S) == 2
    # the slave select rose between the two transfers, so the device saw two commands
    assert [selected for selected, _ in dev.selects] == [True, False, True]


@pytest.mark.parametrize("phases, message", [
    (dict(trans=3, inst_bits=8), "transfer type 3"),
    (dict(trans=1, inst_bits=4), "4-bit instruction"),
    (dict(trans=1, inst_bits=8, addr_bits=28), "28-bit address"),
])
def test_phases_the_model_cannot_pass_as_bytes_are_unmodelled(bus, phases, message):
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_TX, 2), spi_ctrlr0=spi_ctrlr0(**phases))
    with pytest.raises(UnmodelledAccess, match=message):
        spi.write(s.DR_FIRST, 4, 1, 0)
        spi.write(s.DR_FIRST, 4, 1, 0)


def test_receiving_in_quad_format_on_spi0_or_spi1_is_unmodelled(bus):
    # the LCD and the SD card neither answer in quad nor take wait cycles
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_RX, 2), ctrlr1=0, spi_ctrlr0=spi_ctrlr0(trans=1, inst_bits=8))
    with pytest.raises(UnmodelledAccess, match="receiving in quad format"):
        spi.write(s.DR_FIRST, 4, 0x6B, 0)


def test_a_queued_receive_does_not_start_once_the_select_is_cleared(bus3):
    board, spi, dev = bus3
    setup(spi, ctrlr0_dwc(8, s.TMOD_RX, 2), ctrlr1=0, spi_ctrlr0=spi_ctrlr0(trans=1, inst_bits=8, addr_bits=24))
    for value in (0x6B, 0x000100, 0x6B, 0x000200):
        spi.write(s.DR_FIRST, 4, value, 0)
    spi.write(s.SER, 4, 0, PS_PER_NS)
    spi.advance(PS_PER_S)
    assert [data for _, data, _ in dev.transfers][:2] == [b"\x6B", b"\x00\x01\x00"]
    assert b"\x00\x02\x00" not in [data for _, data, _ in dev.transfers]


def test_transmit_and_receive_in_quad_format_is_unmodelled(bus):
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_TX_RX, 2))
    with pytest.raises(UnmodelledAccess, match="transmit-and-receive mode in quad"):
        spi.write(s.DR_FIRST, 4, 1, 0)


def test_spi3_ctrlr0_fields_sit_where_the_dwc_ssi_has_them(board):
    """SPI3 (DWC_ssi): dfs [4:0], work mode [9:8], tmod [11:10], frame format [23:22] (the SDK's
    spi.c offsets for spi_num 3); reset: 8-bit frames."""
    spi = board.spi3
    assert spi.frame_bits == 8 and spi.tmod == s.TMOD_TX_RX and spi.frame_format == 0
    spi.write(s.CTRLR0, 4, 31 | s.TMOD_RX << 10 | 2 << 22, 0)
    assert (spi.frame_bits, spi.tmod, spi.frame_format) == (32, s.TMOD_RX, 2)
    assert spi.read(s.XIP_CTRL, 4, 0) == 0            # the XIP registers exist (XIP itself is not modelled)


def test_endian_conversion_is_unmodelled(bus):
    board, spi, dev = bus
    spi.write(s.ENDIAN, 4, 1, 0)
    setup(spi, ctrlr0(8, s.TMOD_TX))
    with pytest.raises(UnmodelledAccess, match="endian"):
        spi.write(s.DR_FIRST, 4, 1, 0)


def test_spi_unknown_offset_and_read_only_registers(bus):
    board, spi, dev = bus
    with pytest.raises(UnmodelledAccess):
        spi.read(0x100, 4, 0)
    with pytest.raises(UnmodelledAccess, match="read-only"):
        spi.write(s.SR, 4, 0, 0)
    with pytest.raises(UnmodelledAccess, match="read-only"):
        spi.write(s.TXFLR, 4, 0, 0)


def test_baudr_bit_zero_is_ignored(bus):
    board, spi, dev = bus
    setup(spi, ctrlr0(8, s.TMOD_TX), baudr=BAUDR + 1)
    assert spi.frame_period() == FRAME8
    setup(spi, ctrlr0(8, s.TMOD_TX), baudr=0)
    spi.write(s.DR_FIRST, 4, 1, 0)                        # no serial clock: nothing moves
    assert txflr(spi, PS_PER_S) == 1
    assert dev.received == b""


def test_identical_frames_read_by_the_cpu_are_each_popped_once():
    """Reading the data register from one pc and getting the same value ten times: each read
    pops a frame, once (a repeated load would pop one nobody sees; and such reads are not a poll,
    test_emptying_the_receive_fifo_is_not_polling)."""
    board = make_board(program(SPI1_TX_RX + """
        li      t1, 12
    1:  sw      zero, 0x60(s1)
        addi    t1, t1, -1
        bnez    t1, 1b
        li      t2, 12
    2:  lw      t1, 0x24(s1)               # wait for all twelve replies
        bne     t1, t2, 2b
        li      t1, 10
        li      s3, 0
    3:  lw      t0, 0x60(s1)               # ten reads from one pc, all 0xFF
        add     s3, s3, t0
        addi    t1, t1, -1
        bnez    t1, 3b
        lw      s2, 0x24(s1)               # two frames left
        lw      s4, 0x60(s1)
    """))
    dev = RecordingDevice(b"\xFF" * 11 + b"\x5A")
    board.spi1.device_for_ss = lambda ss: dev if ss == 0 else None
    run_to_done(board)
    assert reg(board, "s3") == 10 * 0xFF
    assert reg(board, "s2") == 2
    assert reg(board, "s4") == 0xFF
