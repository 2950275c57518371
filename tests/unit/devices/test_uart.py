"""UART1-3, DesignWare APB UARTs (devices/uart.py): the divisor latch and DLF as the Kendryte SDK's
uart_configure programs them, byte times, 16-byte FIFOs, the programmable THRE mode the SDK's
putchar relies on, IIR, LSR, USR, the receiver, loopback, SRR; the PLIC sources 11-13; and the
Dock's console, which is whatever FPIOA routes to pad 5."""
from __future__ import annotations

import pytest

from emulator.devices import uart as u
from emulator.devices.fpioa import FUNC_UART1_RX, FUNC_UART1_TX
from emulator.devices.plic import SOURCE_UART1
from emulator.frontends.uart_input import UartInput
from emulator.vtime import PS_PER_MS, cycles_time
from k210_fixtures import idle_elf, make_board, program, reg, run_to_done, run_until  # noqa: F401

APB0_HZ = 26_000_000             # a cold board: ACLK from the oscillator, apb0_clk_sel 0
PAD_RX, PAD_TX = 4, 5
MS = PS_PER_MS


def configure(uart, baud: int, lcr: int = 3, now: int = 0) -> int:
    """What the SDK's uart_configure writes (8 data bits by default, 1 stop bit, no parity),
    with FIFOs on, programmable THRE mode, transmit threshold 8 (FCR 0x31 | 0x8). Returns the APB0
    clocks a bit lasts."""
    divisor = APB0_HZ // baud
    dlh, rest = divisor >> 12, divisor - ((divisor >> 12) << 12)
    dll, dlf = rest // 16, rest - (rest // 16) * 16
    uart.write(u.LCR, 4, u.LCR_DLAB, now)
    uart.write(u.IER, 4, dlh, now)
    uart.write(u.RBR, 4, dll, now)
    uart.write(u.DLF, 4, dlf, now)
    uart.write(u.LCR, 4, 0, now)
    uart.write(u.LCR, 4, lcr, now)
    uart.write(u.IER, 4, u.IER_PTIME, now)
    uart.write(u.IIR, 4, 0 << 6 | 3 << 4 | 1 << 3 | 1, now)
    return 16 * (dlh << 8 | dll) + dlf


def bits_time(bits: float, clocks: int) -> int:
    """How long `bits` bits (whole or half) of `clocks` APB0 clocks each last: rounded up once,
    as the UART counts a train of bytes from its start."""
    return cycles_time(round(2 * bits) * clocks, 2 * APB0_HZ)


@pytest.fixture
def board(idle_elf):
    return make_board(idle_elf)


def route(board, rx_function: int | None, tx_function: int | None) -> None:
    if rx_function is not None:
        board.fpioa.write(4 * PAD_RX, 4, rx_function, 0)
    if tx_function is not None:
        board.fpioa.write(4 * PAD_TX, 4, tx_function | 0xF << 8 | 1 << 12, 0)


def test_the_sdk_divisor_sets_the_bit_time(board):
    uart = board.uarts[2]
    clocks = configure(uart, 115_200)
    # 26 MHz / 115200 = 225.69: DLH:DLL 14, DLF 1 -> 16 x 14.0625 clocks a bit, 115,555 baud
    assert clocks == 225
    assert uart.bit_time() == cycles_time(225, APB0_HZ)
    uart.write(u.LCR, 4, u.LCR_DLAB | 3, 0)
    assert uart.read(u.RBR, 4, 0) == 14 and uart.read(u.IER, 4, 0) == 0      # DLL, DLH with DLAB
    uart.write(u.LCR, 4, 3, 0)
    assert uart.read(u.IER, 4, 0) == u.IER_PTIME                                   # IER without


@pytest.mark.parametrize("lcr, bits", [(3, 10), (3 | u.LCR_PEN, 11), (3 | u.LCR_STOP, 11), (0, 7),
                                       (u.LCR_STOP, 7.5)])
def test_a_byte_takes_start_data_parity_and_stop_bits(board, lcr, bits):
    route(board, None, FUNC_UART1_TX)
    uart = board.uarts[0]
    clocks = configure(uart, 1_000_000, lcr)
    uart.write(u.RBR, 4, 0x41, MS)
    uart.advance(MS + bits_time(bits, clocks) - 1)             # a picosecond before the stop bit ends
    assert board.uart_output == {}
    uart.advance(MS + bits_time(bits, clocks))
    assert bytes(board.uart_output["UART1"]) == b"A"
    assert uart.last_byte_time == MS + bits_time(bits, clocks)


def test_bytes_back_to_back_end_counted_from_the_first(board):
    """At 115200 baud from 26 MHz a byte is no whole number of picoseconds: the k-th of a train ends
    k byte times after the train began (rounded up once), however often the UART was advanced."""
    uart = board.uarts[0]
    clocks = configure(uart, 115_200)
    ends = []
    uart.on_byte = lambda byte: ends.append(uart.last_byte_time)
    for n in range(17):                                          # one on the wire, 16 in the FIFO
        uart.write(u.RBR, 4, 0x30 + n, 0)
    for t in range(0, bits_time(17 * 10, clocks) + 1, 12_345_679):
        uart.advance(t)
    uart.advance(bits_time(17 * 10, clocks))
    assert ends == [bits_time(k * 10, clocks) for k in range(1, 18)]


def test_programmable_thre_mode_lsr_bit_5_means_fifo_full(board):
    """The SDK's putchar waits `while (LSR & (1 << 5))`: with IER bit 7 and the FIFOs on, bit 5 is
    set while the 16-byte transmit FIFO is full, not while it is empty (DW_apb_uart, PTIME)."""
    uart = board.uarts[2]
    configure(uart, 115_200)
    assert not uart.read(u.LSR, 4, 0) & u.LSR_THRE              # empty: the writer may go on
    assert uart.read(u.LSR, 4, 0) & u.LSR_TEMT
    for n in range(17):                                          # one on the wire, 16 in the FIFO
        uart.write(u.RBR, 4, 0x30 + n, 0)
    assert uart.read(u.LSR, 4, 0) & u.LSR_THRE
    assert uart.read(u.TFL, 4, 0) == 16
    assert uart.read(u.USR, 4, 0) == u.USR_BUSY                # full, not empty, transmitting
    uart.write(u.RBR, 4, 0x7A, 0)                               # lost, with a warning
    assert any("transmit FIFO was full was lost" in w for w in board.warnings)
    uart.write(u.IER, 4, 0, 0)                                  # 16550 mode: bit 5 is THR empty
    assert not uart.read(u.LSR, 4, 0) & u.LSR_THRE


def test_thre_interrupt_16550_mode_cleared_by_reading_iir(board):
    uart = board.uarts[0]
    clocks = configure(uart, 1_000_000)
    uart.write(u.IER, 4, 0, 0)
    assert uart.read(u.IIR, 4, 0) == 0xC1                        # FIFOs on, nothing pending
    uart.write(u.IER, 4, u.IER_ETBEI, 0)                         # enabling it with THR empty: at once
    assert uart.irq_line()
    assert uart.read(u.IIR, 4, 0) == 0xC2
    assert uart.read(u.IIR, 4, 0) == 0xC1                      # the read cleared it
    uart.write(u.RBR, 4, 0x55, 0)                              # into the shifter: the FIFO empties
    assert uart.read(u.IIR, 4, 0) == 0xC2
    uart.write(u.RBR, 4, 0x56, 0)                              # waits in the FIFO: no THRE
    assert uart.read(u.IIR, 4, 0) == 0xC1
    assert uart.read(u.IIR, 4, bits_time(10, clocks) - 1) == 0xC1
    uart.advance(bits_time(10, clocks))                         # 0x56 moved to the shifter
    assert uart.read(u.IIR, 4, bits_time(10, clocks)) == 0xC2


def test_thre_interrupt_in_programmable_mode_follows_the_threshold(board):
    uart = board.uarts[0]
    configure(uart, 1_000_000)                                   # threshold: half full (8)
    uart.write(u.IER, 4, u.IER_PTIME | u.IER_ETBEI, 0)
    for n in range(9):
        uart.write(u.RBR, 4, n, 0)                               # 1 on the wire, 8 waiting
    assert uart.read(u.IIR, 4, 0) == 0xC2
    uart.write(u.RBR, 4, 9, 0)                                   # 9 waiting: above it
    assert uart.read(u.IIR, 4, 0) == 0xC1
    assert uart.read(u.STET, 4, 0) == 3 and uart.read(u.SFE, 4, 0) == 1


def test_receiver_takes_the_host_bytes_at_the_baud_rate_and_raises_its_interrupts(board):
    route(board, FUNC_UART1_RX + 4, None)                        # UART3 from pad 4
    uart = board.uarts[2]
    clocks = configure(uart, 1_000_000)
    board.connect_serial_input(UartInput(b"hi!"))
    uart.write(u.IER, 4, u.IER_ERBFI, 0)                         # receive trigger: 1 byte
    uart.advance(0)
    assert not uart.read(u.LSR, 4, 0) & u.LSR_DR
    t = bits_time(10, clocks)
    assert not uart.read(u.LSR, 4, t - 1) & u.LSR_DR
    uart.advance(t)
    assert uart.read(u.LSR, 4, t) & u.LSR_DR and uart.read(u.RFL, 4, t) == 1
    assert uart.read(u.IIR, 4, t) == 0xC4                        # received data available
    assert SOURCE_UART1 + 2 in board._high_sources()
    assert uart.read(u.RBR, 4, t) == ord("h")
    t = bits_time(30, clocks)
    uart.advance(t)
    assert uart.read(u.RFL, 4, t) == 2
    assert bytes([uart.read(u.RBR, 4, t), uart.read(u.RBR, 4, t)]) == b"i!"
    assert uart.read(u.IIR, 4, t) == 0xC1
    assert not board.uarts[0].input.has_byte(t)                  # UART1 is not routed from pad 4


def test_a_reset_in_the_middle_of_a_byte_has_the_host_send_it_again(board):
    # the SDK's start-up configures UART3 and the program's uart_init resets it; a byte caught
    # on the wire then is neither lost nor counted twice
    route(board, FUNC_UART1_RX + 4, None)
    uart = board.uarts[2]
    clocks = configure(uart, 1_000_000)
    board.connect_serial_input(UartInput(b"ab"))
    uart.advance(bits_time(5, clocks))                           # 'a' half in
    uart.reset(bits_time(5, clocks))
    assert uart.bytes_received == 0
    t = bits_time(5, clocks)
    configure(uart, 1_000_000, now=t)
    uart.advance(t + bits_time(20, clocks))
    assert uart.read(u.RFL, 4, t + bits_time(20, clocks)) == 2
    assert bytes([uart.read(u.RBR, 4, t), uart.read(u.RBR, 4, t)]) == b"ab"
    assert uart.bytes_received == 2
    uart.reset(t + bits_time(21, clocks))
    assert uart.bytes_received == 2                              # the run's count outlives the reset


def test_a_byte_left_in_the_fifo_below_the_trigger_times_out(board):
    route(board, FUNC_UART1_RX, None)
    uart = board.uarts[0]
    clocks = configure(uart, 1_000_000)
    uart.write(u.IIR, 4, 2 << 6 | 1, 0)                          # trigger: half full
    board.connect_serial_input(UartInput(b"x"))
    uart.write(u.IER, 4, u.IER_ERBFI, 0)
    t = bits_time(10, clocks)
    uart.advance(t)
    assert uart.read(u.IIR, 4, t) == 0xC1                        # one byte: under the trigger
    timeout = uart.next_event_time(t)
    assert timeout == t + bits_time(4 * 10, clocks)              # four character times
    assert uart.read(u.IIR, 4, timeout - 1) == 0xC1
    assert uart.read(u.IIR, 4, timeout) == 0xCC


def test_loopback_receives_what_it_sends(board):
    uart = board.uarts[1]
    clocks = configure(uart, 1_000_000)
    uart.write(u.MCR, 4, u.MCR_LOOPBACK, 0)
    uart.write(u.RBR, 4, 0x99, 0)
    uart.advance(bits_time(10, clocks))
    assert uart.read(u.RBR, 4, bits_time(10, clocks)) == 0x99
    assert board.uart_output == {}                                # nothing on the pin


def test_srr_and_fcr_reset_the_fifos(board):
    uart = board.uarts[0]
    configure(uart, 1_000_000)
    for n in range(5):
        uart.write(u.RBR, 4, n, 0)
    assert uart.read(u.TFL, 4, 0) == 4
    uart.write(u.IIR, 4, 1 | u.FCR_XFIFOR, 0)
    assert uart.read(u.TFL, 4, 0) == 0
    uart.write(u.SRR, 4, u.SRR_UR, 0)
    assert uart.read(u.LCR, 4, 0) == 0 and uart.read(u.IER, 4, 0) == 0
    assert uart.read(u.CTR, 4, 0) == u.PERIPHERAL_ID


def test_the_console_is_what_pad_5_carries(board):
    """The Dock's USB-serial bridge listens on pad 5: a UART's bytes reach the console only
    while FPIOA routes that UART's TX there; every UART's bytes are kept either way."""
    heard = bytearray()
    board._console = heard.append
    uart1, uart3 = board.uarts[0], board.uarts[2]
    clocks = configure(uart1, 1_000_000)
    configure(uart3, 1_000_000)
    uart1.write(u.RBR, 4, ord("a"), 0)
    uart3.write(u.RBR, 4, ord("b"), 0)
    board.advance_devices(bits_time(10, clocks))
    assert heard == b""
    route(board, None, FUNC_UART1_TX + 4)                       # UART3_TX on pad 5
    uart1.write(u.RBR, 4, ord("c"), MS)
    uart3.write(u.RBR, 4, ord("d"), MS)
    board.advance_devices(MS + bits_time(10, clocks))
    assert heard == b"d"
    assert {name: bytes(sent) for name, sent in board.uart_output.items()} == {"UART1": b"ac", "UART3": b"bd"}


def test_an_sdk_style_program_prints_on_uart3_through_pads_4_and_5():
    """The SDK's start-up: UART3's clock on (APB0 and clk_en_peri bit 18), its reset pulsed,
    pads 4/5 to UART3, uart_configure for 115200, then putchar waiting on LSR bit 5."""
    board = make_board(program("""
        li      s0, 0x50440000
        lw      t0, 0x28(s0)
        ori     t0, t0, 1 << 3
        sw      t0, 0x28(s0)                 # clk_en_cent: APB0
        lw      t0, 0x2C(s0)
        li      t1, (1 << 18) | (1 << 20)
        or      t0, t0, t1
        sw      t0, 0x2C(s0)                 # clk_en_peri: UART3, FPIOA
        lw      t0, 0x34(s0)
        li      t1, 1 << 18
        or      t0, t0, t1
        sw      t0, 0x34(s0)                 # peri_reset: UART3 in reset ...
        not     t1, t1
        and     t0, t0, t1
        sw      t0, 0x34(s0)                 # ... and out
        li      s1, 0x502B0000
        li      t0, 68 | (1 << 20)
        sw      t0, 16(s1)                   # pad 4: UART3_RX
        li      t0, 69 | (0xF << 8) | (1 << 12)
        sw      t0, 20(s1)                   # pad 5: UART3_TX
        li      s2, 0x50230000
        li      t0, 0x80
        sw      t0, 0x0C(s2)                 # LCR.DLAB
        sw      zero, 0x04(s2)               # DLH
        li      t0, 14
        sw      t0, 0x00(s2)                 # DLL: 26 MHz / 115200 = 16 x 14 + 1
        li      t0, 1
        sw      t0, 0xC0(s2)                 # DLF
        sw      zero, 0x0C(s2)
        li      t0, 3
        sw      t0, 0x0C(s2)                 # 8N1
        li      t0, 0x80
        sw      t0, 0x04(s2)                 # IER: programmable THRE
        li      t0, 0x39
        sw      t0, 0x08(s2)                 # FCR
        la      s3, text
    1:  lbu     t1, 0(s3)
        beqz    t1, 3f
    2:  lw      t2, 0x14(s2)                 # LSR: wait while bit 5 (FIFO full)
        andi    t2, t2, 1 << 5
        bnez    t2, 2b
        sw      t1, 0(s2)                    # THR
        addi    s3, s3, 1
        j       1b
    3:  lw      t2, 0x14(s2)                 # wait until the transmitter is empty (TEMT)
        andi    t2, t2, 1 << 6
        beqz    t2, 3b
    """, data='text: .asciz "hello from UART3 through pad 5, longer than one FIFO\\n"'))
    heard = bytearray()
    board._console = heard.append
    run_to_done(board, max_time_s=0.02)
    assert heard == b"hello from UART3 through pad 5, longer than one FIFO\n"
    assert [line for _, line in board.console_lines] == ["hello from UART3 through pad 5, longer than one FIFO"]
    # the bytes of 10 bits at 26e6 / 225 baud, back to back
    assert board.uarts[2].last_byte_time >= cycles_time(len(heard) * 10 * 225, APB0_HZ)


def test_dma_keeps_the_transmit_fifo_full_and_takes_what_is_received(board):
    """The SDK's uart_send_data_dma / uart_receive_data_dma: SYSCTL dma_sel routes UARTn's TX or
    RX request to a channel, one 32-bit item a byte; the block is done when its last item is in
    the FIFO (sending) or in memory (receiving)."""
    from emulator.devices import dmac as d
    from dmac_channels import DST, SRC, chcfg, ctl, run_devices, setup_channel, w
    uart = board.uarts[0]
    clocks = configure(uart, 1_000_000)
    text = b"DMA to UART1, more than sixteen bytes\n"
    board.memory.load(SRC, b"".join(bytes([c, 0, 0, 0]) for c in text))
    board.sysctl.write(0x64, 4, 15, 0)                         # dma_sel: channel 0 <- UART1_TX
    w(board, d.CFG, d.CFG_ENABLE, 0)
    setup_channel(board, 0, sar=SRC, dar=uart.BASE, items=len(text), ctl_value=ctl(dinc_fixed=True),
                  cfg_value=chcfg(d.TT_MEM2PER, hs_dst_sw=False, dst_per=0))
    w(board, d.CHEN, 0x0101, 0)
    t_done = run_devices(board, 0, lambda t: not board.dmac.values[d.CHEN] & 1)
    # done once the last byte is in the FIFO: 16 bytes before the end of the wire
    assert t_done == bits_time((len(text) - 17) * 10, clocks)
    t_end = run_devices(board, t_done, lambda t: len(board.uart_output.get("UART1", b"")) == len(text))
    assert bytes(board.uart_output["UART1"]) == text
    assert t_end == bits_time(len(text) * 10, clocks)
    # receiving: loopback brings the bytes back, a second channel takes them
    uart.write(u.MCR, 4, u.MCR_LOOPBACK, t_end)
    board.sysctl.write(0x64, 4, 14 << 6, t_end)                # channel 1 <- UART1_RX
    setup_channel(board, 1, sar=uart.BASE, dar=DST, items=3, ctl_value=ctl(sinc_fixed=True),
                  cfg_value=chcfg(d.TT_PER2MEM, hs_src_sw=False, src_per=1), now=t_end)
    w(board, d.CHEN, 0x0202, t_end)
    for c in b"abc":
        uart.write(u.RBR, 4, c, t_end)
    run_devices(board, t_end, lambda t: not board.dmac.values[d.CHEN] & 2)
    assert board.memory.read(DST, 12) == b"a\0\0\0b\0\0\0c\0\0\0"


def test_a_read_of_lsr_that_clears_an_error_is_not_a_repeatable_read(board):
    """LSR is declared steady (the bus may answer a poll of it from the last read until the UART's
    next event), but a read that clears a latched error takes something: it says so (took_on_read),
    and the bus does not answer the next read from it, which reads without the error."""
    uart = board.uarts[2]
    configure(uart, 1_000_000)
    uart._errors = u.LSR_OE                                      # (latched: an overrun, loopback's way)
    uart.took_on_read = False
    assert uart.read(u.LSR, 4, 0) & u.LSR_OE
    assert uart.took_on_read
    uart.took_on_read = False
    assert not uart.read(u.LSR, 4, 0) & u.LSR_OE and not uart.took_on_read
    assert uart.stable_until(u.LSR, 0) > 0                       # a plain read again: steady
