"""Programming the DMAC's channels from a test, register by register (devices/dmac.py: SAR, DAR,
BLOCK_TS, CTL, CFG), and moving the devices' time on until a transfer is done: for the DMAC's own
tests (unit/devices/test_dmac.py) and the blocks it serves (UART DMA in unit/devices/test_uart.py)."""
from __future__ import annotations

from emulator.devices import dmac as d
from emulator.vtime import PS_PER_S

SRC, DST = 0x8010_0000, 0x8020_0000
W32 = 2                                          # transfer width code for 32 bits


def ch(n: int, off: int) -> int:
    return d.CH_BASE + d.CH_STRIDE * n + off


def ctl(src_width=W32, dst_width=W32, sinc_fixed=False, dinc_fixed=False) -> int:
    return sinc_fixed << 4 | dinc_fixed << 6 | src_width << 8 | dst_width << 11


def chcfg(tt=d.TT_MEM2MEM, hs_src_sw=True, hs_dst_sw=True, src_per=0, dst_per=0) -> int:
    return tt << 32 | hs_src_sw << 35 | hs_dst_sw << 36 | src_per << 39 | dst_per << 44


def w(board, off, value, now):
    board.dmac.write(off, 8, value, now)


def r(board, off, now):
    return board.dmac.read(off, 8, now)


def setup_channel(board, n, *, sar, dar, items, ctl_value, cfg_value, now=0):
    w(board, ch(n, d.SAR), sar, now)
    w(board, ch(n, d.DAR), dar, now)
    w(board, ch(n, d.BLOCK_TS), items - 1, now)
    w(board, ch(n, d.CTL), ctl_value, now)
    w(board, ch(n, d.CH_CFG), cfg_value, now)


def memcpy_channel(board, n, items, now=0, src=SRC, dst=DST):
    setup_channel(board, n, sar=src, dar=dst, items=items, ctl_value=ctl(), cfg_value=chcfg(), now=now)


def run_devices(board, t, until, limit=PS_PER_S):
    """Moves device time from t, event by event, until until(t) holds; returns the time."""
    board.advance_devices(t)
    while not until(t):
        nxt = board.next_device_event(t)
        assert nxt is not None and nxt <= limit, "no further device event"
        t = nxt
        board.advance_devices(t)
    return t
