"""UARTHS transmit path (facts sheet section 6): baud = core clock / (div + 1), ten bit
times per byte (start, 8 data, stop), an 8-entry transmit FIFO, txctrl.txen."""
from __future__ import annotations

import pytest

from emulator.devices import uarths as u
from emulator.errors import UnmodelledAccess
from emulator.vtime import NEVER, PS_PER_MS, PS_PER_S, PS_PER_US, cycles_time
from k210_fixtures import idle_elf, make_board, program, route_uarths_to_the_console, run_until  # noqa: F401

CPU_HZ = 26_000_000
DIV = 25                       # 26 MHz / 26 = 1 Mbaud: one bit per microsecond
BIT = cycles_time(DIV + 1, CPU_HZ)
BYTE = cycles_time(10 * (DIV + 1), CPU_HZ)
US, MS, S = PS_PER_US, PS_PER_MS, PS_PER_S


@pytest.fixture
def console_board(idle_elf):
    out: list[int] = []
    board = route_uarths_to_the_console(make_board(idle_elf, console=lambda b: out.append(b)))
    board.uarths.write(u.DIV, 4, DIV, 0)
    return board, out


def full(board, now) -> bool:
    return bool(board.uarths.read(u.TXDATA, 4, now) & u.FULL)


def test_bytes_reach_the_console_after_ten_bit_times(console_board):
    board, out = console_board
    uart = board.uarths
    uart.write(u.TXCTRL, 4, 1, 0)
    t0 = 3 * US
    for ch in b"OK!":
        uart.write(u.TXDATA, 4, ch, t0)
    uart.advance(t0 + BYTE - 1)                      # a picosecond before the stop bit ends
    assert out == []
    uart.advance(t0 + BYTE)
    assert out == [ord("O")]
    uart.advance(t0 + 2 * BYTE - 1)
    assert out == [ord("O")]
    uart.advance(t0 + 2 * BYTE)
    assert bytes(out) == b"OK"
    assert uart.next_event_time(t0 + 2 * BYTE) == t0 + 3 * BYTE
    uart.advance(t0 + 3 * BYTE)
    assert bytes(out) == b"OK!"
    assert uart.next_event_time(t0 + 3 * BYTE) is None


def test_byte_time_follows_div(console_board):
    board, out = console_board
    uart = board.uarths
    uart.write(u.DIV, 4, 2 * DIV + 1, 0)              # half the baud rate
    uart.write(u.TXCTRL, 4, 1, 0)
    uart.write(u.TXDATA, 4, 0x55, 0)
    uart.advance(BYTE * 199 // 100)
    uart.advance(BYTE * 2 - 1)
    assert out == []
    uart.advance(BYTE * 2)
    assert out == [0x55]


def test_two_stop_bits_make_eleven_bit_times(console_board):
    board, out = console_board
    uart = board.uarths
    uart.write(u.TXCTRL, 4, 0b11, 0)                  # txen, nstop = 2
    uart.write(u.TXDATA, 4, 0x41, 0)
    uart.advance(11 * BIT - 1)
    assert out == []
    uart.advance(11 * BIT)
    assert out == [0x41]


def test_nothing_is_sent_while_txen_is_clear(console_board):
    board, out = console_board
    uart = board.uarths
    uart.write(u.TXDATA, 4, ord("a"), 0)
    uart.write(u.TXDATA, 4, ord("b"), 0)
    uart.advance(S)
    assert out == []
    assert uart.next_event_time(S) is None
    uart.write(u.TXCTRL, 4, 1, S)                    # enable: the queue drains from now
    uart.advance(S + BYTE - 1)
    assert out == []
    uart.advance(S + 2 * BYTE)
    assert bytes(out) == b"ab"


def test_fifo_full_after_eight_queued_bytes_and_a_write_to_a_full_fifo_is_lost(console_board):
    board, out = console_board
    uart = board.uarths
    for i in range(8):
        assert not full(board, 0), i
        uart.write(u.TXDATA, 4, 0x30 + i, 0)
    assert full(board, 0)
    uart.write(u.TXDATA, 4, ord("X"), 0)            # lost
    uart.write(u.TXCTRL, 4, 1, 0)
    # enabling moved one byte into the shift register: a FIFO slot is free again
    assert not full(board, 0)
    uart.advance(S)
    assert bytes(out) == b"01234567"


def test_a_lost_byte_is_a_warning_counted_not_repeated(console_board):
    board, out = console_board
    uart = board.uarths
    for i in range(8):
        uart.write(u.TXDATA, 4, 0x30 + i, MS)
    assert board.warnings == []
    for i in range(5):                              # five bytes into a full FIFO: all lost
        uart.write(u.TXDATA, 4, ord("X"), MS + i * US)
    assert board.warnings == [
        "[     1.000 ms] UARTHS: a byte written to txdata while the 8-byte transmit FIFO was full was lost"
        ": a writer must wait while txdata reads bit 31 (full) (5 times in all, the last at 1.004 ms)"]


def test_distinct_warnings_are_capped(console_board):
    board, _ = console_board
    for n in range(130):
        board.warn(f"warning number {n}")
    assert len(board.warnings) == 101
    assert board.warnings[-1] == "30 further warnings not listed (only the first 100 distinct ones are)"


def test_with_txen_the_shift_register_holds_a_ninth_byte(console_board):
    board, out = console_board
    uart = board.uarths
    uart.write(u.TXCTRL, 4, 1, 0)
    for i in range(9):
        uart.write(u.TXDATA, 4, 0x61 + i, 0)
    assert full(board, 0)
    uart.write(u.TXDATA, 4, ord("X"), 0)            # lost
    assert full(board, BYTE - 1)
    assert not full(board, BYTE)                            # first byte out, next one shifting
    uart.advance(S)
    assert bytes(out) == b"abcdefghi"


def test_txdata_is_stable_until_a_byte_leaves_the_full_fifo(console_board):
    """A writer polling txdata is answered once a byte (txdata is declared steady: it changes only
    at the UART's events or by an access): full reads stay full until the byte on the wire has gone
    (and not a moment longer), a FIFO with room is answered until the UART's next event, and one
    that cannot drain (txen clear) stays full."""
    board, _ = console_board
    uart = board.uarths
    assert not full(board, 0) and uart.stable_until(u.TXDATA, 0) == NEVER
    for i in range(8):
        uart.write(u.TXDATA, 4, 0x61 + i, 0)
    assert full(board, US) and uart.stable_until(u.TXDATA, US) == NEVER               # txen clear
    uart.write(u.TXCTRL, 4, 1, 2 * US)
    uart.write(u.TXDATA, 4, 0x69, 2 * US)         # the first byte went to the wire: room for a ninth
    t = 2 * US + BYTE // 2
    assert full(board, t)
    until = uart.stable_until(u.TXDATA, t)
    assert until == 2 * US + BYTE
    assert full(board, until - 1) and not full(board, until)
    assert uart.stable_until(u.TXDATA, until) == uart.next_event_time(until) == until + BYTE
    assert uart.stable_until(u.RXDATA, until) == until                 # reading it takes a byte


def test_rxdata_reads_empty_and_unknown_offsets_are_unmodelled(console_board):
    board, _ = console_board
    assert board.uarths.read(u.RXDATA, 4, 0) & u.EMPTY
    with pytest.raises(UnmodelledAccess):
        board.uarths.read(0x1C, 4, 0)
    with pytest.raises(UnmodelledAccess, match="read-only"):
        board.uarths.write(u.RXDATA, 4, 0, 0)


def test_txwm_interrupt_pending_below_the_watermark(console_board):
    board, _ = console_board
    uart = board.uarths
    uart.write(u.TXCTRL, 4, 2 << 16, 0)              # txcnt 2, txen off
    assert uart.read(u.IP, 4, 0) & u.IP_TXWM
    uart.write(u.TXDATA, 4, 1, 0)
    uart.write(u.TXDATA, 4, 2, 0)
    assert not uart.read(u.IP, 4, 0) & u.IP_TXWM
    assert not uart.irq_line()
    uart.write(u.IE, 4, u.IP_TXWM, 0)
    uart.write(u.TXCTRL, 4, 2 << 16 | 1, 0)          # txen: one byte leaves the FIFO
    assert uart.irq_line()


def test_quiet_byte_ends_are_the_byte_ends_up_to_a_line_end(console_board):
    """The ends of bytes that change nothing but the console's record (Uarths.quiet_byte_ends):
    those in a row from the byte on the wire up to a newline (the board reads each line at its
    end), as advance works them out; the next loud event is the newline's end."""
    board, out = console_board
    uart = board.uarths
    assert uart.quiet_byte_ends() == ()                              # nothing on the wire
    uart.write(u.TXCTRL, 4, 1, 0)
    for ch in b"ab\ncd":
        uart.write(u.TXDATA, 4, ch, 0)
    assert uart.quiet_byte_ends() == (BYTE, 2 * BYTE) and uart.next_event_time(0) == BYTE
    newline_end = 3 * BYTE
    assert uart.next_loud_event_time(0) == newline_end
    uart.advance(newline_end)                                        # the line is out: "cd" is quiet
    assert bytes(out) == b"ab\n"
    assert uart.quiet_byte_ends() == (4 * BYTE, 5 * BYTE) and uart.next_event_time(newline_end) == 4 * BYTE
    assert uart.next_loud_event_time(newline_end) is None             # nothing but quiet bytes left


def test_with_the_transmitter_off_only_the_byte_on_the_wire_ends(console_board):
    """txen = 0: the byte on the wire ends, the FIFO's wait; so only that end is ahead."""
    board, _ = console_board
    uart = board.uarths
    uart.write(u.TXCTRL, 4, 1, 0)
    for ch in b"abc":
        uart.write(u.TXDATA, 4, ch, 0)
    uart.write(u.TXCTRL, 4, 0, BYTE // 2)
    assert uart.quiet_byte_ends() == (BYTE,)
    assert uart.next_loud_event_time(BYTE // 2) is None


def test_quiet_byte_ends_are_exact_where_a_byte_is_no_whole_number_of_picoseconds(console_board):
    """At 115200 baud from 26 MHz a byte is no whole number of picoseconds: each end is counted
    from the train's start and rounded up once, so the ends are not a first end plus multiples of
    one byte time; quiet_byte_ends gives them as the UART will hear them (the fast engine's turns
    alone stop at each, as _turn would), and the UART hears each at that time."""
    board, out = console_board
    uart = board.uarths
    uart.write(u.DIV, 4, 225 - 1, 0)
    uart.write(u.TXCTRL, 4, 1, 0)
    for ch in b"abcdefgh":
        uart.write(u.TXDATA, 4, ch, 0)
    ends = uart.quiet_byte_ends()
    assert ends == tuple(cycles_time(k * 10 * 225, CPU_HZ) for k in range(1, 9))
    assert len({b - a for a, b in zip(ends, ends[1:])}) == 2          # (not evenly spaced)
    assert uart.next_loud_event_time(0) is None
    heard = []
    uart.on_byte = lambda byte: heard.append(uart.last_byte_time)
    uart.advance(ends[-1])
    assert tuple(heard) == ends


@pytest.mark.parametrize("why", ["watermark interrupt", "every byte heard"])
def test_no_byte_is_quiet_when_its_end_may_matter(console_board, why):
    """With the transmit-watermark interrupt enabled a byte's end may raise it; a console watch
    (every_byte_heard) may end the run at any byte: then every end is an event."""
    board, _ = console_board
    uart = board.uarths
    if why == "watermark interrupt":
        uart.write(u.IE, 4, u.IP_TXWM, 0)
    else:
        uart.every_byte_heard = True
    uart.write(u.TXCTRL, 4, 1, 0)
    for ch in b"abc":
        uart.write(u.TXDATA, 4, ch, 0)
    assert uart.quiet_byte_ends() == ()
    assert uart.next_loud_event_time(0) == uart.next_event_time(0) == BYTE


def test_a_program_prints_through_uarths():
    elf = program("""
        li      s0, 0x38000000
        li      t0, 25
        sw      t0, 0x18(s0)            # div
        li      t0, 1
        sw      t0, 0x08(s0)            # txen
        la      s1, message
    1:  lbu     t1, 0(s1)
        beqz    t1, 3f
    2:  lw      t2, 0(s0)              # wait while the FIFO is full
        bltz    t2, 2b
        sw      t1, 0(s0)
        addi    s1, s1, 1
        j       1b
    3:
    """, data="""
    message: .asciz "Hello, K210 board model! 0123456789"
    """)
    out = bytearray()
    board = route_uarths_to_the_console(make_board(elf, console=out.append, quantum=2000))
    text = b"Hello, K210 board model! 0123456789"
    run_until(board, lambda b: len(out) == len(text), max_time_s=1e-3)
    assert bytes(out) == text
    # the run cannot be faster than the wire: 10 bit times per byte
    assert board.time >= len(text) * BYTE
    assert board.time <= len(text) * BYTE + cycles_time(2000, CPU_HZ) + US


# --- the receiver (--uart-input) ---------------------------------------------------------------

def receiving_board(idle_elf, data: bytes):
    from emulator.frontends.uart_input import UartInput
    board = make_board(idle_elf)
    board.uarths.write(u.DIV, 4, DIV, 0)
    board.uarths.input = UartInput(data)
    return board, board.uarths


def rx(uart, now) -> int:
    return uart.read(u.RXDATA, 4, now)


def test_the_receiver_takes_a_byte_every_ten_bit_times_once_enabled(idle_elf):
    board, uart = receiving_board(idle_elf, b"hi")
    uart.advance(MS)
    assert rx(uart, MS) & u.EMPTY                       # receiver off: the host waits
    assert uart.next_event_time(MS) is None
    t0 = 2 * MS
    uart.write(u.RXCTRL, 4, u.RXCTRL_RXEN, t0)
    assert uart.next_event_time(t0) == t0 + BYTE
    assert rx(uart, t0 + BYTE - 1) & u.EMPTY
    assert rx(uart, t0 + BYTE) == ord("h")
    assert rx(uart, t0 + 2 * BYTE) == ord("i")
    assert rx(uart, t0 + 3 * BYTE) & u.EMPTY
    assert uart.bytes_received == 2


def test_a_full_receive_fifo_holds_the_host_back_and_rxwm_follows_rxcnt(idle_elf):
    data = bytes(range(0x41, 0x41 + 12))
    board, uart = receiving_board(idle_elf, data)
    uart.write(u.RXCTRL, 4, u.RXCTRL_RXEN | 3 << 16, 0)        # rxcnt 3
    uart.write(u.IE, 4, u.IP_RXWM, 0)
    uart.advance(3 * BYTE)
    assert not uart.read_ip() & u.IP_RXWM and not uart.irq_line()     # 3 bytes: not more than rxcnt
    uart.advance(4 * BYTE - 1)
    assert not uart.read_ip() & u.IP_RXWM
    uart.advance(4 * BYTE)
    assert uart.read_ip() & u.IP_RXWM and uart.irq_line()
    late = 100 * BYTE                                           # the firmware looks late
    uart.advance(late)
    assert uart.bytes_received == u.RX_FIFO_DEPTH               # the rest waits on the host's side
    got = [rx(uart, late) for _ in range(u.RX_FIFO_DEPTH)]
    assert bytes(got) == data[:u.RX_FIFO_DEPTH]
    assert rx(uart, late) & u.EMPTY
    assert uart.next_event_time(late) == late + BYTE                  # the next one started when room came
    got += [rx(uart, late + k * BYTE) for k in range(1, 5)]
    assert bytes(got) == data
